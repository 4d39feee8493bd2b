// Ensembles: after a reconstruction, the "Ensemble members" setting's N more reconstructions,
// each fitting a bootstrap draw of the systems on a grid moved by up to half a cell (as `wslap
// reconstruct --ensemble N --seed S`). The main worker draws the members (`ensemblePlan`), a
// pool of workers (one per core, each its own WebAssembly instance) runs them, each member's
// maps go back to the main worker as it finishes, and the main worker combines them
// (`ensembleFinish`). Then: the spread view (a tab), the intervals in the caption and under
// the views, the ensemble's downloads, and its values in the map's read-out.

import { LensClient } from '../lens-client.js';
import { poolSize, projectForTrials } from './pool.js';
import { button, save } from './downloads.js';

/** Workers that run an ensemble's members, one member at a time each. */
export class EnsemblePool {
  constructor(size) {
    this.workers = Array.from({ length: size }, (_, k) => new LensClient({ name: `pool-${k + 1}` }));
    this.busy = 0; // workers running a member now
  }

  get size() { return this.workers.length; }

  /** Runs every member of `plan` on `project` (the main session's, without its result);
   * `onMember(answer)` gets each member's `{record, kappa, magnif}` as it is done (awaited,
   * so the next member of that worker starts after it). `onProgress` gets `{done, total,
   * running}` at every report: `running` maps each member being run to its worker's last
   * progress report (null before the first). A worker that fails fails the run with a
   * message naming the member; the caller closes the pool in any case. */
  async run(project, plan, onMember, onProgress) {
    const total = plan.draws.length;
    const running = new Map();
    let next = 1;
    let done = 0;
    const report = () => onProgress({ done, total, running });
    report();
    const work = async (worker, k) => {
      try {
        await worker.request('openProject', { text: project, name: 'project' });
      } catch (err) {
        throw failure(err, `The ensemble failed: pool worker ${k + 1} could not open the project`);
      }
      while (next <= total) {
        const member = next++;
        running.set(member, null);
        this.busy += 1;
        report();
        let answer;
        try {
          answer = await worker.request('ensembleMember', { plan, member }, (p) => {
            running.set(member, p);
            report();
          });
        } catch (err) {
          throw failure(err, `The ensemble failed at member ${member}`);
        } finally {
          this.busy -= 1;
        }
        running.delete(member);
        await onMember(answer);
        done += 1;
        report();
      }
    };
    await Promise.all(this.workers.map(work));
  }

  /** Terminates every worker at once; their jobs fail as cancelled. */
  close() {
    for (const w of this.workers) w.close();
    this.busy = 0;
  }
}

/** `err` with `what` in front, kept as a cancel when it is one. */
function failure(err, what) {
  if (err.cancelled) return err;
  return new Error(`${what}: ${err.message}`);
}

/** Runs the ensemble the settings ask for after the main worker's reconstruction, if any:
 * `ask` talks to the main worker, `onPool(pool)` is told the pool while it runs (null after;
 * Cancel closes it), `iterations` is a member's iteration count for the progress. `onProgress`
 * gets `{elapsed_ms, units, total, words}`. Resolves with the main worker's `resultInfo`
 * after the members are combined, or null when the settings ask for no ensemble. */
export async function runEnsemble({ ask, onPool, iterations, onProgress }) {
  const { plan } = await ask('ensemblePlan');
  if (!plan) return null;
  const t0 = performance.now();
  const n = plan.draws.length;
  const project = projectForTrials(await ask('textFile', { name: 'project.json' }));
  const pool = new EnsemblePool(poolSize(n));
  pool.cancelledText = 'Cancelled the ensemble: every worker was stopped; the reconstruction is shown without it.';
  onPool(pool);
  try {
    await pool.run(project, plan, (answer) => ask('ensembleAdd', answer), ({ done, running }) => {
      let partial = 0;
      for (const p of running.values()) partial += p ? Math.min(1, p.iteration / Math.max(1, iterations)) : 0;
      const members = [...running.keys()];
      const highest = Math.max(done, ...members);
      const workers = `${pool.size} worker${pool.size === 1 ? '' : 's'}`;
      onProgress({
        elapsed_ms: performance.now() - t0,
        units: done + Math.min(partial, 0.99 * members.length),
        total: n,
        words: `Ensemble: member ${highest} of ${n}, ${done} done; ${members.length
          ? `${workers} running member${members.length === 1 ? '' : 's'} ${members.join(', ')}` : `starting ${workers}`}`,
      });
    });
  } finally {
    pool.close();
    onPool(null);
  }
  // The members are of the project the pool was given: the session must still be it.
  if (projectForTrials(await ask('textFile', { name: 'project.json' })) !== project) {
    throw new Error('The data or settings changed while the ensemble ran: press Reconstruct again.');
  }
  const info = await ask('ensembleFinish', { plan, complete: true });
  info.ensemble_ms = performance.now() - t0;
  return info;
}

// The result's ensemble on screen (ensemble.json), or null: its z_s for the caption.
let shown = null;

/** A number in the caption's style. */
const fixed = (v, d) => (v == null || !Number.isFinite(v) ? '–' : v.toFixed(d));
const mass = (v) => v.toExponential(2).replace('e+', 'e');

/** The ensemble's intervals of a result's summary (summary.json with
 * `einstein_radius_interval_arcsec`, `mass_within_interval_msun`, `ensemble_members`) as a
 * sentence for the caption; '' without an ensemble. */
export function ensembleCaption(summary) {
  const n = summary?.ensemble_members;
  if (!n) return '';
  const r = summary.einstein_radius_interval_arcsec;
  // The members' radii are at the z_s of the run, which the curves' may have left since.
  const z = shown && shown.z_source !== summary.maps?.z_source ? ` at z_s = ${shown.z_source}` : '';
  const radius = r ? `Einstein radius${z} ${fixed(r[0], 1)} – ${fixed(r[1], 1)}″` : 'no Einstein radius';
  const masses = (summary.mass_within_interval_msun ?? []).filter(([, m]) => m)
    .map(([within, [lo, hi]]) => `${mass(lo)} – ${mass(hi)} M☉ within ${fixed(within, 0)}″`);
  const widened = summary.ensemble_calibration?.factor > 1
    ? `, widened ×${fixed(summary.ensemble_calibration.factor, 2)}` : '';
  return ` Ensemble of ${n} members (68% intervals about this map${widened}): ${radius}${masses.length ? `; ${masses.join(', ')}` : ''}.`;
}

/** The ensemble's values in the map's read-out (`h.ensemble` of a hover answer), '' without. */
export function ensembleReadout(h) {
  const e = h?.ensemble;
  if (!e || h.no_data) return '';
  const z = e.z_source === h.z_source ? '' : ` at z_s = ${e.z_source}`;
  return `; ensemble of ${e.members}: κ std ${fixed(e.kappa_std, 3)}, μ${z} 16–84% ` +
    `${fixed(e.magnification_p16, 2)} to ${fixed(e.magnification_p84, 2)} (median ${fixed(e.magnification_p50, 2)})`;
}

const FITS = ['kappa-mean.fits', 'kappa-std.fits', 'magnif-p16.fits', 'magnif-p50.fits', 'magnif-p84.fits'];

/** Shows the result's ensemble (`ensemble`: ensemble.json as the worker gives it, with `maps`
 * false when a reopened project kept its intervals only, or null) under the views, with its
 * downloads; adds them to the downloads panel and shows or hides the spread tab. `app` gives
 * the files (`ensembleFiles`, `textFile`) and shows errors. */
export function showEnsemble(ensemble, app) {
  const box = document.getElementById('ensemble-box');
  const tab = document.getElementById('tab-spread');
  document.getElementById('ensemble-downloads')?.remove();
  shown = ensemble;
  // A project keeps the ensemble's statistics maps up to a size: without them, no spread.
  const maps = ensemble?.maps !== false;
  tab.hidden = !ensemble || !maps;
  if (!ensemble) {
    box.replaceChildren();
    box.hidden = true;
    return;
  }
  const n = ensemble.members.length;
  const fail = (err) => app.showError(err.message);
  const file = (name) => () => app.ensembleFiles()
    .then((files) => files.find((f) => f.name === name))
    .then((f) => save(name, new Blob([f.bytes], { type: name.endsWith('.png') ? 'image/png' : 'application/fits' })), fail);
  const json = () => app.textFile('ensemble.json')
    .then((t) => save('ensemble.json', new Blob([t], { type: 'application/json' })), fail);
  const buttons = () => [
    ...(maps ? FITS.map((name) => button(name, `dl-${name.replaceAll('.', '-')}`, file(name))) : []),
    button('ensemble.json', 'dl-ensemble-json', json),
    ...(maps ? [button('kappa-std.png', 'dl-kappa-std-png', file('kappa-std.png'))] : []),
  ];
  // What is not offered, said where the downloads are.
  const missing = () => {
    const p = document.createElement('p');
    p.className = 'hint ensemble-missing';
    const cli = document.createElement('code');
    cli.textContent = `wslap reconstruct --ensemble ${n} --seed ${ensemble.seed}`;
    cli.style.whiteSpace = 'nowrap';
    p.append(`${maps ? '' : 'This ensemble was reopened from a project that kept its intervals only '
      + '(its maps were too large to keep): press Reconstruct to run it again for its maps, the spread and the '
      + 'magnification intervals. '}The members' own maps (range/, one κ and one μ map per member) are not kept by `
      + 'the app; ', cli, ' writes them.');
    return p;
  };
  const r = ensemble.einstein_radius_interval_arcsec;
  const radii = ensemble.members.map((m) => m.einstein_radius_arcsec).filter(Number.isFinite);
  const masses = (ensemble.mass_within_interval_msun ?? []).map(([within, m]) =>
    `<li>within ${fixed(within, 0)}″: ${m ? `${mass(m[0])} – ${mass(m[1])} M☉` : 'not on every member\'s map'}</li>`).join('');
  const c = ensemble.calibration;
  const calibration = c ? `<p id="ensemble-calibration">At the ${c.images} images of the systems they left out,
    the members' predictions miss by a median of ${fixed(c.miss_median_arcsec, 2)}″ for a spread of
    ${fixed(c.spread_median_arcsec, 2)}″ (ratio ${fixed(c.ratio, 2)}, 1 when the spread is the error): ${c.factor > 1
    ? `the intervals and κ's spread are widened ×${fixed(c.factor, 2)}` : 'the intervals are the members\' own spread'}.</p>` : '';
  // Members whose first map was crowded (the verdict's rule) and who fitted their draw's next
  // candidates, as the main run does; some may have found none uncrowded.
  const moved = ensemble.members.filter((m) => m.crowded_maps?.length);
  const still = moved.filter((m) => m.crowded);
  const crowded = moved.length ? `<p id="ensemble-crowded">${moved.length} of ${n} members' first maps predicted far
    more images than observed for more than a third of the systems (critical curves winding through the images):
    those members fitted the next candidates of their own draw instead, as this map's choice does${still.length
    ? `, and ${still.length} found none better and kept the least crowded` : ''}.</p>` : '';
  box.innerHTML = `<h3>Ensemble of ${n} members (seed ${ensemble.seed})</h3>
    <p id="ensemble-summary">How sure the map is: ${n} more reconstructions, each fitting a bootstrap draw of the
    systems on a grid moved by up to half a cell. Einstein radius at z_s = ${ensemble.z_source}, 68% interval
    about this map: <b>${r ? `${fixed(r[0], 2)} – ${fixed(r[1], 2)}″` : 'none'}</b>${radii.length ? ` (members
    ${fixed(Math.min(...radii), 2)} – ${fixed(Math.max(...radii), 2)}″)` : ''}. Projected mass:</p>
    <ul id="ensemble-masses">${masses}</ul>${calibration}${crowded}
    <p class="hint">${ensemble.note}${maps ? ` The tab "Ensemble spread" shows κ's spread about this map; a click
    on the mass map reads out the magnification's 16th – 84th percentiles over the members.` : ''}</p>`;
  box.append(...buttons(), missing());
  box.hidden = false;
  const group = document.createElement('div');
  group.className = 'download-group';
  group.id = 'ensemble-downloads';
  group.innerHTML = `<h3>Ensemble of ${n} (FITS, HFF style; JSON; PNG)</h3>`;
  // The same files as under the views, with their own ids.
  for (const b of buttons()) {
    b.id = `${b.id}-panel`;
    group.append(b);
  }
  group.append(missing());
  const downloads = document.getElementById('downloads');
  downloads.insertBefore(group, downloads.lastElementChild);
}

// Page wiring: the worker client, the session's life cycle (example, files, project, runs,
// cancel, persistence) and the panels of js/*.js.

import { LensClient } from './lens-client.js';
import { loadProject, loadPrevious, saveProject, hasSaved, setAside, setAsideList, deleteSetAside } from './js/store.js';
import { buildFileRows, foldedList, setFileStatus, ROLES } from './js/files.js';
import { buildSettings, showSettings, showChoiceNote, fieldMessage } from './js/settings.js';
import { wireViews, showPng, showSystems, showCrossval, showStrengthChoice, viewOptions, currentView, refreshReadout, clearPin, pinAt } from './js/views.js';
import { showDownloads, save } from './js/downloads.js';
import { wireFigureDownload } from './js/figure-download.js';
import { StrengthPool, poolSize, projectForTrials } from './js/pool.js';
import { wireIterates, showIterates, syncIterates, iterateOption } from './js/iterates.js';
import { showVerdict } from './js/verdict.js';
import { wireLocate, locateExamples } from './js/coords.js';
import { runEnsemble, showEnsemble, ensembleCaption } from './js/ensemble.js';

// Offline use once loaded (sw.js), for the lessons and the playground too. Without it (an old
// browser, a file:// page) the app still works online.
if ('serviceWorker' in navigator) {
  navigator.serviceWorker.register('sw.js').catch(() => {});
}

// `?playground` and `?lesson=ID`: the live lensing playground (www/playground/) and its lessons
// instead of this app; the rest of this module then never runs. A first visit (no parameters,
// no project saved in this browser) opens the first lesson: something a newcomer understands,
// with the research app one click away (`?app`, or any of its parameters).
const route = new URLSearchParams(location.search);
let lessonsFirst = false;
if (!route.has('playground') && !route.has('lesson') && location.search === '') {
  lessonsFirst = !(await hasSaved());
  if (lessonsFirst) history.replaceState(null, '', `?lesson=lens-equation${location.hash}`);
}
if (lessonsFirst || route.has('playground') || route.has('lesson')) {
  await import('./playground/playground.js');
  await new Promise(() => {});
}

const $ = (id) => document.getElementById(id);
// Page parameters: `?example=ID` opens that built-in example (in the full app only when no
// project is saved in this browser, which it would replace); `?embed` is the compact demo for
// other pages' iframes: the example, Reconstruct and the views, nothing kept in the browser.
const params = new URLSearchParams(location.search);
const EMBED = params.has('embed');
if (EMBED) document.body.classList.add('embed');
let examples = [];
let resultKind = null; // kind of the shown result, null before any
let lastProject = null; // the worker's project.json after the last change (restored on cancel)
let settings = null;
// The session's name once your own files have replaced an example.
const OWN_DATA = 'Your data';
const NEW_PROJECT = 'New project';
// Files that failed to load while an earlier file of their role stayed in use: role ->
// {file, kept}. Said in the caption of the runs made meanwhile; a file of that role that loads,
// an example or a new project clears it.
const rejected = new Map();
// Files refused only for want of a Lenstool .par (the core's code 'wants-par'), by role: a
// member catalogue that reads as a .par's potfile (arcsec from its reference), arclets without
// a redshift (the .par's z_source gives them one). Read again once a .par loads (for members,
// one that names a potfile). An example, a project or a file of the role that loads forgets it.
const waitingForPar = new Map();

const client = new LensClient({ onCrash: (m) => showError(m), onRestart: restoreSession });
const ask = (type, payload = {}, onProgress) => client.request(type, payload, onProgress);

// Settings as the worker answered them, numbered in the order it did (`revision`), so that the
// form never shows an older answer over a newer one (answers are awaited in the worker's order).
let revision = 0;
async function askSettings(type, payload) {
  const answer = await ask(type, payload);
  answer.revision = ++revision;
  return answer;
}

function setStatus(text) { $('status').textContent = text; }
function showError(text) { $('error').textContent = text; $('error').hidden = false; }
function clearError() { $('error').hidden = true; $('error').textContent = ''; }

async function persist() {
  lastProject = await ask('textFile', { name: 'project.json' });
  if (EMBED) return null; // a demo in someone's page keeps nothing
  const problem = await saveProject(lastProject);
  if (problem) setStatus(problem);
  return problem;
}

async function refreshLoaded() {
  const loaded = await ask('loaded');
  $('reconstruct').disabled = !(loaded.images || loaded.arcs);
  // A .par with a potfile runs once its member catalogue is loaded (the status line says so).
  $('forward').disabled = !loaded.model || Boolean(loaded.missing_potfile);
  $('lookup').disabled = !(loaded.deflection_x && loaded.deflection_y);
  $('crossval').disabled = $('reconstruct').disabled;
  // Overlays with nothing to draw are greyed out (their choice is kept for when there is).
  $('show-members').disabled = !(loaded.members || loaded.model);
  $('show-model-curves').disabled = !loaded.model;
  showSkyWarnings(loaded.sky_warnings ?? []);
  // A refused file's predecessor that is gone (an example's file replaced by one's own
  // data) is no longer what runs are made with: nothing to say about it.
  for (const [role, { kept }] of rejected) if (loaded[role] !== kept) rejected.delete(role);
  return loaded;
}

/** Under the status line while the loaded files lie apart on the sky (files of different
 * clusters): the core's sentence per file, which names both files and their positions. */
function showSkyWarnings(warnings) {
  const box = $('sky-warning');
  box.replaceChildren();
  box.hidden = warnings.length === 0;
  if (!warnings.length) return;
  const head = document.createElement('strong');
  head.textContent = 'These files are of different parts of the sky. ';
  box.append(head, warnings.join(' '));
}

/** A sentence for the status line when the loaded files lie apart on the sky. */
function skyNote() {
  return $('sky-warning').hidden ? '' : ' But the files are of different parts of the sky (see below).';
}

/** What the loaded files allow, as the status line says it when nothing else is to be said. */
function readyText(loaded) {
  // A model file at another z_lens than the settings' would not be compared: said before the run.
  if (loaded.images || loaded.arcs) return `Ready: press Reconstruct.${loaded.model_z_lens_note ? ` But ${loaded.model_z_lens_note}.` : ''}`;
  if (loaded.model && loaded.missing_potfile) {
    const file = loaded.missing_potfile.split('/').pop();
    return `Load ${file}, the member catalogue ${loaded.model}'s potfile names, as the member catalogue: then press Forward model.`;
  }
  if (loaded.model) return 'Ready: press Forward model.';
  if (loaded.deflection_x && loaded.deflection_y) return 'Ready: press Deflection look-up.';
  if (loaded.deflection_x || loaded.deflection_y) return `Load the deflection ${loaded.deflection_x ? 'y' : 'x'} map too for the look-up.`;
  return 'Load an image catalogue or arcs to reconstruct (under Files), or open an example.';
}

/** No result on screen: caption, notes, downloads and the clicked point go with it. */
function showNoResult() {
  resultKind = null;
  $('summary').textContent = '';
  verdictBase = null;
  showVerdict(null);
  locateExamples(null);
  runNotes(null);
  showStrengthChoice(null);
  showChoiceNote(null);
  showIterates(null);
  showEnsemble(null, app);
  clearPin();
  $('downloads').innerHTML = '<p class="hint">Run something first.</p>';
}

/** The Example menu: a blank entry for one's own data, then every example (a playground
 * observation opened in this page is one too, added after the menu was first made). */
function fillExampleMenu() {
  $('example-select').innerHTML = '<option value="" disabled>(your data)</option>'
    + examples.map((e, k) => `<option value="${k}">${e.name}</option>`).join('');
}

function describe(name, text) {
  $('project-name').textContent = name;
  $('project-description').textContent = text;
  // The menu shows the example that is open, or its blank entry for anything else, so that
  // choosing any example (also the first) is a change that loads it.
  if ($('example-select').options.length !== examples.length + 1) fillExampleMenu();
  const k = examples.findIndex((e) => e.name === name);
  $('example-select').value = k >= 0 ? String(k) : '';
  // An example's model file is the true lens it was made from: legends say so.
  const truth = k >= 0 && examples[k].files.some((f) => f.role === 'model' && f.truth);
  document.body.dataset.truthModel = truth ? 'yes' : 'no';
  $('model-curves-label').textContent = truth ? 'true lens' : 'model curves';
}

async function render() {
  const view = currentView();
  try {
    if (view === 'systems') {
      showSystems(resultKind ? await ask('sources') : []);
      return;
    }
    const name = resultKind ? view : 'data';
    if (!resultKind && view !== 'kappa') {
      $('summary').textContent = 'Reconstruct (or run a forward model) to see this view.';
      $('view-image').hidden = true;
      return;
    }
    // The mass map of the iterate on the slider (js/iterates.js); the other views, the
    // downloads and the products are the result's.
    const options = name === 'kappa' ? { ...viewOptions(), ...iterateOption() } : viewOptions();
    const { png } = await ask('view', { name, options });
    showPng(name, png);
    // The data before any result: the figure's title says what it is; an earlier view's
    // message ("no catalogue is loaded") must not stay beside it.
    if (name === 'data') $('summary').textContent = '';
    syncIterates();
    // The read-out under a still cursor follows the new map (z_s, a new result).
    if (name === 'kappa') await refreshReadout();
  } catch (err) {
    $('view-image').hidden = true;
    $('summary').textContent = err.message;
  }
}

// The result's own verdict and what its box offers; the box shows the verdict that counts
// the cross-validation's held-out images while the cross-validation is on screen.
let verdictBase = null;
let verdictOffers = {};
let crossvalShown = false;

/** Shows the result's verdict, or, while a cross-validation is on screen, the one that counts
 * its held-out images (the core's; the result's own if it cannot give one). */
async function refreshVerdict() {
  let verdict = verdictBase;
  if (verdictBase && crossvalShown) {
    try {
      verdict = (await ask('verdict')) ?? verdictBase;
    } catch {
      verdict = verdictBase;
    }
  }
  showVerdict(verdict, verdictOffers);
}

function caption(info) {
  verdictBase = info.summary.verdict ?? null;
  verdictOffers = { fitRows: fitCommentedRows, modelGalaxies: info.model_galaxies ?? [], fitModel: fitModelGalaxies };
  showVerdict(verdictBase, verdictOffers);
  if (crossvalShown && verdictBase) refreshVerdict();
  const s = info.summary.maps ?? info.summary;
  // The solver, when it is not the paper's QADP.
  const best = info.summary.settings?.solver?.method === 'accelerated_gradient'
    ? ' of the accelerated gradient (the best fit, not QADP)' : '';
  const status = info.status ? `${info.status}, ${info.iterations} iterations${best}; ` : '';
  // A null map side: the tangential curve leaves every map measured, the radius is a lower bound.
  const bound = s.einstein_radius_map_arcsec === null ? '≥ ' : '';
  // A reconstruction's member factors C: 1 is the M/L of the settings. Where the data hardly
  // measure them (the grid can do what the members do), the start and the iteration count set
  // them, and the caption says so.
  const c = info.summary.c_per_layer ?? [];
  const unmeasured = info.summary.c_unmeasured ? ', which these data hardly measure (see the warnings)' : '';
  const factors = c.length ? `member factor C = ${c.map((v) => v.toFixed(2)).join(', ')}${unmeasured}; ` : '';
  // The tidal field of mass beyond the grid, fitted with the map (Lenstool's gamma, angle_pos).
  const xs = info.summary.external_shear;
  // Asked for but not fitted: the core says why (the least-mass regulariser fits none).
  const leftOut = info.summary.external_shear_left_out;
  const external = xs ? `external shear γ = ${xs.gamma.toFixed(3)} along ${xs.angle_deg.toFixed(0)}°; `
    : leftOut ? `no external shear (${leftOut}); ` : '';
  // Observed images against the predicted ones: the median (the typical image) and the rms
  // (which one image whose pair has merged can dominate); then the same for the held-out
  // systems: how well the model predicts images it was not given.
  const sum = info.summary;
  const offsetText = (what, median, rms) => (median == null || rms == null ? ''
    : `${what} median ${median.toFixed(2)}″, rms ${rms.toFixed(2)}″; `);
  const offsets = offsetText('image offsets', sum.image_offset_median_arcsec, sum.image_plane_rms_arcsec);
  const held = offsetText('held-out images:', sum.holdout_image_offset_median_arcsec,
    sum.holdout_image_plane_rms_arcsec);
  // Weak lensing: the arclets fitted and their reduced-shear chi^2 (about 2 per arclet at the
  // shape noise).
  const wl = sum.weak_lensing;
  const shear = wl ? `${wl.arclets} arclets, χ² ${wl.chi2_per_arclet.toFixed(2)} per arclet; ` : '';
  // A loaded model file that is not drawn next to a reconstruction says why.
  const note = info.model_note ? ` ${info.model_note}.` : '';
  const stale = [...rejected.values()].map(({ file, kept }) => ` Made with ${kept}: ${file} had errors and was not loaded.`).join('')
    + ($('sky-warning').hidden ? '' : ' Made with files of different parts of the sky (see the warning above).');
  // The main curve's alone, when the other loops (members', a neighbouring group's) add to it.
  const mainCurve = info.main_curve_arcsec == null ? '' : ` (the main curve alone ${info.main_curve_arcsec.toFixed(1)}″)`;
  // No tangential curve at all: a radius of 0″ would read as a measurement.
  const radius = s.einstein_radius_arcsec === 0 && s.einstein_radius_map_arcsec !== null
    ? `Einstein radius: none (no tangential critical curve at z_s = ${s.z_source}); `
    : `Einstein radius ${bound}${s.einstein_radius_arcsec.toFixed(1)}″ at z_s = ${s.z_source}${mainCurve}; `;
  $('summary').textContent = `${status}${radius}` +
    `${factors}${external}${offsets}${held}${shear}${s.tangential_curves} tangential and ${s.radial_curves} radial critical curves.${ensembleCaption(sum)}${note}${stale}`;
}

/** Under the views: the systems a run left out of the fit and its warnings (collapsed: a
 * member catalogue wider than the field gives one per member). Built from text nodes. */
function runNotes(summary) {
  const box = $('run-notes');
  box.replaceChildren();
  // summary.json's `systems_excluded`: "id (why)", the reason in words.
  const left = summary?.systems_excluded ?? [];
  if (left.length) {
    const p = document.createElement('p');
    p.id = 'left-out';
    p.textContent = `Left out of the fit: ${left.join(', ')}.`;
    box.append(p);
  }
  const warnings = summary?.warnings ?? [];
  if (warnings.length) {
    const details = foldedList(`${warnings.length} warning${warnings.length === 1 ? '' : 's'} from the run`, warnings);
    details.id = 'run-warnings';
    box.append(details);
  }
}

async function showResult(info) {
  resultKind = info.kind;
  caption(info);
  runNotes(info.summary);
  showStrengthChoice(info.summary?.strength_choice,
    (info.summary?.free_redshifts?.systems ?? []).map(([id]) => id),
    info.summary?.settings?.grid?.external_shear_sigma != null);
  showChoiceNote(info.summary?.strength_choice);
  showDownloads(info.kind, app);
  showIterates(info.kind === 'reconstruct' ? (await ask('iterates')).iterates : null);
  showEnsemble(info.summary?.ensemble_members ? await ask('ensembleInfo') : null, app);
  if (currentView() === 'spread' && $('tab-spread').hidden) $('tab-kappa').click();
  // The position box's examples at these data's sky reference.
  locateExamples(await app.pointReadout([0, 0]).catch(() => null));
}

// A job that runs (its status words) is noted in the tab's sessionStorage until it ends: a
// reload stops it, and the page that opens next says so (`sayInterrupted`).
const RUNNING_KEY = 'wslap.running';
const RUNNING_WORDS = {
  'Reconstructing…': 'a reconstruction',
  'Computing…': 'a computation',
  'Cross-validating…': 'a cross-validation',
};

function showProgress(on) {
  try {
    if (on) sessionStorage.setItem(RUNNING_KEY, $('status').textContent);
    else sessionStorage.removeItem(RUNNING_KEY);
  } catch { /* storage refused: nothing to say after a reload */ }
  $('progress-box').hidden = !on;
  $('cancel').hidden = !on;
  for (const id of ['reconstruct', 'forward', 'lookup', 'crossval']) $(id).disabled = on || $(id).disabled;
}

/** The progress bar at `k` of `total` units after `elapsed_ms`, with `words` and the time left. */
function progressAt(elapsedMs, k, total, words) {
  const frac = Math.min(1, k / total);
  const left = frac > 0 ? (elapsedMs / frac - elapsedMs) / 1000 : NaN;
  $('progress').value = frac;
  $('progress-text').textContent = `${words}, about ${Number.isFinite(left) ? left.toFixed(0) : '?'} s left`;
}

/** Runs `job(onProgress)` in the worker with the progress bar and Cancel shown: `status` while
 * it runs, `done(answer)` after it; a failure shows its message (a cancel says nothing here).
 * `position(p)` gives a progress report's `[done, total]` iterations and its words. */
async function inWorker(status, job, position, done) {
  clearError();
  setStatus(status);
  showProgress(true);
  $('progress').value = 0;
  $('progress-text').textContent = 'Building the linear system…';
  try {
    const answer = await job((p) => progressAt(p.elapsed_ms, ...position(p)));
    await done(answer);
  } catch (err) {
    if (err.cancelled) return;
    setStatus('Failed.');
    showError(err.message);
  } finally {
    showProgress(false);
    await refreshLoaded().catch(() => {});
  }
}

// The pool of an "auto" strength's candidates or of an ensemble's members while they run
// (Cancel closes it).
let pool = null;

function run(kind) {
  const total = settings?.reconstruct?.solver?.iterations ?? 1;
  const iterations = (p) => `iteration ${p.iteration} / ${total}, objective ${p.objective.toExponential(4)}`;
  // The wall time of an "auto" run: its candidates, then the reconstruction.
  const t0 = performance.now();
  return inWorker(kind === 'reconstruct' ? 'Reconstructing…' : 'Computing…',
    async (onProgress) => {
      const plan = kind === 'reconstruct' ? (await ask('strengthPlan')).plan : null;
      if (!plan) return ask('run', { kind }, onProgress);
      // The first round's map is a whole result: shown and kept while the choice is made again.
      return autoStrength(plan, total, onProgress, (first, estimated) => display(first,
        `Showing the map of the first choice; choosing again with the ${estimated} estimated redshift${
          estimated === 1 ? '' : 's'} fitted…`));
    },
    // A report of `autoStrength` carries its own position; the others are the solver's.
    (p) => (p.words ? [p.units, p.total, p.words] : [p.iteration, total, iterations(p)]),
    async (info) => {
      const wall = info.summary?.strength_choice?.candidates?.length ? performance.now() - t0 : info.elapsed_ms;
      await display(info, `Done in ${(wall / 1000).toFixed(2)} s.`);
      if (kind === 'reconstruct') await ensemble(wall);
    });
}

/** Shows the result `info`, draws it, saves it with the project, and only then says `status`
 * (with why it was not saved, if it was not): a status read as "this is the result" (the final
 * "Done", or the first round's map of an "auto" choice, which a Cancel keeps) comes when the
 * map is on screen and saved. */
async function display(info, status) {
  await showResult(info);
  await render();
  const problem = await persist();
  setStatus(problem ? `${status} The app ${problem}.` : status);
}

/** After a reconstruction that took `mainMs`, the ensemble the settings ask for (js/ensemble.js),
 * with the same progress bar and Cancel; the map stays usable meanwhile. */
async function ensemble(mainMs) {
  const total = settings?.reconstruct?.solver?.iterations ?? 1;
  const info = await runEnsemble({
    ask,
    iterations: total,
    onPool: (p) => { pool = p; },
    onProgress: (p) => progressAt(p.elapsed_ms, p.units, p.total, p.words),
  });
  if (!info) return;
  setStatus(`Done in ${(mainMs / 1000).toFixed(2)} s; ensemble of ${info.summary.ensemble_members} members in ${
    (info.ensemble_ms / 1000).toFixed(2)} s.`);
  await showResult(info);
  // The project keeps the ensemble: a reload or a restarted worker shows it again.
  await persist();
  await render();
}

/** Relative cost of trying `candidate`, its cells per side to the power 0.75, so that the time
 * left is not read from the cheap coarse-grid trials that run first. Measured on AS1063 gold
 * with the defaults (27 candidates, 2 workers; `node benches/app-eta.mjs`, BENCHMARKS.md): the
 * time left read with equal costs was 25% low (median over the run), with 0.75 +12% and +17%
 * in two runs; a power of 1.5 read +36 to +74% (with other work on the cores) and was not kept. */
const trialCost = (candidate) => (candidate?.cells ?? 32) ** 0.75;

/** An "auto" regulariser strength: each candidate of `plan` is cross-validated in a pool
 * worker (js/pool.js) on the main session's project, then the main worker reconstructs with
 * the strength their rows choose. When that run estimated redshifts, `showFirst(info,
 * estimated)` shows its map, the candidates are tried again with those systems fitted in every
 * fold (the core's second round; a Cancel then keeps the first map), and the main worker
 * keeps its map or fits the one they choose now. `onProgress` gets `{elapsed_ms, units, total,
 * words}`: the folds done of every candidate's folds, each weighted by its cost
 * (`trialCost`), plus each final solve (weighted as a fold of the costliest candidate); the
 * second round, when there is one, adds its own to the total as it starts. */
async function autoStrength(plan, iterations, onProgress, showFirst) {
  const t0 = performance.now();
  const trialsWork = plan.candidates.reduce((w, c) => w + plan.folds * trialCost(c), 0);
  const last = Math.max(...plan.candidates.map(trialCost));
  const project = projectForTrials(await ask('textFile', { name: 'project.json' }));
  const report = (units, total, words) => onProgress({ elapsed_ms: performance.now() - t0, units, total, words });
  const trials = await poolTrials(project, plan, (work, words) => report(work, trialsWork + last,
    `Choosing the regulariser: ${words}`));
  const info = await ask('runWithTrials', { trials, folds: plan.folds }, (p) => report(
    trialsWork + last * Math.min(1, p.iteration / iterations), trialsWork + last,
    `Reconstructing with the chosen strength: iteration ${p.iteration} / ${iterations}`));
  const { round } = await ask('secondStrengthRound');
  if (!round) return info;
  const first = trialsWork + last;
  const total = 2 * first;
  const estimated = round.estimates.z_estimates.length;
  await showFirst(info, estimated);
  const again = await poolTrials(project, round, (work, words) => report(first + work, total,
    `Choosing again with the ${estimated} estimated redshift${estimated === 1 ? '' : 's'} fitted: ${words}`),
  'Cancelled the second round of the choice: the map of the first choice is kept.');
  return ask('chooseAgainWithTrials', { trials: again }, (p) => report(
    first + trialsWork + last * Math.min(1, p.iteration / iterations), total,
    `Reconstructing with the strength chosen again: iteration ${p.iteration} / ${iterations}`));
}

/** The rows of every candidate of `plan` (`{candidates, folds, estimates?}`), tried in a new
 * pool on `project` (`projectForTrials`); `onProgress(work, words)` gets the weighted folds
 * done and what the workers are doing; `cancelledText`, what a Cancel says (if not the
 * default). Fails when the session's data or settings changed meanwhile (the rows would be of
 * another project). */
async function poolTrials(project, plan, onProgress, cancelledText) {
  const n = plan.candidates.length;
  const mine = new StrengthPool(poolSize(n));
  if (cancelledText) mine.cancelledText = cancelledText;
  pool = mine;
  let trials;
  try {
    trials = await mine.trials(project, plan, ({ done, work, running }) => {
      const at = [...running].map(([c, p]) => `${c} (${p ? `iteration ${p.iteration}` : 'starting'})`);
      const workers = `${mine.size} worker${mine.size === 1 ? '' : 's'}`;
      onProgress(work, `${done} of ${n} candidates done; ${
        at.length ? `${workers} trying ${at.join(', ')}` : `starting ${workers}`}`);
    }, trialCost);
  } finally {
    mine.close();
    if (pool === mine) pool = null;
  }
  // The rows are of the project the pool was given: the session must still be it.
  if (projectForTrials(await ask('textFile', { name: 'project.json' })) !== project) {
    throw new Error('The data or settings changed while the regulariser was being chosen: press Reconstruct again.');
  }
  return trials;
}

// The last cross-validation, shown until the data or a setting changes (it was made with them).
function clearCrossval() {
  showCrossval(null);
  if (crossvalShown) {
    crossvalShown = false;
    showVerdict(verdictBase, verdictOffers);
  }
}

function crossValidate() {
  const n = settings?.reconstruct?.solver?.iterations ?? 1;
  return inWorker('Cross-validating…',
    (onProgress) => ask('crossValidate', {}, onProgress),
    (p) => [(p.fold - 1) * n + p.iteration, p.folds * n, `fold ${p.fold} / ${p.folds}, iteration ${p.iteration} / ${n}`],
    async (cv) => {
      const seconds = cv.runs.reduce((t, r) => t + r.elapsed_ms, 0) / 1000;
      setStatus(`Cross-validated in ${seconds.toFixed(2)} s (${cv.runs.length} folds).`);
      const files = await ask('crossvalFiles');
      showCrossval(cv, () => save('crossval.json',
        new Blob([JSON.stringify(cv, null, 2)], { type: 'application/json' })), files);
      crossvalShown = true;
      await refreshVerdict();
      $('crossval-box').scrollIntoView({ block: 'nearest' });
    });
}

/** The core failed in the worker (`message` says how) and the client started a fresh one:
 * `send` puts the session as last saved (`lastProject`: its files, settings and result) back
 * into it before any other job; then the page shows it again. */
async function restoreSession(send, message) {
  showError(message);
  setStatus('The core failed; restoring your data…');
  let report = null;
  try {
    if (lastProject) report = await send('openProject', { text: lastProject, name: 'the session' });
  } finally {
    // Once the client is ready again, which waits for this function to return; also when the
    // project did not open (the page then shows the empty session it has).
    client.ready.then(async () => {
      await afterOpen(report);
      const result = report?.result === 'restored' || report?.result === 'recomputed';
      setStatus(!report ? 'Restarted after the failure, with an empty session.'
        : `Restarted after the failure: your files${result ? ', settings and last result' : ' and settings'} are back.`);
    }).catch((err) => showError(err.message));
  }
}

async function cancel() {
  // While the candidates run, the main worker waits with the session as it was (or, in the
  // second round of an "auto" choice and during an ensemble, with the result shown and saved):
  // stopping the pool is enough.
  if (pool) {
    const text = pool.cancelledText ?? 'Cancelled. The loaded data and the previous result are kept.';
    pool.close();
    pool = null;
    showProgress(false);
    setStatus(text);
    return;
  }
  client.cancel();
  showProgress(false);
  setStatus('Cancelled; restoring the session…');
  await client.ready;
  if (lastProject) await openProject(lastProject, 'the session', true);
  setStatus('Cancelled. The loaded data and the previous result are kept.');
}

// Shows the worker's settings after they changed there (an open, or leaving an example).
async function showSessionSettings() {
  settings = await askSettings('settings');
  showSettings(settings, { force: true });
  $('z-curves').value = settings.reconstruct.products.z_source;
}

async function afterOpen(report) {
  clearCrossval();
  await showSessionSettings();
  const loaded = await refreshLoaded();
  // Each file's line as when it was loaded by hand: its counts and warnings.
  const reports = new Map((report?.files ?? []).map((r) => [r.role, r]));
  for (const { role } of ROLES) {
    const r = reports.get(role);
    if (r && r.name === loaded[role]) showFileReport(role, r);
    else setFileStatus(role, loaded[role] ? `${loaded[role]}: loaded` : '');
  }
  rejected.clear();
  waitingForPar.clear();
  showNoResult();
  if (report?.result === 'restored' || report?.result === 'recomputed') await showResult(await ask('resultInfo'));
  await render();
  return loaded;
}

async function openProject(text, name, quiet = false) {
  const report = await ask('openProject', { text, name });
  if (!quiet) describe(report.name || name, `Project: ${report.message}.`);
  await afterOpen(report);
  lastProject = text;
  return report;
}

async function loadExample(ex) {
  clearError();
  await ask('reset');
  await ask('setName', { name: ex.name });
  await ask('setField', { path: 'z_lens', value: ex.z_lens });
  for (const [path, value] of Object.entries(ex.settings ?? {})) await ask('setField', { path, value });
  for (const f of ex.files) {
    const text = f.text ?? await (await fetch(`examples/${f.path}`)).text();
    await ask('loadText', { role: f.role, name: f.name ?? f.path.split('/').pop(), text });
  }
  describe(ex.name, ex.description);
  $('full-app').href = `./?example=${encodeURIComponent(ex.id)}`;
  const loaded = await afterOpen(null);
  await persist();
  setStatus(readyText(loaded));
}

/** `?from=playground`: the playground's "Invert with WSLAP+" left an observation in
 * sessionStorage (www/playground/observe.js). It opens as an example would (its files given as
 * text, its model the true lens), with a link back to the scene, and is reconstructed. False
 * when there is none (a reload after it was opened: the saved project opens instead). */
async function openFromPlayground() {
  const key = 'wslap.playground.observation';
  const text = sessionStorage.getItem(key);
  sessionStorage.removeItem(key);
  history.replaceState(null, '', location.pathname + (params.get('simd') ? `?simd=${params.get('simd')}` : ''));
  if (!text) return false;
  const handed = JSON.parse(text);
  const ex = { ...handed, id: 'playground', settings: Object.fromEntries(handed.settings) };
  // As a built-in example: legends call its model "the true lens", your own file replaces it.
  examples.push(ex);
  // What makes it one after a reload (the saved project holds its files): kept without them.
  try {
    localStorage.setItem(OBSERVED_KEY, JSON.stringify({ ...ex, files: ex.files.map(({ text: _, ...f }) => f) }));
  } catch { /* no storage: after a reload its model is called by its file name */ }
  await enqueue(() => loadExample(ex));
  backToPlayground(ex);
  await run('reconstruct');
  return true;
}

/** localStorage key of the last observation opened from the playground, without its files. */
const OBSERVED_KEY = 'wslap.playground.opened';

/** The last observation opened from the playground, as an example (its files without their
 * texts): a saved project of it reopens with its model as the true lens and the link back. */
function observedExample() {
  try {
    const ex = JSON.parse(localStorage.getItem(OBSERVED_KEY) ?? 'null');
    return ex?.id === 'playground' && typeof ex.name === 'string' && Array.isArray(ex.files) ? ex : null;
  } catch {
    return null;
  }
}

/** The link back to the playground scene `ex` was observed from, after its description. */
function backToPlayground(ex) {
  if (!ex.back || !String(ex.back).startsWith('./?playground')) return;
  $('back-to-playground')?.remove();
  const back = document.createElement('a');
  back.id = 'back-to-playground';
  back.href = ex.back;
  back.textContent = 'Back to the playground scene';
  $('project-description').append(' ', back);
}

// The example that is open (the session carries its name), if any.
function openExample() {
  return examples.find((e) => e.name === $('project-name').textContent);
}

// Your own file replaces the open example: the example's files of other roles are removed, and
// so are the settings it set that still have its values (settings you changed stay). Called
// after your file has loaded, so a bad file leaves the example as it was.
async function leaveExample(ex, role) {
  for (const f of ex.files) {
    if (f.role === role) continue;
    await ask('clear', { role: f.role });
    setFileStatus(f.role, '');
  }
  // In one job of the worker, so that a setting you change meanwhile is changed before or after
  // it, never in between (where it would be put back to its default).
  settings = await askSettings('resetSettings', { fields: Object.entries({ z_lens: ex.z_lens, ...ex.settings }) });
  await ask('setName', { name: OWN_DATA });
  describe(OWN_DATA, `Your files replace the example "${ex.name}": its other files and the ` +
    'settings it had set are gone (settings you changed stay). Check z_lens before you run.');
  // Not forced: an input whose change is on its way keeps it.
  showSettings(settings);
  $('z-curves').value = settings.reconstruct.products.z_source;
}

// A file's warnings quoted in its line (and the status line); the rest are listed under a
// "more" toggle beside the file, so that a file with hundreds does not make a page of them.
const INLINE_WARNINGS = 3;

/** The status line of a loaded file: its LoadReport's summary and its first warnings. */
function reportText(report) {
  const n = report.warnings.length;
  const rest = n - INLINE_WARNINGS;
  const quoted = report.warnings.slice(0, INLINE_WARNINGS).join('; ');
  const warn = n ? ` (${n} warning${n === 1 ? '' : 's'}: ${quoted}${rest > 0 ? `; ${rest} more listed below` : ''})` : '';
  return `${report.name}: ${report.summary}${warn}`;
}

/** Shows a loaded file's report beside it: `reportText`, then its other warnings folded. */
function showFileReport(role, report) {
  setFileStatus(role, reportText(report), false, report.warnings.slice(INLINE_WARNINGS));
}

async function onFile(role, file) {
  clearError();
  const example = role === 'project' ? undefined : openExample();
  try {
    let report;
    if (role === 'project') {
      report = await openProject(await file.text(), file.name);
      setFileStatus(role, `${file.name}: ${report.message}`);
      await persist();
      return;
    }
    if (role.startsWith('deflection')) {
      const bytes = await file.arrayBuffer();
      report = await ask('loadFits', { axis: role.endsWith('x') ? 0 : 1, name: file.name, bytes });
    } else {
      report = await ask('loadText', { role, name: file.name, text: await file.text() });
    }
    showFileReport(role, report);
    clearCrossval();
    if (example) {
      await leaveExample(example, role);
      // The example's result drew the example's data: it goes with them.
      await ask('clearResult');
      showNoResult();
    } else if ($('project-name').textContent === NEW_PROJECT) {
      // The new project has data now: its heading no longer says nothing is loaded.
      await ask('setName', { name: OWN_DATA });
      describe(OWN_DATA, 'Your files, with the settings below: check z_lens before you run.');
    }
    const loaded = await refreshLoaded();
    await persist();
    if (!resultKind) {
      await render();
      setStatus(readyText(loaded) + skyNote());
    } else if (skyNote()) setStatus(skyNote().trim().replace(/^But t/, 'T'));
    // A result stays on screen; the line no longer speaks of a file refused before this one.
    else setStatus(`Loaded ${reportText(report)}; the map shown was made before it.`);
  } catch (err) {
    // The file before it (if any) stays loaded: said next to the file, at the top of the
    // results and in the next run's caption, so that nobody takes a run on it for one on theirs.
    const kept = role === 'project' ? null : (await ask('loaded').catch(() => ({})))[role];
    // While an example is open its file is the one kept: the user never loaded it.
    const still = !kept ? '' : example ? ` The example "${example.name}" stays open as it was.`
      : ` Still using ${kept} loaded before.`;
    // A sentence of its own before the next one ("... (at most 10^6). Still using ...").
    const message = /[.!?]$/.test(err.message) ? err.message : `${err.message}.`;
    setFileStatus(role, `${message}${still ? `\n${still.trim()}` : ''}`, true);
    // The box names the file once ("x.cat was not loaded: line 2: ..."), not twice.
    const why = message.startsWith(`${file.name}: `) ? message.slice(file.name.length + 2) : message;
    showError(`${file.name} was not loaded: ${why}${still}`);
    setStatus(`${file.name} was not loaded (see the message below).`);
    if (kept) rejected.set(role, { file: file.name, kept });
    if (err.code === 'wants-par') waitingForPar.set(role, file);
    return;
  }
  rejected.delete(role);
  waitingForPar.delete(role);
  if (role === 'model' && waitingForPar.size) await readAgainForPar(file.name);
}

/** What a file refused for want of a .par is read as once `par` is loaded. */
const READ_WITH_PAR = {
  members: (par) => `as the member catalogue of ${par}'s potfile`,
  shear: (par) => `with the redshift ${par} gives arclets without one`,
};

/** The files refused for want of a .par, read again now that the model file `par` is one (a
 * member catalogue only when the .par names a potfile); the status line says which load. */
async function readAgainForPar(par) {
  const loaded = await ask('loaded');
  if (!loaded.model_is_par) return;
  const read = [];
  for (const [role, file] of [...waitingForPar]) {
    if (role === 'members' && !loaded.missing_potfile) continue;
    waitingForPar.delete(role);
    await onFile(role, file);
    if ((await ask('loaded'))[role] === file.name) read.push(`${file.name} ${READ_WITH_PAR[role](par)}`);
  }
  if (read.length) {
    setStatus(`Refused before ${par} was loaded, now read: ${read.join('; ')}. ${$('status').textContent}`);
  }
}

// Files and examples are opened one at a time, in the order they came (a drop of several
// files, a picker or the example menu used while a file still loads): each must see what the
// one before it left. Two files at once both saw the example open, and each one's leaveExample
// cleared the file the other had just loaded.
let openQueue = Promise.resolve();
function enqueue(task) {
  openQueue = openQueue.then(task).catch((err) => showError(err.message));
  return openQueue;
}
function queueFile(role, file) { return enqueue(() => onFile(role, file)); }

/** Starts over with nothing loaded and the default settings; the status line offers to undo
 * it (the project as it was is kept in memory until the page closes). */
async function newProject() {
  let before = null;
  await enqueue(async () => {
    before = lastProject;
    clearError();
    await ask('reset');
    await ask('setName', { name: NEW_PROJECT });
    describe(NEW_PROJECT, 'Nothing loaded yet: add your catalogues under "Files", or pick an example.');
    const loaded = await afterOpen(null);
    await persist();
    setStatus(readyText(loaded));
  });
  offerUndo(before, 'undo-new-project', 'Undo New project');
}

/** Opens the example `ex` from the menu. When it replaces one's own project (not an example,
 * which the menu gives back, nor an empty new project), the status line offers to go back to
 * it: its files, settings and result are kept in memory until the page closes. */
async function pickExample(ex) {
  let before = null;
  let name = '';
  await enqueue(async () => {
    name = $('project-name').textContent;
    if (!openExample() && name !== NEW_PROJECT) before = lastProject;
    await loadExample(ex);
  });
  offerUndo(before, 'undo-example', `Undo: back to "${name}"`);
}

/** Appends to the status line a button `id` that reopens `before` (a project.json), unless
 * there was none. */
function offerUndo(before, id, label) {
  if (!before) return;
  const undo = document.createElement('button');
  undo.type = 'button';
  undo.id = id;
  undo.className = 'link';
  undo.textContent = label;
  undo.addEventListener('click', () => enqueue(async () => {
    const report = await openProject(before, 'the previous project');
    await persist();
    setStatus(`Back to the project as it was${report.message ? `: ${report.message}` : ''}.`);
  }));
  $('status').append(' ', undo);
}

/** The verdict's offer: the member catalogue's commented-out rows `[{line, id}]` (the BCGs a
 * Lenstool set-up models in its .par, one per core) become members, and the reconstruction
 * runs again. */
async function fitCommentedRows(rows) {
  const ids = rows.map((r) => r.id).join(', ');
  await changeThenReconstruct(`Member${rows.length > 1 ? 's' : ''} ${ids} ${rows.length > 1 ? 'were' : 'was'} not fitted`, async () => {
    const report = await ask('uncommentMembers', { lines: rows.map((r) => r.line) });
    showFileReport('members', report);
    clearCrossval();
    await refreshLoaded();
    await persist();
  });
}

/** The verdict's other offer: the galaxies the loaded .par models on its own (its BCG) are
 * fitted as members from now on (the setting shows it), and the reconstruction runs again. */
async function fitModelGalaxies() {
  await changeThenReconstruct("The .par's galaxies were not fitted", async () => {
    await applySetting('members_from_model', true);
    showSettings(settings);
  });
}

/** Runs `change` in the file queue, then reconstructs; if it fails, says so after `failed`
 * and does not run. */
async function changeThenReconstruct(failed, change) {
  let changed = false;
  await enqueue(async () => {
    clearError();
    try {
      await change();
      changed = true;
    } catch (err) {
      showError(`${failed}: ${err.message}`);
    }
  });
  if (changed) await run('reconstruct');
}

async function applySetting(path, value) {
  if (path === 'reconstruct.products.z_source') return setZ(value);
  settings = await askSettings('setField', { path, value });
  clearCrossval();
  // A DS9 region file's arc pixels follow the constraint pixel: say how many there are now.
  if (path === 'reconstruct.constraints.pixel_arcsec') {
    const report = await ask('reload', { role: 'arcs' });
    if (report) showFileReport('arcs', report);
  }
  // A Lenstool model is read again with the single-plane setting (its warnings name the
  // blocks moved; turned off, a multi-plane model is refused and says so).
  if (path === 'lenstool_single_plane') {
    try {
      const report = await ask('reload', { role: 'model' });
      if (report) showFileReport('model', report);
    } catch (err) {
      setFileStatus('model', err.message);
    }
  }
  // The status line's "Ready" follows z_lens: its note on a model at another z_lens goes or comes.
  if (path === 'z_lens' && /^Ready/.test($('status').textContent)) setStatus(readyText(await refreshLoaded()) + skyNote());
  await persist();
  return settings;
}

async function setZ(z) {
  settings = await askSettings('setZSource', { z });
  $('z-curves').value = z;
  showSettings(settings);
  if (resultKind) {
    caption(await ask('resultInfo'));
    await render();
  }
  await persist();
  return settings;
}

const app = {
  render,
  hover: (x, y) => ask('hover', { options: { ...viewOptions(), ...iterateOption() }, x, y }),
  pointReadout: ([x, y]) => ask('pointReadout', { options: { ...viewOptions(), ...iterateOption() }, x, y }),
  counterImages: ([x, y]) => ask('counterImages', { x, y }),
  counterImageRegions: ([x, y]) => ask('counterImageRegions', { x, y }),
  textFile: (name) => ask('textFile', { name }),
  fitsFile: async (name) => (await ask('fitsFiles')).find((f) => f.name === name).bytes,
  viewPng: async (name, extra = {}) => (await ask('view', { name, options: { ...viewOptions(), ...extra } })).png,
  ensembleFiles: () => ask('ensembleFiles'),
  showError,
};

async function start() {
  buildFileRows($('file-rows'), $('drop-zone'), queueFile);
  buildSettings($('settings-form'), applySetting);
  wireViews(app);
  wireLocate({ locate: (text) => ask('locate', { text }), pinAt });
  wireIterates(app);
  wireFigureDownload(app);
  $('reconstruct').addEventListener('click', () => run('reconstruct'));
  $('forward').addEventListener('click', () => run('forward'));
  $('lookup').addEventListener('click', () => run('lookup'));
  $('crossval').addEventListener('click', crossValidate);
  $('new-project').addEventListener('click', newProject);
  $('cancel').addEventListener('click', cancel);
  $('scale').addEventListener('change', render);
  for (const id of ['show-members', 'show-observed', 'show-predicted', 'show-model-curves']) $(id).addEventListener('change', render);
  $('z-curves').addEventListener('change', async () => {
    try { await setZ(Number($('z-curves').value)); $('z-curves-error').textContent = ''; } catch (err) {
      $('z-curves-error').textContent = fieldMessage(err.message, 'reconstruct.products.z_source');
      $('z-curves').value = settings?.reconstruct?.products?.z_source ?? 2;
    }
  });
  try {
    examples = (await (await fetch('examples/index.json')).json()).examples;
  } catch (err) {
    showError(`could not read the examples: ${err.message}`);
  }
  fillExampleMenu();
  $('example-select').addEventListener('change', () => pickExample(examples[$('example-select').value]));
  const { version, simd } = await client.ready;
  setStatus(`Worker ready (wslap ${version}).`);
  $('core-info').textContent = `Core: wslap ${version}, WebAssembly with ${
    simd === 'relaxed' ? 'relaxed SIMD (fused multiply-add)' : 'SIMD'}.`;
  const wanted = params.get('example');
  const linked = examples.find((e) => e.id === wanted);
  // Said after the fallback has opened (opening an example clears the error line).
  const unknown = () => {
    if (wanted !== null && !linked) showError(`no built-in example "${wanted}" (there are: ${examples.map((e) => e.id).join(', ')})`);
  };
  if (params.get('from') === 'playground' && await openFromPlayground()) return;
  const observed = observedExample();
  if (observed) examples.push(observed);
  const restored = EMBED ? null : await openSaved();
  if (!EMBED) await showSetAside();
  if (restored && observed && $('project-name').textContent === observed.name) backToPlayground(observed);
  if (restored) {
    const link = linked ? ` (the link's example, "${linked.name}", is in the Example menu)` : '';
    setStatus(restored === 'current' ? `Restored your project from this browser${link}.`
      : `Restored the copy of your project saved before the last one, which did not open (it is kept, see below)${link}.`);
    sayInterrupted();
    unknown();
    return;
  }
  const first = linked ?? examples[0];
  if (first) await loadExample(first);
  if (!$('set-aside').hidden) setStatus(`Your saved project did not open; it is kept (see below). Opened the example "${first?.name}".`);
  sayInterrupted();
  unknown();
}

/** After a reload that stopped a job (`RUNNING_KEY`), adds to the status line what stopped. */
function sayInterrupted() {
  let words = null;
  try {
    words = sessionStorage.getItem(RUNNING_KEY);
    sessionStorage.removeItem(RUNNING_KEY);
  } catch { return; }
  if (words == null) return;
  const what = RUNNING_WORDS[words] ?? 'a run';
  setStatus(`${$('status').textContent} The page was reloaded during ${what}, which stopped unfinished: start it again when you like.`);
}

/** Opens the project kept in this browser: its last copy, else the one saved before it. A copy
 * that does not open (corrupt, cut short, saved by a newer version) is set aside with the
 * reason, never dropped (js/store.js). Returns which copy opened ('current' or 'previous'), or
 * null when none did. */
async function openSaved() {
  for (const [which, read] of [['current', loadProject], ['previous', loadPrevious]]) {
    const text = await read();
    if (text == null) continue;
    try {
      if (typeof text !== 'string') throw new Error('saved project: it is not text');
      await openProject(text, 'saved project');
      return which;
    } catch (err) {
      // The copy stays where it was if the browser refuses to move it: never dropped.
      await setAside(which, err.message);
    }
  }
  return null;
}

/** Lists the projects set aside (js/store.js) above the views: what happened, that the copy is
 * kept, a download and a delete for each. */
async function showSetAside() {
  const box = $('set-aside');
  const entries = await setAsideList();
  box.replaceChildren();
  box.hidden = entries.length === 0;
  for (const e of entries) {
    const day = e.at.slice(0, 10);
    const row = document.createElement('div');
    row.className = 'set-aside-entry';
    const text = document.createElement('p');
    const head = document.createElement('strong');
    head.textContent = 'A project saved in this browser could not be opened';
    // A copy cut short (a crash in the middle of a save, in an older version) says so first.
    const cut = /EOF while parsing|ends too early/.test(e.reason) ? 'it was cut short while it was saved: ' : '';
    const why = cut + e.reason.replace(/^saved project: /, '');
    text.append(head, ` (found on ${day}): ${why}. It was set aside, not deleted: download it to keep it (e.g. to open it with the version that saved it, or to send it with a bug report), or delete it.`);
    const name = `wslap-project-set-aside-${e.at.replace(/[:.]/g, '-')}.json`;
    const download = document.createElement('button');
    download.type = 'button';
    download.className = 'secondary';
    download.textContent = 'Download it';
    download.addEventListener('click', () => save(name, new Blob([e.text], { type: 'application/json' })));
    const remove = document.createElement('button');
    remove.type = 'button';
    remove.className = 'secondary';
    remove.textContent = 'Delete it';
    remove.addEventListener('click', async () => {
      await deleteSetAside(e.id);
      await showSetAside();
    });
    const buttons = document.createElement('div');
    buttons.className = 'buttons small';
    buttons.append(download, remove);
    row.append(text, buttons);
    box.append(row);
  }
}

start().catch((err) => showError(err.message));

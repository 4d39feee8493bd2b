// The result views: tabs, PNGs from the worker shown through blob URLs (decoded off the main
// thread), the hover/click read-out on the mass map (its texts: js/coords.js); the per-system
// table is drawn by js/systems-table.js.

import { button, save } from './downloads.js';
import { offsetsCell, showSystems } from './systems-table.js';
import { readoutText, counterImagesText } from './coords.js';

export { showSystems };

const img = () => document.getElementById('view-image');
let current = 'kappa';
let url = null;
let renders = 0; // views shown so far: `data-render` on the image tells a new drawing from an old one
const pngs = {}; // view name -> Blob, for downloads
let app = null; // renders views and answers hovers (set by wireViews)
let point = null; // { x, y, pin }: PNG pixels of the kappa view last hovered or clicked
let pin = null; // [x, y] arcsec last clicked on the kappa map: its source's images are drawn and listed
let busy = false; // a hover question is on its way
let queued = false; // ask again when it is answered (the cursor moved or the map changed)

/** Asks for the read-out at `point` and shows it; one question at a time, the latest wins. An
 * answer that arrives after another view was chosen is dropped: the read-out is of the mass
 * map, and the tab switch has cleared it. */
async function readOut() {
  if (!point) return;
  if (busy) { queued = true; return; }
  busy = true;
  const { x, y, pin } = point;
  const readout = document.getElementById('readout');
  try {
    const h = await app.hover(x, y);
    if (h && current === 'kappa') {
      const text = readoutText(h);
      readout.textContent = pin ? `Clicked: ${text}` : text;
    }
  } catch { /* the worker is busy with a run or was restarted */ }
  busy = false;
  if (queued) { queued = false; await readOut(); }
}

/** The read-out at the pinned point when it was typed, not clicked (no cursor is over it). */
async function readPin() {
  const readout = document.getElementById('readout');
  let text;
  try {
    text = `Typed: ${readoutText(await app.pointReadout(pin))}`;
  } catch (err) {
    text = `Typed: ${err.message}`;
  }
  // Another view may have been chosen while the worker answered (see readOut).
  if (current === 'kappa') readout.textContent = text;
}

/** Lists the images of the pinned point's source (or hides the list). */
async function listCounterImages() {
  const box = document.getElementById('counter-images');
  if (!pin) {
    box.replaceChildren();
    box.hidden = true;
    return;
  }
  let text;
  try {
    text = counterImagesText(await app.counterImages(pin));
  } catch (err) {
    text = `The clicked point: ${err.message}.`;
  }
  const p = document.createElement('span');
  p.id = 'counter-images-text';
  p.textContent = `${text} `;
  const clear = button('Clear', 'clear-pin', () => { pin = null; listCounterImages(); app.render(); }, 'link');
  const reg = button('counter-images.reg', 'dl-counter-images-reg', () => app.counterImageRegions(pin)
    .then((t) => save('counter-images.reg', new Blob([t], { type: 'text/plain' })), (err) => app.showError(err.message)), 'link');
  reg.title = 'The clicked point and its source\'s images as DS9 regions, to lay over the cluster image';
  box.replaceChildren(p, reg, document.createTextNode(' · '), clear);
  box.hidden = false;
}

/** Pins the point `[x, y]` (arcsec) as a click there would: its read-out, its source's
 * images listed and drawn (a typed position, js/coords.js). */
export async function pinAt(p) {
  pin = p;
  point = null;
  await app.render();
}

/** Forgets the clicked point and the read-out: they belong to maps that are gone (another
 * example or project was opened). */
export function clearPin() {
  pin = null;
  point = null;
  document.getElementById('readout').textContent = '';
  listCounterImages();
}

/** Reads out again at the last point, e.g. after z_s changed: μ depends on it; so do the
 * clicked point's images, which are listed again. */
export async function refreshReadout() {
  if (img().dataset.view !== 'kappa') return;
  if (point) await readOut();
  else if (pin) await readPin();
  await listCounterImages();
}

export function viewOptions() {
  const on = (id) => document.getElementById(id).checked;
  return {
    scale: document.getElementById('scale').value,
    show_members: on('show-members'),
    show_observed: on('show-observed'),
    show_predicted: on('show-predicted'),
    show_model_curves: on('show-model-curves'),
    model_is_truth: document.body.dataset.truthModel === 'yes',
    pin_arcsec: pin,
  };
}

export function currentView() { return current; }
export function viewBlob(name) { return pngs[name] ?? null; }

function selectTab(name) {
  current = name;
  for (const tab of document.querySelectorAll('[role=tab]')) {
    tab.setAttribute('aria-selected', String(tab.dataset.view === name));
    tab.tabIndex = tab.dataset.view === name ? 0 : -1;
  }
  // The colour scale and the "Show" boxes belong to the mass map (and the data before a run);
  // the other views ignore them, so they are greyed out there. So is the read-out, which is of
  // the mass map.
  const map = name === 'kappa';
  document.getElementById('scale').disabled = !map;
  document.getElementById('show-options').disabled = !map;
  if (!map) document.getElementById('readout').textContent = '';
  document.getElementById('counter-images').hidden = !map || !pin;
}

/** Shows PNG `bytes` as the view `name`. */
export function showPng(name, bytes) {
  const blob = new Blob([bytes], { type: 'image/png' });
  pngs[name] = blob;
  if (url) URL.revokeObjectURL(url);
  url = URL.createObjectURL(blob);
  const el = img();
  el.src = url;
  el.alt = { kappa: 'Convergence map with critical curves', data: 'The loaded data',
    source: 'Source plane with caustics', radial: 'Radial profile', convergence: 'Solver progress: objective, grid mass and C against iteration',
    spread: 'Standard deviation of the ensemble\'s convergence with the critical curves' }[name] ?? name;
  el.dataset.view = name;
  el.dataset.render = String(++renders);
  el.hidden = false;
  document.getElementById('systems').hidden = true;
  document.getElementById('figure').hidden = false;
}

/** `text` (a system or image id from a user's file) safe inside HTML. */
const esc = (text) => String(text).replace(/[&<>"']/g, (c) => `&#${c.charCodeAt(0)};`);

/** A number with `d` decimals, or a dash when there is none. */
const fmt = (v, d = 2) => (v == null ? '–' : Number(v).toFixed(d));

/** A candidate's grid of `cells` a side, in words. */
const grid = (cells) => `${esc(cells)} × ${esc(cells)} cells`;

/** The curve an "auto" regulariser strength was chosen from (summary.json's
 * `strength_choice`): per candidate strength (and regulariser, when several were tried) the
 * held-out images' median and rms offsets from their predictions, with a bar for the median,
 * and the fitted images' median; the chosen row is marked. `null` (or a choice without
 * candidates) hides it. `estimated`: ids of the systems whose redshift the run estimated
 * (summary.json's `free_redshifts`), which the candidates' folds do not hold. `shear`: the
 * settings ask for an external shear, whose fit the least-mass (density) regulariser leaves out. */
export function showStrengthChoice(choice, estimated = [], shear = false) {
  const box = document.getElementById('strength-box');
  const rows = choice?.candidates ?? [];
  if (!rows.length) {
    box.replaceChildren();
    box.hidden = true;
    return;
  }
  const medians = rows.map((r) => r.holdout_median_arcsec).filter((v) => v != null);
  const top = Math.max(...medians, 1e-9);
  const unmatched = rows.some((r) => r.holdout_unmatched > 0);
  // The regulariser and the grid in the candidate's name when several were tried.
  const kinds = new Set(rows.map((r) => r.regulariser).filter((k) => k != null));
  const byKind = kinds.size > 1;
  const grids = new Set(rows.map((r) => r.cells).filter((c) => c != null));
  const byGrid = grids.size > 1;
  // Two candidates are the same when their strengths are and their regulariser and grid, where
  // both say one (results saved before those were candidates do not).
  const same = (a, b) => a.strength === b.strength
    && (a.regulariser == null || b.regulariser == null || a.regulariser === b.regulariser)
    && (a.cells == null || b.cells == null || a.cells === b.cells);
  const isChosen = (r) => same(r, { strength: choice.chosen, regulariser: choice.chosen_regulariser, cells: choice.chosen_cells });
  const bar = (v) => `<span class="bar-track" aria-hidden="true">${v == null ? ''
    : `<span class="bar" style="width:${(100 * v / top).toFixed(1)}%"></span>`}</span>`;
  const mark = ' <span class="mark">✓ chosen</span>';
  // Candidates that predicted best but whose maps were crowded, passed over (the core's
  // avoid_crowded_map).
  const passed = choice.crowded_maps ?? [];
  const passedOf = (r) => passed.find((p) => same(p, r));
  const body = rows.map((r) => {
    const chosen = isChosen(r);
    const crowded = passedOf(r);
    // The candidate: its strength, after its regulariser and before its grid when several were tried.
    const name = `${byKind ? `${esc(r.regulariser)} ` : ''}${esc(r.strength)}${byGrid && r.cells != null ? `, ${grid(r.cells)}` : ''}`;
    return `<tr${chosen ? ' class="chosen"' : ''} data-strength="${esc(r.strength)}" data-regulariser="${esc(r.regulariser ?? '')}" data-cells="${esc(r.cells ?? '')}">
      <th scope="row">${name}${chosen ? mark : ''}${crowded ? ` <span class="mark passed">crowded map: ${
  crowded.crowded_systems} of ${crowded.systems} systems, passed over</span>` : ''}</th>
      <td><span class="bar-cell"><span class="value">${fmt(r.holdout_median_arcsec)}</span>${bar(r.holdout_median_arcsec)}</span></td>
      <td>${fmt(r.holdout_rms_arcsec)}</td><td>${fmt(r.fit_median_arcsec)}</td>${
  unmatched ? `<td>${r.holdout_unmatched}</td>` : ''}</tr>`;
  }).join('');
  const what = (byKind && choice.chosen_regulariser != null
    ? `${esc(choice.chosen_regulariser)} at strength ${esc(choice.chosen)}` : `strength ${esc(choice.chosen)}`)
    + (byGrid && choice.chosen_cells != null ? ` on ${grid(choice.chosen_cells)}` : '');
  const tried = [byKind && 'regulariser', 'strength', byGrid && 'grid'].filter(Boolean);
  box.innerHTML = `<h3>Regulariser ${what}, chosen by cross-validation</h3>
    <p id="strength-summary">The ${tried.length > 1 ? `${tried.slice(0, -1).join(', ')} and ${tried.at(-1)}` : 'strength'} whose held-out images were
    predicted best${passed.length ? ', crowded maps passed over (below)' : ''}. Each candidate was tried over ${choice.folds} folds: every fold fits the lens without some of
    the systems and predicts their images, so the held-out offsets say how well the map finds images it was not
    given (smaller is better), while the fitted median says how closely it reproduces those it was given.
    Offsets from the predictions in arcsec${unmatched ? '; unmatched: held-out images with no predicted image, which count first' : ''}.${
  shear && kinds.has('density') ? ` The least-mass regulariser (density) is fitted without the external shear:
    it charges the map for its mass and the shear for nothing, and would trade the one for the other.` : ''}${
  estimatedNote(choice, estimated, byKind, byGrid)}${passed.length ? ` ${passed.length === 1 ? 'One candidate' : `${passed.length} candidates`}
    that predicted better ${passed.length === 1 ? 'was' : 'were'} passed over: ${passed.length === 1 ? 'its map predicts' : 'their maps predict'}
    more than twice as many images as observed for more than a third of the systems. Such a map's critical curves wind
    through the images' region, and a crowd of predicted images always has one near a held-out image, which flatters its
    offsets; the verdict would not trust its small scales, so the next candidates in order were fitted (at most three)
    and the first map that is not crowded was used, else the least crowded.` : ''}</p>
    <div class="table-scroll"><table id="strength-table">
    <thead><tr><th scope="col">${byKind || byGrid ? 'candidate' : 'strength'}</th><th scope="col">held-out median</th>
    <th scope="col">held-out rms</th><th scope="col">fitted median</th>${unmatched ? '<th scope="col">unmatched</th>' : ''}</tr></thead>
    <tbody>${body}</tbody></table></div>`;
  box.hidden = false;
}

/** What the strength choice's caption says of the systems whose redshift was estimated
 * (`estimated`, ids): with a second round (`choice.before_estimates`), that the candidates
 * were tried again with them fitted in every fold, and what the first round had chosen. */
function estimatedNote(choice, estimated, byKind, byGrid) {
  if (!estimated.length) return '';
  const one = estimated.length === 1;
  const which = `${one ? 'System' : 'Systems'} ${estimated.map(esc).join(', ')}`;
  const first = choice.before_estimates;
  if (!first) {
    return ` ${which} had no redshift and ${one ? 'is' : 'are'} not in these folds (the redshift is estimated on the
      chosen map), so these offsets come from fewer systems than the result and its cross-validation.`;
  }
  const same = first.strength === choice.chosen && first.regulariser === choice.chosen_regulariser
    && first.cells === choice.chosen_cells;
  const named = `${byKind ? `${esc(first.regulariser)} at strength ` : 'strength '}${esc(first.strength)}${
    byGrid && first.cells != null ? ` on ${grid(first.cells)}` : ''}`;
  return ` ${which} had no redshift: ${one ? 'its redshift was' : 'their redshifts were'} estimated on the map the
    systems with one chose (${named}), then every candidate was tried again with ${one ? 'it' : 'them'} fitted in
    every fold at ${one ? 'that redshift' : 'those redshifts'}, as the map fits ${one ? 'it' : 'them'}, and only the
    others held out: these are the offsets of that second round, ${same ? 'which chose the same' : 'which chose this one instead'}.`;
}

// The object URL of the cross-validation's spread figure on screen (revoked when it goes).
let spreadUrl = null;

/** The cross-validation (crossval.json) under the views: the held-out images' offsets against
 * the fitted ones', per predicted system its fold and image offsets, and the folds' convergence
 * maps from `files` (`{name, bytes}`: the spread as a figure, the maps as FITS); `null` hides
 * it. */
export function showCrossval(cv, onDownload, files = []) {
  const box = document.getElementById('crossval-box');
  if (spreadUrl) URL.revokeObjectURL(spreadUrl);
  spreadUrl = null;
  if (!cv) {
    box.replaceChildren();
    box.hidden = true;
    return;
  }
  const cancelled = cv.status === 'Cancelled' ? ` Cancelled after ${cv.runs.length} of ${cv.folds} folds.` : '';
  const fixed = cv.always_fitted ?? [];
  const always = fixed.length
    ? ` ${fixed.length === 1 ? 'System' : 'Systems'} ${fixed.map(esc).join(', ')}, whose redshift the reconstruction estimated,
      ${fixed.length === 1 ? 'is' : 'are'} fitted in every fold at that redshift and not predicted.` : '';
  const unmatched = cv.holdout_images_unmatched
    ? ` ${cv.holdout_images_unmatched} of ${cv.holdout_images} held-out images had no predicted image.` : '';
  const span = (values, d) => {
    const lo = Math.min(...values);
    const hi = Math.max(...values);
    return lo === hi ? fmt(lo, d) : `${fmt(lo, d)} – ${fmt(hi, d)}`;
  };
  const runs = cv.runs;
  const thetas = runs.map((r) => r.einstein_radius_arcsec);
  const layers = runs.length ? runs[0].c.length : 0;
  const factors = [...Array(layers).keys()].map((l) => span(runs.map((r) => r.c[l]), 2));
  // The folds' projected mass inside each summary radius that every fold's map holds.
  const massSpan = (values) => {
    const [lo, hi] = [Math.min(...values), Math.max(...values)].map((v) => v.toExponential(2).replace('e+', 'e'));
    return lo === hi ? lo : `${lo} – ${hi}`;
  };
  const masses = runs.length < 2 ? [] : (runs[0].mass_within_arcsec ?? [])
    .map(([r], k) => [r, runs.map((run) => run.mass_within_arcsec?.[k]?.[1])])
    .filter(([, values]) => values.every((m) => Number.isFinite(m)))
    .map(([r, values]) => `within ${fmt(r, 0)}″ ${massSpan(values)} M☉`);
  const spread = runs.length < 2 ? '' : ` Across the folds the Einstein radius at z_s = ${runs[0].einstein_radius_z_source} is
    ${span(thetas, 1)}″${factors.length ? ` and the member factor C is ${factors.join(', ')}` : ''}: how much the answer
    depends on which systems are fitted.${masses.length ? ` Their projected mass: ${masses.join('; ')}.` : ''}`;
  // With an "auto" strength each fold chose again on its own systems (crossval.json's `chosen`),
  // passing over crowded maps as the run does.
  const choices = new Map();
  for (const r of runs.filter((r) => r.chosen)) {
    const c = r.chosen;
    const key = `${esc(c.regulariser)} ${esc(c.strength)}${c.cells != null ? ` on ${grid(c.cells)}` : ''}`;
    choices.set(key, (choices.get(key) ?? 0) + 1);
  }
  const passedOver = runs.filter((r) => r.crowded_maps?.length).length;
  const chose = choices.size ? ` With the "auto" strength each fold chose again on its own systems: ${[...choices]
    .map(([key, n]) => `${key} (${n} ${n === 1 ? 'fold' : 'folds'})`).join(', ')}${passedOver ? `; ${passedOver} of
    ${runs.length} passed over a crowded map first, as the reconstruction does` : ''}.` : '';
  const rows = cv.systems.map((s) => `<tr><th scope="row">${esc(s.id)}</th><td>${s.fold}</td><td>${fmt(s.z, 3)}</td>
    ${offsetsCell(s.observed)}
    <td>${fmt(s.image_plane_rms_arcsec)}</td></tr>`).join('');
  box.innerHTML = `<h3>Cross-validation, ${cv.folds} folds</h3>
    <p id="crossval-summary">Each fold reconstructs the lens without one group of the systems and predicts
    that group's images, so every system is predicted once by a lens that never saw it. Held-out images lie ${fmt(cv.holdout_image_offset_median_arcsec)}″ from
    their predictions (median; rms ${fmt(cv.holdout_image_plane_rms_arcsec)}″), the fitted ones
    ${fmt(cv.fit_image_offset_median_arcsec)}″: the first says how well these settings find images the model
    was not given.${spread}${chose}${always}${unmatched}${cancelled}</p>
    <details id="crossval-systems"><summary>Per system (${cv.systems.length})</summary>
    <p class="table-caption" id="crossval-caption">Per held-out system: the fold that left it out, its redshift, each
    observed image's offset from the nearest predicted image (arcsec) with the fold's magnification there, and their rms</p>
    <div class="table-scroll"><table aria-describedby="crossval-caption"><thead><tr><th scope="col">system</th><th scope="col">fold</th><th scope="col">z</th>
    <th scope="col">offsets [″] (μ)</th><th scope="col">rms [″]</th></tr></thead><tbody>${rows}</tbody></table></div></details>`;
  const type = (name) => (name.endsWith('.png') ? 'image/png' : 'application/fits');
  const png = files.find((f) => f.name.endsWith('.png'));
  if (png) {
    spreadUrl = URL.createObjectURL(new Blob([png.bytes], { type: 'image/png' }));
    const figure = document.createElement('figure');
    figure.id = 'crossval-spread-figure';
    figure.innerHTML = `<img id="crossval-spread" src="${spreadUrl}"
      alt="Map of the standard deviation of the folds' convergence">
      <figcaption>Standard deviation of the ${runs.length} folds' convergence κ, on the map a reconstruction
      with these settings makes (with the critical curves of the result on screen when it is that map): where
      the mass map depends on which systems are fitted. (A delete-a-group jackknife would take √(K − 1) times
      it as the standard error of the map from all the systems.)</figcaption>`;
    box.append(figure);
  }
  box.append(button('crossval.json', 'dl-crossval-json', onDownload));
  for (const f of files) {
    box.append(button(f.name, `dl-${f.name.replace(/\./g, '-')}`,
      () => save(f.name, new Blob([f.bytes], { type: type(f.name) }))));
  }
  box.hidden = false;
}

/** Wires the tabs (click and arrow keys) and the read-out. `app` renders views and hovers. */
export function wireViews(appApi) {
  app = appApi;
  const tabs = [...document.querySelectorAll('[role=tab]')];
  tabs.forEach((tab, k) => {
    tab.addEventListener('click', () => { selectTab(tab.dataset.view); app.render(); });
    tab.addEventListener('keydown', (e) => {
      const step = { ArrowRight: 1, ArrowLeft: -1 }[e.key];
      if (!step) return;
      const next = tabs[(k + step + tabs.length) % tabs.length];
      next.focus();
      next.click();
    });
  });
  selectTab('kappa');
  const ask = (e, pin) => {
    const el = img();
    // The mass map still on screen while another view is drawn has no read-out either.
    if (current !== 'kappa' || el.dataset.view !== 'kappa' || !el.naturalWidth) return;
    const r = el.getBoundingClientRect();
    point = {
      x: (e.clientX - r.left) * el.naturalWidth / r.width,
      y: (e.clientY - r.top) * el.naturalHeight / r.height,
      pin,
    };
    readOut();
  };
  img().addEventListener('mousemove', (e) => ask(e, false));
  img().addEventListener('click', async (e) => {
    ask(e, true);
    // The point under the click, in arcsec: its source's images are drawn and listed.
    const h = await app.hover(point.x, point.y).catch(() => null);
    if (!h) return;
    pin = [h.x_arcsec, h.y_arcsec];
    await app.render();
  });
}

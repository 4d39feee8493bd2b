// The settings form: each input edits one field of AppSettings (a dot path) through the
// worker, which validates it; a refused value shows the core's message and is put back.

export const FIELDS = [
  { path: 'z_lens', label: 'Lens redshift z_lens', type: 'number', step: 0.001 },
  { path: 'h0', label: 'H0 [km/s/Mpc]', type: 'number', step: 0.1 },
  { path: 'omega_m', label: 'Ωm (flat ΛCDM)', type: 'number', step: 0.01 },
  { path: 'reconstruct.grid.cells', label: 'Grid cells per side', type: 'int',
    hint: 'with the strength "auto", the finest grid tried: a half and three quarters of it are tried too, and the grid whose held-out images are predicted best is used (a number for the strength keeps this grid)' },
  { path: 'reconstruct.grid.cell_sigma_factor', label: 'Cell width (Gaussian σ / cell size)', type: 'number', step: 0.05 },
  { path: 'reconstruct.grid.width_arcsec', label: 'Field width [arcsec] (empty: automatic)', type: 'optional' },
  { path: 'reconstruct.grid.external_shear_sigma', label: 'External shear: prior width on γ1, γ2 (empty: none)', type: 'optional',
    hint: 'the map gets the tidal field of mass beyond the grid (Lenstool\'s profile 14), fitted with it and given in the caption (default 0.1, the scale of published clusters\' shears; empty: no shear, as in the paper)' },
  { path: 'reconstruct.grid.refinements', label: 'Grid refinements (0 to 4)', type: 'int',
    hint: 'multi-resolution grid: after each solution the quarter of the cells with the most mass are split in four and the fit runs again' },
  { path: 'reconstruct.members.mass_to_light', label: 'Members M/L [Msun/Lsun]', type: 'number', step: 1 },
  { path: 'reconstruct.members.mass_to_light_scatter_dex', label: 'Uncertainty of the members\' M/L [dex]', type: 'number', step: 0.05,
    hint: 'each ensemble member draws its own M/L from this log-normal scatter (default 0.3 dex, a factor 2): point images hardly measure the members\' mass, so the spread should hold it (0 to 2; 0: every member uses the M/L above)' },
  { path: 'reconstruct.members.layers', label: 'Member layers', type: 'text',
    hint: 'none, single, bcg or brightest:N' },
  { path: 'reconstruct.members.mag_star', label: 'Member L* magnitude (empty: from M* = −21.5 at z_lens)', type: 'optional',
    hint: 'the apparent magnitude, in the catalogue\'s band, of a galaxy of 5e10 Lsun: sets the members\' luminosities' },
  { path: 'reconstruct.members.profile', label: 'Member halo profile', type: 'select',
    options: [['tnfw', 'truncated NFW'], ['nfw', 'NFW (untruncated)']] },
  { path: 'reconstruct.members.r_trunc_lstar_kpc', label: 'Truncation radius of an L* halo [kpc]', type: 'number', step: 1,
    hint: 'truncated NFW only; the other members\' radii scale with mass^(1/3), like the scale radius (10 kpc at L*)' },
  { path: 'reconstruct.members.c_prior_sigma', label: 'Prior width on the member factor C (empty: C free)', type: 'optional',
    hint: 'e.g. 0.1 holds C near 1 (the M/L above); helps with few point images' },
  { path: 'reconstruct.constraints.mode', label: 'Constraint mode', type: 'select',
    options: ['ellipse', 'point', 'arcs'] },
  { path: 'reconstruct.constraints.pixel_arcsec', label: 'Constraint pixel [arcsec]', type: 'number', step: 0.01,
    hint: 'the lattice that fills catalogue ellipses and DS9 region arcs (0.2: an HST pixel)' },
  { path: 'reconstruct.constraints.default_z', label: 'Redshift for images with z = 0 (empty: estimate it)', type: 'optional',
    hint: 'catalogues write 0 for an unknown redshift; such a system is left out of a first fit, its redshift estimated on that lens (0.5 to 8, shown with its 68% interval in the systems table) and then fitted; a number here gives them all that redshift instead' },
  { path: 'reconstruct.constraints.free_z_systems', label: 'Estimate the redshift of systems (ids, e.g. 3, 7)', type: 'list',
    hint: 'as for a system with z = 0, even though the catalogue gives one: e.g. to test a photometric redshift' },
  { path: 'reconstruct.constraints.weighting', label: 'Pixel weights', type: 'select',
    options: [['equal_per_image', 'each image equal'], ['equal_per_pixel', 'each pixel equal'], ['equal_per_system', 'each system equal']],
    hint: 'each image equal (default): a big arc does not drown the small images of other systems' },
  { path: 'reconstruct.solver.method', label: 'Solver', type: 'select',
    options: [['exact', 'exact minimiser (default)'], ['qadp', 'QADP (paper)'], ['accelerated_gradient', 'best fit']],
    hint: 'exact (default): the minimiser of the stated objective (image-plane misfit plus the regulariser), whatever the start; QADP stopped early is the paper\'s method (the iteration count regularises; set the regulariser to none); the best fit (accelerated gradient) over-fits extended arcs without a regulariser' },
  { path: 'reconstruct.objective.regulariser', label: 'Regulariser', type: 'select',
    options: [['gradient', 'smoothest mass (default)'], ['curvature', 'least curved'], ['density', 'least concentrated'], ['none', 'none (QADP\'s early stop)']],
    hint: 'among the maps that fit the images, the one the regulariser prefers; its strength is chosen by cross-validation (the held-out images); least concentrated (least mass, the members counted too) fits no external shear' },
  { path: 'reconstruct.objective.strength', label: 'Regulariser strength ("auto" or a number)', type: 'strength',
    options: ['auto', '0.001', '0.01', '0.1', '1', '10'],
    hint: 'auto (default): each candidate strength, with each regulariser and three grids, is cross-validated in parallel workers, and the one whose held-out images are predicted best is used; a number fixes it (0: no regulariser) and keeps the regulariser and grid set here' },
  { path: 'reconstruct.objective.image_plane_iterations', label: 'Image-plane updates', type: 'int',
    hint: 'times the residuals are re-weighted by the magnification (default 2; 0: source-plane residuals)' },
  { path: 'reconstruct.shear.shape_noise', label: 'Arclet shape noise (weak lensing)', type: 'number', step: 0.01,
    hint: 'scatter of each ellipticity component of the arclets (default 0.3): each galaxy\'s two rows have weight 1/σ²' },
  { path: 'reconstruct.solver.iterations', label: 'Iterations', type: 'int' },
  { path: 'holdout', label: 'Hold out systems (ids, e.g. 3, 7)', type: 'list',
    hint: 'left out of the fit, then predicted by the model: their image offsets show how well it finds images it was not given' },
  { path: 'lenstool_single_plane', label: 'Lenstool models at several redshifts: single-plane approximation', type: 'bool',
    options: [['false', 'off: refuse them'], ['true', 'on: every potential at the main lens redshift']],
    hint: 'a .par model with a foreground or background group: on, each such block is moved to the main lens plane (angular sizes and velocity dispersion kept) and named in a warning' },
  { path: 'members_from_model', label: 'Galaxies and redshift priors from the .par', type: 'bool',
    options: [['false', 'off'], ['true', 'on: use them too']],
    hint: 'the galaxies a loaded Lenstool .par models on its own (a core of at most 5 kpc and a mag: typically the BCG, which its member catalogue then leaves out) are fitted as members too, and the redshift priors of its image block (z_m_limit lines: fixed, uniform or normal) replace the catalogue\'s redshifts of the systems they name, as in Lenstool (wslap reconstruct --par)' },
  { path: 'reconstruct.members.fit_commented_bcg', label: 'Fit commented-out BCG rows', type: 'bool',
    options: [['true', 'on (default)'], ['false', 'off: leave them out and warn']],
    hint: 'when no member near the multiple images is as bright as a brightest cluster galaxy (4 L* or more) and commented-out (#) rows of the member catalogue there are, those rows are fitted as BCGs (one per core of a cluster with several): Lenstool set-ups model the BCGs in the .par and comment them out of the potfile catalogue; the run\'s warnings name the lines' },
  { path: 'ensemble.members', label: 'Ensemble members (0: none)', type: 'int',
    hint: 'after each reconstruction, this many more (2 to 200), run in parallel workers: each fits a bootstrap draw of the systems on a grid moved by up to half a cell, with the members\' M/L drawn from its uncertainty; gives the spread of the map, the magnification\'s interval in the read-out and the intervals of the Einstein radius and masses (wslap reconstruct --ensemble N)' },
  { path: 'ensemble.seed', label: 'Ensemble seed', type: 'int',
    hint: 'the same seed draws the same members, here and with wslap reconstruct --seed' },
  { path: 'reconstruct.products.z_source', label: 'z_s of the curves', type: 'number', step: 0.1 },
  { path: 'reconstruct.products.pixels', label: 'Map pixels per side', type: 'int' },
  { path: 'reconstruct.products.size_arcsec', label: 'Map width [arcsec] (empty: the field)', type: 'optional',
    hint: 'rounded, for a reconstruction, so that a grid cell spans whole map pixels (fast maps)' },
];

// A change is sent when an input fires 'change'; the worker answers with all the settings.
// Such an answer may arrive while the user types in another input (or in the same one again),
// so a refresh never touches an input that is being edited (typed into since its last change)
// or whose own change is still on its way. Answers carry `revision`, the order in which the
// worker produced them: one older than the settings shown only settles its own input.
let changes = 0; // number of the last change sent
let shown = -1; // revision of the settings the form shows
const busy = new Map(); // input -> { edited: typed since its last change, waiting: number of its change in flight }
const id = (path) => `set-${path.replaceAll('.', '-')}`;

/** The value at dot path `path` (e.g. 'reconstruct.grid.cells') of `obj`, or undefined. */
export function valueAt(obj, path) {
  return path.split('.').reduce((o, k) => (o == null ? undefined : o[k]), obj);
}

function parse(field, raw) {
  if (field.type === 'text' || field.type === 'select') return raw;
  if (field.type === 'bool') return raw === 'true';
  // The strength is the string "auto" or a JSON number (a numeric string is refused).
  if (field.type === 'strength' && raw.trim().toLowerCase() === 'auto') return 'auto';
  if (field.type === 'list') return raw.split(/[\s,]+/).filter((t) => t !== '');
  if (field.type === 'optional' && raw.trim() === '') return null;
  const v = Number(raw);
  if (raw.trim() === '' || !Number.isFinite(v)) return raw; // let the core name the problem
  return field.type === 'int' ? Math.round(v) : v;
}

/** Builds the form. `apply(path, value)` resolves with the new settings or throws. */
/**
 * `message` about the setting at `path`, as shown next to its labelled field: without the path
 * the core puts first ("reconstruct.grid.cells: ...") nor the dotted name a range check gives
 * the value ("grid.cells = 0 is not allowed" -> "0 is not allowed"; "cosmology.z_lens = -1"
 * for the field z_lens). A message about another setting keeps its names.
 */
export function fieldMessage(message, path) {
  const last = path.split('.').at(-1);
  let text = message.startsWith(`${path}: `) ? message.slice(path.length + 2) : message;
  const named = text.match(/^([\w]+(?:\.[\w]+)*) = /);
  if (named && named[1].split('.').at(-1) === last) text = text.slice(named[0].length);
  return text;
}

export function buildSettings(form, apply) {
  for (const f of FIELDS) {
    const row = document.createElement('div');
    row.className = 'field';
    const control = ['select', 'bool'].includes(f.type)
      ? `<select id="${id(f.path)}">${f.options.map((o) => (Array.isArray(o)
        ? `<option value="${o[0]}">${o[1]}</option>`
        : `<option>${o}</option>`)).join('')}</select>`
      : f.type === 'strength'
        ? `<input id="${id(f.path)}" type="text" inputmode="decimal" list="${id(f.path)}-list">
          <datalist id="${id(f.path)}-list">${f.options.map((o) => `<option value="${o}"></option>`).join('')}</datalist>`
        : `<input id="${id(f.path)}" type="${['text', 'list'].includes(f.type) ? 'text' : 'number'}" ${f.step ? `step="${f.step}"` : f.type === 'int' ? '' : 'step="any"'}>`;
    row.innerHTML = `<label for="${id(f.path)}">${f.label}</label>${control}
      ${f.hint ? `<small class="hint">${f.hint}</small>` : ''}
      <span class="field-error" id="${id(f.path)}-error" role="alert"></span>`;
    form.append(row);
    const input = row.querySelector('input, select');
    const state = { edited: false, waiting: 0 };
    busy.set(input, state);
    input.addEventListener('input', () => { state.edited = true; });
    input.addEventListener('change', async () => {
      const err = document.getElementById(`${id(f.path)}-error`);
      const ticket = ++changes;
      // The message was about the value before: this one is being checked.
      err.textContent = '';
      state.edited = false;
      state.waiting = ticket;
      let settings = null;
      let problem = null;
      try {
        settings = await apply(f.path, parse(f, input.value));
      } catch (e) {
        problem = e;
      }
      // Only the answer to this input's latest change settles it.
      if (state.waiting !== ticket) return;
      state.waiting = 0;
      // A cancel restarts the worker and then shows the restored settings.
      if (problem?.cancelled) return;
      if (problem) {
        // Shown next to the labelled field: without the setting's path the core puts first,
        // nor the path a range check names its value by ("members.x = 5 is not allowed").
        err.textContent = fieldMessage(problem.message, f.path);
        if (!state.edited) input.value = input.dataset.good ?? '';
        return;
      }
      err.textContent = '';
      if ((settings.revision ?? Infinity) >= shown) refresh(settings);
      else if (!state.edited) input.value = input.dataset.good; // the newer settings shown hold it
    });
  }
}

/** Shows `settings`: inputs that are being edited or wait for the answer to their own change
 * keep what the user typed (only the value they fall back to moves). */
function refresh(settings) {
  shown = settings.revision ?? shown;
  for (const f of FIELDS) {
    const input = document.getElementById(id(f.path));
    if (!input) continue;
    const v = valueAt(settings, f.path);
    const text = v == null ? '' : Array.isArray(v) ? v.join(', ') : String(v);
    input.dataset.good = text;
    const state = busy.get(input);
    if (!state || (!state.edited && !state.waiting)) input.value = text;
  }
}

/** Puts `settings` into the form (and remembers them as the values to fall back to), unless
 * newer ones are shown. With `force` (a project or example was opened) every input shows them
 * and pending edits are dropped; otherwise inputs being edited keep what the user typed. */
export function showSettings(settings, { force = false } = {}) {
  if (force) {
    for (const state of busy.values()) { state.edited = false; state.waiting = 0; }
  } else if ((settings.revision ?? Infinity) < shown) {
    return;
  }
  refresh(settings);
}

/** Under the regulariser's strength, what the last run's "auto" choice used (`choice`:
 * summary.json's `strength_choice`), since the fields above keep the settings as set; nothing
 * without one. */
export function showChoiceNote(choice) {
  const input = document.getElementById(id('reconstruct.objective.strength'));
  if (!input) return;
  const row = input.closest('.field');
  let note = row.querySelector('.chosen-note');
  if (!choice) {
    note?.remove();
    return;
  }
  if (!note) {
    note = document.createElement('small');
    note.className = 'hint chosen-note';
    row.querySelector('.field-error').before(note);
  }
  const kinds = FIELDS.find((f) => f.path === 'reconstruct.objective.regulariser').options;
  const kind = kinds.find(([k]) => k === choice.chosen_regulariser)?.[1];
  const parts = [kind ? `${kind} (${choice.chosen_regulariser})` : null, `strength ${choice.chosen}`,
    choice.chosen_cells != null ? `${choice.chosen_cells} × ${choice.chosen_cells} cells` : null];
  note.textContent = `The last run's choice: ${parts.filter(Boolean).join(', ')} (the table under the map). `
    + 'The regulariser and grid fields keep the settings as set: "auto" starts from them again.';
}

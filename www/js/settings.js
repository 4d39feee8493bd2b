// The settings form: each input edits one field of AppSettings (a dot path) through the
// worker, which validates it; a refused value shows the core's message and is put back.

export const FIELDS = [
  { path: 'z_lens', label: 'Lens redshift z_lens', type: 'number', step: 0.001 },
  { path: 'h0', label: 'H0 [km/s/Mpc]', type: 'number', step: 0.1 },
  { path: 'omega_m', label: 'Ωm (flat ΛCDM)', type: 'number', step: 0.01 },
  { path: 'reconstruct.grid.cells', label: 'Grid cells per side', type: 'int' },
  { path: 'reconstruct.grid.width_arcsec', label: 'Field width [arcsec] (empty: automatic)', type: 'optional' },
  { path: 'reconstruct.members.mass_to_light', label: 'Members M/L [Msun/Lsun]', type: 'number', step: 1 },
  { path: 'reconstruct.members.layers', label: 'Member layers', type: 'text',
    hint: 'none, single, bcg or brightest:N' },
  { path: 'reconstruct.constraints.mode', label: 'Constraint mode', type: 'select',
    options: ['ellipse', 'point', 'arcs'] },
  { path: 'reconstruct.solver.iterations', label: 'QADP iterations', type: 'int' },
  { path: 'reconstruct.products.z_source', label: 'z_s of the curves', type: 'number', step: 0.1 },
  { path: 'reconstruct.products.pixels', label: 'Map pixels per side', type: 'int' },
  { path: 'reconstruct.products.size_arcsec', label: 'Map width [arcsec] (empty: the field)', type: 'optional' },
];

let changes = 0;
const id = (path) => `set-${path.replaceAll('.', '-')}`;

function get(obj, path) {
  return path.split('.').reduce((o, k) => (o == null ? undefined : o[k]), obj);
}

function parse(field, raw) {
  if (field.type === 'text' || field.type === 'select') return raw;
  if (field.type === 'optional' && raw.trim() === '') return null;
  const v = Number(raw);
  if (raw.trim() === '' || !Number.isFinite(v)) return raw; // let the core name the problem
  return field.type === 'int' ? Math.round(v) : v;
}

/** Builds the form. `apply(path, value)` resolves with the new settings or throws. */
export function buildSettings(form, apply) {
  for (const f of FIELDS) {
    const row = document.createElement('div');
    row.className = 'field';
    const control = f.type === 'select'
      ? `<select id="${id(f.path)}">${f.options.map((o) => `<option>${o}</option>`).join('')}</select>`
      : `<input id="${id(f.path)}" type="${f.type === 'text' ? 'text' : 'number'}" ${f.step ? `step="${f.step}"` : ''}>`;
    row.innerHTML = `<label for="${id(f.path)}">${f.label}</label>${control}
      ${f.hint ? `<small class="hint">${f.hint}</small>` : ''}
      <span class="field-error" id="${id(f.path)}-error" role="alert"></span>`;
    form.append(row);
    const input = row.querySelector('input, select');
    input.addEventListener('change', async () => {
      const err = document.getElementById(`${id(f.path)}-error`);
      const ticket = ++changes;
      try {
        const settings = await apply(f.path, parse(f, input.value));
        err.textContent = '';
        // An older answer must not overwrite the form after a newer change.
        if (ticket === changes) showSettings(settings);
        else input.dataset.good = input.value;
      } catch (e) {
        err.textContent = e.message;
        input.value = input.dataset.good ?? '';
      }
    });
  }
}

/** Puts `settings` into the form (and remembers them as the values to fall back to). */
export function showSettings(settings) {
  for (const f of FIELDS) {
    const input = document.getElementById(id(f.path));
    if (!input) continue;
    const v = get(settings, f.path);
    input.value = v == null ? '' : String(v);
    input.dataset.good = input.value;
  }
}

// The per-system table of a reconstruction (sources.json rows), sortable by its columns: a
// click (or Enter / Space on the header's button) sorts by that column, a second one reverses
// the order; the sorted header carries aria-sort. The verdict's worst systems are marked.

import { worstSystems } from './verdict.js';

/** `text` (a system or image id from a user's file) safe inside HTML. */
const esc = (text) => String(text).replace(/[&<>"']/g, (c) => `&#${c.charCodeAt(0)};`);

/** A number with `d` decimals, or a dash when there is none. */
const fmt = (v, d = 2) => (v == null ? '–' : Number(v).toFixed(d));

/** A table cell of observed images: each one's offset from the nearest predicted image and
 * the model's magnification there. */
export const offsetsCell = (observed) => `<td>${observed.map((o) => `${esc(o.id)}: ${fmt(o.offset_arcsec)}${
  o.magnification == null ? '' : ` (μ ${fmt(o.magnification, 1)})`}`).join('<br>')}</td>`;

/** A system's own redshift prior (sources.json `z_prior`, from a .par's z_m_limit line) in
 * words, or '' without one. */
const priorText = (p) => {
  if (p == null) return '';
  if (p.range) return `uniform ${fmt(p.range[0], 2)}–${fmt(p.range[1], 2)}`;
  if (p.normal) return `normal ${fmt(p.normal[0], 2)} ± ${fmt(p.normal[1], 2)}`;
  return `fixed at ${fmt(p.fixed, 3)}`;
};

/** A system's redshift: as given, assumed (`*`, the default redshift), fixed by its own
 * prior, or estimated by the fit with its 68% interval (and its own prior, if any). */
const zCell = (s) => {
  const prior = priorText(s.z_prior);
  if (s.z_estimate == null) {
    const title = prior ? ` title="its own prior (a .par's z_m_limit line): ${prior}"` : '';
    return `<td${title}>${fmt(s.z, 3)}${s.z_assumed ? '*' : ''}</td>`;
  }
  const under = prior ? `, under its own prior (${prior})` : '';
  // How far the interval moves the system's images: added to their position error in
  // quadrature, so an uncertain redshift weighs little in the map.
  const e = s.z_position_error_arcsec;
  const fitted = e == null ? '' : `; fitted with ${fmt(e, 2)}″ added to its images' position error (how far they move across the interval)`;
  // An interval that ends at the top of the range searched: the images do not bound it there.
  const open = s.z_open_above ? ' (open above)' : '';
  const openTitle = s.z_open_above ? ', open above: it ends at the top of the range searched, where the images no longer bound it' : '';
  return `<td class="z-estimated" title="estimated on the lens of the systems with a redshift${under}, 68% interval${openTitle} (the run's warnings say over the maps of which regularisers)${fitted}">${fmt(s.z_estimate, 2)} est.<br><small>${fmt(s.z_interval[0], 2)}–${fmt(s.z_interval[1], 2)}${open}</small>${prior ? `<br><small>prior ${prior.replace(/^uniform /, '').replace(/^normal /, '')}</small>` : ''}${e == null ? '' : `<br><small>± ${fmt(e, 2)}″</small>`}</td>`;
};

/** Ids in natural order: "2" before "10", "2.1" before "2.10". */
const byId = new Intl.Collator('en', { numeric: true }).compare;

/** The largest offset of a system's observed images (an image with no predicted one counts
 * as infinitely far). */
function largestOffset(s) {
  if (s.observed.some((o) => o.offset_arcsec == null)) return Infinity;
  return Math.max(0, ...s.observed.map((o) => o.offset_arcsec));
}

/** Predicted images the map shows (|μ| ≥ 0.1) against the observed ones. */
const shown = (s) => s.predicted.filter((p) => Math.abs(p.magnification) >= 0.1).length;

/** The columns: header, sort key (none: not sortable) and the default direction of a first
 * click (the worst first for the checks). */
const COLUMNS = [
  { key: 'system', head: 'system', value: (s) => s.id, compare: byId },
  { key: 'z', head: 'z', value: (s) => s.z },
  { key: 'beta', head: 'β [″]' },
  { key: 'scatter', head: 'scatter [″]', value: (s) => s.scatter_arcsec, first: 'descending' },
  { key: 'images', head: 'images obs. / pred.', value: (s) => shown(s) - s.observed.length },
  { key: 'offsets', head: 'offsets [″] (μ)', value: largestOffset, first: 'descending' },
  { key: 'rms', head: 'rms [″]', value: (s) => s.image_plane_rms_arcsec ?? Infinity, first: 'descending' },
  // The verdict's worst systems in its order, first; then the others.
  { key: 'check', head: 'check', value: (s) => worstRank(s.id), first: 'ascending' },
];

// The verdict's worst systems, worst first (from the last result's summary).
let worstOrder = new Map();
const worstRank = (id) => worstOrder.get(id) ?? Infinity;

// The sort on screen: { key, direction } or null (the file's order); kept across redraws.
let sorted = null;
let rows = [];

const numeric = (a, b) => (a === b ? 0 : a < b ? -1 : 1);

function order(sources) {
  if (!sorted) return sources;
  const col = COLUMNS.find((c) => c.key === sorted.key);
  const compare = col.compare ?? numeric;
  const sign = sorted.direction === 'ascending' ? 1 : -1;
  // Stable: ties keep the file's order.
  return sources.map((s, k) => [s, k])
    .sort(([a, ka], [b, kb]) => sign * compare(col.value(a), col.value(b)) || ka - kb)
    .map(([s]) => s);
}

function row(s, worst) {
  // The colour of the system's arc pixels in the views (none for catalogue systems).
  const swatch = s.rgb ? `<span class="swatch" style="background:${s.rgb}" aria-hidden="true"></span>` : '';
  const problem = worst.get(s.id);
  const n = shown(s);
  return `<tr data-id="${esc(s.id)}"${problem ? ' class="worst"' : ''}><th scope="row">${swatch}${esc(s.id)}${s.held_out ? ' (held out)' : ''}</th>
    ${zCell(s)}<td>${fmt(s.beta_arcsec[0])}, ${fmt(s.beta_arcsec[1])}</td>
    <td>${fmt(s.scatter_arcsec)}</td><td>${s.observed.length} / ${n}${s.predicted.length > n ? ` <span class="hint">(+${s.predicted.length - n} faint)</span>` : ''}</td>
    ${offsetsCell(s.observed)}
    <td>${fmt(s.image_plane_rms_arcsec)}</td><td class="check">${problem ? `⚠ ${esc(problem)}` : ''}</td></tr>`;
}

function header(col) {
  if (!col.value) return `<th scope="col">${col.head}</th>`;
  const on = sorted?.key === col.key;
  const aria = on ? ` aria-sort="${sorted.direction}"` : '';
  const arrow = on ? (sorted.direction === 'ascending' ? ' ▲' : ' ▼') : '';
  return `<th scope="col"${aria}><button type="button" class="sort" data-sort="${col.key}"
    title="Sort by ${col.head.replace(/ \[.*$/, '')}">${col.head}<span aria-hidden="true">${arrow}</span></button></th>`;
}

function draw() {
  const box = document.getElementById('systems');
  const list = worstSystems();
  const worst = new Map(list.map((w) => [w.id, w.problem]));
  worstOrder = new Map(list.map((w, k) => [w.id, k]));
  const body = order(rows).map((s) => row(s, worst)).join('');
  box.innerHTML = rows.length === 0 ? '<p class="hint">No systems: not a reconstruction.</p>'
    : `<p class="table-caption" id="systems-caption">Per system: redshift (est.: estimated by the fit, with its 68% interval (open above: it reaches the top of the range searched, where the images no longer bound it) and, ± ″, how far that interval moves its images, which the fit adds to their position error; *: the default redshift assumed), solved source position β, source-plane scatter, images observed / predicted (those the map shows, |μ| ≥ 0.1; the demagnified ones in brackets), offsets of the observed images from the nearest predicted one (arcsec) and the model's magnification μ at each observed image: a large offset where |μ| is high usually means the image lies near a critical curve with its source just outside the model's caustic, so its pair has merged. Check: the verdict's worst systems (ringed on the map), worst first when sorted by it. Click a column's header to sort by it.</p>
    <div class="table-scroll"><table id="systems-table" aria-describedby="systems-caption"><thead><tr>${COLUMNS.map(header).join('')}</tr></thead><tbody>${body}</tbody></table></div>`;
  for (const b of box.querySelectorAll('button.sort')) {
    b.addEventListener('click', () => {
      const col = COLUMNS.find((c) => c.key === b.dataset.sort);
      const first = col.first ?? 'ascending';
      const flip = { ascending: 'descending', descending: 'ascending' };
      sorted = sorted?.key === col.key ? { key: col.key, direction: flip[sorted.direction] } : { key: col.key, direction: first };
      draw();
      box.querySelector(`button.sort[data-sort="${col.key}"]`).focus();
    });
  }
}

/** Shows the per-system table of `sources` (sources.json rows) in the sort chosen last. */
export function showSystems(sources) {
  rows = sources;
  draw();
  document.getElementById('systems').hidden = false;
  document.getElementById('figure').hidden = true;
}

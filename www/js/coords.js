// Coordinates on the mass map: the read-out's text (arcsec in the frame, and RA/Dec where the
// data have a sky reference), the list of a point's counter-images in their order of arrival,
// and the box where a position is typed or pasted (RA/Dec in degrees or sexagesimal, or x y in
// arcsec): the core reads it (`locate`) and the page pins it as a click would, without the mouse.

import { ensembleReadout } from './ensemble.js';

/** A number with `d` decimals, or a dash. */
const fmt = (v, d = 2) => (v == null ? '–' : Number(v).toFixed(d));

/** "x = …″, y = …″ from the frame's origin" and, with a sky reference, "RA Dec". */
export function whereText(h) {
  const xy = `x = ${fmt(h.x_arcsec)}″, y = ${fmt(h.y_arcsec)}″`;
  return h.radec_sexagesimal ? `RA, Dec ${h.radec_sexagesimal} (${fmt(h.radec_deg[0], 5)}°, ${fmt(h.radec_deg[1], 5)}°); ${xy} from the reference`
    : `${xy} (the data give no sky reference)`;
}

/** The read-out of a hover or click answer (`hover` / `pointReadout` of the worker). */
export function readoutText(h) {
  const where = whereText(h);
  if (h.no_data) return `${where}: no data (the deflection maps are blank here)`;
  return `${where}; κ = ${h.kappa.toFixed(3)}, μ(z_s = ${h.z_source}) = ${h.magnification.toFixed(2)} at this point${ensembleReadout(h)}`;
}

/** "1st", "2nd", … */
const ordinal = (k) => `${k}${['th', 'st', 'nd', 'rd'][(k % 100 > 10 && k % 100 < 14) || k % 10 > 3 ? 0 : k % 10]}`;

/** A delay in days as the list shows it: "arrives first" for the first image, days (and
 * years) after it for the others. */
function delayText(days) {
  if (days == null) return '';
  if (days === 0) return ', arrives first';
  const d = `${Math.round(days).toLocaleString('en')} d`;
  return `, Δt ${Math.abs(days) >= 365.25 ? `${d} (${(days / 365.25).toFixed(1)} yr)` : d}`;
}

/** The images of the point's source (`counterImages` of the worker), in their order of
 * arrival; the image at the point itself is named, with its magnification next to the one at
 * the point (both from the same maps, so they differ only by the distance between them). */
export function counterImagesText(c) {
  const order = c.images.map((image, k) => ({ image, k }))
    .sort((a, b) => (a.image.delay_days ?? Infinity) - (b.image.delay_days ?? Infinity));
  const timed = order.every(({ image }) => image.delay_days != null);
  const items = order.map(({ image, k }, rank) => {
    const [x, y] = image.position_arcsec;
    const sky = c.images_sexagesimal?.[k] ? ` at ${c.images_sexagesimal[k]}` : '';
    const here = k === c.point_image ? ' (the image at the point)' : '';
    const when = timed ? `${ordinal(rank + 1)} ` : '';
    return `${when}(${fmt(x)}, ${fmt(y)}) μ ${fmt(image.magnification, 1)} (parity ${image.magnification < 0 ? '−' : '+'})${
      delayText(image.delay_days)}${sky}${here}`;
  });
  const n = c.images.length;
  const atPoint = `Magnification at the point itself: ${fmt(c.point_magnification)}`;
  const found = c.point_image == null ? 'no image of its source was found at the point'
    : `at the image found there (${fmt(c.point_image_distance_arcsec, 3)}″ away): ${fmt(c.images[c.point_image].magnification)}`;
  return `The source behind (${fmt(c.x_arcsec)}″, ${fmt(c.y_arcsec)}″) lies at β = (${fmt(c.beta_arcsec[0])}″, ` +
    `${fmt(c.beta_arcsec[1])}″); at z_s = ${c.z_source} it has ${n} image${n === 1 ? '' : 's'} ` +
    `(yellow squares where |μ| ≥ 0.1; positions in arcsec${timed ? ', in order of arrival, Δt after the first' : ''}): ` +
    `${items.join('; ')}. ${atPoint}; ${found}.`;
}

/** The position box's placeholder before there is a result to read. */
const NO_DATA_PLACEHOLDER = 'RA Dec, or x y in arcsec';

/** The box's help, its examples at the data's sky reference (`h`: the read-out at the frame's
 * origin, or null before any result). */
function locateHelp(h) {
  const what = 'κ, μ and the images of the source behind it.';
  if (!h) {
    // No data's sky reference yet: the forms, with no cluster's position as an example.
    return `RA Dec in degrees or sexagesimal (hh:mm:ss.ss ±dd:mm:ss.s), or x y in arcsec from the
      reference (for example 12.5 -3.2): ${what}`;
  }
  if (!h.radec_sexagesimal) return `x y in arcsec from the frame's origin (for example 12.5 -3.2; these data give no sky reference): ${what}`;
  return `RA Dec in degrees (${fmt(h.radec_deg[0], 4)} ${fmt(h.radec_deg[1], 4)}) or sexagesimal
    (${h.radec_sexagesimal}), or x y in arcsec from that reference (for example 12.5 -3.2): ${what}`;
}

/** Gives the position box examples at the loaded data's sky reference: `h` is the read-out at
 * the frame's origin (0, 0). */
export function locateExamples(h) {
  const help = document.getElementById('locate-help');
  const input = document.getElementById('locate-input');
  if (!help || !input) return;
  help.textContent = locateHelp(h).replace(/\s+/g, ' ');
  input.placeholder = h ? (h.radec_sexagesimal ?? '12.5 -3.2') : NO_DATA_PLACEHOLDER;
}

/** Adds the box for a typed position after the read-out. `locate(text)` resolves to the point
 * (`{x_arcsec, y_arcsec, form_words}`) or rejects with the core's message; `pinAt(point)` pins
 * it as a click on the map would. */
export function wireLocate({ locate, pinAt }) {
  const form = document.createElement('form');
  form.id = 'locate-form';
  form.className = 'locate';
  form.noValidate = true;
  form.innerHTML = `<label for="locate-input">Go to a position</label>
    <span class="locate-row"><input id="locate-input" type="text" autocomplete="off" spellcheck="false"
      placeholder="${NO_DATA_PLACEHOLDER}" aria-describedby="locate-help locate-error">
    <button type="submit" id="locate-go" class="secondary">Show</button></span>
    <span id="locate-help" class="hint">${locateHelp(null)}</span>
    <span id="locate-error" class="field-error" role="alert"></span>`;
  const input = form.querySelector('#locate-input');
  const error = form.querySelector('#locate-error');
  form.addEventListener('submit', async (e) => {
    e.preventDefault();
    error.textContent = '';
    input.removeAttribute('aria-invalid');
    try {
      const p = await locate(input.value);
      form.dataset.readAs = p.form_words;
      await pinAt([p.x_arcsec, p.y_arcsec]);
    } catch (err) {
      error.textContent = err.message;
      input.setAttribute('aria-invalid', 'true');
    }
  });
  document.getElementById('readout').after(form);
}

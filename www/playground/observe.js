// "Observe" and "Invert with WSLAP+" in the playground: the core turns the scene into mock data
// (src/playground/observe.rs); this module shows what was detected over the image plane and
// hands the files to the research app (www/main.js, `?from=playground`) through
// sessionStorage, which survives the navigation and stays in this tab.

import { encodeFragment, LENS_NAMES, SOURCE_NAMES } from './scene.js';

/** sessionStorage key of the observation handed to the research app. */
export const HANDOFF_KEY = 'wslap.playground.observation';
const OBSERVED = '#ff66d9';

/** A name for the project the research app opens: the scene's lenses and sources. */
function sceneName(scene) {
  const lenses = scene.lenses.map((l) => LENS_NAMES[l.type] ?? l.type).join(', ');
  const sources = scene.sources.map((s) => `${SOURCE_NAMES[s.type] ?? s.type} z=${s.z}`).join(', ');
  return `Playground: ${lenses}; ${sources}`;
}

/** What was detected, in words. */
function summary(obs) {
  const systems = obs.systems.map((s) => {
    const n = s.images.length;
    const what = s.kind === 'point' ? `${n} point images`
      : `${n} arcs, ${s.pixels.reduce((a, b) => a + b, 0)} pixels`;
    return `system ${s.id} (z = ${s.z}): ${what}`;
  });
  const found = systems.length ? `Observed: ${systems.join('; ')}.` : 'Nothing multiply imaged was detected.';
  const notes = obs.notes.length ? ` ${obs.notes.map((n) => n[0].toUpperCase() + n.slice(1)).join('. ')}.` : '';
  return `${found}${notes}`;
}

/** The telescope's settings for Observe, as the core names them (src/playground/observe.rs,
 * `ObserveOptions`): [field, label, default, check(value, all, fov) -> problem or ''] */
const OPTIONS = [
  ['pixel_arcsec', 'pixel size (″)', 0.2, (v, o, fov) => (!(v > 0) ? 'must be positive'
    : fov / v > 1024 ? `gives ${Math.ceil(fov / v)} pixels across the ${fov}″ view, more than 1024: at least ${short(fov / 1024)}″` : '')],
  ['psf_fwhm_arcsec', 'blur, FWHM (″)', 0.3, (v) => (v >= 0 && v <= 10 ? '' : 'must be 0 (no blur) to 10')],
  ['noise', 'noise (× peak)', 0.02, (v, o) => (!(v > 0 && v <= 1) ? 'must be above 0 and at most 1 (the peak brightness)'
    : v * o.threshold_sigma >= 1 ? `leaves nothing to detect at the ${o.threshold_sigma}σ threshold: must be below ${short(1 / o.threshold_sigma)}` : '')],
  ['threshold_sigma', 'detection threshold (σ)', 5, (v, o) => (!(v > 0) ? 'must be positive'
    : v * o.noise >= 1 ? `is above the peak with noise ${o.noise}: must be below ${short(1 / o.noise)}` : '')],
  ['min_abs_magnification', 'faintest point image |μ|', 0.3, (v) => (v >= 0 ? '' : 'must be 0 or more')],
  ['seed', 'noise seed', 1, (v) => (Number.isInteger(v) && v >= 0 && v <= Number.MAX_SAFE_INTEGER ? '' : 'must be a whole number, 0 or more')],
];

/** `v` with 3 significant digits, as typed (50, not 50.0). */
const short = (v) => String(Number(v.toPrecision(3)));

/** "0.2″ pixels, 0.3″ blur, noise 2%, 5σ": the options in words for the panel's heading. */
function optionsWords(o) {
  return `${o.pixel_arcsec}″ pixels, ${o.psf_fwhm_arcsec ? `${o.psf_fwhm_arcsec}″ blur` : 'no blur'}, `
    + `noise ${Number((o.noise * 100).toPrecision(3))}%, ${o.threshold_sigma}σ detection`;
}

/**
 * The telescope's options in `box` (a collapsed panel): typed, checked as they change (a value
 * that does not fit is said next to its field and the last good one kept). `fov()` is the
 * view's side in arcsec. Returns `() => options` for Observe.
 */
export function wireObserveOptions(box, fov) {
  const options = Object.fromEntries(OPTIONS.map(([f, , d]) => [f, d]));
  box.replaceChildren();
  const summary = document.createElement('summary');
  const head = () => { summary.textContent = `Observe with ${optionsWords(options)}`; };
  head();
  box.append(summary);
  for (const [field, label, , check] of OPTIONS) {
    const row = document.createElement('div');
    row.className = 'pg-obs-field';
    const id = `pg-obs-${field}`;
    const name = document.createElement('label');
    name.htmlFor = id;
    name.textContent = label;
    const input = document.createElement('input');
    input.id = id;
    input.type = 'text';
    input.inputMode = 'decimal';
    input.value = String(options[field]);
    input.dataset.field = field;
    const err = document.createElement('span');
    err.className = 'pg-field-error';
    err.id = `${id}-error`;
    err.setAttribute('role', 'alert');
    input.setAttribute('aria-describedby', err.id);
    input.addEventListener('change', () => {
      const text = input.value.trim();
      const v = Number(text);
      const what = label.replace(/ \(.*\)$/, '');
      const problem = text === '' || !Number.isFinite(v) ? `${what}: "${text}" is not a number`
        : check(v, options, fov()) && `${what} ${v} ${check(v, options, fov())}`;
      if (problem) {
        err.textContent = `${problem}; kept ${options[field]}.`;
        input.value = String(options[field]);
        input.setAttribute('aria-invalid', 'true');
        return;
      }
      err.textContent = '';
      input.removeAttribute('aria-invalid');
      options[field] = v;
      head();
    });
    row.append(name, input, err);
    box.append(row);
  }
  return () => ({ ...options });
}

/**
 * Wires the Observe and Invert buttons. `getScene()` gives the scene shown, `redraw()` draws
 * the views again, `say(text)` writes the read-out, `getOptions()` gives the telescope's
 * options. Returns `{draw(ctx, toCanvas, scale), clear()}`: `draw` puts the detections over
 * the image plane, `clear` forgets them (the scene changed).
 */
export function wireObserve({ client, observeButton, invertButton, getScene, redraw, say, tidy, getOptions = () => ({}) }) {
  let observation = null;
  let observedScene = null;
  const clear = () => {
    if (!observation) return;
    observation = null;
    invertButton.hidden = true;
    redraw();
  };
  observeButton.addEventListener('click', async () => {
    const scene = tidy(getScene());
    observeButton.disabled = true;
    say('Observing: rendering each source at the telescope\'s pixels, blurring, adding noise…');
    try {
      observation = await client.request({ type: 'observe', scene: JSON.stringify(scene), options: getOptions() });
      observedScene = scene;
      say(summary(observation));
      invertButton.hidden = observation.systems.length === 0;
      const root = document.getElementById('playground');
      root.dataset.observed = String(observation.systems.length);
      root.dataset.observations = String(Number(root.dataset.observations ?? 0) + 1);
    } catch (e) {
      say(`Observe failed: ${e.message}`);
    } finally {
      observeButton.disabled = false;
      redraw();
    }
  });
  invertButton.addEventListener('click', () => {
    if (!observation) return;
    const arcs = observation.settings.some(([p, v]) => p === 'reconstruct.constraints.mode' && v === 'arcs');
    const files = [
      arcs ? { role: 'arcs', name: 'arcs.json', text: observation.arcs_json }
        : { role: 'images', name: 'images.cat', text: observation.images_cat },
      observation.members_cat && { role: 'members', name: 'members.cat', text: observation.members_cat },
      { role: 'model', name: 'model.json', text: observation.model_json, truth: true },
    ].filter(Boolean);
    const back = `./?playground${encodeFragment(observedScene)}`;
    sessionStorage.setItem(HANDOFF_KEY, JSON.stringify({
      name: sceneName(observedScene),
      description: `${summary(observation)} Made in the playground: the true lens is loaded too, `
        + 'so the figures compare the reconstruction with it.',
      z_lens: observation.z_lens,
      settings: observation.settings,
      files,
      back,
    }));
    const simd = new URLSearchParams(location.search).get('simd');
    location.href = `./?from=playground${simd ? `&simd=${encodeURIComponent(simd)}` : ''}`;
  });

  function draw(ctx, toCanvas, dpr) {
    if (!observation) return;
    ctx.save();
    ctx.fillStyle = 'rgba(255,102,217,0.75)';
    ctx.strokeStyle = OBSERVED;
    ctx.lineWidth = 1.5 * dpr;
    const side = Math.max(2, 1.5 * dpr);
    for (const s of observation.systems) {
      for (const [x, y] of s.arc_pixels) {
        const [px, py] = toCanvas(x, y);
        ctx.fillRect(px - side / 2, py - side / 2, side, side);
      }
      if (s.kind !== 'point') continue;
      for (const [x, y] of s.images) {
        const [px, py] = toCanvas(x, y);
        const r = 7 * dpr;
        ctx.beginPath();
        ctx.moveTo(px - r, py); ctx.lineTo(px + r, py);
        ctx.moveTo(px, py - r); ctx.lineTo(px, py + r);
        ctx.stroke();
      }
    }
    ctx.restore();
  }
  return { draw, clear };
}

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

/**
 * Wires the Observe and Invert buttons. `getScene()` gives the scene shown, `redraw()` draws
 * the views again, `say(text)` writes the read-out. Returns `{draw(ctx, toCanvas, scale),
 * clear()}`: `draw` puts the detections over the image plane, `clear` forgets them (the
 * scene changed).
 */
export function wireObserve({ client, observeButton, invertButton, getScene, redraw, say, tidy }) {
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
      observation = await client.request({ type: 'observe', scene: JSON.stringify(scene), options: {} });
      observedScene = scene;
      say(summary(observation));
      invertButton.hidden = observation.systems.length === 0;
      document.getElementById('playground').dataset.observed = String(observation.systems.length);
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

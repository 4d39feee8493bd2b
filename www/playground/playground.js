// The live lensing playground (`index.html?playground`): drag lenses and sources, watch the
// lensed image, critical curves and caustics move. Every number drawn here comes from the
// Rust core in ./worker.js; this module only draws and handles the pointer.

import { PlaygroundClient } from './client.js';
import {
  DEFAULT_SCENE, FIELDS, SOURCE_FIELDS, NEW_LENS, NEW_SOURCE, LENS_NAMES, SOURCE_NAMES,
  draggable, encodeFragment, decodeFragment, tidyScene,
} from './scene.js';
import { wireObserve, wireObserveOptions } from './observe.js';

const params = new URLSearchParams(location.search);
const EMBED = params.has('embed');
// Pixels a side while the pointer drags, and after it is released.
const DRAG_PIXELS = 128;
const FULL_PIXELS = 512;
const COLORS = {
  tangential: '#ff5a4f', radial: '#5ab0ff', tcaustic: '#ffb14f', rcaustic: '#8fe3ff',
  lens: '#ffffff', source: '#ffe066', ray: '#7CFC00', image: '#ff66d9',
  kappa: 'rgba(255,255,255,0.55)', magnification: 'rgba(255,210,120,0.7)', arrival: 'rgba(160,255,190,0.7)',
};

// ---------------------------------------------------------------- page

for (const el of document.body.children) el.style.display = 'none';
document.body.classList.add('pg-body');
if (EMBED) document.body.classList.add('pg-embed');
const css = document.createElement('link');
css.rel = 'stylesheet';
css.href = new URL('./playground.css', import.meta.url).href;
document.head.append(css);
document.title = 'Lensing playground · WSLAP+';

const root = document.createElement('div');
root.id = 'playground';
root.innerHTML = `
  <header class="pg-head">
    <h1>Lensing playground</h1>
    <p class="pg-lede">Mass bends light: drag the lenses (white) on the left or the sources (yellow) on the right and watch the images, critical curves and caustics move.</p>
  </header>
  <div class="pg-bar" id="pg-bar">
    <label><input type="checkbox" id="pg-curves" checked> curves</label>
    <label><input type="checkbox" id="pg-caustics" checked> caustics</label>
    <select id="pg-contours" aria-label="contours">
      <option value="">no contours</option>
      <option value="kappa">κ contours</option>
      <option value="magnification">|μ| contours</option>
      <option value="arrival">arrival time</option>
    </select>
    <label><input type="checkbox" id="pg-timing"> ms/frame</label>
    <button id="pg-share" type="button">Share link</button>
    ${EMBED ? '' : '<button id="pg-download" type="button" title="Both views drawn again at 1024 pixels a side, as a PNG for a slide or a paper">Download PNG</button>'}
    ${EMBED ? '' : '<button id="pg-observe" type="button" title="Freeze the scene into mock telescope data">Observe</button><button id="pg-invert" type="button" hidden>Invert with WSLAP+</button>'}
    ${EMBED ? '<a id="pg-open" target="_blank" rel="noopener">Open full</a>' : '<a href="./?app">Research app</a>'}
  </div>
  <div class="pg-main">
    <div class="pg-views" id="pg-views">
      <figure class="pg-view">
        <canvas id="pg-image" aria-label="image plane: drag the lenses"></canvas>
        <figcaption>Image plane (what the telescope sees) <span id="pg-fov"></span></figcaption>
        <output id="pg-ms" class="pg-ms" hidden></output>
      </figure>
      <figure class="pg-view">
        <canvas id="pg-source" aria-label="source plane: drag the sources"></canvas>
        <figcaption>Source plane (without the lens)</figcaption>
      </figure>
    </div>
    <aside class="pg-panel" id="pg-panel">
      <div class="pg-readout" id="pg-readout">Hover (or tap) the image plane to see where a ray lands; hover (or tap) the source plane to see every image of that point.</div>
      ${EMBED ? '' : '<details class="pg-observe-opts" id="pg-observe-opts"></details>'}
      <div class="pg-palette">
        <span>Add lens:</span>
        ${Object.keys(NEW_LENS).map((k) => `<button type="button" data-lens="${k}">${LENS_NAMES[k]}</button>`).join('')}
      </div>
      <div class="pg-palette">
        <span>Add source:</span>
        ${Object.keys(NEW_SOURCE).map((k) => `<button type="button" data-source="${k}">${SOURCE_NAMES[k]}</button>`).join('')}
        <label class="pg-upload">picture…<input type="file" id="pg-upload" accept="image/png,image/jpeg"></label>
      </div>
      <p class="pg-note">Uploaded pictures stay in this browser: a shared link shows where they were, not the picture.</p>
      <ul class="pg-list" id="pg-list"></ul>
      <div class="pg-params" id="pg-params"></div>
      <div class="pg-params" id="pg-scene-params"></div>
      <p class="pg-error" id="pg-error" hidden></p>
    </aside>
  </div>`;
document.body.append(root);

const $ = (id) => document.getElementById(id);
if (EMBED) {
  // Embedded, the panel is hidden: the read-out (what a hover or a tap says: positions, μ,
  // parity, delays) goes under the two planes instead.
  const stage = document.createElement('div');
  stage.className = 'pg-stage';
  $('pg-views').before(stage);
  stage.append($('pg-views'), $('pg-readout'));
}
const imageCanvas = $('pg-image');
const sourceCanvas = $('pg-source');
const client = new PlaygroundClient();

// ---------------------------------------------------------------- state

let scene = structuredClone(DEFAULT_SCENE);
try {
  const shared = decodeFragment(location.hash);
  if (shared) scene = shared;
} catch (e) {
  showError(`The link's scene could not be read (${e.message}); showing the default scene.`);
}
let selected = { list: 'lenses', index: 0 };
let frame = null; // last frame drawn: {pixels, image, source, curves, points}
let imageBitmap = null;
let sourceBitmap = null;
let contours = [];
let hover = null; // {kind: 'ray', landings, at} | {kind: 'images', images, at}
let drag = null; // {list, index, canvas, pointerId}
let nextSlot = 1;
// Frame timing: round trips from sending a scene to drawing its frame.
const stats = { frames: [], longestTaskMs: 0 };
window.__playground = {
  stats,
  get scene() { return scene; },
  get frame() { return frame; },
  /** The full frame on screen is of the scene as it is now (tests wait for this). */
  get settled() { return frame?.pixels === FULL_PIXELS && frame.sceneText === JSON.stringify(tidyScene(scene)); },
};
try {
  new PerformanceObserver((list) => {
    for (const e of list.getEntries()) stats.longestTaskMs = Math.max(stats.longestTaskMs, e.duration);
  }).observe({ type: 'longtask', buffered: true });
} catch { /* no long-task timing in this browser */ }

function showError(text) {
  const el = $('pg-error');
  if (!el) return;
  el.textContent = text;
  el.hidden = !text;
}

// ---------------------------------------------------------------- coordinates

const fov = () => scene.fov;
const sourceFov = () => scene.source_fov ?? scene.fov / 2;
function toCanvas(canvas, side, x, y) {
  return [(x / side + 0.5) * canvas.width, (0.5 - y / side) * canvas.height];
}
function toSky(canvas, side, ev) {
  const r = canvas.getBoundingClientRect();
  return [((ev.clientX - r.left) / r.width - 0.5) * side, (0.5 - (ev.clientY - r.top) / r.height) * side];
}

// ---------------------------------------------------------------- computing

let sentAt = 0;
async function compute(pixels) {
  const t0 = performance.now();
  sentAt = t0;
  let result;
  let sent;
  try {
    sent = JSON.stringify(tidyScene(scene));
    result = await client.latest('frame', { type: 'frame', scene: sent, pixels });
  } catch (e) {
    showError(e.message);
    return;
  }
  if (!result) return; // replaced by a newer scene
  showError('');
  const n = result.pixels;
  [imageBitmap, sourceBitmap] = await Promise.all([
    createImageBitmap(new ImageData(result.image, n, n)),
    createImageBitmap(new ImageData(result.source, n, n)),
  ]);
  frame = result;
  frame.sceneText = sent;
  draw();
  const ms = performance.now() - t0;
  stats.frames.push({ pixels: n, roundTripMs: ms, computeMs: result.compute_ms, workerMs: result.worker_ms });
  if (stats.frames.length > 500) stats.frames.shift();
  showTiming(n);
  root.dataset.frames = String(Number(root.dataset.frames ?? 0) + 1);
  root.dataset.pixels = String(n);
}

function showTiming(n) {
  const recent = stats.frames.filter((f) => f.pixels === n).slice(-10);
  const mean = recent.reduce((s, f) => s + f.roundTripMs, 0) / Math.max(1, recent.length);
  $('pg-ms').textContent = `${Math.round(mean)} ms/frame (${n}²)`;
}

let contourJob = 0;
async function refreshContours() {
  const kind = $('pg-contours').value;
  const job = ++contourJob;
  if (!kind) { contours = []; draw(); return; }
  const src = scene.sources[selected.list === 'sources' ? selected.index : 0] ?? { x: 0, y: 0, z: 2 };
  const lines = await client.latest('contours', { type: 'contours', kind, pixels: 256, z: src.z, x: src.x, y: src.y })
    .catch((e) => { showError(e.message); return null; });
  if (lines && job === contourJob) { contours = lines; draw(); }
}

/** A scene change while dragging (coarse frame) or after it (full frame, contours, link). */
function changed(final) {
  observed?.clear();
  const drawn = compute(final ? FULL_PIXELS : DRAG_PIXELS);
  if (final) {
    // After the worker has this scene: contours asked for at once were drawn for the last.
    drawn.then(refreshContours);
    history.replaceState(null, '', location.pathname + location.search + encodeFragment(scene));
    updateOpenLink();
  }
}

// ---------------------------------------------------------------- drawing

function sizeCanvases() {
  const dpr = window.devicePixelRatio || 1;
  const views = $('pg-views');
  const bar = $('pg-bar');
  const head = root.querySelector('.pg-head');
  const w = window.innerWidth;
  const h = window.innerHeight;
  let side;
  let stacked;
  if (EMBED) {
    // Everything above the views (the bar, a lesson's card) takes its height from them.
    const top = views.getBoundingClientRect().top + window.scrollY;
    const free = h - top - 2 * 22 - 18 - $('pg-readout').offsetHeight - 6; // captions, read-out, margins
    stacked = w < free * 0.9;
    side = stacked ? Math.min(w - 12, free / 2) : Math.min((w - 24) / 2, free + 22);
  } else {
    const panel = w >= 900 ? (document.body.classList.contains('pg-present') ? 480 : 340) : 0;
    const free = h - bar.offsetHeight - head.offsetHeight - 50;
    stacked = w < 700;
    side = stacked ? Math.min(w - 16, 520) : Math.min((w - panel - 48) / 2, free, 620);
  }
  side = Math.max(120, Math.floor(side));
  views.classList.toggle('stacked', stacked);
  for (const c of [imageCanvas, sourceCanvas]) {
    c.style.width = `${side}px`;
    c.style.height = `${side}px`;
    c.width = Math.round(side * dpr);
    c.height = Math.round(side * dpr);
  }
  draw();
}

function polyline(ctx, canvas, side, points, closed, color, width) {
  if (points.length < 2) return;
  ctx.beginPath();
  points.forEach(([x, y], k) => {
    const [px, py] = toCanvas(canvas, side, x, y);
    if (k === 0) ctx.moveTo(px, py); else ctx.lineTo(px, py);
  });
  if (closed) ctx.closePath();
  ctx.strokeStyle = color;
  ctx.lineWidth = width;
  ctx.stroke();
}

function marker(ctx, px, py, color, r, label) {
  ctx.beginPath();
  ctx.arc(px, py, r, 0, 2 * Math.PI);
  ctx.strokeStyle = color;
  ctx.lineWidth = Math.max(1.5, r / 4);
  ctx.stroke();
  ctx.beginPath();
  ctx.moveTo(px - r * 0.5, py); ctx.lineTo(px + r * 0.5, py);
  ctx.moveTo(px, py - r * 0.5); ctx.lineTo(px, py + r * 0.5);
  ctx.stroke();
  if (label) {
    ctx.fillStyle = color;
    ctx.fillText(label, px + r + 3, py - r);
  }
}

/** Draws both views: on screen (`draw()`), or into the canvases of a downloaded figure
 * (`target`: its canvases, bitmaps and frame, and `unit`, canvas pixels per CSS pixel of the
 * screen's lines and text; no hover marks). */
function draw(target = null) {
  const t = target ?? {
    image: imageCanvas, source: sourceCanvas, imageBitmap, sourceBitmap, frame,
    unit: window.devicePixelRatio || 1, hover,
  };
  const { unit: dpr, hover: marks } = t;
  const fr = t.frame;
  const lw = 1.6 * dpr;
  const font = `${Math.round(12 * dpr)}px system-ui, sans-serif`;
  // Image plane.
  const image = t.image;
  let ctx = image.getContext('2d');
  ctx.font = font;
  ctx.fillStyle = '#080a14';
  ctx.fillRect(0, 0, image.width, image.height);
  if (t.imageBitmap) {
    ctx.imageSmoothingEnabled = true;
    ctx.drawImage(t.imageBitmap, 0, 0, image.width, image.height);
  }
  for (const c of contours) {
    polyline(ctx, image, fov(), c.points, c.closed, COLORS[$('pg-contours').value] ?? '#fff', lw * 0.7);
  }
  if (fr && $('pg-curves').checked) {
    for (const plane of fr.curves) {
      for (const c of plane.tangential) polyline(ctx, image, fov(), c, false, COLORS.tangential, lw);
      for (const r of plane.radial) polyline(ctx, image, fov(), r, false, COLORS.radial, lw);
    }
  }
  scene.lenses.forEach((l, k) => {
    if (!draggable(l)) return;
    const [px, py] = toCanvas(image, fov(), l.x, l.y);
    const on = selected.list === 'lenses' && selected.index === k;
    marker(ctx, px, py, COLORS.lens, (on ? 9 : 7) * dpr, on ? LENS_NAMES[l.type] : '');
  });
  if (fr) {
    for (const p of fr.points) {
      for (const im of p.images) {
        const [px, py] = toCanvas(image, fov(), im.x, im.y);
        const r = Math.min(10, 2 + 2 * Math.sqrt(Math.abs(im.magnification))) * dpr;
        ctx.beginPath();
        ctx.arc(px, py, r, 0, 2 * Math.PI);
        ctx.fillStyle = COLORS.source;
        ctx.fill();
      }
    }
  }
  observed?.draw(ctx, (x, y) => toCanvas(image, fov(), x, y), dpr);
  if (marks?.kind === 'ray') {
    const [px, py] = toCanvas(image, fov(), marks.at[0], marks.at[1]);
    marker(ctx, px, py, COLORS.ray, 6 * dpr);
  }
  if (marks?.kind === 'images') {
    for (const im of marks.images) {
      const [px, py] = toCanvas(image, fov(), im.x, im.y);
      marker(ctx, px, py, COLORS.image, 7 * dpr, `μ=${im.magnification.toFixed(1)}`);
    }
  }
  // Source plane.
  const source = t.source;
  ctx = source.getContext('2d');
  ctx.font = font;
  ctx.fillStyle = '#080a14';
  ctx.fillRect(0, 0, source.width, source.height);
  if (t.sourceBitmap) ctx.drawImage(t.sourceBitmap, 0, 0, source.width, source.height);
  if (fr && $('pg-caustics').checked) {
    for (const plane of fr.curves) {
      for (const c of plane.tangential_caustics) polyline(ctx, source, sourceFov(), c, false, COLORS.tcaustic, lw);
      for (const r of plane.radial_caustics) polyline(ctx, source, sourceFov(), r, false, COLORS.rcaustic, lw);
    }
  }
  scene.sources.forEach((s, k) => {
    const [px, py] = toCanvas(source, sourceFov(), s.x, s.y);
    const on = selected.list === 'sources' && selected.index === k;
    marker(ctx, px, py, COLORS.source, (on ? 8 : 6) * dpr, `z=${s.z}`);
  });
  if (marks?.kind === 'ray') {
    for (const l of marks.landings) {
      const [px, py] = toCanvas(source, sourceFov(), l.x, l.y);
      marker(ctx, px, py, COLORS.ray, 6 * dpr, `z=${l.z}`);
    }
  }
  if (marks?.kind === 'images') {
    const [px, py] = toCanvas(source, sourceFov(), marks.at[0], marks.at[1]);
    marker(ctx, px, py, COLORS.image, 6 * dpr);
  }
}

// ---------------------------------------------------------------- figure download

/** Pixels a side of each view in a downloaded figure: the core's largest frame, twice the
 * full frame on screen. */
const FIGURE_PIXELS = 1024;
/** Screen pixels a side the figure's lines and text are sized for: a view this wide on screen
 * looks like the figure shrunk to it. */
const FIGURE_DESIGN_SIDE = 420;

/** Both views of the scene drawn again by the core at FIGURE_PIXELS a side, side by side with
 * their captions, lines and text as on screen grown with the figure; a PNG Blob. */
async function figurePng() {
  const sent = JSON.stringify(tidyScene(scene));
  const big = await client.request({ type: 'frame', scene: sent, pixels: FIGURE_PIXELS });
  // The next live frame is computed for the scene again (the worker's session is shared).
  const n = big.pixels;
  const [imageBits, sourceBits] = await Promise.all([
    createImageBitmap(new ImageData(big.image, n, n)),
    createImageBitmap(new ImageData(big.source, n, n)),
  ]);
  const unit = n / FIGURE_DESIGN_SIDE;
  const panel = () => { const c = document.createElement('canvas'); c.width = n; c.height = n; return c; };
  const [image, source] = [panel(), panel()];
  draw({ image, source, imageBitmap: imageBits, sourceBitmap: sourceBits, frame: big, unit, hover: null });
  const gap = Math.round(12 * unit);
  const fontPx = Math.round(13 * unit);
  const band = Math.round(fontPx * 1.8);
  const fig = document.createElement('canvas');
  fig.width = 2 * n + 3 * gap;
  fig.height = n + band + 2 * gap;
  const ctx = fig.getContext('2d');
  ctx.fillStyle = '#0c0f1c';
  ctx.fillRect(0, 0, fig.width, fig.height);
  ctx.drawImage(image, gap, gap);
  ctx.drawImage(source, 2 * gap + n, gap);
  ctx.fillStyle = '#c9cfe6';
  ctx.font = `${fontPx}px system-ui, sans-serif`;
  ctx.textBaseline = 'middle';
  const y = gap + n + band / 2;
  ctx.fillText(`Image plane, ${fov()}″ across (what the telescope sees)`, gap, y);
  ctx.fillText(`Source plane, ${sourceFov()}″ across (without the lens)`, 2 * gap + n, y);
  return new Promise((resolve, reject) => fig.toBlob((b) => (b ? resolve(b) : reject(new Error('the browser made no PNG'))), 'image/png'));
}

async function downloadFigure() {
  const button = $('pg-download');
  button.disabled = true;
  try {
    const blob = await figurePng();
    const a = document.createElement('a');
    a.href = URL.createObjectURL(blob);
    a.download = `lensing-playground-${FIGURE_PIXELS}px.png`;
    document.body.append(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(a.href), 10_000);
  } catch (e) {
    showError(`The figure could not be made: ${e.message}`);
  } finally {
    button.disabled = false;
  }
}

// ---------------------------------------------------------------- pointer

function hit(list, canvas, side, ev) {
  const r = canvas.getBoundingClientRect();
  const [x, y] = toSky(canvas, side, ev);
  const reach = (EMBED || ev.pointerType === 'touch' ? 22 : 12) / r.width * side;
  let best = -1;
  let bestD = reach;
  scene[list].forEach((item, k) => {
    if (!draggable(item)) return;
    const d = Math.hypot(item.x - x, item.y - y);
    if (d < bestD) { best = k; bestD = d; }
  });
  return best;
}

function wirePointer(canvas, list, side) {
  canvas.addEventListener('pointerdown', (ev) => {
    const k = hit(list, canvas, side(), ev);
    if (k < 0) {
      // A touch screen has no hover: a tap away from the handles reads out where it lands.
      if (ev.pointerType !== 'mouse') hoverAt(list, ...toSky(canvas, side(), ev));
      return;
    }
    ev.preventDefault();
    canvas.setPointerCapture(ev.pointerId);
    const [x, y] = toSky(canvas, side(), ev);
    const item = scene[list][k];
    drag = { list, index: k, canvas, pointerId: ev.pointerId, dx: item.x - x, dy: item.y - y };
    selected = { list, index: k };
    hover = null;
    showList();
    showParams();
  });
  canvas.addEventListener('pointermove', (ev) => {
    const [x, y] = toSky(canvas, side(), ev);
    if (drag && drag.canvas === canvas && drag.pointerId === ev.pointerId) {
      const item = scene[drag.list][drag.index];
      item.x = Number((x + drag.dx).toFixed(3));
      item.y = Number((y + drag.dy).toFixed(3));
      syncParams();
      changed(false);
      return;
    }
    if (ev.pointerType === 'touch') return;
    hoverAt(list, x, y);
  });
  const end = (ev) => {
    if (drag && drag.pointerId === ev.pointerId) {
      drag = null;
      changed(true);
    }
  };
  canvas.addEventListener('pointerup', end);
  canvas.addEventListener('pointercancel', end);
  canvas.addEventListener('pointerleave', () => { if (!drag) { hover = null; draw(); } });
}

async function hoverAt(list, x, y) {
  if (list === 'lenses') {
    const landings = await client.latest('hover', { type: 'ray', x, y }).catch(() => null);
    if (!landings || drag) return;
    hover = { kind: 'ray', landings, at: [x, y] };
    $('pg-readout').textContent = `Ray seen at (${x.toFixed(2)}″, ${y.toFixed(2)}″) lands at ` +
      landings.map((l) => `(${l.x.toFixed(2)}″, ${l.y.toFixed(2)}″) for z = ${l.z} (μ = ${l.magnification.toFixed(2)})`).join('; ');
  } else {
    const src = scene.sources[selected.list === 'sources' ? selected.index : 0];
    const z = src?.z ?? 2;
    const images = await client.latest('hover', { type: 'images', x, y, z }).catch(() => null);
    if (!images || drag) return;
    hover = { kind: 'images', images, at: [x, y] };
    const rows = images.map((im, k) => `<tr><td>${k + 1}</td><td>(${im.x.toFixed(2)}, ${im.y.toFixed(2)})</td>` +
      `<td>${im.magnification.toFixed(2)}</td><td>${im.parity}</td><td>${im.kind}</td><td>${im.delay_days.toFixed(1)}</td></tr>`).join('');
    $('pg-readout').innerHTML = `${images.length} image${images.length === 1 ? '' : 's'} of a point at ` +
      `(${x.toFixed(2)}″, ${y.toFixed(2)}″), z = ${z}:` +
      `<table><tr><th>#</th><th>position (″)</th><th>μ</th><th>parity</th><th>arrival</th><th>delay (days)</th></tr>${rows}</table>`;
  }
  draw();
}

// ---------------------------------------------------------------- panel

function itemName(list, item) {
  return list === 'lenses' ? LENS_NAMES[item.type] ?? item.type : item.type === 'point' ? 'point source' : `${SOURCE_NAMES[item.type] ?? item.type} source`;
}

function showList() {
  const ul = $('pg-list');
  ul.innerHTML = '';
  for (const list of ['lenses', 'sources']) {
    scene[list].forEach((item, k) => {
      const li = document.createElement('li');
      const on = selected.list === list && selected.index === k;
      li.className = on ? 'on' : '';
      const b = document.createElement('button');
      b.type = 'button';
      b.textContent = itemName(list, item) + (item.type === 'image' ? ' (picture)' : '');
      b.onclick = () => { selected = { list, index: k }; showList(); showParams(); draw(); refreshContours(); };
      const x = document.createElement('button');
      x.type = 'button';
      x.className = 'pg-remove';
      x.textContent = '×';
      x.title = 'remove';
      x.onclick = () => {
        scene[list].splice(k, 1);
        selected = { list: 'lenses', index: 0 };
        showList(); showParams(); changed(true);
      };
      li.append(b, x);
      ul.append(li);
    });
  }
}

function fieldRow(obj, [field, label, min, max, step, log], onInput) {
  const row = document.createElement('label');
  row.className = 'pg-field';
  const name = document.createElement('span');
  name.textContent = label;
  const slider = document.createElement('input');
  slider.type = 'range';
  const number = document.createElement('input');
  number.type = 'number';
  number.step = 'any';
  number.dataset.field = field;
  const toSlider = (v) => (log ? Math.log10(v) : v);
  slider.min = String(toSlider(min));
  slider.max = String(toSlider(max));
  slider.step = String(step);
  const set = () => { slider.value = String(toSlider(obj[field])); number.value = String(obj[field]); };
  set();
  slider.addEventListener('input', () => {
    const v = log ? Number((10 ** Number(slider.value)).toPrecision(4)) : Number(slider.value);
    obj[field] = v;
    number.value = String(v);
    onInput(false);
  });
  slider.addEventListener('change', () => onInput(true));
  number.addEventListener('change', () => {
    const v = Number(number.value);
    if (!Number.isFinite(v)) { set(); return; }
    obj[field] = v;
    slider.value = String(toSlider(v));
    onInput(true);
  });
  row.sync = set;
  row.append(name, slider, number);
  return row;
}

function showParams() {
  const box = $('pg-params');
  box.innerHTML = '';
  const item = scene[selected.list]?.[selected.index];
  if (item) {
    const h = document.createElement('h2');
    h.textContent = itemName(selected.list, item);
    box.append(h);
    const fields = (selected.list === 'lenses' ? FIELDS : SOURCE_FIELDS)[item.type] ?? [];
    for (const f of fields) box.append(fieldRow(item, f, changed));
  }
  const sp = $('pg-scene-params');
  sp.innerHTML = '<h2>Scene</h2>';
  sp.append(fieldRow(scene, ['z_lens', 'lens redshift', 0.05, 1.5, 0.01], changed));
  sp.append(fieldRow(scene, ['fov', 'field of view (″)', 5, 200, 1], (final) => { changed(final); }));
}

function syncParams() {
  for (const row of $('pg-params').querySelectorAll('.pg-field')) row.sync?.();
}

function add(list, template) {
  scene[list].push(structuredClone(template));
  selected = { list, index: scene[list].length - 1 };
  showList(); showParams(); changed(true);
}

root.querySelectorAll('[data-lens]').forEach((b) => { b.onclick = () => add('lenses', NEW_LENS[b.dataset.lens]); });
root.querySelectorAll('[data-source]').forEach((b) => { b.onclick = () => add('sources', NEW_SOURCE[b.dataset.source]); });
$('pg-upload').addEventListener('change', async (ev) => {
  const file = ev.target.files?.[0];
  if (!file) return;
  const slot = nextSlot++;
  try {
    await client.request({ type: 'picture', slot, blob: file });
  } catch (e) { showError(`The picture could not be read: ${e.message}`); return; }
  add('sources', { type: 'image', x: 0.3, y: 0.3, z: 2, size: Number((sourceFov() / 3).toFixed(2)), slot });
  ev.target.value = '';
});

// ---------------------------------------------------------------- toggles, share, embed

$('pg-curves').onchange = () => draw();
$('pg-caustics').onchange = () => draw();
$('pg-contours').onchange = refreshContours;
$('pg-timing').onchange = () => { $('pg-ms').hidden = !$('pg-timing').checked; };
if (!EMBED) $('pg-download').onclick = downloadFigure;
$('pg-share').onclick = async () => {
  const link = location.origin + location.pathname + '?playground' + encodeFragment(scene);
  try {
    await navigator.clipboard.writeText(link);
    $('pg-readout').textContent = 'Link copied: it reopens this scene (uploaded pictures are not in it).';
  } catch {
    $('pg-readout').textContent = `Link to this scene (uploaded pictures are not in it): ${link}`;
  }
};
function updateOpenLink() {
  const a = $('pg-open');
  if (a) a.href = location.pathname + '?playground' + encodeFragment(scene);
}

/** What a lesson (./lessons.js) may do to the playground: put a scene in and set the
 * toggles as the lesson wants them; `resize` after its panel changed size. */
export const api = {
  root,
  EMBED,
  hasSharedScene: Boolean(location.hash && decodeFragmentSafe(location.hash)),
  loadScene(next, show = {}) {
    scene = structuredClone(next);
    selected = { list: 'lenses', index: 0 };
    hover = null;
    if (show.curves !== undefined) $('pg-curves').checked = show.curves;
    if (show.caustics !== undefined) $('pg-caustics').checked = show.caustics;
    if (show.contours !== undefined) $('pg-contours').value = show.contours;
    showList();
    showParams();
    changed(true);
  },
  setToggles(show = {}) {
    if (show.curves !== undefined) $('pg-curves').checked = show.curves;
    if (show.caustics !== undefined) $('pg-caustics').checked = show.caustics;
    if (show.contours !== undefined) $('pg-contours').value = show.contours;
    refreshContours();
    draw();
  },
  resize: () => sizeCanvases(),
};
function decodeFragmentSafe(hash) {
  try { return decodeFragment(hash); } catch { return null; }
}

$('pg-fov').textContent = '';
// Observe, then Invert (./observe.js); not in an embedded playground.
const observed = EMBED ? null : wireObserve({
  client, observeButton: $('pg-observe'), invertButton: $('pg-invert'), getScene: () => scene,
  redraw: () => draw(), say: (text) => { $('pg-readout').textContent = text; }, tidy: tidyScene,
  getOptions: wireObserveOptions($('pg-observe-opts'), fov),
});
wirePointer(imageCanvas, 'lenses', fov);
wirePointer(sourceCanvas, 'sources', sourceFov);
window.addEventListener('resize', sizeCanvases);
showList();
showParams();
sizeCanvases();
updateOpenLink();
compute(FULL_PIXELS).then(() => { root.dataset.ready = '1'; });
if (params.has('lesson')) {
  import('./lessons.js').then((m) => m.startLessons(api, params.get('lesson')))
    .catch((e) => showError(`The lessons could not be opened: ${e.message}`));
}

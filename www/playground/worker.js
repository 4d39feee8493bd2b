// Runs the playground's lensing (the Rust core compiled to WebAssembly) off the main thread.
// One PlaygroundSession; one message switch on `msg.type`; every answer carries the job's id.
// All physics is the core's: this file only passes scenes in and pixels and curves out.

import init, { PlaygroundSession } from '../pkg/wslap.js';
import '../js/simd.js';

/** The relaxed-SIMD core where it runs (unless `?simd=baseline`), else the baseline one, as
 * www/worker.js chooses. */
async function loadCore() {
  const relaxed = new URL('../' + self.wslapCore.relaxed, import.meta.url);
  const baseline = new URL('../' + self.wslapCore.baseline, import.meta.url);
  const forced = new URLSearchParams(self.location.search).get('simd');
  if (forced !== 'baseline' && self.wslapCore.hasRelaxedSimd()) {
    try { await init({ module_or_path: relaxed }); return; } catch { /* use the baseline */ }
  }
  await init({ module_or_path: baseline });
}

const ready = loadCore();
let session = null;
// Longest side, in pixels, an uploaded picture is kept at.
const PICTURE_SIDE = 512;

/** RGBA pixels of an uploaded PNG/JPEG, scaled to at most PICTURE_SIDE a side. */
async function picturePixels(blob) {
  const bitmap = await createImageBitmap(blob);
  const scale = Math.min(1, PICTURE_SIDE / Math.max(bitmap.width, bitmap.height));
  const w = Math.max(1, Math.round(bitmap.width * scale));
  const h = Math.max(1, Math.round(bitmap.height * scale));
  const canvas = new OffscreenCanvas(w, h);
  const ctx = canvas.getContext('2d');
  ctx.drawImage(bitmap, 0, 0, w, h);
  bitmap.close();
  return { w, h, rgba: new Uint8Array(ctx.getImageData(0, 0, w, h).data.buffer) };
}

async function handle(msg) {
  await ready;
  switch (msg.type) {
    case 'frame': {
      const t0 = performance.now();
      if (session) session.set_scene(msg.scene);
      else session = new PlaygroundSession(msg.scene);
      const frame = session.frame(msg.pixels);
      frame.worker_ms = performance.now() - t0;
      return [frame, [frame.image.buffer, frame.source.buffer]];
    }
    case 'picture': {
      const { w, h, rgba } = await picturePixels(msg.blob);
      session?.set_picture(msg.slot, w, h, rgba);
      return [{ width: w, height: h }];
    }
    case 'ray': return [session ? session.ray(msg.x, msg.y) : []];
    case 'images': return [session ? session.images_of(msg.x, msg.y, msg.z) : []];
    case 'contours':
      return [session ? session.contours(msg.kind, msg.pixels, msg.z, msg.x, msg.y) : []];
    case 'truth': return [session ? session.truth_model_json() : null];
    case 'observe': {
      if (session) session.set_scene(msg.scene);
      else session = new PlaygroundSession(msg.scene);
      return [session.observe(JSON.stringify(msg.options ?? {}))];
    }
    default: throw new Error(`unknown job type ${msg.type}`);
  }
}

// Jobs run one at a time in the order they came.
let queue = Promise.resolve();
self.onmessage = (e) => {
  const msg = e.data;
  queue = queue.then(async () => {
    try {
      const [result, transfer = []] = await handle(msg);
      self.postMessage({ id: msg.id, result }, transfer);
    } catch (err) {
      self.postMessage({ id: msg.id, error: String(err?.message ?? err) });
    }
  });
};

// Runs the WSLAP+ core (Rust compiled to WebAssembly) off the main thread. It holds one
// AppSession; one message switch on `msg.type`; every job answers `result` or `error` by id.

import init, * as core from './pkg/wslap.js';

let session = null;

const handlers = {
  loadText: (m) => session.load_text(m.role, m.name, m.text),
  clear: (m) => session.clear(m.role),
  loadFits: (m) => session.load_fits(m.axis, m.name, new Uint8Array(m.bytes)),
  settings: () => session.settings(),
  setField: (m) => session.set_field(m.path, m.value),
  setName: (m) => session.set_name(m.name),
  // Throttled progress (at most every 100 ms) is posted from inside the Rust loop.
  run: (m, progress) => session.run(m.kind, progress),
  resultInfo: () => session.result_info(),
  setZSource: (m) => session.set_z_source(m.z),
  view: (m) => ({ png: session.view(m.name, m.options ?? null) }),
  hover: (m) => session.hover(m.options ?? null, m.x, m.y),
  sources: () => session.sources(),
  textFile: (m) => session.text_file(m.name),
  fitsFiles: () => session.fits_files(),
  openProject: (m) => session.open_project(m.text, m.name),
  loaded: () => session.loaded(),
  // A fresh session (used after a cancel restarted the worker, or to start over).
  reset: () => { session = new core.AppSession(); return {}; },
};

function transferables(result) {
  if (result?.png) return [result.png.buffer];
  if (Array.isArray(result)) return result.filter((f) => f?.bytes).map((f) => f.bytes.buffer);
  return [];
}

async function start() {
  try {
    await init();
    session = new core.AppSession();
  } catch (err) {
    postMessage({ type: 'fatal', message: String(err?.message ?? err) });
    return;
  }
  self.onmessage = (event) => {
    const msg = event.data;
    const progress = (p) => postMessage({ id: msg.id, type: 'progress', ...p });
    const handler = handlers[msg.type];
    try {
      if (!handler) throw new Error(`unknown job type '${msg.type}'`);
      const result = handler(msg, progress) ?? {};
      postMessage({ id: msg.id, type: 'result', result }, transferables(result));
    } catch (err) {
      postMessage({ id: msg.id, type: 'error', message: String(err?.message ?? err) });
    }
  };
  postMessage({ type: 'ready', version: core.version() });
}

start();

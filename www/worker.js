// Runs the WSLAP+ core (Rust compiled to WebAssembly) off the main thread. It holds one
// AppSession; one message switch on `msg.type`; every job answers `result` or `error` by id.
// A failure inside the core (a panic, or memory it could not get) aborts the WebAssembly
// instance, which cannot be used again: the job's answer says so (`crashed`), the worker takes
// no more jobs, and lens-client.js replaces it and restores the session.

import init, * as core from './pkg/wslap.js';
import './js/simd.js';

// The two builds of the core (js/simd.js). `?simd=baseline` on the page (passed on by
// lens-client.js) forces the baseline module.
const CORE = {
  relaxed: new URL(self.wslapCore.relaxed, import.meta.url),
  baseline: new URL(self.wslapCore.baseline, import.meta.url),
};

// The core's exports once loaded (its `memory` is the WebAssembly memory the session lives in).
let exports = null;

// Loads the relaxed-SIMD core where it can run, else (or if it fails to load) the baseline one;
// returns which.
async function loadCore() {
  const forced = new URLSearchParams(self.location.search).get('simd');
  if (forced !== 'baseline' && self.wslapCore.hasRelaxedSimd()) {
    try {
      exports = await init({ module_or_path: CORE.relaxed });
      return 'relaxed';
    } catch { /* e.g. a build without the second module: use the baseline one */ }
  }
  exports = await init({ module_or_path: CORE.baseline });
  return 'baseline';
}

/** The size of the core's WebAssembly memory (bytes). It only grows: its high-water mark.
 * Also a worker global, read by the soak test (tests/e2e/soak.mjs) from outside the page. */
self.wslapMemory = () => ({ wasm_bytes: exports?.memory?.buffer?.byteLength ?? null });

let session = null;

// `?test-panic=JOB` (passed on by lens-client.js to the first worker only): the first job of
// type JOB panics inside the core instead, for the page's test of a failure of the core
// (tests/e2e/recovery.test.mjs).
let testPanic = new URLSearchParams(self.location.search).get('test-panic');

/** The message of a failure inside the core: the panic's (worker-global `wslapPanic`, set by
 * the core's panic hook), else the trap's ("unreachable" for an abort, which is also how an
 * allocation the browser refuses ends). */
function coreFailure(err) {
  const why = self.wslapPanic ?? (err.message === 'unreachable'
    ? 'it stopped at once, out of memory or at a bug ("unreachable")' : err.message);
  return `The computation failed inside the core: ${why}; the session was restarted with your data.`;
}

/** The value at dot path `path` (e.g. 'reconstruct.grid.cells') of `obj`, or undefined. */
const valueAt = (obj, path) => path.split('.').reduce((o, k) => (o == null ? undefined : o[k]), obj);

const handlers = {
  loadText: (m) => session.load_text(m.role, m.name, m.text),
  uncommentMembers: (m) => session.uncomment_members(Uint32Array.from(m.lines)),
  clear: (m) => session.clear(m.role),
  loadFits: (m) => session.load_fits(m.axis, m.name, new Uint8Array(m.bytes)),
  settings: () => session.settings(),
  setField: (m) => session.set_field(m.path, m.value),
  // The settings of `m.fields` ([dot path, value] pairs: an example's) that still have those
  // values go back to their defaults, in one job. A reset refused with the others as they are
  // (the exact solver while the example's regulariser is still "none") is tried again after
  // them, until a round changes nothing. Returns the settings.
  resetSettings: (m) => {
    const fresh = new core.AppSession();
    let defaults;
    try { defaults = fresh.settings(); } finally { fresh.free(); }
    const current = session.settings();
    let todo = m.fields.filter(([path, value]) => valueAt(current, path) === value);
    while (todo.length) {
      const refused = todo.filter(([path]) => {
        try { session.set_field(path, valueAt(defaults, path)); return false; } catch { return true; }
      });
      if (refused.length === todo.length) break;
      todo = refused;
    }
    return session.settings();
  },
  setName: (m) => session.set_name(m.name),
  // Throttled progress (at most every 100 ms) is posted from inside the Rust loop.
  run: (m, progress) => session.run(m.kind, progress),
  // An "auto" regulariser strength in pieces (js/pool.js): the plan (`{plan: null}` when the
  // strength is a number or too few systems can be held out), one candidate's
  // cross-validation (in a pool worker), then the reconstruction with the strength they choose.
  strengthPlan: () => ({ plan: session.strength_plan() }),
  strengthTrial: (m, progress) => session.strength_trial(m.candidate, m.folds, m.estimates ?? null, progress),
  runWithTrials: (m, progress) => session.run_with_trials(m.trials, m.folds, progress),
  // The second round, after a run that estimated redshifts (`{round: null}` without one): its
  // candidates are tried like the first's, with its `estimates`, then the choice made again.
  secondStrengthRound: () => ({ round: session.second_strength_round() }),
  chooseAgainWithTrials: (m, progress) => session.choose_again_with_trials(m.trials, progress),
  // An ensemble (js/ensemble.js): the plan (`{plan: null}` without one), a member (in a pool
  // worker), each member handed to the main worker, then combined.
  ensemblePlan: () => ({ plan: session.ensemble_plan() }),
  ensembleMember: (m, progress) => session.ensemble_member(m.plan, m.member, progress),
  ensembleAdd: (m) => session.ensemble_add(m.record, m.kappa, m.magnif),
  ensembleFinish: (m) => session.ensemble_finish(m.plan, m.complete),
  ensembleInfo: () => session.ensemble_info(),
  ensembleFiles: () => session.ensemble_files(),
  crossValidate: (m, progress) => session.cross_validate(progress),
  crossvalFiles: () => session.crossval_files(),
  verdict: () => session.verdict(),
  resultInfo: () => session.result_info(),
  // The iterates the last reconstruction kept (`{iterates: null}` when none), for the slider.
  iterates: () => ({ iterates: session.iterates() }),
  setZSource: (m) => session.set_z_source(m.z),
  view: (m) => ({ png: session.view(m.name, m.options ?? null) }),
  hover: (m) => session.hover(m.options ?? null, m.x, m.y),
  pointReadout: (m) => session.point_readout(m.options ?? null, m.x, m.y),
  locate: (m) => session.locate(m.text),
  counterImages: (m) => session.counter_images(m.x, m.y),
  counterImageRegions: (m) => session.counter_image_regions(m.x, m.y),
  sources: () => session.sources(),
  textFile: (m) => session.text_file(m.name),
  fitsFiles: () => session.fits_files(),
  openProject: (m) => session.open_project(m.text, m.name),
  loaded: () => session.loaded(),
  memory: () => self.wslapMemory(),
  reload: (m) => session.reload(m.role),
  // A fresh session (used after a cancel restarted the worker, or to start over).
  reset: () => { session = new core.AppSession(); return {}; },
  clearResult: () => { session.clear_result(); return {}; },
};

function transferables(result) {
  if (result?.png) return [result.png.buffer];
  if (result?.kappa && result?.magnif) return [result.kappa.buffer, result.magnif.buffer];
  if (Array.isArray(result)) return result.filter((f) => f?.bytes).map((f) => f.bytes.buffer);
  return [];
}

async function start() {
  let simd;
  try {
    simd = await loadCore();
    session = new core.AppSession();
  } catch (err) {
    postMessage({ type: 'fatal', message: String(err?.message ?? err) });
    return;
  }
  self.onmessage = (event) => {
    const msg = event.data;
    const progress = (p) => postMessage({ id: msg.id, type: 'progress', ...p });
    let handler = handlers[msg.type];
    if (msg.type === testPanic) {
      testPanic = null;
      handler = () => session.fail_for_test();
    }
    try {
      if (!handler) throw new Error(`unknown job type '${msg.type}'`);
      const result = handler(msg, progress) ?? {};
      postMessage({ id: msg.id, type: 'result', result }, transferables(result));
    } catch (err) {
      if (err instanceof WebAssembly.RuntimeError) {
        // The instance is unusable (a call now fails with "recursive use of an object"):
        // answer this job and any sent meanwhile as crashed; lens-client.js ends this worker.
        const message = coreFailure(err);
        self.onmessage = (e) => postMessage({ id: e.data.id, type: 'error', message, crashed: true });
        postMessage({ id: msg.id, type: 'error', message, crashed: true });
        return;
      }
      // `code` names the error's kind where the core gives one (e.g. 'wants-par').
      postMessage({ id: msg.id, type: 'error', message: String(err?.message ?? err), code: err?.code });
    }
  };
  postMessage({ type: 'ready', version: core.version(), simd });
}

start();

// Runs the WSLAP+ core (Rust compiled to WebAssembly) off the main thread.
// One message switch on `msg.type`; every job answers with `result` or `error` under its id.

import init, * as core from './pkg/wslap.js';

const handlers = {
  // Maps, critical curves and the kappa figure for a model file (forward mode).
  forward(msg, progress) {
    progress('Computing maps and critical curves…');
    const started = performance.now();
    const result = core.forward_products(msg.model ?? core.example_model_json(), msg.options ?? {});
    const elapsedMs = performance.now() - started;
    return { ...result, elapsedMs };
  },
  // Parses and checks a model file; throws an error naming the file, line and field.
  validateModel(msg) {
    core.validate_model(msg.model, msg.name ?? 'model.json');
    return {};
  },
  exampleModel() {
    return { model: core.example_model_json() };
  },
};

async function start() {
  try {
    await init();
  } catch (err) {
    postMessage({ type: 'fatal', message: String(err?.message ?? err) });
    return;
  }
  self.onmessage = (event) => {
    const msg = event.data;
    const progress = (message) => postMessage({ id: msg.id, type: 'progress', message });
    const handler = handlers[msg.type];
    try {
      if (!handler) throw new Error(`unknown job type '${msg.type}'`);
      const result = handler(msg, progress);
      const transfer = result.png ? [result.png.buffer] : [];
      postMessage({ id: msg.id, type: 'result', result }, transfer);
    } catch (err) {
      postMessage({ id: msg.id, type: 'error', message: String(err?.message ?? err) });
    }
  };
  postMessage({ type: 'ready', version: core.version() });
}

start();

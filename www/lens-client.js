// The only module that owns Workers: it starts one, sends jobs, routes progress and results
// back to their callers, and cancels by terminating the worker and starting a fresh one (the
// pool of js/pool.js closes its workers instead). When the core fails inside the worker (a
// panic ends its WebAssembly instance) or the worker dies, it starts a fresh one the same way
// and lets the page put its session back before any other job (`onRestart`).

const WORKER_URL = new URL('./worker.js', import.meta.url);
// `?simd=baseline` on the page makes the worker use the baseline-SIMD core (see worker.js).
const pageParams = new URLSearchParams(globalThis.location?.search ?? '');
const simdChoice = pageParams.get('simd');
if (simdChoice) WORKER_URL.searchParams.set('simd', simdChoice);

export class LensClient {
  /** `name`, when given, is added to the worker's URL (`?worker=name`), which tells a pool
   * worker from the main one in the browser's tools and in tests; the worker ignores it.
   * `onRestart(send, message)`, after a failure of the core (`message` says which), gets the
   * fresh worker first: `send(type, payload)` runs a job there before any other is sent. */
  constructor({ onReady, onCrash, onRestart, name } = {}) {
    this.onReady = onReady ?? (() => {});
    this.onCrash = onCrash ?? (() => {});
    this.onRestart = onRestart ?? (async () => {});
    this.url = new URL(WORKER_URL);
    if (name) this.url.searchParams.set('worker', name);
    // `?test-panic=JOB` (tests/e2e/recovery.test.mjs): the main worker's first JOB panics in
    // the core; the workers started after it do not.
    const testPanic = pageParams.get('test-panic');
    this.firstUrl = new URL(this.url);
    if (testPanic && !name) this.firstUrl.searchParams.set('test-panic', testPanic);
    this.nextId = 1;
    this.pending = new Map();
    this.restoring = false;
    this.start();
  }

  start() {
    this.worker = new Worker(this.firstUrl ?? this.url, { type: 'module' });
    this.firstUrl = null;
    this.started = false;
    this.ready = new Promise((resolve, reject) => {
      this.resolveReady = resolve;
      this.rejectReady = reject;
    });
    this.worker.onmessage = (event) => this.receive(event.data);
    this.worker.onerror = (event) => {
      event.preventDefault();
      if (this.started) {
        // It ran, so it can run again: a fresh one with the session put back.
        this.restart(`The worker failed (${event.message || 'no reason given'}); it was restarted with your data.`);
        return;
      }
      const message = `The worker failed: ${event.message || 'it could not be loaded'}`;
      this.rejectReady(new Error(message));
      this.failAll(message);
      this.onCrash(message);
    };
  }

  receive(msg) {
    if (msg.type === 'ready') {
      this.started = true;
      this.resolveReady(msg);
      this.onReady(msg);
      return;
    }
    if (msg.type === 'fatal') {
      const message = `The worker could not start: ${msg.message}`;
      this.rejectReady(new Error(message));
      this.failAll(message);
      this.onCrash(message);
      return;
    }
    if (msg.type === 'error' && msg.crashed) {
      this.restart(msg.message);
      return;
    }
    const job = this.pending.get(msg.id);
    if (!job) return; // a job cancelled meanwhile
    if (msg.type === 'progress') {
      job.onProgress(msg);
    } else if (msg.type === 'result') {
      this.pending.delete(msg.id);
      job.resolve(msg.result);
    } else if (msg.type === 'error') {
      this.pending.delete(msg.id);
      const err = new Error(msg.message);
      if (msg.code) err.code = msg.code;
      job.reject(err);
    }
  }

  failAll(message) {
    for (const job of this.pending.values()) job.reject(new Error(message));
    this.pending.clear();
  }

  /** Sends one job; resolves with its result. `onProgress` receives progress messages. */
  async request(type, payload, onProgress = () => {}) {
    await this.ready;
    return this.post(type, payload, onProgress);
  }

  /** Sends one job now, ready or not. */
  post(type, payload, onProgress = () => {}) {
    const id = this.nextId++;
    return new Promise((resolve, reject) => {
      this.pending.set(id, { resolve, reject, onProgress });
      this.worker.postMessage({ id, type, ...payload });
    });
  }

  /** Stops every running job at once and starts a fresh worker. */
  cancel() {
    this.close();
    this.start();
  }

  /** The core failed with `message`: every running job fails with it (`crashed` set), a fresh
   * worker starts, and `onRestart` restores the session there before `ready` resolves. A
   * failure while restoring starts one more worker, left empty (the restore would fail
   * again). */
  restart(message) {
    const again = this.restoring;
    const err = new Error(message);
    err.crashed = true;
    this.close(err);
    this.start();
    const { worker, ready } = this;
    this.restoring = !again;
    const gated = ready.then(async (info) => {
      if (!again) {
        try {
          await this.onRestart((type, payload) => this.post(type, payload), message);
        } catch { /* the fresh worker keeps an empty session */ } finally {
          if (this.worker === worker) this.restoring = false;
        }
      }
      // Failed again meanwhile: the jobs waiting go to the newest worker once it is ready.
      return this.ready === gated ? info : this.ready;
    });
    this.ready = gated;
    this.ready.catch(() => {});
  }

  /** Stops the worker and every running job at once (they fail with `reason`: cancelled
   * unless given). */
  close(reason = cancelled()) {
    this.worker.terminate();
    this.worker.onmessage = null;
    this.worker.onerror = null;
    this.rejectReady(reason);
    this.ready.catch(() => {});
    const jobs = [...this.pending.values()];
    this.pending.clear();
    for (const job of jobs) job.reject(reason);
  }
}

function cancelled() {
  const err = new Error('Cancelled');
  err.cancelled = true;
  return err;
}

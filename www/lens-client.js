// The only module that owns Workers: it starts one, sends jobs, routes progress and results
// back to their callers, and cancels by terminating the worker and starting a fresh one (the
// pool of js/pool.js closes its workers instead).

const WORKER_URL = new URL('./worker.js', import.meta.url);
// `?simd=baseline` on the page makes the worker use the baseline-SIMD core (see worker.js).
const simdChoice = new URLSearchParams(globalThis.location?.search ?? '').get('simd');
if (simdChoice) WORKER_URL.searchParams.set('simd', simdChoice);

export class LensClient {
  /** `name`, when given, is added to the worker's URL (`?worker=name`), which tells a pool
   * worker from the main one in the browser's tools and in tests; the worker ignores it. */
  constructor({ onReady, onCrash, name } = {}) {
    this.onReady = onReady ?? (() => {});
    this.onCrash = onCrash ?? (() => {});
    this.url = new URL(WORKER_URL);
    if (name) this.url.searchParams.set('worker', name);
    this.nextId = 1;
    this.pending = new Map();
    this.start();
  }

  start() {
    this.worker = new Worker(this.url, { type: 'module' });
    this.ready = new Promise((resolve, reject) => {
      this.resolveReady = resolve;
      this.rejectReady = reject;
    });
    this.worker.onmessage = (event) => this.receive(event.data);
    this.worker.onerror = (event) => {
      event.preventDefault();
      const message = `The worker failed: ${event.message || 'it could not be loaded'}`;
      this.rejectReady(new Error(message));
      this.failAll(message);
      this.onCrash(message);
    };
  }

  receive(msg) {
    if (msg.type === 'ready') {
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
    const job = this.pending.get(msg.id);
    if (!job) return; // a job cancelled meanwhile
    if (msg.type === 'progress') {
      job.onProgress(msg);
    } else if (msg.type === 'result') {
      this.pending.delete(msg.id);
      job.resolve(msg.result);
    } else if (msg.type === 'error') {
      this.pending.delete(msg.id);
      job.reject(new Error(msg.message));
    }
  }

  failAll(message) {
    for (const job of this.pending.values()) job.reject(new Error(message));
    this.pending.clear();
  }

  /** Sends one job; resolves with its result. `onProgress` receives progress messages. */
  async request(type, payload, onProgress = () => {}) {
    await this.ready;
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

  /** Stops the worker and every running job at once (they fail as cancelled). */
  close() {
    this.worker.terminate();
    this.worker.onmessage = null;
    this.worker.onerror = null;
    this.rejectReady(cancelled());
    this.ready.catch(() => {});
    const jobs = [...this.pending.values()];
    this.pending.clear();
    for (const job of jobs) job.reject(cancelled());
  }
}

function cancelled() {
  const err = new Error('Cancelled');
  err.cancelled = true;
  return err;
}

// The one module that talks to the playground's worker. Jobs go by channel: a channel has at
// most one job in the worker and keeps only the latest job waiting behind it, so pointer moves
// coalesce (the worker always computes the newest scene, never a backlog).

export class PlaygroundClient {
  constructor() {
    // `?simd=baseline` on the page forces the baseline core, as for the research app.
    const url = new URL('./worker.js', import.meta.url);
    const simd = new URLSearchParams(location.search).get('simd');
    if (simd) url.searchParams.set('simd', simd);
    this.worker = new Worker(url, { type: 'module' });
    this.nextId = 1;
    this.waiting = new Map(); // id -> {resolve, reject}
    this.channels = new Map(); // name -> {busy, pending: {msg, resolve, reject} | null}
    this.worker.onmessage = (e) => {
      const { id, result, error } = e.data;
      const job = this.waiting.get(id);
      if (!job) return;
      this.waiting.delete(id);
      if (error !== undefined) job.reject(new Error(error)); else job.resolve(result);
    };
  }

  /** Sends one job now and resolves with its answer. */
  request(msg, transfer = []) {
    const id = this.nextId++;
    return new Promise((resolve, reject) => {
      this.waiting.set(id, { resolve, reject });
      this.worker.postMessage({ ...msg, id }, transfer);
    });
  }

  /** Sends `msg` on `channel`, or, if that channel is busy, keeps it as the one job to send
   * next (a job waiting there before is dropped: it resolves with null). */
  latest(channel, msg) {
    let ch = this.channels.get(channel);
    if (!ch) { ch = { busy: false, pending: null }; this.channels.set(channel, ch); }
    return new Promise((resolve, reject) => {
      if (ch.busy) {
        ch.pending?.resolve(null);
        ch.pending = { msg, resolve, reject };
        return;
      }
      this.#run(ch, { msg, resolve, reject });
    });
  }

  #run(ch, job) {
    ch.busy = true;
    this.request(job.msg).then(job.resolve, job.reject).finally(() => {
      ch.busy = false;
      const next = ch.pending;
      ch.pending = null;
      if (next) this.#run(ch, next);
    });
  }
}

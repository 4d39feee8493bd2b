// The candidates of an "auto" regulariser strength, cross-validated in parallel: a pool of
// extra workers (each its own WebAssembly instance) opens the main session's project and takes
// the candidates one at a time; the rows come back in the candidates' order for the main
// worker's `runWithTrials`.

import { LensClient } from '../lens-client.js';

/** How many pool workers to start for `candidates` candidates: one per core
 * (`navigator.hardwareConcurrency`), at most 4 and at most one per candidate. `?workers=N` on
 * the page sets the number of cores (benches/app-auto.mjs compares 1 and 2). */
export function poolSize(candidates) {
  const forced = Number(new URLSearchParams(globalThis.location?.search ?? '').get('workers'));
  const cores = Number.isInteger(forced) && forced > 0 ? forced
    : Math.min(navigator.hardwareConcurrency || 1, 4);
  return Math.max(1, Math.min(cores, candidates));
}

/** A candidate of the plan in words: a strength (`0.1`), or a regulariser with its strength
 * and grid (`curvature 0.1 on 24×24`) when the plan pairs them. */
export function candidateLabel(c) {
  if (typeof c === 'number') return String(c);
  return `${c.regulariser} ${c.strength}${c.cells != null ? ` on ${c.cells}×${c.cells}` : ''}`;
}

/** The project text `project` (the main worker's project.json) without its result: a pool
 * worker needs only the data and settings, and would otherwise rebuild the last result's
 * maps first. */
export function projectForTrials(project) {
  const p = JSON.parse(project);
  p.result = null;
  return JSON.stringify(p);
}

export class StrengthPool {
  constructor(size) {
    this.workers = Array.from({ length: size }, (_, k) => new LensClient({ name: `pool-${k + 1}` }));
  }

  get size() { return this.workers.length; }

  /** Cross-validates every candidate of `plan` (`{candidates, folds}`, and `estimates` for a
   * second round: the redshifts each fold fits) on `project` (see
   * `projectForTrials`); resolves with the rows in the order of the candidates. `onProgress`
   * gets `{done, total, folds, running}` at every report and when a candidate is done:
   * `running` maps each candidate being tried (`candidateLabel`) to its worker's last progress
   * report, `folds` is
   * the number of folds finished of all the candidates (those of a running one counted from
   * the reports: a fold's first solve pass, `level` 0, follows the last pass of the fold
   * before; a fold shorter than the 100 ms between reports can be missed, which only makes
   * the count low), and `work` the same folds each weighted by `weight(candidate)` (its
   * relative cost; 1 each without). A worker that fails or dies fails the whole
   * run with a message naming the candidate; the caller closes the pool in any case. */
  async trials(project, plan, onProgress, weight = () => 1) {
    const { candidates, folds } = plan;
    const estimates = plan.estimates ?? null;
    const rows = new Array(candidates.length);
    const running = new Map();
    const foldsSeen = new Map(); // candidate -> folds of it seen to end
    const weights = new Map(candidates.map((c) => [candidateLabel(c), weight(c)]));
    let next = 0;
    let done = 0;
    let doneWork = 0;
    const report = () => {
      let partial = 0;
      let partialWork = 0;
      for (const [label, f] of foldsSeen) {
        partial += Math.min(f, folds - 1);
        partialWork += Math.min(f, folds - 1) * weights.get(label);
      }
      onProgress({ done, total: candidates.length, folds: done * folds + partial,
        work: doneWork + partialWork, running });
    };
    report();
    const work = async (worker, k) => {
      try {
        await worker.request('openProject', { text: project, name: 'project' });
      } catch (err) {
        throw failure(err, `Choosing the regulariser failed: pool worker ${k + 1} could not open the project`);
      }
      while (next < candidates.length) {
        const i = next++;
        const candidate = candidates[i];
        const label = candidateLabel(candidate);
        running.set(label, null);
        foldsSeen.set(label, 0);
        report();
        try {
          rows[i] = await worker.request('strengthTrial', { candidate, folds, estimates }, (p) => {
            const last = running.get(label);
            if (last && last.level > 0 && p.level === 0) foldsSeen.set(label, foldsSeen.get(label) + 1);
            running.set(label, p);
            report();
          });
        } catch (err) {
          throw failure(err, `Choosing the regulariser failed: the worker trying ${label} stopped`);
        }
        running.delete(label);
        foldsSeen.delete(label);
        done += 1;
        doneWork += folds * weights.get(label);
        report();
      }
    };
    await Promise.all(this.workers.map(work));
    return rows;
  }

  /** Terminates every worker at once; their jobs fail as cancelled. */
  close() {
    for (const w of this.workers) w.close();
  }
}

/** `err` with `what` in front, kept as a cancel when it is one. */
function failure(err, what) {
  if (err.cancelled) return err;
  return new Error(`${what}: ${err.message}`);
}

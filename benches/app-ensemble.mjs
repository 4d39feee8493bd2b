// The browser app's ensemble of the built-in example (the simulated A1689-like cluster, its
// own settings) with MEMBERS members (20 by default): the wall time of the ensemble (from the
// end of the main reconstruction to the combined result, as the status line says it), with 1
// and with 2 pool workers (`?workers=N`, www/js/pool.js's `poolSize`), alternating, RUNS times
// each, a fresh browser per run. Prints every run (with the machine's 1-minute load average
// before and after it), the median per pool size and their ratio. BENCHMARKS.md records the
// figures.
//
//   npm run build && node benches/app-ensemble.mjs        (RUNS=3, MEMBERS=20 by default)
//
// Needs www/pkg (npm run build) and /usr/bin/chromium (or CHROMIUM).
import { cpus, loadavg } from 'node:os';
import { openApp, setField, waitStatus } from '../tests/e2e/browser.mjs';

const RUNS = Number(process.env.RUNS ?? 3);
const MEMBERS = Number(process.env.MEMBERS ?? 20);
const SIZES = [1, 2];
const DONE = /^Done in (\d+\.\d+) s; ensemble of (\d+) members in (\d+\.\d+) s\./;

/** One reconstruction with its ensemble in a fresh browser with `workers` pool workers:
 * the ensemble's time and the main run's (s, from the status line) and the wall time from
 * the click (measured here). */
async function run(workers) {
  const app = await openApp({ query: `?app&workers=${workers}` });
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    await setField(page, '#set-ensemble-members', MEMBERS);
    const t0 = Date.now();
    await page.click('#reconstruct');
    await waitStatus(page, DONE, 3_600_000);
    const wall = (Date.now() - t0) / 1000;
    const [, main, members, ensemble] = (await page.textContent('#status')).match(DONE);
    if (Number(members) !== MEMBERS) throw new Error(`${members} members, not ${MEMBERS}`);
    return { wall, main: Number(main), ensemble: Number(ensemble) };
  } finally {
    await app.close();
  }
}

const median = (xs) => {
  const s = [...xs].sort((a, b) => a - b);
  return s.length % 2 ? s[(s.length - 1) / 2] : (s[s.length / 2 - 1] + s[s.length / 2]) / 2;
};

console.log(`machine: ${cpus().length} cores (${cpus()[0]?.model ?? '?'}), ${MEMBERS} members, ${RUNS} runs per pool size, alternating`);
const times = Object.fromEntries(SIZES.map((n) => [n, []]));
for (let k = 0; k < RUNS; k++) {
  for (const n of SIZES) {
    const before = loadavg()[0];
    const r = await run(n);
    times[n].push(r.ensemble);
    console.log(`run ${k + 1}, ${n} pool worker${n === 1 ? '' : 's'}: ensemble ${r.ensemble.toFixed(1)} s (main run ${
      r.main.toFixed(1)} s, click to result ${r.wall.toFixed(1)} s), load average ${before.toFixed(2)} before, ${loadavg()[0].toFixed(2)} after`);
  }
}
for (const n of SIZES) {
  console.log(`${n} pool worker${n === 1 ? '' : 's'}: median ${median(times[n]).toFixed(1)} s (${times[n].map((t) => t.toFixed(1)).join(', ')})`);
}
console.log(`2 workers / 1 worker: ${(median(times[2]) / median(times[1])).toFixed(2)}x the time (target at most 0.6x)`);

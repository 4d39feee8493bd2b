// The browser app's "auto" regulariser strength on the AS1063 gold catalogues (images and
// members, z_lens 0.348, the app's defaults otherwise): the wall time from Reconstruct to the
// result, with 1 and with 2 pool workers for the candidates (`?workers=N`, www/js/pool.js),
// alternating, RUNS times each. Prints every run (with the chosen candidate and the machine's
// 1-minute load average after it), the median per pool size. BENCHMARKS.md records the figures.
//
//   npm run build && node benches/app-auto.mjs        (RUNS=5 by default)
//
// Needs www/pkg (npm run build), ../shared/data/AS1063 and /usr/bin/chromium (or CHROMIUM).
import { cpus, loadavg } from 'node:os';
import { join } from 'node:path';
import { openApp, ROOT, setField, waitStatus } from '../tests/e2e/browser.mjs';

const AS1063 = join(ROOT, '..', 'shared', 'data', 'AS1063', 'lenstool_cats');
const RUNS = Number(process.env.RUNS ?? 5);
const SIZES = [1, 2];

/** One auto reconstruction in a fresh browser with `workers` pool workers: the wall time in s
 * (the click to "Done in", measured here), the app's own figure and the chosen candidate. */
async function run(workers) {
  const app = await openApp({ query: `?workers=${workers}` });
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    await page.setInputFiles('#file-images', join(AS1063, 'cats_gold_mul_gold.cat'));
    await page.waitForFunction(() => document.getElementById('project-name').textContent === 'Your data'
      && /19 systems/.test(document.getElementById('status-images').textContent));
    await page.setInputFiles('#file-members', join(AS1063, 'cats_gold_ref_potential_w_clumpNE.cat'));
    await page.waitForFunction(() => /members/.test(document.getElementById('status-members').textContent));
    await setField(page, '#set-z_lens', 0.348);
    if (await page.inputValue('#set-reconstruct-objective-strength') !== 'auto') throw new Error('strength is not auto');
    const t0 = Date.now();
    await page.click('#reconstruct');
    await waitStatus(page, /^Done in/, 1_200_000);
    const wall = (Date.now() - t0) / 1000;
    const status = await page.textContent('#status');
    const row = await page.$eval('#strength-table tr.chosen', (tr) => ({ ...tr.dataset }));
    const chosen = `${row.regulariser} ${row.strength}`.trim();
    return { wall, app: Number(status.match(/Done in (\d+(?:\.\d+)?) s/)[1]), chosen };
  } finally {
    await app.close();
  }
}

const median = (xs) => {
  const s = [...xs].sort((a, b) => a - b);
  return s.length % 2 ? s[(s.length - 1) / 2] : (s[s.length / 2 - 1] + s[s.length / 2]) / 2;
};

console.log(`machine: ${cpus().length} cores (${cpus()[0]?.model ?? '?'}), ${RUNS} runs per pool size, alternating`);
const times = Object.fromEntries(SIZES.map((n) => [n, []]));
for (let k = 0; k < RUNS; k++) {
  for (const n of SIZES) {
    const r = await run(n);
    times[n].push(r.wall);
    console.log(`run ${k + 1}, ${n} pool worker${n === 1 ? '' : 's'}: ${r.wall.toFixed(1)} s (status line ${
      r.app.toFixed(1)} s), chosen ${r.chosen}, load average ${loadavg()[0].toFixed(2)}`);
  }
}
for (const n of SIZES) {
  console.log(`${n} pool worker${n === 1 ? '' : 's'}: median ${median(times[n]).toFixed(1)} s (${times[n].map((t) => t.toFixed(1)).join(', ')})`);
}
console.log(`speed-up of 2 workers over 1: ${(median(times[1]) / median(times[2])).toFixed(2)}x`);

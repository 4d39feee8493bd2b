// The browser app's built-in example (the simulated A1689-like cluster) reconstructed in the
// web worker with the example's own settings, against the same run natively on one thread.
// Prints the worker time ("Done in" of the status line), first contentful paint, the native
// wall time and their ratio, and the wasm bundle size. BENCHMARKS.md records the figures.
//
//   npm run build && cargo build --release && node benches/app-example.mjs
//
// Needs www/pkg (npm run build), target/release/wslap (under CARGO_TARGET_DIR if set) and
// /usr/bin/chromium (or CHROMIUM). `SIMD=baseline` measures the baseline-SIMD core.
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readFileSync, statSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { openApp, ROOT, waitStatus } from '../tests/e2e/browser.mjs';

const index = JSON.parse(readFileSync(join(ROOT, 'www/examples/index.json'), 'utf8'));
const example = index.examples[0];

// The example's settings as the CONFIG.json of `wslap reconstruct` (dot paths under
// "reconstruct."), over the app's defaults that differ from the CLI's (256-pixel maps:
// APP_MAP_PIXELS in src/app/settings.rs); `nativeRun` adds the thread count.
const config = { products: { pixels: 256 } };
for (const [path, value] of Object.entries(example.settings)) {
  const keys = path.split('.');
  if (keys[0] !== 'reconstruct') continue;
  let node = config;
  for (const k of keys.slice(1, -1)) node = node[k] ??= {};
  node[keys.at(-1)] = value;
}
const file = (role) => join(ROOT, 'www/examples', example.files.find((f) => f.role === role).path);

const app = await openApp({ query: process.env.SIMD ? `?simd=${process.env.SIMD}` : '' });
let worker;
let paint;
let workerStages;
let core;
try {
  const { page } = app;
  await waitStatus(page, /^Ready/);
  paint = await page.evaluate(() =>
    performance.getEntriesByName('first-contentful-paint')[0]?.startTime);
  core = await page.textContent('#core-info');
  await page.click('#reconstruct');
  await waitStatus(page, /^Done in/, 600_000);
  const status = await page.textContent('#status');
  worker = Number(status.match(/Done in (\d+(?:\.\d+)?) s/)[1]);
  // The worker's own stage timings, from its summary.json.
  await page.$eval('details:has(#downloads)', (d) => { d.open = true; });
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('#dl-summary-json')]);
  workerStages = JSON.parse(readFileSync(await download.path(), 'utf8')).timings_ms;
} finally {
  await app.close();
}

const dir = mkdtempSync(join(tmpdir(), 'wslap-bench-'));
// `wslap reconstruct` with the example's settings on `threads` threads (0: all cores); returns
// the wall time in s and the stage timings of its summary.json.
function nativeRun(threads) {
  const cfg = join(dir, `config-${threads}.json`);
  writeFileSync(cfg, JSON.stringify({ ...config, system: { threads } }));
  const out = join(dir, `out-${threads}`);
  const t0 = process.hrtime.bigint();
  execFileSync(join(process.env.CARGO_TARGET_DIR ?? join(ROOT, 'target'), 'release/wslap'), [
    'reconstruct', '--arcs', file('arcs'), '--members', file('members'),
    '--z-lens', String(example.z_lens), '--config', cfg, '--out', out,
  ], { stdio: 'ignore' });
  const wall = Number(process.hrtime.bigint() - t0) / 1e9;
  return [wall, JSON.parse(readFileSync(join(out, 'summary.json'), 'utf8')).timings_ms];
}
const [native, nativeStages] = nativeRun(1);
const [nativeAll, nativeAllStages] = nativeRun(0);
const stages = (t) => Object.entries(t).map(([k, v]) => `${k} ${(v / 1e3).toFixed(2)}`).join(', ');
const wasm = statSync(join(ROOT, 'www/pkg/wslap_bg.wasm')).size;
const wasmRelaxed = statSync(join(ROOT, 'www/pkg/wslap_relaxed_bg.wasm')).size;

console.log(`example: ${example.id}, settings ${JSON.stringify(config)}`);
console.log(core);
console.log(`browser worker: ${worker.toFixed(1)} s (stages in s: ${stages(workerStages)})`);
console.log(`native, one thread: ${native.toFixed(1)} s wall (stages in s: ${stages(nativeStages)})`);
console.log(`native, all cores: ${nativeAll.toFixed(1)} s wall (stages in s: ${stages(nativeAllStages)})`);
console.log(`ratio: ${(worker / native).toFixed(2)}x (against all cores: ${(worker / nativeAll).toFixed(2)}x)`);
console.log(`first contentful paint: ${paint?.toFixed(0)} ms`);
console.log(`wasm bundle: ${(wasm / 1e6).toFixed(2)} MB (baseline SIMD), ${(wasmRelaxed / 1e6).toFixed(2)} MB (relaxed SIMD); a browser loads one`);

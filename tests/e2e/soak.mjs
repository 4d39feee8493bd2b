// Soak test (issue #25), `npm run soak`; not part of `npm test` (a few minutes). In one page
// session: 10 cycles, each switching examples (the simulated A1689 example, then the teaching
// example), loading a file, cross-validating and running 5 quick reconstructions (50 in all).
// It reports the worker's WebAssembly memory (and `performance.measureUserAgentSpecificMemory`
// where the page is cross-origin isolated, which this test arranges) before and after, and
// per cycle, and asserts that memory does not grow without bound:
//
//   RULE: from the end of the first cycle (every kind of job has run once) to the end, the
//   worker's WebAssembly memory grows by at most GROWTH_LIMIT_MIB = 24 MiB. A WebAssembly memory
//   never shrinks, and its allocator grows it in steps of 3.6 MiB while it settles: measured,
//   33.2 MiB after cycle 1, then 47.4 MiB from cycle 5 or 8 on in three runs, still 47.4 MiB at
//   cycle 24 of a run of 120 reconstructions. A leak of half a MiB per reconstruction (one teaching
//   result, its 256 x 256 maps, is several MiB) would add more than 22 MiB over the 45 runs
//   after cycle 1.
//
// Figures are printed as one JSON line (`soak: {...}`) for BENCHMARKS.md.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { openApp, runToMap, setField, waitStatus, ROOT } from './browser.mjs';

// `SOAK_CYCLES=N npm run soak` runs longer (the same rule applies).
const CYCLES = Number(process.env.SOAK_CYCLES ?? 10);
const RUNS_PER_CYCLE = 5;
const GROWTH_LIMIT_MIB = 24;
const TEACHING = 'Teaching example: one halo, four sources';
const A1689 = 'Simulated A1689-like cluster (the WSLAP+ paper\'s test)';
const MEMBERS = join(ROOT, 'www', 'examples', 'a1689-sim', 'members.cat');
const MIB = 1024 * 1024;

/** The app's main worker (not a pool worker, whose URL says `worker=`). */
function mainWorker(page) {
  const workers = page.workers().filter((w) => /worker\.js/.test(w.url()) && !/[?&]worker=/.test(w.url()));
  assert.equal(workers.length, 1, workers.map((w) => w.url()).join(', '));
  return workers[0];
}

/** The main worker's WebAssembly memory (bytes). */
async function wasmBytes(page) {
  return (await mainWorker(page).evaluate(() => self.wslapMemory())).wasm_bytes;
}

/** `performance.measureUserAgentSpecificMemory()` of the page: `{bytes, workers}` (all, and the
 * part attributed to workers), or null where the browser does not offer it. */
async function uaMemory(page) {
  return page.evaluate(async () => {
    if (!self.crossOriginIsolated || !performance.measureUserAgentSpecificMemory) return null;
    const m = await performance.measureUserAgentSpecificMemory();
    // The part attributed to workers, where the browser says so.
    const workers = m.breakdown.filter((b) => b.attribution.some((a) => /Worker/.test(a.scope)))
      .reduce((t, b) => t + b.bytes, 0);
    return { bytes: m.bytes, workers };
  });
}

async function openExample(page, label) {
  await page.selectOption('#example-select', { label });
  await page.waitForFunction((l) => document.getElementById('project-name').textContent === l, label);
  await waitStatus(page, /^Ready/);
}

test('50 reconstructions, file loads and example switches in one page: memory stays bounded', { timeout: 30 * 60_000 }, async () => {
  const t0 = Date.now();
  // Without the service worker, so that the headers below reach every response (the workers'
  // scripts too): cross-origin isolation turns on measureUserAgentSpecificMemory.
  const app = await openApp({ serviceWorkers: 'block' });
  const { page } = app;
  try {
    await page.route('**/*', async (route) => {
      const response = await route.fetch();
      await route.fulfill({
        response,
        headers: {
          ...response.headers(),
          'cross-origin-opener-policy': 'same-origin',
          'cross-origin-embedder-policy': 'require-corp',
        },
      });
    });
    await page.goto(`${app.url}?app`);
    await waitStatus(page, /^Ready/);
    const start = { wasm: await wasmBytes(page), ua: await uaMemory(page) };
    const perCycle = [];
    let runs = 0;
    let fileLoads = 0;
    let switches = 0;
    for (let cycle = 1; cycle <= CYCLES; cycle++) {
      await openExample(page, A1689);
      await openExample(page, TEACHING);
      switches += 2;
      // A file: the teaching example leaves for "Your data" with it; the teaching example
      // is opened again for the runs.
      await page.setInputFiles('#file-members', MEMBERS);
      await page.waitForFunction(() => document.getElementById('project-name').textContent === 'Your data'
        && /members/.test(document.getElementById('status-members').textContent));
      await waitStatus(page, /^Load an image catalogue or arcs to reconstruct/);
      fileLoads += 1;
      await openExample(page, TEACHING);
      switches += 1;
      await setField(page, '#set-reconstruct-solver-iterations', 200);
      await page.click('#crossval');
      await waitStatus(page, /^Cross-validated in/, 120_000);
      for (let k = 0; k < RUNS_PER_CYCLE; k++) {
        // A different iteration count each time: every run is a new solve.
        await setField(page, '#set-reconstruct-solver-iterations', 200 + 10 * k);
        await runToMap(page, '#reconstruct', 120_000);
        runs += 1;
      }
      perCycle.push(await wasmBytes(page));
      console.log(`cycle ${cycle}: ${runs} reconstructions, wasm memory ${(perCycle.at(-1) / MIB).toFixed(1)} MiB, ${((Date.now() - t0) / 1000).toFixed(0)} s`);
    }
    const end = { wasm: await wasmBytes(page), ua: await uaMemory(page) };
    const figures = {
      runs, fileLoads, exampleSwitches: switches, crossValidations: CYCLES,
      seconds: Math.round((Date.now() - t0) / 1000),
      wasmMiB: { start: start.wasm / MIB, perCycle: perCycle.map((b) => b / MIB), end: end.wasm / MIB },
      uaMemoryMiB: start.ua == null ? null : {
        start: start.ua.bytes / MIB, end: end.ua.bytes / MIB,
        workersStart: start.ua.workers / MIB, workersEnd: end.ua.workers / MIB,
      },
    };
    console.log(`soak: ${JSON.stringify(figures)}`);
    assert.equal(runs, CYCLES * RUNS_PER_CYCLE);
    const [first, last] = [perCycle[0], perCycle.at(-1)];
    assert.ok(last - first <= GROWTH_LIMIT_MIB * MIB,
      `wasm memory grew by more than ${GROWTH_LIMIT_MIB} MiB after cycle 1: ${first / MIB} -> ${last / MIB} MiB`);
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

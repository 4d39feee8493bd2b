// End-to-end: the worker loads the relaxed-SIMD build of the core where the browser has relaxed
// SIMD (Chromium does), the baseline-SIMD build when the page asks for it (`?simd=baseline`),
// and both builds give the same reconstruction to rounding.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFile } from 'node:fs/promises';
import { openApp, setField, waitStatus } from './browser.mjs';

/** The teaching example reconstructed with `query` on the page: the footer's core line and
 * the run's summary.json. */
async function teachingRun(query) {
  const app = await openApp({ query });
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    const core = await page.textContent('#core-info');
    await page.selectOption('#example-select', { label: 'Teaching example: one halo, four sources' });
    await page.waitForFunction(() => /Teaching/.test(document.getElementById('project-name').textContent));
    await setField(page, '#set-reconstruct-solver-iterations', 600);
    await page.click('#reconstruct');
    await waitStatus(page, /^Done in/);
    await page.$eval('details:has(#downloads)', (d) => { d.open = true; });
    const [download] = await Promise.all([page.waitForEvent('download'), page.click('#dl-summary-json')]);
    const summary = JSON.parse(await readFile(await download.path(), 'utf8'));
    assert.deepEqual(app.consoleErrors, []);
    return { core, summary };
  } finally {
    await app.close();
  }
}

test('relaxed-SIMD and baseline-SIMD cores load as asked and agree', async () => {
  const relaxed = await teachingRun('?app');
  const baseline = await teachingRun('?simd=baseline');
  assert.match(relaxed.core, /relaxed SIMD/);
  assert.match(baseline.core, /WebAssembly with SIMD\./);
  for (const key of ['grid_mass_msun', 'image_plane_rms_arcsec', 'einstein_radius_arcsec']) {
    const [r, b] = [relaxed.summary[key], baseline.summary[key]];
    assert.ok(Number.isFinite(r) && r > 0, `${key} = ${r}`);
    assert.ok(Math.abs(r - b) <= 1e-4 * Math.abs(b), `${key}: relaxed ${r}, baseline ${b}`);
  }
  assert.equal(relaxed.summary.iterations, 600);
  assert.equal(baseline.summary.iterations, 600);
});

// End-to-end: the page survives failures of its core. A panic inside the WebAssembly core
// (here one a test asks for with `?test-panic=run`: the first Reconstruct panics, as a bug
// would) is reported plainly, the worker is replaced and the session put back with its data,
// settings and result, and everything works afterwards; so when the worker dies outright. A
// grid the browser cannot hold (128 x 128 cells, which used to end the run with a bare
// "unreachable" and leave every control dead) is refused when it is set, with the memory it
// would need.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { openApp, runToMap, setField, waitStatus, ARTIFACTS, SETTLE_TIMEOUT_MS } from './browser.mjs';

const QUICK_ITERATIONS = 600;
const CRASH_MESSAGE = 'The computation failed inside the core: the failure a test asked for; '
  + 'the session was restarted with your data.';

/** Waits until `#error` shows `pattern`. */
async function waitError(page, pattern, timeout = 60_000) {
  await page.waitForFunction((src) => {
    const el = document.getElementById('error');
    return !el.hidden && new RegExp(src).test(el.textContent);
  }, pattern.source, { timeout });
}

test('a panic in the core is reported and the session comes back with its data', async () => {
  const app = await openApp({ height: 720, query: '?test-panic=run' });
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    // Settings of one's own, which the restored session must keep.
    await setField(page, '#set-reconstruct-solver-iterations', QUICK_ITERATIONS);
    await setField(page, '#set-reconstruct-grid-cells', 28);
    await page.click('#reconstruct');
    await waitError(page, /^The computation failed inside the core/);
    assert.equal(await page.textContent('#error'), CRASH_MESSAGE);
    await waitStatus(page, /^Restarted after the failure: your files and settings are back\.$/);
    await page.screenshot({ path: join(ARTIFACTS, 'recovery-1280.png') });
    await page.setViewportSize({ width: 390, height: 844 });
    await page.locator('#status').scrollIntoViewIfNeeded();
    await page.screenshot({ path: join(ARTIFACTS, 'recovery-390.png') });
    await page.setViewportSize({ width: 1280, height: 720 });
    // The data and the settings are back, and every control works (before, each change
    // failed with "recursive use of an object detected" and the buttons stayed disabled).
    assert.equal(await page.inputValue('#set-reconstruct-solver-iterations'), String(QUICK_ITERATIONS));
    assert.equal(await page.inputValue('#set-reconstruct-grid-cells'), '28');
    assert.match(await page.textContent('#status-arcs'), /^arcs\.json: \d+ systems, \d+ arc pixels/);
    assert.equal(await page.isDisabled('#reconstruct'), false);
    await setField(page, '#set-reconstruct-solver-iterations', QUICK_ITERATIONS - 100);
    await runToMap(page, '#reconstruct');
    const caption = await page.textContent('#summary');
    assert.match(caption, new RegExp(`^Completed, ${QUICK_ITERATIONS - 100} iterations; Einstein radius`));
    assert.equal(await page.isHidden('#error'), true, 'a new run clears the failure');

    // The worker dies outright (an error nothing in it catches): the page starts another one
    // with the session, the result just computed included.
    const worker = page.workers().filter((w) => !w.url().includes('worker=pool')).at(-1);
    await worker.evaluate(() => { setTimeout(() => { throw new Error('the worker broke'); }); });
    await waitError(page, /^The worker failed \(.*the worker broke\); it was restarted with your data\.$/);
    await waitStatus(page, /^Restarted after the failure: your files, settings and last result are back\.$/);
    // The result comes back from the saved project ("Restored"), the same map.
    const result = caption.slice(caption.indexOf('Einstein radius'));
    await page.waitForFunction((r) => document.getElementById('summary').textContent.endsWith(r), result,
      { timeout: SETTLE_TIMEOUT_MS });
    assert.equal(await page.isDisabled('#reconstruct'), false);
    await setField(page, '#set-reconstruct-grid-cells', 30);
    assert.deepEqual(app.consoleErrors.filter((e) => !/the worker broke/.test(e)), []);
  } finally {
    await app.close();
  }
});

test('settings a run cannot use are refused when set: a grid the browser cannot hold with the memory it needs, a value with its range', async () => {
  const app = await openApp({ height: 720 });
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    const cells = '#set-reconstruct-grid-cells';
    await page.$eval(cells, (el) => { el.closest('details').open = true; });
    await page.locator(cells).fill('128');
    await page.locator(cells).dispatchEvent('change');
    await page.waitForFunction((sel) => document.getElementById(`${document.querySelector(sel).id}-error`).textContent,
      cells, { timeout: SETTLE_TIMEOUT_MS });
    const refusal = await page.textContent(`${cells}-error`);
    // Next to the labelled field, without the setting's path.
    assert.match(refusal, /^a run with these settings would need at least \d+\.\d GiB of memory, more than the 2\.5 GiB a browser tab can give a run: its linear system has 16384 unknowns \(16384 cells\), so a 16384 x 16384 matrix of 2\.0 GiB, .*; lower grid\.cells \(or grid\.refinements\)$/);
    assert.equal(await page.inputValue(cells), '32', 'the accepted value comes back');
    await page.locator(`${cells}-error`).scrollIntoViewIfNeeded();
    await page.screenshot({ path: join(ARTIFACTS, 'cells-128-refused.png') });
    // A value out of its range is refused with the range, not the setting's path.
    const scatter = '#set-reconstruct-members-mass_to_light_scatter_dex';
    await page.locator(scatter).fill('5');
    await page.locator(scatter).dispatchEvent('change');
    await page.waitForFunction((sel) => document.getElementById(`${document.querySelector(sel).id}-error`).textContent,
      scatter, { timeout: SETTLE_TIMEOUT_MS });
    assert.equal(await page.textContent(`${scatter}-error`), '5 is not allowed (must be between 0 and 2)');
    assert.equal(await page.inputValue(scatter), '0.3', 'the accepted value comes back');
    // Nothing else is touched: the example still reconstructs.
    await setField(page, '#set-reconstruct-solver-iterations', QUICK_ITERATIONS);
    await runToMap(page, '#reconstruct');
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

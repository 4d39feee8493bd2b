// End-to-end: after Reconstruct on the teaching example, the slider under the mass map steps
// through the iterates the run kept: each shows another map (pixels differ), the keyboard moves
// it, Play advances it up to the result, and other views hide it.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { openApp, imageStats, renderCount, runToMap, waitView, waitStatus, watchLongTasks, ARTIFACTS } from './browser.mjs';

/** A digest of the pixels of `#view-image` once loaded: the sum of every channel and the
 * number of pixels of the tangential curves' red. */
async function pixels(page) {
  const { sum, reddish } = await imageStats(page, '#view-image');
  return { sum, red: reddish };
}

const label = (page) => page.textContent('#iterate-label');

/** Does `action` and waits for the mass map it draws. */
async function redrawn(page, action) {
  const before = await renderCount(page);
  await action();
  await waitView(page, 'kappa', before);
}

test('the iteration slider shows the maps of the kept iterates and Play steps through them', async () => {
  const app = await openApp({ width: 1280, height: 720, query: '?example=teaching' });
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    assert.equal(await page.isVisible('#iterates'), false, 'no slider before a run');
    await runToMap(page, '#reconstruct');
    await page.waitForSelector('#iterates:not([hidden])');
    assert.match(await label(page), /^iteration 3000 of 3000 \(the result\)$/);
    const final = await pixels(page);
    await page.screenshot({ path: join(ARTIFACTS, 'iterates-result.png') });

    // The keyboard: Home goes to the start, then each arrow one kept iterate further.
    await page.focus('#iterate-slider');
    await redrawn(page, () => page.keyboard.press('Home'));
    assert.match(await label(page), /^iteration 0 of 3000$/);
    const start = await pixels(page);
    const times = [];
    for (let k = 0; k < 10; k++) {
      const t0 = Date.now();
      await redrawn(page, () => page.keyboard.press('ArrowRight'));
      times.push(Date.now() - t0);
    }
    console.log(`one iterate's map drawn in ${times.sort((a, b) => a - b)[5]} ms (median of 10)`);
    const early = await page.$eval('#iterate-slider', (el) => Number(el.value));
    assert.equal(early, 10);
    const earlyText = await label(page);
    const earlyPixels = await pixels(page);
    assert.match(earlyText, /^iteration \d+ of 3000$/);
    assert.match(await page.$eval('#view-image', (img) => img.alt), /Convergence map/);
    // Different iterations, different maps.
    assert.notEqual(start.sum, final.sum, 'the start looks like the result');
    assert.notEqual(earlyPixels.sum, final.sum, `${earlyText} looks like the result`);
    assert.notEqual(earlyPixels.sum, start.sum, `${earlyText} looks like the start`);
    await page.screenshot({ path: join(ARTIFACTS, 'iterates-early.png') });

    // Play steps towards the result a few iterates a second, drawn in the worker: the main
    // thread stays free.
    const longTasks = await watchLongTasks(page);
    await page.click('#iterate-play');
    assert.equal(await page.textContent('#iterate-play'), 'Pause');
    await page.waitForFunction((k) => Number(document.getElementById('iterate-slider').value) >= k + 3, early,
      { timeout: 30_000 });
    await page.waitForFunction(() => document.getElementById('iterate-play').textContent === 'Play',
      null, { timeout: 60_000 });
    assert.match(await label(page), /\(the result\)$/);
    await page.waitForFunction(() => document.getElementById('view-image').complete);
    assert.equal((await pixels(page)).sum, final.sum, 'Play ends on the result');
    assert.deepEqual((await longTasks()).filter(([, d]) => d > 100), [], 'main-thread tasks over 100 ms');

    // "Result" comes back from an earlier iterate; another view hides the slider.
    await page.focus('#iterate-slider');
    await redrawn(page, () => page.keyboard.press('Home'));
    await redrawn(page, () => page.click('#iterate-final'));
    assert.equal((await pixels(page)).sum, final.sum);
    await page.click('#tab-radial');
    await page.waitForFunction(() => document.getElementById('iterates').hidden);
    await redrawn(page, () => page.click('#tab-kappa'));
    assert.equal(await page.isVisible('#iterates'), true);

    // At phone width the slider fits the page.
    await page.setViewportSize({ width: 390, height: 844 });
    await redrawn(page, () => page.$eval('#iterate-slider', (el) => {
      el.value = '12';
      el.dispatchEvent(new Event('input', { bubbles: true }));
    }));
    const overflow = await page.evaluate(() => document.documentElement.scrollWidth - window.innerWidth);
    assert.ok(overflow <= 0, `the page is ${overflow} px wider than the phone`);
    await page.$eval('#iterates', (el) => el.scrollIntoView({ block: 'center' }));
    await page.screenshot({ path: join(ARTIFACTS, 'iterates-phone.png') });
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

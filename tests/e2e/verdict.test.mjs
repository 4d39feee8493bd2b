// End-to-end: after a reconstruction of the built-in example the verdict sits beside the map
// (one of three words, its reasons and numbers), the worst systems are ringed on the map, and
// the systems table sorts by its columns with the mouse and the keyboard.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { openApp, imageStats, runToMap, ARTIFACTS, setField, waitStatus } from './browser.mjs';

/** Iterations of the quick runs (the example's own setting is 8000). */
const QUICK_ITERATIONS = 600;
/** The worst systems' rings (WORST_RGB of src/app/views.rs). */
const WORST = { rgb: [255, 90, 0], tol: 10 };
const WORDS = ['good', 'usable with care', 'do not trust the small scales'];

/** Opens the app on the example and reconstructs it quickly; returns the app. */
async function reconstructed(viewport = {}) {
  const app = await openApp(viewport);
  await waitStatus(app.page, /^Ready/);
  await setField(app.page, '#set-reconstruct-solver-iterations', QUICK_ITERATIONS);
  await runToMap(app.page, '#reconstruct', 120_000);
  await app.page.waitForSelector('#verdict:not([hidden])');
  return app;
}

test('the verdict beside the map says how far to trust it, and rings the worst systems', async () => {
  const app = await reconstructed({ width: 1280, height: 720 });
  try {
    const { page } = app;
    await page.evaluate(() => window.scrollTo(0, 0));
    await page.screenshot({ path: join(ARTIFACTS, 'verdict-1280x720.png') });
    const words = await page.textContent('#verdict-words');
    assert.ok(WORDS.includes(words), words);
    assert.equal(await page.getAttribute('#verdict', 'data-trust'), { good: 'good', 'usable with care': 'usable_with_care',
      'do not trust the small scales': 'do_not_trust_small_scales' }[words]);
    const reasons = await page.textContent('#verdict-reasons');
    const sentences = reasons.split(/(?<=\.) (?=[A-Z0-9])/);
    assert.ok(sentences.length >= 1 && sentences.length <= 2, reasons);
    const facts = await page.locator('#verdict-facts li').allTextContents();
    assert.match(facts[0], /^Image offsets \(median\): fitted \d+\.\d\d″$/);
    assert.match(facts[1], /^Predicted images \(\|μ\| ≥ 0\.1\) of 30 systems: \d+ as many as observed/);
    assert.match(facts[2], /^Members with critical curves of their own at z_s = 3: \d+/);
    // The same verdict is in summary.json.
    await page.click('#downloads-panel summary');
    const [dl] = await Promise.all([page.waitForEvent('download'), page.click('#dl-summary-json')]);
    const chunks = [];
    for await (const c of await dl.createReadStream()) chunks.push(c);
    const summary = JSON.parse(Buffer.concat(chunks).toString());
    assert.equal(summary.verdict.words, words);
    assert.equal(summary.verdict.reasons, reasons);
    // Its worst systems are ringed on the map, in the warning colour, and listed.
    const worst = summary.verdict.worst;
    if (worst.length) {
      const ring = (await imageStats(page, '#view-image', WORST)).near;
      assert.ok(ring > 100 * worst.length, `${ring} pixels of the rings of ${worst.length} systems`);
      assert.equal(facts.at(-1), `Worst systems (ringed on the map; why: Image systems): ${worst.map((w) => w.id).join(', ')}`);
    }
    // On a phone the verdict comes with the map.
    await page.setViewportSize({ width: 390, height: 844 });
    await page.locator('#verdict').scrollIntoViewIfNeeded();
    const box = await page.locator('#verdict').boundingBox();
    assert.ok(box.width <= 390 && box.x >= 0, JSON.stringify(box));
    assert.equal(await page.evaluate(() => document.documentElement.scrollWidth), 390);
    await page.locator('#figure').screenshot({ path: join(ARTIFACTS, 'verdict-390.png') });
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

/** The table's rows as `[id, value of column k]`. */
async function column(page, k) {
  return page.$$eval('#systems tbody tr', (trs, n) => trs.map((tr) => [tr.dataset.id, tr.children[n].textContent]), k);
}

test('the systems table sorts by a column header, by mouse and keyboard, with aria-sort', async () => {
  const app = await reconstructed();
  try {
    const { page } = app;
    await page.click('#tab-systems');
    await page.waitForSelector('#systems table');
    const fileOrder = (await column(page, 0)).map(([id]) => id);
    assert.equal(fileOrder.length, 30);
    assert.equal(await page.locator('#systems th[aria-sort]').count(), 0);
    // z: ascending on the first click, descending on the second.
    await page.click('#systems button.sort[data-sort="z"]');
    assert.equal(await page.getAttribute('#systems th:has(button[data-sort="z"])', 'aria-sort'), 'ascending');
    const z = (await column(page, 1)).map(([, t]) => parseFloat(t));
    assert.deepEqual(z, [...z].sort((a, b) => a - b));
    await page.click('#systems button.sort[data-sort="z"]');
    assert.equal(await page.getAttribute('#systems th:has(button[data-sort="z"])', 'aria-sort'), 'descending');
    const zDown = (await column(page, 1)).map(([, t]) => parseFloat(t));
    assert.deepEqual(zDown, [...zDown].sort((a, b) => b - a));
    assert.equal(await page.locator('#systems th[aria-sort]').count(), 1);
    // The keyboard: Tab to the rms header and Enter sorts the largest first; focus stays.
    await page.focus('#systems button.sort[data-sort="scatter"]');
    await page.keyboard.press('Tab');
    await page.keyboard.press('Tab');
    await page.keyboard.press('Tab');
    assert.equal(await page.evaluate(() => document.activeElement.dataset.sort), 'rms');
    await page.keyboard.press('Enter');
    assert.equal(await page.getAttribute('#systems th:has(button[data-sort="rms"])', 'aria-sort'), 'descending');
    assert.equal(await page.evaluate(() => document.activeElement.dataset.sort), 'rms');
    const rms = (await column(page, 6)).map(([, t]) => (t === '–' ? Infinity : parseFloat(t)));
    assert.deepEqual(rms, [...rms].sort((a, b) => b - a));
    await page.keyboard.press(' ');
    assert.equal(await page.getAttribute('#systems th:has(button[data-sort="rms"])', 'aria-sort'), 'ascending');
    // The system ids sort naturally (2 before 10).
    await page.click('#systems button.sort[data-sort="system"]');
    assert.deepEqual((await column(page, 0)).map(([id]) => id), [...fileOrder].sort((a, b) => Number(a) - Number(b)));
    // "check": the verdict's worst systems first, in its order, each with its problem.
    const worst = await page.$$eval('#verdict-facts li', (lis) => lis.at(-1).textContent);
    await page.click('#systems button.sort[data-sort="check"]');
    const checks = await column(page, 7);
    const flagged = checks.filter(([, t]) => t.startsWith('⚠'));
    if (/^Worst/.test(worst)) {
      assert.ok(flagged.length >= 1 && flagged.length <= 5, JSON.stringify(checks));
      assert.deepEqual(checks.slice(0, flagged.length), flagged);
      assert.ok(worst.endsWith(`: ${flagged.map(([id]) => id).join(', ')}`), worst);
    }
    // The sort stays when the table is drawn again.
    await page.click('#tab-kappa');
    await page.click('#tab-systems');
    await page.waitForSelector('#systems table');
    assert.equal(await page.getAttribute('#systems th:has(button[data-sort="check"])', 'aria-sort'), 'ascending');
    await page.screenshot({ path: join(ARTIFACTS, 'verdict-systems-sorted.png'), fullPage: true });
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

// "Observe, then invert" in Chromium: the first lesson's scene (www/playground/scenes/
// first-inversion.json) opened in the playground from its link, observed, handed to the
// research app, reconstructed; the reconstruction's Einstein radius (the caption's) against
// the truth's (the playground's critical curve at the same source redshift, from the core).
// Screenshots of Observe and of the comparison at 1280 x 720 and 390 px wide. At 1280 x 720
// the comparison downloads at twice its size, and after a reload the project comes back with
// its true lens, the link back to the scene and the iterates of the slider.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFile } from 'node:fs/promises';
import { join } from 'node:path';
import { openApp, imageSize, imageStats, pngSize, renderCount, waitStatus, waitView, ARTIFACTS, ROOT } from './browser.mjs';

const READY_TIMEOUT_MS = 120_000;
const RUN_TIMEOUT_MS = 300_000;
// The target: the Einstein radius within 10% of the truth's.
const EINSTEIN_RTOL = 0.10;

/** `#s1=` + base64url of the scene's JSON, as www/playground/scene.js writes it. */
async function sceneFragment() {
  const scene = JSON.parse(await readFile(join(ROOT, 'www/playground/scenes/first-inversion.json'), 'utf8'));
  return '#s1=' + Buffer.from(JSON.stringify(scene)).toString('base64url');
}

/** The comparison as a figure twice its size; then a reload of the page: the saved project
 * opens with its model as the true lens, the link back to the scene, and the slider over the
 * same iterates, whose maps differ. */
async function downloadAndReload(page) {
  const [w, h] = await imageSize(page, '#view-image');
  await page.selectOption('#figure-scale', '2');
  const [dl] = await Promise.all([page.waitForEvent('download'), page.click('#dl-figure')]);
  assert.equal(dl.suggestedFilename(), 'compare-with-truth@2x.png');
  const [w2, h2] = pngSize(await readFile(await dl.path()));
  assert.ok(Math.abs(w2 - 2 * w) <= 8 && Math.abs(h2 - 2 * h) <= 8, `compare at 2x: ${w2} x ${h2}, shown ${w} x ${h}`);

  let before = await renderCount(page);
  await page.click('#tab-kappa');
  await waitView(page, 'kappa', before, READY_TIMEOUT_MS);
  await page.waitForSelector('#iterates:not([hidden])');
  const label = await page.textContent('#iterate-label');
  const steps = await page.$eval('#iterate-slider', (el) => el.max);
  const back = await page.getAttribute('#back-to-playground', 'href');
  await page.reload();
  await waitStatus(page, /^Restored your project/, READY_TIMEOUT_MS);
  await waitView(page, 'kappa', 0, READY_TIMEOUT_MS);
  assert.equal(await page.getAttribute('body', 'data-truth-model'), 'yes', 'the model is the true lens again');
  assert.equal(await page.getAttribute('#back-to-playground', 'href'), back);
  await page.waitForSelector('#iterates:not([hidden])');
  assert.equal(await page.textContent('#iterate-label'), label);
  assert.equal(await page.$eval('#iterate-slider', (el) => el.max), steps, 'the same iterates');
  const result = (await imageStats(page, '#view-image')).sum;
  before = await renderCount(page);
  await page.focus('#iterate-slider');
  await page.keyboard.press('Home');
  await waitView(page, 'kappa', before, READY_TIMEOUT_MS);
  assert.match(await page.textContent('#iterate-label'), /^iteration 0 of/);
  assert.notEqual((await imageStats(page, '#view-image')).sum, result, 'the start looks like the result');
  await page.screenshot({ path: join(ARTIFACTS, 'observe-reloaded-1280x720.png') });
}

for (const [width, height, tag] of [[1280, 720, '1280x720'], [390, 844, '390']]) {
  test(`observe then invert the first lesson's scene (${tag})`, async () => {
    const app = await openApp({ width, height, query: `?playground${await sceneFragment()}` });
    const { page } = app;
    try {
      await page.waitForFunction(() => document.getElementById('playground')?.dataset.ready === '1',
        null, { timeout: READY_TIMEOUT_MS });
      await page.click('#pg-observe');
      await page.waitForFunction(() => document.getElementById('playground').dataset.observed !== undefined,
        null, { timeout: READY_TIMEOUT_MS });
      const readout = await page.textContent('#pg-readout');
      console.log(`observed (${tag}): ${readout}`);
      assert.match(readout, /system 1 \(z = 2\): \d+ arcs/);
      assert.match(readout, /system 2 \(z = 3\): \d+ point images/);
      await page.screenshot({ path: join(ARTIFACTS, `observe-${tag}.png`) });
      // The truth's Einstein radius at z_s = 3, from the core's critical curve of the scene.
      const truth = await page.evaluate(() => window.__playground.frame.curves.find((c) => c.z === 3).einstein_radius_arcsec);

      await page.click('#pg-invert');
      await waitStatus(page, /^Done in/, RUN_TIMEOUT_MS);
      await waitView(page, 'kappa', 0, READY_TIMEOUT_MS);
      const caption = await page.textContent('#summary');
      const ours = Number(caption.match(/Einstein radius ≥? ?([\d.]+)″ at z_s = 3/)[1]);
      console.log(`first inversion (${tag}): Einstein radius at z_s = 3: truth ${truth.toFixed(2)}″, reconstruction ${ours}″`);
      assert.ok(Math.abs(ours / truth - 1) < EINSTEIN_RTOL, `${ours} vs ${truth}`);
      assert.equal(await page.getAttribute('body', 'data-truth-model'), 'yes');
      assert.match(await page.textContent('#project-name'), /^Playground: SIE/);
      // The Example menu shows the observation (an example of its own), not a blank.
      const menu = await page.$eval('#example-select', (s) => s.selectedOptions[0]?.textContent ?? '');
      assert.match(menu, /^Playground: SIE/);
      const back = await page.getAttribute('#back-to-playground', 'href');
      assert.ok(back.startsWith('./?playground#s1='), back);

      // The comparison with the truth.
      await page.click('#tab-compare');
      await waitView(page, 'compare', 0, READY_TIMEOUT_MS);
      await page.locator('#figure').scrollIntoViewIfNeeded();
      await page.screenshot({ path: join(ARTIFACTS, `compare-${tag}.png`) });
      if (width === 1280) await downloadAndReload(page);
      assert.deepEqual(app.consoleErrors, []);
    } finally {
      await app.close();
    }
  });
}

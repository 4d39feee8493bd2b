// "Observe, then invert" in Chromium: the first lesson's scene (www/playground/scenes/
// first-inversion.json) opened in the playground from its link, observed, handed to the
// research app, reconstructed; the reconstruction's Einstein radius (the caption's) against
// the truth's (the playground's critical curve at the same source redshift, from the core).
// Screenshots of Observe and of the comparison at 1280 x 720 and 390 px wide.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFile } from 'node:fs/promises';
import { join } from 'node:path';
import { openApp, waitStatus, waitView, ARTIFACTS, ROOT } from './browser.mjs';

const READY_TIMEOUT_MS = 120_000;
const RUN_TIMEOUT_MS = 300_000;
// The target: the Einstein radius within 10% of the truth's.
const EINSTEIN_RTOL = 0.10;

/** `#s1=` + base64url of the scene's JSON, as www/playground/scene.js writes it. */
async function sceneFragment() {
  const scene = JSON.parse(await readFile(join(ROOT, 'www/playground/scenes/first-inversion.json'), 'utf8'));
  return '#s1=' + Buffer.from(JSON.stringify(scene)).toString('base64url');
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
      const back = await page.getAttribute('#back-to-playground', 'href');
      assert.ok(back.startsWith('./?playground#s1='), back);

      // The comparison with the truth.
      await page.click('#tab-compare');
      await waitView(page, 'compare', 0, READY_TIMEOUT_MS);
      await page.locator('#figure').scrollIntoViewIfNeeded();
      await page.screenshot({ path: join(ARTIFACTS, `compare-${tag}.png`) });
      assert.deepEqual(app.consoleErrors, []);
    } finally {
      await app.close();
    }
  });
}

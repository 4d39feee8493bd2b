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
  // Before a result the position box gives no cluster's coordinates as its example.
  assert.equal(await app.page.getAttribute('#locate-input', 'placeholder'), 'RA Dec, or x y in arcsec');
  assert.doesNotMatch(await app.page.textContent('#locate-help'), /\d\d:\d\d:\d\d/);
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
    // The table replaces the map (the figure's grid layout must not show it through [hidden]).
    assert.equal(await page.isVisible('#figure'), false);
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

test('a typed coordinate reads out κ, μ and the counter-images without the mouse; a bad one says why', async () => {
  const app = await reconstructed({ width: 1280, height: 720 });
  try {
    const { page } = app;
    // The example's frame: offsets from its sky reference (members.cat's #REFERENCE).
    const [ra0, dec0] = [197.872917, -1.341111];
    // The box's examples are this cluster's reference, not another's.
    await page.waitForFunction((deg) => document.getElementById('locate-help').textContent.includes(deg),
      `(${ra0.toFixed(4)} ${dec0.toFixed(4)})`);
    assert.match(await page.getAttribute('#locate-input', 'placeholder'), /^13:11:29\.\d\d -01:20:28\.\d$/);
    const [x, y] = [-40.0, -20.0];
    const ra = ra0 - x / 3600 / Math.cos(dec0 * Math.PI / 180);
    const dec = dec0 + y / 3600;
    const readoutAfter = async (text) => {
      // Emptied first, so that the wait sees this position's read-out, not the last one's.
      await page.$eval('#readout', (el) => { el.textContent = ''; });
      await page.fill('#locate-input', text);
      await page.press('#locate-input', 'Enter');
      await page.waitForFunction(() => /^Typed: /.test(document.getElementById('readout').textContent));
    };
    // RA/Dec in degrees, typed and sent with Enter: the point, its RA/Dec, κ and μ.
    await readoutAfter(`${ra.toFixed(6)} ${dec.toFixed(6)}`);
    const readout = await page.textContent('#readout');
    const m = readout.match(/^Typed: RA, Dec (\d\d:\d\d:\d\d\.\d\d [+-]\d\d:\d\d:\d\d\.\d) \(([\d.]+)°, (-?[\d.]+)°\); x = (-?[\d.]+)″, y = (-?[\d.]+)″ from the reference; κ = ([\d.]+), μ\(z_s = 3\) = (-?[\d.]+) at this point$/);
    assert.ok(m, readout);
    assert.ok(Math.abs(Number(m[4]) - x) < 0.01 && Math.abs(Number(m[5]) - y) < 0.01, readout);
    assert.equal(await page.getAttribute('#locate-form', 'data-read-as'), 'RA/Dec in degrees');
    // The source's images in their order of arrival, the one at the point named, and the
    // magnification at the point and at that image side by side.
    await page.waitForSelector('#counter-images:not([hidden])');
    const listed = await page.textContent('#counter-images-text');
    assert.match(listed, /at z_s = 3 it has \d+ images? \(yellow squares where \|μ\| ≥ 0\.1; positions in arcsec, in order of arrival/);
    assert.match(listed, /^The source behind \(-40\.00″, -20\.00″\)/);
    assert.match(listed, /1st \(-?[\d.]+, -?[\d.]+\) μ -?[\d.]+ \(parity [+−]\), arrives first at \d\d:\d\d:\d\d\.\d\d/);
    const atPoint = listed.match(/Magnification at the point itself: (-?[\d.]+); at the image found there \(([\d.]+)″ away\): (-?[\d.]+)\./);
    assert.ok(atPoint, listed);
    assert.equal(atPoint[1], Number(m[7]).toFixed(2), 'the read-out and the list give one μ at the point');
    assert.ok(Number(atPoint[2]) < 0.1, listed);
    assert.equal([...listed.matchAll(/\(the image at the point\)/g)].length, 1, listed);
    await page.locator('#figure').screenshot({ path: join(ARTIFACTS, 'verdict-locate-1280.png') });
    // Sexagesimal and arcsec give the same point.
    await readoutAfter('13:11:32.17 -01:20:48.0');
    assert.match(await page.textContent('#readout'), /x = -(39\.9\d|40\.0\d)″, y = -(19\.9\d|20\.0\d)″/);
    assert.equal(await page.getAttribute('#locate-form', 'data-read-as'), 'RA/Dec, sexagesimal');
    await readoutAfter('-40 -20 arcsec');
    assert.match(await page.textContent('#readout'), /x = -40\.00″, y = -20\.00″ from the reference/);
    // A bad coordinate: the reason next to the box, the pinned point kept.
    const before = await page.textContent('#readout');
    await page.fill('#locate-input', 'xyz');
    await page.click('#locate-go');
    await page.waitForFunction(() => document.getElementById('locate-error').textContent !== '');
    assert.equal(await page.textContent('#locate-error'),
      "could not read 'xyz' as a coordinate: expected two values (RA Dec, or x y in arcsec), found 1");
    assert.equal(await page.getAttribute('#locate-input', 'aria-invalid'), 'true');
    assert.equal(await page.textContent('#readout'), before);
    await page.fill('#locate-input', '13:11:31 -95:00:00');
    await page.click('#locate-go');
    await page.waitForFunction(() => /Dec/.test(document.getElementById('locate-error').textContent));
    assert.match(await page.textContent('#locate-error'), /^could not read '13:11:31 -95:00:00' as a coordinate: Dec '-95:00:00' is outside \+-90 degrees$/);
    // Off the maps.
    await page.fill('#locate-input', '500 0 arcsec');
    await page.click('#locate-go');
    await page.waitForFunction(() => /off the/.test(document.getElementById('locate-error').textContent));
    // On a phone the box is usable and nothing overflows.
    await page.setViewportSize({ width: 390, height: 844 });
    await page.fill('#locate-input', '-40 -20');
    await page.press('#locate-input', 'Enter');
    await page.waitForFunction(() => document.getElementById('locate-error').textContent === '');
    assert.equal(await page.evaluate(() => document.documentElement.scrollWidth), 390);
    await page.locator('#figure').screenshot({ path: join(ARTIFACTS, 'verdict-locate-390.png') });
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('the offer to fit a .par galaxy names one without a magnitude by the mass it stands for', async () => {
  const app = await openApp();
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    // A verdict that misses its BCG, and two galaxies of a .par: one with a `mag`, one (a
    // starting .par's BCG, MACS1931's `potentiel 3`) with a velocity dispersion only.
    const text = await page.evaluate(async () => {
      const { showVerdict } = await import('./js/verdict.js');
      const verdict = {
        trust: 'usable_with_care', words: 'usable with care', reasons: 'No BCG.', systems: 3,
        systems_matched: 3, members: 10, members_with_own_curves: 0, worst: [], bcg: { missing: true },
      };
      showVerdict(verdict, {
        modelGalaxies: [
          { id: 'O3', line: 55, mag: 17.037, mag_from_mass: false },
          { id: '3', line: 66, mag: 16.8312, mag_from_mass: true },
        ],
        fitModel: () => {},
      });
      return document.getElementById('fit-model-galaxies').textContent;
    });
    assert.equal(text, "Fit the .par's galaxies (O3, mag 17.04; 3, as massive as a mag 16.83 member) and reconstruct again");
    await page.locator('#verdict').screenshot({ path: join(ARTIFACTS, 'verdict-offer-by-mass.png') });
    // The longer words wrap inside the box on a phone.
    await page.setViewportSize({ width: 390, height: 844 });
    const button = await page.locator('#fit-model-galaxies').boundingBox();
    assert.ok(button.x >= 0 && button.x + button.width <= 390, JSON.stringify(button));
    assert.equal(await page.evaluate(() => document.documentElement.scrollWidth), 390);
    await page.locator('#verdict').screenshot({ path: join(ARTIFACTS, 'verdict-offer-by-mass-390.png') });
    await page.evaluate(async () => (await import('./js/verdict.js')).showVerdict(null));
    assert.equal(await page.isHidden('#verdict'), true);
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

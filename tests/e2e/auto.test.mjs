// End-to-end: the regulariser's strength "auto" (the default for your own data) cross-validates
// its candidates in a pool of extra workers (www/js/pool.js), then reconstructs; the result
// shows the curve it chose from. Cancel during the candidates stops every worker; a worker
// that fails fails the run with its message.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { readFile } from 'node:fs/promises';
import { openApp, phoneShot, runToMap, ARTIFACTS, ROOT, setField, waitStatus } from './browser.mjs';

const AS1063 = join(ROOT, '..', 'shared', 'data', 'AS1063', 'lenstool_cats');
// The pool workers' URLs carry `worker=pool-N` (lens-client.js).
const POOL = /[?&]worker=pool-\d+/;

/** Opens the app and loads the AS1063 gold catalogues (images and members) at z_lens 0.348,
 * with the app's defaults otherwise: the strength "auto". */
async function openAs1063(options) {
  const app = await openApp(options);
  const { page } = app;
  await waitStatus(page, /^Ready/);
  await page.setInputFiles('#file-images', join(AS1063, 'cats_gold_mul_gold.cat'));
  await page.waitForFunction(() => /19 systems, 50 images/.test(document.getElementById('status-images').textContent));
  await page.waitForFunction(() => document.getElementById('project-name').textContent === 'Your data');
  await page.setInputFiles('#file-members', join(AS1063, 'cats_gold_ref_potential_w_clumpNE.cat'));
  await page.waitForFunction(() => /members/.test(document.getElementById('status-members').textContent));
  await setField(page, '#set-z_lens', 0.348);
  assert.equal(await page.inputValue('#set-reconstruct-objective-strength'), 'auto');
  return app;
}

/** The pool workers alive in the page. */
const poolWorkers = (page) => page.workers().filter((w) => POOL.test(w.url()));

test('AS1063 gold with the strength "auto": the candidates run in workers and the curve is shown', async () => {
  const app = await openAs1063();
  try {
    const { page } = app;
    const t0 = Date.now();
    await page.click('#reconstruct');
    // One progress bar: the candidates done, and those being tried at their iteration.
    await page.waitForFunction(() => /^Choosing the regulariser: \d+ of \d+ candidates done; \d workers? trying [\w. ×,]+ \(iteration \d+\)/
      .test(document.getElementById('progress-text').textContent), null, { timeout: 60_000 });
    const candidates = Number((await page.textContent('#progress-text')).match(/of (\d+) candidates/)[1]);
    const workers = Math.min(await page.evaluate(() => navigator.hardwareConcurrency), 4, candidates);
    assert.equal(poolWorkers(page).length, workers);
    await page.screenshot({ path: join(ARTIFACTS, 'app-auto-progress.png') });
    await waitStatus(page, /^Done in/, 600_000);
    const seconds = (Date.now() - t0) / 1000;
    // The pool is gone once the candidates are done.
    assert.equal(poolWorkers(page).length, 0);

    // The curve: one row per candidate, the chosen one marked, and what it means.
    assert.equal(await page.locator('#strength-table tbody tr').count(), candidates);
    assert.equal(await page.locator('#strength-table tr.chosen').count(), 1);
    const chosen = await page.textContent('#strength-table tr.chosen th');
    assert.match(chosen, /✓ chosen/);
    assert.match(await page.innerText('#strength-summary'), /whose held-out images were predicted best/);
    // Every system has a redshift: the folds hold them all.
    assert.doesNotMatch(await page.innerText('#strength-summary'), /had no redshift/);
    const strengths = (await page.$$eval('#strength-table tbody tr', (trs) => trs.map((tr) => Number(tr.dataset.strength))));
    const cells = (await page.$$eval('#strength-table tbody tr', (trs) => trs.map((tr) => Number(tr.dataset.cells))));
    const chosenRow = await page.$eval('#strength-table tr.chosen', (tr) => ({ ...tr.dataset }));

    await page.click('#downloads-panel summary');
    const [dl] = await Promise.all([page.waitForEvent('download'), page.click('#dl-summary-json')]);
    const summary = JSON.parse(await readFile(await dl.path(), 'utf8'));
    const choice = summary.strength_choice;
    assert.ok(choice, 'summary.json has strength_choice');
    assert.equal(summary.settings.objective.strength, 'auto');
    // Every candidate strength of the settings with each regulariser and each grid "auto" tries.
    const o = summary.settings.objective;
    const grids = [...new Set(o.auto_grid_scales.map((s) => Math.max(1, Math.round(s * summary.settings.grid.cells))))];
    assert.equal(grids.length, 3, 'the default tries three grids');
    // Each regulariser, the least-mass one too (fitted without the default external shear).
    assert.equal(summary.settings.grid.external_shear_sigma, 0.1);
    const kinds = o.auto_regularisers;
    assert.ok(kinds.includes('density'), 'the defaults ask for density too');
    assert.deepEqual([...new Set(choice.candidates.map((c) => c.regulariser))].sort(), [...kinds].sort());
    assert.equal(choice.candidates.length, o.candidates.length * kinds.length * grids.length);
    assert.deepEqual(choice.candidates.map((c) => c.strength), strengths);
    assert.deepEqual(choice.candidates.map((c) => c.cells), cells);
    assert.deepEqual([...new Set(cells)].sort((a, b) => a - b), grids.sort((a, b) => a - b));
    assert.deepEqual([...new Set(strengths)].sort((a, b) => a - b), [...o.candidates].sort((a, b) => a - b));
    assert.equal(choice.folds, o.folds);
    assert.ok(choice.candidates.every((c) => Number.isFinite(c.holdout_median_arcsec)), JSON.stringify(choice));
    assert.equal(Number(chosenRow.strength), choice.chosen);
    if (choice.chosen_regulariser !== undefined) assert.equal(chosenRow.regulariser, choice.chosen_regulariser);
    assert.equal(Number(chosenRow.cells), choice.chosen_cells);
    // The reconstruction was made on the chosen grid.
    assert.equal(summary.grid_cells, choice.chosen_cells ** 2);
    // The rule: the fewest unmatched held-out images, then the smallest held-out median.
    const best = [...choice.candidates].sort((a, b) => a.holdout_unmatched - b.holdout_unmatched
      || a.holdout_median_arcsec - b.holdout_median_arcsec)[0];
    assert.equal(choice.chosen, best.strength);
    if (choice.chosen_regulariser !== undefined) assert.equal(choice.chosen_regulariser, best.regulariser);
    assert.equal(choice.chosen_cells, best.cells);
    // With no system held out and no folds, the verdict's held-out figure is the chosen
    // settings' in the choice's cross-validation, and says so.
    assert.equal(summary.verdict.holdout_from, 'choice');
    assert.equal(summary.verdict.holdout_offset_median_arcsec, best.holdout_median_arcsec);
    assert.match(await page.textContent('#verdict-facts li'),
      /^Image offsets \(median\): fitted \d+\.\d\d″, held out while choosing the settings \d+\.\d\d″$/);
    // One main tangential curve: the largest holds most of the area inside them.
    assert.ok(summary.maps.tangential_main_area_share > 0.8,
      `main tangential curve holds ${summary.maps.tangential_main_area_share} of the area`);
    await page.click('#downloads-panel summary');
    // The settings keep the regulariser and grid as set; a note under the strength says what
    // the choice used.
    const note = page.locator('#settings-form .chosen-note');
    assert.equal(await note.count(), 1);
    const kindLabel = choice.chosen_regulariser === 'density' ? 'least concentrated'
      : choice.chosen_regulariser === 'curvature' ? 'least curved' : 'smoothest mass';
    assert.equal(await note.textContent(), `The last run's choice: ${kindLabel} (${choice.chosen_regulariser}), strength ${
      choice.chosen}, ${choice.chosen_cells} × ${choice.chosen_cells} cells (the table under the map). The regulariser and grid fields keep the settings as set: "auto" starts from them again.`);
    await page.$eval('#set-reconstruct-objective-strength', (el) => { el.closest('details').open = true; });
    const field = page.locator('#set-reconstruct-objective-strength').locator('xpath=..');
    await field.scrollIntoViewIfNeeded();
    await field.screenshot({ path: join(ARTIFACTS, 'app-auto-choice-note.png') });

    await page.locator('#strength-box').scrollIntoViewIfNeeded();
    await page.screenshot({ path: join(ARTIFACTS, 'app-auto-result.png'), fullPage: true });
    await phoneShot(page, page.locator('#strength-box'), 'app-auto-result-phone.png');
    await field.screenshot({ path: join(ARTIFACTS, 'app-auto-choice-note-phone.png') });
    assert.deepEqual(app.consoleErrors, []);
    console.log(`AS1063 gold, auto, ${candidates} candidates in ${workers} pool workers: ${seconds.toFixed(1)} s`);
  } finally {
    await app.close();
  }
});

test('Cancel during the candidates stops every worker and a later Reconstruct works', async () => {
  const app = await openAs1063();
  try {
    const { page } = app;
    await page.click('#reconstruct');
    await page.waitForFunction(() => /trying .*\(iteration \d+\)/.test(document.getElementById('progress-text').textContent),
      null, { timeout: 60_000 });
    assert.ok(poolWorkers(page).length >= 1);
    const closed = poolWorkers(page).map((w) => new Promise((resolve) => w.once('close', resolve)));
    const t0 = Date.now();
    await page.click('#cancel');
    await waitStatus(page, /^Cancelled\./);
    await Promise.all(closed);
    assert.ok(Date.now() - t0 < 5000, 'cancel took too long');
    assert.equal(poolWorkers(page).length, 0);
    assert.equal(await page.isHidden('#progress-box'), true);
    assert.equal(await page.isEnabled('#reconstruct'), true);
    // The data are still loaded, and a new run (here at a fixed strength, quicker) works.
    await setField(page, '#set-reconstruct-objective-strength', 0.1);
    await runToMap(page, '#reconstruct', 120_000);
    assert.match(await page.textContent('#summary'), /Einstein radius/);
    // A fixed strength has no curve to show.
    assert.equal(await page.isHidden('#strength-box'), true);
    assert.match(await page.textContent('#summary'), /external shear γ = /);
    // The least-mass regulariser fits no shear, and the caption says why (summary.json's words).
    await setField(page, '#set-reconstruct-objective-regulariser', 'density');
    await runToMap(page, '#reconstruct', 120_000);
    assert.match(await page.textContent('#summary'), /no external shear \(the least-mass regulariser fits none\)/);
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('a pool worker that fails fails the run with its message, and the app still works', async () => {
  const app = await openApp({ query: '?workers=2', serviceWorkers: 'block' });
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    // The teaching example with the strength "auto" (its settings pin the paper's method: the
    // regulariser and the exact solver are set back first).
    await page.selectOption('#example-select', { label: 'Teaching example: one halo, four sources' });
    await page.waitForFunction(() => /Teaching/.test(document.getElementById('project-name').textContent));
    await setField(page, '#set-reconstruct-objective-regulariser', 'gradient');
    await setField(page, '#set-reconstruct-objective-strength', 'auto');
    await setField(page, '#set-reconstruct-solver-method', 'exact');
    // A number typed as text is sent as a number, "auto" as the word; anything else is refused.
    await page.fill('#set-reconstruct-objective-strength', 'strong');
    await page.dispatchEvent('#set-reconstruct-objective-strength', 'change');
    await page.waitForFunction(() => document.getElementById('set-reconstruct-objective-strength-error').textContent !== '');
    assert.equal(await page.inputValue('#set-reconstruct-objective-strength'), 'auto');
    // The second pool worker's script fails to load.
    await page.route(/worker\.js\?.*worker=pool-2/, (route) => route.fulfill({
      contentType: 'text/javascript', body: 'throw new Error("simulated crash");',
    }));
    await page.click('#reconstruct');
    await waitStatus(page, /^Failed\./, 60_000);
    assert.match(await page.textContent('#error'), /Choosing the regulariser failed: .*simulated crash/);
    assert.equal(poolWorkers(page).length, 0);
    assert.equal(await page.isHidden('#progress-box'), true);
    // Without the broken worker the same run completes, with its curve.
    await page.unroute(/worker\.js\?.*worker=pool-2/);
    await runToMap(page, '#reconstruct', 120_000);
    assert.equal(await page.locator('#strength-table tr.chosen').count(), 1);
    await page.screenshot({ path: join(ARTIFACTS, 'app-auto-teaching.png'), fullPage: true });
  } finally {
    await app.close();
  }
});

test('a choice that passed over a crowded map says so, at 1280 px and on a phone', async () => {
  // The shape of Jauzac et al.'s MACS J1149 run (BENCHMARKS.md): least mass 0.01 predicted the
  // held-out images best but its map crowded 22 of 45 systems, so gradient 0.1 was used.
  const row = (regulariser, strength, median) => ({
    regulariser, strength, cells: 32, holdout_median_arcsec: median, holdout_rms_arcsec: 2 * median,
    holdout_unmatched: 0, fit_median_arcsec: 0.3, holdout_by_system: [],
  });
  const choice = {
    folds: 4,
    candidates: [row('density', 0.01, 0.66), row('gradient', 0.1, 0.68), row('curvature', 1, 0.9)],
    chosen: 0.1, chosen_regulariser: 'gradient', chosen_cells: 32, rule: '', before_estimates: null,
    crowded_maps: [{ regulariser: 'density', strength: 0.01, cells: 32, crowded_systems: 22, systems: 45 }],
  };
  const app = await openApp();
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    await page.evaluate(async (c) => (await import('./js/views.js')).showStrengthChoice(c), choice);
    const box = page.locator('#strength-box');
    await box.scrollIntoViewIfNeeded();
    assert.match(await page.textContent('#strength-table tr.chosen th'), /^gradient 0\.1 ✓ chosen/);
    const first = await page.textContent('#strength-table tbody tr:first-child th');
    assert.match(first, /density 0\.01\s+crowded map: 22 of 45 systems, passed over/);
    // The other rows carry no such mark.
    assert.equal(await page.locator('#strength-table .mark.passed').count(), 1);
    const summary = (await page.textContent('#strength-summary')).replace(/\s+/g, ' ');
    assert.match(summary, /predicted best, crowded maps passed over \(below\)\./);
    assert.match(summary, /One candidate that predicted better was passed over: its map predicts more than twice as many images as observed for more than a third of the systems\./);
    await box.screenshot({ path: join(ARTIFACTS, 'app-auto-crowded.png') });
    await phoneShot(page, box, 'app-auto-crowded-phone.png');
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('a cross-validation of an "auto" run says what each fold chose, at 1280 px and on a phone', async () => {
  // Three folds of an "auto" run: two chose gradient 0.1, one passed over a crowded least-mass map.
  const run = (fold, chosen, passed) => ({
    fold, held_out: [String(fold)], status: 'Converged', iterations: 12, c: [0.5], grid_mass_msun: 1e14,
    einstein_radius_arcsec: 24 + fold / 10, einstein_radius_z_source: 2, mass_within_arcsec: [],
    fit_image_offset_median_arcsec: 0.3, holdout_image_offset_median_arcsec: 0.7, elapsed_ms: 1000,
    chosen, crowding: { crowded_systems: 2, systems: 30 },
    crowded_maps: passed ? [{ regulariser: 'density', strength: 0.01, cells: 32, crowded_systems: 14, systems: 30 }] : [],
  });
  const gradient = { regulariser: 'gradient', strength: 0.1, cells: 32 };
  const cv = {
    folds: 3, status: 'Completed', holdout_images: 30, holdout_images_unmatched: 0,
    holdout_image_offset_median_arcsec: 0.7, holdout_image_plane_rms_arcsec: 1.4, fit_image_offset_median_arcsec: 0.3,
    runs: [run(1, gradient, false), run(2, gradient, true), run(3, { regulariser: 'curvature', strength: 1, cells: 16 }, false)],
    always_fitted: [], systems: [],
  };
  const app = await openApp();
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    await page.evaluate(async (c) => (await import('./js/views.js')).showCrossval(c, () => {}), cv);
    const text = (await page.textContent('#crossval-summary')).replace(/\s+/g, ' ');
    assert.match(text, /each fold chose again on its own systems: gradient 0\.1 on 32 × 32 cells \(2 folds\), curvature 1 on 16 × 16 cells \(1 fold\); 1 of 3 passed over a crowded map first, as the reconstruction does\./);
    const box = page.locator('#crossval-box');
    await box.scrollIntoViewIfNeeded();
    await box.screenshot({ path: join(ARTIFACTS, 'app-crossval-auto.png') });
    await phoneShot(page, box, 'app-crossval-auto-phone.png');
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

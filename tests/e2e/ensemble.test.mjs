// End-to-end: the "Ensemble members" setting runs that many more reconstructions after
// Reconstruct, spread over a pool of workers (www/js/ensemble.js) with one progress bar; the
// result gains the spread view, the ensemble's downloads, its intervals in the caption and its
// values in the read-out. Cancel during the members stops every worker and leaves the app
// usable. The project keeps the ensemble: a restarted worker and a reload show it again.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFile } from 'node:fs/promises';
import { join } from 'node:path';
import { idb, openApp, phoneShot, ARTIFACTS, fitsAxes, imageStats, renderCount, savedProject, setField, waitStatus, waitView } from './browser.mjs';

// The pool workers' URLs carry `worker=pool-N` (lens-client.js).
const POOL = /[?&]worker=pool-\d+/;
const poolWorkers = (page) => page.workers().filter((w) => POOL.test(w.url()));
const ENSEMBLE_DONE = /^Done in \d+\.\d+ s; ensemble of (\d+) members in \d+\.\d+ s\./;

/** Downloads `id`'s file; resolves with its name and bytes. */
async function download(page, id) {
  const [dl] = await Promise.all([page.waitForEvent('download'), page.click(`#${id}`)]);
  return { name: dl.suggestedFilename(), bytes: await readFile(await dl.path()) };
}

test('an ensemble of the built-in example gives the spread view, the downloads and the intervals', async () => {
  const app = await openApp({ query: '?app&workers=2' });
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    assert.equal(await page.inputValue('#set-ensemble-members'), '0');
    assert.equal(await page.isHidden('#tab-spread'), true);
    await setField(page, '#set-ensemble-members', 3);
    await page.click('#reconstruct');
    // One progress bar for all the members, the pool's two workers running them.
    await page.waitForFunction(() => /^Ensemble: member [1-3] of 3, \d done; 2 workers running members? [\d, ]+, about/
      .test(document.getElementById('progress-text').textContent), null, { timeout: 120_000 });
    assert.equal(poolWorkers(page).length, 2);
    await waitStatus(page, ENSEMBLE_DONE, 300_000);
    assert.equal(poolWorkers(page).length, 0);
    await page.waitForSelector('#progress-box', { state: 'hidden' });

    // The intervals: in the caption and under the views.
    const caption = await page.textContent('#summary');
    assert.match(caption, /Ensemble of 3 members \(68% intervals about this map(, widened ×\d+\.\d\d)?\): Einstein radius \d+\.\d – \d+\.\d″/);
    assert.match(await page.innerText('#ensemble-summary'), /Einstein radius at z_s = 3, 68% interval\s+about this map/);
    assert.equal(await page.locator('#ensemble-masses li').count(), 3);

    // The spread view.
    assert.equal(await page.isVisible('#tab-spread'), true);
    const before = await renderCount(page);
    await page.click('#tab-spread');
    await waitView(page, 'spread', before);
    const stats = await imageStats(page, '#view-image');
    assert.ok(stats.distinctColours > 50, `spread figure has ${stats.distinctColours} colours`);
    assert.ok(stats.reddish > 50, 'the tangential critical curve (red) is drawn');
    await page.screenshot({ path: join(ARTIFACTS, 'app-ensemble-spread.png'), fullPage: true });

    // The read-out on the mass map: the magnification's interval and kappa's spread.
    const back = await renderCount(page);
    await page.click('#tab-kappa');
    await waitView(page, 'kappa', back);
    const box = await page.locator('#view-image').boundingBox();
    await page.mouse.click(box.x + box.width * 0.45, box.y + box.height * 0.4);
    await page.waitForFunction(() => /^Clicked: .*ensemble of 3: κ std \d\.\d{3}, μ 16–84% -?\d+\.\d\d to -?\d+\.\d\d \(median -?\d+\.\d\d\)/
      .test(document.getElementById('readout').textContent), null, { timeout: 30_000 });

    // The downloads: the five maps on the result's map, ensemble.json and the figure.
    await page.click('#downloads-panel summary');
    for (const name of ['kappa-mean', 'kappa-std', 'magnif-p16', 'magnif-p50', 'magnif-p84']) {
      const f = await download(page, `dl-${name}-fits-panel`);
      assert.equal(f.name, `${name}.fits`);
      assert.deepEqual(fitsAxes(f.bytes), [256, 256]);
      assert.match(f.bytes.subarray(0, 2880 * 2).toString('latin1'), /NMEMBERS= +3/);
    }
    const ensemble = JSON.parse((await download(page, 'dl-ensemble-json-panel')).bytes.toString('utf8'));
    assert.equal(ensemble.members.length, 3);
    assert.equal(ensemble.seed, 1);
    assert.equal(ensemble.status, 'Completed');
    const png = await download(page, 'dl-kappa-std-png-panel');
    assert.equal(png.bytes.subarray(1, 4).toString('latin1'), 'PNG');
    const summary = JSON.parse((await download(page, 'dl-summary-json')).bytes.toString('utf8'));
    assert.equal(summary.ensemble_members, 3);
    assert.deepEqual(summary.einstein_radius_interval_arcsec, ensemble.einstein_radius_interval_arcsec);
    assert.equal(summary.mass_within_interval_msun.length, 3);
    assert.deepEqual(summary.ensemble_calibration, ensemble.calibration ?? null);
    // The interval is about the map the caption gives: it holds its Einstein radius.
    const [lo, hi] = ensemble.einstein_radius_interval_arcsec;
    assert.ok(lo <= summary.einstein_radius_arcsec && summary.einstein_radius_arcsec <= hi,
      `${lo} - ${hi} against ${summary.einstein_radius_arcsec}`);
    // Every member says where it predicts the images of the systems it left out; where three
    // of them predict one image, the box says how their misses compare with their spread.
    assert.ok(ensemble.members.every((m) => Array.isArray(m.left_out_images)));
    // Every member says how crowded its map is; the box says when a member's first one was.
    assert.ok(ensemble.members.every((m) => Number.isInteger(m.crowding?.systems)));
    assert.equal(await page.isVisible('#ensemble-crowded'), ensemble.members.some((m) => m.crowded_maps.length > 0));
    assert.equal(await page.isVisible('#ensemble-calibration'), ensemble.calibration != null);
    if (ensemble.calibration) {
      assert.match(await page.innerText('#ensemble-calibration'), /miss by a median of \d+\.\d\d″ for a spread of/);
    }
    await page.click('#downloads-panel summary');

    await page.locator('#ensemble-box').scrollIntoViewIfNeeded();
    await page.screenshot({ path: join(ARTIFACTS, 'app-ensemble-result.png'), fullPage: true });
    await phoneShot(page, page.locator('#ensemble-box'), 'app-ensemble-result-phone.png');
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('members that passed over crowded maps are said under the views, at 1280 px and on a phone', async () => {
  // The shape of Jauzac et al.'s MACS J1149 ensemble (BENCHMARKS.md): of four members, one
  // kept its first map, two moved off crowded ones, and one found none uncrowded.
  // `kept`: every map it tried was crowded (16 of 40 systems is over a third).
  const member = (k, crowded, passed, kept = false) => ({
    member: k, fitted: [], grid_shift_arcsec: [0, 0], redshifts: [], regulariser: 'gradient', strength: 0.1,
    cells: 32, crowding: { crowded_systems: crowded, systems: 40 }, crowded: kept, member_mass_factor: 1,
    status: 'Converged',
    c: [0.5], einstein_radius_arcsec: 24 + k, mass_within_arcsec: [], left_out_image_offset_median_arcsec: 0.8,
    left_out_images: [], elapsed_ms: 1000,
    crowded_maps: passed.map((n) => ({ regulariser: 'density', strength: 0.01, cells: 32, crowded_systems: n, systems: 40 })),
  });
  const ensemble = {
    status: 'Completed', seed: 1, z_source: 2, note: 'What the spread includes.', maps: false,
    members: [member(1, 2, []), member(2, 3, [20]), member(3, 8, [25, 18]), member(4, 16, [30, 22, 19], true)],
    einstein_radius_interval_arcsec: [22.1, 27.9], mass_within_interval_msun: [], calibration: null,
  };
  const app = await openApp();
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    await page.evaluate(async (e) => (await import('./js/ensemble.js')).showEnsemble(e, {}), ensemble);
    const text = (await page.innerText('#ensemble-crowded')).replace(/\s+/g, ' ');
    assert.match(text, /^3 of 4 members' first maps predicted far more images than observed for more than a third of the systems/);
    assert.match(text, /, and 1 found none better and kept the least crowded\.$/);
    const box = page.locator('#ensemble-box');
    await box.scrollIntoViewIfNeeded();
    await box.screenshot({ path: join(ARTIFACTS, 'app-ensemble-crowded.png') });
    await phoneShot(page, box, 'app-ensemble-crowded-phone.png');
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('Cancel during the members stops every worker and the app stays usable', async () => {
  const app = await openApp({ query: '?app&workers=2' });
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    await setField(page, '#set-ensemble-members', 20);
    await page.click('#reconstruct');
    await page.waitForFunction(() => /^Ensemble: .* running members? \d/.test(document.getElementById('progress-text').textContent),
      null, { timeout: 120_000 });
    const workers = poolWorkers(page);
    assert.equal(workers.length, 2);
    const closed = workers.map((w) => new Promise((resolve) => w.once('close', resolve)));
    const t0 = Date.now();
    await page.click('#cancel');
    await waitStatus(page, /^Cancelled the ensemble: every worker was stopped/);
    await Promise.all(closed);
    assert.ok(Date.now() - t0 < 5000, 'cancel took too long');
    assert.equal(poolWorkers(page).length, 0);
    assert.equal(await page.isHidden('#progress-box'), true);
    assert.equal(await page.isEnabled('#reconstruct'), true);
    // The reconstruction stays, without an ensemble.
    assert.match(await page.textContent('#summary'), /Einstein radius/);
    assert.doesNotMatch(await page.textContent('#summary'), /Ensemble of/);
    assert.equal(await page.isHidden('#tab-spread'), true);
    // A later run with a smaller ensemble completes.
    await setField(page, '#set-ensemble-members', 2);
    await page.click('#reconstruct');
    await waitStatus(page, ENSEMBLE_DONE, 300_000);
    assert.equal(Number((await page.textContent('#status')).match(ENSEMBLE_DONE)[1]), 2);
    assert.equal(poolWorkers(page).length, 0);
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('a restarted worker and a reload show the ensemble again: caption, spread view, read-out, downloads', async () => {
  const app = await openApp({ query: '?app&workers=2', height: 720 });
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    await setField(page, '#set-ensemble-members', 2);
    await page.click('#reconstruct');
    await waitStatus(page, ENSEMBLE_DONE, 300_000);
    const interval = (await page.textContent('#summary')).match(/Ensemble of 2 members \(68% intervals about this map(, widened ×\d+\.\d\d)?\): Einstein radius \d+\.\d – \d+\.\d″/);
    assert.ok(interval, await page.textContent('#summary'));
    // The project in IndexedDB has the ensemble once it is saved after the members.
    await savedProject(page, /"maps_f32_base64"/);

    // The main worker dies: the page starts another one with the session, ensemble included.
    const main = page.workers().filter((w) => !POOL.test(w.url())).at(-1);
    await main.evaluate(() => { setTimeout(() => { throw new Error('the worker broke'); }); });
    await waitStatus(page, /^Restarted after the failure: your files, settings and last result are back\.$/, 120_000);
    await page.waitForFunction((i) => document.getElementById('summary').textContent.includes(i), interval[0],
      { timeout: 30_000 });
    assert.equal(await page.isVisible('#tab-spread'), true);

    await page.reload();
    await waitStatus(page, /^Restored your project from this browser/, 120_000);
    assert.ok((await page.textContent('#summary')).includes(interval[0]), `${await page.textContent('#summary')} / ${await page.textContent('#project-description')}`);
    assert.match(await page.textContent('#project-description'), /its ensemble of 2 members restored/);
    assert.match(await page.innerText('#ensemble-summary'), /Einstein radius at z_s = 3, 68% interval\s+about this map/);
    assert.equal(await page.isVisible('#tab-spread'), true);
    const before = await renderCount(page);
    await page.click('#tab-spread');
    await waitView(page, 'spread', before);
    const stats = await imageStats(page, '#view-image');
    assert.ok(stats.distinctColours > 50, `spread figure has ${stats.distinctColours} colours`);
    await page.screenshot({ path: join(ARTIFACTS, 'app-ensemble-reloaded.png') });
    const back = await renderCount(page);
    await page.click('#tab-kappa');
    await waitView(page, 'kappa', back);
    const box = await page.locator('#view-image').boundingBox();
    await page.mouse.click(box.x + box.width * 0.45, box.y + box.height * 0.4);
    await page.waitForFunction(() => /^Clicked: .*ensemble of 2: κ std \d\.\d{3}, μ 16–84% -?\d+\.\d\d to -?\d+\.\d\d/
      .test(document.getElementById('readout').textContent), null, { timeout: 30_000 });
    // The downloads made from what the project keeps, and what it does not keep said there.
    await page.click('#downloads-panel summary');
    const f = await download(page, 'dl-magnif-p84-fits-panel');
    assert.deepEqual(fitsAxes(f.bytes), [256, 256]);
    assert.match(f.bytes.subarray(0, 2880 * 2).toString('latin1'), /NMEMBERS= +2/);
    assert.match(await page.innerText('#ensemble-downloads'), /members' own maps \(range\/.*\) are not kept by the app/);
    await page.click('#downloads-panel summary');
    await page.locator('#ensemble-box').scrollIntoViewIfNeeded();
    await page.screenshot({ path: join(ARTIFACTS, 'app-ensemble-reloaded-box.png') });
    await phoneShot(page, page.locator('#ensemble-box'), 'app-ensemble-reloaded-phone.png');

    // A project that kept the intervals only (maps above the size a project keeps): the caption
    // and the intervals, no spread view, and the page says why and what to do.
    await page.setViewportSize({ width: 1280, height: 720 });
    const kept = JSON.parse(await idb(page, 'get', 'current'));
    delete kept.result.ensemble.maps_f32_base64;
    await idb(page, 'put', 'current', JSON.stringify(kept));
    await page.reload();
    await waitStatus(page, /^Restored your project from this browser/, 120_000);
    assert.ok((await page.textContent('#summary')).includes(interval[0]));
    assert.match(await page.textContent('#project-description'), /its ensemble of 2 members restored \(its intervals only/);
    assert.equal(await page.isHidden('#tab-spread'), true);
    assert.match(await page.innerText('#ensemble-box'), /kept its intervals only .* press Reconstruct to run it again/);
    assert.equal(await page.locator('#dl-kappa-std-fits').count(), 0);
    assert.equal(await page.locator('#dl-ensemble-json').count(), 1);
    await page.locator('#ensemble-box').screenshot({ path: join(ARTIFACTS, 'app-ensemble-intervals-only.png') });
    assert.deepEqual(app.consoleErrors.filter((e) => !/the worker broke/.test(e)), []);
  } finally {
    await app.close();
  }
});

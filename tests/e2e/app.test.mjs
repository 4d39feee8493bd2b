// End-to-end: the app opens on the built-in example, reconstructs it in the worker and shows a
// mass map with critical curves; hover, z_s redraw, FITS download, reload restore, phone width.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { readFile } from 'node:fs/promises';
import { openApp, imageStats, renderCount, runToMap, waitView, ARTIFACTS, setField, waitStatus, fitsAxes, watchLongTasks } from './browser.mjs';

/** Iterations of the quick test runs (the examples' own settings are 8000 and 3000). */
const QUICK_ITERATIONS = 600;
/** The first system's arc pixels on the data view: magenta (255, 60, 255) at opacity 0.7 over
 * the flat map's middle viridis colour (33, 145, 140), within a few levels of rounding. */
const FIRST_SYSTEM_ON_DATA = { rgb: [188, 86, 220], tol: 5 };

test('the built-in example reconstructs and shows a map with critical curves', async () => {
  const app = await openApp();
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    assert.match(await page.textContent('#project-name'), /Simulated A1689/);
    // The data are shown before anything is computed.
    await page.waitForSelector('#view-image:not([hidden])');
    const data = await imageStats(page, '#view-image', FIRST_SYSTEM_ON_DATA);
    assert.ok(data.near > 20, `arc pixels of system 1 not drawn (${data.near} pixels of its colour)`);
    await page.screenshot({ path: join(ARTIFACTS, 'app-data.png'), fullPage: true });

    await setField(page, '#set-reconstruct-solver-iterations', QUICK_ITERATIONS);
    // From Reconstruct to the map on screen, the main thread is never blocked for more than
    // 50 ms: the run is in the worker, and so is the rendering.
    const longTasks = await watchLongTasks(page);
    await runToMap(page, '#reconstruct');
    assert.deepEqual(await longTasks(), [], 'main-thread tasks over 50 ms [start, duration]');
    const stats = await imageStats(page, '#view-image');
    assert.ok(stats.width >= 400 && stats.height >= 400, `figure is ${stats.width}x${stats.height}`);
    assert.ok(stats.distinctColours > 200, `only ${stats.distinctColours} distinct colours`);
    assert.ok(stats.reddish > 50, `only ${stats.reddish} red curve pixels`);
    const before = await page.textContent('#summary');
    const r2 = Number(before.match(/Einstein radius (\d+\.\d)″/)[1]);
    assert.ok(r2 > 3, before);
    // The arcs hardly measure C (the grid can do what the members do): the caption says so,
    // and a warning says why.
    assert.match(before, /member factor C = [\d.]+, which these data hardly measure/);
    const warned = await page.locator('#run-warnings li').allTextContents();
    assert.ok(warned.some((w) => /^member layer "members": the grid cells and source positions reproduce all but/.test(w)),
      warned.join(' | '));
    await page.screenshot({ path: join(ARTIFACTS, 'app-example.png'), fullPage: true });

    // "Show: predicted" off removes the orange crosses of the predicted images (and their
    // legend entry); on again brings them back.
    const orange = { rgb: [255, 170, 0], tol: 12 };
    const withPredicted = (await imageStats(page, '#view-image', orange)).near;
    assert.ok(withPredicted > 50, `only ${withPredicted} orange pixels of predicted images`);
    const redrawn = async (toggle) => {
      const shown = await renderCount(page);
      await toggle();
      await waitView(page, 'kappa', shown);
    };
    await redrawn(() => page.uncheck('#show-predicted'));
    const without = (await imageStats(page, '#view-image', orange)).near;
    assert.ok(without < withPredicted / 10, `${without} orange pixels left of ${withPredicted}`);
    await page.screenshot({ path: join(ARTIFACTS, 'app-example-no-predicted.png'), fullPage: true });
    await redrawn(() => page.check('#show-predicted'));
    assert.equal((await imageStats(page, '#view-image', orange)).near, withPredicted);
    // "Show: model curves" off removes the true lens's critical curves (white, dashed), counted
    // over the title and the map (the legend under it reflows without their entry).
    const mapRows = { rows: 520 };
    const withModel = (await imageStats(page, '#view-image', mapRows)).white;
    await redrawn(() => page.uncheck('#show-model-curves'));
    const withoutModel = (await imageStats(page, '#view-image', mapRows)).white;
    assert.ok(withModel > withoutModel + 300, `white pixels: ${withModel} with the model's curves, ${withoutModel} without`);
    await redrawn(() => page.check('#show-model-curves'));

    // Hover read-out in the middle of the map.
    const box = await (await page.$('#view-image')).boundingBox();
    await page.mouse.move(box.x + box.width * 0.45, box.y + box.height * 0.5);
    await page.waitForFunction(() => /κ = /.test(document.getElementById('readout').textContent));

    // A higher z_s redraws larger curves without solving again; the read-out under the
    // still cursor follows it.
    await setField(page, '#z-curves', 5);
    await page.waitForFunction((r) => {
      const m = document.getElementById('summary').textContent.match(/Einstein radius (\d+\.\d)″ at z_s = 5/);
      return m && Number(m[1]) > r;
    }, r2);
    await page.waitForFunction(() => /μ\(z_s = 5\)/.test(document.getElementById('readout').textContent));

    // Every view renders.
    for (const tab of ['source', 'radial', 'convergence']) {
      await page.click(`#tab-${tab}`);
      await waitView(page, tab);
      const s = await imageStats(page, '#view-image');
      assert.ok(s.distinctColours > 20, `${tab}: ${s.distinctColours} colours`);
      if (tab === 'radial') {
        // The example's true model (its model.json), dashed in vermillion next to the result.
        const model = await imageStats(page, '#view-image', { rgb: [213, 94, 0], tol: 12 });
        assert.ok(model.near > 200, `${model.near} pixels of the model's profile`);
      }
      // The mass map's options and read-out do not apply here.
      assert.ok(await page.isDisabled('#scale') && await page.isDisabled('#show-members'), tab);
      assert.equal(await page.textContent('#readout'), '');
      await page.screenshot({ path: join(ARTIFACTS, `app-view-${tab}.png`), fullPage: true });
    }
    await page.click('#tab-systems');
    await page.waitForSelector('#systems table');
    assert.equal(await page.locator('#systems tbody tr').count(), 30);
    await page.click('#tab-kappa');
    assert.ok(await page.isEnabled('#scale') && await page.isEnabled('#show-members'));
    // Neither did the redraws, the hover read-out and the views since.
    assert.deepEqual(await longTasks(), [], 'main-thread tasks over 50 ms [start, duration]');

    // The FITS download parses with the map size.
    await page.click('#downloads-panel summary');
    const [download] = await Promise.all([page.waitForEvent('download'), page.click('#dl-kappa-fits')]);
    const bytes = await readFile(await download.path());
    assert.deepEqual(fitsAxes(bytes), [256, 256]);
    const [psi] = await Promise.all([page.waitForEvent('download'), page.click('#dl-psi-fits')]);
    assert.deepEqual(fitsAxes(await readFile(await psi.path())), [256, 256]);
    const [dl2] = await Promise.all([page.waitForEvent('download'), page.click('#dl-summary-json')]);
    const summary = JSON.parse(await readFile(await dl2.path(), 'utf8'));
    assert.equal(summary.settings.solver.iterations, QUICK_ITERATIONS);
    // The images as DS9 circles: one per observed image of each system, and the predicted ones.
    const [dl3] = await Promise.all([page.waitForEvent('download'), page.click('#dl-images-reg')]);
    const regions = (await readFile(await dl3.path(), 'utf8')).split('\n');
    const [dl4] = await Promise.all([page.waitForEvent('download'), page.click('#dl-sources-json')]);
    const sources = JSON.parse(await readFile(await dl4.path(), 'utf8'));
    const count = (tag) => regions.filter((l) => l.startsWith('circle(') && l.includes(`tag={${tag}}`)).length;
    assert.equal(regions[0], '# Region file format: DS9 version 4.1');
    assert.equal(count('observed'), sources.reduce((n, s) => n + s.observed.length, 0));
    // (Not the demagnified ones, |μ| < 0.1, as on the map.)
    const shown = (s) => s.predicted.filter((p) => Math.abs(p.magnification) >= 0.1).length;
    assert.equal(count('predicted'), sources.reduce((n, s) => n + shown(s), 0));
    assert.ok(count('observed') >= 60, `${count('observed')} observed images`);

    // Reload: the project comes back from IndexedDB without solving again.
    await page.reload();
    await waitStatus(page, /^Restored/);
    await waitView(page, 'kappa');
    const again = await imageStats(page, '#view-image');
    assert.ok(again.reddish > 50, `after reload only ${again.reddish} red curve pixels`);
    assert.match(await page.textContent('#summary'), /Restored/);
    assert.deepEqual(app.consoleErrors, []);
    assert.deepEqual(app.foreignRequests, []);
  } finally {
    await app.close();
  }
});

/** Opens the teaching example from the menu, with QUICK_ITERATIONS. */
async function openTeaching(page) {
  await waitStatus(page, /^Ready/);
  await page.selectOption('#example-select', { label: 'Teaching example: one halo, four sources' });
  await page.waitForFunction(() => /Teaching/.test(document.getElementById('project-name').textContent));
  await setField(page, '#set-reconstruct-solver-iterations', QUICK_ITERATIONS);
}

test('the teaching example loads from the menu and reconstructs', async () => {
  const app = await openApp();
  try {
    const { page } = app;
    await openTeaching(page);
    // From Reconstruct to the map on screen, the main thread is never blocked for more than
    // 50 ms: the run is in the worker, and so is the rendering.
    const longTasks = await watchLongTasks(page);
    await runToMap(page, '#reconstruct');
    assert.deepEqual(await longTasks(), [], 'main-thread tasks over 50 ms [start, duration]');
    const stats = await imageStats(page, '#view-image');
    assert.ok(stats.reddish > 50, `only ${stats.reddish} red curve pixels`);
    await page.click('#tab-systems');
    await page.waitForSelector('#systems table');
    assert.equal(await page.locator('#systems tbody tr').count(), 4);
    await page.screenshot({ path: join(ARTIFACTS, 'app-teaching.png'), fullPage: true });
    // A click on the map: the source behind the point and all its images, listed and drawn as
    // yellow squares; the clicked point is one of them. z_s moves them; Clear removes them.
    const shown = await renderCount(page);
    await page.click('#tab-kappa');
    await waitView(page, 'kappa', shown);
    const yellow = async () => (await imageStats(page, '#view-image', { rgb: [255, 235, 0], tol: 40 })).near;
    const plain = await yellow();
    const box = await page.$eval('#view-image', (el) => { const r = el.getBoundingClientRect(); return [r.left, r.top, r.width, r.height]; });
    let before = await renderCount(page);
    await page.mouse.click(box[0] + 0.42 * box[2], box[1] + 0.38 * box[3]);
    await waitView(page, 'kappa', before);
    await page.waitForSelector('#counter-images:not([hidden])');
    const listed = await page.textContent('#counter-images-text');
    const m = listed.match(/behind \((-?[\d.]+)″, (-?[\d.]+)″\) lies at β = .*; at z_s = 2 it has (\d+) images?/);
    assert.ok(m, listed);
    const images = [...listed.matchAll(/\((-?[\d.]+), (-?[\d.]+)\) μ/g)].map((g) => [Number(g[1]), Number(g[2])]);
    assert.equal(images.length, Number(m[3]), listed);
    assert.ok(images.some(([x, y]) => Math.hypot(x - Number(m[1]), y - Number(m[2])) < 0.02), listed);
    // Each image with its parity and, when there are several, the first to arrive and the
    // delays of the others.
    assert.equal([...listed.matchAll(/\(parity [+−]\)/g)].length, images.length, listed);
    if (images.length > 1) {
      assert.equal([...listed.matchAll(/arrives first/g)].length, 1, listed);
      assert.equal([...listed.matchAll(/Δt [\d,]+ d/g)].length, images.length - 1, listed);
    }
    assert.ok(await yellow() > plain + 20, 'the images are drawn');
    // The same as DS9 regions: the clicked point and each image with |μ| >= 0.1.
    const bright = [...listed.matchAll(/μ (-?[\d.]+)/g)].filter((g) => Math.abs(Number(g[1])) >= 0.1).length;
    const [reg] = await Promise.all([page.waitForEvent('download'), page.click('#dl-counter-images-reg')]);
    const circles = (await readFile(await reg.path(), 'utf8')).split('\n').filter((l) => l.startsWith('circle('));
    assert.equal(circles.length, 1 + bright, circles.join('\n'));
    assert.ok(circles.every((l) => l.includes('color=yellow')), circles.join('\n'));
    await setField(page, '#z-curves', 3);
    await page.waitForFunction(() => /at z_s = 3 it has/.test(document.getElementById('counter-images-text').textContent));
    const pinned = await yellow();
    before = await renderCount(page);
    await page.click('#clear-pin');
    await waitView(page, 'kappa', before);
    assert.equal(await page.isHidden('#counter-images'), true);
    // The map at z_s = 3 is another map than the one at 2 (its predicted images and curves
    // moved, and their antialiased edges can pass for yellow): compared with itself pinned.
    const cleared = await yellow();
    assert.ok(cleared <= pinned - 20, `no images drawn after Clear: ${cleared} yellow pixels, ${pinned} with the pin, ${plain} at z_s = 2`);
    assert.doesNotMatch(await page.textContent('#summary'), /accelerated gradient/);
    // The solver setting: the best fit's run says so in the caption.
    await setField(page, '#set-reconstruct-solver-method', 'accelerated_gradient');
    assert.equal(await page.$eval('#set-reconstruct-solver-method', (el) => el.selectedOptions[0].textContent), 'best fit');
    await page.click('#reconstruct');
    await waitStatus(page, /^Done in/);
    await page.waitForFunction(() => /accelerated gradient/.test(document.getElementById('summary').textContent));
    // A held-out system is predicted, not fitted: marked in the table, summarised in the caption.
    await setField(page, '#set-reconstruct-solver-method', 'qadp');
    await setField(page, '#set-holdout', '2');
    assert.equal(await page.inputValue('#set-holdout'), '2');
    await page.click('#reconstruct');
    await waitStatus(page, /^Done in/);
    await page.waitForFunction(() => /held-out images: median \d+\.\d\d″, rms \d+\.\d\d″/
      .test(document.getElementById('summary').textContent));
    await page.click('#tab-systems');
    await page.waitForSelector('#systems table');
    assert.equal(await page.textContent('#left-out'), 'Left out of the fit: 2 (held out).');
    const heads = await page.$$eval('#systems tbody th', (ths) => ths.map((th) => th.textContent));
    assert.deepEqual(heads.filter((t) => /held out/.test(t)), ['2 (held out)']);
    await page.screenshot({ path: join(ARTIFACTS, 'app-teaching-holdout.png'), fullPage: true });
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('Cross-validate predicts each system once and keeps the result on screen', async () => {
  const app = await openApp();
  try {
    const { page } = app;
    await openTeaching(page);
    await runToMap(page, '#reconstruct');
    const caption = await page.textContent('#summary');
    // Four systems: one fold each (fewer than five). The worker runs the folds; the page stays free.
    const longTasks = await watchLongTasks(page);
    await page.click('#crossval');
    await waitStatus(page, /^Cross-validated in [\d.]+ s \(4 folds\)\.$/);
    assert.deepEqual(await longTasks(), [], 'main-thread tasks over 50 ms [start, duration]');
    const text = (await page.textContent('#crossval-summary')).replace(/\s+/g, ' ');
    const m = text.match(/Held-out images lie (\d+\.\d\d)″ from their predictions \(median; rms (\d+\.\d\d)″\), the fitted ones (\d+\.\d\d)″/);
    assert.ok(m, text);
    const [median, rms, fitted] = m.slice(1).map(Number);
    assert.ok(median > 0 && rms >= median && fitted >= 0, text);
    await page.click('#crossval-systems summary');
    const folds = await page.$$eval('#crossval-box tbody tr td:nth-child(2)', (tds) => tds.map((td) => td.textContent));
    assert.deepEqual(folds.sort(), ['1', '2', '3', '4']);
    // The reconstruction on screen is the one from before; its verdict now counts the
    // held-out images of the cross-validation (the map's own had none held out).
    assert.equal(await page.textContent('#summary'), caption);
    const offsets = async () => (await page.locator('#verdict-facts li').allTextContents())[0];
    await page.waitForFunction(() => /held out in the cross-validation/.test(document.getElementById('verdict-facts')?.textContent));
    assert.match(await offsets(), new RegExp(`^Image offsets \\(median\\): fitted [\\d.]+″, held out in the cross-validation ${median.toFixed(2)}″$`));
    await page.screenshot({ path: join(ARTIFACTS, 'app-crossval.png'), fullPage: true });
    const [download] = await Promise.all([page.waitForEvent('download'), page.click('#dl-crossval-json')]);
    const cv = JSON.parse(await readFile(await download.path(), 'utf8'));
    assert.equal(cv.folds, 4);
    assert.equal(cv.systems.length, 4);
    assert.equal(cv.holdout_image_offset_median_arcsec.toFixed(2), median.toFixed(2));
    // The spread of the folds' Einstein radii, as the panel gives it.
    const thetas = cv.runs.map((r) => r.einstein_radius_arcsec);
    const spread = text.match(/Across the folds the Einstein radius at z_s = 2 is ([\d.]+)(?: – ([\d.]+))?″/);
    assert.ok(spread, text);
    assert.equal(spread[1], Math.min(...thetas).toFixed(1));
    assert.equal(spread[2] ?? spread[1], Math.max(...thetas).toFixed(1));
    // And their projected mass within 10″ and 20″ (50″ leaves the teaching example's 60″ map).
    for (const [k, r] of [[0, 10], [1, 20]]) {
      const ms = cv.runs.map((run) => run.mass_within_arcsec[k][1]);
      const want = [Math.min(...ms), Math.max(...ms)].map((v) => v.toExponential(2).replace('e+', 'e'));
      assert.ok(text.includes(`within ${r}″ ${want[0] === want[1] ? want[0] : want.join(' – ')} M☉`), text);
    }
    assert.ok(!text.includes('within 50″'), text);
    // The folds' convergence: the spread drawn as a figure (with the red tangential curve),
    // and the mean and spread as FITS maps on the result's pixels.
    const stats = await imageStats(page, '#crossval-spread');
    assert.ok(stats.width > 200 && stats.distinctColours > 50 && stats.reddish > 20, JSON.stringify(stats));
    await page.$eval('details:has(#downloads)', (d) => { d.open = true; });
    const axes = async (id) => {
      const [d] = await Promise.all([page.waitForEvent('download'), page.click(id)]);
      return fitsAxes(await readFile(await d.path()));
    };
    const result = await axes('#dl-kappa-fits');
    assert.deepEqual(await axes('#dl-crossval-kappa-mean-fits'), result);
    assert.deepEqual(await axes('#dl-crossval-kappa-spread-fits'), result);
    // Made with the settings of its time: a change takes it away.
    await setField(page, '#set-reconstruct-solver-iterations', QUICK_ITERATIONS + 100);
    await page.waitForSelector('#crossval-box', { state: 'hidden', timeout: 5000 });
    // ... and the verdict is the result's own again.
    assert.match(await offsets(), /^Image offsets \(median\): fitted [\d.]+″$/);
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('?embed is a compact demo that keeps nothing; ?example= opens an example without replacing a saved project', async () => {
  const app = await openApp({ width: 900, height: 700, query: '?embed&example=teaching' });
  try {
    const { page, url } = app;
    await waitStatus(page, /^Ready/);
    assert.match(await page.textContent('#project-name'), /^Teaching example/);
    // Only the example, Reconstruct and the views; a link to the full app on the same example.
    for (const hidden of ['header', 'footer', '#files-panel', '#settings-panel', '#downloads-panel', '#lookup']) {
      assert.ok(await page.isHidden(hidden), hidden);
    }
    assert.ok(await page.isVisible('#full-app'));
    assert.equal(await page.getAttribute('#full-app', 'href'), './?example=teaching');
    await runToMap(page, '#reconstruct');
    const stats = await imageStats(page, '#view-image');
    assert.ok(stats.reddish > 50, `only ${stats.reddish} red curve pixels`);
    await page.screenshot({ path: join(ARTIFACTS, 'app-embed.png'), fullPage: true });

    // Nothing was saved: the full app opens on its first example, and that one is saved.
    await page.goto(`${url}?app`);
    await waitStatus(page, /^Ready/);
    assert.match(await page.textContent('#project-name'), /^Simulated A1689/);
    assert.ok(await page.isVisible('#files-panel') && await page.isHidden('#full-app'));
    // A link to an example restores the saved project instead, and says where the example is.
    await page.goto(`${url}?example=teaching`);
    await waitStatus(page, /^Restored your project from this browser \(the link's example, "Teaching example: one halo, four sources", is in the Example menu\)\.$/);
    assert.match(await page.textContent('#project-name'), /^Simulated A1689/);
    // An unknown example is named, with the ones there are.
    await page.goto(`${url}?embed&example=nope`);
    await page.waitForFunction(() => /no built-in example "nope" \(there are: a1689-sim, teaching\)/.test(document.getElementById('error').textContent));
    await waitStatus(page, /^Ready/);
    assert.match(await page.textContent('#project-name'), /^Simulated A1689/);
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('the embedded demo shows the map first and fits 900 x 720 and 390 x 844 without scrolling', async () => {
  for (const [width, height] of [[900, 720], [390, 844]]) {
    const app = await openApp({ width, height, query: '?embed&example=teaching' });
    try {
      const { page } = app;
      await waitStatus(page, /^Ready/);
      await runToMap(page, '#reconstruct');
      const size = await page.evaluate(() => ({
        scrollWidth: document.documentElement.scrollWidth,
        scrollHeight: document.documentElement.scrollHeight,
        mapTop: document.getElementById('view-image').getBoundingClientRect().top,
        controlsTop: document.querySelector('.controls').getBoundingClientRect().top,
        mapWidth: document.getElementById('view-image').getBoundingClientRect().width,
      }));
      assert.ok(size.scrollWidth <= width && size.scrollHeight <= height,
        `${width} x ${height}: the page is ${size.scrollWidth} x ${size.scrollHeight}`);
      // The map is the largest thing in the frame: most of the width on a phone, beside the
      // controls on a wide frame (above them on a phone).
      assert.ok(size.mapWidth >= 0.5 * width, `${width} x ${height}: the map is ${size.mapWidth} px wide`);
      if (width < 800) assert.ok(size.mapTop < size.controlsTop, 'on a phone the map comes first');
      // Research controls stay in the full app.
      for (const hidden of ['#show-options', '#project-description', '#run-notes']) {
        assert.ok(await page.isHidden(hidden), `${hidden} shows at ${width} x ${height}`);
      }
      await page.screenshot({ path: join(ARTIFACTS, `app-embed-${width}x${height}.png`) });
      assert.deepEqual(app.consoleErrors, []);
    } finally {
      await app.close();
    }
  }
});

test('the full app explains itself: a plain sentence, what happens here, names a lecturer uses', async () => {
  const app = await openApp({ width: 1280, height: 720, query: '?example=teaching' });
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    assert.match(await page.textContent('header .intro'), /bend the light of galaxies behind them/);
    await page.click('#about-panel summary');
    const about = (await page.textContent('#about-panel')).replace(/\s+/g, ' ');
    assert.match(about, /the iteration count is the regulariser/);
    assert.match(about, /a uniform external shear for the pull of mass beyond the field/);
    assert.match(about, /chosen by holding systems out/);
    assert.equal((await page.textContent('#tab-convergence')).trim(), 'Solver progress');
    // The example's model file is the lens the data were made from.
    assert.equal(await page.textContent('#model-curves-label'), 'true lens');
    await runToMap(page, '#reconstruct');
    // The caption sits next to the map, and the map with its caption is in the first screen.
    const box = await page.evaluate(() => {
      const r = (id) => document.getElementById(id).getBoundingClientRect();
      return { map: r('view-image'), caption: r('summary') };
    });
    assert.ok(box.caption.left >= box.map.right, `the caption starts at x = ${box.caption.left}, the map ends at ${box.map.right}`);
    assert.ok(box.map.bottom <= 720 && box.caption.bottom <= 720, `the map ends at y = ${box.map.bottom}, the caption at ${box.caption.bottom}`);
    await page.screenshot({ path: join(ARTIFACTS, 'app-1280x720.png') });
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('every field of the settings form is a setting of the core', async () => {
  const app = await openApp();
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    // Each field, sent back with the value it shows, is taken (an unknown path or a value of
    // the wrong type would come back as the field's error).
    const ids = await page.$$eval('#settings-form input, #settings-form select', (els) => els.map((el) => el.id));
    assert.ok(ids.length >= 20, `${ids.length} fields`);
    for (const id of ids) {
      await setField(page, `#${id}`, await page.inputValue(`#${id}`));
    }
    assert.deepEqual(await page.$$eval('#settings-form .field-error', (els) => els.map((e) => e.textContent).filter(Boolean)), []);
    // The value each field shows is one the browser's own checks allow too (an input with no
    // step took 1, and the shear prior's default 0.1, which the example leaves empty, read as
    // invalid to them).
    await setField(page, '#set-reconstruct-grid-external_shear_sigma', 0.1);
    assert.deepEqual(await page.$$eval('#settings-form input', (els) => els.filter((el) => !el.checkValidity())
      .map((el) => `${el.id} = ${el.value}: ${el.validationMessage}`)), []);
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('the page fits a phone-width screen', async () => {
  const app = await openApp({ width: 390, height: 844 });
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    await setField(page, '#set-reconstruct-solver-iterations', 200);
    await runToMap(page, '#reconstruct');
    const overflow = await page.evaluate(() => document.documentElement.scrollWidth - window.innerWidth);
    assert.ok(overflow <= 0, `page is ${overflow}px wider than the screen`);
    await page.screenshot({ path: join(ARTIFACTS, 'app-phone.png'), fullPage: true });
    // The systems table is wider than a phone: it scrolls in its own box, whose right edge
    // is shaded while more columns lie beyond it, and the left edge once scrolled.
    await page.click('#tab-systems');
    const box = page.locator('#systems .table-scroll');
    await box.waitFor();
    const [scroll, client] = await box.evaluate((el) => [el.scrollWidth, el.clientWidth]);
    assert.ok(scroll > client, `the table (${scroll}px) fits its box (${client}px)`);
    assert.match(await box.evaluate((el) => getComputedStyle(el).backgroundAttachment), /^local, local, scroll, scroll$/);
    // The table's first rows (the whole box is thousands of pixels tall).
    await box.evaluate((el) => el.scrollIntoView({ block: 'start' }));
    const top = async (name) => {
      const at = await box.boundingBox();
      await page.screenshot({ path: join(ARTIFACTS, name), clip: { ...at, height: 300 } });
    };
    await top('app-phone-systems.png');
    await box.evaluate((el) => { el.scrollLeft = el.scrollWidth; });
    await top('app-phone-systems-scrolled.png');
  } finally {
    await app.close();
  }
});

// The live lensing playground (index.html?playground) in Chromium: dragging a lens changes the
// lensed image and the curves, a shared link reopens a pixel-identical scene, the frame time
// while dragging (printed), the embedded layouts fit without scrolling and a finger drags a
// lens there, the figure download is drawn larger than the screen, Observe's options are
// typed and checked, and no page is wider than the window.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFile } from 'node:fs/promises';
import { join } from 'node:path';
import { openApp, pngSize, waitStatus, ARTIFACTS } from './browser.mjs';

const READY_TIMEOUT_MS = 120_000;

async function ready(page) {
  await page.waitForFunction(() => document.getElementById('playground')?.dataset.ready === '1',
    null, { timeout: READY_TIMEOUT_MS });
}

/** Waits until at least `count` frames of `pixels` a side have been drawn. */
async function framesOf(page, pixels, count) {
  await page.waitForFunction(([n, k]) => window.__playground.stats.frames.filter((f) => f.pixels === n).length >= k,
    [pixels, count], { timeout: READY_TIMEOUT_MS });
}

/** A checksum of the last frame's lensed image and its curves' vertex count and sum. */
async function snapshot(page) {
  return page.evaluate(() => {
    const f = window.__playground.frame;
    let h = 0;
    for (let k = 0; k < f.image.length; k++) h = (h * 31 + f.image[k]) >>> 0;
    let n = 0;
    let s = 0;
    for (const c of f.curves) for (const line of c.tangential.concat(c.radial)) for (const [x, y] of line) { n++; s += x + 2 * y; }
    return { pixels: f.pixels, image: h, curveVertices: n, curveSum: s, canvas: document.getElementById('pg-image').toDataURL() };
  });
}

const median = (v) => { const s = [...v].sort((a, b) => a - b); return s[Math.floor(s.length / 2)]; };

test('dragging a lens moves the arcs and curves; a shared link reopens the same scene', async () => {
  const app = await openApp({ width: 1280, height: 720, query: '?playground' });
  const { page } = app;
  try {
    await ready(page);
    await page.mouse.move(2, 2);
    await page.screenshot({ path: join(ARTIFACTS, 'playground-1280x720.png') });
    const before = await snapshot(page);
    assert.equal(before.pixels, 512);
    // The SIE sits at the centre of the image plane.
    const box = await page.locator('#pg-image').boundingBox();
    const [cx, cy] = [box.x + box.width / 2, box.y + box.height / 2];
    await page.evaluate(() => { window.__playground.stats.frames.length = 0; window.__playground.stats.longestTaskMs = 0; });
    await page.mouse.move(cx, cy);
    await page.mouse.down();
    const t0 = Date.now();
    for (let k = 1; k <= 40; k++) {
      await page.mouse.move(cx + k * 2, cy + k);
      await page.waitForTimeout(16);
    }
    const dragMs = Date.now() - t0;
    await page.mouse.up();
    await page.mouse.move(2, 2);
    await framesOf(page, 512, 1);
    await page.waitForTimeout(300);
    const after = await snapshot(page);
    const stats = await page.evaluate(() => window.__playground.stats);
    const drag = stats.frames.filter((f) => f.pixels === 128);
    const full = stats.frames.filter((f) => f.pixels === 512);
    console.log(`playground drag: ${drag.length} frames of 128^2 in ${dragMs} ms of dragging; ` +
      `round trip median ${median(drag.map((f) => f.roundTripMs)).toFixed(1)} ms, ` +
      `core median ${median(drag.map((f) => f.computeMs)).toFixed(1)} ms`);
    console.log(`playground full frame 512^2: round trip ${full.map((f) => f.roundTripMs.toFixed(0)).join(', ')} ms, ` +
      `core ${full.map((f) => f.computeMs.toFixed(0)).join(', ')} ms; longest main-thread task ${stats.longestTaskMs} ms`);
    assert.ok(drag.length >= 3, `frames were computed while dragging (${drag.length})`);
    assert.notEqual(after.image, before.image, 'the lensed image changed');
    assert.notEqual(after.curveSum, before.curveSum, 'the critical curves moved');
    const moved = await page.evaluate(() => window.__playground.scene.lenses[0]);
    assert.ok(moved.x > 1, `the lens moved right (${moved.x})`);

    // The URL holds the scene: a second page opened on it shows the same pixels.
    const link = page.url();
    assert.match(link, /#s1=/);
    const other = await page.context().browser().newPage({ viewport: { width: 1280, height: 720 } });
    await other.goto(link);
    await ready(other);
    await other.mouse.move(2, 2);
    await other.waitForTimeout(300);
    const reopened = await snapshot(other);
    assert.equal(reopened.image, after.image, 'the same lensed image');
    assert.equal(reopened.curveSum, after.curveSum, 'the same curves');
    assert.equal(reopened.canvas, after.canvas, 'the same canvas, pixel for pixel');
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

for (const [width, height] of [[900, 720], [390, 844]]) {
  test(`the embedded playground fits ${width}x${height} without scrolling`, async () => {
    const app = await openApp({ width, height, query: '?embed&playground' });
    const { page } = app;
    try {
      await ready(page);
      await page.screenshot({ path: join(ARTIFACTS, `playground-embed-${width}x${height}.png`) });
      const size = await page.evaluate(() => ({
        w: document.documentElement.scrollWidth, h: document.documentElement.scrollHeight,
        canvas: document.getElementById('pg-image').getBoundingClientRect().width,
        panel: getComputedStyle(document.getElementById('pg-panel')).display,
      }));
      assert.ok(size.w <= width && size.h <= height, `page ${size.w}x${size.h} scrolls in ${width}x${height}`);
      assert.ok(size.canvas >= Math.min(width, height) * 0.4, `the map is ${size.canvas} px wide`);
      assert.equal(size.panel, 'none', 'no editing panel in the embed');
    } finally {
      await app.close();
    }
  });
}

/** Drags with one finger (Chromium's touch input, as a phone sends it) from `[x0, y0]` by
 * `[dx, dy]` CSS pixels in `steps` moves. */
async function touchDrag(page, [x0, y0], [dx, dy], steps = 20) {
  const cdp = await page.context().newCDPSession(page);
  const at = (x, y) => [{ x, y, radiusX: 4, radiusY: 4, force: 1, id: 1 }];
  await cdp.send('Input.dispatchTouchEvent', { type: 'touchStart', touchPoints: at(x0, y0) });
  for (let k = 1; k <= steps; k++) {
    await cdp.send('Input.dispatchTouchEvent', { type: 'touchMove', touchPoints: at(x0 + dx * k / steps, y0 + dy * k / steps) });
    await page.waitForTimeout(16);
  }
  await cdp.send('Input.dispatchTouchEvent', { type: 'touchEnd', touchPoints: [] });
  await cdp.detach();
}

for (const query of ['?embed&playground', '?embed&lesson=lens-equation']) {
  test(`a finger drags a lens in ${query} at 390x844`, async () => {
    const app = await openApp({ width: 390, height: 844, query, hasTouch: true });
    const { page } = app;
    try {
      await ready(page);
      await page.waitForFunction(() => window.__playground.settled, null, { timeout: READY_TIMEOUT_MS });
      const before = await snapshot(page);
      const lens = await page.evaluate(() => ({ ...window.__playground.scene.lenses[0] }));
      const box = await page.locator('#pg-image').boundingBox();
      const fov = await page.evaluate(() => window.__playground.scene.fov);
      const start = [box.x + (lens.x / fov + 0.5) * box.width, box.y + (0.5 - lens.y / fov) * box.height];
      // The page does not scroll or zoom under the finger: the canvas takes the gesture.
      assert.equal(await page.$eval('#pg-image', (c) => getComputedStyle(c).touchAction), 'none');
      await touchDrag(page, start, [box.width * 0.15, -box.height * 0.1]);
      await page.waitForFunction(() => window.__playground.settled, null, { timeout: READY_TIMEOUT_MS });
      const moved = await page.evaluate(() => window.__playground.scene.lenses[0]);
      assert.ok(moved.x > lens.x + 0.1 * fov && moved.y > lens.y + 0.05 * fov,
        `the lens went from (${lens.x}, ${lens.y}) to (${moved.x}, ${moved.y})`);
      const after = await snapshot(page);
      assert.notEqual(after.image, before.image, 'the lensed image changed');
      assert.notEqual(after.canvas, before.canvas, 'the pixels on screen changed');
      assert.equal(await page.evaluate(() => window.scrollY), 0, 'the page scrolled');
      await page.screenshot({ path: join(ARTIFACTS, `touch-${query.includes('lesson') ? 'lesson' : 'playground'}-390.png`) });
      // A finger cannot hover: a tap away from the handles reads out the ray there.
      await page.touchscreen.tap(box.x + 0.1 * box.width, box.y + 0.9 * box.height);
      await page.waitForFunction(() => /^Ray seen at/.test(document.getElementById('pg-readout').textContent),
        null, { timeout: READY_TIMEOUT_MS });
      assert.deepEqual(app.consoleErrors, []);
    } finally {
      await app.close();
    }
  });
}

test('/playground/ leads to the playground', async () => {
  const app = await openApp({ width: 1280, height: 720, query: 'playground/' });
  try {
    await app.page.waitForURL(/\/\?playground$/);
    await ready(app.page);
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('Download PNG gives both views drawn again at 1024 pixels a side', async () => {
  const app = await openApp({ width: 1280, height: 720, query: '?playground' });
  const { page } = app;
  try {
    await ready(page);
    const shown = await page.$eval('#pg-image', (c) => c.width);
    const [download] = await Promise.all([page.waitForEvent('download'), page.click('#pg-download')]);
    assert.equal(download.suggestedFilename(), 'lensing-playground-1024px.png');
    const [w, h] = pngSize(await readFile(await download.path()));
    console.log(`playground figure: ${w} x ${h} (a view is ${shown} px on screen)`);
    // Two views of 1024 pixels side by side, margins and a caption line.
    assert.ok(w >= 2 * 1024 && w <= 2 * 1024 + 200 && h >= 1024 && h <= 1024 + 200, `${w} x ${h}`);
    assert.ok(w > 4 * shown, `not larger than the screen: ${w} against ${shown}`);
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

/** Sum of the arc pixels Observe reports in the read-out ("system 1 (z = 2): 2 arcs, 311 pixels"). */
const arcPixels = (text) => [...text.matchAll(/(\d+) pixels/g)].reduce((s, m) => s + Number(m[1]), 0);

test('Observe\'s telescope options are typed, checked, and used', async () => {
  const app = await openApp({ width: 1280, height: 720, query: '?playground' });
  const { page } = app;
  const observe = async () => {
    const n = await page.evaluate(() => Number(document.getElementById('playground').dataset.observations ?? 0));
    await page.click('#pg-observe');
    await page.waitForFunction((k) => Number(document.getElementById('playground').dataset.observations ?? 0) > k,
      n, { timeout: READY_TIMEOUT_MS });
    return page.textContent('#pg-readout');
  };
  const type = async (field, value) => {
    await page.fill(`#pg-obs-${field}`, String(value));
    await page.press(`#pg-obs-${field}`, 'Tab');
  };
  try {
    await ready(page);
    const fine = await observe();
    assert.match(fine, /\d+ arcs, \d+ pixels/);
    await page.click('#pg-observe-opts summary');
    assert.match(await page.textContent('#pg-observe-opts summary'), /0\.2″ pixels, 0\.3″ blur, noise 2%, 5σ detection/);
    // Wrong values are said next to their field, and the last good value stays.
    await type('pixel_arcsec', 'abc');
    assert.equal(await page.textContent('#pg-obs-pixel_arcsec-error'), 'pixel size: "abc" is not a number; kept 0.2.');
    assert.equal(await page.inputValue('#pg-obs-pixel_arcsec'), '0.2');
    await type('pixel_arcsec', 0.01);
    assert.match(await page.textContent('#pg-obs-pixel_arcsec-error'), /^pixel size 0\.01 gives 4000 pixels across the 40″ view, more than 1024/);
    await type('threshold_sigma', 60);
    assert.match(await page.textContent('#pg-obs-threshold_sigma-error'), /^detection threshold 60 is above the peak with noise 0\.02: must be below 50; kept 5\.$/);
    await page.screenshot({ path: join(ARTIFACTS, 'observe-options-errors-1280x720.png') });
    // Good values clear the message, show in the heading, and reach the core.
    await type('pixel_arcsec', 0.4);
    assert.equal(await page.textContent('#pg-obs-pixel_arcsec-error'), '');
    await type('threshold_sigma', 10);
    assert.match(await page.textContent('#pg-observe-opts summary'), /0\.4″ pixels, 0\.3″ blur, noise 2%, 10σ detection/);
    const coarse = await observe();
    console.log(`observed at 0.2″, 5σ: ${fine}\nobserved at 0.4″, 10σ: ${coarse}`);
    assert.ok(arcPixels(coarse) < arcPixels(fine) / 2, `${arcPixels(coarse)} arc pixels at 0.4″, ${arcPixels(fine)} at 0.2″`);
    await page.screenshot({ path: join(ARTIFACTS, 'observe-options-1280x720.png') });
    await page.setViewportSize({ width: 390, height: 844 });
    await page.locator('#pg-observe-opts').scrollIntoViewIfNeeded();
    await page.screenshot({ path: join(ARTIFACTS, 'observe-options-390.png') });
    assert.ok(await page.evaluate(() => document.documentElement.scrollWidth <= window.innerWidth));
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

// No page scrolls sideways: the research app (with a result on screen), the playground and a
// lesson, on a laptop and on a phone.
for (const [width, height] of [[1280, 720], [390, 844]]) {
  test(`no page is wider than ${width}x${height}`, async () => {
    for (const query of ['?example=teaching', '?playground', '?lesson=curves-and-caustics']) {
      const app = await openApp({ width, height, query });
      const { page } = app;
      try {
        if (query.includes('example')) await waitStatus(page, /^Ready/);
        else await ready(page);
        await page.waitForTimeout(500);
        const [scroll, inner] = await page.evaluate(() => [document.documentElement.scrollWidth, window.innerWidth]);
        assert.ok(scroll <= inner, `${query} at ${width}x${height}: the page is ${scroll} px wide in ${inner}`);
      } finally {
        await app.close();
      }
    }
  });
}

// The live lensing playground (index.html?playground) in Chromium: dragging a lens changes the
// lensed image and the curves, a shared link reopens a pixel-identical scene, the frame time
// while dragging (printed), and the embedded layouts fit without scrolling.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { openApp, ARTIFACTS } from './browser.mjs';

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

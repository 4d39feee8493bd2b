// End-to-end: the lessons (index.html?lesson=ID, www/lessons/index.json) in Chromium. A first
// visit opens the first lesson; every lesson opens its scene, with Next/Previous and the link
// kept; the mass-sheet lesson's two lenses give the same images and delays 0.7 times apart
// (the physics, computed by the core); presenter mode enlarges the text; embedded lessons fit
// 900 x 720 and 390 x 844 without scrolling.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { readFile } from 'node:fs/promises';
import { openApp, ARTIFACTS, ROOT } from './browser.mjs';

const TIMEOUT_MS = 120_000;
const { lessons } = JSON.parse(await readFile(join(ROOT, 'www', 'lessons', 'index.json'), 'utf8'));
for (const l of lessons) {
  if (l.scene_file) l.scene = JSON.parse(await readFile(join(ROOT, 'www', l.scene_file), 'utf8'));
}

/** Waits until the full (512²) frame on screen is of the scene now in the playground. */
async function fullFrame(page) {
  await page.waitForFunction(() => window.__playground?.settled, null, { timeout: TIMEOUT_MS });
}
const scene = (page) => page.evaluate(() => JSON.parse(JSON.stringify(window.__playground.scene)));

test('a first visit opens the first lesson; each lesson opens its scene and the link follows', async () => {
  const app = await openApp({ width: 1280, height: 720, query: '' });
  const { page } = app;
  try {
    await page.waitForSelector('#pg-lesson');
    assert.match(page.url(), /\?lesson=lens-equation(#|$)/);
    assert.match(await page.textContent('.pg-lesson-count'), /^Lesson 1 of \d+$/);
    assert.equal(await page.getAttribute('.pg-lesson-app', 'href'), './?app');
    // The read-out the lessons ask to look at sits right under the planes, on the first
    // screen, not below the lesson's text.
    const [canvas, readout] = await Promise.all(['#pg-image', '#pg-readout'].map((s) => page.locator(s).boundingBox()));
    assert.ok(readout.y > canvas.y + canvas.height && readout.y < 720 - 40 && readout.x < canvas.x + canvas.width,
      `read-out at ${JSON.stringify(readout)}, image plane at ${JSON.stringify(canvas)}`);
    for (let k = 0; k < lessons.length; k++) {
      const lesson = lessons[k];
      await page.waitForFunction((t) => document.querySelector('.pg-lesson-title')?.textContent === t, lesson.title);
      await fullFrame(page);
      const want = lesson.scenes ? lesson.scenes[0].scene : lesson.scene;
      assert.deepEqual((await scene(page)).lenses, want.lenses, lesson.id);
      assert.equal(await page.$eval('#pg-curves', (el) => el.checked), lesson.show.curves, lesson.id);
      assert.match(page.url(), new RegExp(`\\?lesson=${lesson.id}#s1=`));
      await page.screenshot({ path: join(ARTIFACTS, `lesson-${k + 1}-${lesson.id}.png`) });
      if (k + 1 < lessons.length) {
        await page.click('#pg-lesson-next');
        await fullFrame(page);
      }
    }
    assert.ok(await page.isDisabled('#pg-lesson-next'));
    // Back goes to the lesson before.
    await page.goBack();
    await page.waitForFunction((t) => document.querySelector('.pg-lesson-title')?.textContent === t, lessons.at(-2).title);
    // Presenter mode: larger text, the editing controls step back.
    const size = () => page.$eval('.pg-lesson p', (el) => parseFloat(getComputedStyle(el).fontSize));
    const normal = await size();
    await page.click('#pg-present');
    assert.ok(await size() >= 1.4 * normal, `presenter text ${await size()} px vs ${normal} px`);
    assert.ok(await page.isHidden('.pg-palette'));
    await page.screenshot({ path: join(ARTIFACTS, 'lesson-presenter.png') });
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('the mass-sheet lesson: lens B keeps lens A\'s images, and its delays are 0.7 times A\'s', async () => {
  const app = await openApp({ width: 1280, height: 720, query: '?lesson=mass-sheet' });
  const { page } = app;
  try {
    await page.waitForSelector('#pg-lesson-scene-1');
    await fullFrame(page);
    const look = () => page.evaluate(() => {
      const f = window.__playground.frame;
      return { image: Array.from(f.image), points: f.points.map((p) => p.images) };
    });
    const a = await look();
    await page.click('#pg-lesson-scene-1');
    await fullFrame(page);
    const b = await look();
    assert.equal((await scene(page)).lenses.length, 2, 'lens B has the sheet');
    // The lensed image: the same pixels (within rounding) though the lens and source differ.
    let differ = 0;
    for (let k = 0; k < a.image.length; k++) if (Math.abs(a.image[k] - b.image[k]) > 3) differ++;
    assert.ok(differ < 0.002 * a.image.length, `${differ} of ${a.image.length} image channels differ`);
    // The point source's images: same places; delays scaled by λ = 0.7.
    const [ia, ib] = [a.points[0], b.points[0]];
    assert.equal(ia.length, ib.length);
    assert.ok(ia.length >= 2, `${ia.length} images`);
    for (const p of ia) {
      const q = ib.reduce((best, c) => (Math.hypot(c.x - p.x, c.y - p.y) < Math.hypot(best.x - p.x, best.y - p.y) ? c : best));
      assert.ok(Math.hypot(q.x - p.x, q.y - p.y) < 0.01, `image (${p.x}, ${p.y}) moved to (${q.x}, ${q.y})`);
      if (p.delay_days > 1) assert.ok(Math.abs(q.delay_days / p.delay_days - 0.7) < 0.01, `delay ${p.delay_days} d became ${q.delay_days} d`);
    }
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('on a phone the lesson comes before the planes; on a wide screen it stays beside them', async () => {
  for (const [width, height] of [[390, 844], [1280, 720]]) {
    const app = await openApp({ width, height, query: '?lesson=curves-and-caustics' });
    const { page } = app;
    try {
      await page.waitForSelector('#pg-lesson');
      await fullFrame(page);
      const [title, canvas] = await Promise.all(['.pg-lesson-title', '#pg-image'].map((s) => page.locator(s).boundingBox()));
      if (width < 900) {
        assert.ok(title.y + title.height < canvas.y, `${width}: title at ${title.y}, image plane at ${canvas.y}`);
      } else {
        assert.ok(title.x > canvas.x + canvas.width, `${width}: title at x ${title.x}, image plane ends at ${canvas.x + canvas.width}`);
      }
      await page.screenshot({ path: join(ARTIFACTS, `lesson-placement-${width}x${height}.png`) });
      assert.deepEqual(app.consoleErrors, []);
    } finally {
      await app.close();
    }
  }
});

test('an embedded lesson fits 900 x 720 and 390 x 844 without scrolling, read-out included', async () => {
  for (const [width, height] of [[900, 720], [390, 844]]) {
    const app = await openApp({ width, height, query: '?embed&lesson=curves-and-caustics' });
    const { page } = app;
    try {
      await page.waitForSelector('#pg-lesson');
      await fullFrame(page);
      const size = await page.evaluate(() => [document.documentElement.scrollWidth, document.documentElement.scrollHeight]);
      assert.ok(size[0] <= width && size[1] <= height, `${width} x ${height}: the page is ${size.join(' x ')}`);
      assert.ok(await page.isHidden('#pg-panel'), 'no research controls');
      // What a hover says (the lessons ask to read it) is under the planes, inside the page.
      const box = await page.locator('#pg-source').boundingBox();
      await page.mouse.move(box.x + box.width * 0.52, box.y + box.height * 0.49);
      await page.waitForFunction(() => /images? of a point/.test(document.getElementById('pg-readout').textContent));
      const readout = await page.locator('#pg-readout').boundingBox();
      assert.ok(readout.y >= box.y + box.height && readout.y + readout.height <= height,
        `${width} x ${height}: read-out at ${readout.y} - ${readout.y + readout.height}`);
      await page.screenshot({ path: join(ARTIFACTS, `lesson-embed-${width}x${height}.png`) });
      assert.deepEqual(app.consoleErrors, []);
    } finally {
      await app.close();
    }
  }
});

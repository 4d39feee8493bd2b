// Full-frame (512²) times of the playground after releasing a dragged lens and a dragged
// source, R rounds each, in headless Chromium (BENCHMARKS.md, "Playground frame times").
// node benches/playground-release.mjs [R] [QUERY]   (defaults 5, ?playground&simd=baseline)
import { openApp } from '../tests/e2e/browser.mjs';
const R = Number(process.argv[2] ?? 5);
const query = process.argv[3] ?? '?playground&simd=baseline';
const app = await openApp({ width: 1280, height: 720, query });
const { page } = app;
const median = (v) => { const s = [...v].sort((a, b) => a - b); return s[Math.floor(s.length / 2)]; };
await page.waitForFunction(() => document.getElementById('playground')?.dataset.ready === '1', null, { timeout: 300000 });
await page.waitForTimeout(1000);
async function dragAndRelease(canvasId, sx, sy, side, dx, dy) {
  const box = await page.locator(canvasId).boundingBox();
  const [px, py] = [box.x + (sx / side + 0.5) * box.width, box.y + (0.5 - sy / side) * box.height];
  await page.evaluate(() => { window.__playground.stats.frames.length = 0; });
  await page.mouse.move(px, py);
  await page.mouse.down();
  for (let k = 1; k <= 10; k++) { await page.mouse.move(px + k * dx, py + k * dy); await page.waitForTimeout(16); }
  await page.mouse.up();
  await page.mouse.move(2, 2);
  await page.waitForFunction(() => window.__playground.stats.frames.some((f) => f.pixels === 512), null, { timeout: 60000 });
  await page.waitForTimeout(200);
  const st = await page.evaluate(() => window.__playground.stats);
  return st.frames.filter((f) => f.pixels === 512).at(-1);
}
const lens = [], source = [];
await page.evaluate(() => { window.__playground.stats.longestTaskMs = 0; });
for (let r = 0; r < R; r++) {
  const sc = await page.evaluate(() => window.__playground.scene);
  const dir = r % 2 ? -1 : 1;
  lens.push(await dragAndRelease('#pg-image', sc.lenses[0].x, sc.lenses[0].y, sc.fov, 2 * dir, dir));
  const s = sc.sources[0];
  source.push(await dragAndRelease('#pg-source', s.x, s.y, sc.source_fov ?? sc.fov / 2, dir, 0));
}
const longest = await page.evaluate(() => window.__playground.stats.longestTaskMs);
const fmt = (a, key) => `${median(a.map((f) => f[key])).toFixed(0)} [${a.map((f) => f[key].toFixed(0)).join(' ')}]`;
console.log(`lens released: round trip ${fmt(lens, 'roundTripMs')} ms, core ${fmt(lens, 'computeMs')} ms`);
console.log(`source released: round trip ${fmt(source, 'roundTripMs')} ms, core ${fmt(source, 'computeMs')} ms`);
console.log(`longest main-thread task ${longest} ms`);
await app.close();

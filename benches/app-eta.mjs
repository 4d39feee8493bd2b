// How true the app's "about N s left" is during an "auto" reconstruction of the AS1063 gold
// catalogues (images and members, z_lens 0.348, the app's defaults otherwise): the progress
// line is read every 2 s and, once the run is done, each reading is set against the time that
// was really left. Prints the readings and the median and worst relative error over the
// readings taken between 10% and 90% of the run. BENCHMARKS.md records the figures.
//
//   npm run build && node benches/app-eta.mjs
//
// Needs www/pkg (npm run build), ../shared/data/AS1063 and /usr/bin/chromium (or CHROMIUM).
import { join } from 'node:path';
import { openApp, ROOT, setField, waitStatus } from '../tests/e2e/browser.mjs';

const AS1063 = join(ROOT, '..', 'shared', 'data', 'AS1063', 'lenstool_cats');
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

const app = await openApp();
try {
  const { page } = app;
  await waitStatus(page, /^Ready/);
  await page.setInputFiles('#file-images', join(AS1063, 'cats_gold_mul_gold.cat'));
  await page.waitForFunction(() => /19 systems/.test(document.getElementById('status-images').textContent));
  await page.setInputFiles('#file-members', join(AS1063, 'cats_gold_ref_potential_w_clumpNE.cat'));
  await page.waitForFunction(() => /members/.test(document.getElementById('status-members').textContent));
  await setField(page, '#set-z_lens', 0.348);
  const t0 = Date.now();
  await page.click('#reconstruct');
  const readings = [];
  while (!/^Done in/.test(await page.textContent('#status'))) {
    const said = (await page.textContent('#progress-text')).match(/about (\d+) s left/);
    if (said) readings.push([(Date.now() - t0) / 1000, Number(said[1])]);
    await sleep(2000);
  }
  const total = (Date.now() - t0) / 1000;
  const rows = readings.map(([t, said]) => ({ t, said, left: total - t, error: said / (total - t) - 1 }));
  for (const r of rows) console.log(`${r.t.toFixed(0)} s: said ${r.said} s left, ${r.left.toFixed(0)} s were`);
  const mid = rows.filter((r) => r.t > 0.1 * total && r.t < 0.9 * total).map((r) => r.error);
  mid.sort((a, b) => Math.abs(a) - Math.abs(b));
  const pct = (e) => `${e >= 0 ? '+' : ''}${(100 * e).toFixed(0)}%`;
  console.log(`done in ${total.toFixed(0)} s; between 10% and 90% of the run the time left read `
    + `${pct(mid[Math.floor(mid.length / 2)])} (median |error|), worst ${pct(mid.at(-1))}`);
} finally {
  await app.close();
}

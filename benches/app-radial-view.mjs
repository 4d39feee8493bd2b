// The radial-profile view of the built-in example after a short reconstruction (600
// iterations): the time from clicking its tab to the image on screen, three times. The first
// also computes the true model's profile (model.json, drawn dashed next to the result); later
// ones reuse it. BENCHMARKS.md records the figures.
//
//   npm run build && node benches/app-radial-view.mjs
//
// Needs www/pkg (npm run build) and /usr/bin/chromium (or CHROMIUM).
import { openApp, setField, waitStatus } from '../tests/e2e/browser.mjs';

const app = await openApp();
try {
  const { page } = app;
  await waitStatus(page, /^Ready/);
  await setField(page, '#set-reconstruct-solver-iterations', 600);
  await page.click('#reconstruct');
  await waitStatus(page, /^Done in/, 120_000);
  await page.waitForFunction(() => document.getElementById('view-image').dataset.view === 'kappa');
  for (let k = 0; k < 3; k++) {
    const t0 = performance.now();
    await page.click('#tab-radial');
    await page.waitForFunction(() => {
      const el = document.getElementById('view-image');
      return el.dataset.view === 'radial' && el.complete;
    });
    const ms = performance.now() - t0;
    await page.click('#tab-convergence');
    await page.waitForFunction(() => document.getElementById('view-image').dataset.view === 'convergence');
    console.log(`radial view, ${k === 0 ? 'first (with the model profile)' : 'again'}: ${ms.toFixed(0)} ms`);
  }
} finally {
  await app.close();
}

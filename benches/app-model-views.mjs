// What comparing with the loaded model costs in the browser: the built-in example after a
// short reconstruction (600 iterations), from "Done" to the mass map on screen, with the true
// model's critical curves drawn ("Show: model curves") and without them; turning them on over a
// result; then the radial-profile view (the model's profile comes from the same maps) and the
// mass map again. The worker computes the model's maps once per field and keeps them for the
// next run, so the first time the curves are shown (round 1, "turning them on") carries that
// cost and the rest do not. Three rounds. BENCHMARKS.md records the figures.
//
//   npm run build && node benches/app-model-views.mjs
//
// Needs www/pkg (npm run build) and /usr/bin/chromium (or CHROMIUM).
import { openApp, renderCount, setField, waitStatus, waitView } from '../tests/e2e/browser.mjs';

const app = await openApp();
try {
  const { page } = app;
  await waitStatus(page, /^Ready/);
  await setField(page, '#set-reconstruct-solver-iterations', 600);
  // `shown` waits for the next drawing of `view` after the render count `after` and returns the
  // milliseconds since `start`.
  const count = () => renderCount(page);
  const shown = async (view, after, start) => {
    await waitView(page, view, after, 120_000);
    return performance.now() - start;
  };
  const click = async (selector, view) => {
    const n = await count();
    const t = performance.now();
    await page.click(selector);
    return shown(view, n, t);
  };
  // From the run's "Done" to the mass map (the render queued after the run).
  const afterRun = async () => {
    await page.click('#reconstruct');
    await waitStatus(page, /^Reconstructing/, 10_000);
    const n = await count();
    await waitStatus(page, /^Done in/, 120_000);
    return shown('kappa', n, performance.now());
  };
  for (let k = 0; k < 3; k++) {
    await page.uncheck('#show-model-curves');
    const without = await afterRun();
    const turnedOn = await click('#show-model-curves', 'kappa');
    const withCurves = await afterRun();
    const radial = await click('#tab-radial', 'radial');
    const again = await click('#tab-kappa', 'kappa');
    console.log(`round ${k + 1}: mass map after the run without model curves ${without.toFixed(0)} ms, ` +
      `with them ${withCurves.toFixed(0)} ms; turning them on over a result ${turnedOn.toFixed(0)} ms; ` +
      `then the radial view ${radial.toFixed(0)} ms and the mass map again ${again.toFixed(0)} ms`);
  }
} finally {
  await app.close();
}

// End-to-end: the page loads, the worker answers, the kappa map with critical curves appears.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { writeFile, mkdtemp } from 'node:fs/promises';
import { tmpdir } from 'node:os';
import { openApp, imageStats, ARTIFACTS } from './browser.mjs';

test('the built-in example renders a kappa map with critical curves', async () => {
  const app = await openApp();
  try {
    const { page } = app;
    await page.waitForSelector('#kappa-map:not([hidden])', { timeout: 60_000 });
    await page.waitForFunction(() => document.getElementById('status').textContent.startsWith('Done'));
    const stats = await imageStats(page, '#kappa-map');
    assert.ok(stats.width >= 400 && stats.height >= 400, `figure is ${stats.width}x${stats.height}`);
    // A colour-mapped field has many colours; a blank or flat image has a handful.
    assert.ok(stats.distinctColours > 200, `only ${stats.distinctColours} distinct colours`);
    // Tangential critical curves are drawn in red.
    assert.ok(stats.reddish > 50, `only ${stats.reddish} red curve pixels`);
    const summary = await page.textContent('#summary');
    assert.match(summary, /Einstein radius \d+\.\d″/);
    assert.equal(await page.isHidden('#error'), true);
    await page.screenshot({ path: join(ARTIFACTS, 'app-example.png'), fullPage: true });
    assert.deepEqual(app.consoleErrors, []);
    assert.deepEqual(app.foreignRequests, []);
  } finally {
    await app.close();
  }
});

test('a malformed model file shows its error and keeps the current map', async () => {
  const app = await openApp();
  try {
    const { page } = app;
    await page.waitForSelector('#kappa-map:not([hidden])', { timeout: 60_000 });
    const before = await page.getAttribute('#kappa-map', 'src');
    const dir = await mkdtemp(join(tmpdir(), 'wslap-e2e-'));
    const bad = join(dir, 'bad-model.json');
    await writeFile(bad, '{\n  "z_lens": 0.3,\n  "components": [\n    {"type": "sis", "x": 0, "y": 0, "sigma_v": -5}\n  ]\n}\n');
    await page.setInputFiles('#model-file', bad);
    await page.waitForSelector('#model-file-status.bad');
    const message = await page.textContent('#model-file-status');
    assert.match(message, /bad-model\.json/);
    assert.match(message, /sigma_v/);
    assert.equal(await page.getAttribute('#kappa-map', 'src'), before);
    await page.screenshot({ path: join(ARTIFACTS, 'app-bad-file.png'), fullPage: true });
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('the page fits a phone-width screen', async () => {
  const app = await openApp({ width: 390, height: 844 });
  try {
    const { page } = app;
    await page.waitForSelector('#kappa-map:not([hidden])', { timeout: 60_000 });
    const overflow = await page.evaluate(() => document.documentElement.scrollWidth - window.innerWidth);
    assert.ok(overflow <= 0, `page is ${overflow}px wider than the screen`);
    await page.screenshot({ path: join(ARTIFACTS, 'app-phone.png'), fullPage: true });
  } finally {
    await app.close();
  }
});

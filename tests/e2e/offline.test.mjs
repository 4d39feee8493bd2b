// End-to-end: once loaded, the app works with its server gone (www/sw.js): a reload shows the
// kept project and a reconstruction runs.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readdir, readFile } from 'node:fs/promises';
import { join, relative } from 'node:path';
import { openApp, runToMap, ROOT, ARTIFACTS, setField, waitStatus } from './browser.mjs';

/** Every file of www/ outside examples/ (those are cached from examples/index.json). */
async function appFiles(dir = join(ROOT, 'www')) {
  const files = [];
  for (const entry of await readdir(dir, { withFileTypes: true })) {
    const path = join(dir, entry.name);
    if (entry.isDirectory()) {
      if (entry.name !== 'examples') files.push(...await appFiles(path));
    } else {
      files.push(relative(join(ROOT, 'www'), path));
    }
  }
  return files;
}

test('after one visit the app reloads and reconstructs with the server gone', async () => {
  const app = await openApp();
  try {
    const { page, url } = app;
    await waitStatus(page, /^Ready/);
    await page.selectOption('#example-select', { label: 'Teaching example: one halo, four sources' });
    await page.waitForFunction(() => /Teaching/.test(document.getElementById('project-name').textContent));
    await setField(page, '#set-reconstruct-solver-iterations', 300);
    // The service worker has cached every file the app has but sw.js and the build of the core
    // this browser does not run (Chromium has relaxed SIMD).
    assert.match(await page.textContent('#core-info'), /relaxed SIMD/);
    const unused = 'pkg/wslap_bg.wasm';
    const cached = await page.evaluate(async () => {
      await Promise.race([navigator.serviceWorker.ready, new Promise((_, reject) =>
        setTimeout(() => reject(new Error('no service worker became active in 30 s')), 30_000))]);
      const keys = await (await caches.open('wslap-app')).keys();
      return keys.map((r) => r.url);
    });
    for (const file of await appFiles()) {
      if (file === 'sw.js' || file === unused) continue;
      assert.ok(cached.includes(url + file), `${file} is not cached for offline use`);
    }
    assert.ok(!cached.includes(url + unused), `${unused} was downloaded, though this browser does not run it`);
    const { examples } = JSON.parse(await readFile(join(ROOT, 'www/examples/index.json'), 'utf8'));
    for (const file of examples.flatMap((e) => e.files.map((f) => `examples/${f.path}`))) {
      assert.ok(cached.includes(url + file), `${file} is not cached for offline use`);
    }

    await app.stopServer();
    await page.reload();
    await waitStatus(page, /^Restored your project/);
    assert.match(await page.textContent('#project-name'), /Teaching/);
    // The example menu shows the restored example, not the first one.
    assert.equal(await page.$eval('#example-select', (s) => s.selectedOptions[0]?.textContent),
      'Teaching example: one halo, four sources');
    assert.match(await page.textContent('#core-info'), /^Core: wslap/);
    await runToMap(page, '#reconstruct');
    await page.screenshot({ path: join(ARTIFACTS, 'app-offline.png'), fullPage: true });
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

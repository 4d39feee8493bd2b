// End-to-end: nothing kept in the browser is lost (issue #25). A saved project that is corrupt
// or was saved by a newer version is set aside with a message, a download and a delete, and
// the app opens cleanly; a last copy that does not open falls back to the copy saved before
// it; a save that is not a whole project never replaces the good copy.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFile } from 'node:fs/promises';
import { idb, openApp, phoneShot, runToMap, savedProject, setField, waitStatus } from './browser.mjs';

/** The project text the app saved, once it matches `pattern`. */
async function savedText(page, pattern = /wslap-project/) {
  await waitStatus(page, /^Ready/);
  return savedProject(page, pattern);
}

test('a corrupt and a too-new saved project are set aside, downloadable, and the app opens', async () => {
  const app = await openApp();
  try {
    const { page } = app;
    const good = await savedText(page);
    const tooNew = good.replace('"version": 1', '"version": 99');
    assert.notEqual(tooNew, good);
    // A save cut short by a crash, and a project of a future version as the fallback.
    const corrupt = good.slice(0, Math.floor(good.length / 2));
    await idb(page, 'put', 'current', corrupt);
    await idb(page, 'put', 'previous', tooNew);
    await page.reload();
    await page.waitForSelector('#set-aside:not([hidden])');
    await waitStatus(page, /^Your saved project did not open; it is kept \(see below\)\. Opened the example/);
    const entries = await page.locator('.set-aside-entry p').allTextContents();
    assert.equal(entries.length, 2, entries.join(' | '));
    assert.ok(entries.every((t) => t.startsWith('A project saved in this browser could not be opened')), entries.join(' | '));
    assert.ok(entries.every((t) => /It was set aside, not deleted/.test(t)), entries.join(' | '));
    const cut = entries.findIndex((t) => /: it was cut short while it was saved: line \d+, column \d+: ends too early, /.test(t));
    const newer = entries.findIndex((t) => /saved by a newer version of wslap \(project format version 99; this version reads version 1\)/.test(t));
    assert.ok(cut >= 0 && newer >= 0, entries.join(' | '));
    // Neither is sent to the page as a debug dump.
    assert.ok(entries.every((t) => !/Error\(|\{"|undefined/.test(t)), entries.join(' | '));
    await page.screenshot({ path: 'test-artifacts/app-set-aside.png' });
    // The download is the copy as it was kept.
    const [download] = await Promise.all([
      page.waitForEvent('download'),
      page.locator('.set-aside-entry').nth(newer).getByRole('button', { name: 'Download it' }).click(),
    ]);
    assert.match(download.suggestedFilename(), /^wslap-project-set-aside-.*\.json$/);
    assert.equal(await readFile(await download.path(), 'utf8'), tooNew);
    // Deleting one leaves the other; the app works meanwhile and after a reload.
    await page.locator('.set-aside-entry').nth(cut).getByRole('button', { name: 'Delete it' }).click();
    await page.waitForFunction(() => document.querySelectorAll('.set-aside-entry').length === 1);
    assert.match(await page.textContent('.set-aside-entry p'), /version 99/);
    await page.selectOption('#example-select', { label: 'Teaching example: one halo, four sources' });
    await waitStatus(page, /^Ready: press Reconstruct\.$/);
    await setField(page, '#set-reconstruct-solver-iterations', 400);
    await runToMap(page, '#reconstruct');
    await page.reload();
    await waitStatus(page, /^Restored your project from this browser\.$/);
    assert.match(await page.textContent('#project-name'), /Teaching/);
    assert.equal(await page.locator('.set-aside-entry').count(), 1);
    await page.getByRole('button', { name: 'Delete it' }).click();
    await page.waitForSelector('#set-aside[hidden]', { state: 'attached' });
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('a last copy that does not open falls back to the one before; a cut save never replaces it', async () => {
  const app = await openApp();
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    await page.selectOption('#example-select', { label: 'Teaching example: one halo, four sources' });
    await page.waitForFunction(() => /Teaching/.test(document.getElementById('project-name').textContent));
    const good = await savedText(page, /"name": "Teaching/);
    // A save that is not a whole project (a crash mid-way) is refused; the good copy stays.
    const refused = await page.evaluate(async (text) => (await import('./js/store.js')).saveProject(text),
      good.slice(0, 100));
    assert.match(refused, /^did not keep the project in this browser: it is not whole \(it ends before its closing brace\); the copy saved before is kept$/);
    assert.equal(await idb(page, 'get', 'current'), good);
    // Each save keeps the copy before it, so a bad last copy falls back to it.
    await setField(page, '#set-reconstruct-solver-iterations', 300);
    await savedText(page, /"iterations": 300/);
    assert.equal(await idb(page, 'get', 'previous'), good);
    // A whole project whose catalogue does not read.
    await idb(page, 'put', 'current', JSON.stringify({ format: 'wslap-project', version: 1, data: { images: { name: 'images.cat', text: '1.1 x 3 0.5 0.5 0 2 25\n' } } }));
    await page.reload();
    await waitStatus(page, /^Restored the copy of your project saved before the last one, which did not open/);
    assert.match(await page.textContent('#project-name'), /Teaching/);
    assert.equal(await page.locator('.set-aside-entry').count(), 1);
    assert.match(await page.textContent('.set-aside-entry p'), /images\.cat: line 1/);
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('a reload during a run says the run stopped, once', async () => {
  const app = await openApp();
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    await page.selectOption('#example-select', { label: 'Teaching example: one halo, four sources' });
    await page.waitForFunction(() => /Teaching/.test(document.getElementById('project-name').textContent));
    await waitStatus(page, /^Ready: press Reconstruct\.$/);
    await setField(page, '#set-reconstruct-solver-iterations', 1000000);
    await page.click('#reconstruct');
    await page.waitForSelector('#progress-box:not([hidden])');
    await page.reload();
    await waitStatus(page, /^Restored your project from this browser\. The page was reloaded during a reconstruction, which stopped unfinished: start it again when you like\.$/);
    assert.ok(await page.isEnabled('#reconstruct'));
    assert.ok(await page.isHidden('#progress-box'));
    assert.equal(await page.inputValue('#set-reconstruct-solver-iterations'), '1000000');
    await page.screenshot({ path: 'test-artifacts/app-reload-mid-run.png' });
    await phoneShot(page, page.locator('#status'), 'app-reload-mid-run-phone.png');
    // Said once: the next reload has nothing to say about it.
    await page.reload();
    await waitStatus(page, /^Restored your project from this browser\.$/);
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

// End-to-end: the app's own failures found by using it as a new user would (issue #25): a
// rejected file says which file is still in use, where the user looks and in the caption; a
// result, clicked point and status never outlive the data they belong to; New project starts
// over and can be undone, as can an example picked over your own files; a file with many
// warnings quotes a few and folds the rest.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFile } from 'node:fs/promises';
import { join } from 'node:path';
import { openApp, phoneShot, runToMap, setField, waitStatus, ROOT, ARTIFACTS } from './browser.mjs';

const MEMBERS = join(ROOT, 'www', 'examples', 'a1689-sim', 'members.cat');

/** Opens the teaching example with a quick iteration count. */
async function teaching(page) {
  await page.selectOption('#example-select', { label: 'Teaching example: one halo, four sources' });
  await page.waitForFunction(() => /Teaching/.test(document.getElementById('project-name').textContent));
  await waitStatus(page, /^Ready: press Reconstruct\.$/);
  await setField(page, '#set-reconstruct-solver-iterations', 400);
}

test('a rejected file keeps the one before, and says so at the top and in the caption', async () => {
  const app = await openApp();
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    await teaching(page);
    await page.setInputFiles('#file-images', { name: 'bad.cat', mimeType: 'text/plain', buffer: Buffer.from('#REFERENCE 0\n1 not-a-number 2 0.5 0.5 0 2.0 25\n') });
    await page.waitForSelector('#error:not([hidden])');
    const error = await page.textContent('#error');
    assert.match(error, /^bad\.cat was not loaded: line 2/);
    // The example's images.cat is kept, but the user never loaded it: the example is named.
    assert.match(error, /The example "Teaching example: one halo, four sources" stays open as it was\.$/);
    assert.match(await page.textContent('#status'), /^bad\.cat was not loaded/);
    assert.match(await page.textContent('#status-images'), /The example "Teaching example: one halo, four sources" stays open as it was\./);
    assert.equal(await page.textContent('#project-name'), 'Teaching example: one halo, four sources');
    await runToMap(page, '#reconstruct');
    assert.match(await page.textContent('#summary'), /Made with images\.cat: bad\.cat had errors and was not loaded\./);
    // A refused model keeps the example's model.json, until one's own data replace the
    // example (and its model): the caption then has nothing to say about either.
    await page.setInputFiles('#file-model', { name: 'garbage.json', mimeType: 'application/json', buffer: Buffer.from('{ nope') });
    await waitStatus(page, /^garbage\.json was not loaded/);
    // Your own data with a result on screen: a refused file, then a good one. The status line
    // speaks of the good one, not of the refusal.
    const good = join(ROOT, 'www', 'examples', 'teaching', 'images.cat');
    await page.setInputFiles('#file-images', good);
    await waitStatus(page, /^Ready: press Reconstruct\.$/);
    await runToMap(page, '#reconstruct');
    assert.doesNotMatch(await page.textContent('#summary'), /Made with|had errors/);
    await page.setInputFiles('#file-images', { name: 'bad.cat', mimeType: 'text/plain', buffer: Buffer.from('#REFERENCE 0\n1 x 2 0.5 0.5 0 2.0 25\n') });
    await waitStatus(page, /^bad\.cat was not loaded/);
    assert.match(await page.textContent('#error'), /Still using images\.cat loaded before\.$/);
    await page.setInputFiles('#file-images', good);
    await waitStatus(page, /^Loaded images\.cat: .*; the map shown was made before it\.$/);
    assert.ok(await page.isHidden('#error'));
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('a member catalogue picked as the image catalogue is named as one, and the example stays', async () => {
  const app = await openApp();
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    await teaching(page);
    await page.setInputFiles('#file-images', MEMBERS);
    await page.waitForSelector('#error:not([hidden])');
    const error = await page.textContent('#error');
    assert.match(error, /^members\.cat was not loaded: column 7 \(z\) holds [\d.]+ to [\d.]+ on \d+ rows \(line \d+: [\d.]+\), which read as magnitudes, not source redshifts: this looks like a member catalogue \(id x y a b theta mag lum\), not an image catalogue/);
    assert.match(error, /The example "Teaching example: one halo, four sources" stays open as it was\.$/);
    assert.match(await page.textContent('#status-images'), /looks like a member catalogue/);
    await page.locator('#error').screenshot({ path: join(ARTIFACTS, 'error-members-as-images.png') });
    await page.setViewportSize({ width: 390, height: 844 });
    assert.equal(await page.evaluate(() => document.documentElement.scrollWidth), 390);
    await page.locator('#error').screenshot({ path: join(ARTIFACTS, 'error-members-as-images-390.png') });
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('a result, a clicked point and the status never outlive their data', async () => {
  const app = await openApp();
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    await teaching(page);
    await runToMap(page, '#reconstruct');
    // A click lists the clicked point's images; another example forgets them.
    const box = await page.$eval('#view-image', (el) => { const r = el.getBoundingClientRect(); return [r.left, r.top, r.width, r.height]; });
    await page.mouse.click(box[0] + 0.42 * box[2], box[1] + 0.38 * box[3]);
    await page.waitForSelector('#counter-images:not([hidden])');
    await page.selectOption('#example-select', { label: 'Simulated A1689-like cluster (the WSLAP+ paper\'s test)' });
    await page.waitForFunction(() => /A1689/.test(document.getElementById('project-name').textContent));
    await waitStatus(page, /^Ready: press Reconstruct\.$/);
    assert.ok(await page.isHidden('#counter-images'), 'the clicked point of the other example is still listed');
    assert.equal(await page.textContent('#readout'), '');
    // Run the example, then replace it with a member catalogue alone: the example's result
    // (its arcs and members on the map) goes, and the status says what can be done now.
    await setField(page, '#set-reconstruct-solver-iterations', 300);
    await runToMap(page, '#reconstruct', 180_000);
    await page.setInputFiles('#file-members', MEMBERS);
    await page.waitForFunction(() => document.getElementById('project-name').textContent === 'Your data');
    await waitStatus(page, /^Load an image catalogue or arcs to reconstruct/);
    assert.ok(await page.isDisabled('#reconstruct'));
    assert.equal(await page.textContent('#summary'), '');
    assert.match(await page.textContent('#downloads'), /Run something first/);
    await page.waitForFunction(() => document.getElementById('view-image').dataset.view === 'data');
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('New project starts over and can be undone', async () => {
  const app = await openApp();
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    await teaching(page);
    await page.click('#new-project');
    await page.waitForFunction(() => document.getElementById('project-name').textContent === 'New project');
    await waitStatus(page, /^Load an image catalogue or arcs/);
    assert.ok(await page.isDisabled('#reconstruct'));
    // No figure of the data that went (the hidden image stayed on screen before).
    await page.waitForSelector('#view-image', { state: 'hidden' });
    for (const role of ['images', 'model']) assert.equal(await page.textContent(`#status-${role}`), '');
    // Saved as such: a reload opens the empty project.
    await page.reload();
    await waitStatus(page, /^Restored your project/);
    assert.equal(await page.textContent('#project-name'), 'New project');
    // A file loaded into it makes it one's own data: the heading no longer says nothing is
    // loaded.
    await page.setInputFiles('#file-images', join(ROOT, 'www', 'examples', 'teaching', 'images.cat'));
    await waitStatus(page, /^Ready: press Reconstruct\.$/);
    assert.equal(await page.textContent('#project-name'), 'Your data');
    assert.doesNotMatch(await page.textContent('#project-description'), /Nothing loaded/);
    // Undo is offered right after New project (in this page, not after a reload).
    await teaching(page);
    await page.click('#new-project');
    await page.click('#undo-new-project');
    await waitStatus(page, /^Back to the project as it was/);
    assert.equal(await page.textContent('#project-name'), 'Teaching example: one halo, four sources');
    assert.match(await page.textContent('#status-images'), /images\.cat/);
    assert.ok(await page.isEnabled('#reconstruct'));
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('an example picked over your own files can be undone', async () => {
  const app = await openApp();
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    await page.click('#new-project');
    await waitStatus(page, /^Load an image catalogue or arcs/);
    await page.setInputFiles('#file-images', join(ROOT, 'www', 'examples', 'teaching', 'images.cat'));
    await waitStatus(page, /^Ready: press Reconstruct\.$/);
    await setField(page, '#set-reconstruct-solver-iterations', 321);
    assert.equal(await page.textContent('#project-name'), 'Your data');
    // An example chosen from the menu replaces the files and settings; the status line offers
    // the way back.
    await page.selectOption('#example-select', { label: 'Teaching example: one halo, four sources' });
    await page.waitForFunction(() => /Teaching/.test(document.getElementById('project-name').textContent));
    await page.waitForSelector('#undo-example');
    assert.match(await page.textContent('#status'), /^Ready: press Reconstruct\. Undo: back to "Your data"$/);
    await page.evaluate(() => window.scrollTo(0, 0));
    await page.screenshot({ path: join(ARTIFACTS, 'undo-example.png') });
    await phoneShot(page, page.locator('#status'), 'undo-example-phone.png');
    await page.setViewportSize({ width: 1280, height: 900 });
    await page.click('#undo-example');
    await waitStatus(page, /^Back to the project as it was/);
    assert.equal(await page.textContent('#project-name'), 'Your data');
    assert.match(await page.textContent('#status-images'), /images\.cat/);
    assert.equal(await page.inputValue('#set-reconstruct-solver-iterations'), '321');
    // Kept as the session: a reload opens one's own data again.
    await page.reload();
    await waitStatus(page, /^Restored your project/);
    assert.equal(await page.textContent('#project-name'), 'Your data');
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

test('a file with many warnings quotes three and folds the rest beside it', async () => {
  const app = await openApp();
  try {
    const { page } = app;
    await waitStatus(page, /^Ready/);
    await teaching(page);
    // Seven rows written twice: seven warnings, each naming its line.
    const text = await readFile(MEMBERS, 'utf8');
    const rows = text.split('\n').filter((l) => /^\d/.test(l)).slice(0, 7);
    await page.setInputFiles('#file-members', { name: 'twice.cat', mimeType: 'text/plain', buffer: Buffer.from(`${text.trimEnd()}\n${rows.join('\n')}\n`) });
    await page.waitForSelector('#status-members .more-warnings');
    const line = await page.evaluate(() => document.getElementById('status-members').firstChild.textContent);
    assert.match(line, /^twice\.cat: 101 members \(7 warnings: (twice\.cat: line \d+: member '\d+' repeats line \d+ exactly.*?; ){3}4 more listed below\)$/);
    assert.equal(await page.textContent('#status-members .more-warnings summary'), '4 more warnings');
    assert.ok(await page.isHidden('#status-members .more-warnings li >> nth=0'));
    await page.click('#status-members .more-warnings summary');
    const more = await page.locator('#status-members .more-warnings li').allTextContents();
    assert.equal(more.length, 4);
    assert.ok(more.every((w) => /^twice\.cat: line \d+: member '\d+' repeats line \d+ exactly/.test(w)), more.join(' | '));
    await page.locator('#status-members').scrollIntoViewIfNeeded();
    await page.screenshot({ path: join(ARTIFACTS, 'file-more-warnings.png') });
    await phoneShot(page, page.locator('#status-members'), 'file-more-warnings-phone.png');
    // A reload shows the same line and list (the project keeps each file's report).
    await page.setViewportSize({ width: 1280, height: 900 });
    await page.reload();
    await waitStatus(page, /^Restored your project/);
    assert.equal(await page.evaluate(() => document.getElementById('status-members').firstChild.textContent), line);
    assert.equal(await page.locator('#status-members .more-warnings li').count(), 4);
    assert.deepEqual(app.consoleErrors, []);
  } finally {
    await app.close();
  }
});

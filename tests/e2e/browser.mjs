// Shared by the end-to-end tests: serve www/ on a free localhost port and drive Debian's
// Chromium through playwright-core (no downloaded browser).
import assert from 'node:assert/strict';
import { mkdir } from 'node:fs/promises';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
import { serve } from '../../.ci/serve.mjs';

export const ROOT = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
export const ARTIFACTS = join(ROOT, 'test-artifacts');
/** How long a setting may take to be accepted by the worker (ms). The worker takes messages in
 * turn, so a setting waits for the jobs sent before it (the views drawn after a file loaded),
 * which on a loaded machine can take well over 15 s; the limit only turns a hang into a
 * failure, it measures nothing. */
export const SETTLE_TIMEOUT_MS = 60_000;

const CHROMIUM_FLAGS = [
  '--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
  '--disable-component-update', '--disable-sync', '--no-first-run', '--disable-quic',
];

/** Starts the server and the browser and opens the page (with `query`, e.g. '?simd=baseline';
 * by default `?app`, the research app: a first visit without parameters opens the lessons);
 * returns { page, url, consoleErrors, close }. `serviceWorkers: 'block'` keeps the app's
 * service worker out (so that `page.route` sees the workers' requests); `hasTouch` gives the
 * page a touch screen. */
export async function openApp({ width = 1280, height = 900, query = '?app', serviceWorkers = 'allow', hasTouch = false } = {}) {
  await mkdir(ARTIFACTS, { recursive: true });
  const server = await serve(join(ROOT, 'www'), 0, '127.0.0.1');
  const url = `http://127.0.0.1:${server.address().port}/`;
  const browser = await chromium.launch({
    executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
    args: CHROMIUM_FLAGS,
  });
  const page = await browser.newPage({ viewport: { width, height }, serviceWorkers, hasTouch });
  const consoleErrors = [];
  page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
  page.on('pageerror', (e) => consoleErrors.push(String(e)));
  // Nothing may leave the page's origin.
  const foreignRequests = [];
  page.on('request', (r) => { if (!r.url().startsWith(url) && !r.url().startsWith('data:') && !r.url().startsWith('blob:')) foreignRequests.push(r.url()); });
  await page.goto(url + query);
  return {
    page, url, consoleErrors, foreignRequests,
    /** Stops the web server, as if the network had gone (the browser stays open). */
    async stopServer() {
      server.closeAllConnections();
      await new Promise((r) => server.close(r));
    },
    async close() {
      await browser.close();
      await new Promise((r) => server.close(r));
    },
  };
}

/** Narrows the page to a phone (390 x 844), checks that nothing is wider than the screen, and
 * saves a screenshot of `locator` as `name` in test-artifacts/ (a box the test just looked at
 * at desktop width, seen as a phone shows it). */
export async function phoneShot(page, locator, name) {
  await page.setViewportSize({ width: 390, height: 844 });
  const overflow = await page.evaluate(() => document.documentElement.scrollWidth - window.innerWidth);
  assert.ok(overflow <= 0, `page is ${overflow}px wider than a phone`);
  await locator.screenshot({ path: join(ARTIFACTS, name) });
}

const PNG_SIGNATURE = [0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a];

/** `[width, height]` from the IHDR chunk of the PNG `bytes` (a Buffer); throws on another file. */
export function pngSize(bytes) {
  if (PNG_SIGNATURE.some((b, k) => bytes[k] !== b)) throw new Error('not a PNG');
  if (bytes.subarray(12, 16).toString('latin1') !== 'IHDR') throw new Error('a PNG without IHDR first');
  return [bytes.readUInt32BE(16), bytes.readUInt32BE(20)];
}

/** `[width, height]` of the image `selector` once it has loaded (read in the task that sees
 * it loaded, like `imageStats`). */
export async function imageSize(page, selector) {
  return page.$eval(selector, async (img) => {
    for (let k = 0; k < 300 && !(img.complete && img.naturalWidth > 0); k++) {
      await new Promise((r) => setTimeout(r, 100));
    }
    return [img.naturalWidth, img.naturalHeight];
  });
}

/** How many views the app has shown so far (`data-render` of `#view-image`), for `waitView`. */
export async function renderCount(page) {
  return page.$eval('#view-image', (img) => Number(img.dataset.render ?? 0));
}

/** Waits until `#view-image` shows the view `name` drawn after render number `after` (from
 * `renderCount` before the action), loaded. The app keeps the previous drawing on screen, with
 * its view name, until the new one arrives, so the name alone can match an old map. */
export async function waitView(page, name, after = 0, timeout = 60_000) {
  await page.waitForFunction(([n, k]) => {
    const img = document.getElementById('view-image');
    return img.dataset.view === n && Number(img.dataset.render ?? 0) > k &&
      img.complete && img.naturalWidth > 0;
  }, [name, after], { timeout });
}

/** Presses the run button `button` (Reconstruct, Forward model, Deflection look-up), waits for
 * "Done in" and then for the mass map of that run (drawn after the one on screen before). */
export async function runToMap(page, button, timeout = 60_000) {
  const before = await renderCount(page);
  await page.click(button);
  await waitStatus(page, /^Done in/, timeout);
  await waitView(page, 'kappa', before);
}

/** Statistics of the rendered image `selector` read back through a canvas in the page (`sum`:
 * every colour channel added up, a digest that tells two drawings apart);
 * `near` counts the pixels within `tol` (per channel) of the colour `rgb`. The app sets an
 * image's `src` and `data-view` together and the browser decodes it later, and a view can be
 * drawn again at any time (a new `src`), so the page waits until the image has loaded and
 * reads it in the same task. `rows` counts only the top rows of the image (e.g. the map without
 * the legend under it, whose rows reflow when an entry comes or goes). */
export async function imageStats(page, selector, { rgb = [0, 0, 0], tol = -1, rows = Infinity } = {}) {
  return page.$eval(selector, async (img, [want, tol, rows]) => {
    for (let k = 0; k < 300 && !(img.complete && img.naturalWidth > 0); k++) {
      await new Promise((r) => setTimeout(r, 100));
    }
    const c = document.createElement('canvas');
    c.width = img.naturalWidth;
    c.height = img.naturalHeight;
    const ctx = c.getContext('2d');
    ctx.drawImage(img, 0, 0);
    const { data } = ctx.getImageData(0, 0, c.width, c.height);
    const colours = new Set();
    let reddish = 0;
    let magenta = 0;
    let white = 0;
    let near = 0;
    let sum = 0;
    const end = Math.min(data.length, (Number.isFinite(rows) ? rows : c.height) * c.width * 4);
    for (let k = 0; k < end; k += 4) {
      const [r, g, b] = [data[k], data[k + 1], data[k + 2]];
      sum += r + g + b;
      if (Math.abs(r - want[0]) <= tol && Math.abs(g - want[1]) <= tol && Math.abs(b - want[2]) <= tol) near += 1;
      colours.add((r >> 3) << 10 | (g >> 3) << 5 | (b >> 3));
      if (r > 200 && g < 80 && b < 80) reddish += 1;
      if (r > 220 && g < 100 && b > 220) magenta += 1;
      if (r > 250 && g > 250 && b > 250) white += 1;
    }
    return { width: c.width, height: c.height, distinctColours: colours.size, reddish, magenta, white, near, sum };
  }, [rgb, tol, rows]);
}

/** Types `value` into the input `selector` (or picks the option of that value of a select) and
 * commits it (a change event). */
export async function setField(page, selector, value) {
  const tag = await page.$eval(selector, (el) => {
    const d = el.closest('details');
    if (d) d.open = true;
    return el.tagName;
  });
  if (tag === 'SELECT') {
    await page.locator(selector).selectOption(String(value));
  } else {
    await page.locator(selector).fill(String(value));
    await page.locator(selector).dispatchEvent('change');
  }
  // Settings inputs remember the last accepted value in data-good; wait for it (or an error).
  const isSetting = await page.$eval(selector, (el) => el.id.startsWith('set-'));
  if (!isSetting) return;
  try {
    await page.waitForFunction(([sel, v]) => {
      const el = document.querySelector(sel);
      const err = document.getElementById(`${el.id}-error`);
      if (err && err.textContent) throw new Error(`${sel}: ${err.textContent}`);
      return el.dataset.good === v && el.value === v;
    }, [selector, String(value)], { timeout: SETTLE_TIMEOUT_MS });
  } catch (err) {
    const [shown, good] = await page.$eval(selector, (el) => [el.value, el.dataset.good]);
    const status = await page.textContent('#status');
    throw new Error(`${selector} = '${value}' never accepted (shown '${shown}', accepted '${good}', status '${status}'): ${err.message}`);
  }
}

/** Starts recording the page's long tasks (main-thread tasks over 50 ms, Chromium's Long Tasks
 * API); returns an async function that gives those recorded so far as [start ms, duration ms]. */
export async function watchLongTasks(page) {
  await page.evaluate(() => {
    window.__longTasks = [];
    new PerformanceObserver((list) => {
      for (const e of list.getEntries()) window.__longTasks.push([Math.round(e.startTime), Math.round(e.duration)]);
    }).observe({ type: 'longtask' });
  });
  return () => page.evaluate(() => window.__longTasks);
}

/** Waits until the status line matches `pattern` (fails with the error shown, if any). */
export async function waitStatus(page, pattern, timeout = 60_000) {
  try {
    await page.waitForFunction((src) => new RegExp(src).test(document.getElementById('status').textContent),
      pattern.source, { timeout });
  } catch (err) {
    const status = await page.textContent('#status');
    const error = await page.textContent('#error');
    throw new Error(`status '${status}' (error: '${error}') never matched ${pattern}: ${err.message}`);
  }
}

/** Loads an image catalogue and a member catalogue into the open app (each a path, or a
 * `{ name, mimeType, buffer }` as `setInputFiles` takes it), waits until each file's status
 * line matches its pattern, and sets z_lens. */
export async function loadCatalogues(page, { images, members, zLens, imagesSay = /systems/, membersSay = /members/ }) {
  const said = async (role, file, pattern) => {
    await page.setInputFiles(`#file-${role}`, file);
    await page.waitForFunction(([id, src]) => new RegExp(src).test(document.getElementById(id).textContent),
      [`status-${role}`, pattern.source]);
  };
  await said('images', images, imagesSay);
  await said('members', members, membersSay);
  await setField(page, '#set-z_lens', zLens);
}

/** Runs `op` ('get', 'put', 'keys') on the app's IndexedDB store from the page. */
export function idb(page, op, key, value) {
  return page.evaluate(([op, key, value]) => new Promise((resolve, reject) => {
    const open = indexedDB.open('wslap', 1);
    open.onupgradeneeded = () => open.result.createObjectStore('projects');
    open.onerror = () => reject(open.error);
    open.onsuccess = () => {
      const db = open.result;
      const tx = db.transaction('projects', op === 'put' ? 'readwrite' : 'readonly');
      const s = tx.objectStore('projects');
      const req = op === 'put' ? s.put(value, key) : op === 'get' ? s.get(key) : s.getAllKeys();
      tx.oncomplete = () => { db.close(); resolve(req.result); };
      tx.onerror = () => reject(tx.error);
    };
  }), [op, key, value]);
}

/** The project text the app keeps in IndexedDB, once it matches `pattern` (polled: Playwright's
 * `waitForFunction` takes a returned promise as a true value and does not wait for it). */
export async function savedProject(page, pattern = /wslap-project/, timeout = 30_000) {
  const deadline = Date.now() + timeout;
  for (;;) {
    const text = await idb(page, 'get', 'current');
    if (pattern.test(text ?? '')) return text;
    if (Date.now() >= deadline) throw new Error(`no saved project matching ${pattern} after ${timeout / 1000} s`);
    await new Promise((r) => setTimeout(r, 200));
  }
}

/** [NAXIS1, NAXIS2] of a FITS file's primary header. */
export function fitsAxes(bytes) {
  const header = bytes.subarray(0, 2880 * 4).toString('latin1');
  const card = (key) => Number(header.match(new RegExp(`${key} *= *(\\d+)`))[1]);
  return [card('NAXIS1'), card('NAXIS2')];
}

// Shared by the end-to-end tests: serve www/ on a free localhost port and drive Debian's
// Chromium through playwright-core (no downloaded browser).
import { mkdir } from 'node:fs/promises';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';
import { serve } from '../../.ci/serve.mjs';

const ROOT = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
export const ARTIFACTS = join(ROOT, 'test-artifacts');

const CHROMIUM_FLAGS = [
  '--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
  '--disable-component-update', '--disable-sync', '--no-first-run', '--disable-quic',
];

/** Starts the server and the browser; returns { page, url, consoleErrors, close }. */
export async function openApp({ width = 1280, height = 900 } = {}) {
  await mkdir(ARTIFACTS, { recursive: true });
  const server = await serve(join(ROOT, 'www'), 0, '127.0.0.1');
  const url = `http://127.0.0.1:${server.address().port}/`;
  const browser = await chromium.launch({
    executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
    args: CHROMIUM_FLAGS,
  });
  const page = await browser.newPage({ viewport: { width, height } });
  const consoleErrors = [];
  page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
  page.on('pageerror', (e) => consoleErrors.push(String(e)));
  // Nothing may leave the page's origin.
  const foreignRequests = [];
  page.on('request', (r) => { if (!r.url().startsWith(url) && !r.url().startsWith('data:') && !r.url().startsWith('blob:')) foreignRequests.push(r.url()); });
  await page.goto(url);
  return {
    page, url, consoleErrors, foreignRequests,
    async close() {
      await browser.close();
      await new Promise((r) => server.close(r));
    },
  };
}

/** Statistics of the rendered image `selector` read back through a canvas in the page. */
export async function imageStats(page, selector) {
  return page.$eval(selector, (img) => {
    const c = document.createElement('canvas');
    c.width = img.naturalWidth;
    c.height = img.naturalHeight;
    const ctx = c.getContext('2d');
    ctx.drawImage(img, 0, 0);
    const { data } = ctx.getImageData(0, 0, c.width, c.height);
    const colours = new Set();
    let reddish = 0;
    for (let k = 0; k < data.length; k += 4) {
      const [r, g, b] = [data[k], data[k + 1], data[k + 2]];
      colours.add((r >> 3) << 10 | (g >> 3) << 5 | (b >> 3));
      if (r > 200 && g < 80 && b < 80) reddish += 1;
    }
    return { width: c.width, height: c.height, distinctColours: colours.size, reddish };
  });
}

// Service worker: keeps the app working offline once it has been loaded.
//
// Every same-origin GET goes to the network first, so a rebuilt app is used at once, and its
// answer is kept in the cache; when the network fails, the cached answer is served. At install
// the app's own files, the build of the core this browser runs (js/simd.js: the worker makes
// the same choice; the other build is 1.7 MB this browser never needs) and the built-in
// examples are cached, so one visit is enough to work offline afterwards.

importScripts('js/simd.js');

const CACHE = 'wslap-app';
const APP_FILES = [
  './',
  'index.html',
  'style.css',
  'main.js',
  'lens-client.js',
  'worker.js',
  'js/coords.js',
  'js/downloads.js',
  'js/ensemble.js',
  'js/figure-download.js',
  'js/files.js',
  'js/iterates.js',
  'js/pool.js',
  'js/settings.js',
  'js/simd.js',
  'js/store.js',
  'js/systems-table.js',
  'js/verdict.js',
  'js/views.js',
  'playground/client.js',
  'playground/index.html',
  'playground/lessons.css',
  'playground/lessons.js',
  'playground/observe.js',
  'playground/playground.css',
  'playground/playground.js',
  'playground/scene.js',
  'playground/scenes/first-inversion.json',
  'playground/worker.js',
  'pkg/wslap.js',
  self.wslapCore.hasRelaxedSimd() ? self.wslapCore.relaxed : self.wslapCore.baseline,
  'examples/index.json',
  'lessons/index.json',
];

self.addEventListener('install', (event) => {
  event.waitUntil((async () => {
    const cache = await caches.open(CACHE);
    await cache.addAll(APP_FILES);
    // The example list was just cached with the app's files: read it from there.
    const { examples } = await (await cache.match('examples/index.json')).json();
    await cache.addAll(examples.flatMap((e) => e.files.map((f) => `examples/${f.path}`)));
    await self.skipWaiting();
  })());
});

self.addEventListener('activate', (event) => event.waitUntil(self.clients.claim()));

self.addEventListener('fetch', (event) => {
  const { request } = event;
  if (request.method !== 'GET' || new URL(request.url).origin !== self.location.origin) return;
  event.respondWith((async () => {
    try {
      const response = await fetch(request);
      if (response.ok) await (await caches.open(CACHE)).put(request, response.clone());
      return response;
    } catch (err) {
      // `?simd=baseline` and the like: the same file.
      const cached = await caches.match(request, { ignoreSearch: true });
      if (cached) return cached;
      throw err;
    }
  })());
});

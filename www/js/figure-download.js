// "Download figure": the view on screen drawn again by the worker 1, 2 or 3 times as large
// (text, lines and markers grow with it) and saved as a PNG, e.g. 2x for a slide and 3x for a
// paper. The control sits under the figure and hides with it.

import { save } from './downloads.js';

/** Figure scales offered (the core accepts 0.25 to 4); the first one after 1 is preselected. */
export const FIGURE_SCALES = [1, 2, 3];
/** File names of the views, as in the downloads panel. */
const FILE_NAMES = { kappa: 'kappa', source: 'source-plane', radial: 'radial-profile', convergence: 'convergence', data: 'data',
  compare: 'compare-with-truth',
  spread: 'kappa-std' };

/** The file name of view `view` drawn at scale `k`: `kappa.png`, `kappa@2x.png`. */
export function figureFileName(view, k) {
  return `${FILE_NAMES[view] ?? view}${k === 1 ? '' : `@${k}x`}.png`;
}

/** Adds the control under `#view-image`. `app.viewPng(view, extraOptions)` draws a view. */
export function wireFigureDownload(app) {
  const img = document.getElementById('view-image');
  const bar = document.createElement('div');
  bar.id = 'figure-download';
  bar.className = 'figure-download';
  const scale = document.createElement('select');
  scale.id = 'figure-scale';
  scale.setAttribute('aria-label', 'Size of the downloaded figure');
  scale.title = 'The figure drawn again this many times as large: text and lines grow with it';
  for (const k of FIGURE_SCALES) {
    const o = new Option(k === 1 ? '1× (as shown)' : `${k}× (${k === 2 ? 'slides' : 'print'})`, String(k));
    o.selected = k === 2;
    scale.append(o);
  }
  const button = document.createElement('button');
  button.type = 'button';
  button.className = 'secondary';
  button.id = 'dl-figure';
  button.textContent = 'Download figure (PNG)';
  button.addEventListener('click', async () => {
    const view = img.dataset.view;
    if (!view) return;
    const k = Number(scale.value);
    button.disabled = true;
    try {
      const bytes = await app.viewPng(view, { figure_scale: k });
      save(figureFileName(view, k), new Blob([bytes], { type: 'image/png' }));
    } catch (err) {
      app.showError(err.message);
    } finally {
      button.disabled = false;
    }
  });
  bar.append(button, scale);
  bar.hidden = img.hidden;
  new MutationObserver(() => { bar.hidden = img.hidden; }).observe(img, { attributes: true, attributeFilter: ['hidden'] });
  img.after(bar);
}

// The downloads panel: FITS maps, DS9 regions, the CLI's JSON files, PNGs of the views and
// the project file. Files are made by the worker on request and saved through blob URLs.

const TEXT_FILES = [
  ['summary.json', 'application/json'],
  ['sources.json', 'application/json'],
  ['images.reg', 'text/plain'],
  ['convergence.json', 'application/json'],
  ['critical-curves.json', 'application/json'],
  ['critical-curves.reg', 'text/plain'],
];
const FITS = ['kappa.fits', 'gamma1.fits', 'gamma2.fits', 'x-arcsec-deflect.fits',
  'y-arcsec-deflect.fits', 'psi.fits', 'magnif.fits'];
const VIEWS = [['kappa', 'kappa.png'], ['source', 'source-plane.png'],
  ['radial', 'radial-profile.png'], ['convergence', 'convergence.png']];

/** Saves `blob` as `name`. */
export function save(name, blob) {
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 10_000);
}

/** A button labelled `label` with id `id` that calls `onClick`; `className` its look. */
export function button(label, id, onClick, className = 'secondary') {
  const b = document.createElement('button');
  b.type = 'button';
  b.className = className;
  b.textContent = label;
  b.id = id;
  b.addEventListener('click', onClick);
  return b;
}

/** Rebuilds the panel for a result of `kind`. `app` gives the files. */
export function showDownloads(kind, app) {
  const box = document.getElementById('downloads');
  box.replaceChildren();
  const group = (title, buttons) => {
    const g = document.createElement('div');
    g.className = 'download-group';
    g.innerHTML = `<h3>${title}</h3>`;
    g.append(...buttons);
    box.append(g);
  };
  const fail = (err) => app.showError(err.message);
  group('Maps (FITS, HFF style)', FITS.map((name) => button(name, `dl-${name.replaceAll('.', '-')}`, () =>
    app.fitsFile(name).then((bytes) => save(name, new Blob([bytes], { type: 'application/fits' })), fail))));
  const texts = kind === 'reconstruct' ? TEXT_FILES : TEXT_FILES.filter(([n]) => !/sources|images|convergence/.test(n));
  group('Results', texts.map(([name, type]) => button(name, `dl-${name.replaceAll('.', '-')}`, () =>
    app.textFile(name).then((text) => save(name, new Blob([text], { type })), fail))));
  const views = kind === 'reconstruct' ? VIEWS : VIEWS.filter(([v]) => v !== 'convergence');
  group('Figures (PNG)', views.map(([view, name]) => button(name, `dl-${name.replaceAll('.', '-')}`, () =>
    app.viewPng(view).then((bytes) => save(name, new Blob([bytes], { type: 'image/png' })), fail))));
  group('Project', [button('project.json', 'dl-project-json', () =>
    app.textFile('project.json').then((t) => save('wslap-project.json', new Blob([t], { type: 'application/json' })), fail))]);
}

// Guided lessons on top of the playground (`?lesson=ID`): each lesson of
// ../lessons/index.json is a scene, a few sentences and things to try. The lesson's panel sits
// above the playground's controls (in an embedded page, a compact card above the views);
// Previous/Next walk the lessons in teaching order, "Presenter" enlarges the text for a
// projector. The scene a lesson opens with goes into the URL fragment like any playground
// scene, so a link reopens the lesson as it was left.

const INDEX = new URL('../lessons/index.json', import.meta.url).href;

/** Opens lesson `id` (the first when unknown) in the playground `api` (./playground.js). */
export async function startLessons(api, id) {
  const css = document.createElement('link');
  css.rel = 'stylesheet';
  css.href = new URL('./lessons.css', import.meta.url).href;
  document.head.append(css);
  const { lessons } = await (await fetch(INDEX)).json();
  // A lesson may share its scene with other pages (`scene_file`, relative to www/).
  await Promise.all(lessons.filter((l) => l.scene_file).map(async (l) => {
    l.scene = await (await fetch(new URL(`../${l.scene_file}`, import.meta.url))).json();
  }));
  const box = document.createElement('section');
  box.id = 'pg-lesson';
  box.className = 'pg-lesson';
  box.setAttribute('aria-label', 'Lesson');
  if (api.EMBED) {
    api.root.querySelector('.pg-main').before(box);
  } else {
    api.root.querySelector('#pg-panel').prepend(box);
    // The read-out the lessons ask to look at goes right under the two planes: in the panel
    // it sat below the lesson's text, out of view.
    const stage = document.createElement('div');
    stage.className = 'pg-stage';
    const views = api.root.querySelector('#pg-views');
    views.before(stage);
    stage.append(views, api.root.querySelector('#pg-readout'));
    // On a narrow screen the panel comes after the planes: the lesson goes above them, so that
    // a phone shows what the lesson is about before two pictures it has not explained.
    const narrow = window.matchMedia('(max-width: 899px)');
    const place = () => {
      if (narrow.matches) stage.before(box);
      else api.root.querySelector('#pg-panel').prepend(box);
    };
    narrow.addEventListener('change', () => { place(); api.resize(); });
    place();
  }
  let first = true;
  const open = (k, push) => {
    const lesson = lessons[k];
    render(api, box, lessons, k, open);
    // A shared link's scene (in the fragment) is the lesson as it was left: keep it.
    if (first && api.hasSharedScene) api.setToggles(lesson.show);
    else api.loadScene(sceneOf(lesson, 0), lesson.show);
    first = false;
    const url = `${location.pathname}?${api.EMBED ? 'embed&' : ''}lesson=${encodeURIComponent(lesson.id)}`;
    if (push) history.pushState(null, '', url + location.hash);
    document.title = `${lesson.title} · lensing lessons · WSLAP+`;
    api.resize();
  };
  const k = lessons.findIndex((l) => l.id === id);
  open(Math.max(0, k), false);
  if (k < 0 && id) {
    note(box, `There is no lesson "${id}"; here is the first (lessons: ${lessons.map((l) => l.id).join(', ')}).`);
  }
  window.addEventListener('popstate', () => {
    const want = new URLSearchParams(location.search).get('lesson');
    const j = lessons.findIndex((l) => l.id === want);
    if (j >= 0) open(j, false);
  });
}

/** The `n`th scene of a lesson (lessons with several scenes offer a switch between them). */
function sceneOf(lesson, n) {
  return lesson.scenes ? lesson.scenes[n].scene : lesson.scene;
}

function note(box, text) {
  const p = document.createElement('p');
  p.className = 'pg-lesson-note';
  p.textContent = text;
  box.append(p);
}

/** Fills the lesson panel for lesson `k`; `open(k, push)` goes to another. Built from text
 * nodes: the lessons file is data, not markup. */
function render(api, box, lessons, k, open) {
  const lesson = lessons[k];
  const el = (tag, cls, text) => {
    const e = document.createElement(tag);
    if (cls) e.className = cls;
    if (text !== undefined) e.textContent = text;
    return e;
  };
  box.replaceChildren();
  if (!api.EMBED) {
    box.append(el('p', 'pg-lesson-intro', 'Gravitational lensing, hands on: each lesson sets up a scene to explore. '
      + 'When you know how lenses work, the research app maps the mass of real clusters from their images.'));
  }
  const head = el('div', 'pg-lesson-head');
  head.append(el('span', 'pg-lesson-count', `Lesson ${k + 1} of ${lessons.length}`));
  const nav = el('span', 'pg-lesson-nav');
  const button = (label, id, onClick, disabled = false) => {
    const b = el('button', '', label);
    b.type = 'button';
    b.id = id;
    b.disabled = disabled;
    b.addEventListener('click', onClick);
    return b;
  };
  nav.append(
    button('← Previous', 'pg-lesson-prev', () => open(k - 1, true), k === 0),
    button('Next →', 'pg-lesson-next', () => open(k + 1, true), k === lessons.length - 1),
  );
  if (!api.EMBED) {
    const present = button('Presenter', 'pg-present', () => {
      const on = document.body.classList.toggle('pg-present');
      present.setAttribute('aria-pressed', String(on));
      api.resize();
    });
    present.setAttribute('aria-pressed', String(document.body.classList.contains('pg-present')));
    present.title = 'Large text for a projector';
    nav.append(present);
  }
  head.append(nav);
  box.append(head);
  box.append(el('h2', 'pg-lesson-title', lesson.title));
  const body = api.EMBED ? el('details', 'pg-lesson-more') : el('div', 'pg-lesson-body');
  if (api.EMBED) body.append(el('summary', '', 'Read the lesson'));
  for (const t of lesson.text) body.append(el('p', '', t));
  if (lesson.scenes) {
    const row = el('div', 'pg-lesson-scenes');
    lesson.scenes.forEach((s, n) => {
      const b = button(s.label, `pg-lesson-scene-${n}`, () => {
        api.loadScene(s.scene);
        row.querySelectorAll('button').forEach((x, m) => x.setAttribute('aria-pressed', String(m === n)));
      });
      b.setAttribute('aria-pressed', String(n === 0));
      row.append(b);
    });
    (api.EMBED ? box : body).append(row);
  }
  body.append(el('h3', '', 'Try this'));
  const list = el('ol', 'pg-lesson-try');
  for (const t of lesson.try) list.append(el('li', '', t));
  body.append(list);
  box.append(body);
  if (api.EMBED) body.addEventListener('toggle', () => api.resize());
  if (!api.EMBED) {
    const all = el('p', 'pg-lesson-all');
    all.append('All lessons: ');
    lessons.forEach((l, m) => {
      const a = el('a', m === k ? 'on' : '', `${m + 1}`);
      a.href = `?lesson=${encodeURIComponent(l.id)}`;
      a.title = l.title;
      a.addEventListener('click', (e) => { e.preventDefault(); open(m, true); });
      all.append(a, ' ');
    });
    const app = el('a', 'pg-lesson-app', 'Research app: reconstruct clusters →');
    app.href = './?app';
    all.append(' · ', app);
    box.append(all);
  }
}

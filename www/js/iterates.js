// Stepping through the iterations: after a reconstruction, a slider under the mass map over the
// iterates the run kept (the worker draws each one's map, curves and predicted images), Play /
// Pause to step through them a few a second, and a button back to the result. With QADP the
// iteration count is the regulariser: this shows what stopping earlier or later would give.

/** Least time between two steps of Play (ms): a few a second, slower when a map takes longer. */
const PLAY_STEP_MS = 300;

let app = null; // { render }: draws the current view (set by wireIterates)
let list = null; // the worker's `iterates` answer: {iterations, method, steps: [{iteration, objective}]}
let shown = null; // index of the iterate on the slider (the last one is the result)
let playing = false;
let drawing = false; // a drawing of the map is on its way
let again = false; // draw once more when it is done (the slider moved meanwhile)

const box = () => document.getElementById('iterates');
const slider = () => document.getElementById('iterate-slider');
const playButton = () => document.getElementById('iterate-play');

/** "iteration 120 of 3000" for iterate `k` (the exact solver's steps are factorisations). */
function words(k) {
  const step = list.steps[k];
  const unit = list.method === 'exact' ? 'step' : 'iteration';
  const last = k === list.steps.length - 1 ? ' (the result)' : '';
  return `${unit} ${step.iteration} of ${list.iterations}${last}`;
}

/** The view option of the iterate shown: `{iterate: k}` while an earlier iterate than the
 * result is on the slider, else nothing (the result's own map). */
export function iterateOption() {
  if (!list || shown == null || shown === list.steps.length - 1) return {};
  return { iterate: shown };
}

function label() {
  const text = words(shown);
  const out = document.getElementById('iterate-label');
  out.textContent = text;
  slider().setAttribute('aria-valuetext', text);
  document.getElementById('iterate-final').disabled = shown === list.steps.length - 1;
}

/** Draws the map of the iterate on the slider; one drawing at a time, the latest wins. */
async function draw() {
  if (drawing) { again = true; return; }
  drawing = true;
  try {
    await app.render();
  } finally {
    drawing = false;
  }
  if (again) { again = false; await draw(); }
}

function select(k) {
  shown = k;
  slider().value = String(k);
  label();
  return draw();
}

function setPlaying(on) {
  playing = on;
  playButton().textContent = on ? 'Pause' : 'Play';
  playButton().setAttribute('aria-pressed', String(on));
}

/** Steps from the iterate on the slider to the result (from the start when it is there). */
async function play() {
  if (shown === list.steps.length - 1) await select(0);
  setPlaying(true);
  while (playing && shown < list.steps.length - 1) {
    const t0 = performance.now();
    await select(shown + 1);
    const wait = PLAY_STEP_MS - (performance.now() - t0);
    if (wait > 0) await new Promise((r) => setTimeout(r, wait));
  }
  setPlaying(false);
}

/** Shows the slider for the iterates of a new result (`null`: none kept, hidden), at the
 * result. */
export function showIterates(iterates) {
  setPlaying(false);
  list = iterates?.steps?.length > 1 ? iterates : null;
  shown = list ? list.steps.length - 1 : null;
  if (!list) {
    box().hidden = true;
    return;
  }
  slider().max = String(list.steps.length - 1);
  slider().value = String(shown);
  label();
  syncIterates();
}

/** Shows the slider with the mass map only (the other views are of the result). */
export function syncIterates() {
  const onMap = document.getElementById('view-image').dataset.view === 'kappa';
  box().hidden = !(list && onMap);
  if (box().hidden) setPlaying(false);
}

/** Builds the slider under the view image; `appApi.render()` draws the current view with
 * `iterateOption()` in its options. */
export function wireIterates(appApi) {
  app = appApi;
  const el = document.createElement('div');
  el.id = 'iterates';
  el.className = 'iterates';
  el.hidden = true;
  el.innerHTML = `<button id="iterate-play" type="button" class="secondary" aria-pressed="false"
      title="Step through the kept iterates up to the result">Play</button>
    <label class="iterate-track">Iterations
      <input id="iterate-slider" type="range" min="0" max="1" step="1" value="1">
    </label>
    <output id="iterate-label" for="iterate-slider" aria-live="off"></output>
    <button id="iterate-final" type="button" class="link" title="Back to the result">Result</button>`;
  document.getElementById('view-image').after(el);
  slider().addEventListener('input', () => {
    setPlaying(false);
    select(Number(slider().value));
  });
  playButton().addEventListener('click', () => (playing ? setPlaying(false) : play()));
  document.getElementById('iterate-final').addEventListener('click', () => {
    setPlaying(false);
    select(list.steps.length - 1);
  });
}

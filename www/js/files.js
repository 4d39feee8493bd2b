// The "Files" panel: one row per file role with a labelled file picker and a status line
// (the parse error with its line, or what was loaded), and a drop zone that guesses roles.

export const ROLES = [
  { role: 'images', label: 'Image catalogue (Lenstool)', accept: '.cat,.txt,.dat' },
  { role: 'members', label: 'Member catalogue (Lenstool)', accept: '.cat,.txt,.dat' },
  { role: 'arcs', label: 'Arcs (JSON, or DS9 regions in fk5)', accept: '.json,.reg' },
  { role: 'shear', label: 'Arclets for weak lensing (Lenstool: id x y a b theta z)', accept: '.cat,.txt,.dat' },
  { role: 'model', label: 'Model file (JSON, or a Lenstool .par; forward mode)', accept: '.json,.par' },
  { role: 'deflection_x', label: 'Deflection x (FITS)', accept: '.fits,.fit' },
  { role: 'deflection_y', label: 'Deflection y (FITS)', accept: '.fits,.fit' },
  { role: 'project', label: 'Project file (JSON)', accept: '.json' },
];

/** Guesses the role of a dropped file from its name and first bytes. */
export async function guessRole(file) {
  const name = file.name.toLowerCase();
  if (/\.fits?$/.test(name)) return /(^|[-_.])y([-_.]|$)|y-arcsec|deflect_y|_y\./.test(name) ? 'deflection_y' : 'deflection_x';
  const head = (await file.slice(0, 4000).text());
  if (name.endsWith('.reg') || /^\s*# Region file format/.test(head)) return 'arcs';
  if (name.endsWith('.par')) return 'model';
  if (name.endsWith('.json')) {
    if (head.includes('wslap-project')) return 'project';
    if (head.includes('"components"')) return 'model';
    return 'arcs';
  }
  if (/arclet|shear|weak|(^|[-_.])wl([-_.]|$)/.test(name)) return 'shear';
  return catalogueRole(head) ?? (/member|pot|gal/.test(name) ? 'members' : 'images');
}

/** A Lenstool catalogue's role from its rows: the 7th column is a redshift in an image
 * catalogue (0 - 12) and a magnitude in a member catalogue (about 14 - 30, or 99 for none), so
 * the median over the first rows tells them apart whatever the file is called (SGAS J1152's
 * `source_ids_ref0.cat` was taken for members by its name). `null` without three such rows.
 * The core's readers refuse a catalogue picked as the other kind by the same column and
 * threshold (`check_kind` in src/catalog/lenstool.rs). */
function catalogueRole(head) {
  const sevenths = head.split(/\r?\n/)
    .map((line) => line.trim())
    .filter((line) => line && !line.startsWith('#'))
    .map((line) => Number(line.split(/\s+/)[6]))
    .filter(Number.isFinite)
    .sort((a, b) => a - b);
  if (sevenths.length < 3) return null;
  return sevenths[Math.floor(sevenths.length / 2)] >= 12 ? 'members' : 'images';
}

/** Builds the rows; `onFile(role, file)` is called for every chosen file. */
export function buildFileRows(container, dropZone, onFile) {
  for (const { role, label, accept } of ROLES) {
    const row = document.createElement('div');
    row.className = 'field file-row';
    row.innerHTML = `<label for="file-${role}">${label}</label>
      <input id="file-${role}" type="file" accept="${accept}">
      <div id="status-${role}" class="file-status" role="status"></div>`;
    container.append(row);
    const input = row.querySelector('input');
    input.addEventListener('change', () => {
      if (input.files[0]) onFile(role, input.files[0]);
      input.value = '';
    });
  }
  // Several files at once, each to the role its name and first lines say.
  const several = async (list) => {
    // Roles are guessed for all files first: a drop's file list is only readable now.
    const files = [...list];
    const roles = await Promise.all(files.map(guessRole));
    files.forEach((file, k) => onFile(roles[k], file));
  };
  const over = (on) => (e) => { e.preventDefault(); dropZone.classList.toggle('over', on); };
  dropZone.addEventListener('dragover', over(true));
  dropZone.addEventListener('dragleave', over(false));
  dropZone.addEventListener('drop', (e) => {
    over(false)(e);
    several(e.dataTransfer.files);
  });
  // Without a mouse to drag with (the keyboard, a phone): a click, Enter or Space opens a
  // chooser of several files, sorted the same way.
  const chooser = document.createElement('input');
  chooser.type = 'file';
  chooser.multiple = true;
  chooser.hidden = true;
  chooser.id = 'drop-zone-chooser';
  dropZone.after(chooser);
  chooser.addEventListener('change', () => {
    several(chooser.files);
    chooser.value = '';
  });
  dropZone.addEventListener('click', () => chooser.click());
  dropZone.addEventListener('keydown', (e) => {
    if (e.key !== 'Enter' && e.key !== ' ') return;
    e.preventDefault();
    chooser.click();
  });
}

/** Shows `text` next to the file of `role` (`bad` for an error), and under it the warnings
 * `more` in a list that opens on a click. */
export function setFileStatus(role, text, bad = false, more = []) {
  const el = document.getElementById(`status-${role}`);
  if (!el) return;
  el.textContent = text;
  el.classList.toggle('bad', bad);
  if (!more.length) return;
  const box = foldedList(`${more.length} more warning${more.length === 1 ? '' : 's'}`, more);
  box.className = 'more-warnings';
  el.append(box);
}

/** A closed `<details>` whose `<summary>` says `summary` and whose list holds `items` (text):
 * a file's warnings past the first few, the run's warnings. */
export function foldedList(summary, items) {
  const box = document.createElement('details');
  const head = document.createElement('summary');
  head.textContent = summary;
  const list = document.createElement('ul');
  for (const text of items) {
    const item = document.createElement('li');
    item.textContent = text;
    list.append(item);
  }
  box.append(head, list);
  return box;
}

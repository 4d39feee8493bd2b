// Keeps the current project (the worker's project.json text) in IndexedDB, so a reload
// restores data, settings and result. Failures are reported, never thrown at the page.
//
// Nothing saved is lost to a crash or a bad copy:
// - a save first checks that the text is a whole project file (it parses, its format is
//   right), then in one transaction (all or nothing) moves the current copy to `previous` and
//   writes the new one, then reads it back and compares; on any failure the copies are as
//   they were;
// - a copy that does not open (corrupt, or saved by a newer version) is set aside under
//   `aside:<time>` with the reason, in one transaction that also removes it from its key, so
//   that the next save cannot overwrite it; the page lists those with a download and a delete.

const DB = 'wslap';
const STORE = 'projects';
const KEY = 'current';
const PREVIOUS = 'previous';
const ASIDE = 'aside:';
const FORMAT = 'wslap-project';

function open() {
  return new Promise((resolve, reject) => {
    const req = indexedDB.open(DB, 1);
    req.onupgradeneeded = () => req.result.createObjectStore(STORE);
    req.onsuccess = () => resolve(req.result);
    req.onerror = () => reject(req.error);
  });
}

/** Runs `action(store)` in one transaction; resolves with what it returns (a request's result
 * is read once the transaction has committed). */
async function run(mode, action) {
  const db = await open();
  try {
    return await new Promise((resolve, reject) => {
      const tx = db.transaction(STORE, mode);
      const out = action(tx.objectStore(STORE));
      tx.oncomplete = () => resolve(out instanceof IDBRequest ? out.result : out);
      tx.onerror = () => reject(tx.error);
      tx.onabort = () => reject(tx.error ?? new Error('the write was aborted'));
    });
  } finally {
    db.close();
  }
}

const get = (key) => run('readonly', (s) => s.get(key));

/** Why `text` is not a whole project file, or null when it is one. The text comes from the
 * core, which writes whole JSON; what can go wrong on the way is an empty or cut text, which
 * this finds without parsing it (a project with FITS maps is many MB: parsing it here would
 * hold up the page at every save). The core parses it in full when it is opened. */
export function projectProblem(text) {
  if (typeof text !== 'string' || text.trim() === '') return 'it is empty';
  if (text.match(/^\s*\{\s*"format":\s*"([^"]*)"/)?.[1] !== FORMAT) return 'it is not a wslap project';
  if (!/\}\s*$/.test(text)) return 'it is not whole (it ends before its closing brace)';
  return null;
}

/** The saved project text, or null. */
export async function loadProject() {
  try {
    return (await get(KEY)) ?? null;
  } catch {
    return null;
  }
}

/** The copy saved before the current one, or null. */
export async function loadPrevious() {
  try {
    return (await get(PREVIOUS)) ?? null;
  } catch {
    return null;
  }
}

/** Whether anything is kept in this browser: a project, its previous copy or one set aside. */
export async function hasSaved() {
  try {
    return (await run('readonly', (s) => s.count())) > 0;
  } catch {
    return false;
  }
}

// Saves of this page run one after another: two at once would each read back the other's
// text, take it for a bad copy and put an older one back.
let saving = Promise.resolve();

/** Saves the project text; returns an error message or null. The copy saved before stays in
 * use until this one is written whole and read back. Saves wait for the one before. */
export function saveProject(text) {
  const done = saving.then(() => saveNow(text));
  saving = done.catch(() => null);
  return done;
}

async function saveNow(text) {
  const problem = projectProblem(text);
  if (problem) return `did not keep the project in this browser: ${problem}; the copy saved before is kept`;
  try {
    await run('readwrite', (s) => {
      const req = s.get(KEY);
      req.onsuccess = () => {
        // The copy in use becomes the fallback, unless it is this very text.
        if (req.result != null && req.result !== text) s.put(req.result, PREVIOUS);
        s.put(text, KEY);
      };
    });
    const back = await get(KEY);
    if (back !== text) {
      // Never seen; but a copy that did not read back whole must not be the one used.
      const previous = await get(PREVIOUS);
      if (previous != null) await run('readwrite', (s) => s.put(previous, KEY));
      return 'could not keep the project in this browser (it did not read back whole); the copy saved before is kept';
    }
    return null;
  } catch (err) {
    return `could not keep the project in this browser: ${err?.message ?? err}; the copy saved before is kept`;
  }
}

/** Forgets the saved project (not what was set aside). */
export async function clearProject() {
  try { await run('readwrite', (s) => { s.delete(KEY); s.delete(PREVIOUS); }); } catch { /* nothing saved */ }
}

/** Sets the copy under `which` ('current' or 'previous') aside with `reason` (why it did not
 * open), in one transaction that removes it from its key. Returns the entry, or null when
 * there was nothing to set aside or the browser refused (the copy then stays where it was). */
export async function setAside(which, reason) {
  const key = which === 'previous' ? PREVIOUS : KEY;
  const at = new Date().toISOString();
  const id = `${ASIDE}${at}:${Math.random().toString(36).slice(2, 8)}`;
  try {
    return await run('readwrite', (s) => {
      const entry = { id, at, reason, text: null };
      const req = s.get(key);
      req.onsuccess = () => {
        if (req.result == null) return;
        entry.text = req.result;
        s.put(entry, id);
        s.delete(key);
      };
      return entry;
    }).then((e) => (e.text == null ? null : e));
  } catch {
    return null;
  }
}

/** The projects set aside, oldest first: `{id, at, reason, text}`. */
export async function setAsideList() {
  try {
    const range = IDBKeyRange.bound(ASIDE, `${ASIDE}\uffff`);
    return (await run('readonly', (s) => s.getAll(range))) ?? [];
  } catch {
    return [];
  }
}

/** Deletes the project set aside under `id`. */
export async function deleteSetAside(id) {
  if (!String(id).startsWith(ASIDE)) return;
  try { await run('readwrite', (s) => s.delete(id)); } catch { /* already gone */ }
}

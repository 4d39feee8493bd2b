// Keeps the current project (the worker's project.json text) in IndexedDB, so a reload
// restores data, settings and result. Failures are reported, never thrown at the page.

const DB = 'wslap';
const STORE = 'projects';
const KEY = 'current';

function open() {
  return new Promise((resolve, reject) => {
    const req = indexedDB.open(DB, 1);
    req.onupgradeneeded = () => req.result.createObjectStore(STORE);
    req.onsuccess = () => resolve(req.result);
    req.onerror = () => reject(req.error);
  });
}

async function run(mode, action) {
  const db = await open();
  try {
    return await new Promise((resolve, reject) => {
      const tx = db.transaction(STORE, mode);
      const req = action(tx.objectStore(STORE));
      tx.oncomplete = () => resolve(req.result);
      tx.onerror = () => reject(tx.error);
    });
  } finally {
    db.close();
  }
}

/** The saved project text, or null. */
export async function loadProject() {
  try {
    return (await run('readonly', (s) => s.get(KEY))) ?? null;
  } catch {
    return null;
  }
}

/** Saves the project text; returns an error message or null. */
export async function saveProject(text) {
  try {
    await run('readwrite', (s) => s.put(text, KEY));
    return null;
  } catch (err) {
    return `could not keep the project in this browser: ${err?.message ?? err}`;
  }
}

/** Forgets the saved project. */
export async function clearProject() {
  try { await run('readwrite', (s) => s.delete(KEY)); } catch { /* nothing saved */ }
}

// The verdict beside the map after a reconstruction (summary.json's `verdict`, computed by the
// core): one of "good", "usable with care", "do not trust the small scales", the reasons in a
// sentence or two, and the numbers behind it. The worst systems are ringed on the map (drawn
// by the core) and marked in the systems table.

let last = null; // the verdict on screen, or null

/** A length in arcsec, or a dash. */
const arcsec = (v) => (v == null ? '–' : `${v.toFixed(2)}″`);

/** The verdict's worst systems `[{id, problem, ...}]` (none without a verdict). */
export function worstSystems() {
  return last?.worst ?? [];
}

// The held-out figure's words by where it comes from (summary.json's `verdict.holdout_from`).
const HELD_OUT_FROM = {
  held_out_systems: 'held out',
  crossval: 'held out in the cross-validation',
  choice: 'held out while choosing the settings',
};

/** Text for the numbers behind the verdict, one per line. */
function facts(v) {
  const held = HELD_OUT_FROM[v.holdout_from] ?? 'held out';
  const out = [`Image offsets (median): fitted ${arcsec(v.fit_offset_median_arcsec)}${
    v.holdout_offset_median_arcsec == null ? '' : `, ${held} ${arcsec(v.holdout_offset_median_arcsec)}`}`];
  const parts = [`${v.systems_matched} as many as observed`];
  if (v.systems_fewer_predicted) parts.push(`${v.systems_fewer_predicted} fewer`);
  if (v.systems_more_predicted) {
    const far = v.systems_far_more_predicted ? ` (${v.systems_far_more_predicted} more than twice as many)` : '';
    parts.push(`${v.systems_more_predicted} more${far}`);
  }
  out.push(`Predicted images (|μ| ≥ 0.1) of ${v.systems} system${v.systems === 1 ? '' : 's'}: ${parts.join(', ')}${
    v.systems_with_lost_images ? `; ${v.systems_with_lost_images} with an image not reproduced` : ''}`);
  const z = v.z_source == null ? '' : ` at z_s = ${v.z_source}`;
  const c = v.members_with_own_curves && v.c_unmeasured ? ' (their mass is assumed: C is hardly measured)' : '';
  // Without member galaxies there is nothing to say about them.
  if (v.members) out.push(`Members with critical curves of their own${z}: ${v.members_with_own_curves}${c}`);
  const fitted = v.bcg?.fitted ?? [];
  if (fitted.length === 1) {
    out.push(`Brightest cluster galaxy: member ${fitted[0].id}, commented out on line ${fitted[0].line} of the member catalogue, fitted (setting "Fit commented-out BCG rows"; the warnings say why)`);
  } else if (fitted.length) {
    out.push(`Brightest cluster galaxies: members ${andList(fitted.map((r) => `${r.id} (line ${r.line})`))}, commented out of the member catalogue, fitted (setting "Fit commented-out BCG rows"; the warnings say why)`);
  }
  if (v.images_on_curves) {
    out.push(`Observed images on a critical curve (|μ| > 100): ${v.images_on_curves} of ${v.images}`);
  }
  if (v.worst.length) out.push(`Worst systems (ringed on the map; why: Image systems): ${v.worst.map((w) => w.id).join(', ')}`);
  return out;
}

/** `items` as English lists them: "a", "a and b", "a, b and c". */
const andList = (items) => (items.length < 2 ? items.join('')
  : `${items.slice(0, -1).join(', ')} and ${items[items.length - 1]}`);

/** Shows `verdict` (or hides the box for `null`: no result, or no reconstruction). When the
 * members lack their BCG, a button offers to fit it: the member catalogue's commented-out rows
 * (`bcg.commented`, one per core: `fitRows([{line, id}])`), else the galaxies of the loaded
 * Lenstool .par (`modelGalaxies`, `[{id, line, mag, mag_from_mass}]`: `fitModel()`). */
export function showVerdict(verdict, { fitRows = null, modelGalaxies = [], fitModel = null } = {}) {
  last = verdict ?? null;
  const box = document.getElementById('verdict');
  if (!box) return;
  box.replaceChildren();
  box.hidden = !last;
  if (!last) return;
  box.dataset.trust = last.trust;
  const head = document.createElement('p');
  head.className = 'verdict-head';
  const word = document.createElement('strong');
  word.id = 'verdict-words';
  word.textContent = last.words;
  head.append('Verdict: ', word);
  const reasons = document.createElement('p');
  reasons.id = 'verdict-reasons';
  reasons.textContent = last.reasons;
  const list = document.createElement('ul');
  list.id = 'verdict-facts';
  for (const text of facts(last)) {
    const li = document.createElement('li');
    li.textContent = text;
    list.append(li);
  }
  box.append(head, reasons, list);
  const offer = (id, text, title, onClick) => {
    const fit = document.createElement('button');
    fit.type = 'button';
    fit.id = id;
    fit.textContent = text;
    fit.title = title;
    fit.addEventListener('click', onClick);
    box.append(fit);
  };
  const rows = last.bcg?.commented ?? [];
  if (rows.length && fitRows) {
    const which = rows.length === 1 ? `member ${rows[0].id} (line ${rows[0].line})`
      : `members ${andList(rows.map((r) => `${r.id} (line ${r.line})`))}`;
    offer('fit-commented-bcg', `Fit ${which} and reconstruct again`,
      `Removes the # before ${rows.length === 1 ? 'that row' : 'those rows'} of the member catalogue you loaded (in this app only: your file is not changed) and runs the reconstruction again.`,
      () => fitRows(rows));
  } else if (last.bcg?.missing && modelGalaxies.length && fitModel) {
    // A fitted .par may list hundreds of galaxies: name a few.
    // A galaxy the .par writes without a magnitude is named by the one its mass stands for.
    const named = modelGalaxies.slice(0, 3).map((g) => (g.mag_from_mass
      ? `${g.id}, as massive as a mag ${g.mag.toFixed(2)} member`
      : `${g.id}, mag ${g.mag.toFixed(2)}`)).join('; ');
    const which = modelGalaxies.length === 1 ? `galaxy (${named})`
      : modelGalaxies.length <= 3 ? `galaxies (${named})`
        : `${modelGalaxies.length} galaxies (${named}; …)`;
    offer('fit-model-galaxies', `Fit the .par's ${which} and reconstruct again`,
      'The loaded Lenstool .par models these galaxies on their own (a core of at most 5 kpc, with a magnitude; without one, the member catalogue\'s commented row where it lies, or else the magnitude whose halo mass is its dPIE\'s, at the least mass its limit priors allow where a starting .par leaves it free): fits them as members (the setting "Galaxies and redshift priors from the .par", which also takes the redshift priors of its z_m_limit lines), as wslap reconstruct --par does, and runs the reconstruction again.',
      fitModel);
  }
}

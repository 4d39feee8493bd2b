// The playground's scenes in the page: the default scene, the parameters each kind of lens
// and source has (for the sliders), and the share format of the URL fragment.
// The scene format itself is the core's (src/playground/mod.rs); nothing here is lensing.

export const DEFAULT_SCENE = {
  v: 1, z_lens: 0.3, fov: 40,
  lenses: [
    { type: 'sie', x: 0, y: 0, sigma_v: 850, q: 0.75, pa: 20 },
    { type: 'member', x: 7, y: -5, mag: 19 },
    { type: 'shear', gamma1: 0.03, gamma2: 0.02 },
  ],
  sources: [
    { type: 'sersic', x: 1.2, y: 0.8, z: 2, r_eff: 0.6, n: 1, q: 0.7, pa: 30 },
    { type: 'gaussian', x: -1.5, y: -1.0, z: 1.2, sigma: 0.35, q: 1, pa: 0 },
    { type: 'point', x: 0.6, y: -0.4, z: 3 },
  ],
};

// Slider ranges: [field, label, min, max, step, log?]. Positions are typed or dragged.
const POS = [['x', 'x (″)', -100, 100, 0.01], ['y', 'y (″)', -100, 100, 0.01]];
const SHAPE = [['q', 'axis ratio q', 0.1, 1, 0.01], ['pa', 'angle (° from +x)', -90, 90, 1]];
export const FIELDS = {
  sis: [...POS, ['sigma_v', 'σ_v (km/s)', 50, 2000, 5]],
  sie: [...POS, ['sigma_v', 'σ_v (km/s)', 50, 2000, 5], ...SHAPE],
  nfw: [...POS, ['m200', 'M200 (M☉)', 1e12, 1e16, 0.01, true], ['c200', 'c200', 1, 20, 0.1], ...SHAPE],
  tnfw: [...POS, ['m200', 'M200 (M☉)', 1e9, 1e15, 0.01, true], ['c200', 'c200', 1, 40, 0.1], ['r_trunc', 'r_trunc (″)', 0.5, 50, 0.1]],
  point: [...POS, ['mass', 'mass (M☉)', 1e9, 1e15, 0.01, true]],
  gaussian: [...POS, ['mass', 'mass (M☉)', 1e10, 1e15, 0.01, true], ['sigma', 'σ (″)', 0.5, 30, 0.1]],
  shear: [['gamma1', 'γ1', -0.3, 0.3, 0.005], ['gamma2', 'γ2', -0.3, 0.3, 0.005]],
  sheet: [['kappa', 'κ', -0.5, 0.8, 0.01]],
  member: [...POS, ['mag', 'magnitude', 15, 24, 0.1]],
};
const Z = ['z', 'redshift z', 0.35, 6, 0.05];
export const SOURCE_FIELDS = {
  gaussian: [...POS, Z, ['sigma', 'σ (″)', 0.05, 5, 0.01], ...SHAPE],
  sersic: [...POS, Z, ['r_eff', 'r_eff (″)', 0.05, 5, 0.01], ['n', 'Sérsic n', 0.5, 8, 0.1], ...SHAPE],
  point: [...POS, Z],
  image: [...POS, Z, ['size', 'size (″)', 0.5, 40, 0.1]],
};

export const NEW_LENS = {
  sie: { type: 'sie', x: 0, y: 0, sigma_v: 600, q: 0.7, pa: 0 },
  sis: { type: 'sis', x: 0, y: 0, sigma_v: 500 },
  nfw: { type: 'nfw', x: 0, y: 0, m200: 1e15, c200: 5, q: 1, pa: 0 },
  point: { type: 'point', x: 0, y: 0, mass: 1e12 },
  member: { type: 'member', x: 5, y: 5, mag: 19.5 },
  shear: { type: 'shear', gamma1: 0.05, gamma2: 0 },
  sheet: { type: 'sheet', kappa: 0.1 },
};
export const NEW_SOURCE = {
  sersic: { type: 'sersic', x: 0.5, y: 0.5, z: 2, r_eff: 0.5, n: 1, q: 0.8, pa: 0 },
  gaussian: { type: 'gaussian', x: 0.5, y: 0.5, z: 2, sigma: 0.3, q: 1, pa: 0 },
  point: { type: 'point', x: 0.3, y: 0.3, z: 2 },
};

export const LENS_NAMES = {
  sis: 'SIS', sie: 'SIE', nfw: 'NFW halo', tnfw: 'truncated NFW', point: 'point mass',
  gaussian: 'Gaussian mass', shear: 'external shear', sheet: 'mass sheet', member: 'member galaxy',
};
export const SOURCE_NAMES = { gaussian: 'Gaussian', sersic: 'Sérsic', point: 'point source', image: 'picture' };

/** Has a position that can be dragged. */
export const draggable = (item) => 'x' in item && 'y' in item;

// ---- share format: `#s1=` + base64url of the compact scene JSON (s1 = version 1).

const PREFIX = '#s1=';

/** The scene without numbers' float noise (6 significant digits), for links. */
function tidy(value) {
  if (typeof value === 'number') return Number(value.toPrecision(6));
  if (Array.isArray(value)) return value.map(tidy);
  if (value && typeof value === 'object') {
    return Object.fromEntries(Object.entries(value).map(([k, v]) => [k, tidy(v)]));
  }
  return value;
}

export function tidyScene(scene) { return tidy(scene); }

/** `#s1=...` for `scene`. */
export function encodeFragment(scene) {
  const bytes = new TextEncoder().encode(JSON.stringify(tidy(scene)));
  let bin = '';
  for (const b of bytes) bin += String.fromCharCode(b);
  return PREFIX + btoa(bin).replace(/\+/g, '-').replace(/\//g, '_').replace(/=+$/, '');
}

/** The scene in `hash`, or null if it holds none; throws on a damaged one. */
export function decodeFragment(hash) {
  if (!hash.startsWith(PREFIX)) return null;
  const b64 = hash.slice(PREFIX.length).replace(/-/g, '+').replace(/_/g, '/');
  const bin = atob(b64 + '='.repeat((4 - b64.length % 4) % 4));
  const bytes = Uint8Array.from(bin, (c) => c.charCodeAt(0));
  return JSON.parse(new TextDecoder().decode(bytes));
}

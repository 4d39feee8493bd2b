// Page wiring: DOM references first, then the worker client, then event handlers.

import { LensClient } from './lens-client.js';

const statusEl = document.getElementById('status');
const errorEl = document.getElementById('error');
const mapImg = document.getElementById('kappa-map');
const summaryEl = document.getElementById('summary');
const modelFileInput = document.getElementById('model-file');
const modelFileStatus = document.getElementById('model-file-status');
const zSourceInput = document.getElementById('z-source');
const scaleSelect = document.getElementById('scale');
const runButton = document.getElementById('run');
const exampleButton = document.getElementById('example');

// The model text currently loaded; null means the built-in example.
let modelText = null;
let modelName = 'built-in example';
let mapUrl = null;

const client = new LensClient({
  onReady: (msg) => setStatus(`Worker ready (wslap ${msg.version}).`),
  onCrash: (message) => showError(message),
});

function setStatus(text) {
  statusEl.textContent = text;
}

function showError(text) {
  errorEl.textContent = text;
  errorEl.hidden = false;
}

function clearError() {
  errorEl.hidden = true;
  errorEl.textContent = '';
}

function options() {
  return { z_source: Number(zSourceInput.value), scale: scaleSelect.value };
}

async function compute() {
  clearError();
  runButton.disabled = true;
  exampleButton.disabled = true;
  try {
    const result = await client.request('forward', { model: modelText, options: options() },
      (p) => setStatus(p.message));
    if (mapUrl) URL.revokeObjectURL(mapUrl);
    mapUrl = URL.createObjectURL(new Blob([result.png], { type: 'image/png' }));
    mapImg.src = mapUrl;
    mapImg.hidden = false;
    const s = result.summary;
    summaryEl.textContent = `${modelName}: z_lens = ${s.z_lens}, z_s = ${s.z_source}, ` +
      `Einstein radius ${s.einstein_radius_arcsec.toFixed(1)}″, ` +
      `${s.tangential_curves} tangential and ${s.radial_curves} radial critical curves.`;
    setStatus(`Done in ${(result.elapsedMs / 1000).toFixed(2)} s.`);
  } catch (err) {
    setStatus('Failed.');
    showError(err.message);
  } finally {
    runButton.disabled = false;
    exampleButton.disabled = false;
  }
}

modelFileInput.addEventListener('change', async () => {
  const file = modelFileInput.files[0];
  if (!file) return;
  const text = await file.text();
  try {
    // Validate in the worker before replacing what is loaded: a bad file loses nothing.
    await client.request('validateModel', { model: text, name: file.name });
    modelText = text;
    modelName = file.name;
    modelFileStatus.textContent = `Loaded ${file.name}.`;
    modelFileStatus.classList.remove('bad');
    compute();
  } catch (err) {
    modelFileStatus.textContent = err.message;
    modelFileStatus.classList.add('bad');
  }
});

runButton.addEventListener('click', compute);
exampleButton.addEventListener('click', () => {
  modelText = null;
  modelName = 'built-in example';
  modelFileStatus.textContent = '';
  compute();
});

compute();

// The wasm core's linear memory after one reconstruction of the app's A1689-like example, for
// BENCHMARKS.md "Memory of a run": the memory never shrinks, so its size is the run's peak.
// Usage (after `npm run build`): node benches/wasm-memory.mjs CELLS [qadp|exact]
import { readFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = join(dirname(fileURLToPath(import.meta.url)), '..');
const [cells, method = 'qadp'] = process.argv.slice(2);
const core = await import(join(root, 'www/pkg/wslap.js'));
const wasm = await core.default({ module_or_path: readFileSync(join(root, 'www/pkg/wslap_bg.wasm')) });
const examples = join(root, 'www/examples');
const example = JSON.parse(readFileSync(join(examples, 'index.json'), 'utf8')).examples[0];
const s = new core.AppSession();
s.set_field('z_lens', example.z_lens);
for (const [path, value] of Object.entries(example.settings)) s.set_field(path, value);
for (const f of example.files) {
  s.load_text(f.role, f.path.split('/').pop(), readFileSync(join(examples, f.path), 'utf8'));
}
s.set_field('reconstruct.solver.iterations', 300);
if (method === 'exact') {
  s.set_field('reconstruct.objective.regulariser', 'gradient');
  s.set_field('reconstruct.objective.strength', 0.1);
  s.set_field('reconstruct.solver.method', 'exact');
  s.set_field('reconstruct.solver.iterations', 30);
}
try {
  s.set_field('reconstruct.grid.cells', Number(cells));
} catch (err) {
  console.log(`cells ${cells} ${method}: refused: ${err.message}`);
  process.exit(0);
}
const t0 = Date.now();
s.run('reconstruct', () => {});
const mib = (wasm.memory.buffer.byteLength / 2 ** 20).toFixed(0);
console.log(`cells ${cells} ${method}: wasm memory ${mib} MiB, ${(Date.now() - t0) / 1000} s, ${s.result_info().status}`);

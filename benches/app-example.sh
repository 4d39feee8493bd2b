#!/usr/bin/env bash
# The browser app's built-in (teaching) example, natively with the same settings as the app
# (www/examples/index.json: 24 x 24 cells, 3000 iterations, 256-pixel maps 60 arcsec wide).
# Compare with the browser worker: WSLAP_BENCH=1 node --test tests/e2e/bench.test.mjs
set -euo pipefail
cd "$(dirname "$0")/.."
cfg="$(mktemp)"
cat > "$cfg" <<'JSON'
{"grid": {"cells": 24}, "solver": {"iterations": 3000},
 "constraints": {"mode": "ellipse"}, "products": {"pixels": 256, "size_arcsec": 60.0},
 "system": {"threads": ${THREADS:-0}}}
JSON
sed -i "s/\${THREADS:-0}/${THREADS:-0}/" "$cfg"
out="$(mktemp -d)"
start=$(date +%s.%N)
cargo run --release --quiet --bin wslap -- reconstruct --images www/examples/teaching/images.cat \
  --z-lens 0.3 --config "$cfg" --out "$out" >/dev/null
end=$(date +%s.%N)
echo "native wall time: $(echo "$end - $start" | bc) s (THREADS=${THREADS:-0}, 0 = all cores)"
python3 -c "import json,sys; t=json.load(open('$out/summary.json'))['timings_ms']; print('stage timings (ms):', t)"

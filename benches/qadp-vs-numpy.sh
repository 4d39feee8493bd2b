#!/usr/bin/env bash
# QADP against the NumPy reference, side by side (BENCHMARKS.md, issue: the inversion): runs
# ../shared/bench/qadp_numpy.py and `cargo bench --bench qadp_bench` RUNS times each, alternating,
# on each program's default threads and on one thread, and prints the 8000 iterations' time of
# every run, the speed-up of the medians, and its range (slowest Rust run against fastest NumPy
# run, and the reverse).
#
#   bash benches/qadp-vs-numpy.sh [RUNS]        (default 3)
#   PYTHON=/path/to/venv/bin/python bash benches/qadp-vs-numpy.sh
#
# Needs a Python with NumPy (`python3 -m venv /tmp/npenv && /tmp/npenv/bin/pip install numpy`,
# then PYTHON=/tmp/npenv/bin/python). Run it on an otherwise idle machine: on a busy one
# OpenBLAS's threads lose far more than Rust's (BENCHMARKS.md).
set -euo pipefail

runs="${1:-3}"
python="${PYTHON:-python3}"
root="$(cd "$(dirname "$0")/.." && pwd)"
numpy_script="$root/../shared/bench/qadp_numpy.py"

[ -f "$numpy_script" ] || { echo "error: $numpy_script not found" >&2; exit 1; }
"$python" -c 'import numpy' 2>/dev/null || {
  echo "error: $python has no NumPy; set PYTHON to one that has (see the top of this script)" >&2
  exit 1
}
cd "$root"
cargo bench --bench qadp_bench --no-run >/dev/null 2>&1 || {
  echo "error: cargo bench --bench qadp_bench does not build" >&2
  exit 1
}

# Seconds of the 8000 iterations in a benchmark's output line.
iterations_s() { grep -o 'qadp_[0-9]*=[0-9.]*s' | head -1 | sed 's/.*=//; s/s$//'; }

declare -A times
for ((k = 1; k <= runs; k++)); do
  times[numpy_default]+=" $("$python" "$numpy_script" | iterations_s)"
  times[rust_default]+=" $(cargo bench -q --bench qadp_bench 2>/dev/null | iterations_s)"
  times[numpy_one]+=" $(OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 "$python" "$numpy_script" | iterations_s)"
  times[rust_one]+=" $(cargo bench -q --bench qadp_bench -- 32 4000 8000 1 2>/dev/null | iterations_s)"
done

echo "8000 QADP iterations (s), $runs runs each, load average: $(cut -d' ' -f1-3 /proc/loadavg)"
for threads in default one; do
  numpy="${times[numpy_$threads]}"
  rust="${times[rust_$threads]}"
  echo "  $threads thread(s): NumPy$numpy | Rust$rust"
  # Sorted, so that awk (any awk) finds the extremes and the median by position.
  sorted() { printf '%s\n' $1 | sort -g | tr '\n' ' '; }
  awk -v n="$(sorted "$numpy")" -v r="$(sorted "$rust")" -v t="$threads" 'BEGIN {
    k = split(n, a, " "); split(r, b, " ");
    if (k % 2) median = a[(k + 1) / 2] / b[(k + 1) / 2];
    else median = (a[k / 2] + a[k / 2 + 1]) / (b[k / 2] + b[k / 2 + 1]);
    printf "  speed-up on %s thread(s): %.2fx of the medians (range %.2f - %.2fx)\n", t, median, a[1] / b[k], a[k] / b[1]
  }'
done

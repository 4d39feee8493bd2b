#!/usr/bin/env bash
# `npm test`: set up what is missing, then run every check and test; exit non-zero on any failure.
set -uo pipefail
source "$(dirname "$0")/lib.sh"

setup_rust
setup_npm
setup_chromium

LOG_DIR="$ROOT/target/test-logs"
mkdir -p "$LOG_DIR"
passed=0
failed=0
failed_steps=()

# run_step NAME COMMAND...: runs one step, shows its output, counts its tests.
run_step() {
  local name="$1"; shift
  local log="$LOG_DIR/${name// /-}.log"
  say "$name"
  "$@" 2>&1 | tee "$log"
  local status=${PIPESTATUS[0]}
  # Tests counted from the runners' own summary lines (cargo/libtest and node --test).
  local p f
  p=$(grep -E '^test result:' "$log" | sed -E 's/.* ([0-9]+) passed.*/\1/' | awk '{s+=$1} END {print s+0}')
  f=$(grep -E '^test result:' "$log" | sed -E 's/.* ([0-9]+) failed.*/\1/' | awk '{s+=$1} END {print s+0}')
  p=$((p + $(grep -E '^# pass [0-9]+' "$log" | awk '{s+=$3} END {print s+0}')))
  f=$((f + $(grep -E '^# fail [0-9]+' "$log" | awk '{s+=$3} END {print s+0}')))
  if [ "$p" -eq 0 ] && [ "$f" -eq 0 ]; then
    # A check without tests of its own (fmt, clippy, build) counts as one.
    if [ "$status" -eq 0 ]; then p=1; else f=1; fi
  elif [ "$status" -ne 0 ] && [ "$f" -eq 0 ]; then
    f=1
  fi
  passed=$((passed + p))
  failed=$((failed + f))
  if [ "$status" -ne 0 ]; then failed_steps+=("$name"); fi
}

export CHROMEDRIVER=/usr/bin/chromedriver
# ChromeDriver leaves a ~40 MB browser profile in $TMPDIR for every wasm test binary (the
# runner stops it without ending the session): keep them under target/ and delete them at exit.
export TMPDIR="$ROOT/target/tmp/browsers"
rm -rf "$TMPDIR" && mkdir -p "$TMPDIR"
trap 'rm -rf "$TMPDIR"' EXIT
export CARGO_TARGET_WASM32_UNKNOWN_UNKNOWN_RUNNER=wasm-bindgen-test-runner
# The runner's time for one test binary in the browser (its default, 20 s, is near what the
# app's tests take in a debug build).
export WASM_BINDGEN_TEST_TIMEOUT=300

run_step "cargo fmt" cargo fmt --all -- --check
run_step "clippy native" cargo clippy --all-targets -- -D warnings
run_step "clippy wasm32" cargo clippy --all-targets --target wasm32-unknown-unknown -- -D warnings
run_step "docs" env RUSTDOCFLAGS="-D warnings" cargo doc --no-deps
run_step "native tests" cargo test
# The committed fuzz corpus and regressions replay in the native tests (tests/fuzz_corpus.rs);
# when nightly and cargo-fuzz are installed, each target also fuzzes briefly (a minute in all).
run_step "fuzz (short)" bash .ci/fuzz.sh --ci 6
run_step "wasm tests in a worker" cargo test --target wasm32-unknown-unknown --test '*'
run_step "wasm build" build_wasm
run_step "browser end-to-end tests" node --test --test-concurrency=1 tests/e2e/

echo
if [ ${#failed_steps[@]} -gt 0 ]; then
  echo "Failed steps: ${failed_steps[*]} (logs in target/test-logs/)"
fi
echo "summary: $passed passed, $failed failed"
[ ${#failed_steps[@]} -eq 0 ] && [ "$failed" -eq 0 ]

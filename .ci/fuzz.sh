#!/usr/bin/env bash
# Coverage-guided fuzzing of the file parsers (fuzz/README.md).
#
#   bash .ci/fuzz.sh [--setup] [--ci] [SECONDS [TARGET...]]   (npm run fuzz -- SECONDS TARGET...)
#
# Runs each target (all when none is named) for SECONDS (default 600) of wall time, one at a
# time, at the lowest priority, on the committed corpus (fuzz/corpus/<target>/, only read) plus what
# earlier runs found (fuzz/work/<target>/, not committed) and, when FUZZ_EXTRA names a
# directory (e.g. ../shared/data), the files in it (only read). Crashes go to
# fuzz/artifacts/<target>/. --setup installs the nightly toolchain and cargo-fuzz when
# missing; without it a missing one skips the run with a message (what CI does). --ci fuzzes
# into a temporary directory, so the run leaves nothing behind but crashes. WSLAP_SKIP_FUZZ=1
# skips the run (e.g. `WSLAP_SKIP_FUZZ=1 npm test` on a busy machine: building the
# sanitised targets takes minutes).
set -uo pipefail
source "$(dirname "$0")/lib.sh"

setup=0
ci=0
while [ $# -gt 0 ]; do
  case "$1" in
    --setup) setup=1; shift ;;
    --ci) ci=1; shift ;;
    *) break ;;
  esac
done
seconds="${1:-600}"
shift || true
targets=("$@")

if [ -n "${WSLAP_SKIP_FUZZ:-}" ]; then
  echo "fuzz: skipped (WSLAP_SKIP_FUZZ is set)"; exit 0
fi
if ! cargo +nightly --version >/dev/null 2>&1; then
  if [ "$setup" = 1 ]; then
    rustup toolchain install nightly --profile minimal || die "rustup could not install nightly."
  else
    echo "fuzz: skipped (no nightly toolchain; 'npm run fuzz' installs it)"; exit 0
  fi
fi
if ! cargo +nightly fuzz --version >/dev/null 2>&1; then
  if [ "$setup" = 1 ]; then
    cargo install cargo-fuzz || die "could not install cargo-fuzz."
  else
    echo "fuzz: skipped (no cargo-fuzz; 'npm run fuzz' installs it)"; exit 0
  fi
fi

# FUZZ_EXTRA is given relative to where the command runs (the repository root for npm run):
# made absolute before moving into fuzz/.
[ -n "${FUZZ_EXTRA:-}" ] && FUZZ_EXTRA="$(realpath "$FUZZ_EXTRA")"
cd "$ROOT/fuzz" || exit 1
[ ${#targets[@]} -gt 0 ] || mapfile -t targets < <(cargo +nightly fuzz list)

# Longest input per target: well above the seeds and real files, small enough to stay fast.
max_len() {
  case "$1" in
    fits_read|project_json) echo 32768 ;;
    fits_roundtrip) echo 16448 ;;
    settings_json) echo 4096 ;;
    *) echo 8192 ;;
  esac
}

nice -n 19 cargo +nightly fuzz build -a || die "the fuzz targets do not build."
tmp=""
if [ "$ci" = 1 ]; then
  tmp="$(mktemp -d)"
  trap 'rm -rf "$tmp"' EXIT
fi
status=0
for t in "${targets[@]}"; do
  work="${tmp:-work}/$t"
  mkdir -p "$work"
  extra=()
  [ -n "${FUZZ_EXTRA:-}" ] && extra=("$FUZZ_EXTRA")
  say "fuzz $t for ${seconds}s"
  TIMEFORMAT="fuzz $t: %U s user, %S s system, %R s wall"
  time {
    nice -n 19 cargo +nightly fuzz run -a "$t" "$work" "corpus/$t" "${extra[@]}" -- \
      -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len="$(max_len "$t")" \
      -print_final_stats=1 2>&1 \
      | grep -E '^(stat::|#[0-9]+ *DONE|==[0-9]+==|SUMMARY|thread .* panicked|Test unit written)'
    [ "${PIPESTATUS[0]}" -eq 0 ] || { echo "fuzz $t: FAILED (see fuzz/artifacts/$t/)"; status=1; }
  }
done
exit $status

# Shared by the project's scripts: messages and the idempotent setup steps.
# Each step checks first and installs only what is missing; a failure says what to do.

say() { printf '\033[1m==> %s\033[0m\n' "$*"; }
die() { printf '\033[31merror:\033[0m %s\n' "$*" >&2; exit 1; }

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT" || exit 1
export PATH="$HOME/.cargo/bin:$PATH"

# The wasm-bindgen version pinned in Cargo.lock (the CLI must match it exactly).
wasm_bindgen_version() {
  awk '/^name = "wasm-bindgen"$/ { getline; gsub(/version = |"/, ""); print; exit }' Cargo.lock
}

setup_rust() {
  command -v cargo >/dev/null || die "cargo not found: install Rust with rustup (https://rustup.rs) and run again."
  if [ ! -f Cargo.lock ]; then
    cargo generate-lockfile || die "could not resolve the crate's dependencies (is crates.io reachable?)"
  fi
  if ! rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown; then
    say "Installing the Rust target wasm32-unknown-unknown"
    rustup target add wasm32-unknown-unknown || die "rustup could not add the wasm32-unknown-unknown target."
  fi
  local want have
  want="$(wasm_bindgen_version)"
  [ -n "$want" ] || die "no wasm-bindgen entry in Cargo.lock"
  have="$(wasm-bindgen --version 2>/dev/null | awk '{print $2}')"
  if [ "$have" != "$want" ]; then
    say "Installing wasm-bindgen-cli $want (found: ${have:-none}); this takes a few minutes, once"
    cargo install wasm-bindgen-cli --version "$want" \
      || die "could not install wasm-bindgen-cli $want with cargo; install it by hand and run again."
  fi
}

setup_npm() {
  command -v npm >/dev/null || die "npm not found: install Node.js 18 or newer and run again."
  if [ ! -d node_modules/playwright-core ]; then
    say "Installing npm packages"
    if [ -f package-lock.json ]; then
      npm ci --no-audit --no-fund || die "npm ci failed (is the npm registry reachable?)"
    else
      npm install --no-audit --no-fund || die "npm install failed (is the npm registry reachable?)"
    fi
  fi
}

setup_chromium() {
  if [ -x /usr/bin/chromium ] && [ -x /usr/bin/chromedriver ]; then
    return
  fi
  say "Installing Debian's chromium and chromium-driver for the browser tests"
  local sudo=""
  if [ "$(id -u)" != 0 ]; then
    command -v sudo >/dev/null || die "chromium and chromium-driver are missing and this user is not root: run 'apt-get install -y chromium chromium-driver' as root."
    sudo="sudo"
  fi
  $sudo apt-get update -q && $sudo apt-get install -y -q chromium chromium-driver \
    || die "apt-get could not install chromium and chromium-driver."
}

# Builds the core twice into www/pkg/: for baseline WebAssembly SIMD (wslap_bg.wasm, every current
# browser) and for relaxed SIMD (wslap_relaxed_bg.wasm: fused multiply-add in the solver's
# kernels, ~1.3x faster where the browser has it). Both share wasm-bindgen's JavaScript glue;
# www/worker.js picks the module. Honours CARGO_TARGET_DIR.
build_wasm() {
  local target="${CARGO_TARGET_DIR:-target}"
  say "Building the WebAssembly core (release)"
  cargo build --lib --release --target wasm32-unknown-unknown || die "the wasm build failed (see above)."
  wasm-bindgen --target web --no-typescript --out-dir www/pkg \
    "$target/wasm32-unknown-unknown/release/wslap.wasm" || die "wasm-bindgen failed (see above)."
  say "Building the WebAssembly core for relaxed SIMD (release)"
  # RUSTFLAGS replaces the rustflags of .cargo/config.toml, so simd128 is named again; a target
  # directory of its own keeps the two builds from invalidating each other.
  local relaxed="$target/relaxed-simd"
  RUSTFLAGS="-C target-feature=+simd128,+relaxed-simd" \
    cargo build --lib --release --target wasm32-unknown-unknown --target-dir "$relaxed" \
    || die "the relaxed-SIMD wasm build failed (see above)."
  wasm-bindgen --target web --no-typescript --out-dir "$relaxed/pkg" \
    "$relaxed/wasm32-unknown-unknown/release/wslap.wasm" || die "wasm-bindgen failed (see above)."
  cmp -s "$relaxed/pkg/wslap.js" www/pkg/wslap.js \
    || die "the two wasm builds have different JavaScript glue ($relaxed/pkg/wslap.js, www/pkg/wslap.js)."
  cp "$relaxed/pkg/wslap_bg.wasm" www/pkg/wslap_relaxed_bg.wasm
}

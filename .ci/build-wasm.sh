#!/usr/bin/env bash
# Builds the wasm core into www/pkg (installs the Rust pieces that are missing first).
set -uo pipefail
source "$(dirname "$0")/lib.sh"
setup_rust
build_wasm

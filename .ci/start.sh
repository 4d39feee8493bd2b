#!/usr/bin/env bash
# `npm start`: set up what is missing, build the wasm core, serve www/ on localhost.
set -uo pipefail
source "$(dirname "$0")/lib.sh"
setup_rust
setup_npm
build_wasm
exec node .ci/serve.mjs www

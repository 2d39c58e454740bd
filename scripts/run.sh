#!/usr/bin/env bash
# Runs naadf's main job on its built-in world. Until the server lands, that is generating
# the default `terrain` world (1024 × 512 × 2048) and printing its `info`.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/ensure-deps.sh
cargo build --release --bin naadf
mkdir -p target/worlds
./target/release/naadf generate --preset terrain -o target/worlds/terrain.naadf "$@"
./target/release/naadf info target/worlds/terrain.naadf

#!/usr/bin/env bash
# Runs the naadf service on its built-in world: `naadf serve` with no arguments generates
# the default `terrain` world (1024 × 512 × 2048) into ./naadf-data on first start (later
# starts resume it) and serves gRPC on 127.0.0.1:50051 and HTTP on 127.0.0.1:8080. Then open
# http://127.0.0.1:50051/ in a browser with WebGPU: the page is served by naadf itself.
# Extra arguments go to `naadf serve`; stop it with Ctrl-C (a final snapshot is written).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/ensure-deps.sh
cargo build --release --bin naadf
exec ./target/release/naadf serve "$@"

#!/usr/bin/env bash
# Runs every check CI runs: formatting, lints and the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/ensure-deps.sh
cargo fmt --all -- --check
cargo clippy --workspace --all-targets -- -D warnings
bash scripts/validate-deploy.sh
# The service without the renderer (tests/tidy.rs checks that its dependency tree names no
# wgpu, winit or nv-flip): tests/no_gpu.rs drives that binary (serve, relay, edit, status,
# mirror, data).
cargo build -p naadf --no-default-features --bin naadf
# Copied aside: the test build below links target/debug/naadf again, with the renderer.
cp target/debug/naadf target/naadf-no-gpu
export NAADF_NO_GPU_BIN="$PWD/target/naadf-no-gpu"
cargo test --workspace

#!/usr/bin/env bash
# Runs every check CI runs: formatting, lints and the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/ensure-deps.sh
cargo fmt --all -- --check
cargo clippy --workspace --all-targets -- -D warnings
bash scripts/validate-deploy.sh
cargo test --workspace

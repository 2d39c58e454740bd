#!/usr/bin/env bash
# Runs every check CI runs: formatting, lints and the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/ensure-deps.sh
# The browser page's tests (tests/web_page.rs) drive Debian's Chromium (installed above) with
# playwright-core from web/: install the page's locked packages, and make a missing browser
# a failure rather than a skip.
if node -e 'const [a, b] = process.versions.node.split(".").map(Number); process.exit(a > 20 || (a === 20 && b >= 19) ? 0 : 1)' 2>/dev/null; then
    npm ci --prefix web --ignore-scripts --no-audit --no-fund >&2
    export NAADF_REQUIRE_BROWSER=1
else
    echo "warning: Node >= 20.19 not found: the browser tests will skip" >&2
fi
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

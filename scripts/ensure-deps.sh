#!/usr/bin/env bash
# Installs what naadf needs beyond a Rust toolchain, if it is missing, and sets the
# environment for headless rendering. Idempotent; source it (`. scripts/ensure-deps.sh`).
#
# - Mesa lavapipe (software Vulkan) and EGL: the render client's tests run wgpu on the CPU
#   when no GPU is present.
# - python3-venv: the server test that drives stock grpcurl installs it from PyPI into a
#   virtual environment.
# - Xvfb, the X client libraries winit loads at run time, and xdotool: the viewer's test
#   opens a real window on a virtual display and clicks in it.
# - Chromium: the render-node test loads the server's status page in a headless browser.
# - g++: the FLIP image metric (the nv-flip crate) compiles NVIDIA's C++ implementation.
# - fonts-dejavu-core: `naadf bench`'s scatter plot draws its text with DejaVu Sans (or the
#   TTF named by NAADF_PLOT_FONT).
# - LP_NUM_THREADS=8: llvmpipe balances uneven compute work badly with one thread per core.
# - XDG_RUNTIME_DIR: silences Vulkan loader warnings on headless machines.

pkgs="mesa-vulkan-drivers libvulkan1 libegl1 libegl-mesa0 libgl1-mesa-dri python3-venv xvfb libx11-xcb1 libxcursor1 libxrandr2 libxi6 libxkbcommon-x11-0 xdotool chromium g++ fonts-dejavu-core"
if command -v dpkg-query >/dev/null 2>&1; then
    missing=""
    for p in $pkgs; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
    done
    if [ -n "$missing" ]; then
        echo "installing:$missing" >&2
        sudo_cmd=""
        [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null 2>&1 && sudo_cmd="sudo"
        $sudo_cmd apt-get update -qq >&2
        DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends $missing >&2
    fi
else
    echo "warning: not a Debian system; install Mesa Vulkan (lavapipe) yourself if tests need it" >&2
fi

if ! command -v cargo >/dev/null 2>&1; then
    if [ -x "$HOME/.cargo/bin/cargo" ]; then
        export PATH="$HOME/.cargo/bin:$PATH"
    else
        echo "error: cargo not found; install Rust from https://rustup.rs" >&2
        return 1 2>/dev/null || exit 1
    fi
fi

# The checks need rustfmt and clippy; rustup's minimal profile lacks them.
if ! cargo fmt --version >/dev/null 2>&1 || ! cargo clippy --version >/dev/null 2>&1; then
    rustup component add rustfmt clippy >&2
fi

export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp/xdg-$(id -u)}"
mkdir -p -m 700 "$XDG_RUNTIME_DIR"
export LP_NUM_THREADS="${LP_NUM_THREADS:-8}"

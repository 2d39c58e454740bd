#!/usr/bin/env bash
# Extended test (not part of .ci/run): builds both images of deploy/ and runs them.
#
# No registry is needed: the base images the Dockerfiles name (debian:bookworm-slim and
# rust:1-bookworm) are made here, the first with debootstrap from Debian's packages, the
# second from it plus Debian's C toolchain and this machine's Rust toolchain. Then:
#   1. `podman build` of deploy/Dockerfile and deploy/render-node.Dockerfile, from a clean
#      clone of HEAD, exactly as they are (docker image format, so HEALTHCHECK is kept);
#   2. the server image with a named volume for /data, until its HEALTHCHECK passes;
#   3. a relay from the same image in front of it, until its HEALTHCHECK passes, and the
#      relay's digest equal to the server's;
#   4. the render-node image registered with the server, until its HEALTHCHECK passes, and
#      a frame rendered by it in the container (lavapipe), asked of the relay.
# The containers share a podman network of their own, as in deploy/compose.yaml; nothing is
# published on the host's ports.
#
# Needs root, podman, runc, debootstrap and git (installed with apt when missing), a Debian
# mirror (DEBIAN_MIRROR, default http://deb.debian.org/debian) and crates.io. Slow: the
# build stage compiles naadf in release inside the container. It skips, saying why, where
# containers cannot run. Everything lives in a podman storage of its own under a temporary
# folder, so this machine's own images (a real debian:bookworm-slim among them) are never
# touched; KEEP=1 keeps that folder and says where it is.
#
#   scripts/build-images.sh
set -euo pipefail

repo=$(cd "$(dirname "$0")/.." && pwd)
mirror=${DEBIAN_MIRROR:-http://deb.debian.org/debian}
skip() {
    echo "SKIPPED: $*" >&2
    exit 0
}
step() { echo "== $*" >&2; }

[ "$(id -u)" = 0 ] || skip "building base images with debootstrap needs root"
need=()
for tool in podman runc debootstrap git; do
    command -v "$tool" >/dev/null || need+=("$tool")
done
if [ ${#need[@]} -gt 0 ]; then
    step "installing ${need[*]}"
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${need[@]}" >/dev/null ||
        skip "cannot install ${need[*]}"
fi

# runc, not crun: crun refuses a host whose cgroups are mounted in hybrid mode. Limits at or
# below this shell's own: podman's defaults are higher than an unprivileged sandbox allows.
limits=(--ulimit "nofile=1024:1024" --ulimit "nproc=1024:1024")
work=$(mktemp -d /tmp/naadf-images.XXXXXX)
# TMPDIR: where the builder keeps the Dockerfiles' cache mounts (crates, target/).
mkdir -p "$work/tmp"
# Podman would run the images' health checks on systemd timers; there is no systemd here, so
# the checks are run by hand below and its complaints about that are left out.
pod() {
    TMPDIR="$work/tmp" podman --runtime runc --root "$work/storage" --runroot "$work/run" "$@" \
        2> >(grep -v -e 'systemd connection' -e 'connect to syslog' >&2)
}
cleanup() {
    pod rm -f -t 5 render-node relay naadf >/dev/null 2>&1 || true
    pod network rm -f "naadf-it-$$" >/dev/null 2>&1 || true
    if [ -n "${KEEP:-}" ]; then
        echo "kept: podman --runtime runc --root $work/storage --runroot $work/run images" >&2
        return
    fi
    pod system reset --force >/dev/null 2>&1 || true
    rm -rf "$work"
}
trap cleanup EXIT

step "debian:bookworm-slim from Debian's packages (debootstrap, $mirror)"
debootstrap --variant=minbase bookworm "$work/rootfs" "$mirror" >"$work/debootstrap.log" 2>&1 ||
    skip "debootstrap failed (see its log): $(tail -n 3 "$work/debootstrap.log")"
tar -C "$work/rootfs" -c . | pod import --change 'CMD ["bash"]' - docker.io/library/debian:bookworm-slim >/dev/null
rm -rf "$work/rootfs"
pod run --rm "${limits[@]}" docker.io/library/debian:bookworm-slim true ||
    skip "podman cannot run a container on this machine"

step "rust:1-bookworm: that image, Debian's C and C++ toolchain (as in the official image) and this machine's Rust toolchain"
mkdir -p "$work/rust-base/local-ca"
cp -a "$(rustc --print sysroot)" "$work/rust-base/rust"
# The certificate authorities this machine adds to its trust store (a TLS-inspecting proxy's,
# say), so that cargo reaches crates.io from the build stage as it does from here.
cp /usr/local/share/ca-certificates/*.crt "$work/rust-base/local-ca/" 2>/dev/null || true
cat >"$work/rust-base/Containerfile" <<'EOF'
FROM docker.io/library/debian:bookworm-slim
RUN apt-get update \
    && apt-get install -y --no-install-recommends gcc g++ make libc6-dev binutils pkg-config ca-certificates \
    && rm -rf /var/lib/apt/lists/*
COPY local-ca/ /usr/local/share/ca-certificates/
RUN update-ca-certificates
COPY rust /usr/local/rust
ENV CARGO_HOME=/usr/local/cargo \
    PATH=/usr/local/rust/bin:/usr/local/cargo/bin:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
EOF
pod build -q --pull=never --network host "${limits[@]}" -t docker.io/library/rust:1-bookworm "$work/rust-base" >/dev/null
rm -rf "$work/rust-base"

step "the images, from a clean clone of HEAD"
git clone -q "$repo" "$work/src"
build() { # DOCKERFILE TAG
    pod build --format docker --pull=never --network host "${limits[@]}" \
        --ignorefile "$work/src/$1.dockerignore" -f "$work/src/$1" -t "$2" "$work/src"
}
build deploy/Dockerfile localhost/naadf:it
build deploy/render-node.Dockerfile localhost/naadf-render-node:it
for image in localhost/naadf:it localhost/naadf-render-node:it; do
    user=$(pod image inspect --format '{{.Config.User}}' "$image")
    health=$(pod image inspect --format '{{json .Config.Healthcheck}}' "$image")
    echo "$image: user $user, healthcheck $health" >&2
    case "$user" in "" | 0 | 0:* | root | root:*) echo "FAIL: $image runs as root" >&2 && exit 1 ;; esac
    [ "$health" != "null" ] || { echo "FAIL: $image has no HEALTHCHECK" >&2 && exit 1; }
done

healthy() { # CONTAINER: waits for its HEALTHCHECK to pass
    for _ in $(seq 1 600); do
        if pod healthcheck run "$1" >/dev/null 2>&1; then
            echo "$1: healthy" >&2
            return 0
        fi
        if [ "$(pod inspect --format '{{.State.Running}}' "$1")" != true ]; then
            pod logs "$1" >&2
            echo "FAIL: $1 exited" >&2
            exit 1
        fi
        sleep 1
    done
    pod logs "$1" >&2
    echo "FAIL: $1 never became healthy" >&2
    exit 1
}
# As deploy/compose.yaml runs them: one network in which services find each other by name,
# read-only root file systems, tokens from the environment.
net=naadf-it-$$
pod network create "$net" >/dev/null
start() { pod run -d --network "$net" "${limits[@]}" --read-only "$@" >/dev/null; }
cli() { pod run --rm --network "$net" "${limits[@]}" "$@"; }

step "the server image, with a named volume for /data (compose's command: a new terrain world)"
start --name naadf -v naadf-data:/data -e NAADF_TOKENS="adm=ops:admin,node=render:render-node,rly=relay:viewer" \
    localhost/naadf:it serve --data /data --grpc 0.0.0.0:50051 --http 0.0.0.0:8080 --generate terrain --insecure
healthy naadf

step "a relay from the same image"
start --name relay -e NAADF_TOKEN=rly -e NAADF_HEALTH_PORT=8081 localhost/naadf:it \
    relay --upstream http://naadf:50051 --grpc 0.0.0.0:50061 --http 0.0.0.0:8081
healthy relay
digest() { # URL: the digest the server or relay at URL reports
    cli localhost/naadf:it status --server "$1" --token adm --json |
        sed -n 's/.*"digest": *"\{0,1\}\([0-9a-fx]*\).*/\1/p'
}
# The server may still be settling its distance fields; the relay follows within moments.
for attempt in $(seq 1 60); do
    server_digest=$(digest http://naadf:50051)
    relay_digest=$(digest http://relay:50061)
    [ -n "$server_digest" ] && [ "$server_digest" = "$relay_digest" ] && break
    [ "$attempt" = 60 ] && { echo "FAIL: relay digest $relay_digest, server $server_digest" >&2 && exit 1; }
    sleep 1
done
echo "digests: server $server_digest, relay $relay_digest" >&2

step "the render-node image (lavapipe, its default server http://naadf:50051), and a frame through the relay"
start --name render-node --tmpfs /tmp -e NAADF_TOKEN=node localhost/naadf-render-node:it
healthy render-node
cli -v "$work:/out" --user 0 localhost/naadf:it frame --server http://relay:50061 --token adm \
    --size 64x36 --mode albedo --camera '{"pos":[512,300,100],"yaw":20,"pitch":-20,"fov_y":60}' -o /out/frame.png
[ "$(head -c 8 "$work/frame.png" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ] ||
    { echo "FAIL: no PNG came back" >&2 && exit 1; }
echo "ok: both images built, non-root, healthy; relay on the server's digest; a frame from the render node" >&2

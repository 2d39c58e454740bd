# syntax=docker/dockerfile:1
#
# The `naadf-render-node` image: `naadf render-node` with the Vulkan loader and Mesa's
# lavapipe (software Vulkan on the CPU) as the fallback. On a GPU host the NVIDIA container
# toolkit mounts the driver and its Vulkan ICD into the container (the NVIDIA_* variables
# below ask for the graphics capability), and wgpu picks the GPU over lavapipe.
# Build from the repository root:
#
#   docker build -f deploy/render-node.Dockerfile -t naadf-render-node .

FROM rust:1-bookworm AS build
WORKDIR /src
COPY . .
RUN --mount=type=cache,target=/usr/local/cargo/registry \
    --mount=type=cache,target=/src/target \
    cargo build --release --locked --bin naadf \
    && strip --strip-debug target/release/naadf \
    && cp target/release/naadf /naadf

FROM debian:bookworm-slim
RUN apt-get update \
    && apt-get install -y --no-install-recommends ca-certificates libstdc++6 libvulkan1 mesa-vulkan-drivers \
    && rm -rf /var/lib/apt/lists/*
RUN groupadd --system --gid 10001 naadf \
    && useradd --system --uid 10001 --gid naadf --home-dir /home/naadf --create-home --shell /usr/sbin/nologin naadf
COPY --from=build /naadf /usr/local/bin/naadf
# NVIDIA container toolkit: every GPU the runtime grants, with Vulkan (graphics) as well
# as compute. LP_NUM_THREADS: lavapipe's threads; llvmpipe balances uneven compute work
# badly with one thread per core. XDG_RUNTIME_DIR quiets the Vulkan loader.
ENV NVIDIA_VISIBLE_DEVICES=all \
    NVIDIA_DRIVER_CAPABILITIES=compute,graphics,utility \
    LP_NUM_THREADS=8 \
    XDG_RUNTIME_DIR=/tmp \
    NAADF_SERVER=http://naadf:50051
USER 10001:10001
WORKDIR /home/naadf
# A render node connects out to the server (NAADF_SERVER, token in NAADF_TOKEN); its only
# port is 8082, GET /health (200 while registered with the server, 503 while it
# reconnects; no token), for this HEALTHCHECK and Kubernetes probes.
EXPOSE 8082
# It stops on Ctrl-C (SIGINT), not on SIGTERM, so that is its stop signal.
STOPSIGNAL SIGINT
# No curl in the image: bash's /dev/tcp sends the request. NAADF_HEALTH_PORT follows a
# changed --http port.
HEALTHCHECK --interval=15s --timeout=5s --start-period=30s --retries=3 \
    CMD ["bash", "-c", "exec 3<>/dev/tcp/127.0.0.1/${NAADF_HEALTH_PORT:-8082} && printf 'GET /health HTTP/1.0\\r\\nHost: localhost\\r\\n\\r\\n' >&3 && head -n 1 <&3 | grep -q ' 200 '"]
ENTRYPOINT ["naadf"]
CMD ["render-node", "--http", "0.0.0.0:8082"]

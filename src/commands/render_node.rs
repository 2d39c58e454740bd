//! `naadf render-node --server URL --token T [--max-size WxH] [--modes ...]`: a headless
//! render node. It follows the world as a GPU mirror (its own `Join`), registers with the
//! server (`RegisterNode`), and renders each job the server routes to it at a version no
//! older than the job's `min_version` — the quiescent state of that version, so that a
//! node's frame equals `naadf render --world` of the same world byte for byte. It
//! reconnects and registers again by itself when the server goes away
//! ([`naadf_client::node::RenderNode`]); this command supplies the GPU renderer and, with
//! `--http`, a `/health` endpoint for container health checks and Kubernetes probes.

use super::args::parse_image_size;
use super::remote::{ServerArgs, block_on};
use anyhow::{Context, Result, anyhow};
use naadf_client::Mode;
use naadf_client::gpu::Headless;
use naadf_client::node::{NodeHealth, RenderNode};
use naadf_client::{FrameImage, FrameSpec, NodeInfo};
use naadf_world::World;
use std::net::SocketAddr;
use std::sync::Arc;

/// Arguments of `render-node`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    server: ServerArgs,
    /// Largest frame this node renders.
    #[arg(long, default_value = "4096x4096", value_parser = parse_image_size)]
    max_size: (u32, u32),
    /// Modes this node renders (comma-separated).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "albedo,material,normal,steps,pathtrace,baseline,gi,roma,irradiance"
    )]
    modes: Vec<String>,
    /// Seconds between reconnection attempts.
    #[arg(long, default_value_t = 1.0)]
    retry: f64,
    /// Serve `GET /health` on this address: 200 while the node is registered with its
    /// server, 503 while it reconnects (JSON either way; no token needed). Off by default.
    #[arg(long, value_name = "ADDR")]
    http: Option<SocketAddr>,
}

/// Runs the node until Ctrl-C.
pub fn run(a: Args) -> Result<()> {
    let modes = a
        .modes
        .iter()
        .map(|m| Mode::parse(m).ok_or_else(|| anyhow!("unknown mode '{m}'")))
        .collect::<Result<_>>()?;
    let retry = super::seconds(a.retry, "--retry")?;
    let mut headless = Headless::new()?;
    // A long-lived node: a world that gains or loses its instances should not stall a
    // frame on compiles.
    headless.gpu.prepare_instance_variants();
    let info = NodeInfo {
        adapter: headless.gpu.describe(),
        modes,
        max_size: a.max_size,
    };
    let render = move |world: &World, spec: &FrameSpec| render_frame(&mut headless, world, spec);
    let adapter = info.adapter.clone();
    let mut node = RenderNode::new(a.server.address(), info, retry, render);
    let health = node.health();
    block_on(async {
        if let Some(addr) = a.http {
            let listener = tokio::net::TcpListener::bind(addr)
                .await
                .with_context(|| format!("cannot listen on {addr} (--http)"))?;
            tracing::info!("health on http://{}/health", listener.local_addr()?);
            let app = axum::Router::new().route("/health", axum::routing::get(move || report(health, adapter)));
            tokio::spawn(async move {
                if let Err(e) = axum::serve(listener, app).await {
                    tracing::error!("the health endpoint stopped: {e}");
                }
            });
        }
        node.run(async {
            let _ = tokio::signal::ctrl_c().await;
        })
        .await;
        Ok(())
    })
}

/// `GET /health`: the node's state, 200 while it is registered with its server.
async fn report(health: Arc<NodeHealth>, adapter: String) -> impl axum::response::IntoResponse {
    let registered = health.registered();
    let code = if registered {
        axum::http::StatusCode::OK
    } else {
        axum::http::StatusCode::SERVICE_UNAVAILABLE
    };
    let body = serde_json::json!({
        "status": if registered { "ok" } else { "unavailable" },
        "registered": registered,
        "adapter": adapter,
        "version": health.version(),
        "frames": health.frames(),
        "failed": health.failed(),
    });
    (code, axum::Json(body))
}

/// Renders one job's frame, PNG unless raw RGBA was asked for.
fn render_frame(headless: &mut Headless, world: &World, spec: &FrameSpec) -> Result<FrameImage> {
    let frame = headless.render_spec(world, spec)?;
    let (width, height) = (frame.width, frame.height);
    let data = if spec.raw { frame.rgba } else { frame.png()? };
    Ok(FrameImage { width, height, data })
}

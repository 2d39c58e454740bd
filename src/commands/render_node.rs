//! `naadf render-node --server URL --token T [--max-size WxH] [--modes ...]`: a headless
//! render node. It follows the world as a GPU mirror (its own `Join`), registers with the
//! server (`RegisterNode`), and renders each job the server routes to it at a version no
//! older than the job's `min_version` — the quiescent state of that version, so that a
//! node's frame equals `naadf render --world` of the same world byte for byte. It
//! reconnects and registers again by itself when the server goes away.

use super::remote::{ServerArgs, block_on, status_error};
use super::render::parse_image_size;
use anyhow::{Result, anyhow};
use naadf_client::Mirror;
use naadf_client::gpu::{Headless, Mode};
use naadf_proto::v1::{FrameJob, FrameResult, NodeHello, NodeMessage, node_message};
use naadf_server::render_router::DEFAULT_DEADLINE;
use naadf_world::World;
use naadf_world::camera::Camera;
use std::time::{Duration, Instant};
use tokio::sync::mpsc;
use tokio_stream::wrappers::ReceiverStream;

/// Arguments of `render-node`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    server: ServerArgs,
    /// Largest frame this node renders.
    #[arg(long, default_value = "4096x4096", value_parser = parse_image_size)]
    max_size: (u32, u32),
    /// Modes this node renders (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "albedo,material,normal,steps")]
    modes: Vec<String>,
    /// Seconds between reconnection attempts.
    #[arg(long, default_value_t = 1.0)]
    retry: f64,
}

/// Runs the node until Ctrl-C.
pub fn run(a: Args) -> Result<()> {
    for m in &a.modes {
        Mode::parse(m).ok_or_else(|| anyhow!("unknown mode '{m}'"))?;
    }
    let retry = super::seconds(a.retry, "--retry")?;
    let mut headless = Headless::new()?;
    let hello = NodeHello {
        adapter: headless.gpu.describe(),
        modes: a.modes.clone(),
        max_width: a.max_size.0,
        max_height: a.max_size.1,
    };
    block_on(async {
        // The last mirrored world survives reconnections: a rejoin sends only what changed.
        let mut cache: Option<World> = None;
        loop {
            tokio::select! {
                r = session(&a.server, &hello, &mut headless, &mut cache) => match r {
                    Ok(()) => tracing::warn!("the server closed the connection; reconnecting"),
                    Err(e) => tracing::warn!("render node session ended: {e:#}; reconnecting"),
                },
                _ = tokio::signal::ctrl_c() => return Ok(()),
            }
            tokio::time::sleep(retry).await;
        }
    })
}

/// One connection: join, register, serve jobs until either stream ends.
async fn session(
    server: &ServerArgs,
    hello: &NodeHello,
    headless: &mut Headless,
    cache: &mut Option<World>,
) -> Result<()> {
    let mut client = server.connect().await?;
    let mut mirror = Mirror::new(cache.take());
    let joined = client.join(mirror.join_request()).await;
    let mut world_stream = match joined {
        Ok(s) => s.into_inner(),
        Err(s) => {
            *cache = mirror.into_world();
            return Err(status_error(s));
        }
    };
    let (out, rx) = mpsc::channel(16);
    out.send(NodeMessage {
        kind: Some(node_message::Kind::Hello(hello.clone())),
    })
    .await?;
    let registered = client.register_node(ReceiverStream::new(rx)).await;
    let mut jobs = match registered {
        Ok(s) => s.into_inner(),
        Err(s) => {
            *cache = mirror.into_world();
            return Err(status_error(s));
        }
    };
    tracing::info!(adapter = %hello.adapter, "registered as a render node");
    // Jobs waiting for the mirror to reach their version, with when they came.
    let mut waiting: Vec<(Instant, FrameJob)> = Vec::new();
    let result = loop {
        tokio::select! {
            m = world_stream.message() => match m {
                Ok(Some(m)) => {
                    if let Err(e) = mirror.handle(&m) {
                        break Err(e.into());
                    }
                }
                Ok(None) => break Ok(()),
                Err(s) => break Err(status_error(s)),
            },
            j = jobs.message() => match j {
                Ok(Some(j)) => waiting.push((Instant::now(), j)),
                Ok(None) => break Ok(()),
                Err(s) => break Err(status_error(s)),
            },
        }
        // A job past its deadline has been given up by the server: drop it (also while
        // the world is not quiescent, so that waiting jobs cannot pile up).
        waiting.retain(|(since, j)| since.elapsed() < deadline_of(j));
        // Serve every job whose version the quiescent mirror has reached.
        let Some(world) = mirror.world().filter(|_| mirror.is_live() && mirror.is_quiescent()) else {
            continue;
        };
        let (ready, later): (Vec<_>, Vec<_>) = waiting
            .drain(..)
            .partition(|(_, j)| j.request.as_ref().is_none_or(|r| r.min_version <= world.version()));
        waiting = later;
        for (_, job) in ready {
            let result = render_job(headless, world, &job);
            if out
                .send(NodeMessage {
                    kind: Some(node_message::Kind::Result(result)),
                })
                .await
                .is_err()
            {
                break;
            }
        }
    };
    *cache = mirror.into_world();
    result
}

/// How long the server waits for `job`.
fn deadline_of(job: &FrameJob) -> Duration {
    match job.request.as_ref().map_or(0, |r| r.timeout_ms) {
        0 => DEFAULT_DEADLINE,
        ms => Duration::from_millis(u64::from(ms)),
    }
}

/// Renders one job; a job the node cannot render becomes an error result, not a failure
/// of the node.
fn render_job(headless: &mut Headless, world: &World, job: &FrameJob) -> FrameResult {
    let mut attempt = || -> Result<FrameResult> {
        let req = job.request.as_ref().ok_or_else(|| anyhow!("the job has no request"))?;
        let camera = Camera::from_json(&req.camera)?;
        let mode = Mode::parse(&req.mode).ok_or_else(|| anyhow!("unknown mode '{}'", req.mode))?;
        let frame = headless.frame(world, &camera, (req.width, req.height), mode, false)?;
        let image = if req.raw { frame.rgba.clone() } else { frame.png()? };
        Ok(FrameResult {
            id: job.id,
            version: world.version(),
            width: frame.width,
            height: frame.height,
            image,
            error: String::new(),
        })
    };
    attempt().unwrap_or_else(|e| FrameResult {
        id: job.id,
        error: format!("{e:#}"),
        ..FrameResult::default()
    })
}

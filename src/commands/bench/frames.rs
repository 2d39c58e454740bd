//! `naadf bench frames --server URL [--world FILE]`: frames per second and latency of
//! `RenderFrame` through the server's render nodes, with `--concurrency` requests in
//! flight; with `--world`, the same frame rendered in-process (GPU, readback, PNG — what a
//! node does per job) for the server's added latency.

use super::shared::Latency;
use crate::commands::args::{parse_image_size, parse_mode, read_camera};
use crate::commands::remote::{ServerArgs, block_on};
use crate::commands::{load_world, print_json};
use anyhow::Result;
use naadf_client::FrameSpec;
use naadf_client::Mode;
use naadf_client::gpu::Headless;
use naadf_world::raysets::fixed_cameras;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `bench frames`.
#[derive(clap::Args)]
pub struct FramesArgs {
    #[command(flatten)]
    server: ServerArgs,
    /// Frames to request.
    #[arg(long, default_value_t = 100)]
    frames: u32,
    /// Requests in flight at once.
    #[arg(long, default_value_t = 2)]
    concurrency: u32,
    /// Frame size.
    #[arg(long, default_value = "320x240", value_parser = parse_image_size)]
    size: (u32, u32),
    /// Render mode.
    #[arg(long, default_value = "albedo", value_parser = parse_mode)]
    mode: Mode,
    /// Camera JSON (default: the first benchmark camera of `--world`, or a fixed view).
    #[arg(long)]
    camera: Option<String>,
    /// The server's world file: also render in-process for the routing overhead.
    #[arg(long)]
    world: Option<PathBuf>,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Report {
    frames: u32,
    concurrency: u32,
    fps: f64,
    latency_ms: Latency,
    /// In-process frames (same size, mode and camera), when `--world` was given.
    #[serde(skip_serializing_if = "Option::is_none")]
    in_process_ms: Option<Latency>,
    /// p50 through the server minus p50 in-process (with one request in flight this is
    /// the routing overhead).
    #[serde(skip_serializing_if = "Option::is_none")]
    added_p50_ms: Option<f64>,
    nodes: Vec<String>,
}

/// Runs `bench frames`.
pub fn run(a: FramesArgs) -> Result<()> {
    let world = a.world.as_deref().map(load_world).transpose()?;
    let camera = match (&a.camera, &world) {
        (Some(c), _) => read_camera(c)?,
        (None, Some(w)) => fixed_cameras(w.size())[0],
        (None, None) => read_camera(r#"{"pos":[64,80,-40],"yaw":0,"pitch":-30}"#)?,
    };
    let spec = FrameSpec::new(camera, a.size, a.mode);
    let (fps, ms, nodes) = block_on(async {
        let client = a.server.connect().await?;
        // One untimed frame: pipelines are built on every node's first frame.
        client.frame(&spec).await?;
        let t0 = Instant::now();
        let per_task = a.frames.div_ceil(a.concurrency.max(1));
        let mut tasks = Vec::new();
        for _ in 0..a.concurrency.max(1) {
            let (c, spec) = (client.clone(), spec.clone());
            tasks.push(tokio::spawn(async move {
                let mut out = Vec::new();
                for _ in 0..per_task {
                    let t = Instant::now();
                    let r = c.frame(&spec).await?;
                    out.push((t.elapsed().as_secs_f64() * 1e3, r.node));
                }
                anyhow::Ok(out)
            }));
        }
        let mut ms = Vec::new();
        let mut nodes = Vec::new();
        for t in tasks {
            for (m, node) in t.await?? {
                ms.push(m);
                if !nodes.contains(&node) {
                    nodes.push(node);
                }
            }
        }
        let fps = ms.len() as f64 / t0.elapsed().as_secs_f64();
        anyhow::Ok((fps, ms, nodes))
    })?;
    let frames = ms.len() as u32;
    let latency = Latency::of(ms);
    let in_process = match &world {
        Some(w) => {
            let mut h = Headless::new()?;
            h.frame(w, &camera, a.size, a.mode, false)?.png()?;
            let mut ms = Vec::new();
            for _ in 0..frames.min(50) {
                let t = Instant::now();
                h.frame(w, &camera, a.size, a.mode, false)?.png()?;
                ms.push(t.elapsed().as_secs_f64() * 1e3);
            }
            Some(Latency::of(ms))
        }
        None => None,
    };
    let report = Report {
        frames,
        concurrency: a.concurrency,
        fps,
        added_p50_ms: in_process.as_ref().map(|l| latency.p50 - l.p50),
        latency_ms: latency,
        in_process_ms: in_process,
        nodes,
    };
    if a.json {
        print_json(&report)?;
    } else {
        println!(
            "{} frames, {} in flight: {:.1} frames/s, latency p50 {:.1} ms, p99 {:.1} ms ({} node(s))",
            report.frames,
            report.concurrency,
            report.fps,
            report.latency_ms.p50,
            report.latency_ms.p99,
            report.nodes.len()
        );
        if let (Some(l), Some(d)) = (&report.in_process_ms, report.added_p50_ms) {
            println!(
                "in-process p50 {:.1} ms, p99 {:.1} ms; added by the server at p50: {d:.1} ms",
                l.p50, l.p99
            );
        }
    }
    Ok(())
}

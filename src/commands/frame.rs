//! `naadf frame --server URL --camera JSON [--size WxH] [--mode M] [--min-version N] -o OUT.png`:
//! asks the server for a frame, which one of its render nodes renders.

use super::args::{LightArgs, parse_image_size, parse_mode, read_camera};
use super::print_json;
use super::remote::{ServerArgs, block_on};
use anyhow::{Context, Result};
use naadf_client::FrameSpec;
use naadf_client::light::LitOptions;
use std::path::PathBuf;
use std::time::Duration;

/// Arguments of `frame`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    server: ServerArgs,
    /// Camera JSON `{"pos":[x,y,z],"yaw":deg,"pitch":deg,"fov_y":deg}`, or a file holding it.
    #[arg(long)]
    camera: String,
    /// Image size `WxH`.
    #[arg(long, default_value = "1280x720", value_parser = parse_image_size)]
    size: (u32, u32),
    /// What to show: albedo, material, normal, steps, pathtrace, baseline, gi, roma or
    /// irradiance.
    #[arg(long, default_value = "albedo", value_parser = parse_mode)]
    mode: naadf_client::Mode,
    #[command(flatten)]
    light: LightArgs,
    /// Frames of a temporal mode (baseline, gi, roma, irradiance) the node renders before
    /// answering, continuing the stream's history.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    frames: u32,
    /// Names this requester's camera stream: its frames go to one node, which keeps the
    /// stream's histories (baseline, gi, roma, irradiance) and sums (pathtrace) between
    /// requests.
    #[arg(long, default_value = "")]
    stream: String,
    /// The oldest world version the frame may show.
    #[arg(long, default_value_t = 0)]
    min_version: u64,
    /// Deadline in milliseconds (0: the server's default).
    #[arg(long, default_value_t = 0)]
    timeout_ms: u32,
    /// PNG file to write.
    #[arg(short, long)]
    output: PathBuf,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    json: bool,
}

#[derive(serde::Serialize)]
struct Summary {
    version: u64,
    width: u32,
    height: u32,
    node: String,
    bytes: usize,
}

/// Requests the frame and writes it.
pub fn run(a: Args) -> Result<()> {
    let spec = FrameSpec {
        min_version: a.min_version,
        timeout: (a.timeout_ms != 0).then(|| Duration::from_millis(u64::from(a.timeout_ms))),
        lit: LitOptions {
            frames: a.frames,
            stream: a.stream.clone(),
            ..a.light.options()?
        },
        ..FrameSpec::new(read_camera(&a.camera)?, a.size, a.mode)
    };
    let reply = block_on(async { Ok(a.server.connect().await?.frame(&spec).await?) })?;
    let image = &reply.image;
    std::fs::write(&a.output, &image.data).with_context(|| format!("cannot write {}", a.output.display()))?;
    if a.json {
        print_json(&Summary {
            version: reply.version,
            width: image.width,
            height: image.height,
            node: reply.node,
            bytes: image.data.len(),
        })?;
    }
    Ok(())
}

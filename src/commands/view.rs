//! `naadf view --server URL [--token T]`: the interactive viewer (docs/RENDERING.md).

use super::args::{parse_image_size, parse_mode, read_camera};
use super::remote::ServerArgs;
use super::{print_json, seconds};
use anyhow::Result;
use naadf_client::Mode;
use naadf_client::viewer::ViewerOptions;
use std::path::PathBuf;

/// Arguments of `view`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    server: ServerArgs,
    /// Window size `WxH`.
    #[arg(long, default_value = "1280x720", value_parser = parse_image_size)]
    size: (u32, u32),
    /// Starting camera (JSON or a file holding it); by default a view over the world.
    #[arg(long)]
    camera: Option<String>,
    /// Render mode (M cycles through them in the window); `gi` falls back to albedo on an
    /// adapter that cannot run it.
    #[arg(long, default_value = "gi", value_parser = parse_mode)]
    mode: Mode,
    /// Flying speed in voxels per second (by default an eighth of the world's width).
    #[arg(long)]
    speed: Option<f64>,
    /// Quit after this many frames of the world.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    frames: Option<u32>,
    /// Write the last frame (with the HUD) here as PNG; needs `--frames`.
    #[arg(long, requires = "frames")]
    screenshot: Option<PathBuf>,
    /// Seconds to wait for the server's world before giving up.
    #[arg(long, default_value_t = 60.0)]
    timeout: f64,
    /// Print a JSON summary on stdout when the window closes.
    #[arg(long)]
    json: bool,
}

/// Runs the viewer.
pub fn run(a: Args) -> Result<()> {
    let summary = naadf_client::viewer::run(ViewerOptions {
        server: a.server.address(),
        size: a.size,
        camera: a.camera.as_deref().map(read_camera).transpose()?,
        mode: a.mode,
        speed: a.speed,
        frames: a.frames,
        screenshot: a.screenshot,
        timeout: seconds(a.timeout, "--timeout")?,
    })?;
    if a.json {
        print_json(&summary)?;
    }
    Ok(())
}

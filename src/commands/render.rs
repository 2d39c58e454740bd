//! `naadf render (--world FILE | --server URL) --camera JSON --size WxH --mode M
//! [--frames N] -o OUT.png [--gbuffer OUT.bin]`

use super::remote::{ServerArgs, block_on, quiescent_world};
use super::{load_world, print_json, seconds};
use anyhow::{Context, Result};
use naadf_client::FrameSpec;
use naadf_client::gpu::{Headless, Mode, write_gbuffer};
use naadf_world::camera::Camera;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `render`.
#[derive(clap::Args)]
pub struct Args {
    /// World file to render (instead of a server's world; takes precedence over
    /// `--server` and `NAADF_SERVER`).
    #[arg(long)]
    world: Option<PathBuf>,
    #[command(flatten)]
    server: ServerArgs,
    #[command(flatten)]
    view: ViewArgs,
    /// Frames to render (all identical: the modes are deterministic); the last is written.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    frames: u32,
    /// PNG file to write.
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the first-hit buffer (the reference's `firstHitData`; docs/RENDERING.md).
    #[arg(long)]
    gbuffer: Option<PathBuf>,
    /// Seconds to wait for a server's world to become quiescent.
    #[arg(long, default_value_t = 60.0)]
    timeout: f64,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    json: bool,
}

/// What a frame shows: camera, size and mode (`render`, `frame`).
#[derive(clap::Args)]
pub struct ViewArgs {
    /// Camera JSON `{"pos":[x,y,z],"yaw":deg,"pitch":deg,"fov_y":deg}`, or a file holding it.
    #[arg(long)]
    pub camera: String,
    /// Image size `WxH`.
    #[arg(long, default_value = "1280x720", value_parser = parse_image_size)]
    pub size: (u32, u32),
    /// What to show.
    #[arg(long, default_value = "albedo", value_parser = parse_mode)]
    pub mode: Mode,
}

impl ViewArgs {
    /// The frame these arguments ask for (PNG, of any version, the server's default
    /// deadline).
    pub fn spec(&self) -> Result<FrameSpec> {
        Ok(FrameSpec::new(read_camera(&self.camera)?, self.size, self.mode))
    }
}

/// Parses `WxH`.
pub fn parse_image_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or("expected WxH, e.g. 1280x720")?;
    let p = |v: &str| v.trim().parse::<u32>().map_err(|e| format!("'{v}': {e}"));
    Ok((p(w)?, p(h)?))
}

/// Parses a render mode name.
pub fn parse_mode(s: &str) -> Result<Mode, String> {
    Mode::parse(s).ok_or_else(|| {
        let names: Vec<_> = Mode::ALL.iter().map(|m| m.name()).collect();
        format!("unknown mode '{s}' (one of: {})", names.join(", "))
    })
}

/// Reads a camera given inline or as a file.
pub fn read_camera(arg: &str) -> Result<Camera> {
    let text = if arg.trim_start().starts_with('{') {
        arg.to_owned()
    } else {
        std::fs::read_to_string(arg).with_context(|| format!("cannot read camera file {arg}"))?
    };
    Ok(Camera::from_json(&text)?)
}

#[derive(serde::Serialize)]
struct Summary {
    width: u32,
    height: u32,
    mode: &'static str,
    version: u64,
    digest: String,
    adapter: String,
    frames: u32,
    /// Mean milliseconds per frame (dispatch and readback).
    frame_ms: f64,
}

/// Renders and writes the image.
pub fn run(a: Args) -> Result<()> {
    let camera = read_camera(&a.view.camera)?;
    let world = match &a.world {
        Some(path) => load_world(path)?,
        None => block_on(quiescent_world(&a.server, None, 0, seconds(a.timeout, "--timeout")?))?,
    };
    let mut headless = Headless::new()?;
    let want_gbuffer = a.gbuffer.is_some();
    // The first frame uploads the world and builds the pipeline; time the rest.
    let (size, mode) = (a.view.size, a.view.mode);
    let mut frame = headless.frame(&world, &camera, size, mode, want_gbuffer)?;
    let t0 = Instant::now();
    for _ in 1..a.frames {
        frame = headless.frame(&world, &camera, size, mode, want_gbuffer)?;
    }
    let frame_ms = if a.frames > 1 {
        t0.elapsed().as_secs_f64() * 1e3 / f64::from(a.frames - 1)
    } else {
        f64::NAN
    };
    let png = frame.png()?;
    std::fs::write(&a.output, png).with_context(|| format!("cannot write {}", a.output.display()))?;
    if let (Some(path), Some(words)) = (&a.gbuffer, &frame.gbuffer) {
        let mut out = std::io::BufWriter::new(
            std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?,
        );
        write_gbuffer(&mut out, frame.width, frame.height, words)
            .and_then(|()| std::io::Write::flush(&mut out))
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    if a.json {
        print_json(&Summary {
            width: frame.width,
            height: frame.height,
            mode: mode.name(),
            version: world.version(),
            digest: world.digest().to_string(),
            adapter: headless.gpu.describe(),
            frames: a.frames,
            frame_ms: if frame_ms.is_nan() { 0.0 } else { frame_ms },
        })?;
    }
    Ok(())
}

//! `naadf render (--world FILE | --server URL) --camera JSON --size WxH --mode M
//! [--frames N] -o OUT.png [--gbuffer OUT.bin]`; for `--mode pathtrace`
//! `[--spp N] [--seed S] [--bounces B] [--sky SKY] [--sun SUN] [--exposure X] [--hdr OUT.pfm]`;
//! for `--mode baseline`, `--mode gi`, `--mode roma` and `--mode irradiance` the same
//! without `--spp`, with `--frames N` and `[--camera-path FILE.jsonl]`; for `--mode roma`
//! also `[--roma-directions K] [--ao-range VOXELS]`, for `--mode irradiance` also
//! `[--irradiance-rays N]`.

use super::args::{LightArgs, parse_image_size, parse_mode, read_camera};
use super::remote::{ServerArgs, block_on, quiescent_world};
use super::{load_world, print_json, progress, seconds};
use anyhow::{Context, Result, bail};
use naadf_client::frame::write_gbuffer;
use naadf_client::gpu::{Headless, Shot};
use naadf_client::light::hdr::Radiance;
use naadf_client::light::{DEFAULT_LIT_BOUNCES, DEFAULT_PATHTRACE_BOUNCES, Light, LitOptions};
use naadf_client::{Frame, Mode};
use naadf_world::World;
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
    /// Camera JSON `{"pos":[x,y,z],"yaw":deg,"pitch":deg,"fov_y":deg}`, or a file holding it.
    #[arg(long, required_unless_present = "camera_path")]
    camera: Option<String>,
    /// A camera per line (JSON Lines); frame i uses line min(i, last) (baseline, gi, roma,
    /// irradiance).
    #[arg(long, conflicts_with = "camera")]
    camera_path: Option<PathBuf>,
    /// Image size `WxH`.
    #[arg(long, default_value = "1280x720", value_parser = parse_image_size)]
    size: (u32, u32),
    /// What to show: albedo, material, normal, steps, pathtrace (the light model,
    /// path-traced), baseline (1-spp path tracing with an exponential TAA), gi (the
    /// paper's GI pipeline), roma (ROMA visibility for ambient occlusion and sun shadows) or
    /// irradiance (a world-space irradiance cache).
    #[arg(long, default_value = "albedo", value_parser = parse_mode)]
    mode: Mode,
    /// Frames to render; the last is written. All identical in the render-pass modes; for
    /// baseline, gi, roma and irradiance, each builds on the history. Not for pathtrace, which
    /// takes --spp.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    frames: Option<u32>,
    #[command(flatten)]
    light: LightArgs,
    /// Also write the linear radiance before exposure and tone mapping (lit modes): PFM, or
    /// OpenEXR for a name ending in `.exr`.
    #[arg(long)]
    hdr: Option<PathBuf>,
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

/// What `run` does, decided from the arguments before any work.
enum Job {
    /// Frames of the render pass.
    Frame(Mode),
    /// A path-traced frame, or frames of a temporal mode: the options and the light.
    Lit(LitOptions, Light),
}

/// Reads a camera path: one camera JSON per non-blank line, at least one.
pub fn read_camera_path(path: &std::path::Path) -> Result<Vec<Camera>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read camera path {}", path.display()))?;
    let cameras = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| Camera::from_json(l).with_context(|| format!("{} line {}", path.display(), i + 1)))
        .collect::<Result<Vec<_>>>()?;
    if cameras.is_empty() {
        bail!("camera path {} holds no camera", path.display());
    }
    Ok(cameras)
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
    /// Samples per pixel (pathtrace).
    #[serde(skip_serializing_if = "Option::is_none")]
    spp: Option<u32>,
    /// Seconds the samples took (pathtrace).
    #[serde(skip_serializing_if = "Option::is_none")]
    seconds: Option<f64>,
}

/// Renders and writes the image.
pub fn run(a: Args) -> Result<()> {
    // Refuse what the mode would ignore before any work: another lit mode's options, and
    // below what only some lit modes take.
    if a.mode.is_lit()
        && let Some(flag) = a.light.foreign_to(a.mode)
    {
        bail!("{flag} does not apply to --mode {}", a.mode.name());
    }
    let job = match a.mode {
        Mode::PathTrace => {
            if a.frames.is_some() {
                bail!("--frames does not apply to pathtrace: give the samples per pixel with --spp");
            }
            refuse_for(&a, &["--gbuffer", "--camera-path"])?;
            let options = a.light.options()?;
            let light = options.light(DEFAULT_PATHTRACE_BOUNCES).map_err(anyhow::Error::msg)?;
            Job::Lit(options, light)
        }
        mode if mode.is_temporal() => {
            refuse_for(&a, &["--gbuffer", "--spp"])?;
            let options = LitOptions {
                frames: a.frames.unwrap_or(1),
                ..a.light.options()?
            };
            let light = options.light(DEFAULT_LIT_BOUNCES).map_err(anyhow::Error::msg)?;
            Job::Lit(options, light)
        }
        mode => {
            let mut lit = a.light.given();
            lit.extend(a.hdr.as_ref().map(|_| "--hdr"));
            lit.extend(a.camera_path.as_ref().map(|_| "--camera-path"));
            if let Some(flag) = lit.first() {
                bail!("{flag} applies to the lit modes only, not to --mode {}", mode.name());
            }
            Job::Frame(mode)
        }
    };
    let cameras = match (&a.camera, &a.camera_path) {
        (Some(c), _) => vec![read_camera(c)?],
        (None, Some(path)) => read_camera_path(path)?,
        (None, None) => bail!("give --camera or --camera-path"),
    };
    let world = match &a.world {
        Some(path) => load_world(path)?,
        None => block_on(quiescent_world(&a.server, None, 0, seconds(a.timeout, "--timeout")?))?,
    };
    let mut headless = Headless::new()?;
    let (frame, summary) = match &job {
        Job::Frame(mode) => render_frames(&mut headless, &world, &cameras[0], &a, *mode)?,
        Job::Lit(options, light) if a.mode == Mode::PathTrace => {
            path_trace(&mut headless, &world, &cameras[0], &a, options, light)?
        }
        Job::Lit(options, light) => temporal(&mut headless, &world, &cameras, &a, options, light)?,
    };
    let png = frame.png()?;
    std::fs::write(&a.output, png).with_context(|| format!("cannot write {}", a.output.display()))?;
    if a.json {
        print_json(&summary)?;
    }
    Ok(())
}

/// Fails if one of `flags` (among `--gbuffer`, `--spp`, `--camera-path`) was given.
fn refuse_for(a: &Args, flags: &[&str]) -> Result<()> {
    let given = |f: &str| match f {
        "--gbuffer" => a.gbuffer.is_some(),
        "--spp" => a.light.given().contains(&"--spp"),
        _ => a.camera_path.is_some(),
    };
    match flags.iter().find(|f| given(f)) {
        Some(f) => bail!("{f} does not apply to --mode {}", a.mode.name()),
        None => Ok(()),
    }
}

/// Renders `--frames` frames of the render pass; writes the first-hit buffer if asked.
fn render_frames(
    headless: &mut Headless,
    world: &World,
    camera: &Camera,
    a: &Args,
    mode: Mode,
) -> Result<(Frame, Summary)> {
    let frames = a.frames.unwrap_or(1);
    let want_gbuffer = a.gbuffer.is_some();
    let size = a.size;
    // The first frame uploads the world and builds the pipeline; time the rest.
    let mut frame = headless.frame(world, camera, size, mode, want_gbuffer)?;
    let t0 = Instant::now();
    for _ in 1..frames {
        frame = headless.frame(world, camera, size, mode, want_gbuffer)?;
    }
    let frame_ms = if frames > 1 {
        t0.elapsed().as_secs_f64() * 1e3 / f64::from(frames - 1)
    } else {
        0.0
    };
    if let (Some(path), Some(words)) = (&a.gbuffer, &frame.gbuffer) {
        let mut out = std::io::BufWriter::new(
            std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?,
        );
        write_gbuffer(&mut out, frame.width, frame.height, words)
            .and_then(|()| std::io::Write::flush(&mut out))
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    let summary = summary(headless, world, &frame, mode.name(), frames, frame_ms);
    Ok((frame, summary))
}

/// Path-traces `--spp` samples per pixel with a progress bar; writes the radiance if asked.
fn path_trace(
    headless: &mut Headless,
    world: &World,
    camera: &Camera,
    a: &Args,
    s: &LitOptions,
    light: &Light,
) -> Result<(Frame, Summary)> {
    let bar = progress(u64::from(s.spp), "path tracing", "spp");
    let t0 = Instant::now();
    let radiance = headless.path_trace(world, &Shot::new(*camera, a.size, *light, s.seed), s.spp, &mut |n| {
        bar.set_position(u64::from(n))
    })?;
    bar.finish_and_clear();
    let secs = t0.elapsed().as_secs_f64();
    let (frame, mut summary) = lit_output(headless, world, a, s, &radiance, 1, secs * 1e3)?;
    summary.spp = Some(s.spp);
    summary.seconds = Some(secs);
    Ok((frame, summary))
}

/// Renders `--frames` frames of a temporal mode (`baseline`, `gi`, `roma`, `irradiance`) along
/// the camera path; writes the last.
fn temporal(
    headless: &mut Headless,
    world: &World,
    cameras: &[Camera],
    a: &Args,
    s: &LitOptions,
    light: &Light,
) -> Result<(Frame, Summary)> {
    let frames = s.frames;
    let bar = progress(u64::from(frames), a.mode.name(), "frames");
    let t0 = Instant::now();
    for i in 0..frames {
        let camera = &cameras[(i as usize).min(cameras.len() - 1)];
        headless.temporal_frame(a.mode, world, &Shot::new(*camera, a.size, *light, s.seed))?;
        bar.set_position(u64::from(i + 1));
    }
    let radiance = headless.temporal_radiance(a.mode)?;
    bar.finish_and_clear();
    let frame_ms = t0.elapsed().as_secs_f64() * 1e3 / f64::from(frames);
    lit_output(headless, world, a, s, &radiance, frames, frame_ms)
}

/// Writes `--hdr` and tone-maps the radiance of a lit mode.
fn lit_output(
    headless: &Headless,
    world: &World,
    a: &Args,
    s: &LitOptions,
    radiance: &Radiance,
    frames: u32,
    frame_ms: f64,
) -> Result<(Frame, Summary)> {
    if let Some(path) = &a.hdr {
        radiance.save(path).map_err(anyhow::Error::msg)?;
    }
    let frame = radiance.tone_mapped(s.exposure);
    let summary = summary(headless, world, &frame, a.mode.name(), frames, frame_ms);
    Ok((frame, summary))
}

fn summary(
    headless: &Headless,
    world: &World,
    frame: &Frame,
    mode: &'static str,
    frames: u32,
    frame_ms: f64,
) -> Summary {
    Summary {
        width: frame.width,
        height: frame.height,
        mode,
        version: world.version(),
        digest: world.digest().to_string(),
        adapter: headless.gpu.describe(),
        frames,
        frame_ms,
        spp: None,
        seconds: None,
    }
}

//! `naadf bench gi WORLD`: the image quality of the lit modes against a path-traced
//! reference (docs/RENDERING.md §3a–b): after `--frames` frames of each mode, FLIP, relative
//! MSE and the mean-luminance bias against a `--reference-spp` path-traced image; and the
//! noise floor, the same figures between two references of different seeds. The modes
//! measured are those built so far: `baseline` (the GI pipeline joins it when it lands).

use crate::commands::load_world;
use crate::commands::print_json;
use crate::commands::progress;
use crate::commands::render::{LightArgs, parse_image_size, read_camera};
use anyhow::{Context, Result, bail};
use naadf_client::gpu::Headless;
use naadf_client::light::DEFAULT_LIT_BOUNCES;
use naadf_client::light::hdr::Radiance;
use naadf_client::light::quality::Quality;
use naadf_world::raysets::fixed_cameras;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `bench gi`.
#[derive(clap::Args)]
pub struct GiArgs {
    /// World file.
    world: PathBuf,
    /// Camera JSON (default: the world's first benchmark camera).
    #[arg(long)]
    camera: Option<String>,
    /// Image size.
    #[arg(long, default_value = "256x144", value_parser = parse_image_size)]
    size: (u32, u32),
    /// Samples per pixel of each reference.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..))]
    reference_spp: u32,
    /// After how many frames each mode is measured (comma-separated, increasing).
    #[arg(long, value_delimiter = ',', default_value = "8,32,64")]
    frames: Vec<u32>,
    /// The light (not `--spp`: the references take `--reference-spp`). Bounces default to
    /// 3, as in the compared modes.
    #[command(flatten)]
    light: LightArgs,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Report {
    size: [u32; 2],
    reference_spp: u32,
    bounces: u32,
    /// Seconds one reference took.
    reference_seconds: f64,
    /// Two references of different seeds against each other.
    noise_floor: Quality,
    /// Mode → frames → quality against the first reference.
    modes: BTreeMap<&'static str, BTreeMap<u32, Quality>>,
    /// Mode → milliseconds per frame.
    frame_ms: BTreeMap<&'static str, f64>,
}

/// Runs the benchmark.
pub fn run(a: GiArgs) -> Result<()> {
    if a.frames.is_empty() || a.frames.contains(&0) || !a.frames.is_sorted() {
        bail!("--frames: give increasing frame counts, each at least 1");
    }
    if a.light.given().contains(&"--spp") {
        bail!("--spp does not apply to bench gi: the references take --reference-spp");
    }
    let world = load_world(&a.world)?;
    let camera = match &a.camera {
        Some(c) => read_camera(c)?,
        None => *fixed_cameras(world.size())
            .first()
            .context("the world has no benchmark camera")?,
    };
    let options = a.light.options()?;
    let light = options.light(DEFAULT_LIT_BOUNCES).map_err(anyhow::Error::msg)?;
    let mut headless = Headless::new()?;
    let last = *a.frames.last().expect("checked above");
    let bar = progress(u64::from(2 * a.reference_spp + last), "bench gi", "steps");

    let mut reference = |seed: u32, done: u64| -> Result<_> {
        let t0 = Instant::now();
        let img = headless.path_trace(&world, &camera, a.size, &light, seed, a.reference_spp, &mut |n| {
            bar.set_position(done + u64::from(n))
        })?;
        Ok((img, t0.elapsed().as_secs_f64()))
    };
    let (ref_a, secs) = reference(options.seed.wrapping_add(1000), 0)?;
    let (ref_b, _) = reference(options.seed.wrapping_add(2000), u64::from(a.reference_spp))?;
    let measure = |img: &Radiance| Quality::measure(img, &ref_a, options.exposure).context("image sizes differ");
    let noise_floor = measure(&ref_b)?;

    let mut baseline = BTreeMap::new();
    let t0 = Instant::now();
    for frame in 1..=last {
        headless.baseline_frame(&world, &camera, a.size, &light, options.seed)?;
        bar.set_position(u64::from(2 * a.reference_spp + frame));
        if a.frames.contains(&frame) {
            baseline.insert(frame, measure(&headless.baseline_radiance()?)?);
        }
    }
    let baseline_ms = t0.elapsed().as_secs_f64() * 1e3 / f64::from(last);
    bar.finish_and_clear();

    let report = Report {
        size: [a.size.0, a.size.1],
        reference_spp: a.reference_spp,
        bounces: light.bounces,
        reference_seconds: secs,
        noise_floor,
        modes: BTreeMap::from([("baseline", baseline)]),
        frame_ms: BTreeMap::from([("baseline", baseline_ms)]),
    };
    if a.json {
        return print_json(&report);
    }
    println!(
        "{}x{}, references of {} spp (B = {}, {:.1} s each)",
        a.size.0, a.size.1, a.reference_spp, light.bounces, secs
    );
    let row = |name: &str, q: &Quality| {
        println!(
            "{name:<22} FLIP {:.4}  relMSE {:.5}  bias {:+.4}",
            q.flip, q.rel_mse, q.bias
        )
    };
    row("noise floor", &report.noise_floor);
    for (mode, by_frames) in &report.modes {
        for (frames, q) in by_frames {
            row(&format!("{mode} after {frames}"), q);
        }
    }
    Ok(())
}

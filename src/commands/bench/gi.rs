//! `naadf bench gi WORLD`: the lit modes measured against the path tracer
//! (docs/RENDERING.md §3a–e, BENCHMARKS.md "Global illumination" and "Lit modes"):
//! - **static quality**: `baseline`, `gi`, `roma` and `irradiance` after `--frames`
//!   frames, FLIP, relative MSE and mean-luminance bias against a `--reference-spp`
//!   path-traced image; the noise floor is the same figures between two references of
//!   different seeds; the temporal flicker of each mode over the frames after the last;
//! - **cost**: milliseconds per frame of `albedo`, `baseline`, `gi`, `roma` and
//!   `irradiance`, timed in alternating rounds, with the ratios per round (median and
//!   range), GI's per-pass GPU times from timestamp queries where the adapter has them,
//!   GI's memory by array, ROMA's maps and the irradiance cache;
//! - **matched time**: each lit mode's quality after the frames it renders in the time 32
//!   `gi` frames take (by the timed medians);
//! - **motion**: a camera path (strafe plus yaw), FLIP against per-pose references at three
//!   poses;
//! - **edit response**: an emitter added in front of the camera, then removed; the frames
//!   until the image mean is within 10 % of the change of its converged value.

use super::face_granularity::{self, FaceGranularity};
use crate::commands::args::{LightArgs, parse_image_size, read_camera};
use crate::commands::load_world;
use crate::commands::print_json;
use crate::commands::progress;
use anyhow::{Context, Result, bail};
use naadf_client::Mode;
use naadf_client::gpu::{Baseline, Gi, GiPass, Gpu, GpuWorld, Irradiance, PathTracer, Renderer, Roma, Shot, Temporal};
use naadf_client::light::hdr::Radiance;
use naadf_client::light::irradiance::IrradianceOptions;
use naadf_client::light::quality::{Quality, flicker, mean_luminance};
use naadf_client::light::roma::RomaOptions;
use naadf_client::light::{DEFAULT_LIT_BOUNCES, Light};
use naadf_world::World;
use naadf_world::camera::Camera;
use naadf_world::ops::{Batch, Limits};
use naadf_world::raysets::content_camera;
use naadf_world::traverse::{Ray, trace_naadf};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `bench gi`.
#[derive(clap::Args)]
pub struct GiArgs {
    /// World file.
    world: PathBuf,
    /// Camera JSON (default: one that frames the world's solid content from above the front left).
    #[arg(long)]
    camera: Option<String>,
    /// Image size.
    #[arg(long, default_value = "256x144", value_parser = parse_image_size)]
    size: (u32, u32),
    /// Samples per pixel of each static reference.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..))]
    reference_spp: u32,
    /// After how many frames each mode is measured (comma-separated, increasing).
    #[arg(long, value_delimiter = ',', default_value = "8,32,64")]
    frames: Vec<u32>,
    /// Timing rounds (each times every mode once, in a rotating order).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
    rounds: u32,
    /// Frames per mode in each timing round.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..))]
    timing_frames: u32,
    /// Samples per pixel of each motion reference (0 skips the motion section).
    #[arg(long, default_value_t = 256)]
    motion_spp: u32,
    /// Skip the edit-response section.
    #[arg(long)]
    no_edit: bool,
    /// Samples per face of the irradiance cache's face-granularity measurement, on the CPU
    /// (0 skips it).
    #[arg(long, default_value_t = 0)]
    face_samples: u32,
    /// The light (not `--spp`: the references take `--reference-spp`). Bounces default to
    /// 3, as in the compared modes.
    #[command(flatten)]
    light: LightArgs,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

/// A median with its range over repeated measurements.
#[derive(Clone, Copy, Debug, Serialize)]
struct Spread {
    median: f64,
    min: f64,
    max: f64,
}

impl Spread {
    fn of(mut v: Vec<f64>) -> Spread {
        v.sort_by(f64::total_cmp);
        Spread {
            median: v[v.len() / 2],
            min: v[0],
            max: v[v.len() - 1],
        }
    }
}

#[derive(Serialize)]
struct Report {
    adapter: String,
    size: [u32; 2],
    reference_spp: u32,
    bounces: u32,
    /// Seconds one reference took.
    reference_seconds: f64,
    /// Two references of different seeds against each other.
    noise_floor: Quality,
    /// Mode → frames → quality against the first reference.
    modes: BTreeMap<&'static str, BTreeMap<u32, Quality>>,
    /// Mode → mean relative luminance change between consecutive frames after the last.
    flicker: BTreeMap<&'static str, f64>,
    /// Mode → milliseconds per frame, over the timing rounds.
    frame_ms: BTreeMap<&'static str, Spread>,
    /// gi / albedo, gi / baseline, roma / albedo, roma / gi, irradiance / albedo and
    /// irradiance / gi frame time, per round.
    ratios: BTreeMap<&'static str, Spread>,
    /// Mode → the frames it renders in the time of [`MATCHED_GI_FRAMES`] `gi` frames, and
    /// its quality after them.
    matched_time: BTreeMap<&'static str, (u32, Quality)>,
    /// ROMA's maps: their bytes, and a frame that writes every tile.
    roma_maps: RomaMaps,
    /// The irradiance cache: its bytes, a frame that starts from an empty cache, and the
    /// entry samples a frame takes.
    irradiance_cache: IrradianceCache,
    /// Voxel faces against block faces as the cache's keys (`--face-samples`).
    face_granularity: Option<FaceGranularity>,
    /// GI pass → GPU milliseconds (median over the timed frames); empty without timestamps.
    gi_pass_ms: Vec<(&'static str, f64)>,
    /// GI array → bytes.
    gi_memory: Vec<(&'static str, u64)>,
    /// Pose frame → mode → quality against that pose's reference.
    motion: BTreeMap<u32, BTreeMap<&'static str, Quality>>,
    /// Mode → (frames after adding, frames after removing) an emitter.
    edit_response: BTreeMap<&'static str, [u32; 2]>,
}

/// What ROMA's maps cost.
#[derive(Serialize)]
struct RomaMaps {
    bytes: u64,
    /// Tiles a frame without maps writes.
    first_tiles: usize,
    /// Milliseconds of that frame, read back (its pipelines built before).
    first_frame_ms: f64,
}

/// What the irradiance cache costs.
#[derive(Serialize)]
struct IrradianceCache {
    bytes: u64,
    /// Entry samples a frame that starts from an empty cache takes.
    first_samples: u32,
    /// Milliseconds of that frame, read back (its pipelines built before).
    first_frame_ms: f64,
    /// Entry samples the last timed frame took.
    samples: u32,
    /// Milliseconds of a frame whose update takes one sample (the sample pass and the
    /// TAA over entries filled before), per round.
    lean_ms: Spread,
    /// The refresh's share: `irradiance` less that lean frame, per round.
    refresh_ms: Spread,
}

/// What every section shares.
struct Bench {
    gpu: Gpu,
    world: World,
    gw: GpuWorld,
    light: Light,
    seed: u32,
    exposure: f32,
    size: (u32, u32),
    roma: RomaOptions,
    irradiance: IrradianceOptions,
}

impl Bench {
    fn reference(&self, camera: &Camera, seed: u32, spp: u32, done: &mut dyn FnMut(u32)) -> Result<Radiance> {
        Ok(PathTracer::new(&self.gpu).render(
            &self.gpu,
            &self.gw,
            &Shot::new(*camera, self.size, self.light, seed),
            spp,
            done,
        )?)
    }

    fn frame(&self, r: &mut dyn Temporal, camera: &Camera) -> Result<()> {
        Ok(r.frame(
            &self.gpu,
            &self.gw,
            &Shot::new(*camera, self.size, self.light, self.seed),
        )?)
    }

    /// The next frame of `r`, read back as a client reads it.
    fn show(&self, r: &mut dyn Temporal, camera: &Camera) -> Result<()> {
        self.frame(r, camera)?;
        r.radiance(&self.gpu)?;
        Ok(())
    }

    fn measure(&self, img: &Radiance, reference: &Radiance) -> Result<Quality> {
        Quality::measure(img, reference, self.exposure).context("image sizes differ")
    }

    /// A fresh renderer of a temporal mode.
    fn temporal(&self, mode: Mode) -> Box<dyn Temporal> {
        match mode {
            Mode::Gi => Box::new(Gi::new(&self.gpu)),
            Mode::Roma => Box::new(self.roma()),
            Mode::Irradiance => Box::new(self.irradiance()),
            _ => Box::new(Baseline::new(&self.gpu)),
        }
    }

    /// A fresh ROMA renderer with the benchmark's settings.
    fn roma(&self) -> Roma {
        let mut roma = Roma::new(&self.gpu);
        roma.set_options(self.roma);
        roma
    }

    /// A fresh irradiance-cache renderer with the benchmark's settings.
    fn irradiance(&self) -> Irradiance {
        let mut irradiance = Irradiance::new(&self.gpu);
        irradiance.set_options(self.irradiance);
        irradiance
    }

    /// The quality of a fresh `mode` after `frames` frames.
    fn quality_after(&self, mode: Mode, camera: &Camera, frames: u32, reference: &Radiance) -> Result<Quality> {
        let mut r = self.temporal(mode);
        for _ in 0..frames {
            self.frame(r.as_mut(), camera)?;
        }
        self.measure(&r.radiance(&self.gpu)?, reference)
    }
}

const COMPARED: [Mode; 4] = [Mode::Baseline, Mode::Gi, Mode::Roma, Mode::Irradiance];
/// Frames the lean irradiance renderer draws with the full budget before it is timed.
const LEAN_WARM_UP: u32 = 32;
/// The `gi` frames whose time the matched-time comparison gives every mode.
const MATCHED_GI_FRAMES: f64 = 32.0;
/// The most frames a mode runs in the matched-time comparison.
const MATCHED_LIMIT: u32 = 1024;
/// Frames the edit response may take before it counts as not settled.
const EDIT_LIMIT: u32 = 64;
/// Frames over which the flicker is averaged.
const FLICKER_FRAMES: u32 = 8;

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
        None => content_camera(&world).context("the world is empty: there is nothing to light")?,
    };
    let options = a.light.options()?;
    let light = options.light(DEFAULT_LIT_BOUNCES).map_err(anyhow::Error::msg)?;
    let gpu = Gpu::new()?;
    let gw = GpuWorld::new(&gpu, &world)?;
    let mut b = Bench {
        gpu,
        world,
        gw,
        light,
        seed: options.seed,
        exposure: options.exposure,
        size: a.size,
        roma: options.roma,
        irradiance: options.irradiance,
    };
    let last = *a.frames.last().expect("checked above");
    let motion_poses = if a.motion_spp > 0 { 3 } else { 0 };
    let steps = 2 * a.reference_spp + motion_poses * a.motion_spp;
    let bar = progress(u64::from(steps), "bench gi: references", "spp");

    // Static quality.
    let t0 = Instant::now();
    let ref_a = b.reference(&camera, options.seed.wrapping_add(1000), a.reference_spp, &mut |n| {
        bar.set_position(u64::from(n))
    })?;
    let secs = t0.elapsed().as_secs_f64();
    let ref_b = b.reference(&camera, options.seed.wrapping_add(2000), a.reference_spp, &mut |n| {
        bar.set_position(u64::from(a.reference_spp + n))
    })?;
    let noise_floor = b.measure(&ref_b, &ref_a)?;
    let mut modes = BTreeMap::new();
    let mut flickers = BTreeMap::new();
    for mode in COMPARED {
        bar.set_message(format!("bench gi: {} frames", mode.name()));
        let mut r = b.temporal(mode);
        let mut by_frames = BTreeMap::new();
        for frame in 1..=last {
            b.frame(r.as_mut(), &camera)?;
            if a.frames.contains(&frame) {
                by_frames.insert(frame, b.measure(&r.radiance(&b.gpu)?, &ref_a)?);
            }
        }
        let mut prev = r.radiance(&b.gpu)?;
        let mut sum = 0.0;
        for _ in 0..FLICKER_FRAMES {
            b.frame(r.as_mut(), &camera)?;
            let now = r.radiance(&b.gpu)?;
            sum += flicker(&prev, &now).unwrap_or(0.0);
            prev = now;
        }
        modes.insert(mode.name(), by_frames);
        flickers.insert(mode.name(), sum / f64::from(FLICKER_FRAMES));
    }

    // Cost.
    bar.set_message("bench gi: timing");
    let (frame_ms, ratios, gi_pass_ms, gi_memory, roma_maps, irradiance_cache) = timing(&b, &camera, &a)?;

    // Matched time.
    bar.set_message("bench gi: matched time");
    let gi_ms = frame_ms["gi"].median;
    let mut matched_time = BTreeMap::new();
    for mode in COMPARED {
        let frames = (MATCHED_GI_FRAMES * gi_ms / frame_ms[mode.name()].median).round() as u32;
        let frames = frames.clamp(1, MATCHED_LIMIT);
        matched_time.insert(mode.name(), (frames, b.quality_after(mode, &camera, frames, &ref_a)?));
    }

    // Motion.
    let mut motion = BTreeMap::new();
    if a.motion_spp > 0 {
        let poses = [last / 4, last * 5 / 8, last].map(|f| f.max(1));
        let path: Vec<Camera> = (0..last).map(|i| moved(&camera, i)).collect();
        let mut references = BTreeMap::new();
        for (k, &f) in poses.iter().enumerate() {
            let done = 2 * a.reference_spp + k as u32 * a.motion_spp;
            let img = b.reference(
                &path[f as usize - 1],
                options.seed.wrapping_add(3000),
                a.motion_spp,
                &mut |n| bar.set_position(u64::from(done + n)),
            )?;
            references.insert(f, img);
        }
        for mode in COMPARED {
            let mut r = b.temporal(mode);
            for (i, cam) in path.iter().enumerate() {
                b.frame(r.as_mut(), cam)?;
                if let Some(reference) = references.get(&(i as u32 + 1)) {
                    let q = b.measure(&r.radiance(&b.gpu)?, reference)?;
                    motion
                        .entry(i as u32 + 1)
                        .or_insert_with(BTreeMap::new)
                        .insert(mode.name(), q);
                }
            }
        }
    }

    // Edit response.
    let mut edit_response = BTreeMap::new();
    if !a.no_edit {
        bar.set_message("bench gi: edit response");
        let (add, remove) = emitter_ops(&b.world, &camera)?;
        for mode in COMPARED {
            edit_response.insert(mode.name(), edit_frames(&mut b, mode, &camera, &add, &remove)?);
        }
    }
    bar.finish_and_clear();

    let face_granularity = (a.face_samples > 0).then(|| {
        bar.set_message("bench gi: face granularity");
        face_granularity::measure(&b.world, b.light, &camera, a.size, a.face_samples)
    });
    let report = Report {
        adapter: b.gpu.describe(),
        size: [a.size.0, a.size.1],
        reference_spp: a.reference_spp,
        bounces: b.light.bounces,
        reference_seconds: secs,
        noise_floor,
        modes,
        flicker: flickers,
        frame_ms,
        ratios,
        matched_time,
        roma_maps,
        irradiance_cache,
        face_granularity,
        gi_pass_ms,
        gi_memory,
        motion,
        edit_response,
    };
    if a.json {
        return print_json(&report);
    }
    print_report(&report);
    Ok(())
}

type Timing = (
    BTreeMap<&'static str, Spread>,
    BTreeMap<&'static str, Spread>,
    Vec<(&'static str, f64)>,
    Vec<(&'static str, u64)>,
    RomaMaps,
    IrradianceCache,
);

/// Times `albedo`, `baseline`, `gi`, `roma` and `irradiance` in `--rounds` rounds of
/// `--timing-frames` frames, rotating the order each round (each frame read back, as a
/// client does).
fn timing(b: &Bench, camera: &Camera, a: &GiArgs) -> Result<Timing> {
    let mut renderer = Renderer::new(&b.gpu);
    let mut baseline = Baseline::new(&b.gpu);
    let mut gi = Gi::new(&b.gpu);
    let mut roma = b.roma();
    let mut irradiance = b.irradiance();
    gi.profile = true;
    let order = [Mode::Albedo, Mode::Baseline, Mode::Gi, Mode::Roma, Mode::Irradiance];
    let mut ms: BTreeMap<&'static str, Vec<f64>> = BTreeMap::new();
    let mut pass_ms: BTreeMap<&'static str, Vec<f64>> = BTreeMap::new();
    // Warm up: pipelines built, histories past their first frame.
    renderer.render(&b.gpu, &b.gw, camera, b.size, Mode::Albedo, false)?;
    b.frame(&mut baseline, camera)?;
    b.frame(&mut gi, camera)?;
    b.frame(&mut irradiance, camera)?;
    // ROMA's first frame after the warm-up's: its pipelines are built, every tile is written.
    b.frame(&mut roma, camera)?;
    roma.forget_maps();
    let t0 = Instant::now();
    b.show(&mut roma, camera)?;
    let roma_maps = RomaMaps {
        bytes: roma.map_bytes(),
        first_tiles: roma.tiles_written(),
        first_frame_ms: t0.elapsed().as_secs_f64() * 1e3,
    };
    // The irradiance cache's first frame after the warm-up's: its pipelines are built, the
    // cache starts empty.
    irradiance.forget_cache();
    let t0 = Instant::now();
    b.show(&mut irradiance, camera)?;
    let first_frame_ms = t0.elapsed().as_secs_f64() * 1e3;
    let first_samples = irradiance.stats(&b.gpu)?.samples;
    // The same frames with the least budget, once the view's entries hold samples (the
    // camera's jitter finds new faces for a while): what the sample pass and the TAA cost
    // without the refresh.
    let mut lean = b.irradiance();
    for _ in 0..LEAN_WARM_UP {
        b.frame(&mut lean, camera)?;
    }
    lean.set_options(IrradianceOptions {
        rays: naadf_client::light::irradiance::MIN_RAYS,
    });
    b.frame(&mut lean, camera)?;
    let mut lean_ms = Vec::new();
    for round in 0..a.rounds as usize {
        for k in 0..order.len() {
            let mode = order[(round + k) % order.len()];
            let t0 = Instant::now();
            for _ in 0..a.timing_frames {
                match mode {
                    Mode::Albedo => drop(renderer.render(&b.gpu, &b.gw, camera, b.size, mode, false)?),
                    Mode::Baseline => b.show(&mut baseline, camera)?,
                    Mode::Roma => b.show(&mut roma, camera)?,
                    Mode::Irradiance => b.show(&mut irradiance, camera)?,
                    _ => {
                        b.show(&mut gi, camera)?;
                        for (p, t) in gi.pass_times(&b.gpu).unwrap_or_default() {
                            pass_ms.entry(p.entry()).or_default().push(t);
                        }
                    }
                }
            }
            ms.entry(mode.name())
                .or_default()
                .push(t0.elapsed().as_secs_f64() * 1e3 / f64::from(a.timing_frames));
        }
        let t0 = Instant::now();
        for _ in 0..a.timing_frames {
            b.show(&mut lean, camera)?;
        }
        lean_ms.push(t0.elapsed().as_secs_f64() * 1e3 / f64::from(a.timing_frames));
    }
    let per_round = |num: &str, den: &str| Spread::of(ms[num].iter().zip(&ms[den]).map(|(n, d)| n / d).collect());
    let ratios = BTreeMap::from([
        ("gi/albedo", per_round("gi", "albedo")),
        ("gi/baseline", per_round("gi", "baseline")),
        ("roma/albedo", per_round("roma", "albedo")),
        ("roma/gi", per_round("roma", "gi")),
        ("irradiance/albedo", per_round("irradiance", "albedo")),
        ("irradiance/gi", per_round("irradiance", "gi")),
    ]);
    let irradiance_cache = IrradianceCache {
        bytes: irradiance.cache_bytes(),
        first_samples,
        first_frame_ms,
        samples: irradiance.stats(&b.gpu)?.samples,
        refresh_ms: Spread::of(ms["irradiance"].iter().zip(&lean_ms).map(|(f, l)| f - l).collect()),
        lean_ms: Spread::of(lean_ms),
    };
    let passes = GiPass::ALL
        .iter()
        .filter_map(|p| pass_ms.remove(p.entry()).map(|v| (p.entry(), Spread::of(v).median)))
        .collect();
    let memory = gi.memory().unwrap_or_default();
    Ok((
        ms.into_iter().map(|(k, v)| (k, Spread::of(v))).collect(),
        ratios,
        passes,
        memory,
        roma_maps,
        irradiance_cache,
    ))
}

/// The camera `i` frames along the motion path: a strafe to the right of 0.25 voxels and
/// a yaw of 0.5° per frame.
fn moved(camera: &Camera, i: u32) -> Camera {
    let right = camera.basis().right;
    let s = 0.25 * f64::from(i);
    Camera {
        pos: std::array::from_fn(|k| camera.pos[k] + right[k] * s),
        yaw: camera.yaw + 0.5 * f64::from(i),
        ..*camera
    }
}

/// The ops that add an emissive 4³ box in front of `camera` (halfway to the first surface
/// along its view, at most 24 voxels away) and that remove it again.
fn emitter_ops(world: &World, camera: &Camera) -> Result<(Batch, Batch)> {
    let forward = camera.basis().forward;
    let ray = Ray::new(camera.pos, forward)?;
    let distance = trace_naadf(world, &ray).map_or(48.0, |h| h.t);
    let reach = (distance * 0.5).min(24.0);
    if reach < 4.0 {
        bail!("the camera faces a surface {distance:.1} voxels away: no room for the test emitter");
    }
    let size = world.size().voxels();
    let centre: [f64; 3] = std::array::from_fn(|k| camera.pos[k] + forward[k] * reach);
    let lo: [i64; 3] = std::array::from_fn(|k| (centre[k].floor() as i64 - 2).clamp(0, i64::from(size[k]) - 4));
    let hi: [i64; 3] = std::array::from_fn(|k| lo[k] + 4);
    let id = world.materials().len();
    let parse = |ops: String| Batch::parse_line(&format!(r#"{{"batch":[{ops}]}}"#)).context("emitter ops");
    let add = parse(format!(
        r#"{{"op":"define_material","id":{id},"kind":"emissive","albedo":[1,1,1],"emission":8}},{{"op":"box","min":{lo:?},"max":{hi:?},"material":{id}}}"#
    ))?;
    let remove = parse(format!(r#"{{"op":"box","min":{lo:?},"max":{hi:?},"material":0}}"#))?;
    Ok((add, remove))
}

/// The image's mean luminance after `frames` more frames of `r`.
fn settle(b: &Bench, r: &mut dyn Temporal, camera: &Camera, frames: u32) -> Result<f64> {
    for _ in 0..frames {
        b.frame(r, camera)?;
    }
    Ok(mean_luminance(&r.radiance(&b.gpu)?))
}

/// Frames until `mode` settles within 10 % of the change after adding the emitter, and
/// after removing it again (EDIT_LIMIT + 1: not within EDIT_LIMIT).
fn edit_frames(b: &mut Bench, mode: Mode, camera: &Camera, add: &Batch, remove: &Batch) -> Result<[u32; 2]> {
    let limits = Limits::default();
    let apply = |b: &mut Bench, batch: &Batch| -> Result<()> {
        b.world.apply(batch, &limits).context("the test emitter")?;
        b.gw.sync(&b.world)?;
        Ok(())
    };
    // Converged values without and with the emitter, from fresh histories.
    let without = settle(b, b.temporal(mode).as_mut(), camera, 64)?;
    apply(b, add)?;
    let with = settle(b, b.temporal(mode).as_mut(), camera, 64)?;
    apply(b, remove)?;
    let mut r = b.temporal(mode);
    settle(b, r.as_mut(), camera, 32)?;
    let mut out = [EDIT_LIMIT + 1; 2];
    for (k, (batch, from, to)) in [(add, without, with), (remove, with, without)].into_iter().enumerate() {
        apply(b, batch)?;
        for f in 1..=EDIT_LIMIT {
            if (settle(b, r.as_mut(), camera, 1)? - to).abs() <= 0.1 * (to - from).abs() {
                out[k] = f;
                break;
            }
        }
        // Converge before the next change.
        settle(b, r.as_mut(), camera, 32)?;
    }
    Ok(out)
}

fn print_report(r: &Report) {
    println!(
        "{} — {}x{}, references of {} spp (B = {}, {:.1} s each)",
        r.adapter, r.size[0], r.size[1], r.reference_spp, r.bounces, r.reference_seconds
    );
    let row = |name: &str, q: &Quality| {
        println!(
            "{name:<24} FLIP {:.4}  relMSE {:.5}  bias {:+.4}",
            q.flip, q.rel_mse, q.bias
        )
    };
    row("noise floor", &r.noise_floor);
    for (mode, by_frames) in &r.modes {
        for (frames, q) in by_frames {
            row(&format!("{mode} after {frames}"), q);
        }
    }
    for (mode, f) in &r.flicker {
        println!("{:<24} flicker {f:.4}", mode);
    }
    for (mode, s) in &r.frame_ms {
        println!("{mode:<24} {:.1} ms/frame ({:.1}–{:.1})", s.median, s.min, s.max);
    }
    for (name, s) in &r.ratios {
        println!("{name:<24} ×{:.2} ({:.2}–{:.2})", s.median, s.min, s.max);
    }
    for (mode, (frames, q)) in &r.matched_time {
        row(&format!("{mode} {frames} fr, matched"), q);
    }
    let m = &r.roma_maps;
    println!(
        "{:<24} {:.2} MB; first frame {:.1} ms ({} tiles written)",
        "roma maps",
        m.bytes as f64 / 1e6,
        m.first_frame_ms,
        m.first_tiles
    );
    let c = &r.irradiance_cache;
    println!(
        "{:<24} {:.2} MB; first frame {:.1} ms ({} samples taken); {} samples a frame after",
        "irradiance cache",
        c.bytes as f64 / 1e6,
        c.first_frame_ms,
        c.first_samples,
        c.samples
    );
    println!(
        "{:<24} sample pass and TAA {:.1} ms ({:.1}–{:.1}), refresh {:.1} ms ({:.1}–{:.1})",
        "irradiance frame",
        c.lean_ms.median,
        c.lean_ms.min,
        c.lean_ms.max,
        c.refresh_ms.median,
        c.refresh_ms.min,
        c.refresh_ms.max
    );
    if let Some(f) = &r.face_granularity {
        println!(
            "{:<24} {} voxel faces, {} block faces over {} pixels; a block-face key adds {:.2} % error, each {}-sample estimate carries {:.2} % noise",
            "irradiance face keys",
            f.voxel_faces,
            f.block_faces,
            f.pixels,
            100.0 * f.block_error,
            f.samples,
            100.0 * f.noise
        );
    }
    for (pass, ms) in &r.gi_pass_ms {
        println!("  {pass:<22} {ms:.3} ms");
    }
    for (name, bytes) in &r.gi_memory {
        println!("  {name:<22} {:.2} MB", *bytes as f64 / 1e6);
    }
    for (frame, by_mode) in &r.motion {
        for (mode, q) in by_mode {
            row(&format!("motion {mode} at {frame}"), q);
        }
    }
    for (mode, [added, removed]) in &r.edit_response {
        println!("{mode:<24} edit response: {added} frames (added), {removed} frames (removed)");
    }
}

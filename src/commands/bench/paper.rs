//! `naadf bench paper WORLD`: the paper's comparison (its Tables 1–3) on one world: bytes,
//! build time and primary and secondary Mrays/s of `naadf`, the SVO, the SVDAG, the dense
//! grid and the hybrid formats R(4³)G(7) and R(3³)G(8), on the same rays in one run
//! (docs/BASELINES.md).

use super::gpu::{Trees, measure_gpu};
use super::plot;
use super::shared::median_range;
use crate::commands::{load_world, print_json};
use anyhow::{Result, bail};
use naadf_client::gpu::Traversal;
use naadf_world::World;
use naadf_world::baselines::{Hybrid, HybridFormat, Svdag, Svo};
use naadf_world::ops::{Batch, Limits, Op};
use naadf_world::raysets::{fixed_cameras, primary_rays, secondary_rays};
use naadf_world::stats::{Bytes, WorldStats};
use naadf_world::traverse::{DenseGrid, Hit, Method, Ray, trace_naadf};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

/// The largest image edge per camera: four cameras of 4096 × 4096 are 67M primary rays.
const MAX_EDGE: u32 = 4096;

/// Arguments of `bench paper`.
#[derive(clap::Args)]
pub struct PaperArgs {
    /// World file.
    world: PathBuf,
    /// Image width per camera.
    #[arg(long, default_value_t = 480)]
    width: u32,
    /// Image height per camera.
    #[arg(long, default_value_t = 270)]
    height: u32,
    /// Timed rounds; each traces both ray sets with every structure, the order rotating.
    #[arg(long, default_value_t = 5)]
    rounds: u32,
    /// Seed of the secondary-ray directions.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Also measure the GPU traversals (naadf, SVO, SVDAG, grid) on the same rays.
    #[arg(long)]
    gpu: bool,
    /// Draw the storage-versus-speed scatter (bytes against Mrays/s, one point per
    /// structure and ray kind; the GPU's too with `--gpu`) as a PNG here.
    #[arg(long, value_name = "OUT.png")]
    plot: Option<PathBuf>,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

/// One structure's figures.
#[derive(Serialize)]
struct Figures {
    /// Bytes by the structure's own count (docs/BASELINES.md).
    bytes: u64,
    /// Median Mrays/s over the rounds, primary and secondary rays (null when skipped).
    primary: Option<f64>,
    secondary: Option<f64>,
    /// Lowest and highest round.
    primary_range: Option<[f64; 2]>,
    secondary_range: Option<[f64; 2]>,
    /// Build time from the world's voxels, in milliseconds (null for the grid).
    build_ms: Option<f64>,
    /// Why the structure was not measured.
    #[serde(skip_serializing_if = "Option::is_none")]
    skipped: Option<String>,
}

impl Figures {
    /// A structure counted but not traced, and why.
    fn unmeasured(bytes: u64, why: String) -> Self {
        Figures {
            bytes,
            primary: None,
            secondary: None,
            primary_range: None,
            secondary_range: None,
            build_ms: None,
            skipped: Some(why),
        }
    }
}

#[derive(Serialize)]
struct Report {
    structures: BTreeMap<&'static str, Figures>,
    /// The hybrid formats R(4³)G(7) and R(3³)G(8) (their build time includes the SVDAG's,
    /// which they are made from).
    hybrid: BTreeMap<&'static str, Figures>,
    /// Primary plus secondary rays.
    rays: usize,
    threads: usize,
    rounds: u32,
    /// NAADF's bytes layer by layer.
    naadf_layers: Bytes,
    /// Per baseline, the median over rounds of NAADF's speed-up on primary and secondary
    /// rays.
    naadf_speedup: BTreeMap<&'static str, [f64; 2]>,
    /// The GPU figures (`--gpu`), or null.
    gpu: Option<GpuSection>,
}

/// The GPU traversals on the same rays (`--gpu`).
#[derive(Serialize)]
struct GpuSection {
    /// The adapter (name, backend, device type).
    adapter: String,
    /// Per structure: median Mrays/s and range over the rounds (bytes and build time are
    /// the CPU section's).
    structures: BTreeMap<&'static str, Figures>,
    /// Per baseline, the median over rounds of NAADF's speed-up on primary and secondary
    /// rays.
    naadf_speedup: BTreeMap<&'static str, [f64; 2]>,
    /// Rays whose GPU result differs from the CPU's, per structure (only rays within a
    /// rounding error of a tie may: the GPU receives them rounded to `f32`).
    mismatches: BTreeMap<&'static str, usize>,
}

/// How a structure traces a ray.
type TraceFn<'a> = Box<dyn Fn(&Ray) -> Option<Hit> + Sync + 'a>;

/// A structure under test: its name and how it traces a ray.
struct Tracer<'a> {
    name: &'static str,
    trace: TraceFn<'a>,
}

/// Runs `bench paper`.
pub fn run(a: PaperArgs) -> Result<()> {
    if !(1..=MAX_EDGE).contains(&a.width) || !(1..=MAX_EDGE).contains(&a.height) {
        bail!("--width and --height must be 1..={MAX_EDGE}");
    }
    let loaded = load_world(&a.world)?;
    let world = static_only(loaded)?;
    let stats = WorldStats::of(&world);
    let (_, naadf_ms) = timed(|| World::build(&world, &|_| {}))?;
    let (svo, svo_ms) = timed(|| Svo::build(&world))?;
    let (svdag, svdag_ms) = timed(|| Svdag::build(&world))?;
    let grid = DenseGrid::from_world(&world);
    // The hybrid-formats paper's two recommended formats, made from the SVDAG.
    // `built[i]`: the format of `hybrids[i]` and its build time (the SVDAG's included).
    let mut hybrids = Vec::new();
    let mut built = Vec::new();
    let mut unbuilt = BTreeMap::new();
    for f in HybridFormat::ALL {
        match timed(|| Hybrid::of(&svdag, f)) {
            Ok((h, ms)) => {
                hybrids.push(h);
                built.push((f.name(), svdag_ms + ms));
            }
            Err(e) => {
                unbuilt.insert(f.name(), Figures::unmeasured(0, e.to_string()));
            }
        }
    }
    let trees = Trees { svo, svdag, hybrids };
    let Trees { svo, svdag, hybrids } = &trees;

    let mut tracers = vec![
        Tracer {
            name: "naadf",
            trace: Box::new(|r| trace_naadf(&world, r)),
        },
        Tracer {
            name: "svo",
            trace: Box::new(|r| svo.trace(r)),
        },
        Tracer {
            name: "svdag",
            trace: Box::new(|r| svdag.trace(r)),
        },
    ];
    if let Ok(g) = &grid {
        tracers.push(Tracer {
            name: "grid",
            trace: Box::new(|r| g.trace(r)),
        });
    }
    for (h, &(name, _)) in hybrids.iter().zip(&built) {
        tracers.push(Tracer {
            name,
            trace: Box::new(|r| h.trace(r)),
        });
    }
    let primary = primary_rays(&fixed_cameras(world.size()), a.width, a.height);
    let hits: Vec<Option<Hit>> = primary.par_iter().map(|r| trace_naadf(&world, r)).collect();
    let secondary = secondary_rays(&primary, &hits, a.seed);
    check_agreement(&tracers, &primary, &secondary)?;

    // rates[structure][set]: Mrays/s per round.
    let rounds = a.rounds.max(1);
    let mut rates = vec![[Vec::new(), Vec::new()]; tracers.len()];
    for round in 0..rounds as usize {
        for k in 0..tracers.len() {
            let s = (k + round) % tracers.len();
            for (set, rays) in [&primary, &secondary].into_iter().enumerate() {
                let t0 = Instant::now();
                let found = rays.par_iter().filter(|r| (tracers[s].trace)(r).is_some()).count();
                std::hint::black_box(found);
                rates[s][set].push(rays.len() as f64 / t0.elapsed().as_secs_f64() / 1e6);
            }
        }
    }
    let names: Vec<&'static str> = tracers.iter().map(|t| t.name).collect();
    let (mut structures, naadf_speedup) = figures_of(&names, &rates, |name| match name {
        "naadf" => (stats.bytes.total, Some(naadf_ms)),
        "svo" => (svo.bytes(), Some(svo_ms)),
        "svdag" => (svdag.bytes(), Some(svdag_ms)),
        "grid" => (world.size().voxel_count() * 2, None),
        hybrid => hybrids
            .iter()
            .zip(&built)
            .find(|(_, (name, _))| *name == hybrid)
            .map_or((0, None), |(h, &(_, ms))| (h.bytes(), Some(ms))),
    });
    if let Err(e) = &grid {
        structures.insert(
            "grid",
            Figures::unmeasured(world.size().voxel_count() * 2, e.to_string()),
        );
    }
    let mut hybrid = unbuilt;
    for (name, _) in &built {
        hybrid.extend(structures.remove_entry(name));
    }
    let gpu = if a.gpu {
        let mut traversals = vec![
            Traversal::Method(Method::Naadf),
            Traversal::Svo,
            Traversal::Svdag,
            Traversal::Method(Method::Grid),
        ];
        traversals.extend(hybrids.iter().filter_map(|h| h.format().map(Traversal::Hybrid)));
        let m = measure_gpu(&world, Some(&trees), &traversals, &primary, &secondary, rounds)?;
        m.check_mismatches(primary.len() + secondary.len())?;
        let names: Vec<&'static str> = m.figures.keys().copied().collect();
        // "naadf" first: the speed-ups are taken against it.
        let names: Vec<&'static str> = ["naadf"]
            .into_iter()
            .chain(names.into_iter().filter(|&n| n != "naadf"))
            .collect();
        let rates: Vec<[Vec<f64>; 2]> = names.iter().map(|n| m.figures[n].rates.clone()).collect();
        let bytes = |name: &str| structures.get(name).or(hybrid.get(name)).map_or(0, |f| f.bytes);
        let (mut gpu_structures, gpu_speedup) = figures_of(&names, &rates, |name| (bytes(name), None));
        for (name, why) in m.skipped {
            gpu_structures.insert(name, Figures::unmeasured(bytes(name), why));
        }
        Some(GpuSection {
            adapter: m.adapter,
            structures: gpu_structures,
            naadf_speedup: gpu_speedup,
            mismatches: m.figures.iter().map(|(&n, f)| (n, f.mismatches)).collect(),
        })
    } else {
        None
    };
    let report = Report {
        structures,
        hybrid,
        rays: primary.len() + secondary.len(),
        threads: rayon::current_num_threads(),
        rounds,
        naadf_layers: stats.bytes,
        naadf_speedup,
        gpu,
    };
    if a.json {
        print_json(&report)?;
    } else {
        print_table(&report);
    }
    if let Some(out) = &a.plot {
        let name = a
            .world
            .file_stem()
            .map_or("world".into(), |s| s.to_string_lossy().into_owned());
        plot::draw_scatter(&name, &plot_points(&report), out)?;
        tracing::info!("scatter written to {}", out.display());
    }
    Ok(())
}

/// The scatter's points: every structure on the CPU, the hybrid formats, and the GPU's
/// structures when measured.
fn plot_points(r: &Report) -> Vec<plot::Point> {
    let point = |name: String, f: &Figures| plot::Point {
        name,
        bytes: f.bytes,
        primary: f.primary,
        secondary: f.secondary,
    };
    let mut points: Vec<plot::Point> = r
        .structures
        .iter()
        .chain(&r.hybrid)
        .filter(|(_, f)| f.bytes > 0)
        .map(|(n, f)| point(n.to_string(), f))
        .collect();
    if let Some(g) = &r.gpu {
        points.extend(
            g.structures
                .iter()
                .filter(|(_, f)| f.primary.is_some())
                .map(|(n, f)| point(format!("{n} (GPU)"), f)),
        );
    }
    points
}

/// Each structure's figures from its Mrays/s per round (`rates[k]`, primary and secondary,
/// for `names[k]`; `naadf` first), with its bytes and build time from `counts`; and NAADF's
/// speed-up over each other structure, the median of the per-round ratios (both sides of
/// each ratio saw the same machine state).
fn figures_of(
    names: &[&'static str],
    rates: &[[Vec<f64>; 2]],
    counts: impl Fn(&str) -> (u64, Option<f64>),
) -> (BTreeMap<&'static str, Figures>, BTreeMap<&'static str, [f64; 2]>) {
    let mut structures = BTreeMap::new();
    let mut speedup = BTreeMap::new();
    for (k, &name) in names.iter().enumerate() {
        let (p, pr) = median_range(&rates[k][0]);
        let (s, sr) = median_range(&rates[k][1]);
        let (bytes, build_ms) = counts(name);
        structures.insert(
            name,
            Figures {
                bytes,
                primary: Some(p),
                secondary: Some(s),
                primary_range: Some(pr),
                secondary_range: Some(sr),
                build_ms,
                skipped: None,
            },
        );
        if k > 0 {
            let ratio = |set: usize| {
                let r: Vec<f64> = rates[0][set].iter().zip(&rates[k][set]).map(|(a, b)| a / b).collect();
                median_range(&r).0
            };
            speedup.insert(name, [ratio(0), ratio(1)]);
        }
    }
    (structures, speedup)
}

/// `f`'s result and the milliseconds it took.
fn timed<T, E>(f: impl FnOnce() -> Result<T, E>) -> Result<(T, f64), E> {
    let t0 = Instant::now();
    let out = f()?;
    Ok((out, t0.elapsed().as_secs_f64() * 1e3))
}

/// The world without its entities: the baselines hold static geometry only.
fn static_only(mut world: World) -> Result<World> {
    let ids: Vec<u32> = world.entity_table().instances.keys().copied().collect();
    if !ids.is_empty() {
        let ops = ids.iter().map(|&id| Op::DespawnEntity { id }).collect::<Vec<_>>();
        let limits = Limits {
            max_ops: ops.len(),
            ..Limits::default()
        };
        world.apply(&Batch { ops }, &limits)?;
        world.grow_until_quiescent();
    }
    Ok(world)
}

/// Fails unless every structure (after `naadf`, the first) finds `naadf`'s voxel, face and `t` on every ray.
fn check_agreement(tracers: &[Tracer], primary: &[Ray], secondary: &[Ray]) -> Result<()> {
    let geometry = |h: Option<Hit>| h.map(|h| (h.voxel, h.normal, h.t));
    for rays in [primary, secondary] {
        for t in &tracers[1..] {
            let differ = rays
                .par_iter()
                .filter(|r| geometry((tracers[0].trace)(r)) != geometry((t.trace)(r)))
                .count();
            if differ > 0 {
                bail!("{differ} of {} rays differ between naadf and {}", rays.len(), t.name);
            }
        }
    }
    Ok(())
}

fn print_table(r: &Report) {
    println!(
        "{:<10} {:>12} {:>10} {:>18} {:>18}",
        "", "bytes", "build ms", "primary Mrays/s", "secondary Mrays/s"
    );
    for (name, f) in r.structures.iter().chain(&r.hybrid) {
        let rate = |v: Option<f64>, range: Option<[f64; 2]>| match (v, range) {
            (Some(v), Some([lo, hi])) => format!("{v:.2} ({lo:.2}–{hi:.2})"),
            _ => "skipped".to_string(),
        };
        println!(
            "{name:<10} {:>12} {:>10} {:>18} {:>18}",
            f.bytes,
            f.build_ms.map_or("—".into(), |m| format!("{m:.0}")),
            rate(f.primary, f.primary_range),
            rate(f.secondary, f.secondary_range)
        );
        if let Some(why) = &f.skipped {
            println!("           ({why})");
        }
    }
    for (name, [p, s]) in &r.naadf_speedup {
        println!(
            "naadf / {name}: primary ×{p:.2}, secondary ×{s:.2} (median of {} rounds)",
            r.rounds
        );
    }
    if let Some(g) = &r.gpu {
        println!("GPU ({}):", g.adapter);
        for (name, f) in &g.structures {
            match (f.primary, f.secondary) {
                (Some(p), Some(s)) => println!(
                    "{name:<8} primary {p:.2} Mrays/s, secondary {s:.2} Mrays/s, {} differ from the CPU",
                    g.mismatches.get(name).copied().unwrap_or(0)
                ),
                _ => println!("{name:<8} skipped ({})", f.skipped.as_deref().unwrap_or("")),
            }
        }
        for (name, [p, s]) in &g.naadf_speedup {
            println!("GPU naadf / {name}: primary ×{p:.2}, secondary ×{s:.2}");
        }
    }
    let l = &r.naadf_layers;
    println!(
        "naadf layers: chunks {} B, blocks {} B, voxels {} B, materials {} B",
        l.chunks, l.blocks, l.voxels, l.materials
    );
    println!("{} rays, {} threads", r.rays, r.threads);
}

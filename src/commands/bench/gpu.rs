//! `naadf bench gpu WORLD`: ray throughput of the GPU traversals (`naadf`, `nodf`, `grid`,
//! and the paper's `svo`, `svdag` and two hybrid formats) on the fixed cameras of `bench traverse`, primary and
//! secondary rays, all measured in one run (rounds in rotating order) so that their ratios
//! mean something on a shared machine. Every GPU result is also checked against the CPU:
//! the world's methods against the `naadf` traversal, the trees against their own CPU walk.
//! `bench paper --gpu` measures with the same code ([`measure_gpu`]).

use super::shared::{median_range, print_ratios};
use crate::commands::{load_world, print_json};
use anyhow::{Result, bail};
use naadf_client::gpu::{Gpu, GpuError, GpuHit, GpuRay, GpuWorld, RayBatch, RayTracer, Traversal};
use naadf_world::World;
use naadf_world::baselines::{Hybrid, HybridFormat, Svdag, Svo};
use naadf_world::raysets::{fixed_cameras, primary_rays, secondary_rays};
use naadf_world::traverse::{Hit, Method, Ray, same_result, trace_naadf};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `bench gpu`.
#[derive(clap::Args)]
pub struct GpuArgs {
    /// World file.
    world: PathBuf,
    /// Image width per camera.
    #[arg(long, default_value_t = 480)]
    width: u32,
    /// Image height per camera.
    #[arg(long, default_value_t = 270)]
    height: u32,
    /// Only the first N fixed cameras (all by default).
    #[arg(long)]
    cameras: Option<usize>,
    /// Timed rounds; each traces both ray sets with every variant, the order rotating. The
    /// median counts.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    repeat: u32,
    /// Seed of the secondary-ray directions.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

/// What `bench gpu` measured.
#[derive(Serialize)]
struct GpuReport {
    /// The adapter (name, backend, device type).
    adapter: String,
    /// Median Mrays/s per variant on primary rays.
    primary: BTreeMap<&'static str, f64>,
    /// Median Mrays/s per variant on secondary rays.
    secondary: BTreeMap<&'static str, f64>,
    /// Primary rays per run.
    rays: usize,
    /// Secondary rays per run.
    secondary_rays: usize,
    /// Dispatches per run of the primary rays (a ray list larger than one storage binding
    /// is split).
    batches: usize,
    /// Timed rounds.
    rounds: u32,
    /// Mean cells visited per ray, per variant (primary, secondary).
    steps: BTreeMap<&'static str, [f64; 2]>,
    /// Rays whose GPU result differs from the CPU's answer for the same `f64` ray, per
    /// variant (primary and secondary together). Only rays within a rounding error of a
    /// tie may differ: the GPU receives the ray rounded to `f32`.
    mismatches: BTreeMap<&'static str, usize>,
    /// Variants not measured, and why.
    skipped: BTreeMap<&'static str, String>,
}

/// One traversal's GPU figures.
pub(super) struct GpuFigures {
    /// Mrays/s per round, primary and secondary rays.
    pub rates: [Vec<f64>; 2],
    /// Mean cells visited per ray (primary, secondary).
    pub steps: [f64; 2],
    /// Rays (both sets) whose GPU result differs from the CPU's.
    pub mismatches: usize,
}

/// What [`measure_gpu`] measured.
pub(super) struct GpuMeasurement {
    /// The adapter (name, backend, device type).
    pub adapter: String,
    /// Dispatches per run of the primary rays.
    pub batches: usize,
    /// Per traversal measured, by name.
    pub figures: BTreeMap<&'static str, GpuFigures>,
    /// Traversals not measured, and why.
    pub skipped: BTreeMap<&'static str, String>,
}

impl GpuMeasurement {
    /// Fails when a traversal differs from the CPU on more rays than the tie allowance: 1
    /// in 10,000 of `rays`, plus one.
    pub fn check_mismatches(&self, rays: usize) -> Result<()> {
        let allowance = rays / 10_000 + 1;
        if let Some((m, f)) = self.figures.iter().find(|(_, f)| f.mismatches > allowance) {
            bail!(
                "{} {m} results differ from the CPU: more than the 1 in 10,000 tie allowance ({allowance})",
                f.mismatches
            );
        }
        Ok(())
    }
}

/// A ray set uploaded once, in as many batches as the binding limit needs.
struct RaySet {
    batches: Vec<RayBatch>,
    len: usize,
}

impl RaySet {
    fn new(gpu: &Gpu, tracer: &RayTracer, rays: &[Ray]) -> Result<Self> {
        let gpu_rays: Vec<GpuRay> = rays.iter().map(GpuRay::from).collect();
        let batches = gpu_rays
            .chunks(RayTracer::max_batch(gpu).max(1))
            .map(|c| tracer.upload(gpu, c))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(RaySet {
            batches,
            len: rays.len(),
        })
    }

    /// Traces the set once with `traversal` and returns the seconds it took.
    fn time(&self, gpu: &Gpu, tracer: &mut RayTracer, world: &GpuWorld, traversal: Traversal) -> Result<f64> {
        let t0 = Instant::now();
        for b in &self.batches {
            tracer.run(gpu, world, b, traversal)?;
        }
        Ok(t0.elapsed().as_secs_f64())
    }

    /// The results of the last run: mean steps, and the rays differing from `cpu`.
    fn check(&self, gpu: &Gpu, tracer: &RayTracer, cpu: &[Option<Hit>]) -> Result<(f64, usize)> {
        let mut results: Vec<GpuHit> = Vec::with_capacity(self.len);
        for b in &self.batches {
            results.extend(tracer.results(gpu, b)?);
        }
        let steps = results.iter().map(|r| f64::from(r.steps)).sum::<f64>() / self.len.max(1) as f64;
        let mismatches = results
            .iter()
            .zip(cpu)
            .filter(|(g, c)| g.exhausted || !same_result(&g.hit, c))
            .count();
        Ok((steps, mismatches))
    }
}

/// The paper's comparison structures of one world, for the traversals that walk them.
pub(super) struct Trees {
    pub svo: Svo,
    pub svdag: Svdag,
    /// The hybrid formats that could be built (a world's cube may be too large for one, or
    /// its buffer beyond 32-bit offsets).
    pub hybrids: Vec<Hybrid>,
}

impl Trees {
    /// Every structure of `world`, or `None` for a world with no solid voxel (which no
    /// structure holds).
    pub fn build(world: &World) -> Option<Trees> {
        let (svo, svdag) = (Svo::build(world).ok()?, Svdag::build(world).ok()?);
        let hybrids = HybridFormat::ALL
            .into_iter()
            .filter_map(|f| Hybrid::of(&svdag, f).ok())
            .collect();
        Some(Trees { svo, svdag, hybrids })
    }
}

/// Measures `traversals` on the GPU on the `primary` and `secondary` rays of `world`, in
/// `rounds` timed rounds whose order rotates (after one untimed run each, which also
/// checks every result against the CPU). Each traversal that needs a comparison structure
/// gets a device copy of the world of its own, so that no round waits for an upload. The
/// trees, when given, must be built from `world`.
pub(super) fn measure_gpu(
    world: &World,
    trees: Option<&Trees>,
    traversals: &[Traversal],
    primary: &[Ray],
    secondary: &[Ray],
    rounds: u32,
) -> Result<GpuMeasurement> {
    let gpu = Gpu::new()?;
    let mut tracer = RayTracer::new(&gpu);
    let sets = [
        RaySet::new(&gpu, &tracer, primary)?,
        RaySet::new(&gpu, &tracer, secondary)?,
    ];
    let mut out = GpuMeasurement {
        adapter: gpu.describe(),
        batches: sets[0].batches.len(),
        figures: BTreeMap::new(),
        skipped: BTreeMap::new(),
    };
    let base = GpuWorld::new(&gpu, world)?;
    let naadf_answers: Answers = [primary, secondary]
        .iter()
        .map(|rays| rays.par_iter().map(|r| trace_naadf(world, r)).collect())
        .collect();
    let mut ready: Vec<Prepared> = Vec::new();
    for &t in traversals {
        // Its own device world for a comparison structure, and a tree's CPU answers
        // (the world's methods share the first device world and `naadf`'s answers).
        let prepared = match (t, trees) {
            (Traversal::Method(Method::Grid), _) => {
                own_world(&gpu, world, |w| w.upload_grid(world)).map(|w| (Some(w), None))
            }
            (Traversal::Method(_), _) => Ok((None, None)),
            (_, None) => {
                out.skipped
                    .insert(t.name(), "the world has no trees (no solid voxel)".into());
                continue;
            }
            (Traversal::Svo, Some(Trees { svo, .. })) => own_world(&gpu, world, |w| w.upload_svo(svo))
                .map(|w| (Some(w), Some(tree_answers(|r| svo.trace(r), primary, secondary)))),
            (Traversal::Svdag, Some(Trees { svdag, .. })) => own_world(&gpu, world, |w| w.upload_svdag(svdag))
                .map(|w| (Some(w), Some(tree_answers(|r| svdag.trace(r), primary, secondary)))),
            (Traversal::Hybrid(f), Some(trees)) => match trees.hybrids.iter().find(|h| h.format() == Some(f)) {
                Some(h) => own_world(&gpu, world, |w| w.upload_hybrid(h))
                    .map(|w| (Some(w), Some(tree_answers(|r| h.trace(r), primary, secondary)))),
                None => {
                    out.skipped
                        .insert(t.name(), format!("no {} could be built for this world", f.name()));
                    continue;
                }
            },
        };
        let (device, answers) = match prepared {
            Ok(p) => p,
            Err(e) => {
                tracing::warn!("skipping {}: {e}", t.name());
                out.skipped.insert(t.name(), e.to_string());
                continue;
            }
        };
        ready.push(Prepared {
            traversal: t,
            device,
            answers,
        });
    }
    // One untimed run each (pipeline build, caches), checked against the CPU.
    for Prepared {
        traversal: t,
        device,
        answers,
    } in &ready
    {
        let answers = answers.as_ref().unwrap_or(&naadf_answers);
        tracing::info!("checking {}", t.name());
        let w = device.as_ref().unwrap_or(&base);
        let mut steps = [0.0; 2];
        let mut mismatches = 0;
        for (k, set) in sets.iter().enumerate() {
            set.time(&gpu, &mut tracer, w, *t)?;
            let (s, m) = set.check(&gpu, &tracer, &answers[k])?;
            steps[k] = s;
            mismatches += m;
        }
        out.figures.insert(
            t.name(),
            GpuFigures {
                rates: [Vec::new(), Vec::new()],
                steps,
                mismatches,
            },
        );
    }
    for round in 0..rounds as usize {
        for k in 0..ready.len() {
            let p = &ready[(k + round) % ready.len()];
            let (t, w) = (&p.traversal, p.device.as_ref().unwrap_or(&base));
            for (s, set) in sets.iter().enumerate() {
                let secs = set.time(&gpu, &mut tracer, w, *t)?;
                let figures = out.figures.get_mut(t.name()).expect("checked above");
                figures.rates[s].push(set.len as f64 / secs / 1e6);
            }
        }
    }
    Ok(out)
}

/// The CPU's answers on the primary and on the secondary rays.
type Answers = Vec<Vec<Option<Hit>>>;

/// A traversal ready to time: its device world (`None`: the shared one) and the CPU's
/// answers (`None`: `naadf`'s).
struct Prepared {
    traversal: Traversal,
    device: Option<GpuWorld>,
    answers: Option<Answers>,
}

/// A device copy of `world` of its own, with a comparison structure uploaded by `upload`.
fn own_world(
    gpu: &Gpu,
    world: &World,
    upload: impl FnOnce(&mut GpuWorld) -> Result<(), GpuError>,
) -> Result<GpuWorld, GpuError> {
    let mut w = GpuWorld::new(gpu, world)?;
    upload(&mut w)?;
    Ok(w)
}

/// A tree's CPU answers on both ray sets.
fn tree_answers(trace: impl Fn(&Ray) -> Option<Hit> + Sync, primary: &[Ray], secondary: &[Ray]) -> Answers {
    [primary, secondary]
        .iter()
        .map(|rays| rays.par_iter().map(&trace).collect())
        .collect()
}

/// Runs `bench gpu`.
pub fn run(a: GpuArgs) -> Result<()> {
    let world = load_world(&a.world)?;
    let mut cameras = fixed_cameras(world.size());
    cameras.truncate(a.cameras.unwrap_or(usize::MAX).max(1));
    let primary = primary_rays(&cameras, a.width, a.height);
    // The secondary rays: cosine bounces off the CPU's primary hits.
    let hits: Vec<Option<Hit>> = primary.par_iter().map(|r| trace_naadf(&world, r)).collect();
    let secondary = secondary_rays(&primary, &hits, a.seed);
    let trees = Trees::build(&world);
    let m = measure_gpu(&world, trees.as_ref(), &Traversal::ALL, &primary, &secondary, a.repeat)?;
    let mut report = GpuReport {
        adapter: m.adapter.clone(),
        primary: BTreeMap::new(),
        secondary: BTreeMap::new(),
        rays: primary.len(),
        secondary_rays: secondary.len(),
        batches: m.batches,
        rounds: a.repeat,
        steps: BTreeMap::new(),
        mismatches: BTreeMap::new(),
        skipped: m.skipped.clone(),
    };
    for (&name, f) in &m.figures {
        report.primary.insert(name, median_range(&f.rates[0]).0);
        report.secondary.insert(name, median_range(&f.rates[1]).0);
        report.steps.insert(name, f.steps);
        report.mismatches.insert(name, f.mismatches);
    }
    if a.json {
        print_json(&report)?;
    } else {
        print_report(&report);
    }
    m.check_mismatches(primary.len() + secondary.len())
}

fn print_report(r: &GpuReport) {
    println!("adapter: {}", r.adapter);
    for (m, p) in &r.primary {
        let st = r.steps[m];
        println!(
            "{m:>6}: primary {p:9.2} Mrays/s ({:.1} steps/ray), secondary {:9.2} Mrays/s ({:.1} steps/ray), {} differ from the CPU",
            st[0], r.secondary[m], st[1], r.mismatches[m]
        );
    }
    for (m, why) in &r.skipped {
        println!("{m:>6}: skipped ({why})");
    }
    println!(
        "{} primary + {} secondary rays, {} batch(es), median of {} rounds",
        r.rays, r.secondary_rays, r.batches, r.rounds
    );
    print_ratios("", &r.primary, &r.secondary);
}

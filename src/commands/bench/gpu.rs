//! `naadf bench gpu WORLD`: ray throughput of the GPU traversal variants (`naadf`, `nodf`
//! and `grid`) on the fixed cameras of `bench traverse`, primary and secondary rays, all
//! measured in one run so that their ratios mean something on a shared machine. Every
//! GPU result is also checked against the CPU `naadf` traversal.

use crate::commands::{load_world, print_json};
use anyhow::{Result, bail};
use naadf_client::gpu::{Gpu, GpuHit, GpuRay, GpuWorld, RayBatch, RayTracer};
use naadf_world::raysets::{fixed_cameras, primary_rays, secondary_rays};
use naadf_world::traverse::{Hit, Method, Ray, Tracer, same_result};
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
    /// Timed runs per variant and ray set; the fastest counts.
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
    /// Mrays/s per variant on primary rays.
    primary: BTreeMap<&'static str, f64>,
    /// Mrays/s per variant on secondary rays.
    secondary: BTreeMap<&'static str, f64>,
    /// Primary rays per run.
    rays: usize,
    /// Secondary rays per run.
    secondary_rays: usize,
    /// Dispatches per run of the primary rays (a ray list larger than one storage binding
    /// is split).
    batches: usize,
    /// Mean cells visited per ray, per variant (primary, secondary).
    steps: BTreeMap<&'static str, [f64; 2]>,
    /// Rays whose GPU result differs from the CPU `naadf` trace of the same `f64` ray,
    /// per variant (primary and secondary together). Only rays within a rounding error
    /// of a tie may differ: the GPU receives the ray rounded to `f32`.
    mismatches: BTreeMap<&'static str, usize>,
    /// Variants not measured, and why.
    skipped: BTreeMap<&'static str, String>,
}

/// A ray set uploaded once, in as many batches as the binding limit needs, with the CPU's
/// answers.
struct RaySet {
    batches: Vec<RayBatch>,
    len: usize,
    cpu: Vec<Option<Hit>>,
}

impl RaySet {
    fn new(gpu: &Gpu, tracer: &RayTracer, rays: &[Ray], cpu: Vec<Option<Hit>>) -> Result<Self> {
        let gpu_rays: Vec<GpuRay> = rays.iter().map(GpuRay::from).collect();
        let batches = gpu_rays
            .chunks(RayTracer::max_batch(gpu).max(1))
            .map(|c| tracer.upload(gpu, c))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(RaySet {
            batches,
            len: rays.len(),
            cpu,
        })
    }

    /// Traces the set once untimed (pipeline build, caches), then `repeat` times; returns
    /// the best Mrays/s, the mean steps and the number of rays differing from the CPU.
    fn measure(
        &self,
        gpu: &Gpu,
        tracer: &mut RayTracer,
        world: &GpuWorld,
        method: Method,
        repeat: u32,
    ) -> Result<(f64, f64, usize)> {
        let run_all = |tracer: &mut RayTracer| -> Result<()> {
            for b in &self.batches {
                tracer.run(gpu, world, b, method)?;
            }
            Ok(())
        };
        run_all(tracer)?;
        let mut best = f64::INFINITY;
        for _ in 0..repeat {
            let t0 = Instant::now();
            run_all(tracer)?;
            best = best.min(t0.elapsed().as_secs_f64());
        }
        let mut results: Vec<GpuHit> = Vec::with_capacity(self.len);
        for b in &self.batches {
            results.extend(tracer.results(gpu, b)?);
        }
        let steps = results.iter().map(|r| f64::from(r.steps)).sum::<f64>() / self.len.max(1) as f64;
        let mismatches = results
            .iter()
            .zip(&self.cpu)
            .filter(|(g, c)| g.exhausted || !same_result(&g.hit, c))
            .count();
        Ok((self.len as f64 / best / 1e6, steps, mismatches))
    }
}

/// Runs `bench gpu`.
pub fn run(a: GpuArgs) -> Result<()> {
    let world = load_world(&a.world)?;
    let mut cameras = fixed_cameras(world.size());
    cameras.truncate(a.cameras.unwrap_or(usize::MAX).max(1));
    let primary = primary_rays(&cameras, a.width, a.height);
    // The CPU oracle, and the secondary rays (cosine bounces off its primary hits).
    let cpu = Tracer::new(&world, Method::Naadf)?;
    let primary_cpu: Vec<Option<Hit>> = primary.par_iter().map(|r| cpu.trace(r)).collect();
    let secondary = secondary_rays(&primary, &primary_cpu, a.seed);
    let secondary_cpu: Vec<Option<Hit>> = secondary.par_iter().map(|r| cpu.trace(r)).collect();

    let gpu = Gpu::new()?;
    let mut gpu_world = GpuWorld::new(&gpu, &world)?;
    let mut report = GpuReport {
        adapter: gpu.describe(),
        primary: BTreeMap::new(),
        secondary: BTreeMap::new(),
        rays: primary.len(),
        secondary_rays: secondary.len(),
        batches: 0,
        steps: BTreeMap::new(),
        mismatches: BTreeMap::new(),
        skipped: BTreeMap::new(),
    };
    if let Err(e) = gpu_world.upload_grid(&world) {
        report.skipped.insert(Method::Grid.name(), e.to_string());
    }
    let mut tracer = RayTracer::new(&gpu);
    let sets = [
        RaySet::new(&gpu, &tracer, &primary, primary_cpu)?,
        RaySet::new(&gpu, &tracer, &secondary, secondary_cpu)?,
    ];
    report.batches = sets[0].batches.len();
    for method in Method::ALL {
        if report.skipped.contains_key(method.name()) {
            tracing::warn!("skipping {}: {}", method.name(), report.skipped[method.name()]);
            continue;
        }
        tracing::info!("measuring {}", method.name());
        let (p_rate, p_steps, p_bad) = sets[0].measure(&gpu, &mut tracer, &gpu_world, method, a.repeat)?;
        let (s_rate, s_steps, s_bad) = sets[1].measure(&gpu, &mut tracer, &gpu_world, method, a.repeat)?;
        report.primary.insert(method.name(), p_rate);
        report.secondary.insert(method.name(), s_rate);
        report.steps.insert(method.name(), [p_steps, s_steps]);
        report.mismatches.insert(method.name(), p_bad + s_bad);
    }
    if a.json {
        print_json(&report)?;
    } else {
        print_report(&report);
    }
    let allowance = (report.rays + report.secondary_rays) / 10_000 + 1;
    if let Some((m, n)) = report.mismatches.iter().find(|(_, n)| **n > allowance) {
        bail!("{n} {m} results differ from the CPU: more than the 1 in 10,000 tie allowance ({allowance})");
    }
    Ok(())
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
        "{} primary + {} secondary rays, {} batch(es)",
        r.rays, r.secondary_rays, r.batches
    );
    super::print_ratios("", &r.primary, &r.secondary);
}

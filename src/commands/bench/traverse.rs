//! `naadf bench traverse WORLD`: ray throughput of the three traversal methods on fixed
//! cameras, and the cost of entities from paired rounds.

use super::shared::{entity_model_op, print_ratios};
use crate::commands::{load_world, print_json};
use anyhow::{Result, bail};
use naadf_world::World;
use naadf_world::ops::{Batch, Limits, Op};
use naadf_world::raysets::{SplitMix64, fixed_cameras, primary_rays, secondary_rays};
use naadf_world::traverse::{Hit, Method, Ray, Tracer, same_result};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `bench traverse`.
#[derive(clap::Args)]
pub struct TraverseArgs {
    /// World file.
    world: PathBuf,
    /// Image width per camera.
    #[arg(long, default_value_t = 480)]
    width: u32,
    /// Image height per camera.
    #[arg(long, default_value_t = 270)]
    height: u32,
    /// Timed runs per method and ray set; the fastest counts.
    #[arg(long, default_value_t = 1)]
    repeat: u32,
    /// Seed of the secondary-ray directions.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// After the plain run, spawn this many entities (8³ models at random poses), measure
    /// again and report the entity cost from paired rounds (see `--rounds`).
    #[arg(long, default_value_t = 0)]
    entities: u32,
    /// Where the entities go: resting on the ground (`surface`, like characters and
    /// vehicles) or anywhere in the air (`air`, the worst case for chunk AADFs).
    #[arg(long, default_value = "surface", value_parser = ["surface", "air"])]
    placement: String,
    /// Paired rounds behind the entity cost, per traversal method: each round traces both
    /// ray sets without and with the entities, a quarter set at a time, alternating which
    /// goes first.
    #[arg(long, default_value_t = 15)]
    rounds: u32,
    /// Also write the world with the entities to this file (for `bench gpu` and `render`).
    #[arg(long)]
    save_entities: Option<PathBuf>,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct TraverseReport {
    /// Mrays/s per method on primary rays.
    primary: BTreeMap<&'static str, f64>,
    /// Mrays/s per method on secondary rays.
    secondary: BTreeMap<&'static str, f64>,
    /// Primary rays per run.
    rays: usize,
    /// Secondary rays per run.
    secondary_rays: usize,
    /// Worker threads.
    threads: usize,
    /// Mean cells visited per ray, per method (primary, secondary).
    steps: BTreeMap<&'static str, [f64; 2]>,
    /// Rays on which a method disagreed with `naadf` (must be 0).
    mismatches: usize,
}

/// Rays a worker traces at a time ([`Tracer::trace_many`]), as a renderer hands them over.
const SLICE: usize = 1024;

/// Pieces a ray set is cut into for the paired rounds of [`EntityCost`].
const PIECES: usize = 4;

/// Traces `rays` on the worker threads, a slice at a time.
fn trace_slices(tracer: &Tracer, rays: &[Ray]) -> Vec<Option<Hit>> {
    rays.par_chunks(SLICE).flat_map_iter(|c| tracer.trace_many(c)).collect()
}

/// Traces `rays` `repeat` times; returns the best Mrays/s, the hits and mean steps.
fn time_rays(tracer: &Tracer, rays: &[Ray], repeat: u32) -> (f64, Vec<Option<Hit>>, f64) {
    // Warm caches and the thread pool.
    std::hint::black_box(trace_slices(tracer, &rays[..rays.len() / 20]));
    let mut best = f64::INFINITY;
    let mut hits = Vec::new();
    for _ in 0..repeat.max(1) {
        let t0 = Instant::now();
        hits = trace_slices(tracer, rays);
        best = best.min(t0.elapsed().as_secs_f64());
    }
    // Steps of missed rays are not reported by the tracer; count hits only.
    let steps: Vec<u32> = hits.iter().flatten().map(|h| h.steps).collect();
    let mean = steps.iter().map(|&s| f64::from(s)).sum::<f64>() / steps.len().max(1) as f64;
    (rays.len() as f64 / best / 1e6, hits, mean)
}

/// The results of the first method run, which the other methods must reproduce.
struct Reference {
    primary_hits: Vec<Option<Hit>>,
    secondary: Vec<Ray>,
    secondary_hits: Vec<Option<Hit>>,
}

/// Runs `bench traverse`.
pub fn run(a: TraverseArgs) -> Result<()> {
    let world = load_world(&a.world)?;
    let (plain, secondary) = measure(&world, &a, None)?;
    let with_entities = if a.entities > 0 {
        let mut crowded = world.clone();
        spawn_entities(&mut crowded, a.entities, a.seed, a.placement == "air")?;
        report_instances(&crowded)?;
        if let Some(path) = &a.save_entities {
            naadf_world::file::save(&crowded, path)?;
        }
        // The same rays as the plain run, so that the difference is the entities' cost.
        let (report, _) = measure(&crowded, &a, Some(secondary.clone()))?;
        let primary = primary_rays(&fixed_cameras(world.size()), a.width, a.height);
        let cost = EntityCost::measure(&crowded, [&primary, &secondary], a.rounds)?;
        report_walk(&crowded, [&primary, &secondary])?;
        Some((report, cost))
    } else {
        None
    };
    let mismatches = plain.mismatches + with_entities.as_ref().map_or(0, |(r, _)| r.mismatches);
    if a.json {
        #[derive(Serialize)]
        struct Out {
            #[serde(flatten)]
            plain: TraverseReport,
            #[serde(skip_serializing_if = "Option::is_none")]
            with_entities: Option<TraverseReport>,
            #[serde(skip_serializing_if = "Option::is_none")]
            entity_cost: Option<EntityCost>,
        }
        let (with_entities, entity_cost) = with_entities.unzip();
        print_json(&Out {
            plain,
            with_entities,
            entity_cost,
        })?;
    } else {
        print_report("", &plain);
        if let Some((r, cost)) = &with_entities {
            print_report(&format!("with {} entities: ", a.entities), r);
            cost.print();
        }
    }
    if mismatches > 0 {
        bail!("{mismatches} rays differ between methods");
    }
    Ok(())
}

/// The ray-throughput cost of entities: the same rays traced through the world with them
/// and through its static world alone ([`Tracer::static_only`]: the world without
/// entities, byte for byte, in the same memory), in interleaved rounds so that both sides
/// of each ratio see the same machine.
#[derive(Serialize)]
struct EntityCost {
    /// Paired rounds per method.
    rounds: u32,
    /// Per method, `[primary, secondary, all rays]`: the median over rounds of
    /// `1 − with/without` (rays per second), as a percentage.
    median_percent: BTreeMap<&'static str, [f64; 3]>,
    /// Per method, `[primary, secondary, all rays]`: the `[lowest, highest]` round.
    range_percent: BTreeMap<&'static str, [[f64; 2]; 3]>,
}

impl EntityCost {
    /// Times `naadf` and `nodf` (the grid method is too slow for many rounds), without and
    /// with the entities. Each round traces both ray sets once per tracer, a piece at a
    /// time: each piece (one [`PIECES`]th of a set) goes through both back to back,
    /// alternating which goes first, so that both sides of a ratio see the machine within
    /// milliseconds of each other (neighbours that steal the processor for a while then slow
    /// both alike).
    fn measure(crowded: &World, sets: [&[Ray]; 2], rounds: u32) -> Result<Self> {
        let rounds = rounds.max(1);
        let mut median_percent = BTreeMap::new();
        let mut range_percent = BTreeMap::new();
        for method in [Method::Naadf, Method::Nodf] {
            let tracers = [
                Tracer::new(crowded, method)?.static_only(),
                Tracer::new(crowded, method)?,
            ];
            for (t, rays) in tracers.iter().zip(sets) {
                trace_all(t, rays);
            }
            // Per set (and for both together): the cost of each round.
            let mut costs: [Vec<f64>; 3] = Default::default();
            for round in 0..rounds {
                // secs[world][set]
                let mut secs = [[0.0; 2]; 2];
                for (k, rays) in sets.iter().enumerate() {
                    for (p, piece) in rays.chunks(rays.len().div_ceil(PIECES).max(1)).enumerate() {
                        let order = if (round as usize + p).is_multiple_of(2) {
                            [0, 1]
                        } else {
                            [1, 0]
                        };
                        for w in order {
                            let t0 = Instant::now();
                            trace_all(&tracers[w], piece);
                            secs[w][k] += t0.elapsed().as_secs_f64();
                        }
                    }
                }
                let cost = |plain: f64, crowded: f64| 100.0 * (1.0 - plain / crowded);
                costs[0].push(cost(secs[0][0], secs[1][0]));
                costs[1].push(cost(secs[0][1], secs[1][1]));
                costs[2].push(cost(secs[0][0] + secs[0][1], secs[1][0] + secs[1][1]));
            }
            let mut median = [0.0; 3];
            let mut range = [[0.0; 2]; 3];
            for (k, c) in costs.iter_mut().enumerate() {
                c.sort_by(f64::total_cmp);
                median[k] = super::shared::percentile(c, 0.5);
                range[k] = [c[0], c[c.len() - 1]];
            }
            median_percent.insert(method.name(), median);
            range_percent.insert(method.name(), range);
        }
        Ok(EntityCost {
            rounds,
            median_percent,
            range_percent,
        })
    }

    fn print(&self) {
        for (m, median) in &self.median_percent {
            let range = self.range_percent[m];
            let parts: Vec<String> = ["primary", "secondary", "all rays"]
                .iter()
                .enumerate()
                .map(|(k, set)| format!("{set} {:.1}% ({:.1}…{:.1})", median[k], range[k][0], range[k][1]))
                .collect();
            println!(
                "entity cost ({m}, median of {} paired rounds): {}",
                self.rounds,
                parts.join(", ")
            );
        }
    }
}

/// Traces every ray once, in parallel, keeping only a checksum so the work is not elided.
fn trace_all(tracer: &Tracer, rays: &[Ray]) {
    let steps: u64 = rays
        .par_chunks(SLICE)
        .map(|c| {
            tracer
                .trace_many(c)
                .iter()
                .flatten()
                .map(|h| u64::from(h.steps))
                .sum::<u64>()
        })
        .sum();
    std::hint::black_box(steps);
}

fn print_report(prefix: &str, r: &TraverseReport) {
    for (m, p) in &r.primary {
        let st = r.steps[m];
        eprintln!(
            "{prefix}{m:>6}: primary {p:8.2} Mrays/s ({:.1} steps/hit), secondary {:8.2} Mrays/s ({:.1} steps/hit)",
            st[0], r.secondary[m], st[1]
        );
    }
    println!(
        "{prefix}{} primary + {} secondary rays, {} threads",
        r.rays, r.secondary_rays, r.threads
    );
    print_ratios(prefix, &r.primary, &r.secondary);
}

/// Spawns `n` 8³ entities (a hollow box) at random poses, in one batch: on the ground
/// (found with a downward ray per column) or, with `air`, at random heights.
/// What the entities cost outside the ray loop: the hierarchy's size, and the time a batch
/// moving every entity takes to apply (which rebuilds the instance buffer and the
/// hierarchy), the median of 5 on a copy.
fn report_instances(world: &World) -> Result<()> {
    let words = world.entity_hierarchy_words();
    let mut copy = world.clone();
    // Per round: applying the batch, then deriving and packing the hierarchy (what a
    // machine that traces or uploads it pays once after the batch).
    let (mut applied, mut derived) = (Vec::new(), Vec::new());
    for round in 0..5 {
        let dx = if round % 2 == 0 { 0.5 } else { -0.5 };
        applied.push(move_all(&mut copy, |p| [p[0] + dx, p[1], p[2]])?.as_secs_f64() * 1e3);
        let t = Instant::now();
        std::hint::black_box(copy.entity_hierarchy_words());
        derived.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        format!("{:.2} ms ({:.2}…{:.2})", v[2], v[0], v[4])
    };
    let half_voxel = copy.entity_instances().to_vec();
    report_refit(world, &half_voxel)?;
    eprintln!(
        "instances: {} in the instance buffer ({} B), hierarchy of {} nodes ({} B); a batch moving all by half a voxel, median of 5: applied {}, its hierarchy derived and packed {}",
        world.entity_table().instances.len(),
        world.entity_instances().len() * 4,
        words.len() / naadf_world::entity::bvh::NODE_WORDS,
        words.len() * 4,
        median(&mut applied),
        median(&mut derived)
    );
    Ok(())
}

/// Where the entity cost of a ray comes from: on one thread, over `sets`, the time a ray
/// takes through `crowded`'s static world alone ([`Tracer::static_only`]) and through
/// `crowded`, traced one by one and in slices ([`Tracer::trace_many`]), against the time the
/// walk through its instance hierarchy alone takes over the rays' spans (from where each
/// enters the world to its static hit or where it leaves), ray by ray and as batches; the
/// median of 7 rounds, the five alternated.
fn report_walk(crowded: &World, sets: [&[Ray]; 2]) -> Result<()> {
    use naadf_world::entity::bvh::Bvh;
    use naadf_world::entity::bvh::WalkRay;
    use naadf_world::entity::bvh::batch::Scratch;
    let bvh = Bvh::build(&naadf_world::entity::instance_boxes(crowded.entity_instances()));
    let dims = crowded.size().voxels();
    let [plain, crowded] = [
        Tracer::new(crowded, Method::Naadf)?.static_only(),
        Tracer::new(crowded, Method::Naadf)?,
    ];
    let rays: Vec<Ray> = sets.iter().flat_map(|rays| rays.iter().copied()).collect();
    // Each ray's walk over its span; rays that miss the world are left out.
    let walks: Vec<WalkRay> = rays
        .iter()
        .filter_map(|r| {
            let (lo, hi) = r.span_in(dims)?;
            let end = plain.trace(r).map_or(hi, |h| h.t);
            Some(WalkRay::new(r.origin(), r.dir(), lo, end))
        })
        .collect();
    // Hits counted, so that the traces are not elided.
    let one_by_one = |t: &Tracer| rays.iter().filter(|r| t.trace(r).is_some()).count() as u64;
    let in_slices = |t: &Tracer| {
        rays.chunks(SLICE)
            .map(|c| t.trace_many(c).iter().flatten().count() as u64)
            .sum::<u64>()
    };
    // Nanoseconds per item of `n` that `work` takes.
    let ns_per = |n: usize, work: &mut dyn FnMut()| {
        let t = Instant::now();
        work();
        t.elapsed().as_secs_f64() * 1e9 / n.max(1) as f64
    };
    let mut times: [Vec<f64>; 5] = Default::default();
    let mut sink = 0u64;
    let mut scratch = Scratch::default();
    for _ in 0..7 {
        times[0].push(ns_per(rays.len(), &mut || sink += in_slices(&plain)));
        times[1].push(ns_per(walks.len(), &mut || {
            for w in &walks {
                bvh.crossing(w, |k| sink += u64::from(k));
            }
        }));
        times[2].push(ns_per(walks.len(), &mut || {
            for c in walks.chunks(SLICE) {
                sink += bvh
                    .crossing_many(c, &mut scratch)
                    .iter()
                    .map(|&(i, k)| u64::from(i ^ k))
                    .sum::<u64>();
            }
        }));
        times[3].push(ns_per(rays.len(), &mut || sink += one_by_one(&crowded)));
        times[4].push(ns_per(rays.len(), &mut || sink += in_slices(&crowded)));
    }
    std::hint::black_box(sink);
    let [world_ray, walk, walk_many, crowded_ray, crowded_many] = times.map(|mut v| {
        v.sort_by(f64::total_cmp);
        v[3]
    });
    let more = |t: f64| 100.0 * (t - world_ray) / world_ray;
    eprintln!(
        "one thread, ns per ray (median of 7): without entities {world_ray:.1}; with them {crowded_ray:.1} one by one ({:.1} % more), \
         {crowded_many:.1} in slices of {SLICE} ({:.1} % more); the hierarchy's walk alone over the rays' spans {walk:.1} ray by ray \
         ({:.1} % of a ray without entities), {walk_many:.1} in batches ({:.1} %)",
        more(crowded_ray),
        more(crowded_many),
        100.0 * walk / world_ray,
        100.0 * walk_many / world_ray
    );
    Ok(())
}

/// Moves every entity of `world` to `to(its position)`, rotation kept, in one batch;
/// returns how long applying the batch took.
fn move_all(world: &mut World, mut to: impl FnMut([f64; 3]) -> [f64; 3]) -> Result<std::time::Duration> {
    let moves = world
        .entity_table()
        .instances
        .iter()
        .map(|(&id, p)| Op::MoveEntity {
            id,
            pos: to(p.pos),
            rot: p.rot,
        })
        .collect::<Vec<_>>();
    let n = moves.len();
    let limits = Limits {
        max_ops: n,
        ..Limits::default()
    };
    let t = std::time::Instant::now();
    world.apply(&Batch { ops: moves }, &limits)?;
    Ok(t.elapsed())
}

/// Rebuilding the hierarchy against refitting it (keeping its shape, moving its boxes),
/// after every entity moved by half a voxel (`half_voxel`: that instance buffer) and after
/// every entity moved anywhere: the time each takes (median of 5) and the nodes a ray is
/// expected to visit ([`Bvh::expected_visits`]).
fn report_refit(world: &World, half_voxel: &[u32]) -> Result<()> {
    use naadf_world::entity::bvh::Bvh;
    use naadf_world::entity::instance_boxes;
    let before = instance_boxes(world.entity_instances());
    let mut anywhere = world.clone();
    let s = world.size().voxels().map(f64::from);
    let mut rng = SplitMix64(0x4EF1);
    move_all(&mut anywhere, |_| [0, 1, 2].map(|a| 4.0 + rng.unit() * (s[a] - 24.0)))?;
    let built = Bvh::build(&before);
    for (what, words) in [("half a voxel", half_voxel), ("anywhere", anywhere.entity_instances())] {
        let after = instance_boxes(words);
        let median = |f: &mut dyn FnMut() -> Bvh| {
            let mut ms: Vec<f64> = (0..5)
                .map(|_| {
                    let t = std::time::Instant::now();
                    std::hint::black_box(f());
                    t.elapsed().as_secs_f64() * 1e3
                })
                .collect();
            ms.sort_by(f64::total_cmp);
            ms[2]
        };
        let rebuild_ms = median(&mut || Bvh::build(&after));
        let refit_ms = median(&mut || {
            let mut b = built.clone();
            b.refit(&after);
            b
        });
        let mut refit = built.clone();
        refit.refit(&after);
        eprintln!(
            "hierarchy after moving every entity {what}: rebuild {rebuild_ms:.3} ms, {:.1} expected node visits; refit {refit_ms:.3} ms (a clone included), {:.1} expected node visits",
            Bvh::build(&after).expected_visits(),
            refit.expected_visits()
        );
    }
    Ok(())
}

fn spawn_entities(world: &mut World, n: u32, seed: u64, air: bool) -> Result<()> {
    let model = entity_model_op();
    let s = world.size().voxels().map(f64::from);
    let mut rng = SplitMix64(seed ^ 0xE171);
    let mut unit = || rng.unit();
    let mut ops = vec![model];
    for id in 0..n {
        let (x, z, h) = (unit() * (s[0] - 16.0) + 4.0, unit() * (s[2] - 16.0) + 4.0, unit());
        let ground = || {
            let down = Ray::new([x + 4.0, s[1] - 0.5, z + 4.0], [0.0, -1.0, 0.0]).ok()?;
            naadf_world::traverse::trace_naadf(world, &down).map(|hit| f64::from(hit.voxel[1]) + 2.0)
        };
        let y = if air { None } else { ground() }.unwrap_or((0.3 + 0.6 * h) * s[1]);
        let pos = [x, y.min(s[1] - 12.0), z];
        let rot = [unit() - 0.5, unit() - 0.5, unit() - 0.5, unit() - 0.5];
        ops.push(Op::SpawnEntity {
            id,
            model: "bench_box".into(),
            pos,
            rot,
        });
    }
    world.apply(
        &Batch { ops },
        &Limits {
            max_ops: n as usize + 1,
            ..Limits::default()
        },
    )?;
    world.grow_until_quiescent();
    Ok(())
}

/// Measures every method on the fixed primary rays of `world` and on `secondary` (by
/// default, cosine rays from the first method's primary hits). Returns the report and the
/// secondary rays used.
fn measure(world: &World, a: &TraverseArgs, secondary: Option<Vec<Ray>>) -> Result<(TraverseReport, Vec<Ray>)> {
    let primary = primary_rays(&fixed_cameras(world.size()), a.width, a.height);
    let mut report = TraverseReport {
        primary: BTreeMap::new(),
        secondary: BTreeMap::new(),
        rays: primary.len(),
        secondary_rays: 0,
        threads: rayon::current_num_threads(),
        steps: BTreeMap::new(),
        mismatches: 0,
    };
    // The first method's results, which the others must reproduce.
    let mut reference: Option<Reference> = None;
    for method in Method::ALL {
        let tracer = match Tracer::new(world, method) {
            Ok(t) => t,
            Err(e) => {
                tracing::warn!("skipping {}: {e}", method.name());
                continue;
            }
        };
        let (p_rate, p_hits, p_steps) = time_rays(&tracer, &primary, a.repeat);
        let secondary = match (&reference, &secondary) {
            (Some(r), _) => r.secondary.clone(),
            (None, Some(fixed)) => fixed.clone(),
            (None, None) => secondary_rays(&primary, &p_hits, a.seed),
        };
        let (s_rate, s_hits, s_steps) = time_rays(&tracer, &secondary, a.repeat);
        match &reference {
            None => {
                reference = Some(Reference {
                    primary_hits: p_hits,
                    secondary,
                    secondary_hits: s_hits,
                })
            }
            Some(r) => {
                report.mismatches += r
                    .primary_hits
                    .iter()
                    .zip(&p_hits)
                    .filter(|(x, y)| !same_result(x, y))
                    .count();
                report.mismatches += r
                    .secondary_hits
                    .iter()
                    .zip(&s_hits)
                    .filter(|(x, y)| !same_result(x, y))
                    .count();
            }
        }
        report.primary.insert(method.name(), p_rate);
        report.secondary.insert(method.name(), s_rate);
        report.steps.insert(method.name(), [p_steps, s_steps]);
    }
    let secondary = reference.map(|r| r.secondary).unwrap_or_default();
    report.secondary_rays = secondary.len();
    Ok((report, secondary))
}

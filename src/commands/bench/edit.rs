//! `naadf bench edit`: edit latency, change-set sizes (and what each change costs on the
//! wire in the record and the patch form), background regrowth and a real edit stream
//! (HashDAG `EditSphere` replays), on a generated world.

use super::shared::{percentile, surface};
use crate::commands::args::PresetArgs;
use crate::commands::print_json;
use anyhow::{Context, Result, bail};
use naadf_client::patch::{PatchMaker, delta_sizes};
use naadf_world::World;
use naadf_world::edit::ChangeSet;
use naadf_world::ops::{Batch, Limits, Op};
use naadf_world::raysets::SplitMix64;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `bench edit`.
#[derive(clap::Args)]
pub struct EditArgs {
    #[command(flatten)]
    preset: PresetArgs,
    /// Edits per kind (single voxel, spheres of radius 4 and 16); radius 64 uses a quarter.
    #[arg(long, default_value_t = 200)]
    edits: usize,
    /// A HashDAG replay CSV whose `EditSphere` rows are scaled into the world and applied.
    #[arg(long)]
    replay: Option<PathBuf>,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize, Default)]
struct KindReport {
    edits: usize,
    median_us: f64,
    p99_us: f64,
    /// Encoded change record, bytes (median).
    record_bytes: usize,
    /// The record after zstd level 3, bytes (median).
    record_zstd_bytes: usize,
    /// Buffer words the change wrote (median): what a GPU mirror uploads.
    words_written: u64,
    /// The `Delta` message of the edit in the record form, bytes (median).
    delta_record_bytes: usize,
    /// The same in the patch form, bytes (median).
    delta_patch_bytes: usize,
    /// The growth steps that followed the edit, in all: record form, bytes (median).
    growth_record_bytes: usize,
    /// The same in the patch form, bytes (median).
    growth_patch_bytes: usize,
    /// Making the edit's patch (what the server's actor does for every change besides
    /// applying it), µs (median).
    patch_us: f64,
}

/// What a run of changes costs on the wire in each form, bytes, and making the patches.
#[derive(Serialize, Default)]
struct WireBytes {
    record: u64,
    patch: u64,
    /// Making the patches, µs.
    patch_us: f64,
}

impl WireBytes {
    /// Adds the deltas of `changes`, which `world` has applied, made with `maker`; returns
    /// their sizes in each form.
    fn add(&mut self, maker: &mut PatchMaker, world: &World, changes: &[ChangeSet]) -> [usize; 2] {
        let mut sum = [0; 2];
        for cs in changes {
            let t0 = Instant::now();
            let patch = maker.patch(world, cs);
            self.patch_us += t0.elapsed().as_secs_f64() * 1e6;
            let [r, p] = delta_sizes(cs, patch);
            sum = [sum[0] + r, sum[1] + p];
        }
        self.record += sum[0] as u64;
        self.patch += sum[1] as u64;
        sum
    }
}

#[derive(Serialize)]
struct ReplayReport {
    file: String,
    edits: usize,
    scale: f64,
    /// `World::apply` only (invalidation included).
    edits_per_s: f64,
    /// Growth to quiescence after the whole stream.
    growth_ms: f64,
    /// The edits' deltas on the wire, in all.
    edit_bytes: WireBytes,
    /// The growth steps' deltas on the wire, in all.
    growth_bytes: WireBytes,
}

#[derive(Serialize)]
struct EditReport {
    size: [u32; 3],
    kinds: BTreeMap<&'static str, KindReport>,
    /// Background growth until quiescent after an edit that empties whole chunks (median).
    regrow_after_emptying_ms: f64,
    regrow_samples: usize,
    /// One batch moving all 1,000 entities, invalidation included (median of 10).
    entity_move_1000_ms: f64,
    /// Encoded record of that batch, bytes.
    entity_move_1000_record_bytes: usize,
    /// Its `Delta` on the wire: record form, patch form, bytes.
    entity_move_1000_delta_bytes: [usize; 2],
    replay: Option<ReplayReport>,
}

fn median<T: Copy + Ord + Default>(mut v: Vec<T>) -> T {
    v.sort_unstable();
    v.get(v.len() / 2).copied().unwrap_or_default()
}

/// Times `batches` one by one, converging growth (untimed) after each.
fn time_batches(world: &mut World, batches: &[Batch]) -> Result<KindReport> {
    let limits = Limits::default();
    let (mut times, mut bytes, mut zbytes, mut words) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut edit_wire, mut growth_wire) = (Vec::new(), Vec::new());
    let mut maker = PatchMaker::new(world);
    let mut wire = WireBytes::default();
    let mut patch_us = Vec::new();
    for b in batches {
        let t0 = Instant::now();
        let applied = world.apply(b, &limits)?;
        times.push(t0.elapsed().as_secs_f64() * 1e6);
        let rec = applied.change.encode();
        zbytes.push(zstd::bulk::compress(&rec, 3)?.len());
        bytes.push(rec.len());
        words.push(applied.change.writes.words());
        let before = wire.patch_us;
        edit_wire.push(wire.add(&mut maker, world, std::slice::from_ref(&applied.change)));
        patch_us.push(wire.patch_us - before);
        // The growth steps' patches read the buffers once growth is done: their sizes,
        // not their exact bytes, are what counts here.
        let grown = world.grow_until_quiescent();
        growth_wire.push(wire.add(&mut maker, world, &grown));
    }
    let form = |v: &[[usize; 2]], k: usize| median(v.iter().map(|s| s[k]).collect());
    times.sort_by(f64::total_cmp);
    Ok(KindReport {
        edits: batches.len(),
        median_us: percentile(&times, 0.5),
        p99_us: percentile(&times, 0.99),
        record_bytes: median(bytes),
        record_zstd_bytes: median(zbytes),
        words_written: median(words),
        delta_record_bytes: form(&edit_wire, 0),
        delta_patch_bytes: form(&edit_wire, 1),
        growth_record_bytes: form(&growth_wire, 0),
        growth_patch_bytes: form(&growth_wire, 1),
        patch_us: {
            patch_us.sort_by(f64::total_cmp);
            percentile(&patch_us, 0.5)
        },
    })
}

/// Runs the edit benchmark.
pub fn run(a: EditArgs) -> Result<()> {
    let mut world = a.preset.generate()?;
    let size = world.size().voxels();
    let mut rng = SplitMix64(a.preset.seed);
    let mut points = Vec::new();
    while points.len() < a.edits.max(8) {
        if let Some(p) = surface(&world, rng.below(size[0]), rng.below(size[2])) {
            points.push(p);
        }
    }
    let mut kinds = BTreeMap::new();
    let voxel_batches: Vec<Batch> = points
        .iter()
        .enumerate()
        .map(|(k, p)| Batch {
            ops: vec![Op::Set {
                voxels: vec![[p[0], p[1] + 1, p[2], (k % 2) as u32 * 2].map(i64::from)],
            }],
        })
        .collect();
    kinds.insert("voxel", time_batches(&mut world, &voxel_batches)?);
    for (name, r, n) in [
        ("sphere_r4", 4.0, a.edits),
        ("sphere_r16", 16.0, a.edits),
        ("sphere_r64", 64.0, a.edits / 4),
    ] {
        let batches: Vec<Batch> = points
            .iter()
            .take(n.max(2))
            .enumerate()
            .map(|(k, p)| Batch {
                ops: vec![Op::Sphere {
                    center: p.map(|v| f64::from(v) + 0.5),
                    radius: r,
                    material: if k % 2 == 0 { 0 } else { 3 },
                }],
            })
            .collect();
        kinds.insert(name, time_batches(&mut world, &batches)?);
    }
    // Erasing a 48³ box under the surface empties whole chunks; time the regrowth.
    let mut regrow = Vec::new();
    for p in points.iter().take(5) {
        let c = [
            p[0].saturating_sub(24),
            p[1].saturating_sub(60),
            p[2].saturating_sub(24),
        ]
        .map(i64::from);
        let b = Batch {
            ops: vec![Op::Box {
                min: c,
                max: c.map(|v| v + 48),
                material: 0,
            }],
        };
        world.apply(&b, &Limits::default())?;
        let t0 = Instant::now();
        world.grow_until_quiescent();
        regrow.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    regrow.sort_by(f64::total_cmp);
    let (entity_move_1000_ms, entity_move_1000_record_bytes, entity_move_1000_delta_bytes) =
        time_entity_moves(&mut world, &points)?;
    let replay = a
        .replay
        .as_ref()
        .map(|path| replay_hashdag(&mut world, path))
        .transpose()?;
    let report = EditReport {
        size,
        kinds,
        regrow_after_emptying_ms: percentile(&regrow, 0.5),
        regrow_samples: regrow.len(),
        entity_move_1000_ms,
        entity_move_1000_record_bytes,
        entity_move_1000_delta_bytes,
        replay,
    };
    if a.json {
        return print_json(&report);
    }
    for (name, k) in &report.kinds {
        println!(
            "{name:>10}: median {:8.1} µs, p99 {:8.1} µs, record {} B ({} B zstd), {} words written",
            k.median_us, k.p99_us, k.record_bytes, k.record_zstd_bytes, k.words_written
        );
        println!(
            "{:>10}  delta {} B record / {} B patch (made in {:.1} µs); its growth steps {} B record / {} B patch",
            "", k.delta_record_bytes, k.delta_patch_bytes, k.patch_us, k.growth_record_bytes, k.growth_patch_bytes
        );
    }
    println!(
        "regrowth after emptying chunks: {:.1} ms (median of {})",
        report.regrow_after_emptying_ms, report.regrow_samples
    );
    println!(
        "moving 1000 entities in one batch: {:.2} ms, record {} B; delta {} B record / {} B patch",
        report.entity_move_1000_ms,
        report.entity_move_1000_record_bytes,
        report.entity_move_1000_delta_bytes[0],
        report.entity_move_1000_delta_bytes[1]
    );
    if let Some(r) = &report.replay {
        println!(
            "replay {}: {} edits at {:.0} edits/s (scale {:.4}), growth {:.1} ms",
            r.file, r.edits, r.edits_per_s, r.scale, r.growth_ms
        );
        println!(
            "  on the wire: edits {} B record / {} B patch; growth {} B record / {} B patch",
            r.edit_bytes.record, r.edit_bytes.patch, r.growth_bytes.record, r.growth_bytes.patch
        );
    }
    Ok(())
}

/// Spawns 1,000 entities a few voxels above surface points, then times batches that move
/// all of them by a voxel or two (converging growth, untimed, between batches). Returns
/// the median time, and the last batch's record and `Delta` sizes (record, patch form).
fn time_entity_moves(world: &mut World, points: &[[u32; 3]]) -> Result<(f64, usize, [usize; 2])> {
    let limits = Limits {
        max_ops: 2000,
        ..Limits::default()
    };
    let pose = |k: usize, step: usize| {
        let p = points[k % points.len()];
        let (x, z) = ((p[0] as usize + 13 * (k / points.len())) % 1000, p[2] as usize);
        [
            x as f64 + (step % 3) as f64,
            f64::from(p[1]) + 6.0,
            z as f64 + 0.5 * (step % 2) as f64,
        ]
    };
    let mut ops = vec![super::shared::entity_model_op()];
    ops.extend((0..1000).map(|k| Op::SpawnEntity {
        id: k as u32,
        model: "bench_box".into(),
        pos: pose(k, 0),
        rot: [0.0, 0.0, 0.0, 1.0],
    }));
    world.apply(&Batch { ops }, &limits)?;
    world.grow_until_quiescent();
    let mut times = Vec::new();
    let (mut bytes, mut wire) = (0, [0; 2]);
    let mut maker = PatchMaker::new(world);
    for step in 1..=10 {
        let ops = (0..1000)
            .map(|k| Op::MoveEntity {
                id: k as u32,
                pos: pose(k, step),
                rot: [0.0, (step as f64 * 0.1).sin(), 0.0, (step as f64 * 0.1).cos()],
            })
            .collect();
        let t0 = Instant::now();
        let applied = world.apply(&Batch { ops }, &limits)?;
        times.push(t0.elapsed().as_secs_f64() * 1e3);
        bytes = applied.change.encode().len();
        wire = delta_sizes(&applied.change, maker.patch(world, &applied.change));
        for grown in world.grow_until_quiescent() {
            maker.patch(world, &grown);
        }
    }
    times.sort_by(f64::total_cmp);
    Ok((percentile(&times, 0.5), bytes, wire))
}

/// Applies the `EditSphere,x,y,z,radius,add` rows of a HashDAG replay, scaled uniformly so
/// that the edited region fits the world (radii scaled alike, at least 1.5 voxels).
fn replay_hashdag(world: &mut World, path: &std::path::Path) -> Result<ReplayReport> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut spheres = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let f: Vec<&str> = line.split(',').collect();
        if f.first() != Some(&"EditSphere") {
            continue;
        }
        let num = |i: usize| -> Result<f64> {
            f.get(i)
                .and_then(|s| s.trim().parse().ok())
                .with_context(|| format!("{}:{}: bad EditSphere row", path.display(), n + 1))
        };
        spheres.push((
            [num(1)?, num(2)?, num(3)?],
            num(4)?,
            f.get(5).is_some_and(|s| s.trim() == "true"),
        ));
    }
    if spheres.is_empty() {
        bail!("{}: no EditSphere rows", path.display());
    }
    let lo: [f64; 3] = std::array::from_fn(|a| spheres.iter().map(|s| s.0[a]).fold(f64::INFINITY, f64::min));
    let hi: [f64; 3] = std::array::from_fn(|a| spheres.iter().map(|s| s.0[a]).fold(f64::NEG_INFINITY, f64::max));
    let size = world.size().voxels().map(f64::from);
    let scale = (0..3)
        .map(|a| size[a] / (hi[a] - lo[a]).max(1.0))
        .fold(f64::INFINITY, f64::min);
    let batches: Vec<Batch> = spheres
        .iter()
        .map(|(c, r, add)| Batch {
            ops: vec![Op::Sphere {
                center: std::array::from_fn(|a| (c[a] - lo[a]) * scale),
                radius: (r * scale).max(1.5),
                material: if *add { 4 } else { 0 },
            }],
        })
        .collect();
    let limits = Limits::default();
    let mut maker = PatchMaker::new(world);
    let (mut edit_bytes, mut growth_bytes) = (WireBytes::default(), WireBytes::default());
    let mut apply_s = 0.0;
    for b in &batches {
        let t0 = Instant::now();
        let applied = world.apply(b, &limits)?;
        apply_s += t0.elapsed().as_secs_f64();
        edit_bytes.add(&mut maker, world, std::slice::from_ref(&applied.change));
    }
    let t1 = Instant::now();
    let grown = world.grow_until_quiescent();
    let growth_ms = t1.elapsed().as_secs_f64() * 1e3;
    growth_bytes.add(&mut maker, world, &grown);
    Ok(ReplayReport {
        file: path.display().to_string(),
        edits: batches.len(),
        scale,
        edits_per_s: batches.len() as f64 / apply_s,
        growth_ms,
        edit_bytes,
        growth_bytes,
    })
}

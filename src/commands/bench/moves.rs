//! `naadf bench moves`: entity moves under load on loopback — `MoveEntities` calls, each
//! moving every one of `--entities` entities to a new pose (one version each), at each of
//! `--rates` calls a second with `--clients` CPU mirrors following, each a `naadf mirror`
//! process of its own (or, with `--in-process`, tasks in the server's process as `bench
//! stream` runs them), and the move-to-every-mirror latency of each call; plus the bytes a
//! move takes in the record and the patch form.

use super::stream::{Editor, LatencyReport, LocalServer, Mirrors, describe, latency_run};
use crate::commands::args::PresetArgs;
use crate::commands::print_json;
use crate::commands::remote::block_on;
use anyhow::{Result, bail};
use naadf_client::Pose;
use naadf_client::patch::{PatchMaker, delta_sizes};
use naadf_world::WorldSize;
use naadf_world::ops::{Batch, Limits, Op};
use naadf_world::raysets::SplitMix64;
use serde::Serialize;

/// Arguments of `bench moves`.
#[derive(clap::Args)]
pub struct MovesArgs {
    #[command(flatten)]
    preset: PresetArgs,
    /// Entities, each moved by every call.
    #[arg(long, default_value_t = 1000)]
    entities: u32,
    /// Calls per second of the latency runs, one run each.
    #[arg(long, value_delimiter = ',', default_value = "60")]
    rates: Vec<u32>,
    /// Mirror clients following.
    #[arg(long, default_value_t = 16)]
    clients: usize,
    /// Seconds per run.
    #[arg(long, default_value_t = 60.0)]
    seconds: f64,
    /// Run the mirrors as tasks in this process (from an in-memory copy of the world)
    /// rather than as `naadf mirror` processes that join over the network.
    #[arg(long)]
    in_process: bool,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Report {
    entities: u32,
    /// The delta of one call, in bytes: record form, patch form.
    record_bytes: usize,
    patch_bytes: usize,
    runs: Vec<LatencyReport>,
    threads: usize,
}

/// The pose of entity `id` in call `call` (0: where it spawns) in a world of `size`: above
/// the middle layer, anywhere in x and z, at any rotation.
fn pose(size: WorldSize, id: u32, call: usize) -> Pose {
    let s = size.voxels().map(f64::from);
    let mut rng = SplitMix64((call as u64) << 16 | u64::from(id));
    Pose {
        id,
        pos: [
            rng.unit() * (s[0] - 16.0),
            s[1] * 0.5 + rng.unit() * (s[1] * 0.5 - 16.0),
            rng.unit() * (s[2] - 16.0),
        ],
        rot: [0; 4].map(|_| rng.unit() - 0.5),
    }
}

fn move_op(p: &Pose) -> Op {
    Op::MoveEntity {
        id: p.id,
        pos: p.pos,
        rot: p.rot,
    }
}

/// Runs the benchmark.
pub fn run(a: MovesArgs) -> Result<()> {
    let mut world = a.preset.generate()?;
    let size = world.size();
    let mut ops = vec![Op::DefineModel {
        name: "crate".into(),
        size: [8, 8, 8],
        voxels: (0..8).map(|k| [k, k, k, 1 + k % 3]).collect(),
    }];
    ops.extend((0..a.entities).map(|id| {
        let p = pose(size, id, 0);
        Op::SpawnEntity {
            id: p.id,
            model: "crate".into(),
            pos: p.pos,
            rot: p.rot,
        }
    }));
    world.apply(&Batch { ops }, &Limits::default())?;
    // One call's delta in both forms, on a copy.
    let (record_bytes, patch_bytes) = {
        let mut copy = world.clone();
        let mut maker = PatchMaker::new(&copy);
        let moves = (0..a.entities).map(|id| move_op(&pose(size, id, 1))).collect();
        let change = copy.apply(&Batch { ops: moves }, &Limits::default())?.change;
        let [r, p] = delta_sizes(&change, maker.patch(&copy, &change));
        (r, p)
    };
    eprintln!(
        "one call moving {} entities: {record_bytes} B in the record form ({:.2} B each), {patch_bytes} B in the patch form ({:.2} B each)",
        a.entities,
        record_bytes as f64 / f64::from(a.entities),
        patch_bytes as f64 / f64::from(a.entities)
    );
    let entities = a.entities;
    block_on(async move {
        let cache = Some(world.clone());
        let server = LocalServer::start(world).await?;
        let url = server.url();
        let editor = Editor::connect(&url).await?;
        let mut last = 0;
        let mut runs = Vec::new();
        let mut call = 1;
        for &rate in &a.rates {
            let count = (f64::from(rate) * a.seconds) as usize;
            let first = call;
            call += count;
            // The poses of every call, made before the run so the editor only sends.
            let calls: Vec<Vec<Pose>> = (0..count)
                .map(|k| (0..entities).map(|id| pose(size, id, first + k)).collect())
                .collect();
            let calls = std::sync::Arc::new(calls);
            let mirrors = Mirrors {
                count: a.clients,
                processes: !a.in_process,
            };
            let r = latency_run(&url, &cache, &editor, mirrors, rate, count, &mut last, move |c, k| {
                let calls = calls.clone();
                async move { Ok(c.move_entities(&calls[k], 0).await?.version) }
            })
            .await?;
            eprintln!(
                "{rate} calls/s × {entities} entities, {} mirrors{}: p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms (acknowledged: p50 {:.2} ms, p99 {:.2} ms)",
                a.clients,
                if a.in_process { " in process" } else { " (processes)" },
                r.p50_ms,
                r.p99_ms,
                r.max_ms,
                r.ack_p50_ms,
                r.ack_p99_ms
            );
            eprintln!("  CPU per call: {}", describe(&r.cpu_per_edit));
            if r.incomplete > 0 {
                bail!("{} versions never reached a mirror", r.incomplete);
            }
            runs.push(r);
        }
        server.shutdown().await?;
        let report = Report {
            entities,
            record_bytes,
            patch_bytes,
            runs,
            threads: rayon::current_num_threads(),
        };
        if a.json {
            print_json(&report)?;
        }
        Ok(())
    })
}

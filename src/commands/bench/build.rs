//! `naadf bench build`: generation, construction and chunk-AADF build times of a preset.

use crate::commands::args::PresetArgs;
use crate::commands::{chunk_progress, print_json};
use anyhow::Result;
use naadf_world::cell::CHUNK_VOXELS;
use naadf_world::model::ModelTable;
use naadf_world::stats::WorldStats;
use naadf_world::{ChunkSource, MaterialTable, World, WorldSize};
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// Arguments of `bench build`.
#[derive(clap::Args)]
pub struct BuildArgs {
    #[command(flatten)]
    preset: PresetArgs,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

/// Raw chunks held in memory, so that construction is timed without generation.
struct MemorySource {
    size: WorldSize,
    materials: MaterialTable,
    models: ModelTable,
    chunks: Vec<Box<[u16; CHUNK_VOXELS]>>,
}

impl ChunkSource for MemorySource {
    fn size(&self) -> WorldSize {
        self.size
    }
    fn materials(&self) -> MaterialTable {
        self.materials.clone()
    }
    fn models(&self) -> ModelTable {
        self.models.clone()
    }
    fn fill_chunk(&self, c: [u32; 3], out: &mut [u16; CHUNK_VOXELS]) {
        out.copy_from_slice(&self.chunks[self.size.chunk_index(c)][..]);
    }
}

#[derive(Serialize)]
struct BuildReport {
    preset: String,
    size: [u32; 3],
    voxels: u64,
    threads: usize,
    /// Generating every raw chunk into memory (the generator's own cost).
    generation_s: f64,
    /// Construction from raw chunks in memory (hashing, dedup, voxel/block AADFs), all threads.
    construction_s: f64,
    /// The same on one thread.
    construction_1_thread_s: f64,
    /// Raw voxels per second per core (from the one-thread run).
    construction_mvoxels_per_s_per_core: f64,
    /// Raw voxels per second, all threads.
    construction_mvoxels_per_s: f64,
    /// Full chunk-AADF build (31 levels × 3 axes), all threads.
    chunk_aadf_s: f64,
    /// Bytes per layer and the dense u16 grid for comparison.
    bytes: naadf_world::stats::Bytes,
    dense_u16_bytes: u64,
    dense_over_structure: f64,
    stats: WorldStats,
}

/// Runs `bench build`.
pub fn run(a: BuildArgs) -> Result<()> {
    let source = a.preset.source()?;
    let size = source.size();
    let n = size.chunk_count();
    let bar = chunk_progress(n as u64, "generating");
    let t0 = Instant::now();
    let chunks: Vec<Box<[u16; CHUNK_VOXELS]>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let c = size.chunk_coords(i);
            let mut raw = Box::new([0u16; CHUNK_VOXELS]);
            match source.uniform_hint(c) {
                Some(m) => raw.fill(m),
                None => source.fill_chunk(c, &mut raw),
            }
            if i % 4096 == 0 {
                bar.set_position(i as u64);
            }
            raw
        })
        .collect();
    let generation_s = t0.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let mem = MemorySource {
        size,
        materials: source.materials(),
        models: source.models(),
        chunks,
    };
    let timed_build = |threads: Option<usize>| -> Result<(World, f64, f64)> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads.unwrap_or(0))
            .build()?;
        pool.install(|| {
            let t0 = Instant::now();
            let mut w = World::build(&mem, &|_| {})?;
            let total = t0.elapsed().as_secs_f64();
            let t1 = Instant::now();
            w.rebuild_chunk_aadf();
            let aadf = t1.elapsed().as_secs_f64();
            Ok((w, total - aadf, aadf))
        })
    };
    let (_, construction_1_thread_s, _) = timed_build(Some(1))?;
    let (world, construction_s, chunk_aadf_s) = timed_build(None)?;
    let stats = WorldStats::of(&world);
    let voxels = size.voxel_count();
    let dense = voxels * 2;
    let r = BuildReport {
        preset: a.preset.preset,
        size: size.voxels(),
        voxels,
        threads: rayon::current_num_threads(),
        generation_s,
        construction_s,
        construction_1_thread_s,
        construction_mvoxels_per_s_per_core: voxels as f64 / construction_1_thread_s / 1e6,
        construction_mvoxels_per_s: voxels as f64 / construction_s / 1e6,
        chunk_aadf_s,
        bytes: stats.bytes,
        dense_u16_bytes: dense,
        dense_over_structure: dense as f64 / stats.bytes.total as f64,
        stats,
    };
    if a.json {
        return print_json(&r);
    }
    println!("{} {:?}: {} voxels, {} threads", r.preset, r.size, r.voxels, r.threads);
    println!("generation          {:.2} s", r.generation_s);
    println!(
        "construction        {:.2} s ({:.0} Mvoxels/s); one thread {:.2} s ({:.0} Mvoxels/s per core)",
        r.construction_s,
        r.construction_mvoxels_per_s,
        r.construction_1_thread_s,
        r.construction_mvoxels_per_s_per_core
    );
    println!("chunk AADF build    {:.3} s", r.chunk_aadf_s);
    println!(
        "structure           {:.1} MiB vs dense u16 {:.1} MiB ({:.1}×)",
        r.bytes.total as f64 / 1048576.0,
        dense as f64 / 1048576.0,
        r.dense_over_structure
    );
    Ok(())
}

//! `naadf info WORLD [--json]`

use super::{load_world, print_json};
use anyhow::Result;
use naadf_world::stats::WorldStats;
use std::path::PathBuf;

/// Arguments of `info`.
#[derive(clap::Args)]
pub struct Args {
    /// World file.
    world: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
}

/// Prints a world's statistics.
pub fn run(a: Args) -> Result<()> {
    let world = load_world(&a.world)?;
    let s = WorldStats::of(&world);
    if a.json {
        return print_json(&s);
    }
    let mib = |b: u64| b as f64 / (1 << 20) as f64;
    let dense = world.size().voxel_count() * 2;
    println!("size          {} × {} × {} voxels", s.size[0], s.size[1], s.size[2]);
    println!("version       {}", world.version());
    println!("solid voxels  {}", s.solid_voxels);
    println!("chunks        {}", s.chunks);
    println!("blocks        {}", s.blocks);
    println!("voxel groups  {}", s.voxel_groups);
    println!("materials     {}", world.materials().len() - 1);
    println!("models        {}", world.models().len());
    println!(
        "memory        {:.1} MiB (chunks {:.1}, blocks {:.1}, voxels {:.1}, materials {:.3}); dense u16 grid {:.1} MiB ({:.1}×)",
        mib(s.bytes.total),
        mib(s.bytes.chunks),
        mib(s.bytes.blocks),
        mib(s.bytes.voxels),
        mib(s.bytes.materials),
        mib(dense),
        dense as f64 / s.bytes.total as f64
    );
    println!("digest        {}", s.digest);
    Ok(())
}

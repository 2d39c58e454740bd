//! `naadf import IN.vox -o OUT.naadf`

use super::{BuildLimit, print_json, save_world};
use anyhow::{Context, Result};
use naadf_world::import::vox::VoxScene;
use naadf_world::stats::WorldStats;
use std::path::PathBuf;

/// Arguments of `import`.
#[derive(clap::Args)]
pub struct Args {
    /// MagicaVoxel scene to import.
    input: PathBuf,
    /// World file to write.
    #[arg(short, long)]
    output: PathBuf,
    /// Print the new world's `info` as JSON on stdout.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    limit: BuildLimit,
}

/// Imports a `.vox` scene into a world file.
pub fn run(a: Args) -> Result<()> {
    let scene = VoxScene::open(&a.input).with_context(|| format!("cannot import {}", a.input.display()))?;
    let size = scene.world_size()?;
    let world = a.limit.build(&scene, &format!("the scene {}", a.input.display()))?;
    save_world(&world, &a.output)?;
    tracing::info!(size = %size, "imported {}", a.input.display());
    if a.json {
        print_json(&WorldStats::of(&world))
    } else {
        Ok(())
    }
}

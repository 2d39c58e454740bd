//! `naadf generate --preset NAME [--size X,Y,Z] [--seed N] -o OUT.naadf`

use super::args::PresetArgs;
use super::{print_json, save_world};
use anyhow::Result;
use naadf_world::stats::WorldStats;
use std::path::PathBuf;

/// Arguments of `generate`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    preset: PresetArgs,
    /// World file to write.
    #[arg(short, long)]
    output: PathBuf,
    /// Print the new world's `info` as JSON on stdout.
    #[arg(long)]
    json: bool,
}

/// Generates a preset world and writes it.
pub fn run(a: Args) -> Result<()> {
    let world = a.preset.generate()?;
    save_world(&world, &a.output)?;
    if a.json {
        print_json(&WorldStats::of(&world))
    } else {
        Ok(())
    }
}

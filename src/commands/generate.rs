//! `naadf generate --preset NAME [--size X,Y,Z] [--seed N] -o OUT.naadf`

use super::{BuildLimit, print_json, save_world};
use anyhow::Result;
use naadf_world::preset::Preset;
use naadf_world::stats::WorldStats;
use naadf_world::{ChunkSource, World, WorldSize};
use std::path::PathBuf;

/// Which procedural world to make (shared by `generate` and `bench build`).
#[derive(clap::Args)]
pub struct PresetArgs {
    /// Preset: `terrain`, `test` or `tiled:<file.vox>`.
    #[arg(long, default_value = "terrain")]
    pub preset: String,
    /// World size `X,Y,Z` in voxels (multiples of 64); default: the preset's.
    #[arg(long, value_parser = parse_size)]
    pub size: Option<WorldSize>,
    /// Seed of the generator.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[command(flatten)]
    pub limit: BuildLimit,
}

impl PresetArgs {
    /// The chunk source these arguments describe.
    pub fn source(&self) -> Result<Box<dyn ChunkSource>> {
        Ok(Preset::parse(&self.preset)?.source(self.size, self.seed)?)
    }
}

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

/// Parses `X,Y,Z` for clap.
pub fn parse_size(s: &str) -> Result<WorldSize, String> {
    WorldSize::parse(s).map_err(|e| e.to_string())
}

/// Generates a preset world and writes it.
pub fn run(a: Args) -> Result<()> {
    let world = generate(&a.preset)?;
    save_world(&world, &a.output)?;
    if a.json {
        print_json(&WorldStats::of(&world))
    } else {
        Ok(())
    }
}

/// Builds a preset world with a progress bar.
pub fn generate(preset: &PresetArgs) -> Result<World> {
    let source = preset.source()?;
    preset.limit.build(&*source, &format!("preset '{}'", preset.preset))
}

//! `naadf export WORLD --raw OUT.bin`

use super::load_world;
use anyhow::{Context, Result};
use std::io::{BufWriter, Write};
use std::path::PathBuf;

/// Arguments of `export`.
#[derive(clap::Args)]
pub struct Args {
    /// World file.
    world: PathBuf,
    /// Write dense little-endian u16 material ids (x fastest, then y, then z) to this file.
    #[arg(long)]
    raw: PathBuf,
}

/// Writes the dense raw export.
pub fn run(a: Args) -> Result<()> {
    let world = load_world(&a.world)?;
    let ctx = || format!("cannot write {}", a.raw.display());
    let mut out = BufWriter::with_capacity(1 << 20, std::fs::File::create(&a.raw).with_context(ctx)?);
    world.export_raw(&mut out).with_context(ctx)?;
    out.flush().with_context(ctx)?;
    Ok(())
}

//! `naadf apply WORLD --ops OPS.jsonl -o OUT.naadf [--json]`: offline edits through the
//! same code path as the server.

use super::{load_world, print_json, save_world};
use anyhow::{Context, Result};
use naadf_world::ops::{Batch, Limits};
use serde::Serialize;
use std::io::BufRead;
use std::path::PathBuf;

/// Arguments of `apply`.
#[derive(clap::Args)]
pub struct Args {
    /// World file to start from.
    world: PathBuf,
    /// Ops JSON lines: one op or `{"batch":[...]}` per line, one version each (`-` reads stdin).
    #[arg(long)]
    ops: PathBuf,
    /// World file to write (after the distance fields have converged).
    #[arg(short, long)]
    output: PathBuf,
    /// Print the final version and digest as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Summary {
    version: u64,
    digest: String,
    batches: u64,
}

/// Applies every batch in order; any bad line fails the command before anything is written.
pub fn run(a: Args) -> Result<()> {
    let mut world = load_world(&a.world)?;
    let reader: Box<dyn BufRead> = if a.ops.as_os_str() == "-" {
        Box::new(std::io::stdin().lock())
    } else {
        let f = std::fs::File::open(&a.ops).with_context(|| format!("cannot open {}", a.ops.display()))?;
        Box::new(std::io::BufReader::new(f))
    };
    let limits = Limits::default();
    let mut batches = 0;
    for (n, line) in reader.lines().enumerate() {
        let line = line.with_context(|| format!("cannot read {}", a.ops.display()))?;
        if line.trim().is_empty() {
            continue;
        }
        let batch = Batch::parse_line(&line).with_context(|| format!("line {}", n + 1))?;
        world
            .apply(&batch, &limits)
            .with_context(|| format!("line {}", n + 1))?;
        batches += 1;
    }
    world.grow_until_quiescent();
    save_world(&world, &a.output)?;
    tracing::info!(version = world.version(), "applied {batches} batches");
    if a.json {
        print_json(&Summary {
            version: world.version(),
            digest: world.digest().to_string(),
            batches,
        })?;
    }
    Ok(())
}

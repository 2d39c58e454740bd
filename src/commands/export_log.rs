//! `naadf export-log DATA_DIR -o SCRIPT [--base OUT.naadf]`: the batches a server applied
//! after its newest snapshot, with their users, as ops-JSON lines that `naadf apply`
//! replays on that snapshot to the same digests.

use super::save_world;
use anyhow::{Context, Result, bail};
use naadf_server::data::{store, wal};
use naadf_world::ops::Batch;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `export-log`.
#[derive(clap::Args)]
pub struct Args {
    /// The server's data directory (read only; the server may keep running).
    data: PathBuf,
    /// Ops-JSON script to write.
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the snapshot the script starts from.
    #[arg(long)]
    base: Option<PathBuf>,
}

/// Writes the script.
pub fn run(a: Args) -> Result<()> {
    let Some(&version) = store::snapshots(&a.data)?.last() else {
        bail!("{} holds no snapshot (is it a naadf data directory?)", a.data.display());
    };
    let entries = wal::read_after(&a.data, version)?;
    let mut out = std::io::BufWriter::new(
        std::fs::File::create(&a.output).with_context(|| format!("cannot create {}", a.output.display()))?,
    );
    for e in &entries {
        let batch = Batch::parse_line(&e.ops).with_context(|| format!("log entry {}", e.version))?;
        let line = serde_json::json!({
            "batch": batch.ops,
            "user": e.user,
            "version": e.version,
        });
        writeln!(out, "{line}")?;
    }
    out.flush()?;
    if let Some(base) = &a.base {
        let (world, _) = store::load_snapshot(&a.data, version)?;
        save_world(&world, base)?;
    }
    eprintln!(
        "wrote {} batches after snapshot version {version} to {}",
        entries.len(),
        a.output.display()
    );
    Ok(())
}

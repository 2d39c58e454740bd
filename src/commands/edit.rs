//! `naadf edit --server URL --ops OPS.jsonl [--token T]`: sends each line as one request
//! and prints the acknowledged versions.

use super::print_json;
use super::remote::{ServerArgs, block_on};
use anyhow::{Context, Result};
use std::io::BufRead;
use std::path::PathBuf;
use std::time::Duration;

/// Arguments of `edit`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    server: ServerArgs,
    /// Ops JSON lines: one op or `{"batch":[...]}` per line, one version each (`-` reads stdin).
    #[arg(long)]
    ops: PathBuf,
    /// Client sequence number of the first line (the next lines count up). A retried
    /// request with the same number is answered with its original version, never applied
    /// twice. Default: derived from the clock, so separate runs do not collide.
    #[arg(long)]
    client_seq: Option<u64>,
    /// Print one JSON object per acknowledged line.
    #[arg(long)]
    json: bool,
}

/// Attempts per request when the server is unreachable or restarting (retries are safe:
/// the server answers a repeated `client_seq` with the original version).
const ATTEMPTS: u32 = 5;

#[derive(serde::Serialize)]
struct Ack {
    line: usize,
    version: u64,
    duplicate: bool,
}

/// Sends every line in order; stops at the first refused one.
pub fn run(a: Args) -> Result<()> {
    let reader: Box<dyn BufRead> = if a.ops.as_os_str() == "-" {
        Box::new(std::io::stdin().lock())
    } else {
        let f = std::fs::File::open(&a.ops).with_context(|| format!("cannot open {}", a.ops.display()))?;
        Box::new(std::io::BufReader::new(f))
    };
    let lines: Vec<(usize, String)> = reader
        .lines()
        .enumerate()
        .map(|(n, l)| l.map(|l| (n + 1, l)))
        .collect::<Result<_, _>>()
        .with_context(|| format!("cannot read {}", a.ops.display()))?;
    let first = a.client_seq.unwrap_or_else(naadf_client::connect::session_client_seq);
    block_on(async move {
        // The client reconnects by itself on the call after a lost connection.
        let client = a.server.connect().await?;
        for (i, (n, line)) in lines.iter().filter(|(_, l)| !l.trim().is_empty()).enumerate() {
            let client_seq = first + i as u64;
            let mut attempt = 0;
            let reply = loop {
                attempt += 1;
                match client.edit(line.as_str(), client_seq).await {
                    Ok(r) => break r,
                    Err(e) if e.is_unavailable() && attempt < ATTEMPTS => {
                        tracing::warn!("{e}; retrying line {n}");
                        tokio::time::sleep(Duration::from_millis(200 << attempt)).await;
                    }
                    Err(e) => return Err(anyhow::Error::from(e).context(format!("line {n}"))),
                }
            };
            if a.json {
                print_json(&Ack {
                    line: *n,
                    version: reply.version,
                    duplicate: reply.duplicate,
                })?;
            } else {
                println!("{}", reply.version);
            }
        }
        Ok(())
    })
}

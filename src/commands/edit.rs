//! `naadf edit --server URL --ops OPS.jsonl [--token T]`: sends each line as one request
//! and prints the acknowledged versions.

use super::print_json;
use super::remote::{ServerArgs, block_on, status_error};
use anyhow::{Context, Result};
use naadf_proto::v1::EditRequest;
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

/// Attempts per request when the server is unreachable or restarting.
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
        let mut client = a.server.connect().await?;
        for (i, (n, line)) in lines.iter().filter(|(_, l)| !l.trim().is_empty()).enumerate() {
            let req = EditRequest {
                ops: line.clone(),
                client_seq: first + i as u64,
            };
            let mut attempt = 0;
            let reply = loop {
                attempt += 1;
                match client.edit(req.clone()).await {
                    Ok(r) => break r.into_inner(),
                    Err(s) if s.code() == tonic::Code::Unavailable && attempt < ATTEMPTS => {
                        tracing::warn!("server unavailable ({}); retrying line {n}", s.message());
                        tokio::time::sleep(Duration::from_millis(200 << attempt)).await;
                        if let Ok(c) = a.server.connect().await {
                            client = c;
                        }
                    }
                    Err(s) => return Err(status_error(s).context(format!("line {n}"))),
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

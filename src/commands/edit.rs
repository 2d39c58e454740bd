//! `naadf edit --server URL --ops OPS.jsonl [--token T]`: sends each line as one request
//! and prints the acknowledged versions.

use super::print_json;
use super::remote::{ServerArgs, block_on};
use anyhow::{Context, Result};
use naadf_client::Backoff;
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
    /// Longest time to keep retrying one line that the server rate-limits or cannot take
    /// (unreachable, restarting), in seconds, backing off exponentially; 0 stops at the
    /// first such refusal. A retry repeats the line's client sequence number, so it is
    /// never applied twice.
    #[arg(long, default_value = "30", value_parser = parse_seconds)]
    retry_for: Duration,
}

/// A duration given in seconds: a non-negative number that a `Duration` holds.
fn parse_seconds(s: &str) -> Result<Duration, String> {
    s.parse::<f64>()
        .ok()
        .and_then(|v| Duration::try_from_secs_f64(v).ok())
        .ok_or_else(|| format!("'{s}' is not a number of seconds ≥ 0"))
}

/// The pauses between tries of one line: 50 ms, doubling up to 2 s.
const RETRY_BACKOFF: Backoff = Backoff::new(Duration::from_millis(50), Duration::from_secs(2));

#[derive(serde::Serialize)]
struct Ack {
    line: usize,
    version: u64,
    duplicate: bool,
}

/// Whether a retry of the same request may pass: the caller was over the rate limit, or
/// the server was out of reach.
fn retryable(e: &naadf_client::Error) -> bool {
    matches!(e, naadf_client::Error::RateLimited(_)) || e.is_unavailable()
}

/// Sends every line in order, retrying rate-limited and unreachable ones for up to
/// `--retry-for`; stops at the first line refused for good.
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
    let retry_for = a.retry_for;
    block_on(async move {
        // The client reconnects by itself on the call after a lost connection.
        let client = a.server.connect().await?;
        for (i, (n, line)) in lines.iter().filter(|(_, l)| !l.trim().is_empty()).enumerate() {
            let client_seq = first + i as u64;
            let (mut waited, mut backoff) = (Duration::ZERO, RETRY_BACKOFF);
            let reply = loop {
                match client.edit(line.as_str(), client_seq).await {
                    Ok(r) => break r,
                    Err(e) if retryable(&e) && waited + backoff.upcoming() <= retry_for => {
                        let pause = backoff.pause();
                        if e.is_unavailable() {
                            tracing::warn!("{e}; retrying line {n} in {} ms", pause.as_millis());
                        } else {
                            tracing::debug!("{e}; retrying line {n} in {} ms", pause.as_millis());
                        }
                        tokio::time::sleep(pause).await;
                        waited += pause;
                    }
                    Err(e) if retryable(&e) && !waited.is_zero() => {
                        let why = format!(
                            "line {n}: still refused after retrying for {:.1} s",
                            waited.as_secs_f64()
                        );
                        return Err(anyhow::Error::from(e).context(why));
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

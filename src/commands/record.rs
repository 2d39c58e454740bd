//! `naadf record --server URL -o SCRIPT [--base WORLD] [--until-version N] [--duration S]`:
//! follows a live server and writes every edit batch it applies, in order and with its
//! user, as a replay script (docs/REPLAY.md). The script ends with the digest of the
//! quiescent world, so replaying it on the world it started from (`--base`) must reproduce
//! that digest exactly.

use super::remote::{ServerArgs, block_on};
use super::{print_json, save_world, seconds};
use anyhow::{Context, Result, bail};
use naadf_client::{Ended, Mirror};
use std::io::Write;
use std::ops::ControlFlow;
use std::path::PathBuf;

/// Arguments of `record`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    server: ServerArgs,
    /// The script to write (lines are flushed as they come: a killed recorder leaves a
    /// valid script of what it saw).
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the world the recording starts from.
    #[arg(long)]
    base: Option<PathBuf>,
    /// Stop once the server has applied this version and is quiescent.
    #[arg(long)]
    until_version: Option<u64>,
    /// Stop after this many seconds (otherwise at Ctrl-C, or when the server ends the stream).
    #[arg(long)]
    duration: Option<f64>,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    json: bool,
}

#[derive(serde::Serialize)]
struct Summary {
    /// The version the recording starts after (the base world's).
    start_version: u64,
    /// The last recorded version.
    end_version: u64,
    /// Batches recorded.
    batches: u64,
    /// The digest of the quiescent world at the end (the script's last expectation).
    digest: String,
}

/// What the recorder has written so far.
struct Recorder {
    out: std::io::BufWriter<std::fs::File>,
    start: Option<u64>,
    last: u64,
    user: Option<String>,
    batches: u64,
}

impl Recorder {
    fn line(&mut self, text: &str) -> Result<()> {
        writeln!(self.out, "{text}")?;
        self.out.flush()?;
        Ok(())
    }

    /// Writes what `m` shows that is new: the start, then each edit batch.
    fn seen(&mut self, m: &Mirror, base: Option<&PathBuf>, url: &str) -> Result<()> {
        let Some(world) = m.world().filter(|_| m.is_live()) else {
            return Ok(());
        };
        if self.start.is_none() {
            let v = world.version();
            if let Some(path) = base {
                save_world(world, path)?;
            }
            self.line(&format!("# recorded from {url}, starting after version {v}"))?;
            self.line(&format!("{{\"wait_version\":{v}}}"))?;
            self.start = Some(v);
            self.last = v;
        }
        let Some(e) = m.last_edit().filter(|e| e.version > self.last) else {
            return Ok(());
        };
        if e.version != self.last + 1 {
            bail!(
                "versions {}..{} were not streamed to the recorder (it fell behind and was sent a snapshot)",
                self.last + 1,
                e.version - 1
            );
        }
        let user = if e.user.is_empty() { "unknown" } else { e.user.as_str() };
        if self.user.as_deref() != Some(user) {
            self.line(&serde_json::json!({ "as_user": user }).to_string())?;
            self.user = Some(user.to_owned());
        }
        self.line(&e.batch.to_json_line())?;
        self.last = e.version;
        self.batches += 1;
        Ok(())
    }
}

/// Runs `record`.
pub fn run(a: Args) -> Result<()> {
    let file = std::fs::File::create(&a.output).with_context(|| format!("cannot create {}", a.output.display()))?;
    let mut rec = Recorder {
        out: std::io::BufWriter::new(file),
        start: None,
        last: 0,
        user: None,
        batches: 0,
    };
    let world = block_on(async {
        let mut session = a.server.connect().await?.join(None).await?;
        session.keep_edits();
        let duration = a.duration.map(|s| seconds(s, "--duration")).transpose()?;
        let stop = async {
            match duration {
                Some(d) => tokio::time::sleep(d).await,
                None => {
                    let _ = tokio::signal::ctrl_c().await;
                }
            }
        };
        let url = a.server.server.clone();
        let ended = session
            .follow(stop, |m| -> Result<ControlFlow<()>> {
                rec.seen(m, a.base.as_ref(), &url)?;
                let done = a.until_version.is_some_and(|v| rec.last >= v) && m.is_quiescent();
                Ok(if done {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                })
            })
            .await?;
        if ended == Ended::Stream {
            tracing::warn!("the server ended the stream");
        }
        session
            .into_world()
            .ok_or_else(|| anyhow::anyhow!("the server sent no world"))
    })?;
    if world.version() != rec.last {
        bail!(
            "the mirror is at version {} but the recording ends at {}: batches were missed",
            world.version(),
            rec.last
        );
    }
    // The quiescent state depends on the content alone, so growing the mirror's copy to
    // the end gives the digest a replay reaches.
    let mut world = world;
    world.grow_until_quiescent();
    let digest = world.digest().to_string();
    rec.line(&format!("{{\"expect_digest\":\"{digest}\"}}"))?;
    let summary = Summary {
        start_version: rec.start.unwrap_or(0),
        end_version: rec.last,
        batches: rec.batches,
        digest,
    };
    if a.json {
        print_json(&summary)?;
    } else {
        eprintln!(
            "recorded {} batches after version {} (to version {}), final digest {}",
            summary.batches, summary.start_version, summary.end_version, summary.digest
        );
    }
    Ok(())
}

//! [`MirrorProcess`]: a CPU mirror in a process of its own (`naadf mirror --log-versions`),
//! for latency runs whose mirrors must not share the server's process and its cores' time
//! slices the way in-process mirrors do.

use super::applied::{Applied, caught_up};
use super::cpu::process_ns_of;
use crate::commands::mirror;
use anyhow::{Context, Result};
use std::process::Stdio;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};
use tokio::io::{AsyncBufReadExt, BufReader};
use tokio::process::{Child, Command};
use tokio::sync::watch;

/// A `naadf mirror` child following a server, and when it applied each version.
pub(super) struct MirrorProcess {
    child: Child,
    applied: watch::Receiver<Option<u64>>,
    reader: tokio::task::JoinHandle<Result<Applied>>,
}

impl MirrorProcess {
    /// Starts a mirror of the server at `url`, joining without a page cache.
    pub(super) fn spawn(url: &str) -> Result<Self> {
        let mut child = Command::new(std::env::current_exe()?)
            .args(["mirror", "--server", url, "--no-cache", "--log-versions"])
            .env_remove("NAADF_TOKEN")
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .kill_on_drop(true)
            .spawn()
            .context("cannot start a mirror process")?;
        let out = child.stdout.take().context("the mirror's stdout")?;
        let (tx, applied) = watch::channel(None);
        let reader = tokio::spawn(async move {
            let mut lines = BufReader::new(out).lines();
            let mut times = Vec::new();
            while let Some(line) = lines.next_line().await? {
                // The quiescent-point lines are not versions.
                let Ok(a) = serde_json::from_str::<mirror::Applied>(&line) else {
                    continue;
                };
                // The child's wall-clock time, moved onto this process's monotonic clock.
                let now = SystemTime::now().duration_since(UNIX_EPOCH)?.as_nanos() as u64;
                let ago = Duration::from_nanos(now.saturating_sub(a.applied_unix_ns));
                times.push((a.version, Instant::now() - ago));
                let _ = tx.send(Some(a.version));
            }
            Ok(times)
        });
        Ok(MirrorProcess { child, applied, reader })
    }

    /// The CPU time the mirror process has used, in nanoseconds (`None` without `/proc`).
    pub(super) fn cpu_ns(&self) -> Option<u64> {
        process_ns_of(&self.child.id()?.to_string())
    }

    /// Waits until the mirror applied `version`.
    pub(super) async fn wait_for(&mut self, version: u64) -> Result<()> {
        caught_up(&mut self.applied, version).await
    }

    /// Ends the mirror; when it applied each version.
    pub(super) async fn finish(mut self) -> Result<Applied> {
        self.child.start_kill()?;
        self.child.wait().await?;
        self.reader.await?
    }
}

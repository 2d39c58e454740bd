//! When a latency run's mirrors applied each version: the [`Applied`] log every kind of
//! mirror keeps, and [`caught_up`], which waits for one to reach a version.

use anyhow::{Context, Result};
use std::time::{Duration, Instant};
use tokio::sync::watch;

/// When each version was applied at one mirror.
pub(super) type Applied = Vec<(u64, Instant)>;

/// Waits until the version a mirror reports through `applied` reaches `version`.
pub(super) async fn caught_up(applied: &mut watch::Receiver<Option<u64>>, version: u64) -> Result<()> {
    tokio::time::timeout(
        Duration::from_secs(600),
        applied.wait_for(|v| v.is_some_and(|v| v >= version)),
    )
    .await
    .context("mirror did not catch up")??;
    Ok(())
}

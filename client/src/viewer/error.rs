//! [`ViewerError`]: why the viewer could not run or stopped.

use crate::gpu::GpuError;
use crate::mirror::MirrorError;
use std::path::PathBuf;
use std::time::Duration;

/// Errors of the viewer.
#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    /// No window could be opened (no display server, …).
    #[error("cannot open a window: {0}")]
    Window(String),
    /// The GPU side failed.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The server could not be reached.
    #[error(transparent)]
    Connect(#[from] crate::Error),
    /// The async runtime of the connection could not start.
    #[error("cannot start the network runtime: {0}")]
    Runtime(std::io::Error),
    /// The stream broke the protocol or the mirror diverged.
    #[error(transparent)]
    Mirror(#[from] MirrorError),
    /// No world arrived in time (with the last connection news).
    #[error("no world from the server after {0:?} ({1})")]
    Timeout(Duration, String),
    /// The server refused the join for good (authentication, protocol).
    #[error("cannot stream the world: {0}")]
    Refused(String),
    /// The screenshot could not be written.
    #[error("cannot write the screenshot {0}: {1}")]
    Screenshot(PathBuf, std::io::Error),
}

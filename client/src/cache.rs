//! [`PageCache`]: a mirrored world kept on disk between sessions, one file per server.
//! Joining with it announces its pages, so a rejoin after a restart costs only the pages
//! that changed (or only the deltas missed, when the server still has them).
//!
//! ```no_run
//! # async fn demo(client: naadf_client::Client) -> Result<(), Box<dyn std::error::Error>> {
//! use naadf_client::PageCache;
//! let cache = PageCache::for_server(None, "http://127.0.0.1:50051").expect("a home directory");
//! let mut session = client.join(cache.load()).await?;
//! let world = session.until_quiescent(0, std::time::Duration::from_secs(60)).await?;
//! cache.save(world)?;
//! # Ok(()) }
//! ```

use naadf_world::{World, WorldError, file};
use std::path::{Path, PathBuf};

/// The cache file of one server.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PageCache {
    path: PathBuf,
}

impl PageCache {
    /// The cache of the server at `url` in `dir`, by default the user's cache directory
    /// (`$XDG_CACHE_HOME/naadf`, else `~/.cache/naadf`); `None` when there is no default.
    /// The file is named after a hash of the URL, so each server has its own.
    pub fn for_server(dir: Option<&Path>, url: &str) -> Option<PageCache> {
        let dir = match dir {
            Some(d) => d.to_path_buf(),
            None => std::env::var_os("XDG_CACHE_HOME")
                .map(PathBuf::from)
                .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?
                .join("naadf"),
        };
        let name = format!("mirror-{:016x}.naadf", naadf_world::hash::xxh3_64(url.as_bytes()));
        Some(PageCache { path: dir.join(name) })
    }

    /// The cache file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The cached world; `None` when there is none, or when it cannot be read (a warning
    /// says why: a cache only saves transfer, so a bad one is ignored, not an error).
    pub fn load(&self) -> Option<World> {
        if !self.path.exists() {
            return None;
        }
        file::load(&self.path)
            .inspect_err(|e| tracing::warn!("ignoring the page cache: {e}"))
            .ok()
    }

    /// Writes `world` as the cache (atomically: a crash leaves the old cache or the new).
    pub fn save(&self, world: &World) -> Result<(), WorldError> {
        if let Some(dir) = self.path.parent() {
            std::fs::create_dir_all(dir).map_err(|e| WorldError::io(format!("cannot create {}", dir.display()), e))?;
        }
        file::save(world, &self.path)
    }
}

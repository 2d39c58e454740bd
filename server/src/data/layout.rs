//! The data directory's layout, which the store ([`crate::data::store`]) and its judgement
//! ([`crate::data::fsck`]) share: the names of its files, its lock, and the errors of working
//! with it.
//!
//! ```text
//! DATA/LOCK                              held (flock) by the one server using DATA
//! DATA/snapshot-<version>.state          server state at <version>: histories, retries
//! DATA/snapshot-<version>.naadf          the world at <version> (a world file)
//! DATA/wal-<base>.log                    batches after <base> (see crate::data::wal)
//! DATA/.snapshot-<version>.<ext>.tmp-…   a snapshot file being written
//! DATA/quarantine/                       files no recovery could explain, moved aside
//! ```

use crate::data::wal::WalError;
use std::fs::File;
use std::path::{Path, PathBuf};

/// The name of the lock file in a data directory.
pub const LOCK: &str = "LOCK";

/// The folder inside a data directory where files that neither a start nor a repair can
/// explain are moved, instead of being deleted: evidence for the operator, read by nothing.
pub const QUARANTINE: &str = "quarantine";

/// Moves `path`, a file of the data directory `dir`, into its [`QUARANTINE`] folder (under
/// a new name if one of that name is there already), durably; returns where it went.
pub fn quarantine(dir: &Path, path: &Path) -> Result<PathBuf, StoreError> {
    let folder = dir.join(QUARANTINE);
    std::fs::create_dir_all(&folder).map_err(|e| StoreError::Io(format!("cannot create {}", folder.display()), e))?;
    let name = path
        .file_name()
        .unwrap_or(path.as_os_str())
        .to_string_lossy()
        .into_owned();
    let mut to = folder.join(&name);
    let mut n = 1;
    while to.exists() {
        to = folder.join(format!("{name}.{n}"));
        n += 1;
    }
    std::fs::rename(path, &to)
        .map_err(|e| StoreError::Io(format!("cannot move {} to {}", path.display(), to.display()), e))?;
    crate::data::wal::sync_dir(&folder)?;
    crate::data::wal::sync_dir(dir)?;
    Ok(to)
}

/// The lock of a data directory, held until dropped.
#[derive(Debug)]
pub struct Lock {
    _file: File,
}

impl Lock {
    /// Takes the lock of `dir` if its lock file exists (opening it writes nothing), else
    /// `None`.
    pub fn existing(dir: &Path) -> Result<Option<Lock>, StoreError> {
        let path = dir.join(LOCK);
        match File::open(&path) {
            Ok(file) => Self::hold(file, dir).map(Some),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
            Err(e) => Err(StoreError::Io(format!("cannot open {}", path.display()), e)),
        }
    }

    /// Takes the lock of `dir`, creating the directory and its lock file if needed.
    pub fn create(dir: &Path) -> Result<Lock, StoreError> {
        std::fs::create_dir_all(dir).map_err(|e| StoreError::Io(format!("cannot create {}", dir.display()), e))?;
        let path = dir.join(LOCK);
        let file = File::options()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
            .map_err(|e| StoreError::Io(format!("cannot open {}", path.display()), e))?;
        Self::hold(file, dir)
    }

    fn hold(file: File, dir: &Path) -> Result<Lock, StoreError> {
        file.try_lock().map_err(|_| StoreError::Locked(dir.to_owned()))?;
        Ok(Lock { _file: file })
    }
}

/// Which file of a snapshot a name is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// `snapshot-<version>.naadf`, the world.
    World,
    /// `snapshot-<version>.state`, the server state.
    State,
}

/// A file name of a snapshot, parsed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SnapshotName {
    /// The snapshot's version.
    pub version: u64,
    /// Which of its files.
    pub part: Part,
    /// Whether it is the temporary file of an atomic write of that file
    /// (`.snapshot-<version>.<ext>.tmp-…`), which only the finished rename makes count.
    pub temporary: bool,
}

/// Parses a file name of a snapshot, or of the temporary file of one being written.
pub fn snapshot_name(name: &str) -> Option<SnapshotName> {
    let (name, temporary) = match name.strip_prefix('.') {
        Some(rest) => (rest.split_once(".tmp-")?.0, true),
        None => (name, false),
    };
    let (version, ext) = name.strip_prefix("snapshot-")?.split_once('.')?;
    let part = match ext {
        "naadf" => Part::World,
        "state" => Part::State,
        _ => return None,
    };
    Some(SnapshotName {
        version: version.parse().ok()?,
        part,
        temporary,
    })
}

/// The world and state files of the snapshot at `version` in `dir`.
pub fn snapshot_paths(dir: &Path, version: u64) -> (PathBuf, PathBuf) {
    (
        dir.join(format!("snapshot-{version:020}.naadf")),
        dir.join(format!("snapshot-{version:020}.state")),
    )
}

/// Errors of the data directory.
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// Another process holds the directory.
    #[error("data directory {0} is in use by another naadf server")]
    Locked(PathBuf),
    /// An I/O failure, with what was being done.
    #[error("{0}: {1}")]
    Io(String, std::io::Error),
    /// A damaged state file.
    #[error("{0}: {1}")]
    BadState(PathBuf, String),
    /// A world file failed to load.
    #[error(transparent)]
    World(#[from] naadf_world::WorldError),
    /// The write-ahead log failed.
    #[error(transparent)]
    Wal(#[from] WalError),
    /// The directory is no valid start: it holds history but nothing to resume from.
    #[error("refusing to start: {0}")]
    Refused(Box<Refusal>),
}

/// Why a server will not start on a directory, and what the operator can do.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "data directory {} {problem}. {remedy} `naadf data check {}` reports what it holds.",
    .dir.display(),
    .dir.display()
)]
pub struct Refusal {
    /// The directory.
    pub dir: PathBuf,
    /// What is missing or damaged, and what was found.
    pub problem: String,
    /// What the operator can do.
    pub remedy: String,
    /// Whether `naadf data repair --apply` makes the directory servable.
    pub repairable: bool,
}

//! The data directory: snapshots and the write-ahead log, laid out as [`crate::data::layout`]
//! describes.
//!
//! A snapshot is written state first, then world, each atomically (temporary file, fsync,
//! rename, directory fsync), so a snapshot counts only when both files exist. Older
//! snapshots and the WAL segments they need are deleted only after a newer one is durable.
//! What a directory holds, and whether a server may start on it, is judged by
//! [`crate::data::fsck`].

use crate::data::fsck::{self, Inspection, Verdict};
use crate::data::layout::{Lock, Part, SnapshotName, snapshot_name, snapshot_paths};
use crate::data::wal;
use naadf_world::World;
use naadf_world::edit::Histories;
use naadf_world::file::{self, WorldParts};
use naadf_world::hash::xxh3_64;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

pub use crate::data::layout::StoreError;

/// Magic of a state file.
const STATE_MAGIC: &[u8; 8] = b"NAADFSTA";

/// Server state persisted beside each world snapshot.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ServerState {
    /// The version the state belongs to.
    pub version: u64,
    /// Undo/redo histories and answered client sequence numbers.
    pub histories: Histories,
}

/// A locked data directory.
#[derive(Debug)]
pub struct DataDir {
    path: PathBuf,
    _lock: Lock,
}

impl DataDir {
    /// Locks the directory and judges what it holds ([`crate::data::fsck`]): returns the locked
    /// directory and what was found, to resume or start anew. A directory the judgement
    /// refuses is left exactly as it was: not even its lock file is created.
    pub fn open(path: &Path) -> Result<(Self, Inspection), StoreError> {
        let (lock, inspection) = fsck::inspect_locked(path, |i| !matches!(i.verdict(), Verdict::Refuse(_)))?;
        if let Verdict::Refuse(r) = inspection.verdict() {
            return Err(StoreError::Refused(Box::new(r)));
        }
        let lock = lock.expect("inspect_locked locks a directory that will be written");
        Ok((
            Self {
                path: path.to_owned(),
                _lock: lock,
            },
            inspection,
        ))
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The versions of the complete snapshots, ascending.
    pub fn snapshots(&self) -> Result<Vec<u64>, StoreError> {
        snapshots(&self.path)
    }

    /// Loads the snapshot at `version`.
    pub fn load(&self, version: u64) -> Result<(World, ServerState), StoreError> {
        load_snapshot(&self.path, version)
    }

    /// Writes a snapshot durably (state, then world).
    pub fn save(&self, parts: &WorldParts, state: &ServerState) -> Result<(), StoreError> {
        let (world_path, state_path) = snapshot_paths(&self.path, parts.version);
        let payload = postcard::to_allocvec(state).expect("state serializes");
        let mut bytes = STATE_MAGIC.to_vec();
        bytes.extend_from_slice(&xxh3_64(&payload).to_le_bytes());
        bytes.extend_from_slice(&payload);
        file::save_atomically(&state_path, &mut |out| {
            out.write_all(&bytes)
                .map_err(|e| naadf_world::WorldError::io(format!("cannot write {}", state_path.display()), e))
        })?;
        file::save_parts(parts, &world_path)?;
        Ok(())
    }

    /// Deletes the snapshots older than `version` and the log segments only they needed.
    pub fn prune(&self, version: u64) -> Result<(), StoreError> {
        wal::prune(&self.path, version)?;
        for v in self.snapshots()? {
            if v < version {
                let (w, s) = snapshot_paths(&self.path, v);
                for p in [w, s] {
                    std::fs::remove_file(&p)
                        .map_err(|e| StoreError::Io(format!("cannot remove {}", p.display()), e))?;
                }
            }
        }
        Ok(wal::sync_dir(&self.path)?)
    }
}

/// The complete snapshots in `dir` (both files present), ascending.
pub fn snapshots(dir: &Path) -> Result<Vec<u64>, StoreError> {
    let mut out = Vec::new();
    let list = std::fs::read_dir(dir).map_err(|e| StoreError::Io(format!("cannot list {}", dir.display()), e))?;
    for e in list {
        let e = e.map_err(|e| StoreError::Io(format!("cannot list {}", dir.display()), e))?;
        let name = e.file_name();
        let Some(SnapshotName {
            version,
            part: Part::World,
            temporary: false,
        }) = name.to_str().and_then(snapshot_name)
        else {
            continue;
        };
        if snapshot_paths(dir, version).1.exists() {
            out.push(version);
        }
    }
    out.sort_unstable();
    Ok(out)
}

/// Loads the snapshot at `version` from `dir` (no lock needed: read-only tools use it).
pub fn load_snapshot(dir: &Path, version: u64) -> Result<(World, ServerState), StoreError> {
    let (world_path, state_path) = snapshot_paths(dir, version);
    let bytes =
        std::fs::read(&state_path).map_err(|e| StoreError::Io(format!("cannot read {}", state_path.display()), e))?;
    let bad = |m: &str| StoreError::BadState(state_path.clone(), m.to_owned());
    if bytes.len() < 16 || &bytes[..8] != STATE_MAGIC {
        return Err(bad("not a naadf state file"));
    }
    let sum = u64::from_le_bytes(bytes[8..16].try_into().expect("8 bytes"));
    if xxh3_64(&bytes[16..]) != sum {
        return Err(bad("checksum mismatch (the file is corrupt)"));
    }
    let state: ServerState = postcard::from_bytes(&bytes[16..]).map_err(|e| bad(&e.to_string()))?;
    let world = file::load(&world_path)?;
    if world.version() != version || state.version != version {
        return Err(bad(&format!(
            "snapshot {version} holds world version {} and state version {}",
            world.version(),
            state.version
        )));
    }
    Ok((world, state))
}

#[cfg(test)]
mod tests {
    use super::*;
    use naadf_world::WorldSize;
    use naadf_world::preset::Preset;

    #[test]
    fn snapshots_round_trip_and_prune() {
        let dir = tempfile::tempdir().unwrap();
        let (d, _) = DataDir::open(dir.path()).unwrap();
        assert!(matches!(DataDir::open(dir.path()), Err(StoreError::Locked(_))));
        let source = Preset::Test
            .source(Some(WorldSize::new(64, 64, 64).unwrap()), 1)
            .unwrap();
        let world = World::build(&*source, &|_| {}).unwrap();
        let mut state = ServerState::default();
        state.histories.answer("u", 3, 0);
        d.save(&world.to_parts(), &state).unwrap();
        let (w, s) = d.load(0).unwrap();
        assert_eq!((w.digest(), s), (world.digest(), state.clone()));
        // A state file without its world does not count; a damaged one is an error.
        std::fs::write(dir.path().join("snapshot-00000000000000000009.state"), b"x").unwrap();
        assert_eq!(d.snapshots().unwrap(), vec![0]);
        let (_, sp) = snapshot_paths(dir.path(), 0);
        let mut b = std::fs::read(&sp).unwrap();
        *b.last_mut().unwrap() ^= 1;
        std::fs::write(&sp, &b).unwrap();
        assert!(d.load(0).unwrap_err().to_string().contains("checksum"));
    }
}

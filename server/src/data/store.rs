//! The data directory: snapshots and the write-ahead log, laid out as [`crate::data::layout`]
//! describes.
//!
//! A snapshot is written state first, then world, each atomically (temporary file, fsync,
//! rename, directory fsync), so a snapshot counts only when both files exist. Once a
//! newer one is durable, the snapshots before the previous one and the WAL segments only
//! they need are deleted: the previous snapshot and the log after it stay, a second road
//! to the newest state should the newest snapshot ever be damaged. What a directory holds,
//! and whether a server may start on it, is judged by [`crate::data::fsck`].

use crate::data::fsck::{self, Inspection, Verdict};
use crate::data::layout::{Lock, Part, SnapshotName, snapshot_name, snapshot_paths};
use crate::data::state::ServerState;
use crate::data::wal;
use naadf_world::World;
use naadf_world::file::{self, WorldParts};
use std::path::{Path, PathBuf};

pub use crate::data::layout::StoreError;

/// A loaded snapshot: the world and the server state beside it.
pub type Snapshot = (World, ServerState);

/// A locked data directory.
#[derive(Debug)]
pub struct DataDir {
    path: PathBuf,
    _lock: Lock,
}

impl DataDir {
    /// Locks the directory and judges what it holds ([`crate::data::fsck`]), loading the
    /// snapshot it would resume from first: returns the locked directory, what was found,
    /// and that snapshot (none for a directory to start anew). A directory the judgement
    /// refuses, a damaged snapshot included, is left exactly as it was: not even its lock
    /// file is created.
    pub fn open(path: &Path) -> Result<(Self, Inspection, Option<Snapshot>), StoreError> {
        let mut loaded = None;
        let mut verify = |i: &mut Inspection| {
            i.verify(|v| {
                if !matches!(&loaded, Some((at, _)) if *at == v) {
                    loaded = Some((v, load_snapshot(path, v).map_err(|e| e.to_string())?));
                }
                Ok(())
            });
        };
        let (lock, mut inspection) = fsck::inspect_locked(path, |i| {
            verify(i);
            !matches!(i.verdict(), Verdict::Refuse(_))
        })?;
        // Without a lock, the look above was verified and refused; with one, this is a
        // new look (under the lock), which the verification must see.
        if lock.is_some() {
            verify(&mut inspection);
        }
        let snapshot = match inspection.verdict() {
            Verdict::Refuse(r) => return Err(StoreError::Refused(Box::new(r))),
            Verdict::New => None,
            Verdict::Resume { snapshot, .. } => loaded.filter(|(v, _)| *v == snapshot).map(|(_, s)| s),
        };
        let lock = lock.expect("inspect_locked locks a directory that will be written");
        let dir = Self {
            path: path.to_owned(),
            _lock: lock,
        };
        Ok((dir, inspection, snapshot))
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The versions of the complete snapshots, ascending.
    pub fn snapshots(&self) -> Result<Vec<u64>, StoreError> {
        snapshots(&self.path)
    }

    /// Writes a snapshot durably (state, then world).
    pub fn save(&self, parts: &WorldParts, state: &ServerState) -> Result<(), StoreError> {
        let (world_path, state_path) = snapshot_paths(&self.path, parts.version);
        let bytes = state.encode();
        file::save_atomically(&state_path, &mut |out| {
            out.write_all(&bytes)
                .map_err(|e| naadf_world::WorldError::io(format!("cannot write {}", state_path.display()), e))
        })?;
        file::save_parts(parts, &world_path)?;
        Ok(())
    }

    /// After the snapshot at `version` was written: deletes the snapshots before the one
    /// that precedes it, and the log segments only they needed.
    pub fn prune(&self, version: u64) -> Result<(), StoreError> {
        let snapshots = self.snapshots()?;
        let Some(&previous) = snapshots.iter().rev().find(|&&v| v < version) else {
            return Ok(());
        };
        wal::prune(&self.path, previous)?;
        for v in snapshots {
            if v < previous {
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
pub fn load_snapshot(dir: &Path, version: u64) -> Result<Snapshot, StoreError> {
    let (world_path, state_path) = snapshot_paths(dir, version);
    let state = ServerState::read(&state_path)?;
    let world = file::load(&world_path)?;
    if world.version() != version || state.version != version {
        return Err(StoreError::BadState(
            state_path,
            format!(
                "snapshot {version} holds world version {} and state version {}",
                world.version(),
                state.version
            ),
        ));
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
        let (d, _, loaded) = DataDir::open(dir.path()).unwrap();
        assert!(loaded.is_none(), "a new directory");
        assert!(matches!(DataDir::open(dir.path()), Err(StoreError::Locked(_))));
        let source = Preset::Test
            .source(Some(WorldSize::new(64, 64, 64).unwrap()), 1)
            .unwrap();
        let world = World::build(&*source, &|_| {}).unwrap();
        let mut state = ServerState::default();
        state.histories.answer("u", 3, 0);
        d.save(&world.to_parts(), &state).unwrap();
        let (w, s) = load_snapshot(dir.path(), 0).unwrap();
        assert_eq!((w.digest(), s), (world.digest(), state.clone()));
        // A state file without its world does not count; a damaged one is an error.
        std::fs::write(dir.path().join("snapshot-00000000000000000009.state"), b"x").unwrap();
        assert_eq!(d.snapshots().unwrap(), vec![0]);
        let (_, sp) = snapshot_paths(dir.path(), 0);
        let mut b = std::fs::read(&sp).unwrap();
        *b.last_mut().unwrap() ^= 1;
        std::fs::write(&sp, &b).unwrap();
        assert!(
            load_snapshot(dir.path(), 0)
                .unwrap_err()
                .to_string()
                .contains("checksum")
        );

        // Pruning after snapshot 9 keeps snapshot 5 and the log from it.
        for v in [5, 9] {
            let mut parts = world.to_parts();
            parts.version = v;
            d.save(
                &parts,
                &ServerState {
                    version: v,
                    ..state.clone()
                },
            )
            .unwrap();
        }
        for base in [0, 5, 9] {
            std::fs::write(dir.path().join(wal::segment_name(base)), b"").unwrap();
        }
        d.prune(9).unwrap();
        assert_eq!(d.snapshots().unwrap(), vec![5, 9]);
        let segments: Vec<u64> = wal::segments(dir.path()).unwrap().into_iter().map(|(b, _)| b).collect();
        assert_eq!(segments, vec![5, 9]);
    }
}

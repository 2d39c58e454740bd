//! Judging a data directory: what it holds, whether a server may start on it, and what
//! `naadf data repair` may change. The server's startup ([`DataDir::open`]) and
//! `naadf data check` share this one judgement.
//!
//! A directory is new only when it holds no log segment and no file of a snapshot, not
//! even a temporary one: anything else is history, and starting a new world over it would
//! serve a state that no history produced. A directory with history resumes from its newest
//! complete snapshot (both files) and the log after it, starting with the segment that
//! starts at that snapshot, or is refused, untouched, with what was found and what the
//! operator can do.
//!
//! Orphans are files no recovery reads: temporary files of snapshot writes that never
//! finished, which startup and `naadf data repair --apply` delete, and the single file of
//! an incomplete snapshot, which they move into the directory's `quarantine/` folder
//! instead: nothing but a crash's temporaries is ever deleted. In a refused directory
//! orphans stay where they are as evidence, unless they are all it holds and no request
//! was ever answered in them: then they are what a first start left when it was killed
//! while writing its first snapshot. The judgement ignores `quarantine/`.
//!
//! When the newest complete snapshot cannot be loaded, an older complete snapshot that
//! loads, with a log that continues it to the last logged version, is another road to the
//! same state: the verdict stays a refusal, and `naadf data repair --apply` takes the road
//! by moving the newer snapshots into `quarantine/`. Checkpoints keep the previous snapshot
//! and the log after it so that such a road exists (see [`crate::data::store`]).
//!
//! [`DataDir::open`]: crate::data::store::DataDir::open

use crate::data::layout::{self, Lock, Part, Refusal, StoreError};
use crate::data::state::ServerState;
use crate::data::wal::{self, Segment, WalError};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The files of one snapshot version found in a directory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SnapshotFiles {
    /// The version.
    pub version: u64,
    /// Whether `snapshot-<version>.naadf` (the world) is there.
    pub world: bool,
    /// Whether `snapshot-<version>.state` (the server state) is there.
    pub state: bool,
    /// Whether its state file is there without its world, reads, and has no request
    /// answered in it: what a first start writes before its first world file.
    pub blank_state: bool,
}

impl SnapshotFiles {
    /// Whether both files are there: only a complete snapshot counts.
    pub fn complete(&self) -> bool {
        self.world && self.state
    }
}

/// One log segment found in a directory.
#[derive(Debug)]
pub struct SegmentFile {
    /// The version it follows (from its name).
    pub base: u64,
    /// The file.
    pub path: PathBuf,
    /// Its records and torn tail, or why it cannot be read.
    pub read: Result<Segment, WalError>,
}

/// What a data directory holds.
#[derive(Debug)]
pub struct Inspection {
    /// The directory.
    pub dir: PathBuf,
    /// The snapshot files, by version, ascending.
    pub snapshots: Vec<SnapshotFiles>,
    /// Temporary files of snapshot writes that never finished.
    pub temporary: Vec<PathBuf>,
    /// The log segments, by base, ascending.
    pub segments: Vec<SegmentFile>,
    /// Files that are none of these (left alone).
    pub other: Vec<PathBuf>,
    /// How many entries the `quarantine/` folder holds (ignored otherwise).
    pub quarantined: usize,
    /// The newest complete snapshot and why it could not be loaded, once
    /// [`Inspection::verify`] found it damaged.
    pub damaged: Option<(u64, String)>,
    /// With a damaged newest snapshot: an older complete snapshot that loads and the
    /// number of logged records that follow it, the log continuing it to the last logged
    /// version (found by [`Inspection::verify`]).
    pub road: Option<(u64, u64)>,
}

/// What a server does with a directory.
#[derive(Debug)]
pub enum Verdict {
    /// Starts a new world: the directory is missing or holds no history.
    New,
    /// Resumes from a snapshot and the log after it.
    Resume {
        /// The version of the newest complete snapshot.
        snapshot: u64,
        /// How many logged records follow it.
        records: u64,
    },
    /// Refuses to start.
    Refuse(Refusal),
}

/// A file no recovery reads.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Orphan {
    /// The file.
    pub path: PathBuf,
    /// What it is.
    pub why: String,
    /// Whether it is moved into `quarantine/` (anything but a crash's temporary file)
    /// rather than deleted.
    pub quarantine: bool,
}

impl Orphan {
    /// Deletes the file or moves it into the quarantine, durably.
    pub fn settle(&self) -> Result<(), StoreError> {
        let dir = match self.path.parent() {
            Some(dir) if !dir.as_os_str().is_empty() => dir,
            _ => Path::new("."),
        };
        if self.quarantine {
            return layout::quarantine(dir, &self.path).map(drop);
        }
        std::fs::remove_file(&self.path)
            .map_err(|e| StoreError::Io(format!("cannot remove {}", self.path.display()), e))?;
        Ok(wal::sync_dir(dir)?)
    }
}

impl std::fmt::Display for Orphan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let verb = if self.quarantine { "move" } else { "remove" };
        let to = if self.quarantine {
            format!(" into {}/", layout::QUARANTINE)
        } else {
            String::new()
        };
        write!(f, "{verb} {}{to}: {}", name(&self.path), self.why)
    }
}

/// One change of `naadf data repair`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Action {
    /// Cuts a torn write off the end of the log.
    Cut {
        /// The segment.
        path: PathBuf,
        /// Where the torn write starts (0: the whole file goes).
        at: u64,
        /// The segment's size.
        len: u64,
    },
    /// Deletes an orphan or moves it into the quarantine.
    Settle(Orphan),
}

impl Action {
    /// Makes the change.
    pub fn apply(&self) -> Result<(), StoreError> {
        match self {
            Action::Cut { path, at, .. } => Ok(wal::cut_tail(path, *at)?),
            Action::Settle(orphan) => orphan.settle(),
        }
    }
}

impl std::fmt::Display for Action {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Action::Cut { path, at: 0, .. } => {
                write!(f, "remove {}: a log segment whose header was never written", name(path))
            }
            Action::Cut { path, at, len } => write!(
                f,
                "cut the torn write off the end of {}: {} bytes from byte {at}",
                name(path),
                len - at
            ),
            Action::Settle(o) => o.fmt(f),
        }
    }
}

/// The file name of `path`, for messages.
fn name(path: &Path) -> String {
    path.file_name()
        .map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned())
}

/// Looks at the directory `dir` without changing anything; a missing directory is new.
pub fn inspect(dir: &Path) -> Result<Inspection, StoreError> {
    let mut found = Inspection {
        dir: dir.to_owned(),
        snapshots: Vec::new(),
        temporary: Vec::new(),
        segments: Vec::new(),
        other: Vec::new(),
        quarantined: 0,
        damaged: None,
        road: None,
    };
    let listing = |e| StoreError::Io(format!("cannot list {}", dir.display()), e);
    let list = match std::fs::read_dir(dir) {
        Ok(list) => list,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(found),
        Err(e) => return Err(listing(e)),
    };
    let mut snapshots = BTreeMap::new();
    let mut segments = Vec::new();
    for e in list {
        let e = e.map_err(listing)?;
        let path = e.path();
        let file_name = e.file_name();
        let Some(file_name) = file_name.to_str() else {
            found.other.push(path);
            continue;
        };
        if file_name == layout::LOCK {
            continue;
        }
        if file_name == layout::QUARANTINE && path.is_dir() {
            found.quarantined = std::fs::read_dir(&path).map_or(0, Iterator::count);
            continue;
        }
        if let Some(s) = layout::snapshot_name(file_name) {
            if s.temporary {
                found.temporary.push(path);
                continue;
            }
            let files = snapshots.entry(s.version).or_insert(SnapshotFiles {
                version: s.version,
                world: false,
                state: false,
                blank_state: false,
            });
            match s.part {
                Part::World => files.world = true,
                Part::State => files.state = true,
            }
        } else if let Some(base) = wal::segment_base(file_name) {
            segments.push((base, path));
        } else {
            found.other.push(path);
        }
    }
    segments.sort();
    let last = segments.len();
    found.segments = segments
        .into_iter()
        .enumerate()
        .map(|(i, (base, path))| SegmentFile {
            read: wal::read_segment(&path, base, i + 1 == last),
            base,
            path,
        })
        .collect();
    for s in snapshots.values_mut().filter(|s| s.state && !s.world) {
        let (_, state) = layout::snapshot_paths(dir, s.version);
        s.blank_state = ServerState::read(&state).is_ok_and(|st| st.is_blank());
    }
    found.snapshots = snapshots.into_values().collect();
    found.temporary.sort();
    found.other.sort();
    Ok(found)
}

/// Locks `dir` and inspects it. An existing lock file is taken before looking, so that a
/// running server is reported as such and no change of one is judged half-done. A missing
/// one is created only when `writes` says the directory will be written after the first
/// look, which is then repeated under the new lock (another process may have started on
/// the directory in between). Returns the lock, if taken, and the inspection.
pub fn inspect_locked(
    dir: &Path,
    mut writes: impl FnMut(&mut Inspection) -> bool,
) -> Result<(Option<Lock>, Inspection), StoreError> {
    if let Some(lock) = Lock::existing(dir)? {
        return Ok((Some(lock), inspect(dir)?));
    }
    let mut first = inspect(dir)?;
    if !writes(&mut first) {
        return Ok((None, first));
    }
    let lock = Lock::create(dir)?;
    Ok((Some(lock), inspect(dir)?))
}

impl Inspection {
    /// The newest complete snapshot, if any.
    pub fn newest_complete(&self) -> Option<u64> {
        self.snapshots.iter().rev().find(|s| s.complete()).map(|s| s.version)
    }

    /// The index of the first segment that recovery from the snapshot at `snapshot` reads
    /// (see [`wal::first_needed`]).
    pub fn first_needed(&self, snapshot: u64) -> usize {
        wal::first_needed(self.segments.iter().map(|s| s.base), snapshot)
    }

    /// Loads the snapshot a server would resume from with `load` (the files' checksums
    /// and contents), so that the verdict, and what `naadf data check` and `data repair`
    /// say, account for a damaged one. When it is damaged, looks for an older road: the
    /// newest older complete snapshot that loads, whose log segment is there and whose log
    /// continues it to the last logged version.
    pub fn verify(&mut self, mut load: impl FnMut(u64) -> Result<(), String>) {
        self.damaged = None;
        self.road = None;
        let Verdict::Resume { snapshot, .. } = self.verdict() else {
            return;
        };
        let Err(e) = load(snapshot) else {
            return;
        };
        self.damaged = Some((snapshot, e));
        let older: Vec<u64> = self
            .snapshots
            .iter()
            .rev()
            .filter(|s| s.complete() && s.version < snapshot)
            .map(|s| s.version)
            .collect();
        for v in older {
            if !self.segments.iter().any(|s| s.base == v) {
                continue;
            }
            if let Ok(records) = self.replay(v)
                && load(v).is_ok()
            {
                self.road = Some((v, records));
                return;
            }
        }
    }

    /// What a server does with the directory.
    pub fn verdict(&self) -> Verdict {
        if let Some((snapshot, e)) = &self.damaged
            && self.newest_complete() == Some(*snapshot)
        {
            let problem =
                format!("cannot be resumed: its newest complete snapshot (version {snapshot}) cannot be loaded: {e}");
            return Verdict::Refuse(match self.road {
                Some((older, records)) => {
                    let dir = self.dir.display();
                    let remedy = format!(
                        "The older snapshot {older} loads, and the log after it reaches every logged \
                         version: `naadf data repair {dir} --apply` moves the newer snapshot files into \
                         {dir}/{}/ and the next start resumes from snapshot {older} and replays \
                         {records} logged record(s), losing nothing.",
                        layout::QUARANTINE
                    );
                    self.refusal(problem, remedy, true)
                }
                None => self.refusal(problem, "Restore the directory from a backup.".into(), false),
            });
        }
        match self.newest_complete() {
            None if self.snapshots.is_empty() && self.temporary.is_empty() && self.segments.is_empty() => Verdict::New,
            None => Verdict::Refuse(self.nothing_to_resume()),
            // A server creates the segment that starts at a snapshot before it writes the
            // snapshot: without it, the edits acknowledged after the snapshot are gone, and
            // resuming would roll the world back to it without a word.
            Some(snapshot) if !self.segments.iter().any(|s| s.base == snapshot) => Verdict::Refuse(self.refusal(
                format!(
                    "cannot be resumed: the log segment {} that starts at its newest complete \
                     snapshot (version {snapshot}) is missing. A server creates that segment \
                     before it writes the snapshot, so every edit acknowledged after version \
                     {snapshot} was logged in it and is lost with it (nothing left here says how \
                     many); serving would roll the world back to version {snapshot}",
                    wal::segment_name(snapshot)
                ),
                self.seed_remedy(snapshot),
                false,
            )),
            Some(snapshot) => match self.replay(snapshot) {
                Ok(records) => Verdict::Resume { snapshot, records },
                Err(e) => Verdict::Refuse(self.refusal(
                    format!(
                        "cannot be resumed: the write-ahead log after its newest complete snapshot \
                         (version {snapshot}) is damaged: {e}"
                    ),
                    // Its world file is there, so a newest one is always found.
                    self.seed_remedy(self.newest_world().unwrap_or(snapshot)),
                    false,
                )),
            },
        }
    }

    /// Checks the log recovery from the snapshot at `snapshot` replays: how many records
    /// follow it.
    fn replay(&self, snapshot: u64) -> Result<u64, String> {
        let needed = self.segments[self.first_needed(snapshot)..]
            .iter()
            .map(|s| s.read.as_ref().map_err(ToString::to_string))
            .collect::<Result<Vec<_>, _>>()?;
        wal::check_sequence(needed, snapshot).map_err(|e| e.to_string())
    }

    /// The refusal of a directory with history but no complete snapshot.
    fn nothing_to_resume(&self) -> Refusal {
        let mut found: Vec<String> = self
            .segments
            .iter()
            .map(|s| {
                let what = match &s.read {
                    Ok(seg) => match seg.versions() {
                        Some((a, b)) => format!("versions {a}–{b}"),
                        None => "no records".into(),
                    },
                    Err(_) => "damaged".into(),
                };
                format!("{} ({what})", name(&s.path))
            })
            .collect();
        for s in &self.snapshots {
            let (world, state) = layout::snapshot_paths(&self.dir, s.version);
            found.push(if s.world {
                format!("{} without its .state", name(&world))
            } else {
                format!("{} without its .naadf", name(&state))
            });
        }
        if !self.temporary.is_empty() {
            found.push(format!(
                "{} temporary file(s) of unfinished snapshot writes",
                self.temporary.len()
            ));
        }
        let problem = format!(
            "holds no complete snapshot (snapshot-<V>.naadf with its snapshot-<V>.state) to resume \
             from, yet it is not new: found {}. Starting a new world here would serve a state that \
             no history produced",
            found.join(", ")
        );
        let dir = self.dir.display();
        if let Some(world) = self.newest_world() {
            return self.refusal(problem, self.seed_remedy(world), false);
        }
        if self.segments.is_empty() && self.snapshots.iter().all(|s| s.blank_state) {
            let remedy = format!(
                "No edit was ever logged or answered here: these are what a first start left \
                 when it was stopped while writing its first snapshot. `naadf data repair {dir} \
                 --apply` removes the temporary files and moves the rest into {dir}/{}/, and the \
                 next start begins a new world.",
                layout::QUARANTINE
            );
            return self.refusal(problem, remedy, true);
        }
        if self.segments.is_empty() {
            let remedy = format!(
                "A server state without its world is all that is left of a world that was served \
                 here (it is not a blank first start's): restore the directory from a backup, or \
                 move it aside and start anew from a world file with `naadf serve --world FILE \
                 --data {dir}`."
            );
            return self.refusal(problem, remedy, false);
        }
        let remedy = format!(
            "The world itself is gone from it: restore the directory from a backup, or move it \
             aside and start anew from a world file with `naadf serve --world FILE --data {dir}`."
        );
        self.refusal(problem, remedy, false)
    }

    /// The version of the newest snapshot world file, complete or not.
    fn newest_world(&self) -> Option<u64> {
        self.snapshots.iter().rev().find(|s| s.world).map(|s| s.version)
    }

    /// The way out of a directory that cannot be resumed: a backup, or a new directory
    /// seeded with the world file at `version`, giving up what only the server state and
    /// the log after it hold.
    fn seed_remedy(&self, version: u64) -> String {
        let lost = self
            .segments
            .iter()
            .filter_map(|s| s.read.as_ref().ok())
            .flat_map(|s| &s.entries)
            .filter(|e| e.version > version)
            .count();
        format!(
            "Restore the directory from a backup, or seed a new one with its newest world file: \
             move this one aside (to MOVED) and run `naadf serve --world MOVED/{} --data {}`, \
             giving up the undo histories, the retry answers and the edits logged after version \
             {version} ({lost} readable in the log).",
            name(&layout::snapshot_paths(&self.dir, version).0),
            self.dir.display()
        )
    }

    fn refusal(&self, problem: String, remedy: String, repairable: bool) -> Refusal {
        Refusal {
            dir: self.dir.clone(),
            problem,
            remedy,
            repairable,
        }
    }

    /// The orphans that startup and `naadf data repair --apply` settle (delete if
    /// temporary, move into the quarantine if not): in a directory that resumes, every
    /// temporary file and every file of an incomplete snapshot; in one refused for holding
    /// nothing but what an interrupted first start left, or refused with an older road,
    /// those. None in any other refused directory, where they are evidence.
    pub fn orphans(&self) -> Vec<Orphan> {
        let removable = match self.verdict() {
            Verdict::Resume { .. } => true,
            Verdict::Refuse(r) => r.repairable,
            Verdict::New => false,
        };
        if !removable {
            return Vec::new();
        }
        let temporary = self.temporary.iter().map(|path| Orphan {
            path: path.clone(),
            why: "the temporary file of a snapshot write that never finished".into(),
            quarantine: false,
        });
        let incomplete = self.snapshots.iter().filter(|s| !s.complete()).map(|s| {
            let (world, state) = layout::snapshot_paths(&self.dir, s.version);
            let (path, missing) = if s.world { (world, state) } else { (state, world) };
            Orphan {
                path,
                why: format!("snapshot {} is incomplete ({} is missing)", s.version, name(&missing)),
                quarantine: true,
            }
        });
        temporary.chain(incomplete).collect()
    }

    /// What `naadf data repair` changes: cut a torn write off the log, take the older road
    /// past a damaged newest snapshot (its files and those of any snapshot between go into
    /// the quarantine), and settle the orphans. Or, when the directory cannot be made
    /// servable, why (and then nothing may change).
    pub fn repair(&self) -> Result<Vec<Action>, Refusal> {
        let mut actions = Vec::new();
        match self.verdict() {
            Verdict::Refuse(r) if !r.repairable => return Err(r),
            Verdict::Resume { .. } => {
                // Only the last segment may end torn; it is always one recovery reads.
                if let Some(Ok(s)) = self.segments.last().map(|s| &s.read)
                    && let Some(at) = s.torn
                {
                    actions.push(Action::Cut {
                        path: s.path.clone(),
                        at,
                        len: s.len,
                    });
                }
            }
            _ => {}
        }
        if let (Some((newest, e)), Some((older, _))) = (&self.damaged, self.road) {
            for s in self.snapshots.iter().filter(|s| s.complete() && s.version > older) {
                let why = if s.version == *newest {
                    format!("snapshot {newest} cannot be loaded: {e}")
                } else {
                    format!(
                        "snapshot {} is newer than snapshot {older}, from which the log is replayed",
                        s.version
                    )
                };
                let (world, state) = layout::snapshot_paths(&self.dir, s.version);
                for path in [world, state] {
                    actions.push(Action::Settle(Orphan {
                        path,
                        why: why.clone(),
                        quarantine: true,
                    }));
                }
            }
        }
        actions.extend(self.orphans().into_iter().map(Action::Settle));
        Ok(actions)
    }

    /// Takes out the segments that recovery from the snapshot at `snapshot` reads (for
    /// [`wal::Wal::resume`]).
    pub fn into_log(self, snapshot: u64) -> Result<Vec<Segment>, WalError> {
        let first = self.first_needed(snapshot);
        self.segments.into_iter().skip(first).map(|s| s.read).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::state::ServerState;
    use crate::data::store::{self, DataDir};
    use crate::data::wal::{Entry, Wal};
    use naadf_world::edit::BatchKind;
    use naadf_world::preset::Preset;
    use naadf_world::{World, WorldSize};

    fn entry(version: u64) -> Entry {
        Entry {
            version,
            user: "alice".into(),
            client_seq: version,
            kind: BatchKind::Edit,
            ops: r#"{"op":"set","voxels":[[1,2,3,4]]}"#.into(),
        }
    }

    /// A directory as a server leaves it: snapshot 0 and three logged edits after it.
    fn served(dir: &Path) {
        let (data, _, _) = DataDir::open(dir).unwrap();
        let source = Preset::Test
            .source(Some(WorldSize::new(64, 64, 64).unwrap()), 1)
            .unwrap();
        let world = World::build(&*source, &|_| {}).unwrap();
        data.save(&world.to_parts(), &ServerState::default()).unwrap();
        let (mut wal, _) = Wal::resume(dir, Vec::new(), 0).unwrap();
        for version in 1..4 {
            wal.append(&entry(version).frame()).unwrap();
        }
        wal.sync().unwrap();
    }

    /// Every file in `dir` with its contents.
    fn contents(dir: &Path) -> BTreeMap<String, Vec<u8>> {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                (e.file_name().into_string().unwrap(), std::fs::read(e.path()).unwrap())
            })
            .collect()
    }

    fn refusal(dir: &Path) -> Refusal {
        match inspect(dir).unwrap().verdict() {
            Verdict::Refuse(r) => r,
            v => panic!("{v:?}"),
        }
    }

    #[test]
    fn only_a_directory_without_history_is_new() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("data");
        assert!(matches!(inspect(&dir).unwrap().verdict(), Verdict::New));
        std::fs::create_dir(&dir).unwrap();
        std::fs::write(dir.join("notes.txt"), "mine").unwrap();
        let found = inspect(&dir).unwrap();
        assert!(matches!(found.verdict(), Verdict::New));
        assert_eq!(found.other, vec![dir.join("notes.txt")]);
        // A first start killed while writing its first snapshot (its blank state written,
        // its world not): refused, but repairable.
        let tmp_world = dir.join(".snapshot-00000000000000000000.naadf.tmp-7-0-1");
        std::fs::write(&tmp_world, "half").unwrap();
        let state = dir.join("snapshot-00000000000000000000.state");
        std::fs::write(&state, ServerState::default().encode()).unwrap();
        let r = refusal(&dir);
        assert!(r.repairable, "{r}");
        assert!(r.to_string().contains("naadf data repair"), "{r}");
        assert!(matches!(DataDir::open(&dir), Err(StoreError::Refused(_))));
        assert!(
            !dir.join(layout::LOCK).exists(),
            "a refused directory gets no lock file"
        );
        for a in inspect(&dir).unwrap().repair().unwrap() {
            a.apply().unwrap();
        }
        // The temporary file is deleted; the state, which is no temporary, is kept aside.
        assert!(!tmp_world.exists() && !state.exists());
        let kept = dir.join(layout::QUARANTINE).join("snapshot-00000000000000000000.state");
        assert_eq!(std::fs::read(kept).unwrap(), ServerState::default().encode());
        assert!(dir.join("notes.txt").exists());
        let found = inspect(&dir).unwrap();
        assert_eq!(found.quarantined, 1);
        assert!(matches!(found.verdict(), Verdict::New), "the quarantine is ignored");
    }

    /// A lone server state in which requests were answered is what is left of a world that
    /// was served: never a first start's leftovers, never repaired away, never a new world.
    #[test]
    fn a_lone_state_of_a_served_world_is_refused_untouched() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        let mut state = ServerState {
            version: 1000,
            ..ServerState::default()
        };
        state.histories.answer("alice", 7, 1000);
        std::fs::write(dir.join("snapshot-00000000000000001000.state"), state.encode()).unwrap();
        let before = contents(dir);
        let r = refusal(dir);
        assert!(!r.repairable, "{r}");
        assert!(!r.remedy.contains("data repair"), "no repair is offered: {r}");
        assert_eq!(inspect(dir).unwrap().repair(), Err(r));
        assert!(matches!(DataDir::open(dir), Err(StoreError::Refused(_))));
        assert_eq!(contents(dir), before, "the refusal changed the directory");
        assert!(!dir.join(layout::LOCK).exists());
    }

    /// Snapshot 0, the log 1–5 across two segments, and a snapshot 3 that does not load:
    /// the older road reaches every version, and repair takes it by moving snapshot 3 into
    /// the quarantine.
    #[test]
    fn a_damaged_newest_snapshot_is_passed_by_an_older_road() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        served(dir);
        let (mut wal, _) = Wal::resume(dir, Vec::new(), 3).unwrap();
        for version in 4..6 {
            wal.append(&entry(version).frame()).unwrap();
        }
        wal.sync().unwrap();
        drop(wal);
        // Snapshot 3's files hold version 0: they do not load as snapshot 3.
        let (w0, s0) = layout::snapshot_paths(dir, 0);
        let (w3, s3) = layout::snapshot_paths(dir, 3);
        std::fs::copy(&w0, &w3).unwrap();
        std::fs::copy(&s0, &s3).unwrap();
        std::fs::remove_file(dir.join(layout::LOCK)).unwrap();
        let load = |v| store::load_snapshot(dir, v).map(drop).map_err(|e| e.to_string());
        let mut found = inspect(dir).unwrap();
        assert!(
            matches!(found.verdict(), Verdict::Resume { snapshot: 3, .. }),
            "unverified"
        );
        found.verify(load);
        assert_eq!(found.road, Some((0, 5)));
        let Verdict::Refuse(r) = found.verdict() else {
            panic!("a damaged snapshot is refused")
        };
        assert!(
            r.repairable && r.remedy.contains("resumes from snapshot 0 and replays 5"),
            "{r}"
        );
        // Opening refuses it too, and writes nothing.
        let before = contents(dir);
        assert!(matches!(DataDir::open(dir), Err(StoreError::Refused(_))));
        assert_eq!(contents(dir), before);
        let actions = found.repair().unwrap();
        assert_eq!(actions.len(), 2, "{actions:?}");
        for a in &actions {
            assert!(a.to_string().starts_with("move snapshot-00000000000000000003."), "{a}");
            a.apply().unwrap();
        }
        let mut after = inspect(dir).unwrap();
        after.verify(load);
        assert!(matches!(
            after.verdict(),
            Verdict::Resume {
                snapshot: 0,
                records: 5
            }
        ));
        assert!(dir.join(layout::QUARANTINE).join(name(&w3)).exists());
        assert!(dir.join(layout::QUARANTINE).join(name(&s3)).exists());
        let (_, _, loaded) = DataDir::open(dir).unwrap();
        assert_eq!(loaded.unwrap().0.version(), 0);
    }

    #[test]
    fn history_without_a_complete_snapshot_is_refused_untouched() {
        for (missing, found, remedy) in [
            (
                &["state"][..],
                "snapshot-00000000000000000000.naadf without its .state",
                "(3 readable in the log)",
            ),
            (
                &["naadf"][..],
                "snapshot-00000000000000000000.state without its .naadf",
                "gone",
            ),
            (
                &["naadf", "state"][..],
                "wal-00000000000000000000.log (versions 1–3)",
                "gone",
            ),
        ] {
            let tmp = tempfile::tempdir().unwrap();
            let dir = tmp.path();
            served(dir);
            for ext in missing {
                std::fs::remove_file(dir.join(format!("snapshot-00000000000000000000.{ext}"))).unwrap();
            }
            std::fs::remove_file(dir.join(layout::LOCK)).unwrap();
            let before = contents(dir);
            let r = refusal(dir);
            let text = r.to_string();
            assert!(!r.repairable && text.contains(found) && text.contains(remedy), "{text}");
            assert!(text.contains("naadf data check"), "{text}");
            let err = DataDir::open(dir).unwrap_err().to_string();
            assert!(err.starts_with("refusing to start: data directory"), "{err}");
            assert_eq!(inspect(dir).unwrap().repair(), Err(r));
            assert!(inspect(dir).unwrap().orphans().is_empty());
            assert_eq!(contents(dir), before, "missing {missing:?}: the directory changed");
        }
    }

    #[test]
    fn a_resumable_directory_loses_its_orphans_and_torn_tail_only() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        served(dir);
        let segment = dir.join(wal::segment_name(0));
        let intact = std::fs::metadata(&segment).unwrap().len();
        std::fs::OpenOptions::new()
            .append(true)
            .open(&segment)
            .and_then(|mut f| std::io::Write::write_all(&mut f, &[0; 100]))
            .unwrap();
        let lone = dir.join("snapshot-00000000000000000002.state");
        std::fs::copy(dir.join("snapshot-00000000000000000000.state"), &lone).unwrap();
        let temps = [
            dir.join(".snapshot-00000000000000000002.naadf.tmp-9-0-5"),
            dir.join(".snapshot-00000000000000000000.state.tmp-9-1-5"),
        ];
        for t in &temps {
            std::fs::write(t, "partial").unwrap();
        }
        let found = inspect(dir).unwrap();
        assert!(matches!(
            found.verdict(),
            Verdict::Resume {
                snapshot: 0,
                records: 3
            }
        ));
        let actions = found.repair().unwrap();
        assert_eq!(actions.len(), 4, "{actions:?}");
        assert_eq!(
            actions[0],
            Action::Cut {
                path: segment.clone(),
                at: intact,
                len: intact + 100
            }
        );
        for a in &actions {
            a.apply().unwrap();
        }
        let after = inspect(dir).unwrap();
        assert!(matches!(
            after.verdict(),
            Verdict::Resume {
                snapshot: 0,
                records: 3
            }
        ));
        assert_eq!(after.repair().unwrap(), vec![]);
        assert!(!lone.exists() && temps.iter().all(|t| !t.exists()));
        assert!(
            dir.join(layout::QUARANTINE).join(name(&lone)).exists(),
            "the lone state is kept aside"
        );
        assert_eq!(std::fs::metadata(&segment).unwrap().len(), intact);
        assert_eq!(store::snapshots(dir).unwrap(), vec![0]);
    }

    #[test]
    fn a_broken_log_after_a_complete_snapshot_is_refused() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        served(dir);
        // Zeros over the second record, the third intact behind them.
        let segment = dir.join(wal::segment_name(0));
        let mut bytes = std::fs::read(&segment).unwrap();
        let second = bytes.len() - entry(3).frame().len() - entry(2).frame().len();
        bytes[second..second + entry(2).frame().len()].fill(0);
        std::fs::write(&segment, &bytes).unwrap();
        let r = refusal(dir);
        assert!(!r.repairable);
        assert!(r.problem.contains("followed by an intact record (version 3)"), "{r}");
        assert!(
            r.remedy.contains("--world MOVED/snapshot-00000000000000000000.naadf"),
            "{r}"
        );
    }

    /// A directory whose newest snapshot lost the log segment that starts at it would
    /// resume at that snapshot and drop every edit acknowledged after it without a word.
    #[test]
    fn a_missing_log_segment_after_the_newest_snapshot_is_refused_untouched() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path();
        served(dir);
        std::fs::remove_file(dir.join(layout::LOCK)).unwrap();
        std::fs::remove_file(dir.join(wal::segment_name(0))).unwrap();
        let before = contents(dir);
        let r = refusal(dir);
        assert!(!r.repairable, "{r}");
        assert!(
            r.problem.contains("wal-00000000000000000000.log")
                && r.problem.contains("is missing")
                && r.problem.contains("roll the world back to version 0"),
            "{r}"
        );
        assert!(
            r.remedy.contains("--world MOVED/snapshot-00000000000000000000.naadf"),
            "{r}"
        );
        assert!(matches!(DataDir::open(dir), Err(StoreError::Refused(_))));
        assert_eq!(inspect(dir).unwrap().repair(), Err(r));
        assert_eq!(contents(dir), before, "the refusal changed the directory");
    }
}

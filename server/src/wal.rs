//! The write-ahead log: every applied batch, durable before it is acknowledged.
//!
//! The log is a sequence of segment files `wal-<base>.log` in the data directory, where
//! `<base>` (20 decimal digits) is the version of the snapshot the segment follows: its
//! first record is version `base + 1`. A checkpoint starts a new segment; segments wholly
//! covered by a durable snapshot are deleted.
//!
//! ```text
//! segment   magic "NAADFWAL" (8 bytes), format u32 LE (1), base version u64 LE
//! record    payload length u32 LE, xxh3-64 of the payload u64 LE, payload
//! payload   postcard of Entry { version, user, client_seq, kind, ops }
//! ```
//!
//! Recovery reads the segments in order and requires consecutive versions. A damaged or
//! short record at the very end of the last segment is a torn write from a crash: it is
//! dropped (and truncated away). Damage anywhere else is corruption, reported as an error
//! rather than silently losing acknowledged edits.

use naadf_world::edit::BatchKind;
use serde::{Deserialize, Serialize};
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use xxhash_rust::xxh3::xxh3_64;

/// The segment magic.
const MAGIC: &[u8; 8] = b"NAADFWAL";
/// The segment format this build writes and reads.
const FORMAT: u32 = 1;
/// Bytes of a segment header.
const HEADER_LEN: u64 = 8 + 4 + 8;
/// Bytes of a record's framing.
const FRAME_LEN: usize = 4 + 8;
/// The largest payload a record may hold (a request is bounded far below this).
const MAX_PAYLOAD: usize = 1 << 30;

/// One logged batch.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Entry {
    /// The version the batch produced.
    pub version: u64,
    /// Who sent it.
    pub user: String,
    /// The request's client sequence number (0: none).
    pub client_seq: u64,
    /// What kind of request it was (undo and redo rebuild the history on replay).
    pub kind: BatchKind,
    /// The batch as one canonical ops-JSON line.
    pub ops: String,
}

impl Entry {
    /// The framed record bytes of this entry.
    pub fn frame(&self) -> Vec<u8> {
        let payload = postcard::to_allocvec(self).expect("entries serialize");
        let mut out = Vec::with_capacity(FRAME_LEN + payload.len());
        out.extend_from_slice(&(payload.len() as u32).to_le_bytes());
        out.extend_from_slice(&xxh3_64(&payload).to_le_bytes());
        out.extend_from_slice(&payload);
        out
    }
}

/// Errors of the log.
#[derive(Debug, thiserror::Error)]
pub enum WalError {
    /// An I/O failure, with what was being done.
    #[error("{0}: {1}")]
    Io(String, std::io::Error),
    /// A damaged log that recovery must not paper over.
    #[error("write-ahead log {0}: {1}")]
    Corrupt(PathBuf, String),
}

fn io(what: impl Into<String>) -> impl FnOnce(std::io::Error) -> WalError {
    let what = what.into();
    move |e| WalError::Io(what, e)
}

/// The file name of the segment following the snapshot at `base`.
pub fn segment_name(base: u64) -> String {
    format!("wal-{base:020}.log")
}

/// The segments in `dir`, by base version.
pub fn segments(dir: &Path) -> Result<Vec<(u64, PathBuf)>, WalError> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).map_err(io(format!("cannot list {}", dir.display())))? {
        let e = e.map_err(io(format!("cannot list {}", dir.display())))?;
        let name = e.file_name();
        let Some(name) = name.to_str() else { continue };
        if let Some(base) = name
            .strip_prefix("wal-")
            .and_then(|r| r.strip_suffix(".log"))
            .and_then(|d| d.parse::<u64>().ok())
        {
            out.push((base, e.path()));
        }
    }
    out.sort();
    Ok(out)
}

/// Reads every record of one segment. Returns the entries and, when the segment ends in a
/// torn record, the byte offset where the intact part ends.
fn read_segment(path: &Path, base: u64, last: bool) -> Result<(Vec<Entry>, Option<u64>), WalError> {
    let corrupt = |m: String| WalError::Corrupt(path.to_owned(), m);
    let mut bytes = Vec::new();
    File::open(path)
        .and_then(|mut f| f.read_to_end(&mut bytes))
        .map_err(io(format!("cannot read {}", path.display())))?;
    if (bytes.len() as u64) < HEADER_LEN {
        // A crash while creating the segment: only possible for the last one.
        return if last {
            Ok((Vec::new(), Some(0)))
        } else {
            Err(corrupt("truncated header".into()))
        };
    }
    if &bytes[..8] != MAGIC {
        return Err(corrupt("bad magic (not a write-ahead log segment)".into()));
    }
    let format = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
    if format != FORMAT {
        return Err(corrupt(format!(
            "unsupported format {format} (this build reads {FORMAT})"
        )));
    }
    let stored_base = u64::from_le_bytes(bytes[12..20].try_into().expect("8 bytes"));
    if stored_base != base {
        return Err(corrupt(format!(
            "header says base {stored_base}, file name says {base}"
        )));
    }
    let mut at = HEADER_LEN as usize;
    let mut out = Vec::new();
    while at < bytes.len() {
        let rest = &bytes[at..];
        // A torn record may only end the last segment.
        let torn = |why: &str| {
            if last {
                Ok(())
            } else {
                Err(corrupt(format!("{why} at byte {at}")))
            }
        };
        if rest.len() < FRAME_LEN {
            torn("truncated record header")?;
            return Ok((out, Some(at as u64)));
        }
        let len = u32::from_le_bytes(rest[..4].try_into().expect("4 bytes")) as usize;
        let sum = u64::from_le_bytes(rest[4..12].try_into().expect("8 bytes"));
        if len > MAX_PAYLOAD {
            return Err(corrupt(format!("record length {len} at byte {at}")));
        }
        let end = FRAME_LEN + len;
        if rest.len() < end {
            torn("truncated record")?;
            return Ok((out, Some(at as u64)));
        }
        let payload = &rest[FRAME_LEN..end];
        if xxh3_64(payload) != sum {
            // A bad checksum on the final record is a torn write; before it, corruption.
            if rest.len() == end {
                torn("checksum mismatch")?;
                return Ok((out, Some(at as u64)));
            }
            return Err(corrupt(format!("checksum mismatch at byte {at}")));
        }
        let e: Entry =
            postcard::from_bytes(payload).map_err(|e| corrupt(format!("undecodable record at byte {at}: {e}")))?;
        out.push(e);
        at += end;
    }
    Ok((out, None))
}

/// Where a torn final record starts: the segment and the byte offset.
type TornTail = (PathBuf, u64);

/// Reads the log in `dir` after version `snapshot` without changing it: the entries in
/// order, and where a torn final record starts (segment and byte offset), if there is one.
fn scan(dir: &Path, snapshot: u64) -> Result<(Vec<Entry>, Option<TornTail>), WalError> {
    let segs = segments(dir)?;
    if let Some((base, _)) = segs.first()
        && *base > snapshot
    {
        return Err(WalError::Corrupt(
            dir.to_owned(),
            format!("the oldest segment starts after version {base}, but the snapshot is at {snapshot}"),
        ));
    }
    let mut entries: Vec<Entry> = Vec::new();
    let mut next = snapshot + 1;
    let mut torn_at = None;
    for (i, (base, path)) in segs.iter().enumerate() {
        let (es, torn) = read_segment(path, *base, i + 1 == segs.len())?;
        for e in es {
            if e.version <= snapshot {
                continue;
            }
            if e.version != next {
                return Err(WalError::Corrupt(
                    path.clone(),
                    format!("version {} follows {} (a gap or a repeat)", e.version, next - 1),
                ));
            }
            next += 1;
            entries.push(e);
        }
        torn_at = torn.map(|at| (path.clone(), at));
    }
    Ok((entries, torn_at))
}

/// The entries after version `snapshot`, read without changing the log (a torn final
/// record is ignored): what `naadf export-log` reads while a server may be running.
pub fn read_after(dir: &Path, snapshot: u64) -> Result<Vec<Entry>, WalError> {
    Ok(scan(dir, snapshot)?.0)
}

/// An open log, appending to its newest segment.
#[derive(Debug)]
pub struct Wal {
    dir: PathBuf,
    file: BufWriter<File>,
    base: u64,
}

impl Wal {
    /// Opens the log in `dir` after a snapshot at version `snapshot`: returns the log and
    /// the entries after the snapshot, in order. A torn final record is dropped and cut off
    /// the file; any other damage, or a gap in the versions, is an error.
    pub fn open(dir: &Path, snapshot: u64) -> Result<(Wal, Vec<Entry>), WalError> {
        let (entries, torn) = scan(dir, snapshot)?;
        let next = snapshot + 1 + entries.len() as u64;
        if let Some((path, at)) = torn {
            tracing::warn!(segment = %path.display(), at, "dropping a torn record at the end of the log");
            if at < HEADER_LEN {
                std::fs::remove_file(&path).map_err(io(format!("cannot remove {}", path.display())))?;
            } else {
                let f = OpenOptions::new()
                    .write(true)
                    .open(&path)
                    .map_err(io(format!("cannot open {}", path.display())))?;
                f.set_len(at)
                    .map_err(io(format!("cannot truncate {}", path.display())))?;
                f.sync_all().map_err(io(format!("cannot fsync {}", path.display())))?;
            }
        }
        // Append to the newest intact segment, or start one after the last version.
        let wal = match segments(dir)?.last() {
            Some((base, path)) => {
                let mut f = OpenOptions::new()
                    .append(true)
                    .open(path)
                    .map_err(io(format!("cannot open {}", path.display())))?;
                f.seek(SeekFrom::End(0)).map_err(io("cannot seek the log"))?;
                Wal {
                    dir: dir.to_owned(),
                    file: BufWriter::new(f),
                    base: *base,
                }
            }
            None => Wal::create(dir, next - 1)?,
        };
        Ok((wal, entries))
    }

    /// Creates a new segment following version `base`, durably.
    fn create(dir: &Path, base: u64) -> Result<Wal, WalError> {
        let path = dir.join(segment_name(base));
        let mut f = OpenOptions::new()
            .create(true)
            .truncate(true)
            .write(true)
            .open(&path)
            .map_err(io(format!("cannot create {}", path.display())))?;
        let mut h = Vec::with_capacity(HEADER_LEN as usize);
        h.extend_from_slice(MAGIC);
        h.extend_from_slice(&FORMAT.to_le_bytes());
        h.extend_from_slice(&base.to_le_bytes());
        f.write_all(&h)
            .map_err(io(format!("cannot write {}", path.display())))?;
        f.sync_all().map_err(io(format!("cannot fsync {}", path.display())))?;
        sync_dir(dir)?;
        Ok(Wal {
            dir: dir.to_owned(),
            file: BufWriter::new(f),
            base,
        })
    }

    /// Appends framed records (not yet durable: call [`Wal::sync`]).
    pub fn append(&mut self, frame: &[u8]) -> Result<(), WalError> {
        self.file.write_all(frame).map_err(io("cannot append to the log"))
    }

    /// Makes everything appended so far durable (one fsync for a whole group of records).
    pub fn sync(&mut self) -> Result<(), WalError> {
        self.file.flush().map_err(io("cannot write the log"))?;
        self.file.get_ref().sync_data().map_err(io("cannot fsync the log"))
    }

    /// Starts a new segment after version `base` (a checkpoint); older segments stay until
    /// [`prune`] removes them behind a durable snapshot.
    pub fn rotate(&mut self, base: u64) -> Result<(), WalError> {
        if base == self.base {
            return Ok(());
        }
        self.sync()?;
        *self = Wal::create(&self.dir, base)?;
        Ok(())
    }
}

/// Deletes the segments that hold nothing after version `snapshot` (every segment older
/// than the newest one whose base is at most `snapshot`).
pub fn prune(dir: &Path, snapshot: u64) -> Result<(), WalError> {
    let segs = segments(dir)?;
    let Some(keep) = segs.iter().rposition(|(base, _)| *base <= snapshot) else {
        return Ok(());
    };
    for (_, path) in &segs[..keep] {
        std::fs::remove_file(path).map_err(io(format!("cannot remove {}", path.display())))?;
    }
    sync_dir(dir)
}

/// Fsyncs a directory so that created, renamed and removed names are durable.
pub fn sync_dir(dir: &Path) -> Result<(), WalError> {
    File::open(dir)
        .and_then(|d| d.sync_all())
        .map_err(io(format!("cannot fsync directory {}", dir.display())))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(v: u64) -> Entry {
        Entry {
            version: v,
            user: "alice".into(),
            client_seq: v * 10,
            kind: BatchKind::Edit,
            ops: format!(r#"{{"op":"set","voxels":[[{v},0,0,1]]}}"#),
        }
    }

    fn write(dir: &Path, snapshot: u64, versions: std::ops::Range<u64>) {
        let (mut wal, _) = Wal::open(dir, snapshot).unwrap();
        for v in versions {
            wal.append(&entry(v).frame()).unwrap();
        }
        wal.sync().unwrap();
    }

    #[test]
    fn entries_survive_reopening_and_rotation() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), 0, 1..6);
        let (mut wal, got) = Wal::open(dir.path(), 0).unwrap();
        assert_eq!(got, (1..6).map(entry).collect::<Vec<_>>());
        wal.rotate(5).unwrap();
        wal.append(&entry(6).frame()).unwrap();
        wal.sync().unwrap();
        drop(wal);
        let (_, got) = Wal::open(dir.path(), 0).unwrap();
        assert_eq!(got.len(), 6);
        // A snapshot at 5 makes the first segment prunable; entries after it remain.
        prune(dir.path(), 5).unwrap();
        assert_eq!(segments(dir.path()).unwrap().len(), 1);
        let (_, got) = Wal::open(dir.path(), 5).unwrap();
        assert_eq!(got, vec![entry(6)]);
        // A snapshot at 3 with the first segment gone cannot be recovered from.
        assert!(Wal::open(dir.path(), 3).is_err());
    }

    #[test]
    fn a_torn_tail_is_dropped_at_every_cut() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), 0, 1..4);
        let path = dir.path().join(segment_name(0));
        let full = std::fs::read(&path).unwrap();
        let three = full.len();
        let two = three - entry(3).frame().len();
        for cut in two..three {
            std::fs::write(&path, &full[..cut]).unwrap();
            let (mut wal, got) = Wal::open(dir.path(), 0).unwrap();
            assert_eq!(got.len(), 2, "cut at {cut}");
            assert_eq!(std::fs::metadata(&path).unwrap().len() as usize, two);
            // Appending after recovery continues cleanly.
            wal.append(&entry(3).frame()).unwrap();
            wal.sync().unwrap();
            drop(wal);
            assert_eq!(Wal::open(dir.path(), 0).unwrap().1.len(), 3);
        }
        // A flipped bit in the last record is torn too; in an earlier one it is corruption.
        let mut bad = full.clone();
        *bad.last_mut().unwrap() ^= 1;
        std::fs::write(&path, &bad).unwrap();
        assert_eq!(Wal::open(dir.path(), 0).unwrap().1.len(), 2);
        let mut bad = full.clone();
        bad[HEADER_LEN as usize + FRAME_LEN + 2] ^= 1;
        std::fs::write(&path, &bad).unwrap();
        let err = Wal::open(dir.path(), 0).unwrap_err().to_string();
        assert!(err.contains("checksum mismatch"), "{err}");
    }

    #[test]
    fn gaps_and_foreign_files_are_errors() {
        let dir = tempfile::tempdir().unwrap();
        let (mut wal, _) = Wal::open(dir.path(), 0).unwrap();
        wal.append(&entry(1).frame()).unwrap();
        wal.append(&entry(3).frame()).unwrap();
        wal.sync().unwrap();
        drop(wal);
        assert!(Wal::open(dir.path(), 0).unwrap_err().to_string().contains("gap"));
        std::fs::write(dir.path().join(segment_name(0)), b"hello, this is not a log").unwrap();
        assert!(Wal::open(dir.path(), 0).unwrap_err().to_string().contains("magic"));
    }
}

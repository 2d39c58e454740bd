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
//! Recovery reads the segments in order and requires consecutive versions. A crash can
//! leave anything after the last durable record: a short record, zeros, garbage, an
//! impossible length, or (in a segment being created) a short or zero header. All such
//! unverifiable bytes at the end of the last segment are one torn write: dropped and
//! truncated away. Damage that an intact record of a later version follows, or damage in
//! any but the last segment, is corruption, reported as an error rather than silently
//! losing acknowledged edits.

use naadf_world::edit::BatchKind;
use naadf_world::hash::xxh3_64;
use serde::{Deserialize, Serialize};
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

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

/// The base version of a segment's file name (see [`segment_name`]), if it is one.
pub fn segment_base(name: &str) -> Option<u64> {
    name.strip_prefix("wal-")?.strip_suffix(".log")?.parse().ok()
}

/// The segments in `dir`, by base version.
pub fn segments(dir: &Path) -> Result<Vec<(u64, PathBuf)>, WalError> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).map_err(io(format!("cannot list {}", dir.display())))? {
        let e = e.map_err(io(format!("cannot list {}", dir.display())))?;
        if let Some(base) = e.file_name().to_str().and_then(segment_base) {
            out.push((base, e.path()));
        }
    }
    out.sort();
    Ok(out)
}

/// One segment as recovery reads it.
#[derive(Debug)]
pub struct Segment {
    /// The version of the snapshot the segment follows (its first record is `base + 1`).
    pub base: u64,
    /// The file.
    pub path: PathBuf,
    /// The file's size in bytes.
    pub len: u64,
    /// Its intact records, in order.
    pub entries: Vec<Entry>,
    /// Where the unverifiable tail a crash left starts, if the segment ends in one: a byte
    /// offset, 0 when not even the header was written. Recovery cuts it off ([`cut_tail`]).
    pub torn: Option<u64>,
}

impl Segment {
    /// The first and last version of its records, if it holds any.
    pub fn versions(&self) -> Option<(u64, u64)> {
        Some((self.entries.first()?.version, self.entries.last()?.version))
    }

    /// Ends the segment at the damage found at byte `at`: a torn write when this is the
    /// last segment and no intact record of a later version follows; otherwise corruption,
    /// described by the error.
    fn damaged(mut self, bytes: &[u8], at: usize, why: &str, last: bool) -> Result<Segment, String> {
        let after = self.entries.last().map_or(self.base, |e| e.version);
        match next_record(bytes, at + 1, after) {
            Some((next, version)) => Err(format!(
                "{why} at byte {at}, followed by an intact record (version {version}) at byte {next}"
            )),
            None if last => {
                self.torn = Some(at as u64);
                Ok(self)
            }
            None => Err(format!("{why} at byte {at} of a segment that later segments follow")),
        }
    }
}

/// Reads one segment without changing it; `last`: whether it is the newest, the only one a
/// torn write may end.
pub fn read_segment(path: &Path, base: u64, last: bool) -> Result<Segment, WalError> {
    let corrupt = |m: String| WalError::Corrupt(path.to_owned(), m);
    let mut bytes = Vec::new();
    File::open(path)
        .and_then(|mut f| f.read_to_end(&mut bytes))
        .map_err(io(format!("cannot read {}", path.display())))?;
    let mut segment = Segment {
        base,
        path: path.to_owned(),
        len: bytes.len() as u64,
        entries: Vec::new(),
        torn: None,
    };
    // A crash while the segment was created leaves its header short, or zeros where the
    // file grew before its data landed.
    let header = &bytes[..bytes.len().min(HEADER_LEN as usize)];
    if header.len() < HEADER_LEN as usize || header.iter().all(|&b| b == 0) {
        return segment.damaged(&bytes, 0, "unwritten header", last).map_err(corrupt);
    }
    if &header[..8] != MAGIC {
        return Err(corrupt("bad magic (not a write-ahead log segment)".into()));
    }
    let format = u32::from_le_bytes(header[8..12].try_into().expect("4 bytes"));
    if format != FORMAT {
        return Err(corrupt(format!(
            "unsupported format {format} (this build reads {FORMAT})"
        )));
    }
    let stored_base = u64::from_le_bytes(header[12..20].try_into().expect("8 bytes"));
    if stored_base != base {
        return Err(corrupt(format!(
            "header says base {stored_base}, file name says {base}"
        )));
    }
    let mut at = HEADER_LEN as usize;
    while at < bytes.len() {
        let (payload, end) = match frame_at(&bytes, at) {
            Ok(frame) => frame,
            Err(why) => return segment.damaged(&bytes, at, why, last).map_err(corrupt),
        };
        // A payload under an intact checksum was written that way: no crash explains it.
        let e: Entry =
            postcard::from_bytes(payload).map_err(|e| corrupt(format!("undecodable record at byte {at}: {e}")))?;
        segment.entries.push(e);
        at = end;
    }
    Ok(segment)
}

/// The record framed at byte `at`: its payload and where it ends, or why it cannot be
/// verified.
fn frame_at(bytes: &[u8], at: usize) -> Result<(&[u8], usize), &'static str> {
    let rest = &bytes[at..];
    let head = rest.get(..FRAME_LEN).ok_or("truncated record header")?;
    let len = u32::from_le_bytes(head[..4].try_into().expect("4 bytes")) as usize;
    let sum = u64::from_le_bytes(head[4..].try_into().expect("8 bytes"));
    if len > MAX_PAYLOAD {
        return Err("impossible record length");
    }
    let payload = rest.get(FRAME_LEN..FRAME_LEN + len).ok_or("truncated record")?;
    if xxh3_64(payload) != sum {
        return Err("checksum mismatch");
    }
    Ok((payload, at + FRAME_LEN + len))
}

/// The first intact record of a version after `after` that starts at or after byte `from`,
/// with that version: proof that damage before it is no torn write at the end of the log.
/// Records of earlier versions prove nothing: they are old file contents a crash exposed.
fn next_record(bytes: &[u8], from: usize, after: u64) -> Option<(usize, u64)> {
    (from..bytes.len()).find_map(|at| {
        // Postcard writes the version first, so most offsets fail before any checksum.
        let (version, _) = postcard::take_from_bytes::<u64>(bytes.get(at + FRAME_LEN..)?).ok()?;
        if version <= after {
            return None;
        }
        let (payload, _) = frame_at(bytes, at).ok()?;
        let e: Entry = postcard::from_bytes(payload).ok()?;
        Some((at, e.version))
    })
}

/// Where recovery from the snapshot at `snapshot` starts reading, given the segments' bases
/// in ascending order: at the newest segment that starts at or before the snapshot (older
/// ones hold only versions it covers). 0 when none does, which [`check_sequence`] reports.
pub fn first_needed(bases: impl IntoIterator<Item = u64>, snapshot: u64) -> usize {
    bases
        .into_iter()
        .enumerate()
        .filter(|&(_, base)| base <= snapshot)
        .last()
        .map_or(0, |(i, _)| i)
}

/// Checks that `segments` (those from [`first_needed`] on, in order) continue the snapshot
/// at `snapshot`: the first starts at or before it, and the versions after it are
/// consecutive. Returns how many records follow the snapshot.
pub fn check_sequence<'a>(segments: impl IntoIterator<Item = &'a Segment>, snapshot: u64) -> Result<u64, WalError> {
    let mut next = snapshot + 1;
    for (i, s) in segments.into_iter().enumerate() {
        if i == 0 && s.base > snapshot {
            return Err(WalError::Corrupt(
                s.path.clone(),
                format!(
                    "the oldest segment follows version {}, but the snapshot is at {snapshot} \
                     (the segments between are missing)",
                    s.base
                ),
            ));
        }
        for e in &s.entries {
            if e.version <= snapshot {
                continue;
            }
            if e.version != next {
                return Err(WalError::Corrupt(
                    s.path.clone(),
                    format!("version {} follows {} (a gap or a repeat)", e.version, next - 1),
                ));
            }
            next += 1;
        }
    }
    Ok(next - snapshot - 1)
}

/// Reads the segments recovery from the snapshot at `snapshot` needs, without changing them.
fn read(dir: &Path, snapshot: u64) -> Result<Vec<Segment>, WalError> {
    let all = segments(dir)?;
    let first = first_needed(all.iter().map(|(base, _)| *base), snapshot);
    all[first..]
        .iter()
        .enumerate()
        .map(|(i, (base, path))| read_segment(path, *base, first + i + 1 == all.len()))
        .collect()
}

/// The entries of `segments` after version `snapshot`, in order.
fn entries_after(segments: Vec<Segment>, snapshot: u64) -> Vec<Entry> {
    segments
        .into_iter()
        .flat_map(|s| s.entries)
        .filter(|e| e.version > snapshot)
        .collect()
}

/// The entries after version `snapshot`, read without changing the log (a torn tail is
/// ignored): what `naadf export-log` reads while a server may be running.
pub fn read_after(dir: &Path, snapshot: u64) -> Result<Vec<Entry>, WalError> {
    let segments = read(dir, snapshot)?;
    check_sequence(&segments, snapshot)?;
    Ok(entries_after(segments, snapshot))
}

/// Cuts the unverifiable tail that starts at byte `at` ([`Segment::torn`]) off the segment
/// at `path`, durably; at 0, where not even the header was written, the file goes.
pub fn cut_tail(path: &Path, at: u64) -> Result<(), WalError> {
    if at == 0 {
        std::fs::remove_file(path).map_err(io(format!("cannot remove {}", path.display())))?;
        return match path.parent() {
            Some(dir) if !dir.as_os_str().is_empty() => sync_dir(dir),
            _ => sync_dir(Path::new(".")),
        };
    }
    let f = OpenOptions::new()
        .write(true)
        .open(path)
        .map_err(io(format!("cannot open {}", path.display())))?;
    f.set_len(at)
        .map_err(io(format!("cannot truncate {}", path.display())))?;
    f.sync_all().map_err(io(format!("cannot fsync {}", path.display())))
}

/// An open log, appending to its newest segment.
#[derive(Debug)]
pub struct Wal {
    dir: PathBuf,
    file: BufWriter<File>,
    base: u64,
}

impl Wal {
    /// Opens the log in `dir` for appending after the snapshot at `snapshot`, given the
    /// segments recovery needs as read (by the data directory's inspection, see
    /// [`crate::data::fsck`]): checks their versions, cuts a torn tail off, and returns the log
    /// and the entries after the snapshot, in order.
    pub fn resume(dir: &Path, segments: Vec<Segment>, snapshot: u64) -> Result<(Wal, Vec<Entry>), WalError> {
        let records = check_sequence(&segments, snapshot)?;
        let mut newest = None;
        for s in &segments {
            if let Some(at) = s.torn {
                tracing::warn!(segment = %s.path.display(), at, bytes = s.len - at, "cutting a torn write off the end of the log");
                cut_tail(&s.path, at)?;
            }
            if s.torn != Some(0) {
                newest = Some(s);
            }
        }
        // Append to the newest segment left, or start one after the last version.
        let wal = match newest {
            Some(s) => {
                let mut f = OpenOptions::new()
                    .append(true)
                    .open(&s.path)
                    .map_err(io(format!("cannot open {}", s.path.display())))?;
                f.seek(SeekFrom::End(0)).map_err(io("cannot seek the log"))?;
                Wal {
                    dir: dir.to_owned(),
                    file: BufWriter::new(f),
                    base: s.base,
                }
            }
            None => Wal::create(dir, snapshot + records)?,
        };
        Ok((wal, entries_after(segments, snapshot)))
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

    /// Opens the log the way the server does after a snapshot at `snapshot`.
    fn open(dir: &Path, snapshot: u64) -> Result<(Wal, Vec<Entry>), WalError> {
        Wal::resume(dir, read(dir, snapshot)?, snapshot)
    }

    fn write(dir: &Path, snapshot: u64, versions: std::ops::Range<u64>) {
        let (mut wal, _) = open(dir, snapshot).unwrap();
        for v in versions {
            wal.append(&entry(v).frame()).unwrap();
        }
        wal.sync().unwrap();
    }

    #[test]
    fn entries_survive_reopening_and_rotation() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), 0, 1..6);
        let (mut wal, got) = open(dir.path(), 0).unwrap();
        assert_eq!(got, (1..6).map(entry).collect::<Vec<_>>());
        wal.rotate(5).unwrap();
        wal.append(&entry(6).frame()).unwrap();
        wal.sync().unwrap();
        drop(wal);
        let (_, got) = open(dir.path(), 0).unwrap();
        assert_eq!(got.len(), 6);
        // A snapshot at 5 makes the first segment prunable; entries after it remain.
        prune(dir.path(), 5).unwrap();
        assert_eq!(segments(dir.path()).unwrap().len(), 1);
        let (_, got) = open(dir.path(), 5).unwrap();
        assert_eq!(got, vec![entry(6)]);
        // A snapshot at 3 with the first segment gone cannot be recovered from.
        assert!(open(dir.path(), 3).is_err());
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
            let (mut wal, got) = open(dir.path(), 0).unwrap();
            assert_eq!(got.len(), 2, "cut at {cut}");
            assert_eq!(std::fs::metadata(&path).unwrap().len() as usize, two);
            // Appending after recovery continues cleanly.
            wal.append(&entry(3).frame()).unwrap();
            wal.sync().unwrap();
            drop(wal);
            assert_eq!(open(dir.path(), 0).unwrap().1.len(), 3);
        }
        // A flipped bit in the last record is torn too; in an earlier one it is corruption.
        let mut bad = full.clone();
        *bad.last_mut().unwrap() ^= 1;
        std::fs::write(&path, &bad).unwrap();
        assert_eq!(open(dir.path(), 0).unwrap().1.len(), 2);
        let mut bad = full.clone();
        bad[HEADER_LEN as usize + FRAME_LEN + 2] ^= 1;
        std::fs::write(&path, &bad).unwrap();
        let err = open(dir.path(), 0).unwrap_err().to_string();
        assert!(err.contains("checksum mismatch"), "{err}");
    }

    /// Whatever a crash leaves after the last durable record is one torn write and is cut
    /// off; damage that an intact later record follows is corruption, wherever it is.
    #[test]
    fn every_unverifiable_tail_is_a_torn_write() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), 0, 1..4);
        let path = dir.path().join(segment_name(0));
        let full = std::fs::read(&path).unwrap();
        let two = full.len() - entry(3).frame().len();
        let with = |tail: &[u8]| [&full[..], tail].concat();
        let mut noise = 0x2545_f491_4f6c_dd1d_u64;
        let garbage: Vec<u8> = (0..4096)
            .map(|_| {
                noise ^= noise << 13;
                noise ^= noise >> 7;
                noise ^= noise << 17;
                noise as u8
            })
            .collect();
        let mut huge_last = full.clone();
        huge_last[two..two + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        for (what, bytes, intact, len) in [
            ("100 zero bytes", with(&[0; 100]), 3, full.len()),
            ("random garbage", with(&garbage), 3, full.len()),
            ("a huge length on the last record", huge_last, 2, two),
        ] {
            std::fs::write(&path, &bytes).unwrap();
            let got = open(dir.path(), 0).unwrap_or_else(|e| panic!("{what}: {e}")).1;
            assert_eq!(got.len(), intact, "{what}");
            assert_eq!(std::fs::metadata(&path).unwrap().len() as usize, len, "{what}");
        }
        // A new segment whose header never reached the disk goes; the log goes on before it.
        std::fs::write(&path, &full).unwrap();
        let fresh = dir.path().join(segment_name(3));
        std::fs::write(&fresh, [0; HEADER_LEN as usize]).unwrap();
        let (mut wal, got) = open(dir.path(), 0).unwrap();
        assert_eq!(got.len(), 3);
        assert!(!fresh.exists());
        wal.append(&entry(4).frame()).unwrap();
        wal.sync().unwrap();
        drop(wal);
        assert_eq!(open(dir.path(), 0).unwrap().1.len(), 4);
        // Zeros over the second record, with the third intact behind them: corruption.
        let mut bad = full.clone();
        let one = two - entry(2).frame().len();
        bad[one..two].fill(0);
        std::fs::write(&path, &bad).unwrap();
        let err = open(dir.path(), 0).unwrap_err().to_string();
        assert!(err.contains("followed by an intact record (version 3)"), "{err}");
        assert_eq!(std::fs::read(&path).unwrap(), bad, "a refused log is left as it was");
    }

    #[test]
    fn gaps_and_foreign_files_are_errors() {
        let dir = tempfile::tempdir().unwrap();
        let (mut wal, _) = open(dir.path(), 0).unwrap();
        wal.append(&entry(1).frame()).unwrap();
        wal.append(&entry(3).frame()).unwrap();
        wal.sync().unwrap();
        drop(wal);
        assert!(open(dir.path(), 0).unwrap_err().to_string().contains("gap"));
        std::fs::write(dir.path().join(segment_name(0)), b"hello, this is not a log").unwrap();
        assert!(open(dir.path(), 0).unwrap_err().to_string().contains("magic"));
    }
}

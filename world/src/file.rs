//! World files (`.naadf`): versioned, zstd-compressed, checksummed.
//!
//! A file is a fixed 40-byte header, one zstd frame holding the payload, and an 8-byte
//! trailer. The byte-by-byte layout, the versioning policy and the buffer layouts the
//! payload carries are specified in `docs/FORMAT.md`; in short (all integers
//! little-endian):
//!
//! ```text
//! header   0  magic            8 bytes  89 4E 41 41 44 46 0D 0A  ("\x89NAADF\r\n")
//!          8  format version   u32      3 (versions 1 and 2 are still read)
//!         12  flags            u32      0 (every bit reserved)
//!         16  payload length   u64      uncompressed payload bytes
//!         24  payload xxh3     u64      xxh3_64 of the uncompressed payload
//!         32  header xxh3      u64      xxh3_64 of header bytes 0..32
//! frame   40  one zstd frame whose content is the payload
//! trailer     xxh3_64 of the frame's bytes (u64), then end of file
//!
//! payload     world size 3×u32 (voxels), edit version u64, then seven sections, each a
//!             u64 byte length followed by that many bytes: material words, model table,
//!             chunks, chunk entities, blocks, voxels, entity table (version 1: the first
//!             six only)
//! ```
//!
//! The entity table section holds the entity types (model names, in order of first use)
//! and the instances with their quantised poses; the entity-type and instance buffers are
//! derived from it on load, deterministically, so a loaded world has the same digest.
//!
//! Version 3 keeps entities out of the static world: its chunk entity section is all zero
//! and no chunk AADF is cut around an entity. Versions 1 and 2 are read with their entities
//! carried over; a version-2 file with entities gets a zero chunk entity buffer and chunk
//! AADFs rebuilt from scratch on load, so its digest changes (an entity-free file's does
//! not).
//!
//! Reading streams the payload straight into the final buffers: every length is checked
//! against the header and against what the world size allows before anything is allocated,
//! buffers grow only as decompressed bytes actually arrive, and the structure is then
//! validated by [`World::from_parts`]. Corrupt input of any kind is an error, never a panic;
//! the three checksums together make every change to a file's bytes an error.

use crate::cell::MAX_MATERIAL;
use crate::digest::BufferId;
use crate::entity::EntityTable;
use crate::error::WorldError;
use crate::hash::{Xxh3, xxh3_64};
use crate::material::{Material, MaterialTable};
use crate::model::ModelTable;
use crate::size::{MAX_SIZE, WorldSize};
use crate::world::{World, bytemuck_u32};
use std::io::{BufRead, BufWriter, Read, Write};
use std::path::{Path, PathBuf};

/// The raw parts a world file stores (see [`read_parts`] and [`write_parts`]).
pub use crate::world::WorldParts;

/// The first eight bytes of every world file: `\x89NAADF\r\n`.
///
/// The high-bit first byte catches 7-bit transfers and text files, and the CR LF pair
/// catches line-ending conversion in either direction.
pub const MAGIC: [u8; 8] = *b"\x89NAADF\r\n";

/// The format version this build writes.
pub const FORMAT_VERSION: u32 = 3;

/// The format versions this build reads: 1 (no entity section), 2 (entities cut into the
/// chunk AADFs and listed per chunk) and 3.
pub const READ_VERSIONS: [u32; 3] = [1, 2, 3];

/// Bytes in the fixed header.
pub const HEADER_LEN: usize = 40;

/// Bytes in the trailer (the xxh3-64 of the compressed frame).
pub const TRAILER_LEN: usize = 8;

/// The zstd compression level used by [`write()`].
pub const COMPRESSION_LEVEL: i32 = 3;

/// Largest model-table section, in bytes (a reader rejects more).
pub const MAX_MODEL_BYTES: u64 = 1 << 30;

/// Largest `blocks` or `voxels` section, in 32-bit words: 30-bit pointers address no more.
pub const MAX_BUFFER_WORDS: u64 = 1 << 30;

/// Slack factor on the per-chunk bounds of `blocks` and `voxels` (see [`section_limits`]).
const SLACK: u64 = 4;

/// Bytes of the fixed part of a version-2 payload: size, version and seven section lengths.
const PAYLOAD_FIXED: u64 = 12 + 8 + 7 * 8;

/// Bytes of the fixed part of a version-1 payload (six sections).
const PAYLOAD_FIXED_V1: u64 = 12 + 8 + 6 * 8;

/// Largest entity-table section, in bytes (a reader rejects more).
pub const MAX_ENTITY_BYTES: u64 = 1 << 28;

/// Largest material section, in bytes (32768 entries of 16 bytes).
const MAX_MATERIAL_BYTES: u64 = 16 * (MAX_MATERIAL as u64 + 1);

/// Upper bounds, in bytes, on the sections of a world of `chunk_count` chunks.
///
/// `blocks` holds at most `4 × 64` words per chunk and `voxels` at most `4 × 2048` words
/// per chunk (four times what a world can hold live at once, as slack for slots freed by
/// edits), each capped at 2³⁰ words. Returns `[materials, models, chunks, chunk_entities,
/// blocks, voxels, entities]`; the `chunks` and `chunk_entities` entries are exact sizes.
pub fn section_limits(chunk_count: u64) -> [u64; 7] {
    let chunk_bytes = 4 * chunk_count;
    [
        MAX_MATERIAL_BYTES,
        MAX_MODEL_BYTES,
        chunk_bytes,
        chunk_bytes,
        4 * (SLACK * 64 * chunk_count).min(MAX_BUFFER_WORDS),
        4 * (SLACK * 2048 * chunk_count).min(MAX_BUFFER_WORDS),
        MAX_ENTITY_BYTES,
    ]
}

/// The largest payload a world of `chunk_count` chunks may declare.
fn max_payload(chunk_count: u64) -> u64 {
    PAYLOAD_FIXED + section_limits(chunk_count).iter().sum::<u64>()
}

/// Names of the seven sections, in file order.
const SECTIONS: [&str; 7] = [
    "materials",
    "models",
    "chunks",
    "chunk_entities",
    "blocks",
    "voxels",
    "entities",
];

/// Borrowed contents of a world, in file order.
struct View<'a> {
    size: WorldSize,
    version: u64,
    materials: &'a [u32],
    models: Vec<u8>,
    chunks: &'a [u32],
    chunk_entities: &'a [u32],
    blocks: &'a [u32],
    voxels: &'a [u32],
    entities: Vec<u8>,
}

/// Writes `world` as a world file to `out` (header, zstd frame, trailer). The payload is
/// streamed from the world's buffers: nothing but the model table is copied.
///
/// Fails with [`WorldError::Capacity`] if a buffer exceeds the format's bounds (a file a
/// reader would reject is never written) and with [`WorldError::Io`] if `out` fails.
pub fn write(world: &World, out: &mut dyn Write) -> Result<(), WorldError> {
    write_view(
        &View {
            size: world.size(),
            version: world.version(),
            materials: world.materials().words(),
            models: world.models().encode(),
            chunks: world.chunks(),
            chunk_entities: world.chunk_entities(),
            blocks: world.blocks(),
            voxels: world.voxels(),
            entities: world.entity_table().encode(),
        },
        out,
    )
}

/// Writes raw parts as a world file, without validating their structure (only the
/// format's size bounds are checked). [`read`] validates; this exists for tools and tests
/// that need to produce exactly the bytes they are given.
pub fn write_parts(parts: &WorldParts, out: &mut dyn Write) -> Result<(), WorldError> {
    write_view(
        &View {
            size: parts.size,
            version: parts.version,
            materials: parts.materials.words(),
            models: parts.models.encode(),
            chunks: &parts.chunks,
            chunk_entities: &parts.chunk_entities,
            blocks: &parts.blocks,
            voxels: &parts.voxels,
            entities: parts.entities.encode(),
        },
        out,
    )
}

fn write_view(v: &View, out: &mut dyn Write) -> Result<(), WorldError> {
    let io = |e| WorldError::io("writing world file", e);
    let sections: [&[u8]; 7] = [
        bytemuck_u32(v.materials),
        &v.models,
        bytemuck_u32(v.chunks),
        bytemuck_u32(v.chunk_entities),
        bytemuck_u32(v.blocks),
        bytemuck_u32(v.voxels),
        &v.entities,
    ];
    let limits = section_limits(v.size.chunk_count() as u64);
    for ((name, s), limit) in SECTIONS.iter().zip(&sections).zip(limits) {
        if s.len() as u64 > limit {
            return Err(WorldError::Capacity(format!(
                "{name} section of {} bytes exceeds the world file's bound of {limit} bytes \
                 for a {} world",
                s.len(),
                v.size
            )));
        }
    }
    let mut fixed = Vec::with_capacity(20);
    for n in v.size.voxels() {
        fixed.extend_from_slice(&n.to_le_bytes());
    }
    fixed.extend_from_slice(&v.version.to_le_bytes());
    let prefixes = sections.map(|s| (s.len() as u64).to_le_bytes());
    let mut pieces: Vec<&[u8]> = vec![&fixed];
    for (p, s) in prefixes.iter().zip(sections) {
        pieces.push(p);
        pieces.push(s);
    }
    let payload_len: u64 = pieces.iter().map(|p| p.len() as u64).sum();
    let mut hasher = Xxh3::new();
    for p in &pieces {
        hasher.update(p);
    }
    out.write_all(&header_bytes(payload_len, hasher.digest())).map_err(io)?;
    let frame = HashingWriter {
        inner: &mut *out,
        hasher: Xxh3::new(),
    };
    let mut enc = zstd::stream::write::Encoder::new(frame, COMPRESSION_LEVEL).map_err(io)?;
    enc.include_contentsize(true).map_err(io)?;
    enc.include_checksum(false).map_err(io)?;
    enc.set_pledged_src_size(Some(payload_len)).map_err(io)?;
    for p in pieces {
        enc.write_all(p).map_err(io)?;
    }
    let frame = enc.finish().map_err(io)?;
    let trailer = frame.hasher.digest().to_le_bytes();
    out.write_all(&trailer).map_err(io)?;
    out.flush().map_err(io)
}

/// Passes bytes through, hashing them.
struct HashingWriter<'a> {
    inner: &'a mut dyn Write,
    hasher: Xxh3,
}

impl Write for HashingWriter<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.hasher.update(&buf[..n]);
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// The 40-byte header for a payload of `len` bytes with xxh3 `checksum`.
fn header_bytes(len: u64, checksum: u64) -> [u8; HEADER_LEN] {
    let mut h = [0u8; HEADER_LEN];
    h[0..8].copy_from_slice(&MAGIC);
    h[8..12].copy_from_slice(&FORMAT_VERSION.to_le_bytes());
    h[12..16].copy_from_slice(&0u32.to_le_bytes());
    h[16..24].copy_from_slice(&len.to_le_bytes());
    h[24..32].copy_from_slice(&checksum.to_le_bytes());
    let own = xxh3_64(&h[..32]);
    h[32..40].copy_from_slice(&own.to_le_bytes());
    h
}

/// Reads a world file from `input` and validates it completely ([`World::from_parts`]).
///
/// Consumes `input` to its end: bytes after the trailer are an error. Every failure is
/// [`WorldError::BadFile`] with a message that names the problem ("not a naadf world file
/// (bad magic)", "unsupported format version N (this build reads 1)", "truncated …",
/// "… checksum mismatch …", …), except failures of `input` itself, which are
/// [`WorldError::Io`].
pub fn read(input: &mut dyn Read) -> Result<World, WorldError> {
    let parts = read_parts(input)?;
    World::from_parts(parts).map_err(into_bad_file)
}

/// Reads a world file's raw parts: header, checksums, framing, section bounds, the world
/// size, and the material and model tables are checked; the buffers' structure is not
/// (that is [`World::from_parts`], which [`read`] calls).
pub fn read_parts(input: &mut dyn Read) -> Result<WorldParts, WorldError> {
    let header = read_header(input)?;
    let frame = FrameReader {
        inner: input,
        buf: vec![0; 1 << 17].into_boxed_slice(),
        pos: 0,
        filled: 0,
        failed: false,
        hasher: Xxh3::new(),
    };
    let decoder = zstd::stream::read::Decoder::with_buffer(frame)
        .map_err(|e| WorldError::io("starting zstd decoder", e))?
        .single_frame();
    let mut p = Payload {
        format: header.version,
        dec: decoder,
        hasher: Xxh3::new(),
        done: 0,
        len: header.payload_len,
    };
    let raw = match p.sections() {
        Ok(raw) => raw,
        Err(Fail::Final(e)) => return Err(e),
        Err(Fail::Structure(msg)) => {
            // A damaged payload usually shows up as a nonsensical length first: report the
            // root cause (I/O, corrupt or truncated compressed data, checksum) if there is one.
            return Err(match p.drain() {
                Ok(()) if p.hasher.digest() != header.payload_checksum => {
                    bad("payload checksum mismatch (the file is corrupt)")
                }
                Ok(()) | Err(Fail::Structure(_)) => bad(msg),
                Err(Fail::Final(e)) => e,
            });
        }
    };
    p.expect_frame_end()?;
    if p.hasher.digest() != header.payload_checksum {
        return Err(bad("payload checksum mismatch (the file is corrupt)"));
    }
    p.dec.finish().trailer()?;
    let (materials, models, entities) = decode_tables(raw.materials, &raw.models, raw.entities.as_deref())?;
    let mut parts = WorldParts {
        size: raw.size,
        version: raw.version,
        materials,
        models,
        chunks: raw.chunks,
        chunk_entities: raw.chunk_entities,
        blocks: raw.blocks,
        voxels: raw.voxels,
        entities,
    };
    if header.version < 3 && !parts.entities.is_empty() {
        lift_entities_out(&mut parts)?;
    }
    Ok(parts)
}

/// Upgrades version-2 parts whose entities were part of the static world: the chunk entity
/// fields become zero and every chunk AADF is rebuilt without the cuts around entities.
fn lift_entities_out(parts: &mut WorldParts) -> Result<(), WorldError> {
    if parts.chunks.len() != parts.size.chunk_count() {
        return Err(bad(format!(
            "{} chunk cells for a {} world",
            parts.chunks.len(),
            parts.size
        )));
    }
    parts.chunk_entities.fill(0);
    crate::aadf::build_chunk_aadf(parts.size, &mut parts.chunks);
    Ok(())
}

/// The buffers a world is transferred by (a snapshot on the wire): the four cell arrays as
/// little-endian u32 words, the material table's words and the model table's canonical
/// encoding. The entity buffers are not among them: they derive from the entity table.
pub const TRANSFERRED: [BufferId; 6] = [
    BufferId::Chunks,
    BufferId::ChunkEntities,
    BufferId::Blocks,
    BufferId::Voxels,
    BufferId::Materials,
    BufferId::Models,
];

/// Assembles world parts from the bytes of the [`TRANSFERRED`] buffers (in that order, as
/// [`World::buffer_bytes`] gives them) and an entity-table encoding. The tables are checked
/// as when reading a file; [`World::from_parts`] checks the rest.
pub fn parts_from_buffers(
    size: WorldSize,
    version: u64,
    buffers: [&[u8]; 6],
    entity_table: &[u8],
) -> Result<WorldParts, WorldError> {
    let words = |i: usize| -> Result<Vec<u32>, WorldError> {
        let b = buffers[i];
        if !b.len().is_multiple_of(4) {
            return Err(bad(format!("{} bytes is not whole words", b.len())));
        }
        Ok(b.chunks_exact(4)
            .map(|w| u32::from_le_bytes(w.try_into().expect("four bytes")))
            .collect())
    };
    let (materials, models, entities) = decode_tables(words(4)?, buffers[5], Some(entity_table))?;
    Ok(WorldParts {
        size,
        version,
        materials,
        models,
        chunks: words(0)?,
        chunk_entities: words(1)?,
        blocks: words(2)?,
        voxels: words(3)?,
        entities,
    })
}

/// Decodes and checks the material, model and entity tables.
fn decode_tables(
    materials: Vec<u32>,
    models: &[u8],
    entities: Option<&[u8]>,
) -> Result<(MaterialTable, ModelTable, EntityTable), WorldError> {
    let materials = MaterialTable::from_words(materials).map_err(|e| bad(format!("material table: {e}")))?;
    for id in 1..materials.len() {
        let at = id * 4;
        let w: [u32; 4] = materials.words()[at..at + 4].try_into().expect("four words");
        Material::decode(w)
            .validate()
            .map_err(|e| bad(format!("material {id}: {e}")))?;
    }
    let models = ModelTable::decode(models).map_err(into_bad_file)?;
    let entities = match entities {
        Some(bytes) => EntityTable::decode(bytes)?,
        None => EntityTable::default(),
    };
    Ok((materials, models, entities))
}

/// Saves `world` to `path` atomically: the file is written to a temporary file in the
/// same directory, flushed and fsynced, then renamed over `path` (and, on Unix, the
/// directory is fsynced). A crash leaves either the old file or the new one, never a mix;
/// on error the temporary file is removed.
pub fn save(world: &World, path: &Path) -> Result<(), WorldError> {
    save_atomically(path, &mut |out| write(world, out))
}

/// [`save`] for raw parts (what a server snapshots while its world moves on).
pub fn save_parts(parts: &WorldParts, path: &Path) -> Result<(), WorldError> {
    save_atomically(path, &mut |out| write_parts(parts, out))
}

/// Writes the file at `path` atomically with `write`: into a temporary file in the same
/// directory, flushed and fsynced, then renamed over `path`, then the directory fsynced (see
/// [`save`]). Other files that must survive a crash whole (a server's state files) use it
/// too.
pub fn save_atomically(
    path: &Path,
    write: &mut dyn FnMut(&mut dyn Write) -> Result<(), WorldError>,
) -> Result<(), WorldError> {
    let name = path.file_name().ok_or_else(|| {
        WorldError::io(
            format!("cannot save {}", path.display()),
            std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file name"),
        )
    })?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let tmp = temp_path(&dir, name);
    let file = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)
        .map_err(|e| WorldError::io(format!("cannot create {}", tmp.display()), e))?;
    let result = (|| {
        let mut w = BufWriter::with_capacity(1 << 20, file);
        write(&mut w).map_err(|e| recontext(e, &tmp))?;
        let file = w
            .into_inner()
            .map_err(|e| WorldError::io(format!("cannot write {}", tmp.display()), e.into_error()))?;
        file.sync_all()
            .map_err(|e| WorldError::io(format!("cannot fsync {}", tmp.display()), e))?;
        drop(file);
        std::fs::rename(&tmp, path)
            .map_err(|e| WorldError::io(format!("cannot rename {} to {}", tmp.display(), path.display()), e))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
        return result;
    }
    #[cfg(unix)]
    std::fs::File::open(&dir)
        .and_then(|d| d.sync_all())
        .map_err(|e| WorldError::io(format!("cannot fsync directory {}", dir.display()), e))?;
    Ok(())
}

/// Loads and validates the world file at `path` (see [`read`]). Errors name the path.
pub fn load(path: &Path) -> Result<World, WorldError> {
    let mut file =
        std::fs::File::open(path).map_err(|e| WorldError::io(format!("cannot open {}", path.display()), e))?;
    read(&mut file).map_err(|e| match e {
        WorldError::BadFile(m) => WorldError::BadFile(format!("{}: {m}", path.display())),
        e => recontext(e, path),
    })
}

/// A fresh temporary file name next to the destination.
fn temp_path(dir: &Path, name: &std::ffi::OsStr) -> PathBuf {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    let mut file = std::ffi::OsString::from(".");
    file.push(name);
    file.push(format!(
        ".tmp-{}-{}-{nanos}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    dir.join(file)
}

/// Names `path` in an I/O error's context.
fn recontext(e: WorldError, path: &Path) -> WorldError {
    match e {
        WorldError::Io { context, source } => WorldError::io(format!("{context} {}", path.display()), source),
        e => e,
    }
}

fn bad(msg: impl Into<String>) -> WorldError {
    WorldError::BadFile(msg.into())
}

/// Reports any non-I/O error of a loaded file as [`WorldError::BadFile`].
fn into_bad_file(e: WorldError) -> WorldError {
    match e {
        e @ (WorldError::BadFile(_) | WorldError::Io { .. }) => e,
        e => WorldError::BadFile(e.to_string()),
    }
}

/// The fields of a checked header.
struct Header {
    version: u32,
    payload_len: u64,
    payload_checksum: u64,
}

/// Reads and checks the fixed header: magic, version, header checksum, flags, and the
/// declared payload length against the largest possible world.
fn read_header(input: &mut dyn Read) -> Result<Header, WorldError> {
    let mut h = [0u8; HEADER_LEN];
    let mut got = 0;
    while got < HEADER_LEN {
        match input.read(&mut h[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(WorldError::io("reading world file header", e)),
        }
    }
    let seen = got.min(MAGIC.len());
    if h[..seen] != MAGIC[..seen] {
        return Err(bad("not a naadf world file (bad magic)"));
    }
    if got == 0 {
        return Err(bad("truncated: the file is empty"));
    }
    let version = u32::from_le_bytes(h[8..12].try_into().expect("4 bytes"));
    if got >= 12 && !READ_VERSIONS.contains(&version) {
        return Err(bad(format!(
            "unsupported format version {version} (this build reads 1, 2 and 3)"
        )));
    }
    if got < HEADER_LEN {
        return Err(bad(format!(
            "truncated: the file ends inside the {HEADER_LEN}-byte header, after {got} bytes"
        )));
    }
    let u64_at = |at: usize| u64::from_le_bytes(h[at..at + 8].try_into().expect("8 bytes"));
    if xxh3_64(&h[..32]) != u64_at(32) {
        return Err(bad("header checksum mismatch (the file is corrupt)"));
    }
    let flags = u32::from_le_bytes(h[12..16].try_into().expect("4 bytes"));
    if flags != 0 {
        return Err(bad(format!(
            "unsupported flags {flags:#010x} (format version {version} defines none)"
        )));
    }
    let payload_len = u64_at(16);
    let largest = max_payload(
        WorldSize::new(MAX_SIZE[0], MAX_SIZE[1], MAX_SIZE[2])
            .expect("the largest world size is valid")
            .chunk_count() as u64,
    );
    let fixed = if version == 1 { PAYLOAD_FIXED_V1 } else { PAYLOAD_FIXED };
    if payload_len < fixed || payload_len > largest {
        return Err(bad(format!(
            "declared payload length {payload_len} is outside {fixed}..={largest} bytes"
        )));
    }
    Ok(Header {
        version,
        payload_len,
        payload_checksum: u64_at(24),
    })
}

/// The compressed input as a `BufRead` for the zstd decoder: hashes exactly the bytes the
/// decoder consumes (the frame), and remembers whether the input itself failed (to tell
/// its errors apart from the decoder's).
struct FrameReader<'a> {
    inner: &'a mut dyn Read,
    buf: Box<[u8]>,
    pos: usize,
    filled: usize,
    failed: bool,
    hasher: Xxh3,
}

impl Read for FrameReader<'_> {
    fn read(&mut self, out: &mut [u8]) -> std::io::Result<usize> {
        let n = {
            let avail = self.fill_buf()?;
            let n = avail.len().min(out.len());
            out[..n].copy_from_slice(&avail[..n]);
            n
        };
        self.consume(n);
        Ok(n)
    }
}

impl BufRead for FrameReader<'_> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        if self.pos == self.filled {
            let n = loop {
                match self.inner.read(&mut self.buf) {
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(e) => {
                        self.failed = true;
                        return Err(e);
                    }
                    Ok(n) => break n,
                }
            };
            self.pos = 0;
            self.filled = n;
        }
        Ok(&self.buf[self.pos..self.filled])
    }

    fn consume(&mut self, amt: usize) {
        let end = (self.pos + amt).min(self.filled);
        self.hasher.update(&self.buf[self.pos..end]);
        self.pos = end;
    }
}

impl FrameReader<'_> {
    /// Reads and checks the trailer after the frame, then expects the end of the input.
    fn trailer(mut self) -> Result<(), WorldError> {
        let frame_hash = self.hasher.digest();
        let io = |e| WorldError::io("reading world file", e);
        let mut t = [0u8; TRAILER_LEN];
        let mut got = 0;
        while got < TRAILER_LEN {
            let avail = self.fill_buf().map_err(io)?;
            if avail.is_empty() {
                return Err(bad(format!(
                    "truncated: the file ends inside the {TRAILER_LEN}-byte trailer"
                )));
            }
            let n = avail.len().min(TRAILER_LEN - got);
            t[got..got + n].copy_from_slice(&avail[..n]);
            self.pos += n;
            got += n;
        }
        if u64::from_le_bytes(t) != frame_hash {
            return Err(bad("compressed data checksum mismatch (the file is corrupt)"));
        }
        if !self.fill_buf().map_err(io)?.is_empty() {
            return Err(bad("trailing bytes after the end of the world file"));
        }
        Ok(())
    }
}

/// Why reading the payload stopped.
enum Fail {
    /// Definitive: I/O failure, truncation, corrupt compressed data.
    Final(WorldError),
    /// The decoded bytes make no sense; the checksum decides whether they are corrupt.
    Structure(String),
}

/// The payload's sections, read but not yet interpreted.
struct RawSections {
    size: WorldSize,
    version: u64,
    materials: Vec<u32>,
    models: Vec<u8>,
    chunks: Vec<u32>,
    chunk_entities: Vec<u32>,
    blocks: Vec<u32>,
    voxels: Vec<u32>,
    /// The entity section (`None` in a version-1 file).
    entities: Option<Vec<u8>>,
}

type Decoder<'a> = zstd::stream::read::Decoder<'static, FrameReader<'a>>;

/// The decompressed payload, read at most up to its declared length and hashed on the way.
struct Payload<'a> {
    /// The file's format version.
    format: u32,
    dec: Decoder<'a>,
    hasher: Xxh3,
    done: u64,
    len: u64,
}

/// Bytes read per step when filling a large buffer: buffers grow only as data arrives.
const STEP: usize = 16 << 20;

impl Payload<'_> {
    /// Classifies a decoder error.
    fn stream_error(&self, e: std::io::Error) -> Fail {
        if self.dec.get_ref().failed {
            Fail::Final(WorldError::io("reading world file", e))
        } else if e.kind() == std::io::ErrorKind::UnexpectedEof {
            Fail::Final(bad(format!(
                "truncated: the compressed payload ends after {} of {} bytes",
                self.done, self.len
            )))
        } else {
            Fail::Final(bad(format!("corrupt compressed payload (zstd: {e})")))
        }
    }

    /// Fills `buf` from the payload. Asking for more than is left of the declared length
    /// is a structure error.
    fn fill(&mut self, buf: &mut [u8], what: &str) -> Result<(), Fail> {
        if buf.len() as u64 > self.len - self.done {
            return Err(Fail::Structure(format!(
                "{what} runs past the declared payload length of {} bytes",
                self.len
            )));
        }
        let mut at = 0;
        while at < buf.len() {
            match self.dec.read(&mut buf[at..]) {
                Ok(0) => {
                    return Err(Fail::Final(bad(format!(
                        "truncated: the payload ends after {} of its declared {} bytes",
                        self.done, self.len
                    ))));
                }
                Ok(n) => {
                    self.hasher.update(&buf[at..at + n]);
                    at += n;
                    self.done += n as u64;
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(self.stream_error(e)),
            }
        }
        Ok(())
    }

    fn u32(&mut self, what: &str) -> Result<u32, Fail> {
        let mut b = [0u8; 4];
        self.fill(&mut b, what)?;
        Ok(u32::from_le_bytes(b))
    }

    fn u64(&mut self, what: &str) -> Result<u64, Fail> {
        let mut b = [0u8; 8];
        self.fill(&mut b, what)?;
        Ok(u64::from_le_bytes(b))
    }

    /// A section's length prefix, checked against `limit` (and `exact`, if given), a
    /// multiple of `unit`, and the rest of the declared payload.
    fn section_len(&mut self, name: &str, limit: u64, unit: u64, exact: bool) -> Result<usize, Fail> {
        let n = self.u64(&format!("{name} section length"))?;
        let wrong = if exact { n != limit } else { n > limit };
        if wrong || n % unit != 0 {
            let want = if exact {
                format!("exactly {limit}")
            } else {
                format!("a multiple of {unit} up to {limit}")
            };
            return Err(Fail::Structure(format!(
                "{name} section of {n} bytes, expected {want} for this world"
            )));
        }
        if n > self.len - self.done {
            return Err(Fail::Structure(format!(
                "{name} section of {n} bytes runs past the declared payload length of {} bytes",
                self.len
            )));
        }
        Ok(n as usize)
    }

    /// A section of `u32` words, grown as data arrives.
    fn words(&mut self, name: &str, limit: u64, unit: u64, exact: bool) -> Result<Vec<u32>, Fail> {
        let n = self.section_len(name, limit, unit, exact)? / 4;
        let mut v: Vec<u32> = Vec::new();
        while v.len() < n {
            let start = v.len();
            let end = n.min(start + STEP / 4);
            v.resize(end, 0);
            self.fill(bytemuck::cast_slice_mut(&mut v[start..end]), name)?;
        }
        for w in &mut v {
            *w = u32::from_le(*w);
        }
        Ok(v)
    }

    /// A section of bytes, grown as data arrives.
    fn bytes(&mut self, name: &str, limit: u64) -> Result<Vec<u8>, Fail> {
        let n = self.section_len(name, limit, 1, false)?;
        let mut v = Vec::new();
        while v.len() < n {
            let start = v.len();
            let end = n.min(start + STEP);
            v.resize(end, 0);
            self.fill(&mut v[start..end], name)?;
        }
        Ok(v)
    }

    /// Reads every section, checking lengths against the world size.
    fn sections(&mut self) -> Result<RawSections, Fail> {
        let dims = [
            self.u32("world size")?,
            self.u32("world size")?,
            self.u32("world size")?,
        ];
        let size =
            WorldSize::new(dims[0], dims[1], dims[2]).map_err(|e| Fail::Structure(format!("world size: {e}")))?;
        let chunk_count = size.chunk_count() as u64;
        let largest = max_payload(chunk_count);
        if self.len > largest {
            return Err(Fail::Structure(format!(
                "declared payload length {} exceeds the {largest} bytes a {size} world can need",
                self.len
            )));
        }
        let version = self.u64("edit version")?;
        let [lm, lmod, lc, le, lb, lv, lent] = section_limits(chunk_count);
        let materials = self.words("materials", lm, 16, false)?;
        let models = self.bytes("models", lmod)?;
        let chunks = self.words("chunks", lc, 4, true)?;
        let chunk_entities = self.words("chunk_entities", le, 4, true)?;
        let blocks = self.words("blocks", lb, 4 * 64, false)?;
        let voxels = self.words("voxels", lv, 4 * 32, false)?;
        let entities = if self.format >= 2 {
            Some(self.bytes("entities", lent)?)
        } else {
            None
        };
        if self.done != self.len {
            return Err(Fail::Structure(format!(
                "{} unused bytes after the last section (declared payload length {})",
                self.len - self.done,
                self.len
            )));
        }
        Ok(RawSections {
            size,
            version,
            materials,
            models,
            chunks,
            chunk_entities,
            blocks,
            voxels,
            entities,
        })
    }

    /// Reads (and hashes) what is left of the declared payload, discarding it.
    fn drain(&mut self) -> Result<(), Fail> {
        let mut buf = vec![0u8; 1 << 16];
        while self.done < self.len {
            let n = (self.len - self.done).min(buf.len() as u64) as usize;
            self.fill(&mut buf[..n], "payload")?;
        }
        Ok(())
    }

    /// Checks that the zstd frame ends exactly at the declared payload length.
    fn expect_frame_end(&mut self) -> Result<(), WorldError> {
        let mut b = [0u8; 1];
        loop {
            return match self.dec.read(&mut b) {
                Ok(0) => Ok(()),
                Ok(_) => Err(bad(format!(
                    "the compressed payload is longer than its declared {} bytes",
                    self.len
                ))),
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => match self.stream_error(e) {
                    Fail::Final(e) => Err(e),
                    Fail::Structure(m) => Err(bad(m)),
                },
            };
        }
    }
}

//! The fuzz targets' harness: one function per target, each taking the fuzzer's raw bytes.
//!
//! Every function returns normally for any input; a panic (including an overflow or a
//! failed property check below) is the bug class these targets look for, because none of
//! these parsers may panic across its API boundary. The binaries in `src/bin/` wrap each
//! function in `afl::fuzz!`, which turns a panic into an abort that AFL++ records as a
//! crash; `reproduce` runs saved inputs through the same functions without AFL.
//!
//! Some formats are guarded by checksums a fuzzer cannot forge. Their targets read the
//! first byte as a mode: one mode feeds the bytes as they are (the real entry point), the
//! other builds a well-framed container around the fuzzed payload so the parsing behind
//! the checksum is reached too.

use naadf_proto::v1::{
    DespawnEntitiesRequest, EditRequest, FrameRequest, JoinRequest, MoveEntitiesRequest, SpawnEntitiesRequest,
    WorldMessage, world_message,
};
use naadf_world::ops::{Batch, DenseCanvas, Limits, apply_batch};
use naadf_world::{MaterialTable, World, WorldSize, file, model::ModelTable};
use prost::Message;
use std::io::Write;
use std::path::PathBuf;

/// A target: takes one input, panics on a bug.
pub type Target = fn(&[u8]);

/// The targets by name, as `reproduce` knows them.
pub const TARGETS: [(&str, Target); 6] = [
    ("vox", vox),
    ("world_file", world_file),
    ("wal", wal),
    ("ops", ops),
    ("replay", replay),
    ("proto", proto),
];

/// The target called `name`.
pub fn target(name: &str) -> Option<Target> {
    TARGETS.iter().find(|(n, _)| *n == name).map(|&(_, f)| f)
}

/// Splits off the mode byte: `(mode, rest)`, or `None` for an empty input.
fn mode(data: &[u8]) -> Option<(u8, &[u8])> {
    data.split_first().map(|(&m, rest)| (m, rest))
}

/// Cuts `data` into length-prefixed pieces (u32 LE lengths, clipped to what is left);
/// whatever cannot hold a prefix becomes one last piece. [`piece`] writes one.
pub fn pieces(mut data: &[u8]) -> Vec<&[u8]> {
    let mut out = Vec::new();
    while data.len() >= 4 {
        let n = (u32::from_le_bytes([data[0], data[1], data[2], data[3]]) as usize).min(data.len() - 4);
        out.push(&data[4..4 + n]);
        data = &data[4 + n..];
    }
    if !data.is_empty() {
        out.push(data);
    }
    out
}

/// Appends `bytes` to `out` as one of [`pieces`].
pub fn piece(out: &mut Vec<u8>, bytes: &[u8]) {
    out.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
    out.extend_from_slice(bytes);
}

/// A small world size chosen by three bytes: 64 or 128 voxels per axis, so that building
/// and validating stay fast.
fn small_size(b: &[u8]) -> WorldSize {
    let edge = |i: usize| if b.get(i).is_some_and(|v| v & 1 == 1) { 128 } else { 64 };
    WorldSize::new(edge(0), edge(1), edge(2)).expect("64 and 128 are valid edges")
}

/// `.vox` import: parse the scene, query it, and for scenes that fit a small world build
/// that world (the painting path of the importer).
pub fn vox(data: &[u8]) {
    use naadf_world::import::vox::{TiledVox, VoxScene};
    let Ok(scene) = VoxScene::from_bytes(data) else { return };
    let e = scene.extent();
    let _ = scene.materials();
    let _ = scene.instance_count();
    for p in [
        [0, 0, 0],
        [e[0] / 2, e[1] / 2, e[2] / 2],
        e.map(|v| v.saturating_sub(1)),
        e,
    ] {
        let _ = scene.material_at(p);
    }
    let Ok(size) = scene.world_size() else { return };
    if size.voxel_count() <= 128 * 128 * 128 {
        let world = World::build(&TiledVox::new(scene, size), &|_| {});
        world.expect("an imported scene that fits a world builds");
    }
}

/// The world file. Mode byte even: the bytes are a file, read with full validation, and a
/// world that reads must write and read back to the same digest. Odd: the checksummed
/// container is skipped and the bytes are the transferred buffers plus an entity table
/// ([`file::parts_from_buffers`], [`World::from_parts`]), the validation behind it.
pub fn world_file(data: &[u8]) {
    let Some((m, rest)) = mode(data) else { return };
    let world = if m & 1 == 0 {
        let Ok(w) = file::read(&mut &rest[..]) else { return };
        w
    } else {
        let (sz, rest) = rest.split_at(rest.len().min(3));
        let p = pieces(rest);
        let get = |i: usize| p.get(i).copied().unwrap_or(&[]);
        let buffers = [get(0), get(1), get(2), get(3), get(4), get(5)];
        let Ok(parts) = file::parts_from_buffers(small_size(sz), 1, buffers, get(6)) else {
            return;
        };
        let Ok(w) = World::from_parts(parts) else { return };
        w
    };
    let mut out = Vec::new();
    file::write(&world, &mut out).expect("a valid world writes");
    let back = file::read(&mut &out[..]).expect("a written world reads back");
    assert_eq!(
        back.digest(),
        world.digest(),
        "the world file round trip changed the world"
    );
}

/// A per-process scratch file (the WAL reader takes a path), in memory where Linux offers
/// a tmpfs.
fn scratch_file(name: &str) -> PathBuf {
    let shm = std::path::Path::new("/dev/shm");
    let dir = if shm.is_dir() {
        shm.to_owned()
    } else {
        std::env::temp_dir()
    };
    dir.join(format!("naadf-fuzz-{}-{name}", std::process::id()))
}

/// The WAL segment magic (see `server/src/data/wal.rs`).
pub const WAL_MAGIC: &[u8; 8] = b"NAADFWAL";
/// The WAL segment format.
pub const WAL_FORMAT: u32 = 1;

/// The WAL reader. Mode byte bit 0: whether the segment is the last one (only the last may
/// end in a torn write); bit 1 set: the rest is a whole segment file; clear: the rest is
/// record payloads (length-prefixed pieces) the harness frames with valid checksums after a
/// valid header, the last piece left unframed as a possible torn tail. The second byte is
/// the base version. Recovered entries then go through `check_sequence` and their ops
/// through [`Batch::parse_line`], as recovery does.
pub fn wal(data: &[u8]) {
    use naadf_server::data::wal;
    let Some((m, rest)) = mode(data) else { return };
    let Some((&base, rest)) = rest.split_first() else {
        return;
    };
    let base = u64::from(base);
    let last = m & 1 == 1;
    let bytes = if m & 2 == 2 {
        rest.to_vec()
    } else {
        let mut out = Vec::with_capacity(rest.len() + 64);
        out.extend_from_slice(WAL_MAGIC);
        out.extend_from_slice(&WAL_FORMAT.to_le_bytes());
        out.extend_from_slice(&base.to_le_bytes());
        let p = pieces(rest);
        for (i, payload) in p.iter().enumerate() {
            if i + 1 == p.len() && p.len() > 1 {
                out.extend_from_slice(payload);
                break;
            }
            out.extend_from_slice(&(payload.len() as u32).to_le_bytes());
            out.extend_from_slice(&naadf_world::hash::xxh3_64(payload).to_le_bytes());
            out.extend_from_slice(payload);
        }
        out
    };
    let path = scratch_file("wal.log");
    std::fs::File::create(&path)
        .and_then(|mut f| f.write_all(&bytes))
        .expect("the scratch file is writable");
    let Ok(segment) = wal::read_segment(&path, base, last) else {
        return;
    };
    assert!(
        segment.torn.is_none_or(|t| t <= segment.len),
        "torn offset past the end"
    );
    let _ = wal::check_sequence([&segment], base);
    for e in &segment.entries {
        let _ = Batch::parse_line(&e.ops);
    }
}

/// Ops JSON lines: parse as the server parses an `EditRequest`; applying the batch to a
/// small world must fail cleanly or succeed, and a batch the world accepts must survive its
/// canonical form (the WAL stores `to_json_line` and recovery re-parses it).
pub fn ops(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let Ok(batch) = Batch::parse_line(&text) else { return };
    check_batch(&batch);
}

/// The checks every parsed batch gets: names, a bounded apply, and for an applied batch
/// the round trip through its canonical line (only applied batches reach the log).
fn check_batch(batch: &Batch) {
    let _ = batch.check_names();
    // Small limits keep one execution fast; the limits are themselves under test.
    let limits = Limits {
        max_ops: 256,
        max_set_voxels: 1 << 12,
        max_fill_volume: 1 << 16,
        max_flood_limit: 1 << 14,
        max_model_voxels: 1 << 12,
    };
    let mut canvas = DenseCanvas::new(WorldSize::new(64, 64, 64).expect("valid size"));
    let mut materials = MaterialTable::default();
    let mut models = ModelTable::default();
    if apply_batch(batch, &mut canvas, &mut materials, &mut models, &limits).is_ok() {
        let line = batch.to_json_line();
        let again = Batch::parse_line(&line).expect("an applied batch's canonical line parses");
        assert_eq!(&again, batch, "the canonical line changed the batch: {line}");
    }
}

/// Replay inputs. Mode byte even: a replay script ([`script::parse_script`]). Odd: a
/// HashDAG CSV, converted to script lines, each of which must parse as a script line.
///
/// [`script::parse_script`]: naadf_world::replay::script::parse_script
pub fn replay(data: &[u8]) {
    use naadf_world::replay::{hashdag, script};
    let Some((m, rest)) = mode(data) else { return };
    let text = String::from_utf8_lossy(rest);
    if m & 1 == 0 {
        let _ = script::parse_script(&text);
    } else {
        let Ok(lines) = hashdag::to_script_lines(&text, &hashdag::HashdagMapping::default()) else {
            return;
        };
        for (row, line) in lines {
            if let Err(e) = script::parse_line(&line) {
                panic!("row {row}: converted line {line} does not parse: {e}");
            }
        }
    }
}

/// The protobuf messages the server accepts, decoded and put through the checks and
/// conversions the service applies before anything reaches the world actor; the mode byte
/// picks the message. Also the snapshot a client assembles from `WorldMessage`s.
pub fn proto(data: &[u8]) {
    use naadf_proto::requests::{despawn_batch, move_batch, spawn_batch};
    let Some((m, rest)) = mode(data) else { return };
    match m % 7 {
        0 => {
            if let Ok(r) = EditRequest::decode(rest)
                && let Ok(b) = Batch::parse_line(&r.ops)
            {
                check_batch(&b);
            }
        }
        1 => {
            if let Ok(r) = SpawnEntitiesRequest::decode(rest)
                && let Ok(b) = spawn_batch(&r)
            {
                check_batch(&b);
            }
        }
        2 => {
            if let Ok(r) = MoveEntitiesRequest::decode(rest)
                && let Ok(b) = move_batch(&r)
            {
                check_batch(&b);
            }
        }
        3 => {
            if let Ok(r) = DespawnEntitiesRequest::decode(rest) {
                check_batch(&despawn_batch(&r));
            }
        }
        4 => {
            if let Ok(r) = JoinRequest::decode(rest) {
                let _ = naadf_server::stream::join::client_pages(&r.cached);
            }
        }
        5 => {
            if let Ok(r) = FrameRequest::decode(rest) {
                let _ = naadf_server::net::service::check_frame(&r);
            }
        }
        _ => snapshot(rest),
    }
}

/// The world budget of the fuzzed client: far below the fuzzer's memory cap.
const FUZZ_WORLD_BYTES: u64 = 256 << 20;

/// A client's snapshot assembly: length-delimited `WorldMessage`s, a header first, then
/// pages, over an empty cache.
fn snapshot(mut data: &[u8]) {
    use naadf_proto::snapshot::Assembly;
    let mut assembly: Option<Assembly> = None;
    while let Ok(msg) = WorldMessage::decode_length_delimited(&mut data) {
        match (msg.kind, assembly.as_mut()) {
            (Some(world_message::Kind::Header(h)), None) => {
                // A client with a small budget: the fuzzer's memory cap catches any
                // allocation out of proportion to it.
                let Ok(a) = Assembly::start(h, Default::default(), FUZZ_WORLD_BYTES) else {
                    return;
                };
                assembly = Some(a);
            }
            (Some(world_message::Kind::Page(p)), Some(a)) => {
                if a.page(&p).is_err() {
                    return;
                }
            }
            _ => return,
        }
        if data.is_empty() {
            break;
        }
    }
    if let Some(a) = assembly
        && a.is_complete()
    {
        let _ = a.finish();
    }
}

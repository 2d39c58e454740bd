//! The `.naadf` world file: round trips, atomic save/load, the documented byte layout, and
//! rejection of every kind of damaged or hostile input (errors, never panics).

use naadf_world::cell::CHUNK_VOXELS;
use naadf_world::file::{self, FORMAT_VERSION, HEADER_LEN, MAGIC, TRAILER_LEN, WorldParts};
use naadf_world::hash::xxh3_64;
use naadf_world::material::MaterialKind;
use naadf_world::model::{Model, ModelTable};
use naadf_world::ops::{Batch, Limits, Op};
use naadf_world::{ChunkSource, Material, MaterialTable, World, WorldError, WorldSize};
use proptest::prelude::*;
use std::path::PathBuf;

// ---------------------------------------------------------------------------------------
// Test worlds
// ---------------------------------------------------------------------------------------

/// SplitMix64: a tiny deterministic generator.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: u32) -> u32 {
        (self.next() % u64::from(n)) as u32
    }
}

enum Shape {
    Sphere { c: [f32; 3], r: f32, m: u16 },
    Box { lo: [u32; 3], hi: [u32; 3], m: u16 },
    Voxel { p: [u32; 3], m: u16 },
}

/// A random-ish world: spheres, boxes (some erasing) and single voxels; later shapes win.
struct Shapes {
    size: WorldSize,
    materials: u16,
    shapes: Vec<Shape>,
    models: ModelTable,
}

impl Shapes {
    fn new(size: WorldSize, seed: u64, count: usize) -> Self {
        let mut rng = Rng(seed);
        let materials = 1 + rng.below(6) as u16;
        let s = size.voxels();
        let mat = |rng: &mut Rng, erase: bool| {
            if erase && rng.below(4) == 0 {
                0
            } else {
                1 + rng.below(u32::from(materials)) as u16
            }
        };
        let mut shapes = Vec::new();
        for _ in 0..count {
            let p = [rng.below(s[0]), rng.below(s[1]), rng.below(s[2])];
            shapes.push(match rng.below(3) {
                0 => Shape::Sphere {
                    c: p.map(|v| v as f32 + 0.3),
                    r: 1.0 + rng.below(20) as f32 * 0.7,
                    m: mat(&mut rng, true),
                },
                1 => {
                    let e = [1 + rng.below(40), 1 + rng.below(40), 1 + rng.below(40)];
                    Shape::Box {
                        lo: p,
                        hi: std::array::from_fn(|a| (p[a] + e[a]).min(s[a])),
                        m: mat(&mut rng, true),
                    }
                }
                _ => Shape::Voxel {
                    p,
                    m: mat(&mut rng, false),
                },
            });
        }
        let mut models = ModelTable::default();
        for k in 0..rng.below(3) {
            let ms = [1 + rng.below(5), 1 + rng.below(5), 1 + rng.below(5)];
            let n = (ms[0] * ms[1] * ms[2]) as usize;
            let voxels = (0..n).map(|_| rng.below(u32::from(materials) + 1) as u16);
            models.insert(format!("model-{k}"), Model::new(ms, voxels.collect()).unwrap());
        }
        Shapes {
            size,
            materials,
            shapes,
            models,
        }
    }

    fn at(&self, p: [u32; 3]) -> u16 {
        let mut m = 0;
        for s in &self.shapes {
            match *s {
                Shape::Sphere { c, r, m: sm } => {
                    let d: f32 = (0..3).map(|a| (p[a] as f32 + 0.5 - c[a]).powi(2)).sum();
                    if d < r * r {
                        m = sm;
                    }
                }
                Shape::Box { lo, hi, m: sm } => {
                    if (0..3).all(|a| lo[a] <= p[a] && p[a] < hi[a]) {
                        m = sm;
                    }
                }
                Shape::Voxel { p: q, m: sm } => {
                    if p == q {
                        m = sm;
                    }
                }
            }
        }
        m
    }
}

impl ChunkSource for Shapes {
    fn size(&self) -> WorldSize {
        self.size
    }
    fn materials(&self) -> MaterialTable {
        let ms: Vec<Material> = (0..self.materials)
            .map(|i| match i % 4 {
                0 => Material::diffuse([0.1 * f32::from(i % 10), 0.5, 0.25]),
                1 => Material {
                    kind: MaterialKind::Emissive,
                    albedo: [1.0, 0.9, 0.8],
                    emission: 12.5,
                    roughness: 0.0,
                },
                2 => Material {
                    kind: MaterialKind::Metal,
                    albedo: [0.9, 0.6, 0.2],
                    emission: 0.0,
                    roughness: 0.3,
                },
                _ => Material {
                    kind: MaterialKind::Mirror,
                    albedo: [1.0; 3],
                    emission: 0.0,
                    roughness: 0.0,
                },
            })
            .collect();
        MaterialTable::from_materials(&ms).unwrap()
    }
    fn models(&self) -> ModelTable {
        self.models.clone()
    }
    fn fill_chunk(&self, c: [u32; 3], out: &mut [u16; CHUNK_VOXELS]) {
        for z in 0..16 {
            for y in 0..16 {
                for x in 0..16 {
                    out[(x + 16 * y + 256 * z) as usize] = self.at([c[0] * 16 + x, c[1] * 16 + y, c[2] * 16 + z]);
                }
            }
        }
    }
}

fn world(size: [u32; 3], seed: u64, shapes: usize) -> World {
    let size = WorldSize::new(size[0], size[1], size[2]).unwrap();
    World::build(&Shapes::new(size, seed, shapes), &|_| {}).unwrap()
}

/// A small world with several mixed chunks, shared groups and models.
fn small_world() -> World {
    world([64, 64, 64], 7, 12)
}

fn to_bytes(w: &World) -> Vec<u8> {
    let mut out = Vec::new();
    file::write(w, &mut out).unwrap();
    out
}

fn from_bytes(bytes: &[u8]) -> Result<World, WorldError> {
    file::read(&mut &bytes[..])
}

/// The message of a `BadFile` error (anything else fails the test).
fn bad_file(r: Result<World, WorldError>) -> String {
    match r {
        Err(WorldError::BadFile(m)) => m,
        Err(e) => panic!("expected a BadFile error, got {e:?}"),
        Ok(_) => panic!("expected a BadFile error, got a world"),
    }
}

fn assert_same(a: &World, b: &World) {
    assert_eq!(a.to_parts(), b.to_parts());
    assert_eq!(a.digest(), b.digest());
    assert_eq!(
        a.free_block_arrays().collect::<Vec<_>>(),
        b.free_block_arrays().collect::<Vec<_>>()
    );
    assert_eq!(
        a.groups().free_slots().collect::<Vec<_>>(),
        b.groups().free_slots().collect::<Vec<_>>()
    );
}

// ---------------------------------------------------------------------------------------
// An independent encoder/decoder written from docs/FORMAT.md
// ---------------------------------------------------------------------------------------

/// The entity-table section of `p`, as FORMAT.md specifies it.
fn entity_section(p: &WorldParts) -> Vec<u8> {
    let mut out = Vec::new();
    let name = |out: &mut Vec<u8>, n: &str| {
        out.extend_from_slice(&(n.len() as u32).to_le_bytes());
        out.extend_from_slice(n.as_bytes());
    };
    out.extend_from_slice(&(p.entities.types.len() as u32).to_le_bytes());
    for t in &p.entities.types {
        name(&mut out, t);
    }
    out.extend_from_slice(&(p.entities.instances.len() as u32).to_le_bytes());
    for (id, e) in &p.entities.instances {
        out.extend_from_slice(&id.to_le_bytes());
        name(&mut out, &e.model);
        for v in e.pos.iter().chain(&e.rot) {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// The payload bytes of `p`, as FORMAT.md specifies them (versions 2 and 3 have the same
/// sections; version 1 has no entity section).
fn payload_of(p: &WorldParts) -> Vec<u8> {
    payload_of_version(p, 3)
}

fn payload_of_version(p: &WorldParts, version: u32) -> Vec<u8> {
    let mut out = Vec::new();
    for n in p.size.voxels() {
        out.extend_from_slice(&n.to_le_bytes());
    }
    out.extend_from_slice(&p.version.to_le_bytes());
    let words = |v: &[u32]| v.iter().flat_map(|w| w.to_le_bytes()).collect::<Vec<u8>>();
    let mut sections = vec![
        words(p.materials.words()),
        p.models.encode(),
        words(&p.chunks),
        words(&p.chunk_entities),
        words(&p.blocks),
        words(&p.voxels),
    ];
    if version >= 2 {
        sections.push(entity_section(p));
    }
    for s in sections {
        out.extend_from_slice(&(s.len() as u64).to_le_bytes());
        out.extend_from_slice(&s);
    }
    out
}

/// A header as FORMAT.md specifies it.
fn header(version: u32, flags: u32, len: u64, checksum: u64) -> Vec<u8> {
    let mut h = MAGIC.to_vec();
    h.extend_from_slice(&version.to_le_bytes());
    h.extend_from_slice(&flags.to_le_bytes());
    h.extend_from_slice(&len.to_le_bytes());
    h.extend_from_slice(&checksum.to_le_bytes());
    let own = xxh3_64(&h);
    h.extend_from_slice(&own.to_le_bytes());
    h
}

/// A complete file around an arbitrary payload, with correct checksums.
fn file_around(payload: &[u8]) -> Vec<u8> {
    file_around_frame(payload, &zstd::stream::encode_all(payload, 3).unwrap())
}

/// A file with a valid header for `payload` around an arbitrary frame, with its trailer.
fn file_around_frame(payload: &[u8], frame: &[u8]) -> Vec<u8> {
    let mut f = header(FORMAT_VERSION, 0, payload.len() as u64, xxh3_64(payload));
    f.extend_from_slice(frame);
    f.extend_from_slice(&xxh3_64(frame).to_le_bytes());
    f
}

#[test]
fn the_file_matches_the_documented_layout() {
    let w = small_world();
    let bytes = to_bytes(&w);
    assert_eq!(&bytes[..8], b"\x89NAADF\r\n");
    assert_eq!((HEADER_LEN, TRAILER_LEN), (40, 8));
    let u32_at = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
    let u64_at = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap());
    assert_eq!(u32_at(8), 3);
    assert_eq!(u32_at(12), 0);
    assert_eq!(u64_at(32), xxh3_64(&bytes[..32]));
    let frame = &bytes[40..bytes.len() - 8];
    assert_eq!(u64_at(bytes.len() - 8), xxh3_64(frame));
    let payload = zstd::stream::decode_all(frame).unwrap();
    assert_eq!(payload.len() as u64, u64_at(16));
    assert_eq!(xxh3_64(&payload), u64_at(24));
    assert_eq!(payload, payload_of(&w.to_parts()));
    // The frame records its content size, and the independent encoder's file reads back.
    assert_eq!(
        zstd::zstd_safe::get_frame_content_size(frame).unwrap(),
        Some(payload.len() as u64)
    );
    assert_same(&from_bytes(&file_around(&payload)).unwrap(), &w);
}

// ---------------------------------------------------------------------------------------
// Round trips
// ---------------------------------------------------------------------------------------

#[test]
fn round_trip_preserves_parts_and_digest() {
    for (size, seed, shapes) in [
        ([64, 64, 64], 1, 0),
        ([64, 64, 64], 2, 30),
        ([128, 64, 64], 3, 40),
        ([64, 128, 192], 4, 60),
    ] {
        let w = world(size, seed, shapes);
        let back = from_bytes(&to_bytes(&w)).unwrap();
        assert_same(&w, &back);
        assert_eq!(back.version(), w.version());
        assert_eq!(back.models(), w.models());
        assert_eq!(back.materials(), w.materials());
        // Writing is deterministic.
        assert_eq!(to_bytes(&back), to_bytes(&w));
    }
}

#[test]
fn round_trip_keeps_free_slots_and_version() {
    let mut p = small_world().to_parts();
    // A zeroed free block array and a zeroed free voxel group, as edits leave behind.
    p.blocks.extend([0; 64]);
    p.voxels.extend([0; 32]);
    p.version = 42;
    let w = World::from_parts(p.clone()).unwrap();
    let mut bytes = Vec::new();
    file::write_parts(&p, &mut bytes).unwrap();
    assert_eq!(bytes, to_bytes(&w));
    let back = from_bytes(&bytes).unwrap();
    assert_same(&w, &back);
    assert_eq!(back.version(), 42);
    assert_eq!(back.free_block_arrays().count(), 1);
    assert_eq!(file::read_parts(&mut &bytes[..]).unwrap(), p);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    #[test]
    fn random_worlds_round_trip(seed in any::<u64>(), shapes in 0usize..50) {
        let w = world([64, 64, 128], seed, shapes);
        let back = from_bytes(&to_bytes(&w)).unwrap();
        prop_assert_eq!(w.to_parts(), back.to_parts());
        prop_assert_eq!(w.digest(), back.digest());
    }
}

// ---------------------------------------------------------------------------------------
// Save and load
// ---------------------------------------------------------------------------------------

/// A fresh directory under the system temp dir, removed on drop.
struct TempDir(PathBuf);

impl TempDir {
    fn new(tag: &str) -> Self {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_nanos();
        let p = std::env::temp_dir().join(format!("naadf-world-file-{tag}-{}-{nanos}", std::process::id()));
        std::fs::create_dir_all(&p).unwrap();
        TempDir(p)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

#[test]
fn save_and_load() {
    let dir = TempDir::new("save");
    let path = dir.0.join("world.naadf");
    let a = small_world();
    file::save(&a, &path).unwrap();
    assert_same(&file::load(&path).unwrap(), &a);
    assert_eq!(std::fs::read(&path).unwrap(), to_bytes(&a));

    // Saving again replaces the file atomically and leaves no temporary files behind.
    let b = world([128, 64, 64], 99, 20);
    file::save(&b, &path).unwrap();
    assert_same(&file::load(&path).unwrap(), &b);
    let names: Vec<_> = std::fs::read_dir(&dir.0)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("world.naadf")]);

    // Errors name the path.
    let missing = dir.0.join("missing.naadf");
    match file::load(&missing) {
        Err(e @ WorldError::Io { .. }) => assert!(e.to_string().contains("missing.naadf"), "{e}"),
        other => panic!("expected an I/O error, got {:?}", other.map(|_| ())),
    }
    let garbage = dir.0.join("garbage.naadf");
    std::fs::write(&garbage, b"hello, world").unwrap();
    let msg = bad_file(file::load(&garbage));
    assert!(msg.contains("garbage.naadf") && msg.contains("bad magic"), "{msg}");
    match file::save(&a, &dir.0.join("no-such-dir").join("w.naadf")) {
        Err(e @ WorldError::Io { .. }) => assert!(e.to_string().contains("no-such-dir"), "{e}"),
        other => panic!("expected an I/O error, got {other:?}"),
    }
    // A failed save leaves the existing file untouched.
    assert_same(&file::load(&path).unwrap(), &b);
}

// ---------------------------------------------------------------------------------------
// Rejection
// ---------------------------------------------------------------------------------------

#[test]
fn rejects_bad_magic() {
    let good = to_bytes(&small_world());
    for i in 0..8 {
        let mut f = good.clone();
        f[i] ^= 0x20;
        assert!(bad_file(from_bytes(&f)).contains("bad magic"));
    }
    // Text-mode mangling: CR LF → LF, LF → CR LF.
    let mut lf = good.clone();
    lf.remove(6);
    assert!(bad_file(from_bytes(&lf)).contains("bad magic"));
    let mut crlf = good.clone();
    crlf.insert(7, b'\r');
    assert!(bad_file(from_bytes(&crlf)).contains("bad magic"));
    for text in [&b"hello"[..], b"{\"size\":[64,64,64]}", b"\x28\xb5\x2f\xfd"] {
        assert!(bad_file(from_bytes(text)).contains("bad magic"));
    }
}

#[test]
fn rejects_other_versions() {
    let good = to_bytes(&small_world());
    for v in [0u32, 4, 7, u32::MAX] {
        let mut f = good.clone();
        f[8..12].copy_from_slice(&v.to_le_bytes());
        let msg = bad_file(from_bytes(&f));
        assert_eq!(
            msg,
            format!("unsupported format version {v} (this build reads 1, 2 and 3)")
        );
        // Also with a header checksum that matches the new version.
        let own = xxh3_64(&f[..32]);
        f[32..40].copy_from_slice(&own.to_le_bytes());
        assert!(bad_file(from_bytes(&f)).starts_with("unsupported format version"));
    }
}

#[test]
fn reads_version_1_files() {
    // Version 1: the same payload without the entity section.
    let w = small_world();
    let payload = payload_of_version(&w.to_parts(), 1);
    let frame = zstd::stream::encode_all(&payload[..], 3).unwrap();
    let mut f = header(1, 0, payload.len() as u64, xxh3_64(&payload));
    f.extend_from_slice(&frame);
    f.extend_from_slice(&xxh3_64(&frame).to_le_bytes());
    let back = from_bytes(&f).unwrap();
    assert_same(&back, &w);
    assert_eq!(back.digest(), w.digest());
    // Written back, it is a version-3 file.
    assert_eq!(to_bytes(&back), to_bytes(&w));
    // A version-1 payload in a version-3 file is short by the entity section.
    let msg = bad_file(from_bytes(&file_around(&payload)));
    assert!(
        msg.contains("entities section") || msg.contains("declared payload"),
        "{msg}"
    );
}

/// A file in `version`'s header around `payload`.
fn file_of_version(version: u32, payload: &[u8]) -> Vec<u8> {
    let frame = zstd::stream::encode_all(payload, 3).unwrap();
    let mut f = header(version, 0, payload.len() as u64, xxh3_64(payload));
    f.extend_from_slice(&frame);
    f.extend_from_slice(&xxh3_64(&frame).to_le_bytes());
    f
}

#[test]
fn reads_version_2_files_with_their_entities_lifted_out_of_the_static_world() {
    // Version 2 listed entities per chunk and cut the chunk AADFs around them.
    let mut w = small_world();
    let batch = Batch {
        ops: vec![
            Op::DefineModel {
                name: "crate".into(),
                size: [3, 2, 3],
                voxels: vec![[0, 0, 0, 1], [2, 1, 2, 2]],
            },
            Op::SpawnEntity {
                id: 4,
                model: "crate".into(),
                pos: [20.25, 40.5, 30.0],
                rot: [0.0, 0.38268343236508984, 0.0, 0.9238795325112867],
            },
        ],
    };
    w.apply(&batch, &Limits::default()).unwrap();
    let mut old = w.to_parts();
    let c = w.size().chunk_index([1, 2, 1]);
    old.chunk_entities[c] = 1;
    if old.chunks[c] >> 30 == 0 {
        old.chunks[c] = 0;
    }
    let f = file_of_version(2, &payload_of_version(&old, 2));
    let back = from_bytes(&f).unwrap();
    // The entities carried over, the chunk entity buffer zero, the AADFs a fresh build's.
    assert_same(&back, &w);
    assert_eq!(back.entity_table(), w.entity_table());
    assert!(back.chunk_entities().iter().all(|&v| v == 0));
    // The same bytes in a version-3 file are refused: version 3 keeps the buffer zero.
    assert!(bad_file(from_bytes(&file_around(&payload_of_version(&old, 3)))).contains("entity field"));
}

#[test]
fn rejects_every_truncation() {
    let good = to_bytes(&small_world());
    assert!(good.len() < 20_000, "test file unexpectedly large: {}", good.len());
    for cut in 0..good.len() {
        let msg = bad_file(from_bytes(&good[..cut]));
        assert!(msg.starts_with("truncated"), "cut at {cut}: {msg}");
    }
    assert!(from_bytes(&good).is_ok());
}

#[test]
fn rejects_trailing_bytes() {
    let mut f = to_bytes(&small_world());
    f.push(0);
    assert!(bad_file(from_bytes(&f)).contains("trailing bytes"));
    // Two files back to back are not one file.
    let g = to_bytes(&small_world());
    let mut two = g.clone();
    two.extend_from_slice(&g);
    assert!(bad_file(from_bytes(&two)).contains("trailing bytes"));
}

/// Every kind of message a damaged file may give.
fn is_damage_message(m: &str) -> bool {
    [
        "bad magic",
        "unsupported format version",
        "checksum mismatch",
        "corrupt compressed payload",
        "truncated",
        "longer than its declared",
    ]
    .iter()
    .any(|k| m.contains(k))
}

#[test]
fn rejects_every_single_bit_flip() {
    let good = to_bytes(&small_world());
    let mut checksum = 0;
    for at in 0..good.len() {
        for bit in 0..8 {
            let mut f = good.clone();
            f[at] ^= 1 << bit;
            let msg = bad_file(from_bytes(&f));
            assert!(is_damage_message(&msg), "bit {bit} of byte {at}: {msg}");
            checksum += usize::from(msg.contains("checksum mismatch"));
        }
    }
    // Most damage is caught by a checksum rather than by luck, and every flip is caught.
    assert!(checksum * 2 > good.len() * 8, "{checksum} of {}", good.len() * 8);
}

#[test]
fn rejects_inconsistent_declared_lengths() {
    let w = small_world();
    let payload = payload_of(&w.to_parts());
    let frame = zstd::stream::encode_all(&payload[..], 3).unwrap();
    let with = |len: u64| {
        let mut f = header(FORMAT_VERSION, 0, len, xxh3_64(&payload));
        f.extend_from_slice(&frame);
        f.extend_from_slice(&xxh3_64(&frame).to_le_bytes());
        f
    };
    let n = payload.len() as u64;
    // Shorter or longer than the frame's content.
    for len in [n - 1, n + 1, n + 1000] {
        let msg = bad_file(from_bytes(&with(len)));
        assert!(
            msg.contains("declared payload length")
                || msg.contains("checksum mismatch")
                || msg.starts_with("truncated"),
            "{len}: {msg}"
        );
    }
    // Absurd lengths are refused from the header alone.
    for len in [0, 10, u64::MAX, 1 << 40] {
        let msg = bad_file(from_bytes(&with(len)));
        assert!(msg.contains("declared payload length"), "{len}: {msg}");
    }
    // Within the global bound but beyond what a 64³ world can need.
    // (The frame is much shorter, so this reads as truncated after the frame's bytes.)
    let msg = bad_file(from_bytes(&with(1 << 32)));
    assert!(msg.contains("can need") || msg.starts_with("truncated"), "{msg}");
    // Nonzero flags.
    let mut f = with(n);
    f[12] = 1;
    let own = xxh3_64(&f[..32]);
    f[32..40].copy_from_slice(&own.to_le_bytes());
    assert!(bad_file(from_bytes(&f)).contains("unsupported flags"));
}

#[test]
fn rejects_hostile_sections_with_valid_checksums() {
    let parts = small_world().to_parts();
    let good = payload_of(&parts);
    let sections_at = 20; // after size and version
    // Offsets of the seven length prefixes.
    let mut at = sections_at;
    let mut prefix = Vec::new();
    for _ in 0..7 {
        prefix.push(at);
        let len = u64::from_le_bytes(good[at..at + 8].try_into().unwrap());
        at += 8 + len as usize;
    }
    assert_eq!(at, good.len());
    let set_len = |k: usize, len: u64| {
        let mut p = good.clone();
        p[prefix[k]..prefix[k] + 8].copy_from_slice(&len.to_le_bytes());
        p
    };
    let cases: Vec<(Vec<u8>, &str)> = vec![
        // A huge section length: rejected before any allocation.
        (set_len(5, 1 << 40), "voxels section"),
        (set_len(4, u64::MAX - 7), "blocks section"),
        (set_len(2, 4), "chunks section"),
        (set_len(0, 17), "materials section"),
        (set_len(1, 1 << 31), "models section"),
        (set_len(6, 1 << 40), "entities section"),
        // A length within bounds that runs past the payload.
        (set_len(1, 200_000), "runs past"),
        // An invalid world size.
        (
            {
                let mut p = good.clone();
                p[0..4].copy_from_slice(&100u32.to_le_bytes());
                p
            },
            "world size",
        ),
        // Extra bytes after the last section.
        (
            {
                let mut p = good.clone();
                p.extend_from_slice(&[0; 5]);
                p
            },
            "unused bytes",
        ),
    ];
    for (payload, want) in cases {
        let msg = bad_file(from_bytes(&file_around(&payload)));
        assert!(msg.contains(want), "want {want:?}: {msg}");
    }
}

#[test]
fn rejects_structurally_invalid_worlds_with_valid_checksums() {
    let good = small_world().to_parts();
    let mixed = good.chunks.iter().position(|&c| c >> 30 == 2).unwrap();
    let mut cases: Vec<(WorldParts, &str)> = Vec::new();

    let mut p = good.clone();
    p.chunks[mixed] = (2 << 30) | (p.blocks.len() as u32 + 64);
    cases.push((p, "block pointer"));

    let mut p = good.clone();
    let other = good.chunks.iter().rposition(|&c| c >> 30 == 2).unwrap();
    assert_ne!(other, mixed);
    p.chunks[other] = p.chunks[mixed];
    cases.push((p, "shared block pointer"));

    let mut p = good.clone();
    let b = p.blocks.iter().position(|&c| c >> 30 == 2).unwrap();
    p.blocks[b] = (2 << 30) | (p.voxels.len() as u32);
    cases.push((p, "voxel pointer"));

    let mut p = good.clone();
    p.chunks[0] = 3 << 30;
    cases.push((p, "invalid cell"));

    let mut p = good.clone();
    p.chunk_entities[0] = 1;
    cases.push((p, "entity"));

    let mut p = good.clone();
    let v = p.voxels.iter().position(|&w| w & 0x8000 != 0).unwrap();
    p.voxels[v] = (p.voxels[v] & !0x7FFF) | 0x7FFF;
    cases.push((p, "voxel group"));

    let mut p = good.clone();
    p.blocks.extend([0; 63]);
    p.blocks.push(5);
    cases.push((p, "not zeroed"));

    for (parts, want) in cases {
        let mut bytes = Vec::new();
        file::write_parts(&parts, &mut bytes).unwrap();
        // The framing is fine: only the structural validation rejects it.
        assert_eq!(file::read_parts(&mut &bytes[..]).unwrap(), parts);
        let msg = bad_file(from_bytes(&bytes));
        assert!(msg.contains(want), "want {want:?}: {msg}");
    }

    // An invalid material entry (NaN albedo) with correct checksums.
    let mut payload = payload_of(&good);
    let nan_half = 0x7E00u32;
    let w1 = 20 + 8 + 16 + 4; // material 1, word 1
    payload[w1..w1 + 4].copy_from_slice(&nan_half.to_le_bytes());
    let msg = bad_file(from_bytes(&file_around(&payload)));
    assert!(msg.contains("material 1"), "{msg}");
}

/// A reader that hands out one byte at a time, interrupting every other call, and fails
/// with an I/O error after `fail_at` bytes.
struct Flaky<'a> {
    bytes: &'a [u8],
    at: usize,
    fail_at: usize,
    calls: usize,
}

impl std::io::Read for Flaky<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        self.calls += 1;
        if self.calls.is_multiple_of(2) {
            return Err(std::io::ErrorKind::Interrupted.into());
        }
        if self.at >= self.fail_at {
            return Err(std::io::Error::other("disk on fire"));
        }
        let n = buf.len().min(1).min(self.bytes.len() - self.at);
        buf[..n].copy_from_slice(&self.bytes[self.at..self.at + n]);
        self.at += n;
        Ok(n)
    }
}

#[test]
fn short_reads_interruptions_and_io_errors() {
    let w = small_world();
    let good = to_bytes(&w);
    let mut r = Flaky {
        bytes: &good,
        at: 0,
        fail_at: usize::MAX,
        calls: 0,
    };
    assert_same(&file::read(&mut r).unwrap(), &w);
    for fail_at in [0, 5, 39, 40, 41, 500, good.len() - 8, good.len() - 1, good.len()] {
        let mut r = Flaky {
            bytes: &good,
            at: 0,
            fail_at,
            calls: 0,
        };
        match file::read(&mut r) {
            Err(e @ WorldError::Io { .. }) => assert!(e.to_string().contains("disk on fire")),
            other => panic!("fail at {fail_at}: expected an I/O error, got {:?}", other.map(|_| ())),
        }
    }
}

#[test]
fn writer_refuses_out_of_bounds_buffers() {
    let mut p = small_world().to_parts();
    p.chunks.push(0);
    let mut out = Vec::new();
    assert!(matches!(file::write_parts(&p, &mut out), Err(WorldError::Capacity(_))));
}

fn valid_header_then(rest: &[u8], len: u64) -> Vec<u8> {
    let mut f = header(FORMAT_VERSION, 0, len, 0x1234);
    f.extend_from_slice(rest);
    f
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn garbage_never_panics(bytes in prop::collection::vec(any::<u8>(), 0..4096)) {
        prop_assert!(from_bytes(&bytes).is_err());
        let mut f = MAGIC.to_vec();
        f.extend_from_slice(&1u32.to_le_bytes());
        f.extend_from_slice(&bytes);
        prop_assert!(from_bytes(&f).is_err());
    }

    #[test]
    fn garbage_after_a_valid_header_never_panics(
        bytes in prop::collection::vec(any::<u8>(), 0..4096),
        len in 68u64..1_000_000,
    ) {
        prop_assert!(from_bytes(&valid_header_then(&bytes, len)).is_err());
        // A real zstd frame of garbage content.
        let frame = zstd::stream::encode_all(&bytes[..], 1).unwrap();
        let msg = bad_file(from_bytes(&file_around_frame(&bytes, &frame)));
        prop_assert!(!msg.is_empty());
    }

    #[test]
    fn damaged_files_never_panic(
        seed in any::<u64>(),
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..6),
    ) {
        let good = to_bytes(&world([64, 64, 64], seed, 8));
        let mut f = good.clone();
        for (i, b) in edits {
            let at = i.index(f.len());
            f[at] = b;
        }
        match from_bytes(&f) {
            Ok(w) => prop_assert_eq!(f, good, "{}", w.digest()),
            Err(WorldError::BadFile(m)) => prop_assert!(is_damage_message(&m), "{}", m),
            Err(e) => prop_assert!(false, "unexpected error {:?}", e),
        }
    }
}

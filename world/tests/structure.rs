//! Construction against the raw-volume oracle: exact round trip, canonical form, reference
//! counts, determinism across thread counts, and AADF validity by brute force.

mod common;

use common::{Raw, adversarial, random_world};
use naadf_world::aadf::chunk_is_free;
use naadf_world::cell::{self, Aadf, State};
use naadf_world::{World, WorldSize};
use std::collections::HashMap;

fn sizes() -> Vec<WorldSize> {
    vec![
        WorldSize::new(64, 64, 64).unwrap(),
        WorldSize::new(128, 64, 64).unwrap(),
        WorldSize::new(64, 128, 192).unwrap(),
    ]
}

fn assert_roundtrip(raw: &Raw, w: &World, what: &str) {
    for p in raw.coords() {
        assert_eq!(w.material_at(p), raw.get(p), "{what}: voxel {p:?}");
    }
    let mut bytes = Vec::new();
    w.export_raw(&mut bytes).unwrap();
    let exported: Vec<u16> = bytes
        .chunks_exact(2)
        .map(|b| u16::from_le_bytes([b[0], b[1]]))
        .collect();
    assert!(exported == raw.v, "{what}: export differs from the raw volume");
}

/// Canonical form, reference counts and pointer sanity.
fn assert_canonical(w: &World, what: &str) {
    let mut refs: HashMap<u32, u32> = HashMap::new();
    for &c in w.chunks() {
        assert_ne!(c >> 30, 3, "{what}: state 3");
        if cell::state(c) == State::Full {
            assert_ne!(cell::material(c), 0, "{what}: full chunk of material 0");
        }
        if cell::state(c) != State::Mixed {
            continue;
        }
        let blocks = &w.blocks()[cell::pointer(c) as usize..][..64];
        assert!(
            !blocks.iter().all(|&b| b == blocks[0] && cell::state(b) != State::Mixed),
            "{what}: uniform mixed chunk"
        );
        for &b in blocks {
            if cell::state(b) == State::Mixed {
                *refs.entry(cell::pointer(b)).or_default() += 1;
                let g: Vec<u16> = (0..64)
                    .map(|i| cell::voxel_material(cell::group_voxel(w.voxels(), cell::pointer(b) as usize, i)))
                    .collect();
                assert!(!g.iter().all(|&m| m == g[0]), "{what}: uniform voxel group");
            }
        }
    }
    assert_eq!(refs.len(), w.groups().live_groups(), "{what}: live group count");
    for (&ptr, &n) in &refs {
        assert_eq!(w.groups().refs(ptr), n, "{what}: refcount of group {ptr}");
    }
    // After a fresh build no two live groups are identical.
    let mut seen = HashMap::new();
    for &ptr in refs.keys() {
        let words = &w.voxels()[ptr as usize..][..32];
        assert!(seen.insert(words.to_vec(), ptr).is_none(), "{what}: duplicate groups");
    }
    for free in w.groups().free_slots() {
        assert!(!refs.contains_key(&free), "{what}: live pointer into a free slot");
    }
}

/// No empty cell's box (at any level) contains a solid cell: brute force over voxels.
fn assert_aadf_valid(raw: &Raw, w: &World, what: &str) {
    let s = raw.size.voxels().map(i64::from);
    let solid_in = |lo: [i64; 3], hi: [i64; 3]| -> bool {
        for z in lo[2].max(0)..hi[2].min(s[2]) {
            for y in lo[1].max(0)..hi[1].min(s[1]) {
                for x in lo[0].max(0)..hi[0].min(s[0]) {
                    if raw.get([x as u32, y as u32, z as u32]) != 0 {
                        return true;
                    }
                }
            }
        }
        false
    };
    let size = raw.size;
    for (i, &c) in w.chunks().iter().enumerate() {
        let cp = size.chunk_coords(i).map(i64::from);
        if chunk_is_free(c, w.chunk_entities()[i]) {
            let f = Aadf::unpack(c, 5);
            let lo: [i64; 3] = std::array::from_fn(|a| (cp[a] - i64::from(f.0[2 * a])) * 16);
            let hi: [i64; 3] = std::array::from_fn(|a| (cp[a] + 1 + i64::from(f.0[2 * a + 1])) * 16);
            assert!(
                !solid_in(lo, hi),
                "{what}: chunk {cp:?} box {f:?} contains solid voxels"
            );
            continue;
        }
        if cell::state(c) != State::Mixed {
            continue;
        }
        for b in 0..64usize {
            let bc = w.blocks()[cell::pointer(c) as usize + b];
            let bp = [b as i64 % 4, b as i64 / 4 % 4, b as i64 / 16];
            let base: [i64; 3] = std::array::from_fn(|a| cp[a] * 16 + bp[a] * 4);
            if cell::state(bc) == State::Empty {
                let f = Aadf::unpack(bc, 2);
                assert_eq!(bc >> 12, 0, "{what}: stray bits in an empty block");
                let lo: [i64; 3] = std::array::from_fn(|a| base[a] - 4 * i64::from(f.0[2 * a]));
                let hi: [i64; 3] = std::array::from_fn(|a| base[a] + 4 + 4 * i64::from(f.0[2 * a + 1]));
                assert!(
                    (0..3).all(|a| bp[a] - i64::from(f.0[2 * a]) >= 0 && bp[a] + i64::from(f.0[2 * a + 1]) <= 3),
                    "{what}: block box leaves its chunk"
                );
                assert!(!solid_in(lo, hi), "{what}: block box contains solid voxels");
            } else if cell::state(bc) == State::Mixed {
                for v in 0..64usize {
                    let vv = cell::group_voxel(w.voxels(), cell::pointer(bc) as usize, v);
                    if cell::voxel_is_solid(vv) {
                        continue;
                    }
                    assert_eq!(vv >> 12, 0, "{what}: stray bits in an empty voxel");
                    let f = Aadf::unpack(u32::from(vv), 2);
                    let vp = [v as i64 % 4, v as i64 / 4 % 4, v as i64 / 16];
                    assert!(
                        (0..3).all(|a| vp[a] - i64::from(f.0[2 * a]) >= 0 && vp[a] + i64::from(f.0[2 * a + 1]) <= 3),
                        "{what}: voxel box leaves its block"
                    );
                    let lo: [i64; 3] = std::array::from_fn(|a| base[a] + vp[a] - i64::from(f.0[2 * a]));
                    let hi: [i64; 3] = std::array::from_fn(|a| base[a] + vp[a] + 1 + i64::from(f.0[2 * a + 1]));
                    assert!(!solid_in(lo, hi), "{what}: voxel box contains solid voxels");
                }
            }
        }
    }
    assert_eq!(w.unsafe_chunk_aadf(), None, "{what}: prefix-sum safety check disagrees");
}

#[test]
fn adversarial_volumes_roundtrip_and_stay_canonical() {
    for size in sizes() {
        for (name, raw) in adversarial(size) {
            let w = raw.build();
            let what = format!("{name} {size}");
            assert_roundtrip(&raw, &w, &what);
            assert_canonical(&w, &what);
            assert_aadf_valid(&raw, &w, &what);
        }
    }
}

#[test]
fn random_volumes_roundtrip_and_stay_canonical() {
    for seed in 0..12u64 {
        let size = sizes()[seed as usize % 3];
        let raw = random_world(size, seed);
        let w = raw.build();
        let what = format!("seed {seed} {size}");
        assert_roundtrip(&raw, &w, &what);
        assert_canonical(&w, &what);
        assert_aadf_valid(&raw, &w, &what);
    }
}

#[test]
fn uniform_collapse() {
    let size = WorldSize::new(64, 64, 64).unwrap();
    let (_, full) = adversarial(size).into_iter().nth(1).unwrap();
    let w = full.build();
    assert!(w.chunks().iter().all(|&c| c == cell::full(2)));
    assert!(w.blocks().is_empty() && w.voxels().is_empty());
    let w = Raw::empty(size, 1).build();
    // An all-empty 4³-chunk world: every chunk reaches the world edge on every side.
    let f = Aadf::unpack(w.chunks()[0], 5);
    assert_eq!(f, Aadf([31, 31, 31, 31, 31, 31]), "outside the world counts as empty");
}

#[test]
fn construction_is_deterministic_across_thread_counts() {
    let raw = random_world(WorldSize::new(128, 64, 128).unwrap(), 99);
    let build_with = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| raw.build())
    };
    let a = build_with(1);
    let b = build_with(4);
    assert!(a.to_parts() == b.to_parts(), "buffers differ between 1 and 4 threads");
    assert_eq!(a.digest(), b.digest());
}

#[test]
fn undefined_material_is_rejected() {
    let mut raw = Raw::empty(WorldSize::new(64, 64, 64).unwrap(), 2);
    raw.set([3, 3, 3], 5);
    let err = World::build(&raw, &|_| {}).err().expect("material 5 is not defined");
    assert!(err.to_string().contains("material 5"), "{err}");
}

#[test]
fn loading_rejects_a_mixed_chunk_of_empty_blocks() {
    let mut raw = Raw::empty(WorldSize::new(64, 64, 64).unwrap(), 1);
    raw.set([1, 1, 1], 1);
    let mut parts = raw.build().to_parts();
    assert!(World::from_parts(parts.clone()).is_ok());
    // Chunk 0 keeps pointing at block array 0, now 64 empty blocks with exact AADFs.
    let fields = naadf_world::aadf::cell_aadf4(!0);
    for (b, f) in fields.iter().enumerate() {
        parts.blocks[b] = u32::from(*f);
    }
    parts.voxels.fill(0);
    let err = World::from_parts(parts).err().expect("non-canonical chunk accepted");
    assert!(err.to_string().contains("collapsed"), "{err}");
}

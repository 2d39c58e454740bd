//! Chunk fingerprints (`naadf_world::fingerprint`) against brute force: after each random
//! batch, the chunks an update reports as changed are exactly those whose decoded voxels,
//! entity records (of entities over them) or those records' entity types differ, and the updated prints equal
//! prints built from scratch.

mod common;

use common::{Rng, random_world};
use naadf_world::cell::CHUNK_VOXELS;
use naadf_world::digest::BufferId;
use naadf_world::entity::pack::{InstanceRecord, RECORD_WORDS};
use naadf_world::entity::{ENTITY_SOLID, chunk_range};
use naadf_world::fingerprint::{ChunkChanges, ChunkPrints, stale_words};
use naadf_world::material::MaterialKind;
use naadf_world::ops::{Batch, Limits, Op};
use naadf_world::{World, WorldSize};
use std::ops::Range;

/// What each chunk shows: its decoded materials, and the records of the entities whose
/// world boxes overlap it (found from the entity table's poses), each followed by its
/// type's solid voxels.
fn shown(w: &World) -> Vec<(Vec<u16>, Vec<u32>)> {
    let c = w.size().chunks();
    let mut over: Vec<Vec<u32>> = vec![Vec::new(); w.size().chunk_count()];
    for (&id, pose) in &w.entity_table().instances {
        let size = w.models().get(&pose.model).unwrap().size();
        let (lo, hi) = chunk_range(w.size(), size, pose.pos, pose.rot).unwrap();
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    over[w.size().chunk_index([x, y, z])].push(id);
                }
            }
        }
    }
    let mut out = Vec::new();
    for z in 0..c[2] {
        for y in 0..c[1] {
            for x in 0..c[0] {
                let mut voxels = vec![0u16; CHUNK_VOXELS];
                w.decode_chunk([x, y, z], (&mut voxels[..]).try_into().unwrap());
                let i = (x + c[0] * (y + c[1] * z)) as usize;
                let mut records = Vec::new();
                for &id in &over[i] {
                    let r = &w.entity_instances()[id as usize * RECORD_WORDS..][..RECORD_WORDS];
                    records.extend_from_slice(r);
                    let t = InstanceRecord::unpack(r);
                    let start = t.voxel_start as usize * 64;
                    let grid = &w.entity_type_voxels()[start..start + t.size.iter().product::<u32>() as usize];
                    records.extend(grid.iter().map(|&v| if v & ENTITY_SOLID != 0 { v } else { 0 }));
                }
                out.push((voxels, records));
            }
        }
    }
    out
}

/// The model the entities are made of, with one voxel of material `m`.
fn crate_model(m: i64) -> Op {
    Op::DefineModel {
        name: "crate".into(),
        size: [5, 4, 6],
        voxels: vec![[0, 0, 0, 2], [4, 3, 5, 3], [2, 1, 2, m]],
    }
}

fn random_batch(rng: &mut Rng, s: [u32; 3], spawned: &mut Vec<u32>) -> Vec<Op> {
    let at = |rng: &mut Rng| [0, 1, 2].map(|a| rng.below(u64::from(s[a])) as i64);
    let pos = |rng: &mut Rng| [0, 1, 2].map(|a| rng.unit() * f64::from(s[a] - 8));
    match rng.below(9) {
        0 => vec![Op::Set {
            voxels: (0..1 + rng.below(4))
                .map(|_| {
                    let p = at(rng);
                    [p[0], p[1], p[2], rng.below(10) as i64]
                })
                .collect(),
        }],
        1 => {
            let min = at(rng);
            vec![Op::Box {
                min,
                max: min.map(|v| v + 1 + rng.below(20) as i64),
                material: rng.below(10) as u16,
            }]
        }
        2 => {
            // Painting a solid region the colour it already has changes nothing.
            let p = at(rng);
            vec![Op::Paint {
                center: p.map(|v| v as f64),
                radius: 3.0,
                material: 1 + rng.below(9) as u16,
            }]
        }
        3 => {
            let id = spawned.len() as u32 + 1;
            spawned.push(id);
            vec![Op::SpawnEntity {
                id,
                model: "crate".into(),
                pos: pos(rng),
                rot: [0.0, 0.0, 0.0, 1.0],
            }]
        }
        4 if !spawned.is_empty() => vec![Op::MoveEntity {
            id: spawned[rng.below(spawned.len() as u64) as usize],
            pos: pos(rng),
            rot: [0.0, 0.3, 0.0, 1.0],
        }],
        5 => vec![Op::DefineMaterial {
            id: 1 + rng.below(9) as u16,
            kind: MaterialKind::Diffuse,
            albedo: [rng.unit() as f32, 0.5, 0.5],
            emission: 0.0,
            roughness: 0.0,
        }],
        // Whole chunks: uniform to uniform cells change only the chunk words.
        7 => {
            let min = at(rng).map(|v| v / 16 * 16);
            vec![Op::Box {
                min,
                max: min.map(|v| v + 16 * (1 + rng.below(2) as i64)),
                material: rng.below(4) as u16,
            }]
        }
        // Every entity changes with its model.
        6 => vec![crate_model(1 + rng.below(9) as i64)],
        // Nothing a ray sees: an empty box in empty space may still reach the world's
        // structure (fields), and an empty batch changes nothing.
        _ => Vec::new(),
    }
}

/// The words that differ between two versions of a buffer, as ranges.
fn differing_words(before: &[u8], after: &[u8]) -> Vec<Range<usize>> {
    let word = |b: &[u8], i: usize| b.get(4 * i..4 * i + 4).map(|w| w.to_vec());
    let n = before.len().max(after.len()).div_ceil(4);
    let mut out: Vec<Range<usize>> = Vec::new();
    for i in (0..n).filter(|&i| word(before, i) != word(after, i)) {
        match out.last_mut() {
            Some(r) if r.end == i => r.end = i + 1,
            _ => out.push(i..i + 1),
        }
    }
    out
}

/// Random batches on random worlds; the update is told the stale words by page hashes
/// (what a mirror knows) or, when `exact`, word by word (so that every way a chunk can
/// be reached, not just its page of chunk words, is exercised).
fn check_updates(exact: bool) {
    for seed in 0..3u64 {
        let size = WorldSize::new(128, 64, 64).unwrap();
        let mut w = random_world(size, seed).build();
        let setup = Batch {
            ops: vec![crate_model(4)],
        };
        w.apply(&setup, &Limits::default()).unwrap();
        let mut prints = ChunkPrints::new(&w);
        let mut rng = Rng(seed + 17);
        let mut spawned = Vec::new();
        let (mut local, mut everything) = (0, 0);
        for step in 0..40 {
            let before = shown(&w);
            let hashes: Vec<Vec<u64>> = BufferId::WORLD.iter().map(|&id| w.page_hashes(id).to_vec()).collect();
            let bytes: Vec<Vec<u8>> = BufferId::WORLD.iter().map(|&id| w.buffer_bytes(id).to_vec()).collect();
            // One to three batches between updates, as when a mirror syncs after several.
            let mut recolours = false;
            for _ in 0..1 + rng.below(3) {
                let ops = random_batch(&mut rng, size.voxels(), &mut spawned);
                recolours |= ops.iter().any(|o| matches!(o, Op::DefineMaterial { .. }));
                w.apply(&Batch { ops }, &Limits::default()).unwrap();
            }
            let stale: Vec<(BufferId, Vec<Range<usize>>)> = BufferId::WORLD
                .iter()
                .enumerate()
                .map(|(k, &id)| match exact {
                    true => (id, differing_words(&bytes[k], &w.buffer_bytes(id))),
                    false => (id, stale_words(&hashes[k], w.page_hashes(id))),
                })
                .collect();
            let got = prints.update(&w, &stale);
            let after = shown(&w);
            let expected: Vec<u32> = (0..after.len())
                .filter(|&i| before[i] != after[i])
                .map(|i| i as u32)
                .collect();
            if recolours {
                assert_eq!(got, ChunkChanges::Everything, "seed {seed} step {step}");
                everything += 1;
            } else {
                assert_eq!(got, ChunkChanges::Chunks(expected.clone()), "seed {seed} step {step}");
                local += usize::from(!expected.is_empty());
            }
            assert!(
                prints == ChunkPrints::new(&w),
                "seed {seed} step {step}: prints as from scratch"
            );
        }
        assert!(
            local > 10 && everything > 0,
            "seed {seed}: {local} local changes, {everything} global"
        );
    }
}

#[test]
fn updates_from_stale_pages_report_exactly_the_chunks_whose_content_changed() {
    check_updates(false);
}

#[test]
fn updates_from_stale_words_report_exactly_the_chunks_whose_content_changed() {
    check_updates(true);
}

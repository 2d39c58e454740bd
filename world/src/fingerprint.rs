//! [`ChunkPrints`]: a fingerprint of what each chunk shows a ray (its voxels' materials and
//! the entity records over it), so that a mirror of the world's buffers can tell which
//! chunks an update changed without knowing the edits that made it.
//!
//! Renderers that keep light from earlier frames use it: light on and from a chunk that
//! changed is stale (docs/RENDERING.md §3c). Distance fields are left out: they change
//! across wide empty areas after any edit, but change nothing a ray sees.
//!
//! An update looks only at the chunks whose words, block array or voxel groups lie in words
//! that may have changed (a mirror knows the 64 KiB pages of the world's digest that
//! changed: [`stale_words`]), and rehashes those. Entities live outside the static world,
//! so their changes come from the instance records instead: every instance whose record
//! or type changed marks the chunks its world box overlaps, before and after.

use crate::World;
use crate::cell::{self, State};
use crate::digest::{BufferId, PAGE_BYTES};
use crate::entity::pack::{InstanceRecord, RECORD_WORDS, conjugate};
use crate::entity::{ENTITY_SOLID, chunk_range};
use crate::hash::Xxh3;
use crate::size::WorldSize;
use rayon::prelude::*;
use std::collections::HashMap;
use std::ops::Range;

/// Words per digest page.
const PAGE_WORDS: usize = PAGE_BYTES / 4;
/// Blocks per chunk.
const BLOCKS: usize = cell::CELLS;

/// The fingerprint of every chunk of a world version, and of the instances over it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChunkPrints {
    /// Per chunk: its static content.
    prints: Vec<u64>,
    /// The instance buffer the prints are of.
    instances: Vec<u32>,
    /// The fingerprint of each entity type the instances use, by `voxelStart`.
    types: HashMap<u32, u64>,
}

/// What changed between two versions of a world, chunk by chunk.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum ChunkChanges {
    /// These chunks (indices, ascending) show something else; the rest are as they were.
    Chunks(Vec<u32>),
    /// Something every chunk's light depends on changed: the materials or the world's size.
    Everything,
}

/// The word ranges of a buffer that may differ between two versions, from the hashes of
/// its 64 KiB pages: every page whose hash differs, or that only one version has.
///
/// ```
/// use naadf_world::fingerprint::stale_words;
/// let page = 16384; // words
/// assert_eq!(stale_words(&[1, 2, 3], &[1, 5, 3, 4]), vec![page..2 * page, 3 * page..4 * page]);
/// ```
pub fn stale_words(before: &[u64], after: &[u64]) -> Vec<Range<usize>> {
    (0..before.len().max(after.len()))
        .filter(|&p| before.get(p) != after.get(p))
        .map(|p| p * PAGE_WORDS..(p + 1) * PAGE_WORDS)
        .collect()
}

impl ChunkPrints {
    /// The fingerprints of every chunk of `world`.
    pub fn new(world: &World) -> Self {
        ChunkPrints {
            prints: (0..world.chunks().len())
                .into_par_iter()
                .map(|i| print(world, i))
                .collect(),
            instances: world.entity_instances().to_vec(),
            types: type_prints(world),
        }
    }

    /// Moves to `world`, whose buffers differ from the version these prints are of only in
    /// the words `stale` lists (per buffer, ranges in ascending order that do not overlap;
    /// [`stale_words`]), and says which chunks now show something else.
    pub fn update(&mut self, world: &World, stale: &[(BufferId, Vec<Range<usize>>)]) -> ChunkChanges {
        let pages = |id: BufferId| -> &[Range<usize>] {
            stale.iter().find(|(b, _)| *b == id).map_or(&[], |(_, p)| p.as_slice())
        };
        if world.chunks().len() != self.prints.len() || !pages(BufferId::Materials).is_empty() {
            *self = ChunkPrints::new(world);
            return ChunkChanges::Everything;
        }
        let [chunk_pages, block_pages, voxel_pages, type_pages, record_pages] = [
            BufferId::Chunks,
            BufferId::Blocks,
            BufferId::Voxels,
            BufferId::EntityTypes,
            BufferId::EntityInstances,
        ]
        .map(pages);
        let (chunks, blocks) = (world.chunks(), world.blocks());
        let candidate = |i: usize| {
            if touches(chunk_pages, i, 1) {
                return true;
            }
            let c = chunks[i];
            if cell::state(c) != State::Mixed {
                return false;
            }
            let array = cell::pointer(c) as usize;
            touches(block_pages, array, BLOCKS)
                || (!voxel_pages.is_empty()
                    && blocks[array..array + BLOCKS].iter().any(|&b| {
                        cell::state(b) == State::Mixed
                            && touches(voxel_pages, cell::pointer(b) as usize, cell::GROUP_WORDS)
                    }))
        };
        let old = &self.prints;
        let changed: Vec<(u32, u64)> = (0..chunks.len())
            .into_par_iter()
            .filter(|&i| candidate(i))
            .filter_map(|i| {
                let p = print(world, i);
                (p != old[i]).then_some((i as u32, p))
            })
            .collect();
        for &(i, p) in &changed {
            self.prints[i as usize] = p;
        }
        let mut out: Vec<u32> = changed.into_iter().map(|(i, _)| i).collect();
        if !record_pages.is_empty() || !type_pages.is_empty() {
            let types = type_prints(world);
            let (before, after) = (&self.instances, world.entity_instances());
            let record = |words: &[u32], types: &HashMap<u32, u64>, slot: usize| {
                let w = words.get(slot * RECORD_WORDS..(slot + 1) * RECORD_WORDS)?;
                (w[4] != 0).then(|| {
                    let r = InstanceRecord::unpack(w);
                    (r, types[&r.voxel_start])
                })
            };
            for slot in 0..before.len().max(after.len()) / RECORD_WORDS {
                let (was, is) = (record(before, &self.types, slot), record(after, &types, slot));
                if was != is {
                    for (r, _) in [was, is].into_iter().flatten() {
                        out.extend(chunks_under(world.size(), &r));
                    }
                }
            }
            self.instances = after.to_vec();
            self.types = types;
        }
        out.sort_unstable();
        out.dedup();
        ChunkChanges::Chunks(out)
    }
}

/// The chunks of a `size` world that an instance's world box overlaps (as [`chunk_range`]
/// clips it to the world): where a change of the record changes what rays see.
pub fn chunks_under(size: WorldSize, r: &InstanceRecord) -> Vec<u32> {
    let Some((lo, hi)) = chunk_range(size, r.size, r.position(), conjugate(r.inv_rotation())) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for z in lo[2]..=hi[2] {
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                out.push(size.chunk_index([x, y, z]) as u32);
            }
        }
    }
    out
}

/// Whether the words `start..start + len` of a buffer meet any of `stale` (ascending,
/// disjoint).
fn touches(stale: &[Range<usize>], start: usize, len: usize) -> bool {
    let k = stale.partition_point(|r| r.end <= start);
    len > 0 && stale.get(k).is_some_and(|r| r.start < start + len)
}

/// The fingerprint of each entity type an instance record uses, by `voxelStart`: its
/// voxels' materials (empty as 0, whatever their fields).
fn type_prints(world: &World) -> HashMap<u32, u64> {
    let mut out = HashMap::new();
    for words in world.entity_instances().chunks_exact(RECORD_WORDS) {
        if words[4] == 0 {
            continue;
        }
        let r = InstanceRecord::unpack(words);
        out.entry(r.voxel_start).or_insert_with(|| {
            let start = r.voxel_start as usize * 64;
            let len = r.size.iter().product::<u32>() as usize;
            let solid: Vec<u32> = world.entity_type_voxels()[start..start + len]
                .iter()
                .map(|&v| if v & ENTITY_SOLID != 0 { v } else { 0 })
                .collect();
            let mut h = Xxh3::new();
            h.update(bytemuck::cast_slice(&solid));
            h.digest()
        });
    }
    out
}

/// The fingerprint of chunk `i`: its blocks' materials (empty cells as 0, whatever their
/// distance fields).
fn print(world: &World, i: usize) -> u64 {
    let mut h = Xxh3::new();
    let c = world.chunks()[i];
    let uniform = |cell: u32| -> u16 {
        match cell::state(cell) {
            State::Full => cell::material(cell),
            _ => 0,
        }
    };
    if cell::state(c) == State::Mixed {
        let array = cell::pointer(c) as usize;
        for &b in &world.blocks()[array..array + BLOCKS] {
            if cell::state(b) == State::Mixed {
                // A group's empty voxels hold fields local to its block, which change only
                // with the block's content: the raw words are as good as the materials.
                let ptr = cell::pointer(b) as usize;
                h.update(&[1]);
                h.update(bytemuck::cast_slice(&world.voxels()[ptr..ptr + cell::GROUP_WORDS]));
            } else {
                h.update(&[0]);
                h.update(&uniform(b).to_le_bytes());
            }
        }
    } else {
        h.update(&[2]);
        h.update(&uniform(c).to_le_bytes());
    }
    h.digest()
}

//! Construction of a world from raw voxels, chunk by chunk (docs/FORMAT.md §7, docs/NAADF.md §5).
//!
//! A [`ChunkSource`] yields one 16³ chunk of material ids at a time, so no dense copy of
//! the world ever exists. Chunks are processed in batches, in linear chunk order:
//! 1. in parallel (rayon), each chunk is classified (uniform or mixed), each of its
//!    blocks hashed and classified, and the voxel and block AADFs computed — all pure
//!    functions of the chunk's content;
//! 2. sequentially, in chunk order, each mixed chunk appends its 64 block cells and each
//!    mixed block acquires its voxel group from the dedup map.
//!
//! Step 2 fixes every pointer in chunk order, so the buffers are the same byte for byte
//! whatever the number of threads. Chunk AADFs are built last, level-major.

use crate::aadf::cell_aadf4;
use crate::cell::{self, CHUNK_VOXELS, GROUP_WORDS, MAX_MATERIAL, State};
use crate::error::WorldError;
use crate::hash::block_hash;
use crate::material::MaterialTable;
use crate::model::ModelTable;
use crate::size::WorldSize;
use rayon::prelude::*;

/// Something that produces a world's raw voxels one chunk at a time.
pub trait ChunkSource: Sync {
    /// The world size.
    fn size(&self) -> WorldSize;

    /// The material table; every id the source emits must be defined in it.
    fn materials(&self) -> MaterialTable;

    /// Models that travel with the world (none by default).
    fn models(&self) -> ModelTable {
        ModelTable::default()
    }

    /// A material id if the whole chunk is known to be that one material (0 = empty). A
    /// fast path for generators; the default says nothing.
    fn uniform_hint(&self, _chunk: [u32; 3]) -> Option<u16> {
        None
    }

    /// Writes the material ids of chunk `chunk` (chunk coordinates) into `out`, indexed
    /// by chunk-local `x + 16y + 256z` (0 = empty).
    fn fill_chunk(&self, chunk: [u32; 3], out: &mut [u16; CHUNK_VOXELS]);
}

/// Chunks per batch: bounds memory held between the parallel and sequential steps.
const BATCH: usize = 4096;

/// One mixed block's voxel group, ready to be deduplicated.
pub(crate) struct GroupPlan {
    /// Block index in the chunk.
    pub block: u8,
    /// Reference hash of the material ids.
    pub hash: u32,
    /// Final voxel words (AADF bits included).
    pub words: [u32; GROUP_WORDS],
}

/// The content-determined form of one chunk, before any pointer is assigned.
pub(crate) enum ChunkPlan {
    /// One material throughout (0 = empty).
    Uniform(u16),
    /// Block cells (uniform ones final, new mixed ones 0 until placed), the new mixed
    /// groups, and the mask of blocks whose existing mixed cell was kept (whose group
    /// reference carries over).
    Mixed {
        blocks: Box<[u32; 64]>,
        groups: Vec<GroupPlan>,
        kept: u64,
    },
}

/// Classifies a raw chunk (material ids, `x + 16y + 256z`). Fails with the offending id
/// on ids above `max_id`.
pub(crate) fn plan_chunk(raw: &[u16; CHUNK_VOXELS], max_id: u16) -> Result<ChunkPlan, u16> {
    // Most chunks of a generated world are uniform: one pass finds them.
    let first = raw[0];
    if raw.iter().all(|&v| v == first) {
        return if first > max_id {
            Err(first)
        } else {
            Ok(ChunkPlan::Uniform(first))
        };
    }
    plan_chunk_keeping(raw, max_id, &|_| None)
}

/// The 64 material ids of block `b` (`x + 4y + 16z` inside the block) of a raw chunk.
#[inline]
pub(crate) fn gather_block(raw: &[u16; CHUNK_VOXELS], b: u32) -> [u16; 64] {
    let (bx, by, bz) = (b % 4 * 4, b / 4 % 4 * 4, b / 16 * 4);
    std::array::from_fn(|i| {
        let i = i as u32;
        raw[cell::index16(bx + i % 4, by + i / 4 % 4, bz + i / 16)]
    })
}

/// Whether block `b` holds the same ids in two raw chunks (compared row by row).
#[inline]
pub(crate) fn block_equal(a: &[u16; CHUNK_VOXELS], b: &[u16; CHUNK_VOXELS], block: u32) -> bool {
    let base = cell::index16(block % 4 * 4, block / 4 % 4 * 4, block / 16 * 4);
    (0..16).all(|row| {
        let at = base + 16 * (row % 4) + 256 * (row / 4);
        a[at..at + 4] == b[at..at + 4]
    })
}

/// [`plan_chunk`] for an edited chunk: `keep(b)` gives the existing cell of a block whose
/// content did not change, and `raw` need only hold the other blocks. A mixed or full cell
/// is kept as is (no gather, no rehash, no new reference); an empty one only counts as
/// empty, since its field depends on its neighbours.
pub(crate) fn plan_chunk_keeping(
    raw: &[u16; CHUNK_VOXELS],
    max_id: u16,
    keep: &dyn Fn(usize) -> Option<u32>,
) -> Result<ChunkPlan, u16> {
    let mut blocks = [0u32; 64];
    let mut groups = Vec::new();
    let mut empty_blocks = 0u64;
    let mut kept = 0u64;
    // The material of every block so far, while they are all uniform and alike.
    let mut uniform: Option<u16> = None;
    let mut alike = true;
    let mut block_is = |m: Option<u16>, b: u32| {
        alike &= m.is_some() && (b == 0 || m == uniform);
        uniform = m;
    };
    for b in 0..64u32 {
        if let Some(c) = keep(b as usize) {
            match cell::state(c) {
                State::Empty => {
                    empty_blocks |= 1 << b;
                    block_is(Some(0), b);
                }
                State::Full => {
                    blocks[b as usize] = c;
                    block_is(Some(cell::material(c)), b);
                }
                State::Mixed => {
                    blocks[b as usize] = c;
                    kept |= 1 << b;
                    block_is(None, b);
                }
            }
            continue;
        }
        let v = gather_block(raw, b);
        if let Some(&bad) = v.iter().find(|&&m| m > max_id) {
            return Err(bad);
        }
        if v.iter().all(|&m| m == v[0]) {
            blocks[b as usize] = cell::uniform(v[0]);
            if v[0] == 0 {
                empty_blocks |= 1 << b;
            }
            block_is(Some(v[0]), b);
            continue;
        }
        block_is(None, b);
        groups.push(GroupPlan {
            block: b as u8,
            hash: block_hash(&v),
            words: group_words(&v),
        });
    }
    if let (true, Some(m)) = (alike, uniform) {
        return Ok(ChunkPlan::Uniform(m));
    }
    let fields = cell_aadf4(empty_blocks);
    for b in 0..64 {
        if empty_blocks >> b & 1 == 1 {
            blocks[b] = u32::from(fields[b]);
        }
    }
    Ok(ChunkPlan::Mixed {
        blocks: Box::new(blocks),
        groups,
        kept,
    })
}

/// The 32 stored words of a voxel group with material ids `v`: solid voxels as
/// `0x8000 | m`, empty voxels as their voxel AADF.
pub fn group_words(v: &[u16; 64]) -> [u32; GROUP_WORDS] {
    let empty = v
        .iter()
        .enumerate()
        .fold(0u64, |m, (i, &x)| m | (u64::from(x == 0) << i));
    let fields = cell_aadf4(empty);
    let cellv = |i: usize| u32::from(if v[i] == 0 { fields[i] } else { cell::voxel(v[i]) });
    std::array::from_fn(|w| cellv(2 * w) | (cellv(2 * w + 1) << 16))
}

/// Plans every chunk of `source` in parallel batches and hands the plans, in linear chunk
/// order, to `place`. Reports the chunks done to `progress`.
pub(crate) fn plan_all(
    source: &dyn ChunkSource,
    progress: &(dyn Fn(u64) + Sync),
    mut place: impl FnMut(usize, ChunkPlan) -> Result<(), WorldError>,
) -> Result<(), WorldError> {
    let size = source.size();
    let max_id = (source.materials().len() - 1).min(usize::from(MAX_MATERIAL)) as u16;
    let n = size.chunk_count();
    let mut done = 0usize;
    while done < n {
        let end = (done + BATCH).min(n);
        let plans: Vec<Result<ChunkPlan, u16>> = (done..end)
            .into_par_iter()
            .map_init(
                || Box::new([0u16; CHUNK_VOXELS]),
                |raw, i| {
                    let c = size.chunk_coords(i);
                    if let Some(m) = source.uniform_hint(c) {
                        return if m > max_id { Err(m) } else { Ok(ChunkPlan::Uniform(m)) };
                    }
                    source.fill_chunk(c, raw);
                    plan_chunk(raw, max_id)
                },
            )
            .collect();
        for (k, plan) in plans.into_iter().enumerate() {
            let plan = plan.map_err(|m| {
                WorldError::InvalidMaterial(format!(
                    "chunk {:?} uses material {m}, but only 1..={max_id} are defined",
                    size.chunk_coords(done + k)
                ))
            })?;
            place(done + k, plan)?;
        }
        done = end;
        progress(done as u64);
    }
    Ok(())
}

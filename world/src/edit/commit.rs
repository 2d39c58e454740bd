//! Writing new chunk contents into the structure: dedup reference counts, copy-on-write of
//! shared voxel groups, free lists, and collapse/expansion of uniform cells.

use super::overlay::Touched;
use super::writes::Writes;
use crate::build::{ChunkPlan, plan_chunk_keeping};
use crate::cell::{self, GROUP_WORDS, State};
use crate::digest::BufferId;
use crate::error::WorldError;
use crate::world::World;

const BLOCK_ARRAY: usize = 64;

impl World {
    /// Replaces a touched chunk's content with its new content (material ids, all defined).
    ///
    /// Blocks whose content did not change keep their cells untouched; only changed blocks
    /// are rehashed.
    ///
    /// Shared groups are never modified: a block whose content changes acquires the group
    /// for its new content (deduplicated, or a new slot) and releases the old one, so other
    /// blocks pointing at the old group keep it. New groups are acquired before old ones are
    /// released, so a group that survives keeps its slot; both steps go in block order, which
    /// makes slot reuse deterministic.
    pub(crate) fn commit_chunk(&mut self, t: &Touched, w: &mut Writes) -> Result<(), WorldError> {
        let i = t.index;
        let max_id = (self.materials.len() - 1) as u16;
        let old = self.chunks[i];
        // Blocks the batch did not change keep their cells (an empty one's field is
        // recomputed: its neighbours may have changed). Only changed blocks are decoded.
        let keep = |b: usize| (t.changed >> b & 1 == 0).then(|| self.block_cell(old, b as u32));
        let plan = plan_chunk_keeping(&t.new, max_id, &keep)
            .map_err(|m| WorldError::InvalidMaterial(format!("material {m} is not defined (1..={max_id})")))?;
        let new = match plan {
            ChunkPlan::Uniform(m) => {
                if cell::state(old) == State::Mixed {
                    self.free_block_array(cell::pointer(old), w);
                }
                // An empty chunk that stays empty keeps its AADF.
                if m == 0 && cell::state(old) == State::Empty {
                    old
                } else {
                    cell::uniform(m)
                }
            }
            ChunkPlan::Mixed {
                mut blocks,
                groups,
                kept,
            } => {
                for g in &groups {
                    let ptr = self.groups.acquire(&mut self.voxels, g.hash, &g.words)?;
                    if self.groups.refs(ptr) == 1 {
                        w.push(BufferId::Voxels, ptr as usize, GROUP_WORDS);
                    }
                    blocks[usize::from(g.block)] = cell::mixed(ptr);
                }
                let arr = if cell::state(old) == State::Mixed {
                    let arr = cell::pointer(old);
                    for b in (0..BLOCK_ARRAY).filter(|&b| kept >> b & 1 == 0) {
                        let bc = self.blocks[arr as usize + b];
                        if cell::state(bc) == State::Mixed {
                            self.release_group(cell::pointer(bc), w);
                        }
                    }
                    arr
                } else {
                    self.alloc_block_array()?
                };
                let cells = &mut self.blocks[arr as usize..][..BLOCK_ARRAY];
                if cells[..] != blocks[..] {
                    cells.copy_from_slice(&blocks[..]);
                    w.push(BufferId::Blocks, arr as usize, BLOCK_ARRAY);
                }
                cell::mixed(arr)
            }
        };
        if new != old {
            self.chunks[i] = new;
            w.push(BufferId::Chunks, i, 1);
        }
        Ok(())
    }

    /// Drops one reference to a group, recording the zeroed slot if it was the last.
    fn release_group(&mut self, ptr: u32, w: &mut Writes) {
        self.groups.release(&mut self.voxels, ptr);
        if self.groups.refs(ptr) == 0 {
            w.push(BufferId::Voxels, ptr as usize, GROUP_WORDS);
        }
    }

    /// Releases a block array's groups, zeroes it and puts it on the free list.
    fn free_block_array(&mut self, arr: u32, w: &mut Writes) {
        for b in 0..BLOCK_ARRAY {
            let bc = self.blocks[arr as usize + b];
            if cell::state(bc) == State::Mixed {
                self.release_group(cell::pointer(bc), w);
            }
        }
        self.blocks[arr as usize..][..BLOCK_ARRAY].fill(0);
        self.free_block_arrays.insert(arr);
        w.push(BufferId::Blocks, arr as usize, BLOCK_ARRAY);
    }

    /// Fails if committing `chunks` touched chunks could outgrow the 30-bit pointers, so
    /// that a batch is refused whole before anything is written.
    pub(crate) fn check_capacity(&self, chunks: usize) -> Result<(), WorldError> {
        let groups = self.voxels.len() + chunks * BLOCK_ARRAY * GROUP_WORDS;
        let blocks = self.blocks.len() + chunks * BLOCK_ARRAY;
        if groups > cell::PAYLOAD as usize || blocks > cell::PAYLOAD as usize {
            return Err(WorldError::Capacity(format!(
                "an edit of {chunks} chunks could exceed the 30-bit buffer pointers"
            )));
        }
        Ok(())
    }
}

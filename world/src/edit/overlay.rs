//! The batch overlay: ops write into decoded copies of the blocks they touch, so the world
//! is untouched until the whole batch has succeeded.

use crate::build::block_equal;
use crate::cell::CHUNK_VOXELS;
use crate::ops::Canvas;
use crate::size::WorldSize;
use crate::world::World;
use rustc_hash::FxHashMap;
use std::cell::Cell;

/// Raw material ids of one chunk, `x + 16y + 256z`.
pub(crate) type RawChunk = Box<[u16; CHUNK_VOXELS]>;

/// A chunk a batch changed: its content before and after, and which of its 64 blocks
/// differ (bit `bx + 4by + 16bz`). Only the blocks the batch wrote to are decoded (the
/// others are 0 in both copies): the changed ones are among them.
pub(crate) struct Touched {
    pub index: usize,
    pub old: RawChunk,
    pub new: RawChunk,
    pub changed: u64,
}

/// A chunk an op wrote to, with the blocks it wrote to decoded.
struct Slot {
    index: usize,
    old: RawChunk,
    new: RawChunk,
    /// The blocks an op wrote to, the only ones decoded (they may still hold what they
    /// held).
    written: u64,
}

/// The block (`bx + 4by + 16bz`) of voxel `vi = x + 16y + 256z` of a chunk.
#[inline]
fn block_of(vi: usize) -> u32 {
    ((vi >> 2 & 3) | (vi >> 6 & 3) << 2 | (vi >> 10 & 3) << 4) as u32
}

/// A copy-on-write view of the world's voxels for one batch.
pub(crate) struct Overlay<'w> {
    world: &'w World,
    /// Touched chunks, in the order ops first wrote to them.
    chunks: Vec<Slot>,
    /// Chunk index → position in `chunks`.
    slots: FxHashMap<usize, usize>,
    /// Position of the chunk last accessed (ops mostly stay in one chunk for a while).
    last: Cell<usize>,
}

impl<'w> Overlay<'w> {
    pub(crate) fn new(world: &'w World) -> Self {
        Overlay {
            world,
            chunks: Vec::new(),
            slots: FxHashMap::default(),
            last: Cell::new(usize::MAX),
        }
    }

    /// The chunks whose content changed, by chunk index, ascending. Only the blocks ops
    /// wrote to are compared.
    pub(crate) fn into_touched(self) -> Vec<Touched> {
        let mut v: Vec<Touched> = self
            .chunks
            .into_iter()
            .filter_map(|s| {
                let changed = (0..64u32)
                    .filter(|&b| s.written >> b & 1 == 1 && !block_equal(&s.old, &s.new, b))
                    .fold(0u64, |m, b| m | 1 << b);
                (changed != 0).then_some(Touched {
                    index: s.index,
                    old: s.old,
                    new: s.new,
                    changed,
                })
            })
            .collect();
        v.sort_unstable_by_key(|t| t.index);
        v
    }

    #[inline]
    fn split(&self, p: [u32; 3]) -> (usize, usize) {
        let ci = self.world.size.chunk_index([p[0] >> 4, p[1] >> 4, p[2] >> 4]);
        (ci, (p[0] & 15 | (p[1] & 15) << 4 | (p[2] & 15) << 8) as usize)
    }

    /// Position of chunk `ci` in `chunks`, if touched.
    #[inline]
    fn slot(&self, ci: usize) -> Option<usize> {
        let last = self.last.get();
        if self.chunks.get(last).is_some_and(|c| c.index == ci) {
            return Some(last);
        }
        let s = self.slots.get(&ci).copied()?;
        self.last.set(s);
        Some(s)
    }
}

impl Canvas for Overlay<'_> {
    fn size(&self) -> WorldSize {
        self.world.size
    }

    #[inline]
    fn get(&self, p: [u32; 3]) -> u16 {
        let (ci, vi) = self.split(p);
        match self.slot(ci) {
            Some(s) if self.chunks[s].written >> block_of(vi) & 1 == 1 => self.chunks[s].new[vi],
            _ => self.world.material_at(p),
        }
    }

    #[inline]
    fn set(&mut self, p: [u32; 3], material: u16) {
        let (ci, vi) = self.split(p);
        let s = match self.slot(ci) {
            Some(s) => s,
            None => {
                self.chunks.push(Slot {
                    index: ci,
                    old: Box::new([0; CHUNK_VOXELS]),
                    new: Box::new([0; CHUNK_VOXELS]),
                    written: 0,
                });
                let s = self.chunks.len() - 1;
                self.slots.insert(ci, s);
                self.last.set(s);
                s
            }
        };
        let slot = &mut self.chunks[s];
        let b = block_of(vi);
        if slot.written >> b & 1 == 0 {
            // First write to this block: decode it into both copies.
            self.world.decode_block(ci, b, &mut slot.old);
            self.world.decode_block(ci, b, &mut slot.new);
            slot.written |= 1 << b;
        }
        slot.new[vi] = material;
    }
}

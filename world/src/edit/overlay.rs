//! The batch overlay: ops write into decoded copies of the chunks they touch, so the world
//! is untouched until the whole batch has succeeded.

use crate::cell::CHUNK_VOXELS;
use crate::ops::Canvas;
use crate::size::WorldSize;
use crate::world::World;
use rustc_hash::FxHashMap;
use std::cell::Cell;

/// Raw material ids of one chunk, `x + 16y + 256z`.
pub(crate) type RawChunk = Box<[u16; CHUNK_VOXELS]>;

/// A chunk a batch wrote to: its content before and after.
pub(crate) struct Touched {
    pub index: usize,
    pub old: RawChunk,
    pub new: RawChunk,
}

/// A copy-on-write view of the world's voxels for one batch.
pub(crate) struct Overlay<'w> {
    world: &'w World,
    /// Touched chunks: (chunk index, content before the batch, content now).
    chunks: Vec<(usize, RawChunk, RawChunk)>,
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

    /// The chunks whose content changed, by chunk index, ascending.
    pub(crate) fn into_touched(self) -> Vec<Touched> {
        let mut v: Vec<Touched> = self
            .chunks
            .into_iter()
            .filter(|(_, old, new)| old != new)
            .map(|(index, old, new)| Touched { index, old, new })
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
        if self.chunks.get(last).is_some_and(|c| c.0 == ci) {
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
            Some(s) => self.chunks[s].2[vi],
            None => self.world.material_at(p),
        }
    }

    #[inline]
    fn set(&mut self, p: [u32; 3], material: u16) {
        let (ci, vi) = self.split(p);
        let s = match self.slot(ci) {
            Some(s) => s,
            None => {
                let mut raw = Box::new([0u16; CHUNK_VOXELS]);
                self.world.decode_chunk(self.world.size.chunk_coords(ci), &mut raw);
                self.chunks.push((ci, raw.clone(), raw));
                let s = self.chunks.len() - 1;
                self.slots.insert(ci, s);
                self.last.set(s);
                s
            }
        };
        self.chunks[s].2[vi] = material;
    }
}

//! The batch overlay: ops write into decoded copies of the chunks they touch, so the world
//! is untouched until the whole batch has succeeded.

use crate::cell::CHUNK_VOXELS;
use crate::ops::Canvas;
use crate::size::WorldSize;
use crate::world::World;
use rustc_hash::FxHashMap;

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
    /// Per touched chunk: (content before the batch, content now).
    chunks: FxHashMap<usize, (RawChunk, RawChunk)>,
}

impl<'w> Overlay<'w> {
    pub(crate) fn new(world: &'w World) -> Self {
        Overlay {
            world,
            chunks: FxHashMap::default(),
        }
    }

    /// The chunks whose content changed, by chunk index, ascending.
    pub(crate) fn into_touched(self) -> Vec<Touched> {
        let mut v: Vec<Touched> = self
            .chunks
            .into_iter()
            .filter(|(_, (old, new))| old != new)
            .map(|(index, (old, new))| Touched { index, old, new })
            .collect();
        v.sort_unstable_by_key(|t| t.index);
        v
    }

    #[inline]
    fn split(&self, p: [u32; 3]) -> (usize, usize) {
        let ci = self.world.size.chunk_index([p[0] >> 4, p[1] >> 4, p[2] >> 4]);
        (ci, (p[0] & 15 | (p[1] & 15) << 4 | (p[2] & 15) << 8) as usize)
    }
}

impl Canvas for Overlay<'_> {
    fn size(&self) -> WorldSize {
        self.world.size
    }

    #[inline]
    fn get(&self, p: [u32; 3]) -> u16 {
        let (ci, vi) = self.split(p);
        match self.chunks.get(&ci) {
            Some((_, raw)) => raw[vi],
            None => self.world.material_at(p),
        }
    }

    #[inline]
    fn set(&mut self, p: [u32; 3], material: u16) {
        let (ci, vi) = self.split(p);
        let world = self.world;
        let (_, raw) = self.chunks.entry(ci).or_insert_with(|| {
            let mut raw = Box::new([0u16; CHUNK_VOXELS]);
            world.decode_chunk(world.size.chunk_coords(ci), &mut raw);
            (raw.clone(), raw)
        });
        raw[vi] = material;
    }
}

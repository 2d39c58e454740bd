//! A plain dense [`Canvas`]: one `u16` per voxel. The oracle of the tests, and handy for
//! tools that work on small worlds.

use super::Canvas;
use crate::size::WorldSize;

/// A dense canvas: material ids, x fastest, then y, then z.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DenseCanvas {
    size: WorldSize,
    voxels: Vec<u16>,
}

impl DenseCanvas {
    /// An empty canvas of `size` (allocates `size.voxel_count()` ids).
    pub fn new(size: WorldSize) -> Self {
        Self {
            size,
            voxels: vec![0; size.voxel_count() as usize],
        }
    }

    /// A canvas over existing ids (x fastest); `None` if the length does not match `size`.
    pub fn from_voxels(size: WorldSize, voxels: Vec<u16>) -> Option<Self> {
        (voxels.len() as u64 == size.voxel_count()).then_some(Self { size, voxels })
    }

    /// The material ids, x fastest.
    pub fn voxels(&self) -> &[u16] {
        &self.voxels
    }

    /// Consumes the canvas, returning its ids.
    pub fn into_voxels(self) -> Vec<u16> {
        self.voxels
    }

    /// Linear index of `p`: `x + y·X + z·X·Y`.
    #[inline]
    pub fn index(&self, p: [u32; 3]) -> usize {
        let s = self.size.voxels();
        p[0] as usize + s[0] as usize * (p[1] as usize + s[1] as usize * p[2] as usize)
    }
}

impl Canvas for DenseCanvas {
    fn size(&self) -> WorldSize {
        self.size
    }

    #[inline]
    fn get(&self, p: [u32; 3]) -> u16 {
        self.voxels[self.index(p)]
    }

    #[inline]
    fn set(&mut self, p: [u32; 3], material: u16) {
        let i = self.index(p);
        self.voxels[i] = material;
    }
}

//! [`Svo`]: a sparse voxel octree of ESVO-style child descriptors, without contours or
//! attachments.
//!
//! Every non-empty node of side 2 and up has a descriptor: its valid mask (bit
//! `x + 2y + 4z` per non-empty child octant) and where its children start. A side-2 node's
//! children are voxels, which have no descriptor. Nothing is shared and nothing collapses:
//! a solid region is stored node by node. The children of a node are contiguous in the
//! level below, in octant order.
//!
//! ESVO packs the valid mask, a leaf mask and a 15-bit relative child pointer (with far
//! pointers beside) into 32 bits; here the child index is a plain `u32` next to the mask,
//! which is no slower to follow. The byte count is the paper's: 4 per descriptor
//! (docs/BASELINES.md).

use super::{MAX_REFS, Step, Tree, block_masks, check_refs, cube_depth, gpu_header, mask_step, trace_tree};
use crate::WorldError;
use crate::traverse::{Hit, Ray};
use crate::world::World;
use rayon::prelude::*;

/// A sparse voxel octree of a world's static geometry.
#[derive(Clone, Debug)]
pub struct Svo {
    /// The world's size in voxels.
    size: [u32; 3],
    /// log2 of the cube's side (at least 3).
    depth: u32,
    /// Per level, from the root (side `2^depth`) down to side 2: each node's valid mask.
    masks: Vec<Vec<u8>>,
    /// Per level above the lowest: the index of each node's first child in the level below.
    first: Vec<Vec<u32>>,
}

/// Occupancy at one node size while building: whether each cell of the grid is non-empty.
struct Occupancy {
    dims: [usize; 3],
    filled: Vec<bool>,
}

impl Occupancy {
    fn get(&self, c: [usize; 3]) -> bool {
        (0..3).all(|a| c[a] < self.dims[a]) && self.filled[c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2])]
    }
}

impl Svo {
    /// Builds the octree of `world`'s static voxels (entities left out). Fails on a world
    /// with no solid voxel, or one with more nodes on a level than 32-bit indices reach.
    ///
    /// ```
    /// use naadf_world::{World, preset::Preset, baselines::Svo};
    /// let src = Preset::Test.source(None, 1).unwrap();
    /// let svo = Svo::build(&World::build(&*src, &|_| {}).unwrap()).unwrap();
    /// assert_eq!(svo.bytes() % 4, 0);
    /// ```
    pub fn build(world: &World) -> Result<Self, WorldError> {
        Self::build_within(world, MAX_REFS)
    }

    /// [`Svo::build`] with fewer than `limit` nodes per level (tests reach the limit with
    /// small worlds).
    pub(crate) fn build_within(world: &World, limit: u64) -> Result<Self, WorldError> {
        let size = world.size().voxels();
        let depth = cube_depth(size).max(3);
        let blocks = block_masks(world)?;
        let block_dims = size.map(|v| (v / 4) as usize);
        // Occupancy of the nodes of side 8 and up, built upward in parallel: grids[j] has
        // cells of side 2^(j + 3).
        let mut grids = vec![Occupancy {
            dims: block_dims.map(|d| d.div_ceil(2)),
            filled: Vec::new(),
        }];
        grids[0].filled = (0..grids[0].dims.iter().product::<usize>())
            .into_par_iter()
            .map(|i| {
                let d = grids[0].dims;
                let p = [i % d[0], i / d[0] % d[1], i / (d[0] * d[1])];
                (0..8).any(|o| {
                    let c = [0, 1, 2].map(|a| 2 * p[a] + (o >> a & 1));
                    (0..3).all(|a| c[a] < block_dims[a])
                        && blocks[c[0] + block_dims[0] * (c[1] + block_dims[1] * c[2])] != 0
                })
            })
            .collect();
        for _ in 4..depth {
            let below = grids.last().expect("one grid");
            let dims = below.dims.map(|d| d.div_ceil(2));
            let filled = (0..dims.iter().product::<usize>())
                .into_par_iter()
                .map(|i| {
                    let p = [i % dims[0], i / dims[0] % dims[1], i / (dims[0] * dims[1])];
                    (0..8).any(|o| below.get([0, 1, 2].map(|a| 2 * p[a] + (o >> a & 1))))
                })
                .collect();
            grids.push(Occupancy { dims, filled });
        }
        let mut svo = Svo {
            size,
            depth,
            masks: vec![Vec::new(); depth as usize],
            first: vec![Vec::new(); depth as usize - 1],
        };
        let block = |c: [usize; 3]| -> u64 {
            if (0..3).all(|a| c[a] < block_dims[a]) {
                blocks[c[0] + block_dims[0] * (c[1] + block_dims[1] * c[2])]
            } else {
                0
            }
        };
        svo.masks[0].push(0);
        svo.add_children(0, [0; 3], &grids, &block)?;
        for (level, masks) in svo.masks.iter().enumerate() {
            check_refs(masks.len() as u64, limit, &format!("the octree's level {level}"))?;
        }
        Ok(svo)
    }

    /// Appends the children of node `node` of `level` (at grid position `p` of its size)
    /// to the level below, then theirs, depth first.
    fn add_children(
        &mut self,
        level: usize,
        p: [usize; 3],
        grids: &[Occupancy],
        block: &dyn Fn([usize; 3]) -> u64,
    ) -> Result<(), WorldError> {
        // Side of the children: 2^(depth − level − 1).
        let k = self.depth as usize - level - 1;
        let node = self.masks[level].len() - 1;
        let child = |o: usize| [0, 1, 2].map(|a| 2 * p[a] + (o >> a & 1));
        let mask: u8 = if k == 0 {
            // A side-2 node: the voxels of its octant of the block.
            let b = block(p.map(|v| v / 2));
            let q = p.map(|v| 2 * (v % 2));
            (0..8).fold(0, |m, o| {
                let v = [0, 1, 2].map(|a| q[a] + (o >> a & 1));
                m | (((b >> (v[0] + 4 * v[1] + 16 * v[2])) & 1) as u8) << o
            })
        } else if k == 1 {
            // A block: its side-2 octants.
            let b = block(p);
            (0..8).fold(0, |m, o| {
                let q = [0, 1, 2].map(|a| 2 * (o >> a & 1));
                let octant_bits = (0..8).fold(0u64, |x, v| {
                    x | b >> ((q[0] + (v & 1)) + 4 * (q[1] + (v >> 1 & 1)) + 16 * (q[2] + (v >> 2 & 1))) & 1
                });
                m | u8::from(octant_bits != 0) << o
            })
        } else if k == 2 {
            (0..8).fold(0, |m, o| m | u8::from(block(child(o)) != 0) << o)
        } else {
            (0..8).fold(0, |m, o| m | u8::from(grids[k - 3].get(child(o))) << o)
        };
        self.masks[level][node] = mask;
        if k == 0 {
            return Ok(());
        }
        let start = self.masks[level + 1].len();
        check_refs(
            start as u64,
            MAX_REFS,
            &format!("the octree's nodes of side {}", 1u64 << k),
        )?;
        self.first[level].push(start as u32);
        // Only deeper levels grow while a child is filled in, so siblings stay contiguous.
        for o in (0..8).filter(|&o| mask >> o & 1 == 1) {
            self.masks[level + 1].push(0);
            self.add_children(level + 1, child(o), grids, block)?;
        }
        Ok(())
    }

    /// Bytes by the paper's count: 4 per descriptor, one per non-empty node of side 2 and
    /// up.
    pub fn bytes(&self) -> u64 {
        4 * self.masks.iter().map(|m| m.len() as u64).sum::<u64>()
    }

    /// The octree as one array of words for the GPU traversal (docs/BASELINES.md): the
    /// [header](super::GPU_HEADER_WORDS) (depth; the leaf level is 0, unused), then every
    /// node as two words, level by level from the root: its valid mask, and the absolute
    /// word of its first child (0 for nodes of side 2). Fails when that exceeds 32-bit
    /// offsets.
    pub fn gpu_words(&self) -> Result<Vec<u32>, WorldError> {
        self.gpu_words_within(MAX_REFS)
    }

    /// [`Svo::gpu_words`] with at most `limit` words.
    pub(crate) fn gpu_words_within(&self, limit: u64) -> Result<Vec<u32>, WorldError> {
        let nodes: usize = self.masks.iter().map(Vec::len).sum();
        let mut words = gpu_header(self.depth, 0, 2 * nodes, limit)?;
        let mut next = (words.len() + 2 * self.masks[0].len()) as u32;
        for (level, masks) in self.masks.iter().enumerate() {
            let first = self.first.get(level);
            for (i, &mask) in masks.iter().enumerate() {
                words.extend([u32::from(mask), first.map_or(0, |f| next + 2 * f[i])]);
            }
            next += 2 * self.masks.get(level + 1).map_or(0, Vec::len) as u32;
        }
        Ok(words)
    }

    /// Nodes per level, from the root (side `2^depth`) down to side 2.
    pub fn node_counts(&self) -> Vec<usize> {
        self.masks.iter().map(Vec::len).collect()
    }

    /// The first solid voxel along `ray` (material 0: the octree holds geometry only), with
    /// the voxel, face and `t` that `naadf` gives.
    pub fn trace(&self, ray: &Ray) -> Option<Hit> {
        trace_tree(self, ray)
    }
}

impl Tree for Svo {
    fn side_log(&self, level: usize) -> u32 {
        self.depth - level as u32
    }

    fn size(&self) -> [u32; 3] {
        self.size
    }

    fn step(&self, level: usize, node: u32, cell: [i64; 3]) -> Step {
        let mask = u32::from(self.masks[level][node as usize]);
        mask_step(mask, cell, self.depth - 1 - level as u32, |rank| {
            self.first[level][node as usize] + rank
        })
    }
}

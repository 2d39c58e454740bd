//! [`Svdag`]: the sparse voxel DAG (Kämpe et al.) in HashDAG's layout.
//!
//! Leaves are 4³ occupancy bitmasks (8 bytes, bit `x + 4y + 16z`). An inner node of side
//! `s ≥ 8` is a `u32` child mask (bit `x + 2y + 4z` for the child octant) followed by one
//! `u32` per non-empty child, in octant order: a word offset into the next level's array,
//! or a leaf index at the lowest inner level (side 8). Every level is deduplicated: an
//! identical subtree is stored once, so a node's children may be shared. The root is node
//! 0 of the first level.
//!
//! Bytes (docs/BASELINES.md): 8 per unique leaf plus 4·(1 + children) per unique inner
//! node.

use super::{MAX_REFS, Step, Tree, block_masks, check_refs, cube_depth, gpu_header, mask_step, trace_tree};
use crate::WorldError;
use crate::traverse::{Hit, Ray};
use crate::world::World;
use rayon::prelude::*;
use std::collections::HashMap;

/// A sparse voxel DAG of a world's static geometry.
#[derive(Clone, Debug)]
pub struct Svdag {
    /// The world's size in voxels (rays enter and leave its box, not the cube's).
    pub(super) size: [u32; 3],
    /// log2 of the cube's side (at least 3: the root is an inner node).
    pub(super) depth: u32,
    /// Inner node words per level, from the root (side `2^depth`) down to side 8.
    pub(super) levels: Vec<Vec<u32>>,
    /// The unique leaf masks.
    pub(super) leaves: Vec<u64>,
}

/// An inner node while building: its mask and up to 8 child references.
type NodeKey = [u32; 9];

impl Svdag {
    /// Builds the DAG of `world`'s static voxels (entities left out), in parallel. Fails
    /// on a world with no solid voxel.
    ///
    /// ```
    /// use naadf_world::{World, preset::Preset, baselines::Svdag};
    /// let src = Preset::Test.source(None, 1).unwrap();
    /// let dag = Svdag::build(&World::build(&*src, &|_| {}).unwrap()).unwrap();
    /// assert!(dag.bytes() > 0);
    /// ```
    pub fn build(world: &World) -> Result<Self, WorldError> {
        Self::build_within(world, MAX_REFS)
    }

    /// [`Svdag::build`] with references limited to fewer than `limit` entries (tests
    /// reach the limit with small worlds).
    pub(crate) fn build_within(world: &World, limit: u64) -> Result<Self, WorldError> {
        let size = world.size().voxels();
        let depth = cube_depth(size).max(3);
        let masks = block_masks(world)?;
        // Leaves, numbered in block order; `refs` holds each grid cell's reference (or
        // NONE) at the level being built.
        let mut leaves = Vec::new();
        let mut leaf_ids = HashMap::new();
        let mut refs: Vec<u32> = masks
            .iter()
            .map(|&m| match m {
                0 => NONE,
                m => *leaf_ids.entry(m).or_insert_with(|| {
                    leaves.push(m);
                    (leaves.len() - 1) as u32
                }),
            })
            .collect();
        check_refs(leaves.len() as u64, limit, "the SVDAG's leaves")?;
        let mut dims = size.map(|v| v / 4);
        let mut levels = Vec::new();
        for _ in 3..=depth {
            let up = dims.map(|d| d.div_ceil(2));
            let (below, d) = (&refs, dims);
            // Each parent's key in parallel; numbering (dedup) in order, so that the
            // layout is a pure function of the world.
            let keys: Vec<NodeKey> = (0..up.iter().map(|&v| v as usize).product::<usize>())
                .into_par_iter()
                .map(|i| {
                    let p = [
                        i % up[0] as usize,
                        i / up[0] as usize % up[1] as usize,
                        i / (up[0] as usize * up[1] as usize),
                    ];
                    let mut key = [NONE; 9];
                    let (mut mask, mut n) = (0u32, 1);
                    for oct in 0..8 {
                        let c = [0, 1, 2].map(|a| 2 * p[a] + (oct >> a & 1));
                        if (0..3).any(|a| c[a] >= d[a] as usize) {
                            continue;
                        }
                        let r = below[c[0] + d[0] as usize * (c[1] + d[1] as usize * c[2])];
                        if r != NONE {
                            mask |= 1 << oct;
                            key[n] = r;
                            n += 1;
                        }
                    }
                    key[0] = mask;
                    key
                })
                .collect();
            let mut words = Vec::new();
            let mut ids: HashMap<NodeKey, u32> = HashMap::new();
            refs = keys
                .iter()
                .map(|key| match key[0] {
                    0 => NONE,
                    mask => *ids.entry(*key).or_insert_with(|| {
                        let at = words.len() as u32;
                        words.extend_from_slice(&key[..1 + mask.count_ones() as usize]);
                        at
                    }),
                })
                .collect();
            // Offsets (and NONE) must fit the 32-bit references.
            check_refs(words.len() as u64, limit, "an SVDAG level's words")?;
            levels.push(words);
            dims = up;
        }
        levels.reverse();
        Ok(Svdag {
            size,
            depth,
            levels,
            leaves,
        })
    }

    /// Bytes by the paper's count: 8 per unique leaf, 4·(1 + children) per unique inner
    /// node.
    pub fn bytes(&self) -> u64 {
        8 * self.leaves.len() as u64 + 4 * self.levels.iter().map(|l| l.len() as u64).sum::<u64>()
    }

    /// The DAG as one array of words for the GPU traversal (docs/BASELINES.md): the
    /// [header](super::GPU_HEADER_WORDS) (depth, the level of the leaves), then the inner
    /// levels from the root down, then the leaves (two words each, low half first). A
    /// reference is rewritten to the absolute word of its node or leaf. Fails when that
    /// exceeds 32-bit offsets.
    pub fn gpu_words(&self) -> Result<Vec<u32>, WorldError> {
        self.gpu_words_within(MAX_REFS)
    }

    /// [`Svdag::gpu_words`] with at most `limit` words.
    pub(crate) fn gpu_words_within(&self, limit: u64) -> Result<Vec<u32>, WorldError> {
        let inner: usize = self.levels.iter().map(Vec::len).sum();
        let mut words = gpu_header(
            self.depth,
            self.levels.len() as u32,
            inner + 2 * self.leaves.len(),
            limit,
        )?;
        // Where each level, and the leaves, start.
        let mut base = Vec::with_capacity(self.levels.len() + 1);
        let mut at = words.len() as u32;
        for level in &self.levels {
            base.push(at);
            at += level.len() as u32;
        }
        base.push(at);
        for (l, level) in self.levels.iter().enumerate() {
            let stride = if l + 1 == self.levels.len() { 2 } else { 1 };
            let mut i = 0;
            while i < level.len() {
                let mask = level[i];
                words.push(mask);
                let children = mask.count_ones() as usize;
                words.extend(level[i + 1..i + 1 + children].iter().map(|&r| base[l + 1] + stride * r));
                i += 1 + children;
            }
        }
        for &leaf in &self.leaves {
            words.extend([leaf as u32, (leaf >> 32) as u32]);
        }
        Ok(words)
    }

    /// Unique leaves and unique inner nodes per level (root first).
    pub fn node_counts(&self) -> (usize, Vec<usize>) {
        let nodes = self
            .levels
            .iter()
            .map(|words| {
                let mut n = 0;
                let mut at = 0;
                while at < words.len() {
                    at += 1 + words[at].count_ones() as usize;
                    n += 1;
                }
                n
            })
            .collect();
        (self.leaves.len(), nodes)
    }

    /// The first solid voxel along `ray` (material 0: the DAG holds geometry only), with
    /// the voxel, face and `t` that `naadf` gives.
    pub fn trace(&self, ray: &Ray) -> Option<Hit> {
        trace_tree(self, ray)
    }
}

impl Tree for Svdag {
    fn side_log(&self, level: usize) -> u32 {
        self.depth - level as u32
    }

    fn size(&self) -> [u32; 3] {
        self.size
    }

    /// Inner levels hold word offsets (leaf indices below side 8); the level below them
    /// holds the leaves.
    fn step(&self, level: usize, node: u32, cell: [i64; 3]) -> Step {
        if level == self.levels.len() {
            let bit = (cell[0] & 3) + 4 * (cell[1] & 3) + 16 * (cell[2] & 3);
            return match self.leaves[node as usize] >> bit & 1 {
                1 => Step::Solid,
                _ => Step::Empty(0),
            };
        }
        // Inner nodes have children of side 8 or more: never a voxel.
        let words = &self.levels[level][node as usize..];
        mask_step(words[0], cell, self.depth - 1 - level as u32, |rank| {
            words[1 + rank as usize]
        })
    }
}

/// No child: an empty cell of the grid being built.
const NONE: u32 = u32::MAX;

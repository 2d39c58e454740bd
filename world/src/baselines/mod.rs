//! The structures the paper compares NAADF with, built from any world: geometry only (the
//! static solid voxels; entities and materials are left out), in a cube of side `2^k` at the
//! world's origin corner, padded with empty space (docs/BASELINES.md).
//!
//! - [`Svdag`]: the sparse voxel DAG of Kämpe et al. in HashDAG's layout: 4³ bitmask
//!   leaves and 2³ inner nodes, identical subtrees stored once per level.
//! - [`Svo`]: a sparse voxel octree of ESVO-style child descriptors (no contours), one per
//!   non-empty node of side 2 and up, nothing shared.
//!
//! Each traverses with the event model every method shares (`traverse/ray.rs`): it skips
//! only empty nodes, so its first hit (voxel, face, `t`) is the one `naadf` finds.

mod svdag;
mod svo;

pub use svdag::Svdag;
pub use svo::Svo;

use crate::WorldError;
use crate::cell::{self, State};
use crate::traverse::{Hit, Ray};
use crate::world::World;
use rayon::prelude::*;

/// The most cells a trace visits: far more than any ray crosses, a guard against loops.
const MAX_STEPS: u32 = 1 << 24;

/// What a tree holds at a cell, one level down from a node.
pub(crate) enum Step {
    /// The child node (an index or offset the tree understands) at the next level.
    Node(u32),
    /// The cell lies in an empty cube of side `2^k` (aligned to its side).
    Empty(u32),
    /// The cell is a solid voxel.
    Solid,
}

/// A tree over the cube of side `2^depth`: the root is node 0 of level 0, and a level-`l`
/// node has side `2^(depth − l)`.
pub(crate) trait Tree {
    /// log2 of the cube's side.
    fn depth(&self) -> u32;
    /// The world's size in voxels: rays enter and leave its box, not the cube's.
    fn size(&self) -> [u32; 3];
    /// What `node` of `level` holds at `cell` (inside it).
    fn step(&self, level: usize, node: u32, cell: [i64; 3]) -> Step;
}

/// The first solid voxel of `tree` along `ray` (material 0: the trees hold geometry
/// only). The walk keeps the path from the root to the current cell; after each step it
/// climbs only as far as the cell it entered leaves that path, then descends to an empty
/// cube (left whole, with the event model every method shares) or a solid voxel.
pub(crate) fn trace_tree(tree: &impl Tree, ray: &Ray) -> Option<Hit> {
    let size = tree.size();
    let depth = tree.depth();
    let entry = ray.entry(size)?;
    let (mut cell, mut t, mut axis) = (entry.cell, entry.t, entry.axis);
    let neg = ray.dir().map(|d| d <= 0.0);
    // path[l]: the level-l node holding `cell`, for l < valid.
    let mut path = [0u32; 33];
    let mut valid = 1;
    let mut steps = 0u32;
    loop {
        steps += 1;
        if steps > MAX_STEPS {
            return None;
        }
        let mut l = valid - 1;
        let empty = loop {
            match tree.step(l, path[l], cell) {
                Step::Node(child) => {
                    l += 1;
                    path[l] = child;
                }
                Step::Empty(k) => break k,
                Step::Solid => return Some(ray.hit(cell, t, axis, 0, steps)),
            }
        };
        valid = l + 1;
        let side = 1i64 << empty;
        let skip = std::array::from_fn(|a| {
            let inside = cell[a] & (side - 1);
            if neg[a] { inside } else { side - 1 - inside }
        });
        let (nt, na, next) = ray.exit(cell, skip);
        if !(0..3).all(|a| next[a] >= 0 && next[a] < i64::from(size[a])) {
            return None;
        }
        // The levels whose node still holds the new cell: those of a side above the
        // highest bit in which the two cells differ.
        let differ = (0..3).fold(0, |d, a| d | (cell[a] ^ next[a]));
        let common = (depth as usize).saturating_sub(64 - differ.leading_zeros() as usize);
        valid = valid.min(common.max(1));
        (cell, t, axis) = (next, nt, Some(na));
    }
}

/// The octant (bit `x + 2y + 4z`) of `cell` in a node whose children have side `2^k`.
#[inline(always)]
pub(crate) fn octant(cell: [i64; 3], k: u32) -> u32 {
    (0..3).fold(0, |o, a| o | (((cell[a] >> k) & 1) as u32) << a)
}

/// The 4³ occupancy of every block of `world`, a bitmask (bit `x + 4y + 16z`), block
/// `bx + nx·(by + ny·bz)` of the `dims / 4` block grid. Fails on a world with no solid
/// voxel.
pub(crate) fn block_masks(world: &World) -> Result<Vec<u64>, WorldError> {
    let dims = world.size().voxels().map(|v| (v / 4) as usize);
    let chunks = world.size().chunks().map(|v| v as usize);
    // One chunk layer (4 block planes) per task: disjoint slices of the output.
    let mut masks = vec![0u64; dims[0] * dims[1] * dims[2]];
    masks
        .par_chunks_mut(dims[0] * dims[1] * 4)
        .enumerate()
        .for_each(|(cz, slab)| {
            for cy in 0..chunks[1] {
                for cx in 0..chunks[0] {
                    let c = world.chunks()[cx + chunks[0] * (cy + chunks[1] * cz)];
                    for b in 0..cell::CELLS {
                        let (bx, by, bz) = (b % 4, b / 4 % 4, b / 16);
                        let at = 4 * cx + bx + dims[0] * (4 * cy + by + dims[1] * bz);
                        slab[at] = match cell::state(c) {
                            State::Empty => 0,
                            State::Full => u64::MAX,
                            State::Mixed => cell_mask(world, world.blocks()[cell::pointer(c) as usize + b]),
                        };
                    }
                }
            }
        });
    if masks.iter().all(|&m| m == 0) {
        return Err(WorldError::Capacity(
            "the world has no solid voxel to build a structure of".into(),
        ));
    }
    Ok(masks)
}

/// The 4³ occupancy of a block cell.
fn cell_mask(world: &World, block: u32) -> u64 {
    match cell::state(block) {
        State::Empty => 0,
        State::Full => u64::MAX,
        State::Mixed => {
            let ptr = cell::pointer(block) as usize;
            (0..cell::CELLS).fold(0, |m, i| {
                m | (u64::from(cell::voxel_is_solid(cell::group_voxel(world.voxels(), ptr, i))) << i)
            })
        }
    }
}

/// log2 of the side of the smallest cube that holds `dims`.
pub(crate) fn cube_depth(dims: [u32; 3]) -> u32 {
    dims.iter()
        .map(|d| d.next_power_of_two().trailing_zeros())
        .max()
        .unwrap_or(0)
}

//! The structures the paper compares NAADF with, built from any world: geometry only (the
//! static solid voxels; entities and materials are left out), in a cube of side `2^k` at the
//! world's origin corner, padded with empty space (docs/BASELINES.md).
//!
//! - [`Svdag`]: the sparse voxel DAG of Kämpe et al. in HashDAG's layout: 4³ bitmask
//!   leaves and 2³ inner nodes, identical subtrees stored once per level.
//! - [`Svo`]: a sparse voxel octree of ESVO-style child descriptors (no contours), one per
//!   non-empty node of side 2 and up, nothing shared.
//! - [`Hybrid`]: a hybrid format `R(W³) G(L)` of the hybrid-voxel-formats paper: a raw
//!   grid over SVDAGs that go down to single voxels, derived from an [`Svdag`].
//!
//! Each traverses with the event model every method shares (`traverse/ray.rs`): it skips
//! only empty nodes, so its first hit (voxel, face, `t`) is the one `naadf` finds.

mod hybrid;
mod svdag;
mod svo;

pub use hybrid::{Hybrid, HybridFormat};
pub use svdag::Svdag;
pub use svo::Svo;

use crate::WorldError;
use crate::cell::{self, State};
use crate::traverse::{Hit, Ray};
use crate::world::World;
use rayon::prelude::*;

/// The most cells a trace visits: far more than any ray crosses, a guard against loops.
const MAX_STEPS: u32 = 1 << 24;

/// Words before the first node in a tree's GPU layout ([`Svdag::gpu_words`],
/// [`Svo::gpu_words`], [`Hybrid::gpu_words`]): log2 of the cube's side, the structure's
/// shape word (the level of the SVDAG's leaves, 0 for the SVO, the depth `L` of a hybrid
/// format's DAGs), and two reserved words. The root node starts right after them.
pub const GPU_HEADER_WORDS: usize = 4;

/// The most words a 32-bit reference (an offset, an index, or a count of them) may
/// address: `u32::MAX` itself marks "no child" while a DAG is built.
pub(crate) const MAX_REFS: u64 = u32::MAX as u64;

/// Checks that `count` words (or nodes, or leaves) stay within `limit` references, and
/// names `what` in the error.
pub(crate) fn check_refs(count: u64, limit: u64, what: &str) -> Result<(), WorldError> {
    if count >= limit {
        return Err(WorldError::Capacity(format!(
            "{what}: {count} entries are beyond the 32-bit references of the structure (fewer than {limit})"
        )));
    }
    Ok(())
}

/// The header of a tree's GPU layout, with room for `body` more words; fails when the
/// layout would exceed `limit` words (its offsets are 32-bit).
fn gpu_header(depth: u32, leaf_level: u32, body: usize, limit: u64) -> Result<Vec<u32>, WorldError> {
    let total = (GPU_HEADER_WORDS + body) as u64;
    check_refs(total, limit, "a GPU layout's words")?;
    let mut words = Vec::with_capacity(total as usize);
    words.extend([depth, leaf_level, 0, 0]);
    Ok(words)
}

/// What a tree holds at a cell, one level down from a node.
pub(crate) enum Step {
    /// The child node (an index or offset the tree understands) at the next level.
    Node(u32),
    /// The cell lies in an empty cube of side `2^k` (aligned to its side).
    Empty(u32),
    /// The cell is a solid voxel.
    Solid,
}

/// A tree over a cube: the root is node 0 of level 0, and every node of a level has the
/// same side, a power of two that shrinks level by level.
pub(crate) trait Tree {
    /// log2 of the side of a `level` node.
    fn side_log(&self, level: usize) -> u32;
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
        // The levels whose node still holds the new cell: those whose side reaches past
        // the highest bit in which the two cells differ (the root always does).
        let differ = (0..3).fold(0, |d, a| d | (cell[a] ^ next[a]));
        let bits = 64 - differ.leading_zeros();
        while valid > 1 && tree.side_log(valid - 1) < bits {
            valid -= 1;
        }
        (cell, t, axis) = (next, nt, Some(na));
    }
}

/// What a node with child mask `mask` holds at `cell`, its children of side `2^k`: an empty
/// cube, a solid voxel (`k` = 0), or a child, which `child` finds from its rank among the
/// set bits (each layout stores its children its own way).
#[inline(always)]
pub(crate) fn mask_step(mask: u32, cell: [i64; 3], k: u32, child: impl FnOnce(u32) -> u32) -> Step {
    let oct = octant(cell, k);
    if mask >> oct & 1 == 0 {
        Step::Empty(k)
    } else if k == 0 {
        Step::Solid
    } else {
        Step::Node(child((mask & ((1 << oct) - 1)).count_ones()))
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::preset::Preset;

    fn world() -> World {
        World::build(&*Preset::Test.source(None, 1).unwrap(), &|_| {}).unwrap()
    }

    /// The 32-bit reference limits, reached with a small world by lowering them: one entry
    /// short of what the structure needs fails with a clear error, the exact need builds.
    #[test]
    fn structures_beyond_their_reference_limits_are_refused() {
        let w = world();
        let dag = Svdag::build(&w).unwrap();
        let (leaves, nodes) = dag.node_counts();
        let widest = dag.levels.iter().map(Vec::len).max().unwrap().max(leaves) as u64;
        let err = Svdag::build_within(&w, widest).unwrap_err().to_string();
        assert!(err.contains("32-bit references"), "{err}");
        assert!(Svdag::build_within(&w, widest + 1).is_ok());
        assert!(nodes.iter().all(|&n| n > 0));

        let words = dag.gpu_words().unwrap();
        let need = words.len() as u64;
        assert!(
            dag.gpu_words_within(need)
                .unwrap_err()
                .to_string()
                .contains("GPU layout")
        );
        assert_eq!(dag.gpu_words_within(need + 1).unwrap(), words);

        let svo = Svo::build(&w).unwrap();
        let widest = *svo.node_counts().iter().max().unwrap() as u64;
        assert!(
            Svo::build_within(&w, widest)
                .unwrap_err()
                .to_string()
                .contains("octree")
        );
        assert!(Svo::build_within(&w, widest + 1).is_ok());
        let words = svo.gpu_words().unwrap();
        assert_eq!(
            words.len(),
            GPU_HEADER_WORDS + 2 * svo.node_counts().iter().sum::<usize>()
        );
        assert!(svo.gpu_words_within(words.len() as u64).is_err());

        let hybrid = Hybrid::build(&dag, 2, 5).unwrap();
        let need = hybrid.gpu_words().len() as u64;
        assert_eq!(need, hybrid.bytes() / 4 + GPU_HEADER_WORDS as u64);
        let err = Hybrid::build_within(&dag, 2, 5, need).unwrap_err().to_string();
        assert!(err.contains("hybrid format's words"), "{err}");
        assert_eq!(
            Hybrid::build_within(&dag, 2, 5, need + 1).unwrap().bytes(),
            hybrid.bytes()
        );
    }

    /// The GPU layouts walk to the same answers as the trees: a CPU walk of the flat words,
    /// written the way the shaders read them, agrees with [`trace_tree`] at every voxel.
    #[test]
    fn gpu_layouts_hold_the_trees() {
        let w = world();
        let size = w.size().voxels();
        let dag = Svdag::build(&w).unwrap();
        let svo = Svo::build(&w).unwrap();
        let (dw, sw) = (dag.gpu_words().unwrap(), svo.gpu_words().unwrap());
        // Descends from the root to the voxel: solid or not, as the shaders do.
        let solid = |words: &[u32], dag: bool, p: [i64; 3]| -> bool {
            let (depth, leaf_level) = (words[0], words[1] as usize);
            let mut node = GPU_HEADER_WORDS as u32;
            for level in 0.. {
                if dag && level == leaf_level {
                    let bit = (p[0] & 3) + 4 * (p[1] & 3) + 16 * (p[2] & 3);
                    let leaf = u64::from(words[node as usize]) | u64::from(words[node as usize + 1]) << 32;
                    return leaf >> bit & 1 == 1;
                }
                let k = depth - 1 - level as u32;
                let (mask, oct) = (words[node as usize], octant(p, k));
                if mask >> oct & 1 == 0 {
                    return false;
                }
                let rank = (mask & ((1 << oct) - 1)).count_ones();
                if !dag && k == 0 {
                    return true;
                }
                node = if dag {
                    words[(node + 1 + rank) as usize]
                } else {
                    words[node as usize + 1] + 2 * rank
                };
            }
            unreachable!()
        };
        let mut solids = 0;
        for z in 0..i64::from(size[2]) {
            for y in 0..i64::from(size[1]) {
                for x in 0..i64::from(size[0]) {
                    let want = w.material_at([x as u32, y as u32, z as u32]) != 0;
                    solids += usize::from(want);
                    assert_eq!(solid(&dw, true, [x, y, z]), want, "svdag at {x},{y},{z}");
                    assert_eq!(solid(&sw, false, [x, y, z]), want, "svo at {x},{y},{z}");
                }
            }
        }
        assert!(solids > 0);
    }
}

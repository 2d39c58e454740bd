//! The structures the paper compares NAADF with, built from any world: geometry only (the
//! static solid voxels; entities and materials are left out), in a cube of side `2^k` at the
//! world's origin corner, padded with empty space (docs/BASELINES.md).
//!
//! - [`Svdag`]: the sparse voxel DAG of Kämpe et al. in HashDAG's layout: 4³ bitmask
//!   leaves and 2³ inner nodes, identical subtrees stored once per level.
//!
//! Each traverses with the event model every method shares (`traverse/ray.rs`): it skips
//! only empty nodes, so its first hit (voxel, face, `t`) is the one `naadf` finds.

mod svdag;

pub use svdag::Svdag;

use crate::WorldError;
use crate::cell::{self, State};
use crate::world::World;
use rayon::prelude::*;

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

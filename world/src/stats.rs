//! Size and content statistics of a world (what `naadf info` prints).

use crate::cell::{self, State};
use crate::world::World;
use rayon::prelude::*;
use serde::Serialize;

/// Bytes held by each buffer.
#[derive(Clone, Copy, Debug, Serialize, PartialEq, Eq)]
pub struct Bytes {
    /// Chunk cells plus chunk entity fields (8 bytes per chunk).
    pub chunks: u64,
    /// Block cells (4 bytes each).
    pub blocks: u64,
    /// Voxel words (4 bytes per two voxels).
    pub voxels: u64,
    /// Material table (16 bytes per entry).
    pub materials: u64,
    /// Sum of the above.
    pub total: u64,
}

/// What `naadf info --json` prints.
#[derive(Clone, Debug, Serialize, PartialEq, Eq)]
pub struct WorldStats {
    /// Size in voxels.
    pub size: [u32; 3],
    /// Solid voxels.
    pub solid_voxels: u64,
    /// Chunk cells.
    pub chunks: u64,
    /// Block cells in live block arrays (64 per mixed chunk).
    pub blocks: u64,
    /// Live (distinct) voxel groups.
    pub voxel_groups: u64,
    /// Buffer sizes.
    pub bytes: Bytes,
    /// World digest, 16 hex digits.
    pub digest: String,
}

impl WorldStats {
    /// Gathers the statistics of `world`.
    pub fn of(world: &World) -> Self {
        let blocks = world.blocks();
        let voxels = world.voxels();
        let solid_voxels = world
            .chunks()
            .par_iter()
            .map(|&c| match cell::state(c) {
                State::Empty => 0,
                State::Full => 4096,
                State::Mixed => blocks[cell::pointer(c) as usize..][..64]
                    .iter()
                    .map(|&b| match cell::state(b) {
                        State::Empty => 0,
                        State::Full => 64,
                        State::Mixed => voxels[cell::pointer(b) as usize..][..32]
                            .iter()
                            .map(|&w| u64::from(w >> 15 & 1) + u64::from(w >> 31))
                            .sum(),
                    })
                    .sum(),
            })
            .sum();
        let mixed_chunks = world
            .chunks()
            .iter()
            .filter(|&&c| cell::state(c) == State::Mixed)
            .count() as u64;
        let bytes_of = |n: usize| 4 * n as u64;
        let chunks_b = bytes_of(world.chunks().len() + world.chunk_entities().len());
        let blocks_b = bytes_of(blocks.len());
        let voxels_b = bytes_of(voxels.len());
        let materials_b = bytes_of(world.materials().words().len());
        WorldStats {
            size: world.size().voxels(),
            solid_voxels,
            chunks: world.chunks().len() as u64,
            blocks: 64 * mixed_chunks,
            voxel_groups: world.groups().live_groups() as u64,
            bytes: Bytes {
                chunks: chunks_b,
                blocks: blocks_b,
                voxels: voxels_b,
                materials: materials_b,
                total: chunks_b + blocks_b + voxels_b + materials_b,
            },
            digest: world.digest().to_string(),
        }
    }
}

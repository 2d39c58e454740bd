//! The dense-grid oracle: Amanatides–Woo over a full decode of the world.

use super::ray::{Hit, Ray};
use crate::cell::CHUNK_VOXELS;
use crate::error::WorldError;
use crate::world::World;
use rayon::prelude::*;

/// Largest dense decode this will allocate (8 GiB of `u16`).
pub const MAX_DENSE_VOXELS: u64 = 1 << 32;

/// Material ids of every voxel, x fastest, then y, then z.
pub struct DenseGrid {
    size: [u32; 3],
    voxels: Vec<u16>,
}

impl DenseGrid {
    /// Decodes `world` densely. Fails if it has more than [`MAX_DENSE_VOXELS`] voxels.
    pub fn from_world(world: &World) -> Result<Self, WorldError> {
        let n = world.size().voxel_count();
        if n > MAX_DENSE_VOXELS {
            return Err(WorldError::Capacity(format!(
                "a dense decode of {} voxels ({} GiB) is too large for the grid method",
                n,
                (n * 2) >> 30
            )));
        }
        let size = world.size().voxels();
        let [sx, sy, _] = size.map(|v| v as usize);
        let [cx, cy, _] = world.size().chunks();
        let mut voxels = vec![0u16; n as usize];
        // One z-slab of 16 planes per task: disjoint slices of the output.
        voxels.par_chunks_mut(sx * sy * 16).enumerate().for_each(|(cz, slab)| {
            let mut raw = [0u16; CHUNK_VOXELS];
            for cyy in 0..cy {
                for cxx in 0..cx {
                    world.decode_chunk([cxx, cyy, cz as u32], &mut raw);
                    for lz in 0..16 {
                        for ly in 0..16 {
                            let dst = cxx as usize * 16 + sx * (cyy as usize * 16 + ly + sy * lz);
                            slab[dst..dst + 16].copy_from_slice(&raw[256 * lz + 16 * ly..][..16]);
                        }
                    }
                }
            }
        });
        Ok(Self { size, voxels })
    }

    /// Material at `p` (inside the grid).
    #[inline]
    pub fn get(&self, p: [u32; 3]) -> u16 {
        let [sx, sy, _] = self.size.map(|v| v as usize);
        self.voxels[p[0] as usize + sx * (p[1] as usize + sy * p[2] as usize)]
    }

    /// Traces `ray` one voxel at a time.
    pub fn trace(&self, ray: &Ray) -> Option<Hit> {
        let entry = ray.entry(self.size)?;
        let (mut cell, mut t, mut axis) = (entry.cell, entry.t, entry.axis);
        let d = ray.dir();
        let step: [i64; 3] = d.map(|v| if v > 0.0 { 1 } else { -1 });
        let next_plane = |c: i64, a: usize| if d[a] > 0.0 { c + 1 } else { c };
        let mut tmax: [f64; 3] = std::array::from_fn(|a| {
            if d[a] == 0.0 {
                f64::INFINITY
            } else {
                ray.t_at(a, next_plane(cell[a], a))
            }
        });
        let size = self.size.map(i64::from);
        let mut steps = 0u32;
        loop {
            steps += 1;
            let m = self.get(cell.map(|v| v as u32));
            if m != 0 {
                return Some(ray.hit(cell, t, axis, m, steps));
            }
            let mut a = 0;
            if tmax[1] < tmax[a] {
                a = 1;
            }
            if tmax[2] < tmax[a] {
                a = 2;
            }
            t = tmax[a];
            cell[a] += step[a];
            axis = Some(a);
            if cell[a] < 0 || cell[a] >= size[a] {
                return None;
            }
            tmax[a] = ray.t_at(a, next_plane(cell[a], a));
        }
    }
}

//! The dense-grid oracle: Amanatides–Woo over a full decode of the world.

use super::entities::{OpenPart, OwnedEntities, WorldPart};
use super::ray::{End, Hit, Ray, Visit, walk};
use crate::error::WorldError;
use crate::world::World;
use rayon::prelude::*;

/// Largest dense decode this will allocate (8 GiB of `u16`).
pub const MAX_DENSE_VOXELS: u64 = 1 << 32;

/// Material ids of every voxel, x fastest, then y, then z.
pub struct DenseGrid {
    size: [u32; 3],
    voxels: Vec<u16>,
    /// A copy of the world's entity buffers (`None` when it has no entities).
    entities: Option<OwnedEntities>,
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
        let mut voxels = vec![0u16; n as usize];
        // One chunk layer (16 planes) per task: disjoint slices of the output.
        voxels
            .par_chunks_mut(sx * sy * 16)
            .enumerate()
            .for_each(|(cz, slab)| world.decode_slab(cz as u32, slab));
        Ok(Self {
            size,
            voxels,
            entities: OwnedEntities::of(world),
        })
    }

    /// The grid without its copy of the entities: rays see the static world alone.
    pub fn static_only(self) -> Self {
        DenseGrid { entities: None, ..self }
    }

    /// Material at `p` (inside the grid).
    #[inline]
    pub fn get(&self, p: [u32; 3]) -> u16 {
        let [sx, sy, _] = self.size.map(|v| v as usize);
        self.voxels[p[0] as usize + sx * (p[1] as usize + sy * p[2] as usize)]
    }

    /// Traces `ray` one voxel at a time, then against the entities whose boxes it crosses
    /// (as every method does: see [`crate::entity`]).
    pub fn trace(&self, ray: &Ray) -> Option<Hit> {
        let part = self.world_part(ray);
        match &self.entities {
            Some(ents) => ents.view().resolve(ray, part),
            None => match part {
                WorldPart::Done(hit) | WorldPart::Open(OpenPart { world: hit, .. }) => hit,
            },
        }
    }

    /// [`DenseGrid::trace`] for each of `rays`, the instance test made for all at once.
    pub fn trace_many(&self, rays: &[Ray]) -> Vec<Option<Hit>> {
        match &self.entities {
            Some(ents) => ents.view().resolve_many(rays, |r| self.world_part(r)),
            None => rays.iter().map(|r| self.trace(r)).collect(),
        }
    }

    /// The walk through the grid: its hit and the ray's span in the world.
    fn world_part(&self, ray: &Ray) -> WorldPart {
        let Some(walk) = walk(ray, self.size, |cell, _| match self.get(cell.map(|v| v as u32)) {
            0 => Visit::Empty,
            m => Visit::Solid(m),
        }) else {
            return WorldPart::Done(None);
        };
        let (world, t_end, steps) = match walk.end {
            End::Hit(h) => (Some(h), h.t, h.steps),
            End::Left { t, steps } | End::Stopped { t, steps } => (None, t, steps),
        };
        WorldPart::Open(OpenPart {
            world,
            t_entry: walk.entry_t,
            t_end,
            steps,
        })
    }
}

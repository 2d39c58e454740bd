//! The dense-grid oracle: Amanatides–Woo over a full decode of the world.

use super::entities::{Candidates, OwnedEntities};
use super::ray::{Hit, Ray};
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

    /// Material at `p` (inside the grid).
    #[inline]
    pub fn get(&self, p: [u32; 3]) -> u16 {
        let [sx, sy, _] = self.size.map(|v| v as usize);
        self.voxels[p[0] as usize + sx * (p[1] as usize + sy * p[2] as usize)]
    }

    /// Traces `ray` one voxel at a time, then against the entities of the chunks it
    /// passed (see [`crate::entity`]).
    pub fn trace(&self, ray: &Ray) -> Option<Hit> {
        let Some(ents) = &self.entities else {
            let walk = walk(ray, self.size, |cell, _| match self.get(cell.map(|v| v as u32)) {
                0 => Visit::Empty,
                m => Visit::Solid(m),
            })?;
            return match walk.end {
                End::Hit(h) => Some(h),
                _ => None,
            };
        };
        let view = ents.view();
        let mut fields = Candidates::default();
        let walk = walk(ray, self.size, |cell, _| {
            let c = cell.map(|v| (v >> 4) as u32);
            fields.push(view.field(c));
            match self.get(cell.map(|v| v as u32)) {
                0 => Visit::Empty,
                m => Visit::Solid(m),
            }
        })?;
        let (world, t_end, steps) = match walk.end {
            End::Hit(h) => (Some(h), h.t, h.steps),
            End::Left { t, steps } | End::Stopped { t, steps } => (None, t, steps),
        };
        view.resolve(ray, world, walk.entry_t, t_end, steps, &fields)
    }
}

/// What a walk found in a cell.
pub(crate) enum Visit {
    /// Nothing: keep going.
    Empty,
    /// A solid cell of this material: the walk ends with a hit.
    Solid(u16),
    /// Stop here without a hit.
    Stop,
}

/// How a walk ended.
pub(crate) enum End {
    /// A solid cell.
    Hit(Hit),
    /// The ray left the grid at time `t`.
    Left { t: f64, steps: u32 },
    /// The visitor stopped it in a cell entered at time `t`.
    Stopped { t: f64, steps: u32 },
}

/// A finished walk.
pub(crate) struct Walk {
    /// When the ray entered the grid (0 for an origin inside).
    pub entry_t: f64,
    /// How it ended.
    pub end: End,
}

/// Amanatides–Woo through the grid `[0, size)` in the event order of [`super::ray`]:
/// `visit(cell, t)` sees every cell the ray passes, with the time it is entered, until it
/// reports a solid cell or asks to stop, or the ray leaves. `None` if the ray misses the
/// grid. Serves both the world's dense decode and entity grids.
pub(crate) fn walk(ray: &Ray, size: [u32; 3], mut visit: impl FnMut([i64; 3], f64) -> Visit) -> Option<Walk> {
    let entry = ray.entry(size)?;
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
    let size = size.map(i64::from);
    let mut steps = 0u32;
    let end = loop {
        steps += 1;
        match visit(cell, t) {
            Visit::Empty => {}
            Visit::Solid(m) => break End::Hit(ray.hit(cell, t, axis, m, steps)),
            Visit::Stop => break End::Stopped { t, steps },
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
            break End::Left { t, steps };
        }
        tmax[a] = ray.t_at(a, next_plane(cell[a], a));
    };
    Some(Walk { entry_t: entry.t, end })
}

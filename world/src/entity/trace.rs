//! Ray tests against entities (NAADF-REFERENCE §3.4), shared by every traversal method.
//!
//! The world loop of a method records the entity fields of the chunks it visits, up to
//! its world hit or to where the ray leaves the world. Every method visits at least one
//! cell of every non-free chunk the ray passes (chunks with entities are never free, so no
//! AADF box covers them), so all methods record the same fields. Then each listed instance
//! is tested in its own frame with the decoded record: `o' = R⁻¹(o − pos)`, `d' = R⁻¹ d`
//! (a rotation, so `t` is the world distance), by the same event-model DDA as the grid
//! method ([`crate::traverse::grid`]) over the entity's dense grid.
//!
//! An entity hit counts when the entity voxel is entered inside the world: at `t` no
//! earlier than where the ray enters the world (parts of an entity outside the world are
//! clipped) and strictly before the world hit (ties go to the world) or before the ray
//! leaves the world. The nearest hit wins; among entity hits at the same `t`, the lowest
//! id. An entity hit reports entity-local voxel and normal.
//!
//! Instances are tested in the order the ray met their chunks, each first against a ball
//! around its local-origin corner (no transform needed), so that a near hit makes the
//! remaining tests cheap.

use super::ENTITY_SOLID;
use super::pack::{InstanceRecord, RECORD_WORDS, rotate};
use crate::traverse::grid::{End, Visit, walk};
use crate::traverse::{Hit, Ray};
use crate::world::World;

/// The entity fields met by a world loop (each run of equal fields once).
#[derive(Default)]
pub(crate) struct Candidates {
    fields: Vec<u32>,
}

impl Candidates {
    /// Records a chunk's entity field (0 = none).
    #[inline]
    pub fn push(&mut self, field: u32) {
        if field != 0 && self.fields.last() != Some(&field) {
            self.fields.push(field);
        }
    }
}

/// The entity buffers a ray test reads.
#[derive(Clone, Copy)]
pub(crate) struct EntityView<'a> {
    dims: [u32; 3],
    chunk_entities: &'a [u32],
    instances: &'a [u32],
    voxels: &'a [u32],
}

/// An owned copy of a world's entity buffers (for the dense-grid method).
pub(crate) struct OwnedEntities {
    dims: [u32; 3],
    chunk_entities: Vec<u32>,
    instances: Vec<u32>,
    voxels: Vec<u32>,
}

impl OwnedEntities {
    /// A copy of `world`'s entity buffers, or `None` if no chunk lists an entity.
    pub fn of(world: &World) -> Option<Self> {
        let v = world.entity_view()?;
        Some(OwnedEntities {
            dims: v.dims,
            chunk_entities: v.chunk_entities.to_vec(),
            instances: v.instances.to_vec(),
            voxels: v.voxels.to_vec(),
        })
    }

    pub fn view(&self) -> EntityView<'_> {
        EntityView {
            dims: self.dims,
            chunk_entities: &self.chunk_entities,
            instances: &self.instances,
            voxels: &self.voxels,
        }
    }
}

impl<'a> EntityView<'a> {
    pub fn new(dims: [u32; 3], chunk_entities: &'a [u32], instances: &'a [u32], voxels: &'a [u32]) -> Self {
        EntityView {
            dims,
            chunk_entities,
            instances,
            voxels,
        }
    }

    /// The entity field of chunk `c` (chunk coordinates inside the world).
    #[inline]
    pub fn field(&self, c: [u32; 3]) -> u32 {
        let d = self.dims.map(|v| v as usize);
        self.chunk_entities[c[0] as usize + d[0] * (c[1] as usize + d[1] * c[2] as usize)]
    }

    /// The final result of a trace: `world` (the world loop's hit, if any, ending at
    /// `t_end`; else `t_end` is where the ray left the world), or a nearer entity hit among
    /// the instances listed in `fields`. `t_entry` is when the ray entered the world and
    /// `steps` the cells the world loop visited; the entity cells visited are added.
    pub fn resolve(
        &self,
        ray: &Ray,
        world: Option<Hit>,
        t_entry: f64,
        t_end: f64,
        mut steps: u32,
        fields: &Candidates,
    ) -> Option<Hit> {
        if fields.fields.is_empty() {
            return world;
        }
        // The listed instances, once each, in the order the ray met them: near hits come
        // first, and lower the limit that rejects the others cheaply.
        let mut listed: Vec<(u32, usize)> = Vec::new();
        for &f in &fields.fields {
            let (ptr, count) = ((f >> 8) as usize, (f & 0xFF) as usize);
            for r in ptr..ptr + count {
                let at = r * RECORD_WORDS;
                if let Some(w) = self.instances.get(at..at + RECORD_WORDS) {
                    listed.push((w[4] & 0x3FFF, at));
                }
            }
        }
        if listed.len() > 1 {
            let mut order: Vec<(u32, usize)> = listed.iter().enumerate().map(|(k, e)| (e.0, k)).collect();
            order.sort_unstable();
            order.dedup_by_key(|e| e.0);
            order.sort_unstable_by_key(|e| e.1);
            listed = order.iter().map(|&(_, k)| listed[k]).collect();
        }
        let mut best: Option<Hit> = None;
        for &(id, at) in &listed {
            // Entity hits must come before the world's end (ties go to the world) and before
            // the best entity hit so far, or at its time with a lower id.
            let (limit, equal_ok) = match &best {
                Some(b) => (b.t, b.entity.is_some_and(|e| id < e)),
                None => (t_end, false),
            };
            let rec = InstanceRecord::unpack(&self.instances[at..at + RECORD_WORDS]);
            if !near(ray, &rec, t_entry, limit) {
                continue;
            }
            if let Some(h) = self.test(ray, &rec, t_entry, limit, equal_ok, &mut steps) {
                best = Some(h);
            }
        }
        best.or(world).map(|mut h| {
            h.steps = steps;
            h
        })
    }

    /// The first solid voxel of one instance entered at `t` in `[t_lo, limit)` (or
    /// `[t_lo, limit]` with `equal_ok`).
    fn test(
        &self,
        ray: &Ray,
        rec: &InstanceRecord,
        t_lo: f64,
        limit: f64,
        equal_ok: bool,
        steps: &mut u32,
    ) -> Option<Hit> {
        let pos = rec.position();
        let inv = rec.inv_rotation();
        let o = ray.origin();
        let local = Ray::raw(rotate(inv, [0, 1, 2].map(|a| o[a] - pos[a])), rotate(inv, ray.dir()));
        let base = rec.voxel_start as usize * super::TYPE_ALIGN;
        let [sx, sy, _] = rec.size.map(|v| v as usize);
        let walk = walk(&local, rec.size, |c, t| {
            if t > limit || (t == limit && !equal_ok) {
                return Visit::Stop;
            }
            if t < t_lo {
                return Visit::Empty;
            }
            let i = base + c[0] as usize + sx * (c[1] as usize + sy * c[2] as usize);
            match self.voxels.get(i) {
                Some(&v) if v & ENTITY_SOLID != 0 => Visit::Solid((v & 0x7FFF) as u16),
                _ => Visit::Empty,
            }
        })?;
        match walk.end {
            End::Hit(mut h) => {
                *steps += h.steps;
                h.entity = Some(rec.id);
                Some(h)
            }
            End::Left { steps: s, .. } | End::Stopped { steps: s, .. } => {
                *steps += s;
                None
            }
        }
    }
}

/// Whether the ray passes within `|size|` of the instance's local-origin corner while in
/// `[t_lo, limit]`: every point of the entity does (it is rotated about that corner), so
/// `false` rejects the instance without transforming the ray. Conservative by 1e-3 voxel.
#[inline]
fn near(ray: &Ray, rec: &InstanceRecord, t_lo: f64, limit: f64) -> bool {
    let pos = rec.position();
    let (o, d) = (ray.origin(), ray.dir());
    let v = [0, 1, 2].map(|a| pos[a] - o[a]);
    let tc = v[0] * d[0] + v[1] * d[1] + v[2] * d[2];
    let r = rec.size.iter().map(|&s| f64::from(s * s)).sum::<f64>().sqrt() + 1e-3;
    let dist2 = v.iter().map(|x| x * x).sum::<f64>() - tc * tc;
    dist2 <= r * r && tc + r >= t_lo && tc - r <= limit
}

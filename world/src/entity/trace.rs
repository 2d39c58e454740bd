//! Ray tests against entities (NAADF-REFERENCE §3.4), shared by every traversal method.
//!
//! The world loop of a method records the entity fields of the chunks it visits, up to
//! its world hit or to where the ray leaves the world. Every method visits at least one
//! cell of every non-free chunk the ray passes (chunks with entities are never free, so no
//! AADF box covers them), so all methods record every instance that could be hit before
//! the world hit (the hierarchy skips full chunks, where the world hit comes first). Then
//! each listed instance is tested in its own frame with the decoded record:
//! `o' = R⁻¹(o − pos)`, `d' = R⁻¹ d` (a rotation, so `t` is the world distance), by the
//! same event-model DDA as the grid method ([`crate::traverse::grid`]) over the entity's
//! dense grid.
//!
//! An entity hit counts when the entity voxel is entered inside the world: at `t` no
//! earlier than where the ray enters the world (parts of an entity outside the world are
//! clipped) and strictly before the world hit (ties go to the world) or before the ray
//! leaves the world. The nearest hit wins; among entity hits at the same `t`, the lowest
//! id. An entity hit reports entity-local voxel and normal.
//!
//! Each listed instance is first tested against its padded world box and oriented box
//! ([`Bounds`], derived on every machine from the records), which needs no transform and
//! rejects most. The rest are tested in the order the ray enters their boxes, so that the first hit usually
//! ends the search: once a box is entered after the best hit, so is every later one.
//! Neither the box test nor the order changes the result, only the work.

use super::ENTITY_SOLID;
use super::pack::{InstanceRecord, RECORD_WORDS, rotate};
use crate::traverse::grid::{End, Visit, walk};
use crate::traverse::{Hit, Ray};
use crate::world::World;
use smallvec::SmallVec;

/// The entity fields met by a world loop (each run of equal fields once). Most rays meet
/// a few at most, so they stay on the stack.
#[derive(Default)]
pub(crate) struct Candidates {
    fields: SmallVec<[u32; 8]>,
}

impl Candidates {
    /// Records the entity field of a chunk the ray enters (0 = none).
    #[inline]
    pub fn push(&mut self, field: u32) {
        if field != 0 && self.fields.last() != Some(&field) {
            self.fields.push(field);
        }
    }
}

/// Where an instance can be hit, for rejecting it cheaply: its world box, and its own
/// oriented box as the ray test places it, both padded. Every point of its grid lies inside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bounds {
    /// The world box.
    lo: [f64; 3],
    hi: [f64; 3],
    /// The grid's frame: its origin corner and the rows of the rotation world → entity.
    pos: [f64; 3],
    to_local: [[f64; 3]; 3],
    size: [f64; 3],
}

impl Bounds {
    /// The bounds of `rec` as [`EntityView::resolve`] places it: the eight corners of its
    /// grid carried from the entity frame to the world by the inverse of the decoded
    /// rotation, padded by [`PAD`] for rounding.
    pub fn of(rec: &InstanceRecord) -> Self {
        let (pos, inv) = (rec.position(), rec.inv_rotation());
        let (lo, hi) = super::world_box(rec.size, pos, super::pack::conjugate(inv));
        let columns = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].map(|e| rotate(inv, e));
        Bounds {
            lo: lo.map(|v| v - PAD),
            hi: hi.map(|v| v + PAD),
            pos,
            to_local: [0, 1, 2].map(|r| columns.map(|c| c[r])),
            size: rec.size.map(f64::from),
        }
    }

    /// The first time in `[t_lo, t_hi]` at which `ray` (with `inv_d` = 1/d per axis) is
    /// inside both boxes, if any: the world box first (cheap), then the oriented one.
    #[inline]
    fn entry(&self, ray: &Ray, inv_d: [f64; 3], t_lo: f64, t_hi: f64) -> Option<f64> {
        let (o, d) = (ray.origin(), ray.dir());
        let t_lo = slab(o, inv_d, self.lo, self.hi, t_lo, t_hi)?;
        let rel = [0, 1, 2].map(|a| o[a] - self.pos[a]);
        let dot = |r: [f64; 3], v: [f64; 3]| r[0] * v[0] + r[1] * v[1] + r[2] * v[2];
        let (o_local, d_local) = (self.to_local.map(|r| dot(r, rel)), self.to_local.map(|r| dot(r, d)));
        slab(
            o_local,
            d_local.map(|v| 1.0 / v),
            [-PAD; 3],
            self.size.map(|s| s + PAD),
            t_lo,
            t_hi,
        )
    }
}

/// The first time in `[t_lo, t_hi]` at which the ray `o + t·d` (given `inv_d` = 1/d per
/// axis) is inside the box `[lo, hi]`, if any.
#[inline]
fn slab(o: [f64; 3], inv_d: [f64; 3], lo: [f64; 3], hi: [f64; 3], t_lo: f64, t_hi: f64) -> Option<f64> {
    let (mut first, mut last) = (t_lo, t_hi);
    for a in 0..3 {
        if inv_d[a].is_infinite() {
            // The ray does not move along this axis (or by less than 1e-300 voxels, far
            // inside the padding).
            if o[a] < lo[a] || o[a] > hi[a] {
                return None;
            }
            continue;
        }
        let (t0, t1) = ((lo[a] - o[a]) * inv_d[a], (hi[a] - o[a]) * inv_d[a]);
        first = first.max(t0.min(t1));
        last = last.min(t0.max(t1));
    }
    (first <= last).then_some(first)
}

/// Padding of [`Bounds`], in voxels: far above the rounding of the rotation, far below a
/// voxel, so that the boxes only ever let more rays through to the exact test.
const PAD: f64 = 1.0 / 64.0;

/// The entity buffers a ray test reads, and the instance boxes derived from them.
#[derive(Clone, Copy)]
pub(crate) struct EntityView<'a> {
    dims: [u32; 3],
    chunk_entities: &'a [u32],
    instances: &'a [u32],
    bounds: &'a [Bounds],
    voxels: &'a [u32],
}

/// An owned copy of a world's entity buffers (for the dense-grid method).
pub(crate) struct OwnedEntities {
    dims: [u32; 3],
    chunk_entities: Vec<u32>,
    instances: Vec<u32>,
    bounds: Vec<Bounds>,
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
            bounds: v.bounds.to_vec(),
            voxels: v.voxels.to_vec(),
        })
    }

    pub fn view(&self) -> EntityView<'_> {
        EntityView {
            dims: self.dims,
            chunk_entities: &self.chunk_entities,
            instances: &self.instances,
            bounds: &self.bounds,
            voxels: &self.voxels,
        }
    }
}

impl<'a> EntityView<'a> {
    pub fn new(
        dims: [u32; 3],
        chunk_entities: &'a [u32],
        instances: &'a [u32],
        bounds: &'a [Bounds],
        voxels: &'a [u32],
    ) -> Self {
        EntityView {
            dims,
            chunk_entities,
            instances,
            bounds,
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
    #[inline(always)]
    pub fn resolve(
        &self,
        ray: &Ray,
        world: Option<Hit>,
        t_entry: f64,
        t_end: f64,
        steps: u32,
        fields: &Candidates,
    ) -> Option<Hit> {
        // Most rays meet no entity field: they pay no call.
        if fields.fields.is_empty() {
            return world;
        }
        self.resolve_listed(ray, world, t_entry, t_end, steps, fields)
    }

    /// [`Self::resolve`] for a ray that met at least one entity field.
    #[inline(never)]
    fn resolve_listed(
        &self,
        ray: &Ray,
        world: Option<Hit>,
        t_entry: f64,
        t_end: f64,
        mut steps: u32,
        fields: &Candidates,
    ) -> Option<Hit> {
        // The instances whose box the ray crosses before the world's end, as (time it
        // enters the box, id, record offset), nearest first: a near hit lowers the limit, and
        // once a box is entered after the limit, so is every later one.
        let inv_d = ray.dir().map(|d| 1.0 / d);
        let mut crossed: SmallVec<[(f64, u32, usize); 8]> = SmallVec::new();
        for &f in &fields.fields {
            let (ptr, count) = ((f >> 8) as usize, (f & 0xFF) as usize);
            for r in ptr..ptr + count {
                let at = r * RECORD_WORDS;
                let (Some(w), Some(b)) = (self.instances.get(at..at + RECORD_WORDS), self.bounds.get(r)) else {
                    continue;
                };
                if let Some(t) = b.entry(ray, inv_d, t_entry, t_end) {
                    crossed.push((t, w[4] & 0x3FFF, at));
                }
            }
        }
        // An instance listed by several chunks has one box: its copies sort together.
        crossed.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        crossed.dedup_by_key(|c| c.1);
        let mut best: Option<Hit> = None;
        for &(t_box, id, at) in &crossed {
            // Entity hits must come before the world's end (ties go to the world) and before
            // the best entity hit so far, or at its time with a lower id.
            let (limit, equal_ok) = match &best {
                Some(b) => (b.t, b.entity.is_some_and(|e| id < e)),
                None => (t_end, false),
            };
            if t_box > limit {
                break;
            }
            let rec = InstanceRecord::unpack(&self.instances[at..at + RECORD_WORDS]);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::entity::pack::quantise_pose;
    use crate::raysets::SplitMix64;

    /// Every world point that the ray test maps into an instance's grid (`R⁻¹(p − pos)`
    /// inside `[0, size]`) lies in the instance's bounds, for random sizes and rotations:
    /// a ray from it, in any direction, is inside at once.
    #[test]
    fn bounds_hold_every_point_the_ray_test_maps_into_the_grid() {
        let mut rng = SplitMix64(7);
        for _ in 0..200 {
            let size = [0; 3].map(|_| 1 + (rng.unit() * 126.0) as u32);
            let rot = [0; 4].map(|_| rng.unit() - 0.5);
            let q = quantise_pose([500.0 + rng.unit(), 300.0 + rng.unit(), 700.0 + rng.unit()], rot).unwrap();
            let rec = InstanceRecord {
                id: 1,
                size,
                voxel_start: 0,
                pos: q.fixed,
                inv_rot: q.inv_rot,
            };
            let b = Bounds::of(&rec);
            let (pos, inv) = (rec.position(), rec.inv_rotation());
            let mut inside = 0;
            for _ in 0..2000 {
                // Points near the grid, its faces and corners most of all.
                let near = [0, 1, 2].map(|a| {
                    let edge = if rng.unit() < 0.5 { 0.0 } else { f64::from(size[a]) };
                    let at = if rng.unit() < 0.5 {
                        edge
                    } else {
                        rng.unit() * f64::from(size[a])
                    };
                    at + (rng.unit() - 0.5) * 0.1
                });
                let w = rotate(crate::entity::pack::conjugate(inv), near);
                let p = [0, 1, 2].map(|a| pos[a] + w[a]);
                let local = rotate(inv, [0, 1, 2].map(|a| p[a] - pos[a]));
                if (0..3).all(|a| local[a] >= 0.0 && local[a] <= f64::from(size[a])) {
                    inside += 1;
                    let ray = Ray::new(p, [0; 3].map(|_| rng.unit() - 0.5)).unwrap();
                    let inv_d = ray.dir().map(|v| 1.0 / v);
                    assert_eq!(b.entry(&ray, inv_d, 0.0, 1.0), Some(0.0), "{p:?} outside {b:?}");
                }
            }
            assert!(inside > 0, "no sample fell in the grid of size {size:?}");
        }
    }

    /// A ray's box entry time lies in the window it is asked for, and rays that start in
    /// the box, or move along one axis only, on a face or not, are handled.
    #[test]
    fn box_entry_times() {
        let entry = |o: [f64; 3], d: [f64; 3], lo: f64, hi: f64| {
            let ray = Ray::new(o, d).unwrap();
            slab(o, ray.dir().map(|v| 1.0 / v), [10.0; 3], [20.0; 3], lo, hi)
        };
        assert_eq!(entry([0.0, 15.0, 15.0], [1.0, 0.0, 0.0], 0.0, 100.0), Some(10.0));
        assert_eq!(entry([0.0, 15.0, 15.0], [1.0, 0.0, 0.0], 12.0, 100.0), Some(12.0));
        assert_eq!(entry([0.0, 15.0, 15.0], [1.0, 0.0, 0.0], 0.0, 9.0), None);
        assert_eq!(entry([0.0, 25.0, 15.0], [1.0, 0.0, 0.0], 0.0, 100.0), None);
        // On a face, moving along it.
        assert_eq!(entry([0.0, 10.0, 20.0], [1.0, 0.0, 0.0], 0.0, 100.0), Some(10.0));
        assert_eq!(entry([15.0, 15.0, 15.0], [0.0, -1.0, 0.0], 0.0, 100.0), Some(0.0));
        assert_eq!(entry([25.0, 25.0, 25.0], [1.0, 1.0, 1.0], 0.0, 100.0), None);
    }
}

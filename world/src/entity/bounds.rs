//! The boxes an entity instance can be hit in, derived from its packed record on every
//! machine (not mirrored, not in the digest): the entity ray test rejects most instances
//! with them before it transforms a ray into an instance's frame. Neither box changes what
//! a ray hits, only the work it takes to find out.

use super::pack::{InstanceRecord, conjugate, rotate};
use crate::traverse::Ray;

/// Where an instance can be hit, for rejecting it cheaply: its world box, and its own
/// oriented box as the ray test places it, both padded. Every point of its grid lies inside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bounds {
    /// The world box.
    lo: [f64; 3],
    hi: [f64; 3],
    /// The grid's frame: its origin corner and the rows of the rotation world → entity (a
    /// matrix, cheaper for the box test than the quaternion `inv`).
    pos: [f64; 3],
    to_local: [[f64; 3]; 3],
    size: [f64; 3],
    /// The decoded rotation world → entity, as the exact ray test applies it
    /// ([`Bounds::local`]), kept so that a tested instance is not decoded per ray.
    inv: [f64; 4],
}

impl Bounds {
    /// The bounds of `rec` as the entity ray test ([`crate::traverse`]) places it: the eight
    /// corners of its grid carried from the entity frame to the world by the inverse of the
    /// decoded rotation, padded by [`PAD`] for rounding.
    pub fn of(rec: &InstanceRecord) -> Self {
        let (pos, inv) = (rec.position(), rec.inv_rotation());
        let (lo, hi) = world_box(rec.size, pos, conjugate(inv));
        let columns = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].map(|e| rotate(inv, e));
        Bounds {
            lo: lo.map(|v| v - PAD),
            hi: hi.map(|v| v + PAD),
            pos,
            to_local: [0, 1, 2].map(|r| columns.map(|c| c[r])),
            size: rec.size.map(f64::from),
            inv,
        }
    }

    /// `ray` in the instance's frame, `o' = R⁻¹(o − pos)`, `d' = R⁻¹ d`, with the decoded
    /// position and rotation (a rotation, so `t` stays the world distance).
    #[inline]
    pub fn local(&self, ray: &Ray) -> Ray {
        let o = ray.origin();
        Ray::raw(
            rotate(self.inv, [0, 1, 2].map(|a| o[a] - self.pos[a])),
            rotate(self.inv, ray.dir()),
        )
    }

    /// The padded world box.
    pub fn world_box(&self) -> ([f64; 3], [f64; 3]) {
        (self.lo, self.hi)
    }

    /// The first time in `[t_lo, t_hi]` at which the ray `o + t·d` is inside the oriented
    /// box, if any. (The world box needs no test here: it is what the hierarchy's lanes
    /// hold, and the ray has entered it to be offered the instance.)
    #[inline]
    pub fn entry(&self, o: [f64; 3], d: [f64; 3], t_lo: f64, t_hi: f64) -> Option<f64> {
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
pub(crate) fn slab(o: [f64; 3], inv_d: [f64; 3], lo: [f64; 3], hi: [f64; 3], t_lo: f64, t_hi: f64) -> Option<f64> {
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

/// Padding of [`Bounds`] ([`super::bvh::BOUNDS_PAD`]).
const PAD: f64 = super::bvh::BOUNDS_PAD;

/// The world box `(lo, hi)` of a grid of `size` whose origin corner is at `pos`, turned by
/// the rotation `rot` (entity → world): the bounds of its eight corners.
pub(crate) fn world_box(size: [u32; 3], pos: [f64; 3], rot: [f64; 4]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for c in 0..8 {
        let corner = [0, 1, 2].map(|a| if c >> a & 1 == 1 { f64::from(size[a]) } else { 0.0 });
        let p = rotate(rot, corner);
        for a in 0..3 {
            lo[a] = lo[a].min(p[a] + pos[a]);
            hi[a] = hi[a].max(p[a] + pos[a]);
        }
    }
    (lo, hi)
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
                let w = rotate(conjugate(inv), near);
                let p = [0, 1, 2].map(|a| pos[a] + w[a]);
                let local = rotate(inv, [0, 1, 2].map(|a| p[a] - pos[a]));
                if (0..3).all(|a| local[a] >= 0.0 && local[a] <= f64::from(size[a])) {
                    inside += 1;
                    let ray = Ray::new(p, [0; 3].map(|_| rng.unit() - 0.5)).unwrap();
                    assert_eq!(
                        b.entry(ray.origin(), ray.dir(), 0.0, 1.0),
                        Some(0.0),
                        "{p:?} outside {b:?}"
                    );
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

//! Rays and the event model shared by every traversal method.
//!
//! A ray `o + t·d` (`d` normalised) crosses the plane `k` of axis `a` at
//! `t_a(k) = (k − o_a)/d_a`, always computed by [`Ray::t_at`] so that every method sees
//! bit-identical times. Crossing events are ordered by `(t, axis)`: at equal `t` the ray
//! steps x first, then y, then z, visiting each cell in between (Amanatides–Woo's order).
//! The cell the ray is in after an event is therefore a pure function of the event.

use crate::error::WorldError;

/// A ray with a normalised direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    o: [f64; 3],
    d: [f64; 3],
}

/// The first solid voxel along a ray: a world voxel, or a voxel of an entity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Coordinates of the voxel: world coordinates, or entity-local ones for an entity hit.
    pub voxel: [u32; 3],
    /// Normal of the entry face (all zero when the origin is inside the voxel); in the
    /// entity's local frame for an entity hit.
    pub normal: [i32; 3],
    /// Distance along the normalised direction to the entry face.
    pub t: f64,
    /// Material id.
    pub material: u16,
    /// Cells visited, the hit cell included (world cells plus the cells of the entity
    /// grids tested).
    pub steps: u32,
    /// The entity hit (its id), or `None` for a world voxel.
    pub entity: Option<u32>,
}

/// Whether two traversal results agree as the contract requires: both miss, or both hit
/// the same voxel (of the world, or of the same entity) through the same face with the same
/// material, `t` within 1e-4 relative.
pub fn same_result(a: &Option<Hit>, b: &Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            a.voxel == b.voxel
                && a.entity == b.entity
                && a.normal == b.normal
                && a.material == b.material
                && (a.t - b.t).abs() <= 1e-4 * a.t.abs().max(1.0)
        }
        _ => false,
    }
}

/// Where a ray begins inside the world: its first cell, the time it is entered, and the
/// axis whose plane it crossed to enter it (`None` when the origin is inside).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Entry {
    pub cell: [i64; 3],
    pub t: f64,
    pub axis: Option<usize>,
}

/// Largest accepted origin coordinate: far beyond any world, small enough that cell
/// indices and boundary times stay exact in `i64` and `f64`.
pub const MAX_COORD: f64 = (1u64 << 30) as f64;

/// Step budget of a ray unless set otherwise: far more cells than any ray crosses in the
/// largest world with AADFs, a guard against runaway loops only. The GPU walk stops there
/// and reports a miss; the CPU light model counts a longer walk as a miss too, so that both
/// path tracers see the same world.
pub const DEFAULT_MAX_STEPS: u32 = 1 << 16;

/// Far-away cell bound for unconstrained axes.
const FAR: i64 = 1 << 40;

/// `floor(p)` without a libm call (x86-64's baseline has no rounding instruction): exact
/// for the |p| < 2^41 that origins within ±2^30 and in-world times give.
#[inline(always)]
fn floor_i64(p: f64) -> i64 {
    let t = p as i64;
    if (t as f64) > p { t - 1 } else { t }
}

impl Ray {
    /// A ray from `origin` along `dir` (normalised here). Fails on a zero or non-finite
    /// direction or a non-finite origin.
    ///
    /// ```
    /// use naadf_world::traverse::Ray;
    /// assert!(Ray::new([0.0; 3], [0.0, 0.0, 2.0]).is_ok());
    /// assert!(Ray::new([0.0; 3], [0.0; 3]).is_err());
    /// ```
    pub fn new(origin: [f64; 3], dir: [f64; 3]) -> Result<Self, WorldError> {
        let len = dir.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !origin.iter().all(|v| v.is_finite() && v.abs() <= MAX_COORD) || !len.is_finite() || len == 0.0 {
            return Err(WorldError::InvalidRay(format!(
                "origin {origin:?}, direction {dir:?}: need a finite origin within ±2^30 and a finite non-zero direction"
            )));
        }
        Ok(Ray {
            o: origin,
            d: dir.map(|v| v / len),
        })
    }

    /// A ray from raw parts, unchecked and not renormalised (entity-local rays: a rotated
    /// unit direction, so that `t` stays the world distance).
    #[inline]
    pub(crate) fn raw(o: [f64; 3], d: [f64; 3]) -> Self {
        Ray { o, d }
    }

    /// The origin.
    pub fn origin(&self) -> [f64; 3] {
        self.o
    }

    /// The normalised direction.
    pub fn dir(&self) -> [f64; 3] {
        self.d
    }

    /// Time at which the ray crosses plane `k` of `axis`.
    #[inline(always)]
    pub fn t_at(&self, axis: usize, k: i64) -> f64 {
        (k as f64 - self.o[axis]) / self.d[axis]
    }

    /// Whether the crossing of plane `k` of axis `b` comes before the event `(t, a)`.
    #[inline(always)]
    fn crossed(&self, b: usize, k: i64, t: f64, a: usize) -> bool {
        let tb = self.t_at(b, k);
        tb < t || (tb == t && b < a)
    }

    /// The cell of axis `b` right after event `(t, a)`, known to lie in `lo..=hi`.
    #[inline(always)]
    pub(crate) fn cell_after(&self, b: usize, t: f64, a: usize, lo: i64, hi: i64) -> i64 {
        let d = self.d[b];
        if lo == hi || d == 0.0 {
            return lo;
        }
        let p = self.o[b] + d * t;
        let fl = floor_i64(p);
        let k = fl.clamp(lo, hi);
        let f = p - fl as f64;
        // Far from a plane the floor is certain: time errors are ~1e-12, far below 1e-7.
        if f > 1e-7 && f < 1.0 - 1e-7 {
            return k;
        }
        let mut k = k;
        if d > 0.0 {
            // Plane k separates cell k-1 from cell k.
            while k < hi && self.crossed(b, k + 1, t, a) {
                k += 1;
            }
            while k > lo && !self.crossed(b, k, t, a) {
                k -= 1;
            }
        } else {
            while k > lo && self.crossed(b, k, t, a) {
                k -= 1;
            }
            while k < hi && !self.crossed(b, k + 1, t, a) {
                k += 1;
            }
        }
        k
    }

    /// The first in-world cell of the ray, or `None` if it never enters the box
    /// `[0, size)`. Rays start at the world box itself (no inset).
    pub(crate) fn entry(&self, size: [u32; 3]) -> Option<Entry> {
        let size = size.map(i64::from);
        let start = self.o.map(floor_i64);
        if (0..3).all(|a| start[a] >= 0 && start[a] < size[a]) {
            return Some(Entry {
                cell: start,
                t: 0.0,
                axis: None,
            });
        }
        // The last slab-entry event, in (t, axis) order.
        let mut best: Option<(f64, usize)> = None;
        for a in 0..3 {
            let plane = if start[a] < 0 {
                if self.d[a] <= 0.0 {
                    return None;
                }
                0
            } else if start[a] >= size[a] {
                if self.d[a] >= 0.0 {
                    return None;
                }
                size[a]
            } else {
                continue;
            };
            let t = self.t_at(a, plane);
            if best.is_none_or(|(bt, _)| t >= bt) {
                best = Some((t, a));
            }
        }
        let (t, axis) = best?;
        let mut cell = [0i64; 3];
        for b in 0..3 {
            cell[b] = if b == axis {
                if self.d[b] > 0.0 { 0 } else { size[b] - 1 }
            } else if self.d[b] > 0.0 {
                self.cell_after(b, t, axis, start[b], FAR)
            } else if self.d[b] < 0.0 {
                self.cell_after(b, t, axis, -FAR, start[b])
            } else {
                start[b]
            };
        }
        (0..3).all(|a| cell[a] >= 0 && cell[a] < size[a]).then_some(Entry {
            cell,
            t,
            axis: Some(axis),
        })
    }

    /// The times `(entered, left)` between which the ray is inside the box `[0, size]` (a
    /// world's voxels), or `None` if it never enters it, as the traversal finds them.
    ///
    /// ```
    /// use naadf_world::traverse::Ray;
    /// let r = Ray::new([-2.0, 1.5, 1.5], [1.0, 0.0, 0.0]).unwrap();
    /// assert_eq!(r.span_in([4, 4, 4]), Some((2.0, 6.0)));
    /// assert_eq!(r.span_in([4, 1, 4]), None);
    /// ```
    pub fn span_in(&self, size: [u32; 3]) -> Option<(f64, f64)> {
        Some((self.entry(size)?.t, self.leave_time(size)))
    }

    /// When the ray leaves the box `[0, size]` (a ray inside it): the first crossing of one
    /// of the far planes it moves toward, where a cell-by-cell walk steps outside.
    pub(crate) fn leave_time(&self, size: [u32; 3]) -> f64 {
        (0..3)
            .filter(|&a| self.d[a] != 0.0)
            .map(|a| self.t_at(a, if self.d[a] > 0.0 { i64::from(size[a]) } else { 0 }))
            .fold(f64::INFINITY, f64::min)
    }

    /// Leaves the empty cuboid made of `cell` extended by `skip[a]` cells toward the ray on
    /// each axis: the exit event `(t, axis)` and the cell entered by it.
    #[inline(always)]
    pub(crate) fn exit(&self, cell: [i64; 3], skip: [i64; 3]) -> (f64, usize, [i64; 3]) {
        let mut bound = [0i64; 3];
        let mut best = (f64::INFINITY, 0usize);
        for a in 0..3 {
            if self.d[a] == 0.0 {
                continue;
            }
            bound[a] = if self.d[a] > 0.0 {
                cell[a] + 1 + skip[a]
            } else {
                cell[a] - skip[a]
            };
            let t = self.t_at(a, bound[a]);
            if t < best.0 {
                best = (t, a);
            }
        }
        let (t, axis) = best;
        let mut next = cell;
        for b in 0..3 {
            next[b] = if b == axis {
                if self.d[b] > 0.0 { bound[b] } else { bound[b] - 1 }
            } else if self.d[b] > 0.0 {
                self.cell_after(b, t, axis, cell[b], cell[b] + skip[b])
            } else if self.d[b] < 0.0 {
                self.cell_after(b, t, axis, cell[b] - skip[b], cell[b])
            } else {
                cell[b]
            };
        }
        (t, axis, next)
    }

    /// The hit record for entering `cell` at `t` through a plane of `axis`.
    #[inline]
    pub(crate) fn hit(&self, cell: [i64; 3], t: f64, axis: Option<usize>, material: u16, steps: u32) -> Hit {
        let mut normal = [0i32; 3];
        if let Some(a) = axis {
            normal[a] = if self.d[a] > 0.0 { -1 } else { 1 };
        }
        // `+ 0.0` turns a −0.0 (from (o − o)/d with d < 0) into 0.0.
        Hit {
            voxel: cell.map(|v| v as u32),
            normal,
            t: t + 0.0,
            material,
            steps,
            entity: None,
        }
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

/// Amanatides–Woo through the grid `[0, size)` in the event order of this module:
/// `visit(cell, t)` sees every cell the ray passes, with the time it is entered, until it
/// reports a solid cell or asks to stop, or the ray leaves. `None` if the ray misses the
/// grid. Serves both the world's dense decode and entity grids.
pub(crate) fn walk(ray: &Ray, size: [u32; 3], mut visit: impl FnMut([i64; 3], f64) -> Visit) -> Option<Walk> {
    let entry = ray.entry(size)?;
    let (mut cell, mut t, mut axis) = (entry.cell, entry.t, entry.axis);
    let d = ray.dir();
    let step: [i64; 3] = d.map(|v| if v > 0.0 { 1 } else { -1 });
    let next_plane = |c: i64, a: usize| if d[a] > 0.0 { c + 1 } else { c };
    // When the ray crosses the next plane of each axis, and the plane after it: the time of
    // a plane is worked out a step before it is needed, so that its division is not on the
    // chain of one step waiting for the last.
    let plane_time = |a: usize, c: i64| {
        if d[a] == 0.0 {
            f64::INFINITY
        } else {
            ray.t_at(a, next_plane(c, a))
        }
    };
    let mut tmax: [f64; 3] = std::array::from_fn(|a| plane_time(a, cell[a]));
    let mut tafter: [f64; 3] = std::array::from_fn(|a| plane_time(a, cell[a] + step[a]));
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
        tmax[a] = tafter[a];
        tafter[a] = plane_time(a, cell[a] + step[a]);
    };
    Some(Walk { entry_t: entry.t, end })
}

//! One ray against one node's four boxes: the node's layout and the ray as the walks read
//! it, shared by the single walk ([`super::Bvh::crossing`]) and the batch walk
//! ([`super::batch`]).

/// Children per node.
pub const WIDTH: usize = 4;
/// Where unused child slots sit (beyond any ray's reach in the world), and the inverse
/// direction component of an axis a ray does not move along.
pub const FAR: f32 = 1e30;

/// How far from the origin a walk's ray may start as it is given (see [`WalkRay::new`]):
/// `f32` rounding moves a position there by at most 2^-9 voxel, far inside [`super::F32_PAD`].
const NEAR_ORIGIN: f64 = (1u32 << 15) as f64;

/// One four-wide node: its children's boxes, axis by axis, lane by lane, and references.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Node {
    pub(super) lo: [[f32; WIDTH]; 3],
    pub(super) hi: [[f32; WIDTH]; 3],
    pub(super) child: [u32; WIDTH],
}

/// The smaller of two lanes (`minps` on x86, unlike `f32::min`'s NaN rule; no NaN arises).
#[inline(always)]
pub(super) fn lane_min(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

#[inline(always)]
pub(super) fn lane_max(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// One ray as a walk reads it, in `f32`: its origin, `1/d` kept finite, and the window of
/// times to look in, widened by more than its rounding.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct WalkRay {
    pub(super) o: [f32; 3],
    pub(super) inv: [f32; 3],
    pub(super) t_lo: f32,
    pub(super) t_hi: f32,
}

impl WalkRay {
    /// The ray `o + t·d` over the times `[t_lo, t_hi]`.
    ///
    /// An origin beyond ±2^15 on some axis (a ray may start up to 2^30 voxels away) would
    /// lose more than [`super::F32_PAD`] in `f32`; such a ray is walked from the start of its
    /// window instead, `o + t_lo·d` worked out in `f64`, with its times counted from there.
    /// The window of a ray that meets an instance lies in the world, below 2^14 on every
    /// axis, so that start is as precise as a near origin. (Near origins stay, so that camera
    /// rays keep their one origin and walk as coherent groups.)
    #[inline]
    pub fn new(o: [f64; 3], d: [f64; 3], t_lo: f64, t_hi: f64) -> Self {
        let (o, t_lo, t_hi) = if o.iter().all(|v| v.abs() < NEAR_ORIGIN) {
            (o, t_lo, t_hi)
        } else {
            (std::array::from_fn(|a| o[a] + t_lo * d[a]), 0.0, t_hi - t_lo)
        };
        WalkRay {
            o: o.map(|v| v as f32),
            // In `f32` from the start: the boxes' padding (`F32_PAD`) covers the rounding.
            // An axis the ray does not move along gets ±FAR, which puts every plane of it
            // at ± far beyond the ray's reach unless the origin lies on it.
            inv: d.map(|v| {
                let i = 1.0 / v as f32;
                if i.is_finite() { i } else { FAR.copysign(i) }
            }),
            t_lo: (t_lo as f32) - 1e-3,
            t_hi: (t_hi as f32) * (1.0 + 1e-6) + 1e-3,
        }
    }

    /// The ray's fields, for a loop that keeps them in registers.
    #[inline(always)]
    pub(super) fn parts(&self) -> ([f32; 3], [f32; 3], f32, f32) {
        (self.o, self.inv, self.t_lo, self.t_hi)
    }

    /// The times at which the ray enters and leaves each lane's box of `n` (within its
    /// window); it meets lane `l` unless `near[l] > far[l]`.
    #[inline(always)]
    pub(super) fn lanes(&self, n: &Node) -> ([f32; WIDTH], [f32; WIDTH]) {
        lanes(n, self.o, self.inv, self.t_lo, self.t_hi)
    }
}

/// [`WalkRay::lanes`] for a ray given by its fields.
#[inline(always)]
pub(super) fn lanes(n: &Node, o: [f32; 3], inv: [f32; 3], t_lo: f32, t_hi: f32) -> ([f32; WIDTH], [f32; WIDTH]) {
    let mut near = [t_lo; WIDTH];
    let mut far = [t_hi; WIDTH];
    for a in 0..3 {
        for l in 0..WIDTH {
            let t0 = (n.lo[a][l] - o[a]) * inv[a];
            let t1 = (n.hi[a][l] - o[a]) * inv[a];
            near[l] = lane_max(near[l], lane_min(t0, t1));
            far[l] = lane_min(far[l], lane_max(t0, t1));
        }
    }
    (near, far)
}

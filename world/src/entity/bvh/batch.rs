//! Walks of many rays at once ([`Bvh::crossing_many`]): the same answers as
//! [`Bvh::crossing`] ray by ray, for less work per ray.
//!
//! One ray's walk is a chain of dependent steps (load a node, test its four boxes, branch on
//! each, pop the next), and for incoherent rays those branches are guesses the processor
//! often gets wrong. A batch is walked instead:
//! - **Coherent groups** ([`GROUP`] consecutive rays from one origin, moving the same way on
//!   every axis, such as neighbouring camera rays) walk the tree once per group, each node
//!   tested against the interval that bounds the group's rays: a group may enter a node
//!   only if that interval enters it. At an instance, each ray of the group is tested on
//!   its own.
//! - **The other rays** descend together, breadth by node: at each node every ray of the
//!   node's list is tested against the four boxes and appended, without a branch, to the
//!   list of each child it enters (`lane_sort`). The tests of different rays do
//!   not wait on each other, and the only branches left are per node, not per ray. A list
//!   of at most `SHORT_LIST` rays (half the lists deep in the tree) walks the rest of its
//!   subtree ray by ray, as [`Bvh::crossing`] does.
//!
//! Both find, for each ray, exactly the instances whose `f32` lane box the ray enters
//! within its window: a parent's box holds its children's, so a ray that enters a leaf's
//! box entered every box above it, and the per-ray test at the leaf is the one
//! [`Bvh::crossing`] makes.

use super::lane_sort::{Kernel, LIST_SLACK, sort_into_lanes};
use super::node::{Node, WIDTH, WalkRay, lane_max, lane_min};
use super::{Bvh, LEAF, NO_CHILD, STACK};

pub use super::lane_sort::BATCH;
/// Consecutive rays tested as one group when they are coherent.
pub const GROUP: usize = 16;
/// A node's list of at most this many rays walks the subtree ray by ray: deep in the tree,
/// where half the lists are this short, sorting them into lanes costs more than it saves.
const SHORT_LIST: usize = 4;

/// What a walk of a batch keeps between calls: one list of rays per child lane and level,
/// the rays no group holds, and the pairs (ray, primitive) met.
#[derive(Default)]
pub struct Scratch {
    levels: Vec<[Vec<u16>; WIDTH]>,
    incoherent: Vec<u16>,
    met: Vec<(u32, u32)>,
}

/// The pairs (ray, primitive) a walk has met so far: `buf[..len]`. A pair is written at
/// `len` in any case and kept by moving `len` past it, so that whether a ray meets a box
/// costs no branch.
struct Met<'a> {
    buf: &'a mut Vec<(u32, u32)>,
    len: usize,
}

impl Met<'_> {
    /// Makes room for `n` more pairs.
    #[inline(always)]
    fn room(&mut self, n: usize) {
        if self.buf.len() < self.len + n {
            let want = (self.len + n).max(2 * self.buf.len());
            self.buf.resize(want, (0, 0));
        }
    }

    /// Writes `pair` and keeps it if `keep` (after [`Met::room`]).
    #[inline(always)]
    fn put(&mut self, pair: (u32, u32), keep: bool) {
        self.buf[self.len] = pair;
        self.len += usize::from(keep);
    }
}

/// What bounds every ray of a group: their one origin, each axis's range of `1/d`, and
/// the union of their windows.
struct Interval {
    o: [f32; 3],
    inv_lo: [f32; 3],
    inv_hi: [f32; 3],
    t_lo: f32,
    t_hi: f32,
}

impl Interval {
    /// The group's bounds if it is coherent (one origin, the same signs of `1/d`), which
    /// keeps them tight enough to be worth testing.
    fn of(group: &[WalkRay]) -> Option<Self> {
        let first = group.first()?;
        let mut b = Interval {
            o: first.o,
            inv_lo: first.inv,
            inv_hi: first.inv,
            t_lo: first.t_lo,
            t_hi: first.t_hi,
        };
        for r in &group[1..] {
            for a in 0..3 {
                if r.o[a] != first.o[a] || (r.inv[a] > 0.0) != (first.inv[a] > 0.0) {
                    return None;
                }
                b.inv_lo[a] = lane_min(b.inv_lo[a], r.inv[a]);
                b.inv_hi[a] = lane_max(b.inv_hi[a], r.inv[a]);
            }
            b.t_lo = lane_min(b.t_lo, r.t_lo);
            b.t_hi = lane_max(b.t_hi, r.t_hi);
        }
        Some(b)
    }

    /// Whether some ray of the group may meet each lane's box of `n`: the lanes' entry and
    /// exit times bounded over the group, as in [`WalkRay::lanes`]. With one origin, each
    /// plane's time `(p − o)·inv` is monotone in `inv`, so its bounds are the two ends.
    #[inline(always)]
    fn lanes(&self, n: &Node) -> ([f32; WIDTH], [f32; WIDTH]) {
        let mut near = [self.t_lo; WIDTH];
        let mut far = [self.t_hi; WIDTH];
        for a in 0..3 {
            let (o, i0, i1) = (self.o[a], self.inv_lo[a], self.inv_hi[a]);
            for l in 0..WIDTH {
                let (p0, p1) = (n.lo[a][l] - o, n.hi[a][l] - o);
                let (a0, b0) = (p0 * i0, p0 * i1);
                let (a1, b1) = (p1 * i0, p1 * i1);
                let low = lane_min(lane_min(a0, b0), lane_min(a1, b1));
                let high = lane_max(lane_max(a0, b0), lane_max(a1, b1));
                near[l] = lane_max(near[l], low);
                far[l] = lane_min(far[l], high);
            }
        }
        (near, far)
    }
}

impl Bvh {
    /// Every pair `(i, k)` of a ray `i` of `rays` and a primitive `k` that [`Bvh::crossing`]
    /// would give that ray, in no particular order (held in `scratch` until its next walk).
    ///
    /// ```
    /// use naadf_world::entity::bvh::{Bvh, WalkRay, batch::Scratch};
    /// let boxes: Vec<_> = (0..100).map(|i| {
    ///     let x = 10.0 * f64::from(i);
    ///     ([x, 0.0, 0.0], [x + 1.0, 1.0, 1.0])
    /// }).collect();
    /// let bvh = Bvh::build(&boxes);
    /// // Rays along +z through boxes 0, 1 and 2.
    /// let rays: Vec<_> = (0..3)
    ///     .map(|i| WalkRay::new([10.0 * f64::from(i) + 0.5, 0.5, -1.0], [0.0, 0.0, 1.0], 0.0, 100.0))
    ///     .collect();
    /// let mut scratch = Scratch::default();
    /// let met = bvh.crossing_many(&rays, &mut scratch);
    /// met.sort();
    /// assert_eq!(met, [(0, 0), (1, 1), (2, 2)]);
    /// ```
    pub fn crossing_many<'s>(&self, rays: &[WalkRay], scratch: &'s mut Scratch) -> &'s mut [(u32, u32)] {
        let mut met = Met {
            buf: &mut scratch.met,
            len: 0,
        };
        if self.nodes.is_empty() {
            return &mut met.buf[..0];
        }
        let kernel = Kernel::detect();
        for (b, batch) in rays.chunks(BATCH).enumerate() {
            let base = (b * BATCH) as u32;
            scratch.incoherent.clear();
            for (g, group) in batch.chunks(GROUP).enumerate() {
                let first = (g * GROUP) as u32;
                match Interval::of(group) {
                    Some(bounds) if group.len() > 1 => self.group_walk(group, base + first, &bounds, &mut met),
                    _ => scratch
                        .incoherent
                        .extend(first as u16..(first as usize + group.len()) as u16),
                }
            }
            if !scratch.incoherent.is_empty() {
                let rays = Rays { batch, kernel };
                self.list_walk(0, &rays, &scratch.incoherent, 0, &mut scratch.levels, &mut |ids, k| {
                    met.room(ids.len());
                    for &i in ids {
                        met.put((base + u32::from(i), k), true);
                    }
                });
            }
        }
        let len = met.len;
        &mut met.buf[..len]
    }

    /// One walk for a coherent group (rays `first..` of the walk); each instance a lane leads
    /// to is tested per ray.
    fn group_walk(&self, group: &[WalkRay], first: u32, bounds: &Interval, met: &mut Met) {
        let mut stack = [0u32; STACK];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let n = &self.nodes[stack[sp] as usize];
            let (near, far) = bounds.lanes(n);
            for l in 0..WIDTH {
                let c = n.child[l];
                if near[l] > far[l] || c == NO_CHILD {
                    continue;
                }
                if c & LEAF == 0 {
                    stack[sp] = c;
                    sp += 1;
                    continue;
                }
                met.room(group.len());
                for (i, r) in (first..).zip(group) {
                    let (near, far) = r.lanes(n);
                    met.put((i, c & !LEAF), near[l] <= far[l]);
                }
            }
        }
    }

    /// Node `at` for the rays `ids` of the batch, then its children for the rays that enter
    /// them; `levels[depth]` holds the lists this level fills.
    fn list_walk(
        &self,
        at: usize,
        rays: &Rays,
        ids: &[u16],
        depth: usize,
        levels: &mut Vec<[Vec<u16>; WIDTH]>,
        visit: &mut impl FnMut(&[u16], u32),
    ) {
        if ids.len() <= SHORT_LIST {
            for &i in ids {
                self.crossing_below(at as u32, &rays.batch[usize::from(i)], |k| visit(&[i], k));
            }
            return;
        }
        let n = &self.nodes[at];
        if levels.len() <= depth {
            levels.push(std::array::from_fn(|_| vec![0; BATCH + LIST_SLACK]));
        }
        let mut lists = std::mem::take(&mut levels[depth]);
        let len = sort_into_lanes(rays.kernel, n, rays.batch, ids, &mut lists);
        for l in 0..WIDTH {
            let c = n.child[l];
            if len[l] == 0 || c == NO_CHILD {
                continue;
            }
            if c & LEAF != 0 {
                visit(&lists[l][..len[l]], c & !LEAF);
            } else {
                self.list_walk(c as usize, rays, &lists[l][..len[l]], depth + 1, levels, visit);
            }
        }
        levels[depth] = lists;
    }
}

/// The rays of a batch, and the build of the list loop this processor runs.
struct Rays<'a> {
    batch: &'a [WalkRay],
    kernel: Kernel,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::entity::bvh::tests::{boxes_strategy, grid_boxes};
    use proptest::prelude::*;

    /// Rays in runs: some runs share an origin and turn a little from ray to ray (camera
    /// rays, walked as groups), the rest start anywhere in any direction, axis-parallel
    /// ones included.
    fn rays() -> impl Strategy<Value = Vec<WalkRay>> {
        let direction = prop::array::uniform3(prop_oneof![Just(0.0), -1.0f64..1.0])
            .prop_filter("a direction", |d| d.iter().any(|&v| v != 0.0));
        let run = (
            prop::array::uniform3(-20.0f64..120.0),
            direction,
            any::<bool>(),
            1usize..40,
            0.0f64..30.0,
            1.0f64..200.0,
        )
            .prop_map(|(o, d, fan, n, t_lo, len)| {
                (0..n)
                    .map(|k| {
                        let turn = 0.01 * k as f64;
                        let (o, d) = if fan {
                            (o, [d[0] + turn, d[1], d[2] - turn])
                        } else {
                            (
                                [o[0] + 7.0 * turn, o[1] * (1.0 - turn), o[2]],
                                [d[1] - turn, d[2], d[0]],
                            )
                        };
                        WalkRay::new(o, d, t_lo, t_lo + len)
                    })
                    .collect::<Vec<_>>()
            });
        prop::collection::vec(run, 1..80).prop_map(|runs| runs.concat())
    }

    proptest! {
        /// A batch finds, for every ray, exactly the primitives the ray's own walk finds.
        #[test]
        fn a_batch_finds_what_each_rays_walk_finds(boxes in boxes_strategy(), rays in rays()) {
            let bvh = Bvh::build(&boxes);
            let mut each = Vec::new();
            for (i, r) in rays.iter().enumerate() {
                bvh.crossing(r, |k| each.push((i as u32, k)));
            }
            let mut scratch = Scratch::default();
            let batch = bvh.crossing_many(&rays, &mut scratch);
            each.sort_unstable();
            batch.sort_unstable();
            prop_assert_eq!(batch, each);
        }
    }

    /// A coherent group's interval bounds each of its rays' entry and exit times, so the
    /// group enters every box one of its rays enters.
    #[test]
    fn a_groups_interval_holds_its_rays() {
        let bvh = Bvh::build(&grid_boxes(4, 20.0, 5.0));
        let group: Vec<WalkRay> = (0..GROUP)
            .map(|k| WalkRay::new([-5.0, -3.0, -4.0], [1.0, 0.6 + 0.02 * k as f64, 0.8], 0.0, 500.0))
            .collect();
        let bounds = Interval::of(&group).expect("one origin and the same signs make a group");
        for n in &bvh.nodes {
            let (g_near, g_far) = bounds.lanes(n);
            for r in &group {
                let (near, far) = r.lanes(n);
                for l in 0..WIDTH {
                    assert!(g_near[l] <= near[l] && far[l] <= g_far[l]);
                }
            }
        }
        let mut apart = group.clone();
        apart[3] = WalkRay::new([-5.0, -3.0, -4.5], [1.0, 0.6, 0.8], 0.0, 500.0);
        assert!(Interval::of(&apart).is_none(), "two origins");
    }
}

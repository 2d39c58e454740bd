//! Walks of many rays at once ([`Bvh::crossing_many`]): the same answers as
//! [`Bvh::crossing`] ray by ray, for less work per ray.
//!
//! One ray's walk is a chain of dependent steps (load a node, test its four boxes, branch on
//! each, pop the next), and for incoherent rays those branches are guesses the processor
//! often gets wrong. A batch is walked instead:
//! - **Coherent groups** ([`GROUP`] consecutive rays from one origin, moving the same way on
//!   every axis, such as neighbouring camera rays) walk the tree once per group, each node
//!   tested against the interval that bounds the group's rays: a group may enter a node
//!   only if that interval enters it. Two neighbouring groups that share their origin and
//!   signs walk it once together, bounded by the union of their intervals, and gather the
//!   instance lanes that walk reaches; each group then tests its own interval against
//!   those, and at an instance its group enters, each ray is tested on its own.
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
use super::{Bvh, EMPTY_NODE, LEAF, NO_CHILD, STACK};
use smallvec::SmallVec;

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
    packs: Vec<Node>,
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

/// Neighbouring coherent runs that walk the tree together when they share an origin and
/// signs: the walk's node tests are shared, and each run still tests its own rays only
/// against the instances its own bounds reach.
const RUNS: usize = 2;

/// A coherent run of consecutive rays of a batch: the first one's index in the walk, the
/// rays, and their bounds.
struct Run<'a> {
    first: u32,
    rays: &'a [WalkRay],
    bounds: Interval,
}

impl Run<'_> {
    /// The bounds of every ray of `runs`, if there are several runs and they share an origin
    /// and signs.
    fn joined(runs: &[Run]) -> Option<Interval> {
        let (first, rest) = runs.split_first()?;
        if rest.is_empty() {
            return None;
        }
        rest.iter()
            .try_fold(first.bounds.clone(), |all, run| all.joined(&run.bounds))
    }
}

/// What bounds every ray of a group: their one origin, each axis's range of `1/d`, and
/// the union of their windows.
#[derive(Clone)]
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

    /// The bounds of both groups, if they share an origin and signs.
    fn joined(&self, b: &Interval) -> Option<Interval> {
        for a in 0..3 {
            if self.o[a] != b.o[a] || (self.inv_lo[a] > 0.0) != (b.inv_lo[a] > 0.0) {
                return None;
            }
        }
        Some(Interval {
            o: self.o,
            inv_lo: std::array::from_fn(|a| lane_min(self.inv_lo[a], b.inv_lo[a])),
            inv_hi: std::array::from_fn(|a| lane_max(self.inv_hi[a], b.inv_hi[a])),
            t_lo: lane_min(self.t_lo, b.t_lo),
            t_hi: lane_max(self.t_hi, b.t_hi),
        })
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
            for (s, pair) in batch.chunks(GROUP * RUNS).enumerate() {
                let mut runs: SmallVec<[Run; RUNS]> = SmallVec::new();
                for (g, rays) in pair.chunks(GROUP).enumerate() {
                    let first = s * GROUP * RUNS + g * GROUP;
                    match Interval::of(rays).filter(|_| rays.len() > 1) {
                        Some(bounds) => runs.push(Run {
                            first: base + first as u32,
                            rays,
                            bounds,
                        }),
                        None => scratch.incoherent.extend(first as u16..(first + rays.len()) as u16),
                    }
                }
                match Run::joined(&runs) {
                    Some(shared) => self.runs_walk(&runs, &shared, &mut scratch.packs, &mut met),
                    None => {
                        for run in &runs {
                            self.runs_walk(std::slice::from_ref(run), &run.bounds, &mut scratch.packs, &mut met);
                        }
                    }
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

    /// One walk for coherent runs that share an origin and signs, bounded by `shared`, which
    /// bounds all their rays: the leaf lanes it reaches are gathered four to a node, then
    /// each run's bounds are tested against those, and each ray of a run against the lanes
    /// its run enters.
    fn runs_walk(&self, runs: &[Run], shared: &Interval, packs: &mut Vec<Node>, met: &mut Met) {
        self.leaf_packs(shared, packs);
        for run in runs {
            for p in packs.iter() {
                let (near, far) = run.bounds.lanes(p);
                for l in 0..WIDTH {
                    let c = p.child[l];
                    if near[l] > far[l] || c == NO_CHILD {
                        continue;
                    }
                    met.room(run.rays.len());
                    for (i, r) in (run.first..).zip(run.rays) {
                        let (near, far) = r.lanes(p);
                        met.put((i, c & !LEAF), near[l] <= far[l]);
                    }
                }
            }
        }
    }

    /// Every leaf lane that a walk bounded by `bounds` reaches, copied four to a node into
    /// `packs` (the same `f32` box, so a ray's test of it is the one its own walk makes).
    fn leaf_packs(&self, bounds: &Interval, packs: &mut Vec<Node>) {
        packs.clear();
        let mut filled = WIDTH;
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
                if filled == WIDTH {
                    packs.push(EMPTY_NODE);
                    filled = 0;
                }
                let p = packs.last_mut().expect("a pack was pushed");
                for a in 0..3 {
                    p.lo[a][filled] = n.lo[a][l];
                    p.hi[a][filled] = n.hi[a][l];
                }
                p.child[filled] = c;
                filled += 1;
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

    /// Pairs (ray, primitive).
    type Pairs = Vec<(u32, u32)>;

    /// The pairs each ray's own walk finds, and those a batch walk of all finds, sorted.
    fn each_and_batch(bvh: &Bvh, rays: &[WalkRay]) -> (Pairs, Pairs) {
        let mut each = Vec::new();
        for (i, r) in rays.iter().enumerate() {
            bvh.crossing(r, |k| each.push((i as u32, k)));
        }
        let mut batch = bvh.crossing_many(rays, &mut Scratch::default()).to_vec();
        each.sort_unstable();
        batch.sort_unstable();
        (each, batch)
    }

    /// Whether `bounds` holds every ray of `rays` at every lane of every node of `bvh`.
    fn holds(bounds: &Interval, rays: &[WalkRay], bvh: &Bvh) -> bool {
        bvh.nodes.iter().all(|n| {
            let (b_near, b_far) = bounds.lanes(n);
            rays.iter().all(|r| {
                let (near, far) = r.lanes(n);
                (0..WIDTH).all(|l| b_near[l] <= near[l] && far[l] <= b_far[l])
            })
        })
    }

    proptest! {
        /// A batch finds, for every ray, exactly the primitives the ray's own walk finds.
        #[test]
        fn a_batch_finds_what_each_rays_walk_finds(boxes in boxes_strategy(), rays in rays()) {
            let (each, batch) = each_and_batch(&Bvh::build(&boxes), &rays);
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
        assert!(holds(&bounds, &group, &bvh));
        let mut apart = group.clone();
        apart[3] = WalkRay::new([-5.0, -3.0, -4.5], [1.0, 0.6, 0.8], 0.0, 500.0);
        assert!(Interval::of(&apart).is_none(), "two origins");
    }

    /// Camera rays: neighbouring coherent runs walk the tree together (their joined bounds
    /// hold every ray of both), runs that part in origin or signs walk alone, and either way
    /// each ray meets exactly what its own walk meets.
    #[test]
    fn neighbouring_runs_walk_together_and_find_what_each_ray_finds() {
        let bvh = Bvh::build(&grid_boxes(6, 15.0, 4.0));
        // Four rows of a 64-pixel image from one camera; the columns cross x = 0, where the
        // sign of `d.x` changes, and the last row comes from another camera.
        let rays: Vec<WalkRay> = (0..256)
            .map(|k| {
                let (row, col) = (k / 64, k % 64);
                let o = if row == 3 {
                    [40.0, 100.0, -30.0]
                } else {
                    [40.0, 40.0, -30.0]
                };
                let d = [(f64::from(col) - 40.0) / 64.0, (f64::from(row) - 1.5) / 8.0, 1.0];
                WalkRay::new(o, d, 0.0, 150.0)
            })
            .collect();
        let runs = |starts: &[usize]| -> Vec<Run> {
            starts
                .iter()
                .map(|&k| Run {
                    first: k as u32,
                    rays: &rays[k..k + GROUP],
                    bounds: Interval::of(&rays[k..k + GROUP]).expect("a coherent run"),
                })
                .collect()
        };
        let shared = Run::joined(&runs(&[0, 16])).expect("one origin, the same signs");
        assert!(holds(&shared, &rays[0..32], &bvh));
        assert!(
            !holds(&runs(&[0])[0].bounds, &rays[0..32], &bvh),
            "one run's bounds hold less"
        );
        assert!(Run::joined(&runs(&[0])).is_none(), "one run walks alone");
        assert!(Run::joined(&runs(&[176, 240])).is_none(), "another origin");
        assert!(Run::joined(&runs(&[0, 48])).is_none(), "other signs");
        assert!(Interval::of(&rays[32..48]).is_none(), "signs change in this run");
        let (each, batch) = each_and_batch(&bvh, &rays);
        assert!(each.len() > 50, "the rays meet boxes");
        assert_eq!(batch, each);
    }
}

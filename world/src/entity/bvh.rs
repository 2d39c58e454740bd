//! [`Bvh`]: a bounding-volume hierarchy over the entity instances' world boxes, built
//! with binned SAH, so that a ray finds the instances it may hit without looking at the
//! chunks it passes. Like [`super::bounds::Bounds`], it is derived on every machine from the
//! instance records: neither mirrored nor digested, and it changes only the work a ray
//! test takes, never its result.
//!
//! The nodes are a flat array in depth-first order: an inner node's first child follows
//! it, and it stores where its second child is; a leaf stores a run of `prims`.

use super::bounds::slab;

/// An axis-aligned box `(lo, hi)`.
pub type Aabb = ([f64; 3], [f64; 3]);

/// Bins per axis of the SAH sweep.
const BINS: usize = 16;
/// Most primitives a leaf holds.
const LEAF_MAX: usize = 4;
/// The cost of visiting a node, relative to testing one primitive's box.
const TRAVERSAL_COST: f64 = 1.0;

/// One node: its box, and either its children (`count == 0`: the first child is the next
/// node, the second is `index`) or its primitives (`prims[index..index + count]`).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Node {
    bounds: Aabb,
    index: u32,
    count: u32,
}

/// A bounding-volume hierarchy over a list of boxes (primitive `i` is box `i`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bvh {
    nodes: Vec<Node>,
    prims: Vec<u32>,
}

fn union(a: &Aabb, b: &Aabb) -> Aabb {
    (
        std::array::from_fn(|k| a.0[k].min(b.0[k])),
        std::array::from_fn(|k| a.1[k].max(b.1[k])),
    )
}

const EMPTY: Aabb = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);

/// Half the surface area of a box (the SAH compares ratios, so the factor does not matter).
fn half_area(b: &Aabb) -> f64 {
    let e: [f64; 3] = std::array::from_fn(|k| (b.1[k] - b.0[k]).max(0.0));
    e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
}

fn centre(b: &Aabb, axis: usize) -> f64 {
    0.5 * (b.0[axis] + b.1[axis])
}

impl Bvh {
    /// The hierarchy over `boxes`: each node split where the binned surface-area heuristic
    /// says a ray pays least, until a split would cost more than testing the boxes.
    ///
    /// ```
    /// use naadf_world::entity::bvh::Bvh;
    /// // A row of 100 unit boxes, 10 apart along x.
    /// let boxes: Vec<_> = (0..100).map(|i| {
    ///     let x = 10.0 * f64::from(i);
    ///     ([x, 0.0, 0.0], [x + 1.0, 1.0, 1.0])
    /// }).collect();
    /// let bvh = Bvh::build(&boxes);
    /// let mut met = Vec::new();
    /// // A ray along +z through the first box: it is found, with at most its leaf's others.
    /// bvh.crossing([0.5, 0.5, -1.0], [f64::INFINITY, f64::INFINITY, 1.0], 0.0, 100.0, |i| met.push(i));
    /// assert!(met.contains(&0) && met.len() <= 4);
    /// ```
    pub fn build(boxes: &[Aabb]) -> Self {
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * boxes.len()),
            prims: (0..boxes.len() as u32).collect(),
        };
        if !boxes.is_empty() {
            bvh.split(boxes, 0, boxes.len());
        }
        bvh
    }

    /// Appends the node over `prims[start..end]` and, below it, its subtree.
    fn split(&mut self, boxes: &[Aabb], start: usize, end: usize) {
        let at = self.nodes.len();
        let run = &self.prims[start..end];
        let bounds = run.iter().fold(EMPTY, |b, &p| union(&b, &boxes[p as usize]));
        self.nodes.push(Node {
            bounds,
            index: start as u32,
            count: (end - start) as u32,
        });
        let n = end - start;
        if n <= 1 {
            return;
        }
        let Some(cut) = best_cut(boxes, run) else {
            return;
        };
        // A small run stays one leaf unless visiting two children and testing their boxes
        // costs less than testing its own.
        let split_cost = 2.0 * TRAVERSAL_COST + cut.cost / half_area(&bounds).max(f64::MIN_POSITIVE);
        if n <= LEAF_MAX && split_cost >= n as f64 {
            return;
        }
        // The cut leaves primitives on both sides ([`best_cut`] skips empty ones).
        let (lower, upper): (Vec<u32>, Vec<u32>) = run
            .iter()
            .partition(|&&p| bin_of(centre(&boxes[p as usize], cut.axis), cut.lo, cut.hi) < cut.bin);
        let mid = start + lower.len();
        self.prims[start..mid].copy_from_slice(&lower);
        self.prims[mid..end].copy_from_slice(&upper);
        self.nodes[at].count = 0;
        self.split(boxes, start, mid);
        self.nodes[at].index = self.nodes.len() as u32;
        self.split(boxes, mid, end);
    }

    /// Calls `visit` once with every primitive whose box the ray `o + t·d` (`inv_d` = 1/d per
    /// axis) is inside at some `t` in `[t_lo, t_hi]`, in no particular order, and with the
    /// others of the leaves those are in (a leaf's boxes are not tested one by one: the
    /// caller tests each primitive exactly anyway).
    pub fn crossing(&self, o: [f64; 3], inv_d: [f64; 3], t_lo: f64, t_hi: f64, mut visit: impl FnMut(u32)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack: smallvec::SmallVec<[u32; 32]> = smallvec::smallvec![0];
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i as usize];
            if slab(o, inv_d, node.bounds.0, node.bounds.1, t_lo, t_hi).is_none() {
                continue;
            }
            if node.count > 0 {
                let run = &self.prims[node.index as usize..(node.index + node.count) as usize];
                run.iter().for_each(|&p| visit(p));
            } else {
                stack.push(node.index);
                stack.push(i + 1);
            }
        }
    }
}

/// The range of the primitives' centres along `axis`.
fn centre_range(boxes: &[Aabb], run: &[u32], axis: usize) -> (f64, f64) {
    run.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &p| {
        let c = centre(&boxes[p as usize], axis);
        (lo.min(c), hi.max(c))
    })
}

fn bin_of(c: f64, lo: f64, hi: f64) -> usize {
    if hi <= lo {
        return 0;
    }
    (((c - lo) / (hi - lo) * BINS as f64) as usize).min(BINS - 1)
}

/// A split of a run of primitives by the binned SAH: the primitives whose centre along
/// `axis` falls in a bin below `bin` (of `BINS` over the centres' range `lo..hi`) go to the
/// lower child.
struct Cut {
    axis: usize,
    lo: f64,
    hi: f64,
    bin: usize,
    /// Each side's half area times its primitive count, summed.
    cost: f64,
}

/// The cheapest split of `run` by the binned SAH that leaves primitives on both sides;
/// `None` when the centres coincide.
fn best_cut(boxes: &[Aabb], run: &[u32]) -> Option<Cut> {
    let mut best: Option<Cut> = None;
    for axis in 0..3 {
        let (lo, hi) = centre_range(boxes, run, axis);
        if hi <= lo {
            continue;
        }
        let mut bins = [(EMPTY, 0usize); BINS];
        for &p in run {
            let b = &mut bins[bin_of(centre(&boxes[p as usize], axis), lo, hi)];
            b.0 = union(&b.0, &boxes[p as usize]);
            b.1 += 1;
        }
        // Sweep from above: the area and count of bins `k..` for each cut `k`.
        let mut above = [(0.0, 0usize); BINS];
        let (mut acc, mut count) = (EMPTY, 0);
        for k in (1..BINS).rev() {
            acc = union(&acc, &bins[k].0);
            count += bins[k].1;
            above[k] = (half_area(&acc), count);
        }
        let (mut acc, mut count) = (EMPTY, 0);
        for k in 1..BINS {
            acc = union(&acc, &bins[k - 1].0);
            count += bins[k - 1].1;
            let (area_above, count_above) = above[k];
            if count == 0 || count_above == 0 {
                continue;
            }
            let cost = half_area(&acc) * count as f64 + area_above * count_above as f64;
            if best.as_ref().is_none_or(|b| cost < b.cost) {
                best = Some(Cut {
                    axis,
                    lo,
                    hi,
                    bin: k,
                    cost,
                });
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn boxes_strategy() -> impl Strategy<Value = Vec<Aabb>> {
        prop::collection::vec(
            (
                prop::array::uniform3(0.0f64..100.0),
                prop::array::uniform3(0.0f64..12.0),
            ),
            0..200,
        )
        .prop_map(|v| {
            v.into_iter()
                .map(|(lo, e)| (lo, std::array::from_fn(|k| lo[k] + e[k])))
                .collect()
        })
    }

    fn ray_strategy() -> impl Strategy<Value = ([f64; 3], [f64; 3])> {
        (
            prop::array::uniform3(-20.0f64..120.0),
            prop::array::uniform3(prop_oneof![Just(0.0), -1.0f64..1.0]),
        )
            .prop_filter("a direction", |(_, d)| d.iter().any(|&v| v != 0.0))
    }

    proptest! {
        /// The hierarchy reports every box a brute-force slab test finds the ray inside
        /// within the interval (rays parallel to axes and along faces included), each
        /// primitive at most once.
        #[test]
        fn the_crossed_boxes_include_the_brute_force_ones(boxes in boxes_strategy(), (o, d) in ray_strategy(),
            t_lo in 0.0f64..50.0, len in 0.0f64..200.0) {
            let bvh = Bvh::build(&boxes);
            let inv_d = d.map(|v| 1.0 / v);
            let mut met = Vec::new();
            bvh.crossing(o, inv_d, t_lo, t_lo + len, |p| met.push(p));
            met.sort_unstable();
            let once = met.windows(2).all(|w| w[0] < w[1]);
            prop_assert!(once, "{:?}", met);
            for i in 0..boxes.len() as u32 {
                if slab(o, inv_d, boxes[i as usize].0, boxes[i as usize].1, t_lo, t_lo + len).is_some() {
                    prop_assert!(met.binary_search(&i).is_ok(), "box {} is crossed", i);
                }
            }
        }

        /// Every primitive is in exactly one leaf, and every node's box holds its subtree's.
        #[test]
        fn the_hierarchy_is_well_formed(boxes in boxes_strategy()) {
            let bvh = Bvh::build(&boxes);
            let mut seen = vec![0u32; boxes.len()];
            fn check(bvh: &Bvh, boxes: &[Aabb], i: usize, seen: &mut [u32]) -> Aabb {
                let n = bvh.nodes[i];
                let inner = if n.count > 0 {
                    bvh.prims[n.index as usize..(n.index + n.count) as usize].iter().fold(EMPTY, |b, &p| {
                        seen[p as usize] += 1;
                        union(&b, &boxes[p as usize])
                    })
                } else {
                    union(&check(bvh, boxes, i + 1, seen), &check(bvh, boxes, n.index as usize, seen))
                };
                assert!((0..3).all(|k| n.bounds.0[k] <= inner.0[k] && inner.1[k] <= n.bounds.1[k]));
                inner
            }
            if !boxes.is_empty() {
                check(&bvh, &boxes, 0, &mut seen);
            }
            prop_assert!(seen.iter().all(|&s| s == 1));
        }
    }

    /// Scattered boxes give a hierarchy that a short ray walks in a few nodes, not all.
    #[test]
    fn a_ray_visits_few_nodes_among_many_boxes() {
        let boxes: Vec<Aabb> = (0..1000)
            .map(|i| {
                let lo = [
                    f64::from(i % 10) * 50.0,
                    f64::from(i / 10 % 10) * 50.0,
                    f64::from(i / 100) * 50.0,
                ];
                (lo, lo.map(|v| v + 3.0))
            })
            .collect();
        let bvh = Bvh::build(&boxes);
        assert!(bvh.nodes.len() < 1000, "{} nodes", bvh.nodes.len());
        let mut met = Vec::new();
        bvh.crossing(
            [1.0, 1.0, -10.0],
            [f64::INFINITY, f64::INFINITY, 1.0],
            0.0,
            1000.0,
            |p| met.push(p),
        );
        met.sort_unstable();
        assert_eq!(met, (0..10).map(|k| k * 100).collect::<Vec<u32>>());
    }
}

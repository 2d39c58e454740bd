//! [`Bvh`]: a four-wide bounding-volume hierarchy over the entity instances' world boxes,
//! through which every ray finds the instances it may hit (docs/NAADF.md §11). Like the
//! instances' boxes (`entity::bounds`), it is derived on every machine from the records:
//! neither mirrored nor digested, and it changes only the work a ray test takes, never its
//! result.
//!
//! It is built in two steps. A binary tree is split top-down by the binned surface-area
//! heuristic down to one instance per leaf (runs of at most [`WIDTH`], and every run below
//! 24 levels, at the median instead, which bounds the depth: [`MAX_DEPTH`]). Then every
//! binary node's children and grandchildren become the children of one four-wide node, so a
//! ray tests four boxes at once (as four lanes on the CPU) and visits half as many levels.
//!
//! The packed form ([`Bvh::words`], docs/FORMAT.md §5.10) is what the GPU walks, node by
//! node of [`NODE_WORDS`] words: the children's boxes as `f32`, axis by axis (`lo.x` of the
//! four children, then `hi.x`, `lo.y`, `hi.y`, `lo.z`, `hi.z`), then the four child
//! references: [`LEAF`]` | slot` for an instance (its slot in the instance buffer), a node
//! index, or [`NO_CHILD`]. Node 0 is the root. Boxes are rounded outward to `f32` and
//! padded by [`F32_PAD`], so that a test in `f32` arithmetic never rejects a box the exact
//! one would enter.

pub mod batch;
mod lane_sort;
mod node;

pub use node::{FAR, WIDTH, WalkRay};
use node::{Node, lanes};

/// An axis-aligned box `(lo, hi)`.
pub type Aabb = ([f64; 3], [f64; 3]);

/// Words of a packed node: six axis rows of four `f32`, then four child references.
pub const NODE_WORDS: usize = 7 * WIDTH;
/// A child reference's flag for an instance (the low bits are its slot).
pub const LEAF: u32 = 0x8000_0000;
/// An unused child slot (its box is the point [`FAR`] on every axis).
pub const NO_CHILD: u32 = u32::MAX;
/// Stack entries a traversal needs at most: each node popped pushes at most three more
/// than it takes, over at most [`MAX_DEPTH`] levels.
pub const STACK: usize = 64;
/// Levels of four-wide nodes below the root at most (half the binary depth bound).
pub const MAX_DEPTH: usize = (SAH_DEPTH + 14) / 2;
// A traversal pops one node and pushes at most four, level by level, over at most one
// level more than a build makes: the root that `joined_words` puts above two hierarchies.
const _: () = assert!(3 * (MAX_DEPTH + 1) < STACK);
/// Binary levels split by the SAH; deeper runs are split at the median, so that the
/// binary depth stays below `SAH_DEPTH + log2(16383)` and the stack bound holds.
pub const SAH_DEPTH: usize = 24;
/// Bins per axis of the SAH sweep.
pub const BINS: usize = 16;
/// Padding of an instance's world and oriented boxes (`entity::bounds`), in voxels:
/// far above the rounding of the rotation, far below a voxel, so that the boxes only ever
/// let more rays through to the exact test.
pub const BOUNDS_PAD: f64 = 1.0 / 64.0;
/// Outward padding of the `f32` boxes, in voxels: far above what `f32` rounding of a
/// position below 2^15 moves a plane (2^-9 voxel), so the `f32` test stays conservative.
pub const F32_PAD: f32 = 1.0 / 64.0;

const EMPTY_NODE: Node = Node {
    lo: [[FAR; WIDTH]; 3],
    hi: [[FAR; WIDTH]; 3],
    child: [NO_CHILD; WIDTH],
};

/// A four-wide bounding-volume hierarchy over a list of boxes (primitive `i` is box `i`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bvh {
    nodes: Vec<Node>,
}

/// A node of the binary tree the four-wide one is made from.
struct Binary {
    bounds: Aabb,
    /// The two children, or `None` for a leaf of one primitive (`prim`).
    children: Option<(usize, usize)>,
    prim: u32,
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
    /// The hierarchy over `boxes`.
    ///
    /// ```
    /// use naadf_world::entity::bvh::{Bvh, WalkRay};
    /// // A row of 100 unit boxes, 10 apart along x.
    /// let boxes: Vec<_> = (0..100).map(|i| {
    ///     let x = 10.0 * f64::from(i);
    ///     ([x, 0.0, 0.0], [x + 1.0, 1.0, 1.0])
    /// }).collect();
    /// let bvh = Bvh::build(&boxes);
    /// let mut met = Vec::new();
    /// // A ray along +z through the first box finds it alone.
    /// let ray = WalkRay::new([0.5, 0.5, -1.0], [0.0, 0.0, 1.0], 0.0, 100.0);
    /// bvh.crossing(&ray, |i| met.push(i));
    /// assert_eq!(met, [0]);
    /// ```
    pub fn build(boxes: &[Aabb]) -> Self {
        let mut bvh = Bvh::default();
        if boxes.is_empty() {
            return bvh;
        }
        let mut prims: Vec<u32> = (0..boxes.len() as u32).collect();
        let mut tree = Vec::with_capacity(2 * boxes.len());
        let input = Input {
            boxes,
            centres: boxes.iter().map(|b| [0, 1, 2].map(|a| centre(b, a))).collect(),
        };
        let root = split(&mut tree, &input, &mut prims, 0);
        bvh.widen(&tree, root);
        bvh
    }

    /// Appends the four-wide node made of binary node `at`'s children and grandchildren
    /// (a leaf root is the one child of the root), and below it their subtrees; returns
    /// its index.
    fn widen(&mut self, tree: &[Binary], at: usize) -> u32 {
        let index = self.nodes.len();
        self.nodes.push(EMPTY_NODE);
        let mut lanes: smallvec::SmallVec<[usize; WIDTH]> = smallvec::SmallVec::new();
        match tree[at].children {
            None => lanes.push(at),
            Some((a, b)) => {
                for c in [a, b] {
                    match tree[c].children {
                        Some((x, y)) => lanes.extend([x, y]),
                        None => lanes.push(c),
                    }
                }
            }
        }
        for (lane, &c) in lanes.iter().enumerate() {
            let (lo, hi) = tree[c].bounds;
            let child = match tree[c].children {
                None => LEAF | tree[c].prim,
                Some(_) => self.widen(tree, c),
            };
            let node = &mut self.nodes[index];
            for a in 0..3 {
                node.lo[a][lane] = outward(lo[a], false);
                node.hi[a][lane] = outward(hi[a], true);
            }
            node.child[lane] = child;
        }
        index as u32
    }

    /// Moves the hierarchy to new `boxes` of the same primitives without changing its
    /// shape (a refit): each lane's box becomes its primitive's box, or the union of its
    /// child node's lanes. Refitting the boxes a hierarchy was built from gives that
    /// hierarchy back; for other boxes it is cheaper than [`Bvh::build`], but a shape
    /// made for other positions may make rays visit far more nodes
    /// ([`Bvh::expected_visits`] tells how many).
    pub fn refit(&mut self, boxes: &[Aabb]) {
        if !self.nodes.is_empty() {
            self.refit_node(0, boxes);
        }
    }

    /// Refits node `i` and the nodes below it; returns the union of its lanes.
    fn refit_node(&mut self, i: usize, boxes: &[Aabb]) -> Aabb {
        let mut all = EMPTY;
        for lane in 0..WIDTH {
            let c = self.nodes[i].child[lane];
            if c == NO_CHILD {
                continue;
            }
            let (lo, hi) = if c & LEAF != 0 {
                boxes[(c & !LEAF) as usize]
            } else {
                self.refit_node(c as usize, boxes)
            };
            let node = &mut self.nodes[i];
            for a in 0..3 {
                node.lo[a][lane] = outward(lo[a], false);
                node.hi[a][lane] = outward(hi[a], true);
            }
            all = union(&all, &(lo, hi));
        }
        all
    }

    /// The surface-area estimate of the nodes a ray that meets the root's box visits: the
    /// sum over nodes of their box's area relative to the root's (the root counts 1). A
    /// measure of a shape's quality that needs no rays.
    pub fn expected_visits(&self) -> f64 {
        let lanes = |n: &Node, l: usize| -> Aabb {
            (
                std::array::from_fn(|a| f64::from(n.lo[a][l])),
                std::array::from_fn(|a| f64::from(n.hi[a][l])),
            )
        };
        let Some(root) = self.nodes.first() else {
            return 0.0;
        };
        let used = |n: &Node| -> smallvec::SmallVec<[usize; WIDTH]> {
            (0..WIDTH).filter(|&l| n.child[l] != NO_CHILD).collect()
        };
        let root_box = used(root).into_iter().fold(EMPTY, |b, l| union(&b, &lanes(root, l)));
        let mut inner = 0.0;
        for n in &self.nodes {
            for l in used(n) {
                if n.child[l] & LEAF == 0 {
                    inner += half_area(&lanes(n, l));
                }
            }
        }
        1.0 + inner / half_area(&root_box)
    }

    /// Calls `visit` once with every primitive whose box `ray` is inside at some time in its
    /// window, in no particular order, and perhaps with a few more whose boxes it passes
    /// within [`F32_PAD`] (the caller tests each exactly anyway). Boxes are tested in
    /// `f32`, four at a time. For many rays at once, [`Bvh::crossing_many`] gives the same
    /// answers for less work.
    pub fn crossing(&self, ray: &WalkRay, visit: impl FnMut(u32)) {
        if self.nodes.is_empty() {
            return;
        }
        self.crossing_below(0, ray, visit);
    }

    /// [`Bvh::crossing`] below node `at` (whose box the ray enters).
    fn crossing_below(&self, at: u32, ray: &WalkRay, mut visit: impl FnMut(u32)) {
        let (o, inv, t_lo, t_hi) = ray.parts();
        let mut stack = [0u32; STACK];
        stack[0] = at;
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let n = &self.nodes[stack[sp] as usize];
            let (near, far) = lanes(n, o, inv, t_lo, t_hi);
            for l in 0..WIDTH {
                let c = n.child[l];
                if near[l] > far[l] || c == NO_CHILD {
                    continue;
                }
                if c & LEAF != 0 {
                    visit(c & !LEAF);
                } else {
                    stack[sp] = c;
                    sp += 1;
                }
            }
        }
    }

    /// The packed nodes (see the module docs), with each leaf's primitive `k` replaced by
    /// `slot_of[k]`.
    pub fn words(&self, slot_of: &[u32]) -> Vec<u32> {
        let mut out = Vec::with_capacity(self.nodes.len() * NODE_WORDS);
        for n in &self.nodes {
            for a in 0..3 {
                out.extend(n.lo[a].map(f32::to_bits));
                out.extend(n.hi[a].map(f32::to_bits));
            }
            out.extend(n.child.map(|c| {
                if c != NO_CHILD && c & LEAF != 0 {
                    LEAF | slot_of[(c & !LEAF) as usize]
                } else {
                    c
                }
            }));
        }
        out
    }

    /// Nodes in the hierarchy.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }
}

/// The packed form of one hierarchy over the primitives of two packed hierarchies `a` and
/// `b` (each as [`Bvh::words`] gives it), with `b`'s leaf slots moved up by `b_slots`: a new
/// root whose first two lanes hold `a`'s and `b`'s roots, then `a`'s nodes and `b`'s. A
/// device whose instance buffer holds local instances after the world's walks this, so that
/// a change of either rebuilds only its own hierarchy.
pub fn joined_words(a: &[u32], b: &[u32], b_slots: u32) -> Vec<u32> {
    let shift = |words: &[u32], nodes: u32, slots: u32, out: &mut Vec<u32>| {
        for node in words.chunks_exact(NODE_WORDS) {
            out.extend_from_slice(&node[..6 * WIDTH]);
            out.extend(node[6 * WIDTH..].iter().map(|&c| match c {
                NO_CHILD => c,
                c if c & LEAF != 0 => c + slots,
                c => c + nodes,
            }));
        }
    };
    let mut out = Vec::with_capacity(a.len() + b.len() + NODE_WORDS);
    if a.is_empty() || b.is_empty() {
        let (words, slots) = if a.is_empty() { (b, b_slots) } else { (a, 0) };
        shift(words, 0, slots, &mut out);
        return out;
    }
    // The new root: lane 0 bounds `a`'s root lanes, lane 1 `b`'s.
    let mut root = [0u32; NODE_WORDS];
    for (lane, words) in [a, b].into_iter().enumerate() {
        let used: Vec<usize> = (0..WIDTH).filter(|&l| words[6 * WIDTH + l] != NO_CHILD).collect();
        for row in 0..6 {
            let v = used.iter().map(|&l| f32::from_bits(words[row * WIDTH + l]));
            // Rows alternate lo, hi per axis.
            let bound = if row % 2 == 0 {
                v.fold(FAR, f32::min)
            } else {
                v.fold(-FAR, f32::max)
            };
            root[row * WIDTH + lane] = bound.to_bits();
        }
    }
    for lane in 2..WIDTH {
        for row in 0..6 {
            root[row * WIDTH + lane] = FAR.to_bits();
        }
    }
    let a_nodes = (a.len() / NODE_WORDS) as u32;
    root[6 * WIDTH..].copy_from_slice(&[1, 1 + a_nodes, NO_CHILD, NO_CHILD]);
    out.extend_from_slice(&root);
    shift(a, 1, 0, &mut out);
    shift(b, 1 + a_nodes, b_slots, &mut out);
    out
}

/// `v` as `f32`, rounded outward (up for an upper bound) and padded by [`F32_PAD`].
fn outward(v: f64, up: bool) -> f32 {
    let p = if up {
        v + f64::from(F32_PAD)
    } else {
        v - f64::from(F32_PAD)
    };
    let f = p as f32;
    if up && f64::from(f) < p {
        f.next_up()
    } else if !up && f64::from(f) > p {
        f.next_down()
    } else {
        f
    }
}

/// What a build splits: each primitive's box and centre.
struct Input<'a> {
    boxes: &'a [Aabb],
    centres: Vec<[f64; 3]>,
}

/// Appends the binary subtree over `prims` (reordering them) and returns its root; `depth`
/// is the level of that root. Runs of at most [`WIDTH`] primitives are split at the median
/// (any split of them makes one four-wide node).
fn split(tree: &mut Vec<Binary>, input: &Input, prims: &mut [u32], depth: usize) -> usize {
    let bounds = prims.iter().fold(EMPTY, |b, &p| union(&b, &input.boxes[p as usize]));
    if let [p] = prims {
        tree.push(Binary {
            bounds,
            children: None,
            prim: *p,
        });
        return tree.len() - 1;
    }
    let cut = if depth < SAH_DEPTH && prims.len() > WIDTH {
        best_cut(input, prims)
    } else {
        None
    };
    let mid = match cut {
        // The cut leaves primitives on both sides ([`best_cut`] skips empty ones).
        Some(cut) => {
            let lower = |p: u32| bin_of(input.centres[p as usize][cut.axis], cut.lo, cut.hi) < cut.bin;
            let (mut i, mut j) = (0, prims.len());
            while i < j {
                if lower(prims[i]) {
                    i += 1;
                } else {
                    j -= 1;
                    prims.swap(i, j);
                }
            }
            i
        }
        None => median(input, prims),
    };
    let (lower, upper) = prims.split_at_mut(mid);
    let a = split(tree, input, lower, depth + 1);
    let b = split(tree, input, upper, depth + 1);
    tree.push(Binary {
        bounds,
        children: Some((a, b)),
        prim: 0,
    });
    tree.len() - 1
}

/// Orders `prims` by their centres along the axis where those spread most (ties by
/// index) and returns the middle.
fn median(input: &Input, prims: &mut [u32]) -> usize {
    let (lo, hi) = centre_ranges(input, prims);
    let axis = (0..3)
        .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
        .unwrap_or(0);
    prims.sort_unstable_by(|&p, &q| {
        input.centres[p as usize][axis]
            .total_cmp(&input.centres[q as usize][axis])
            .then(p.cmp(&q))
    });
    prims.len() / 2
}

/// The range of the primitives' centres on each axis.
fn centre_ranges(input: &Input, run: &[u32]) -> ([f64; 3], [f64; 3]) {
    run.iter()
        .fold(([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]), |(lo, hi), &p| {
            let c = input.centres[p as usize];
            ([0, 1, 2].map(|a| lo[a].min(c[a])), [0, 1, 2].map(|a| hi[a].max(c[a])))
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
/// `None` when the centres coincide. The primitives are binned on all three axes in one
/// pass.
fn best_cut(input: &Input, run: &[u32]) -> Option<Cut> {
    let (lo, hi) = centre_ranges(input, run);
    let mut bins = [[(EMPTY, 0usize); BINS]; 3];
    for &p in run {
        let (c, b) = (input.centres[p as usize], &input.boxes[p as usize]);
        for axis in 0..3 {
            let bin = &mut bins[axis][bin_of(c[axis], lo[axis], hi[axis])];
            bin.0 = union(&bin.0, b);
            bin.1 += 1;
        }
    }
    let mut best: Option<Cut> = None;
    for (axis, bins) in bins.iter().enumerate() {
        if hi[axis] <= lo[axis] {
            continue;
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
                    lo: lo[axis],
                    hi: hi[axis],
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
    use crate::entity::bounds::slab;
    use proptest::prelude::*;

    /// Up to 200 boxes of up to 12 voxels scattered over 100³.
    pub(super) fn boxes_strategy() -> impl Strategy<Value = Vec<Aabb>> {
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

    /// Every node's subtree: the primitives below it, each lane's box holding its child's.
    fn check(bvh: &Bvh, boxes: &[Aabb], i: usize, depth: usize, seen: &mut [u32]) -> usize {
        let n = bvh.nodes[i];
        let mut deepest = depth;
        for l in 0..WIDTH {
            let c = n.child[l];
            if c == NO_CHILD {
                continue;
            }
            let inner = if c & LEAF != 0 {
                seen[(c & !LEAF) as usize] += 1;
                boxes[(c & !LEAF) as usize]
            } else {
                deepest = deepest.max(check(bvh, boxes, c as usize, depth + 1, seen));
                subtree_box(bvh, boxes, c as usize)
            };
            for a in 0..3 {
                assert!(f64::from(n.lo[a][l]) <= inner.0[a] - f64::from(F32_PAD) * 0.99);
                assert!(f64::from(n.hi[a][l]) >= inner.1[a] + f64::from(F32_PAD) * 0.99);
            }
        }
        deepest
    }

    fn subtree_box(bvh: &Bvh, boxes: &[Aabb], i: usize) -> Aabb {
        bvh.nodes[i]
            .child
            .iter()
            .filter(|&&c| c != NO_CHILD)
            .fold(EMPTY, |b, &c| {
                let inner = if c & LEAF != 0 {
                    boxes[(c & !LEAF) as usize]
                } else {
                    subtree_box(bvh, boxes, c as usize)
                };
                union(&b, &inner)
            })
    }

    proptest! {
        /// The hierarchy reports every box a brute-force slab test in `f64` finds the ray
        /// inside within the interval (rays parallel to axes and along faces included),
        /// each primitive at most once.
        #[test]
        fn the_crossed_boxes_include_the_brute_force_ones(boxes in boxes_strategy(), (o, d) in ray_strategy(),
            t_lo in 0.0f64..50.0, len in 0.0f64..200.0) {
            let bvh = Bvh::build(&boxes);
            let inv_d = d.map(|v| 1.0 / v);
            let mut met = Vec::new();
            bvh.crossing(&WalkRay::new(o, d, t_lo, t_lo + len), |p| met.push(p));
            met.sort_unstable();
            let once = met.windows(2).all(|w| w[0] < w[1]);
            prop_assert!(once, "{:?}", met);
            for i in 0..boxes.len() as u32 {
                if slab(o, inv_d, boxes[i as usize].0, boxes[i as usize].1, t_lo, t_lo + len).is_some() {
                    prop_assert!(met.binary_search(&i).is_ok(), "box {} is crossed", i);
                }
            }
        }

        /// Every primitive is in exactly one leaf, every lane's box holds its subtree's
        /// (padded), and the depth stays within the bound the GPU's stack is sized for.
        #[test]
        fn the_hierarchy_is_well_formed(boxes in boxes_strategy()) {
            let bvh = Bvh::build(&boxes);
            let mut seen = vec![0u32; boxes.len()];
            if !boxes.is_empty() {
                prop_assert!(check(&bvh, &boxes, 0, 0, &mut seen) <= MAX_DEPTH);
            }
            prop_assert!(seen.iter().all(|&s| s == 1));
        }
    }

    /// Degenerate inputs (every box the same, or in one long row) keep the depth bound.
    #[test]
    fn degenerate_inputs_keep_the_depth_bound() {
        for boxes in [
            vec![([1.0; 3], [2.0; 3]); 16383],
            (0..16383)
                .map(|i| ([f64::from(i).powi(2); 3], [f64::from(i).powi(2) + 1.0; 3]))
                .collect(),
        ] {
            let bvh = Bvh::build(&boxes);
            let mut seen = vec![0u32; boxes.len()];
            assert!(check(&bvh, &boxes, 0, 0, &mut seen) <= MAX_DEPTH);
            assert!(seen.iter().all(|&s| s == 1));
        }
    }

    /// `n`³ cubes of edge `edge`, `spacing` apart, box `i` at `(i % n, i / n % n, i / n²)`.
    pub(super) fn grid_boxes(n: u32, spacing: f64, edge: f64) -> Vec<Aabb> {
        (0..n * n * n)
            .map(|i| {
                let lo = [i % n, i / n % n, i / n / n].map(|c| f64::from(c) * spacing);
                (lo, lo.map(|v| v + edge))
            })
            .collect()
    }

    /// Scattered boxes give a hierarchy that a short ray walks in a few nodes, not all.
    #[test]
    fn a_ray_finds_just_the_boxes_it_crosses_among_many() {
        let boxes = grid_boxes(10, 50.0, 3.0);
        let bvh = Bvh::build(&boxes);
        assert!(bvh.node_count() < 600, "{} nodes", bvh.node_count());
        let mut met = Vec::new();
        bvh.crossing(&WalkRay::new([1.0, 1.0, -10.0], [0.0, 0.0, 1.0], 0.0, 1000.0), |p| {
            met.push(p)
        });
        met.sort_unstable();
        assert_eq!(met, (0..10).map(|k| k * 100).collect::<Vec<u32>>());
    }

    /// The packed form is the nodes, word for word, with leaves mapped to slots.
    #[test]
    fn a_refit_to_the_same_boxes_is_the_build_and_to_new_ones_stays_exact() {
        let mut rng = crate::raysets::SplitMix64(9);
        let mut boxes_at = |spread: f64| -> Vec<Aabb> {
            (0..300)
                .map(|_| {
                    let c = [0, 1, 2].map(|_| rng.unit() * spread);
                    (c, c.map(|v| v + 3.0))
                })
                .collect()
        };
        let before = boxes_at(200.0);
        let built = Bvh::build(&before);
        let mut refit = built.clone();
        refit.refit(&before);
        assert_eq!(refit, built);
        // Moved everywhere: the old shape still finds exactly the crossed boxes (checked
        // against brute force), only with more visits than a fresh build.
        let after = boxes_at(200.0);
        refit.refit(&after);
        let fresh = Bvh::build(&after);
        assert!(refit.expected_visits() > fresh.expected_visits());
        let mut seen = vec![0u32; after.len()];
        assert!(check(&refit, &after, 0, 0, &mut seen) <= MAX_DEPTH);
        for k in 0..200 {
            let o = [-10.0, f64::from(k), f64::from(k) * 0.7];
            let d = [1.0, 0.3, 0.2];
            let inv = d.map(|v| 1.0 / v);
            let mut met = Vec::new();
            refit.crossing(&WalkRay::new(o, d, 0.0, 400.0), |i| met.push(i));
            for (i, b) in after.iter().enumerate() {
                if slab(o, inv, b.0, b.1, 0.0, 400.0).is_some() {
                    assert!(met.contains(&(i as u32)), "ray {k} misses box {i}");
                }
            }
        }
    }

    #[test]
    fn joined_hierarchies_put_both_roots_under_a_new_one() {
        let a = Bvh::build(&[([0.0; 3], [1.0; 3]), ([5.0; 3], [6.0; 3])]).words(&[0, 1]);
        let b = Bvh::build(&[([9.0, 2.0, 3.0], [10.0, 4.0, 5.0])]).words(&[0]);
        let j = joined_words(&a, &b, 7);
        assert_eq!(j.len(), a.len() + b.len() + NODE_WORDS);
        // The root's lanes: `a`'s root (node 1) spans both of its boxes, `b`'s (node 2) its one.
        assert_eq!(&j[24..28], &[1, 2, NO_CHILD, NO_CHILD]);
        let row = |r: usize, l: usize| f32::from_bits(j[r * WIDTH + l]);
        assert!(row(0, 0) < 0.0 && row(1, 0) > 6.0, "a's x span");
        assert!(
            row(0, 1) < 9.0 && row(1, 1) > 10.0 && row(2, 1) < 2.0 && row(5, 1) > 5.0,
            "b's box"
        );
        assert_eq!(row(0, 2), FAR);
        // `b`'s leaf moved to slot 7; `a`'s kept theirs.
        assert_eq!(j[2 * NODE_WORDS + 24], LEAF | 7);
        assert_eq!(&j[NODE_WORDS + 24..NODE_WORDS + 26], &[LEAF, LEAF | 1]);
        // One side empty: the other, shifted.
        assert_eq!(joined_words(&a, &[], 7), a);
        assert_eq!(joined_words(&[], &b, 7)[24], LEAF | 7);
    }

    #[test]
    fn packed_nodes_map_leaves_to_slots() {
        let boxes = vec![([0.0; 3], [1.0; 3]), ([5.0; 3], [6.0; 3])];
        let bvh = Bvh::build(&boxes);
        let w = bvh.words(&[7, 9]);
        assert_eq!(w.len(), NODE_WORDS);
        let mut refs = w[24..28].to_vec();
        refs.sort_unstable();
        assert_eq!(refs, [LEAF | 7, LEAF | 9, NO_CHILD, NO_CHILD]);
        let lane = w[24..28].iter().position(|&c| c == LEAF | 9).unwrap();
        assert_eq!(f32::from_bits(w[lane]), outward(5.0, false));
        assert_eq!(f32::from_bits(w[4 + lane]), outward(6.0, true));
    }
}

//! The paper's baseline structures (`naadf_world::baselines`: SVDAG, SVO and the hybrid
//! formats) against brute force: every first hit equals the dense grid's and `naadf`'s
//! (voxel, face, `t`) on random and adversarial worlds and rays; byte counts equal a
//! second, simple count made from the dense grid; a repeated pattern deduplicates in the
//! DAG; an empty world is an error.

mod common;

use common::{Raw, Rng, adversarial, random_world, rays, size_for};
use naadf_world::baselines::{Hybrid, Svdag, Svo};
use naadf_world::traverse::{DenseGrid, Hit, Ray, trace_naadf};
use naadf_world::{World, WorldSize};
use std::collections::HashMap;

/// The voxel, face and `t` of a hit (the baselines hold no materials).
fn geometry(h: &Option<Hit>) -> Option<([u32; 3], [i32; 3], f64)> {
    h.map(|h| (h.voxel, h.normal, h.t))
}

fn assert_same_hits(w: &World, dag: &Svdag, svo: &Svo, rays: &[Ray], what: &str) {
    let grid = DenseGrid::from_world(w).unwrap();
    let hybrids: Vec<Hybrid> = hybrid_splits(w.size().voxels())
        .into_iter()
        .map(|(top, depth)| Hybrid::build(dag, top, depth).unwrap())
        .collect();
    for r in rays {
        let expected = geometry(&grid.trace(r));
        assert_eq!(
            geometry(&trace_naadf(w, r)),
            expected,
            "{what}: naadf against the grid, {r:?}"
        );
        assert_eq!(geometry(&dag.trace(r)), expected, "{what}: svdag, {r:?}");
        assert_eq!(geometry(&svo.trace(r)), expected, "{what}: svo, {r:?}");
        for h in &hybrids {
            assert_eq!(geometry(&h.trace(r)), expected, "{what}: {}, {r:?}", h.name());
        }
    }
}

/// The hybrid formats that split `size`'s cube in every way these tests need: a DAG deeper
/// than the cube (single-child nodes above the world), one as deep, a raw grid of 2³ cells,
/// and the shallowest DAG under the finest raw grid.
fn hybrid_splits(size: [u32; 3]) -> [(u32, u32); 4] {
    let depth = size
        .iter()
        .map(|v| v.next_power_of_two().trailing_zeros())
        .max()
        .unwrap();
    [(0, depth + 1), (0, depth), (1, depth - 1), (depth - 3, 3)]
}

/// The SVO's bytes counted again from the dense grid: 4 per non-empty cube of side 2 and
/// up, cube by cube.
fn recount_svo(grid: &DenseGrid, size: [u32; 3]) -> u64 {
    let side = size.iter().max().unwrap().next_power_of_two().max(8);
    let solid = |p: [u32; 3]| (0..3).all(|a| p[a] < size[a]) && grid.get(p) != 0;
    let mut nodes = 0;
    let mut s = 2;
    while s <= side {
        for z in (0..side).step_by(s as usize) {
            for y in (0..side).step_by(s as usize) {
                for x in (0..side).step_by(s as usize) {
                    let any = (0..s * s * s).any(|i| solid([x + i % s, y + i / s % s, z + i / (s * s)]));
                    nodes += u64::from(any);
                }
            }
        }
        s *= 2;
    }
    4 * nodes
}

/// A DAG counted straight from the dense grid: a recursive walk over the cube at `o` of
/// side `s` that numbers each side's distinct subtrees (in `seen`) and adds their bytes:
/// a leaf of side `leaf` is a 64-bit mask (side 4, 8 bytes) or a voxel (side 1, one 4-byte
/// word); an inner node is a mask word and a word per child. `None` when the cube is empty.
struct DagCount<'a> {
    solid: &'a dyn Fn([u32; 3]) -> bool,
    leaf: u32,
    seen: HashMap<u32, HashMap<Vec<u64>, u64>>,
    bytes: u64,
}

impl DagCount<'_> {
    fn walk(&mut self, o: [u32; 3], s: u32) -> Option<u64> {
        let (content, cost) = if s == self.leaf {
            let mut m = 0u64;
            for i in 0..s * s * s {
                if (self.solid)([o[0] + i % s, o[1] + i / s % s, o[2] + i / (s * s)]) {
                    m |= 1 << i;
                }
            }
            if m == 0 {
                return None;
            }
            (vec![m], if s == 4 { 8 } else { 4 })
        } else {
            let h = s / 2;
            let kids: Vec<u64> = (0..8u32)
                .map(|oct| {
                    self.walk([0, 1, 2].map(|a| o[a] + h * (oct >> a & 1)), h)
                        .unwrap_or(u64::MAX)
                })
                .collect();
            let children = kids.iter().filter(|&&k| k != u64::MAX).count() as u64;
            if children == 0 {
                return None;
            }
            (kids, 4 * (1 + children))
        };
        let level = self.seen.entry(s).or_default();
        let next = level.len() as u64;
        let bytes = &mut self.bytes;
        Some(*level.entry(content).or_insert_with(|| {
            *bytes += cost;
            next
        }))
    }
}

/// The SVDAG's bytes counted again from the dense grid.
fn recount_svdag(grid: &DenseGrid, size: [u32; 3]) -> u64 {
    let solid = |p: [u32; 3]| (0..3).all(|a| p[a] < size[a]) && grid.get(p) != 0;
    let mut count = DagCount {
        solid: &solid,
        leaf: 4,
        seen: HashMap::new(),
        bytes: 0,
    };
    count.walk([0; 3], size.iter().max().unwrap().next_power_of_two().max(8));
    count.bytes
}

/// The bytes of the hybrid format R(top³) G(dag) counted again from the dense grid: a raw
/// grid of 4-byte cells over DAGs down to single voxels, one dedup map per node side.
fn recount_hybrid(grid: &DenseGrid, size: [u32; 3], top: u32, dag: u32) -> u64 {
    let solid = |p: [u32; 3]| (0..3).all(|a| p[a] < size[a]) && grid.get(p) != 0;
    let mut count = DagCount {
        solid: &solid,
        leaf: 1,
        seen: HashMap::new(),
        bytes: 0,
    };
    let (cells, side) = (1u32 << top, 1u32 << dag);
    for z in 0..cells {
        for y in 0..cells {
            for x in 0..cells {
                count.walk([x * side, y * side, z * side], side);
            }
        }
    }
    4 * u64::from(cells).pow(3) + count.bytes
}

#[test]
fn hybrid_formats_count_like_a_walk_of_the_dense_grid() {
    let size = WorldSize::new(64, 64, 64).unwrap();
    for seed in 0..2u64 {
        let w = random_world(size, seed).build();
        let dag = Svdag::build(&w).unwrap();
        let grid = DenseGrid::from_world(&w).unwrap();
        // The format larger than the world, as large, and split at several levels.
        for (top, depth) in [(1, 6), (0, 7), (3, 3), (2, 4), (1, 5)] {
            assert_eq!(
                Hybrid::build(&dag, top, depth).unwrap().bytes(),
                recount_hybrid(&grid, size.voxels(), top, depth),
                "seed {seed}: R({top}³) G({depth})"
            );
        }
        let e = Hybrid::build(&dag, 1, 4).unwrap_err();
        assert!(e.to_string().contains("less than the world's cube"), "{e}");
        let e = Hybrid::build(&dag, 5, 2).unwrap_err();
        assert!(e.to_string().contains("depth of 3 or more"), "{e}");
    }
}

#[test]
fn svdag_hits_equal_the_dense_grid_and_naadf_on_random_worlds() {
    for seed in 0..4u64 {
        let size = size_for(seed, &[[64, 64, 64], [128, 64, 64], [64, 128, 192]]);
        let raw = random_world(size, seed);
        let w = raw.build();
        let (dag, svo) = (Svdag::build(&w).unwrap(), Svo::build(&w).unwrap());
        let mut rng = Rng(seed + 1);
        assert_same_hits(
            &w,
            &dag,
            &svo,
            &rays(size.voxels(), &mut rng, 1500),
            &format!("seed {seed}"),
        );
        let grid = DenseGrid::from_world(&w).unwrap();
        assert_eq!(
            dag.bytes(),
            recount_svdag(&grid, size.voxels()),
            "seed {seed}: svdag bytes"
        );
        assert_eq!(svo.bytes(), recount_svo(&grid, size.voxels()), "seed {seed}: svo bytes");
    }
}

#[test]
fn svdag_hits_equal_the_dense_grid_on_adversarial_worlds() {
    let size = WorldSize::new(64, 64, 128).unwrap();
    for (name, raw) in adversarial(size) {
        let w = raw.build();
        if name == "empty" {
            for e in [Svdag::build(&w).unwrap_err(), Svo::build(&w).unwrap_err()] {
                assert!(e.to_string().contains("no solid voxel"), "{e}");
            }
            continue;
        }
        let (dag, svo) = (Svdag::build(&w).unwrap(), Svo::build(&w).unwrap());
        let mut rng = Rng(7);
        assert_same_hits(&w, &dag, &svo, &rays(size.voxels(), &mut rng, 800), name);
        let grid = DenseGrid::from_world(&w).unwrap();
        assert_eq!(dag.bytes(), recount_svdag(&grid, size.voxels()), "{name}: svdag bytes");
        assert_eq!(svo.bytes(), recount_svo(&grid, size.voxels()), "{name}: svo bytes");
    }
}

#[test]
fn a_repeated_pattern_is_stored_once_per_level() {
    let size = WorldSize::new(128, 64, 128).unwrap();
    let mut tiled = Raw::empty(size, 2);
    let mut one = Raw::empty(size, 2);
    // The same 16³ pattern in every tile, or in one tile only.
    let pattern = |p: [u32; 3]| {
        let q = p.map(|v| v % 16);
        (q[0] * 3 + q[1] * 5 + q[2] * 7) % 11 < 3 || q[1] == 0
    };
    for p in tiled.coords().collect::<Vec<_>>() {
        if pattern(p) {
            tiled.set(p, 1);
            if p.iter().all(|&v| v < 16) {
                one.set(p, 1);
            }
        }
    }
    let (tiled, one) = (
        Svdag::build(&tiled.build()).unwrap(),
        Svdag::build(&one.build()).unwrap(),
    );
    // The 256 tiles share their subtrees: the same unique nodes at every level as one
    // tile, and only the pointers of the shared children's parents on top.
    assert_eq!(tiled.node_counts(), one.node_counts());
    let (leaves, nodes) = tiled.node_counts();
    assert!(leaves > 4 && nodes[..3] == [1, 1, 1], "{leaves} leaves, {nodes:?}");
    assert!(
        tiled.bytes() < one.bytes() + 128,
        "{} against {}",
        tiled.bytes(),
        one.bytes()
    );
}

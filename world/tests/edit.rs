//! Editing against independent oracles: a dense array that receives the same ops, brute-
//! force AADF checks, from-scratch rebuilds of the distance fields, the digest recomputed
//! from scratch, and the three traversal methods.

mod common;

use common::{Raw, Rng, assert_aadf_valid, assert_canonical, assert_roundtrip, random_world};
use naadf_world::cell::{self, State};
use naadf_world::edit::{Record, UndoRecord};
use naadf_world::ops::{self, Batch, Canvas, Limits, Op};
use naadf_world::traverse::{DenseGrid, Ray, same_result, trace_naadf, trace_nodf};
use naadf_world::{World, WorldSize};

/// The dense oracle as a canvas for the same ops.
impl Canvas for Raw {
    fn size(&self) -> WorldSize {
        self.size
    }
    fn get(&self, p: [u32; 3]) -> u16 {
        Raw::get(self, p)
    }
    fn set(&mut self, p: [u32; 3], m: u16) {
        Raw::set(self, p, m)
    }
}

/// Applies a batch to the dense oracle.
fn apply_dense(raw: &mut Raw, world: &World, batch: &Batch) {
    let mut materials = world.materials().clone();
    let mut models = world.models().clone();
    ops::apply_batch(batch, raw, &mut materials, &mut models, &Limits::default()).expect("oracle accepts the batch");
}

/// A random batch: boxes, spheres (some huge, emptying whole chunks), paints, copies,
/// single voxels and flood fills.
fn random_batch(rng: &mut Rng, s: [u32; 3], materials: u16) -> Batch {
    let mut ops = Vec::new();
    for _ in 0..1 + rng.below(3) {
        let p = |rng: &mut Rng| [0, 1, 2].map(|a| rng.below(u64::from(s[a]) + 8) as i64 - 4);
        let m = |rng: &mut Rng| {
            if rng.below(3) == 0 {
                0
            } else {
                1 + rng.below(u64::from(materials)) as u16
            }
        };
        let op = match rng.below(8) {
            0 => {
                let (a, b) = (p(rng), p(rng));
                Op::Box {
                    min: [0, 1, 2].map(|k| a[k].min(b[k])),
                    max: [0, 1, 2].map(|k| a[k].max(b[k]) + 1),
                    material: m(rng),
                }
            }
            1 | 2 => {
                let c = p(rng).map(|v| v as f64 + rng.unit());
                let r = if rng.below(4) == 0 {
                    20.0 + rng.unit() * 40.0
                } else {
                    rng.unit() * 9.0
                };
                Op::Sphere {
                    center: c,
                    radius: r,
                    material: m(rng),
                }
            }
            3 => Op::Paint {
                center: p(rng).map(|v| v as f64),
                radius: rng.unit() * 12.0,
                material: 1 + rng.below(u64::from(materials)) as u16,
            },
            4 => {
                let (a, b) = (p(rng), p(rng));
                let min = [0, 1, 2].map(|k| a[k].min(b[k]));
                let max = [0, 1, 2].map(|k| (a[k].max(b[k]) + 1).min(min[k] + 24));
                Op::Copy { min, max, to: p(rng) }
            }
            5 => {
                let n = 1 + rng.below(20);
                let voxels = (0..n).map(|_| {
                    let q = [0, 1, 2].map(|a| rng.below(u64::from(s[a])) as i64);
                    [q[0], q[1], q[2], i64::from(m(rng))]
                });
                Op::Set {
                    voxels: voxels.collect(),
                }
            }
            _ => {
                // Whole-chunk erases and refills exercise collapse and expansion.
                let c = [0, 1, 2].map(|a| (rng.below(u64::from(s[a] / 16)) * 16) as i64);
                Op::Box {
                    min: c,
                    max: c.map(|v| v + 16 * (1 + rng.below(2) as i64)),
                    material: m(rng),
                }
            }
        };
        ops.push(op);
    }
    Batch { ops }
}

fn check_traversal(w: &World, rng: &mut Rng, n: usize) {
    let grid = DenseGrid::from_world(w).unwrap();
    let s = w.size().voxels().map(f64::from);
    for _ in 0..n {
        let o = [0, 1, 2].map(|a| rng.unit() * s[a] * 1.2 - 0.1 * s[a]);
        let d = [0, 1, 2].map(|_| rng.unit() * 2.0 - 1.0);
        let Ok(ray) = Ray::new(o, d) else { continue };
        let (a, b, c) = (trace_naadf(w, &ray), trace_nodf(w, &ray), grid.trace(&ray));
        assert!(
            same_result(&a, &b) && same_result(&a, &c),
            "{ray:?}: {a:?} / {b:?} / {c:?}"
        );
    }
}

/// Every free chunk's AADF equals a from-scratch build of the same voxels.
fn assert_converged(w: &World, raw: &Raw, what: &str) {
    let fresh = raw.build();
    for (i, (&a, &b)) in w.chunks().iter().zip(fresh.chunks()).enumerate() {
        let same_kind = cell::state(a) == cell::state(b) && (cell::state(a) == State::Mixed || a == b);
        assert!(same_kind, "{what}: chunk {i} is {a:#x}, a fresh build has {b:#x}");
    }
}

fn run_sequence(size: WorldSize, seed: u64, batches: usize, growth: impl Fn(&mut Rng) -> Option<usize>) -> World {
    let mut rng = Rng(seed);
    // Growth timing draws from its own stream, so it never changes the batches.
    let mut timing = Rng(seed ^ 0x7157_1A9E);
    let mut raw = random_world(size, seed);
    let mut w = raw.build();
    for v in 0..batches {
        let batch = random_batch(&mut rng, size.voxels(), raw.materials);
        let applied = w
            .apply(&batch, &Limits::default())
            .unwrap_or_else(|e| panic!("batch {v}: {e}"));
        apply_dense(&mut raw, &w, &batch);
        let what = format!("seed {seed} version {}", v + 1);
        assert_eq!(applied.change.version, v as u64 + 1);
        assert_roundtrip(&raw, &w, &what);
        assert_aadf_valid(&raw, &w, &what);
        assert_canonical(&w, &what);
        assert_eq!(w.digest(), w.digest_from_scratch(), "{what}: incremental digest");
        if v % 3 == 0 {
            check_traversal(&w, &mut rng, 150);
        }
        if let Some(budget) = growth(&mut timing) {
            w.grow_distance_fields(budget);
            assert_aadf_valid(&raw, &w, &format!("{what} after growth"));
            assert_eq!(w.digest(), w.digest_from_scratch(), "{what}: digest after growth");
        }
    }
    w.grow_until_quiescent();
    assert!(w.is_quiescent());
    assert_eq!(
        w.digest(),
        w.digest_from_scratch(),
        "seed {seed}: digest after convergence"
    );
    assert_converged(&w, &raw, &format!("seed {seed} final"));
    assert_aadf_valid(&raw, &w, "final");
    check_traversal(&w, &mut rng, 300);
    w
}

#[test]
fn random_edit_sequences_match_a_dense_array() {
    for seed in 0..4u64 {
        let size = common::size_for(seed, &[[64, 64, 64], [128, 64, 64], [64, 128, 128]]);
        run_sequence(size, seed, 12, |rng| {
            (rng.below(2) == 0).then(|| rng.below(40) as usize)
        });
    }
}

/// A world wider than the regrowth radius, so that growth regions are real sub-regions
/// and locality matters.
#[test]
fn growth_converges_to_a_from_scratch_build_in_a_wide_world() {
    let size = WorldSize::new(768, 64, 64).unwrap();
    for seed in 10..12u64 {
        run_sequence(size, seed, 8, |rng| Some(rng.below(100) as usize));
    }
}

#[test]
fn equal_batches_give_equal_digests_whatever_the_growth_timing() {
    let size = WorldSize::new(640, 64, 64).unwrap();
    let lazy = run_sequence(size, 21, 10, |_| None);
    let eager = run_sequence(size, 21, 10, |_| Some(usize::MAX));
    let random = run_sequence(size, 21, 10, |rng| (rng.below(3) == 0).then(|| rng.below(50) as usize));
    assert_eq!(lazy.digest(), eager.digest());
    assert_eq!(lazy.digest(), random.digest());
    assert!(
        lazy.to_parts() == eager.to_parts(),
        "buffers differ between growth timings"
    );
}

/// Growth taken out of the world (as a server runs it on another thread) while edits keep
/// coming, and sometimes stopped partway and finished by the world (as a server's actor
/// does when it cannot wait): every published state is safe, and the converged world
/// equals the one grown in place.
#[test]
fn detached_growth_with_edits_in_between_converges_to_the_same_world() {
    let size = WorldSize::new(640, 64, 64).unwrap();
    let seed = 21;
    let mut rng = Rng(seed);
    let mut timing = Rng(seed ^ 0x5EED);
    let mut raw = random_world(size, seed);
    let mut w = raw.build();
    let mut in_place = raw.build();
    let mut task = None;
    for v in 0..10 {
        if task.is_none() {
            task = w.start_growth();
        }
        let batch = random_batch(&mut rng, size.voxels(), raw.materials);
        w.apply(&batch, &Limits::default()).unwrap();
        in_place.apply(&batch, &Limits::default()).unwrap();
        apply_dense(&mut raw, &w, &batch);
        assert_aadf_valid(&raw, &w, &format!("version {}", v + 1));
        if timing.below(2) == 0
            && let Some(mut t) = task.take()
        {
            // Up to 60 (level, axis) phases on the "thread"; `finish_growth` runs the rest.
            let phases = std::cell::Cell::new(timing.below(60));
            let converged = t.run_until(|| {
                let left = phases.get();
                phases.set(left.saturating_sub(1));
                left == 0
            });
            if !converged {
                assert!(!t.run_until(|| true), "a stopped task stays unfinished until run on");
            }
            w.finish_growth(t);
            assert_aadf_valid(&raw, &w, &format!("version {} after growth", v + 1));
            assert_eq!(w.digest(), w.digest_from_scratch());
        }
    }
    if let Some(t) = task {
        w.finish_growth(t);
    }
    w.grow_until_quiescent();
    assert_converged(&w, &raw, "detached");
    in_place.grow_until_quiescent();
    assert_eq!(w.digest(), in_place.digest());
    assert!(w.to_parts() == in_place.to_parts());
}

#[test]
fn a_bad_op_rejects_the_whole_batch() {
    let raw = random_world(WorldSize::new(64, 64, 64).unwrap(), 3);
    let mut w = raw.build();
    let before = (w.to_parts(), w.digest(), w.version());
    let batch = Batch {
        ops: vec![
            Op::Box {
                min: [0, 0, 0],
                max: [30, 30, 30],
                material: 1,
            },
            Op::Set {
                voxels: vec![[1, 1, 1, 2], [64, 0, 0, 1]],
            },
        ],
    };
    let err = w.apply(&batch, &Limits::default()).unwrap_err();
    assert!(err.to_string().contains("set"), "{err}");
    assert!(
        w.apply(
            &Batch {
                ops: vec![Op::Box {
                    min: [0; 3],
                    max: [4; 3],
                    material: 99
                }]
            },
            &Limits::default()
        )
        .is_err()
    );
    assert!(
        (w.to_parts(), w.digest(), w.version()) == before,
        "a rejected batch changed the world"
    );
}

#[test]
fn single_voxel_change_set_is_small() {
    let size = WorldSize::new(1024, 256, 1024).unwrap();
    let source = naadf_world::preset::Preset::Terrain.source(Some(size), 4).unwrap();
    let mut w = World::build(&*source, &|_| {}).unwrap();
    let batch = Batch::parse_line(r#"{"op":"set","voxels":[[1000,200,1000,3]]}"#).unwrap();
    let applied = w.apply(&batch, &Limits::default()).unwrap();
    let bytes = applied.change.encode();
    assert!(bytes.len() <= 48, "{} bytes", bytes.len());
    // A mirror reproduces the change from the record alone.
    let decoded = Record::decode(&bytes).unwrap();
    let mut mirror = World::build(&*source, &|_| {}).unwrap();
    mirror
        .apply_record(decoded.version, &decoded.record, &Limits::default())
        .unwrap();
    assert_eq!(mirror.digest(), w.digest());
}

#[test]
fn mirrors_following_change_records_stay_identical() {
    let size = WorldSize::new(256, 64, 64).unwrap();
    let raw = random_world(size, 8);
    let mut server = raw.build();
    let mut mirror = raw.build();
    let mut rng = Rng(8);
    for _ in 0..15 {
        let batch = random_batch(&mut rng, size.voxels(), raw.materials);
        let mut changes = vec![server.apply(&batch, &Limits::default()).unwrap().change];
        changes.extend(server.grow_distance_fields(rng.below(200) as usize));
        common::follow(&server, &mut mirror, changes);
    }
}

#[test]
fn undo_and_redo_at_the_content_level() {
    let size = WorldSize::new(128, 64, 64).unwrap();
    let mut rng = Rng(5);
    for round in 0..6 {
        let start = random_world(size, 100 + round);
        let mut w = start.build();
        let batch = random_batch(&mut rng, size.voxels(), start.materials);
        let mut after = Raw {
            size,
            v: start.v.clone(),
            materials: start.materials,
        };
        apply_dense(&mut after, &w, &batch);
        let undo: UndoRecord = w.apply(&batch, &Limits::default()).unwrap().undo;

        // Another user edits a voxel that the batch also wrote.
        let mut others = Vec::new();
        if let Some(&(p, _, written)) = undo.voxels.first() {
            let theirs: u32 = if written == 1 { 2 } else { 1 };
            let b = Batch {
                ops: vec![Op::Set {
                    voxels: vec![[p[0], p[1], p[2], theirs].map(i64::from)],
                }],
            };
            w.apply(&b, &Limits::default()).unwrap();
            others.push((p, theirs as u16));
        }
        let redo = w.apply(&undo.undo_batch(&w), &Limits::default()).unwrap().undo;
        // The oracle: the start content, except the other user's voxel.
        let mut expect = Raw {
            size,
            v: start.v.clone(),
            materials: start.materials,
        };
        for &(p, m) in &others {
            expect.set(p, m);
        }
        assert_roundtrip(&expect, &w, &format!("undo round {round}"));
        // Redo reapplies the batch where the undo restored values.
        w.apply(&redo.undo_batch(&w), &Limits::default()).unwrap();
        for &(p, m) in &others {
            after.set(p, m);
        }
        assert_roundtrip(&after, &w, &format!("redo round {round}"));
        w.grow_until_quiescent();
        assert_converged(&w, &after, "after redo");
    }
}

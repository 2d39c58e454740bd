//! The ops layer from the outside: ops-JSON lines → batches → voxel writes, as the world,
//! the CLI and replay scripts use it (docs/OPS.md), and each op on its own, most of them
//! against brute-force oracles.

use naadf_world::model::{Model, ModelTable};
use naadf_world::ops::{Batch, Canvas, DenseCanvas, EditError, Limits, Op, apply_batch};
use naadf_world::{Material, MaterialKind, MaterialTable, WorldSize};
use proptest::prelude::*;
use std::collections::HashMap;

fn size() -> WorldSize {
    WorldSize::new(64, 128, 64).unwrap()
}

/// A table with materials 1..=`n` defined (plain diffuse: the ops only ask which exist).
fn materials(n: usize) -> MaterialTable {
    MaterialTable::from_materials(&vec![Material::diffuse([0.5; 3]); n]).unwrap()
}

/// A batch overlay over a read-only base, the way the world applies a batch: writes go to
/// the overlay, reads see them; the base stays as it was until the caller commits.
struct Overlay<'a> {
    base: &'a DenseCanvas,
    writes: HashMap<[u32; 3], u16>,
}

impl Canvas for Overlay<'_> {
    fn size(&self) -> WorldSize {
        self.base.size()
    }
    fn get(&self, p: [u32; 3]) -> u16 {
        self.writes.get(&p).copied().unwrap_or_else(|| self.base.get(p))
    }
    fn set(&mut self, p: [u32; 3], material: u16) {
        self.writes.insert(p, material);
    }
}

/// Applies `line` through an overlay; on success commits it into `base`.
fn apply_line(
    line: &str,
    base: &mut DenseCanvas,
    materials: &mut MaterialTable,
    models: &mut ModelTable,
) -> Result<(), EditError> {
    let batch = Batch::parse_line(line)?;
    let (mut mats, mut mods) = (materials.clone(), models.clone());
    let writes = {
        let mut overlay = Overlay {
            base,
            writes: HashMap::new(),
        };
        apply_batch(&batch, &mut overlay, &mut mats, &mut mods, &Limits::default())?;
        overlay.writes
    };
    for (p, m) in writes {
        base.set(p, m);
    }
    *materials = mats;
    *models = mods;
    Ok(())
}

fn count(c: &DenseCanvas, m: u16) -> usize {
    c.voxels().iter().filter(|&&v| v == m).count()
}

#[test]
fn a_session_of_lines() {
    let mut world = DenseCanvas::new(size());
    let mut mats = MaterialTable::default();
    let mut models = ModelTable::default();
    let lines = [
        r#"{"batch":[{"op":"define_material","id":1,"kind":"diffuse","albedo":[0.5,0.5,0.5]},{"op":"define_material","id":2,"kind":"emissive","albedo":[1,0.9,0.7],"emission":20},{"op":"box","min":[0,0,0],"max":[64,8,64],"material":1}]}"#,
        r#"{"op":"sphere","center":[32,8,32],"radius":6,"material":0}"#,
        r#"{"op":"paint","center":[0,0,0],"radius":4,"material":2}"#,
        r#"{"op":"set","voxels":[[1,100,1,2],[2,100,1,1]]}"#,
        r#"{"op":"define_model","name":"lamp","size":[1,3,1],"voxels":[[0,0,0,1],[0,1,0,1],[0,2,0,2]]}"#,
        r#"{"op":"place","model":"lamp","at":[10,8,10]}"#,
        r#"{"op":"copy","min":[10,8,10],"max":[11,11,11],"to":[20,8,20]}"#,
        r#"{"op":"flood_paint","start":[5,100,1],"material":2,"limit":10}"#,
    ];
    let mut results = Vec::new();
    for line in lines {
        results.push(apply_line(line, &mut world, &mut mats, &mut models).map_err(|e| e.to_string()));
    }
    // The last line starts at an empty voxel.
    let last = results.pop().unwrap().unwrap_err();
    assert!(
        last.contains("op 0 (flood_paint)") && last.contains("empty voxel"),
        "{last}"
    );
    for r in results {
        r.unwrap();
    }
    assert!(mats.contains(2) && !mats.contains(3));
    assert_eq!(world.get([32, 7, 32]), 0, "carved by the sphere");
    assert_eq!(world.get([0, 0, 0]), 2, "painted");
    assert_eq!(world.get([0, 20, 0]), 0, "paint doesn't add voxels");
    assert_eq!([world.get([10, 10, 10]), world.get([20, 10, 20])], [2, 2]);
    assert_eq!([world.get([1, 100, 1]), world.get([2, 100, 1])], [2, 1]);
    // Flood from a lamp top: it and the copy's top aren't connected.
    apply_line(
        r#"{"op":"flood_paint","start":[10,10,10],"material":1,"limit":1}"#,
        &mut world,
        &mut mats,
        &mut models,
    )
    .unwrap();
    assert_eq!([world.get([10, 10, 10]), world.get([20, 10, 20])], [1, 2]);
}

#[test]
fn a_rejected_batch_changes_nothing() {
    let mut world = DenseCanvas::new(size());
    let mut mats = materials(1);
    let mut models = ModelTable::default();
    let before = world.clone();
    // The second op names material 7, which nobody defined.
    let e = apply_line(
        r#"{"batch":[{"op":"box","min":[0,0,0],"max":[9,9,9],"material":1},{"op":"define_material","id":3,"kind":"metal","albedo":[1,1,1],"roughness":0.2},{"op":"sphere","center":[5,5,5],"radius":3,"material":7}]}"#,
        &mut world,
        &mut mats,
        &mut models,
    )
    .unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(
            e,
            EditError::Invalid {
                index: 2,
                op: "sphere",
                ..
            }
        ),
        "{msg}"
    );
    assert_eq!(msg, "op 2 (sphere): material 7 is not defined");
    assert!(world == before);
    assert!(!mats.contains(3), "the batch's table copy was discarded");

    // Out-of-world set: rejected whole, naming the coordinate.
    let e = apply_line(
        r#"{"op":"set","voxels":[[0,0,0,1],[64,0,0,1]]}"#,
        &mut world,
        &mut mats,
        &mut models,
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "op 0 (set): voxel 1 at [64, 0, 0] lies outside the world 64×128×64"
    );
    assert!(world == before);
}

#[test]
fn flood_limit_leaves_the_world_alone() {
    let mut world = DenseCanvas::new(size());
    let mut mats = materials(2);
    let mut models = ModelTable::default();
    apply_line(
        r#"{"op":"box","min":[0,0,0],"max":[64,1,64],"material":1}"#,
        &mut world,
        &mut mats,
        &mut models,
    )
    .unwrap();
    let before = world.clone();
    let e = apply_line(
        r#"{"op":"flood_paint","start":[3,0,3],"material":2,"limit":4095}"#,
        &mut world,
        &mut mats,
        &mut models,
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            EditError::Limit {
                index: 0,
                op: "flood_paint",
                ..
            }
        ),
        "{e}"
    );
    assert!(world == before);
    apply_line(
        r#"{"op":"flood_paint","start":[3,0,3],"material":2,"limit":4096}"#,
        &mut world,
        &mut mats,
        &mut models,
    )
    .unwrap();
    assert_eq!(count(&world, 2), 4096);
}

#[test]
fn overlay_and_dense_agree() {
    // The same batch through an overlay and directly on a dense canvas.
    let line = r#"{"batch":[{"op":"define_material","id":4,"kind":"mirror","albedo":[1,1,1]},{"op":"sphere","center":[20.3,30.1,40.7],"radius":17.5,"material":4},{"op":"copy","min":[10,20,30],"max":[40,50,60],"to":[15,25,35]},{"op":"paint","center":[30,40,50],"radius":9,"material":2},{"op":"box","min":[-5,-5,-5],"max":[7,200,7],"material":0},{"op":"flood_paint","start":[20,30,40],"material":1,"limit":100000}]}"#;
    let mut mats = materials(2);
    let mut models = ModelTable::default();
    let mut via_overlay = DenseCanvas::new(size());
    apply_line(line, &mut via_overlay, &mut mats, &mut models).unwrap();
    let mut direct = DenseCanvas::new(size());
    let mut mats2 = materials(2);
    let batch = Batch::parse_line(line).unwrap();
    apply_batch(
        &batch,
        &mut direct,
        &mut mats2,
        &mut ModelTable::default(),
        &Limits::default(),
    )
    .unwrap();
    assert!(via_overlay == direct);
    assert_eq!(mats, mats2);
    assert!(count(&direct, 1) > 1000 && count(&direct, 2) > 0);
}

#[test]
fn canonical_lines() {
    let batch = Batch {
        ops: vec![
            Op::Box {
                min: [0, -1, 2],
                max: [3, 4, 5],
                material: 6,
            },
            Op::Sphere {
                center: [1.5, 2.0, -3.25],
                radius: 4.0,
                material: 0,
            },
            Op::SpawnEntity {
                id: 9,
                model: "car".into(),
                pos: [1.0, 2.0, 3.0],
                rot: [0.0, 0.0, 0.0, 1.0],
            },
        ],
    };
    let line = batch.to_json_line();
    assert_eq!(
        line,
        r#"{"batch":[{"op":"box","min":[0,-1,2],"max":[3,4,5],"material":6},{"op":"sphere","center":[1.5,2.0,-3.25],"radius":4.0,"material":0},{"op":"spawn_entity","id":9,"model":"car","pos":[1.0,2.0,3.0],"rot":[0.0,0.0,0.0,1.0]}]}"#
    );
    assert_eq!(Batch::parse_line(&line).unwrap(), batch);
    assert!(batch.has_entity_ops());
    // Entity ops are the world's: the canvas layer refuses them after checking their shape.
    let mut c = DenseCanvas::new(size());
    let e = apply_batch(
        &batch,
        &mut c,
        &mut materials(6),
        &mut ModelTable::default(),
        &Limits::default(),
    )
    .unwrap_err();
    assert_eq!(e.to_string(), "op 2 (spawn_entity): model 'car' is not defined");
}

#[test]
fn parse_errors_name_the_problem() {
    for (line, want) in [
        (r#"{"op":"teleport","id":1}"#, "unknown variant `teleport`"),
        (
            r#"{"op":"box","min":[0,0,0],"max":[1,1,1],"material":1,"mat":2}"#,
            "unknown field `mat`",
        ),
        (
            r#"{"batch":[{"op":"box","min":[0,0],"max":[1,1,1],"material":1}]}"#,
            "op 0 (box)",
        ),
        (r#"{"op":"set","voxels":[[1,2,3,4]]"#, "EOF"),
    ] {
        let e = Batch::parse_line(line).unwrap_err();
        assert!(matches!(e, EditError::Parse(_)), "{e:?}");
        assert!(e.to_string().contains(want), "{line}: {e}");
    }
}

// Single ops on a cube world, most of them against brute-force oracles.

/// Edge of the cube world the single-op tests use.
const N: u32 = 64;

fn cube() -> WorldSize {
    WorldSize::new(N, N, N).unwrap()
}

/// The next value of a xorshift64 sequence: cheap, deterministic test content.
fn xorshift(s: &mut u64) -> u64 {
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    *s
}

/// A cube canvas with some random-ish content (materials 1..=3 in about `fill` percent of
/// the voxels, the rest empty), from `seed`.
fn noisy(seed: u64, fill: u32) -> DenseCanvas {
    let mut c = DenseCanvas::new(cube());
    let mut s = seed | 1;
    for z in 0..N {
        for y in 0..N {
            for x in 0..N {
                let r = xorshift(&mut s);
                let m = if (r % 100) < u64::from(fill) {
                    (r >> 32) % 3 + 1
                } else {
                    0
                };
                c.set([x, y, z], m as u16);
            }
        }
    }
    c
}

/// Applies one op as op 3 of a batch, with materials 1..=9 and the default limits.
fn run(op: &Op, c: &mut DenseCanvas) -> Result<(), EditError> {
    let mut mats = materials(9);
    let mut models = ModelTable::default();
    op.apply(3, c, &mut mats, &mut models, &Limits::default())
}

fn all() -> impl Iterator<Item = [u32; 3]> {
    (0..N).flat_map(|z| (0..N).flat_map(move |y| (0..N).map(move |x| [x, y, z])))
}

fn brute_inside(c: [f64; 3], r: f64, p: [u32; 3]) -> bool {
    let d = [0, 1, 2].map(|a| f64::from(p[a]) + 0.5 - c[a]);
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < r * r
}

fn in_box(min: [i64; 3], max: [i64; 3], p: [u32; 3]) -> bool {
    (0..3).all(|a| min[a] <= i64::from(p[a]) && i64::from(p[a]) < max[a])
}

fn coord() -> impl Strategy<Value = i64> {
    prop_oneof![-20i64..84, Just(0i64), Just(64), Just(63)]
}

fn fcoord() -> impl Strategy<Value = f64> {
    prop_oneof![
        -20.0f64..84.0,
        (-40i32..170).prop_map(|v| f64::from(v) / 2.0),
        Just(0.0),
        Just(64.0),
    ]
}

fn radius() -> impl Strategy<Value = f64> {
    prop_oneof![
        0.0f64..40.0,
        (0i32..60).prop_map(|v| f64::from(v) / 2.0),
        Just(0.0),
        (0i32..40).prop_map(|v| f64::from(v).sqrt()),
        100.0f64..200.0,
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn box_matches_brute_force(min in [coord(), coord(), coord()], ext in [0i64..40, 0i64..40, 0i64..40],
                               m in 0u16..4, seed in any::<u64>()) {
        let max = [0, 1, 2].map(|a| min[a] + ext[a]);
        let mut c = noisy(seed, 30);
        let before = c.clone();
        run(&Op::Box { min, max, material: m }, &mut c).unwrap();
        for p in all() {
            let want = if in_box(min, max, p) { m } else { before.get(p) };
            prop_assert_eq!(c.get(p), want, "at {:?}", p);
        }
    }

    #[test]
    fn sphere_and_paint_match_brute_force(center in [fcoord(), fcoord(), fcoord()], r in radius(),
                                          m in 1u16..4, erase in any::<bool>(), seed in any::<u64>()) {
        let before = noisy(seed, 40);
        let sm = if erase { 0 } else { m };
        let mut s = before.clone();
        run(&Op::Sphere { center, radius: r, material: sm }, &mut s).unwrap();
        let mut p = before.clone();
        run(&Op::Paint { center, radius: r, material: m }, &mut p).unwrap();
        for q in all() {
            let inside = brute_inside(center, r, q);
            let old = before.get(q);
            prop_assert_eq!(s.get(q), if inside { sm } else { old }, "sphere at {:?}", q);
            prop_assert_eq!(p.get(q), if inside && old != 0 { m } else { old }, "paint at {:?}", q);
        }
    }

    #[test]
    fn copy_matches_brute_force(min in [coord(), coord(), coord()], ext in [0i64..40, 0i64..40, 0i64..40],
                                to in [coord(), coord(), coord()], seed in any::<u64>()) {
        let max = [0, 1, 2].map(|a| min[a] + ext[a]);
        let before = noisy(seed, 50);
        let mut c = before.clone();
        run(&Op::Copy { min, max, to }, &mut c).unwrap();
        let mut want = before.clone();
        for p in all() {
            if in_box(min, max, p) {
                let d = [0, 1, 2].map(|a| i64::from(p[a]) - min[a] + to[a]);
                if cube().contains(d) {
                    want.set(d.map(|v| v as u32), before.get(p));
                }
            }
        }
        prop_assert!(c == want);
    }

    #[test]
    fn flood_matches_brute_force(start in [0i64..64, 0i64..64, 0i64..64], m in 0u16..5, fill in 30u32..=100,
                                 seed in any::<u64>(), limit in prop_oneof![0u64..2000, Just(1u64 << 24)]) {
        let before = noisy(seed, fill);
        let mut c = before.clone();
        let s = start.map(|v| v as u32);
        let r = run(&Op::FloodPaint { start, material: m, limit }, &mut c);
        let from = before.get(s);
        if from == 0 {
            prop_assert!(matches!(r, Err(EditError::Invalid { .. })), "{:?}", r);
            prop_assert!(c == before);
            return Ok(());
        }
        if from == m {
            prop_assert!(r.is_ok());
            prop_assert!(c == before);
            return Ok(());
        }
        // Oracle: depth-first search over a dense visited grid.
        let mut reach = vec![false; before.voxels().len()];
        reach[before.index(s)] = true;
        let mut stack = vec![s];
        while let Some(p) = stack.pop() {
            for a in 0..3 {
                for d in [-1i64, 1] {
                    let v = i64::from(p[a]) + d;
                    if !(0..i64::from(N)).contains(&v) {
                        continue;
                    }
                    let mut q = p;
                    q[a] = v as u32;
                    let i = before.index(q);
                    if !reach[i] && before.get(q) == from {
                        reach[i] = true;
                        stack.push(q);
                    }
                }
            }
        }
        let count = reach.iter().filter(|&&v| v).count() as u64;
        if count > limit {
            prop_assert!(matches!(r, Err(EditError::Limit { .. })), "{:?}", r);
            prop_assert!(c == before, "nothing written");
        } else {
            prop_assert!(r.is_ok(), "{:?}", r);
            for p in all() {
                let want = if reach[before.index(p)] { m } else { before.get(p) };
                prop_assert_eq!(c.get(p), want);
            }
        }
    }

    #[test]
    fn place_matches_brute_force(at in [coord(), coord(), coord()], ms in [1u32..20, 1u32..20, 1u32..20],
                                 seed in any::<u64>(), mseed in any::<u64>()) {
        let before = noisy(seed, 30);
        let mut mats = materials(9);
        let mut models = ModelTable::default();
        let n = (ms[0] * ms[1] * ms[2]) as usize;
        let mut s = mseed | 1;
        let mv: Vec<u16> = (0..n).map(|_| [0, 0, 5, 6][(xorshift(&mut s) % 4) as usize]).collect();
        models.insert("m".into(), Model::new(ms, mv.clone()).unwrap());
        let mut c = before.clone();
        Op::Place { model: "m".into(), at }.apply(0, &mut c, &mut mats, &mut models, &Limits::default()).unwrap();
        for p in all() {
            let l = [0, 1, 2].map(|a| i64::from(p[a]) - at[a]);
            let mut want = before.get(p);
            if (0..3).all(|a| l[a] >= 0 && l[a] < i64::from(ms[a])) {
                let v = mv[(l[0] + i64::from(ms[0]) * (l[1] + i64::from(ms[1]) * l[2])) as usize];
                if v != 0 { want = v; }
            }
            prop_assert_eq!(c.get(p), want, "at {:?}", p);
        }
    }

    #[test]
    fn set_matches_brute_force(vs in proptest::collection::vec([0i64..64, 0i64..64, 0i64..64, 0i64..10], 0..200),
                               seed in any::<u64>()) {
        let before = noisy(seed, 30);
        let mut c = before.clone();
        run(&Op::Set { voxels: vs.clone() }, &mut c).unwrap();
        let mut want = before.clone();
        for v in &vs {
            want.set([v[0] as u32, v[1] as u32, v[2] as u32], v[3] as u16);
        }
        prop_assert!(c == want);
    }
}

/// A canvas that counts calls and stays blank, to watch what ops touch.
struct Counting {
    size: WorldSize,
    sets: u64,
}

impl Canvas for Counting {
    fn size(&self) -> WorldSize {
        self.size
    }
    fn get(&self, _: [u32; 3]) -> u16 {
        1
    }
    fn set(&mut self, _: [u32; 3], _: u16) {
        self.sets += 1;
    }
}

#[test]
fn sphere_edge_cases() {
    // Radius 0: nothing, wherever the centre.
    for c in [[0.5, 0.5, 0.5], [0.0; 3], [10.25, 3.0, 63.5]] {
        let mut k = noisy(1, 50);
        let before = k.clone();
        run(
            &Op::Sphere {
                center: c,
                radius: 0.0,
                material: 2,
            },
            &mut k,
        )
        .unwrap();
        assert!(k == before);
    }
    // A tiny radius around a voxel centre picks exactly that voxel.
    let mut k = DenseCanvas::new(cube());
    run(
        &Op::Sphere {
            center: [3.5, 4.5, 5.5],
            radius: 1e-9,
            material: 2,
        },
        &mut k,
    )
    .unwrap();
    assert_eq!(k.voxels().iter().filter(|&&v| v != 0).count(), 1);
    assert_eq!(k.get([3, 4, 5]), 2);
    // Exactly on the boundary is outside: radius 1 around a voxel centre leaves the six
    // axis neighbours (d² = 1) out.
    let mut k = DenseCanvas::new(cube());
    run(
        &Op::Sphere {
            center: [10.5, 10.5, 10.5],
            radius: 1.0,
            material: 1,
        },
        &mut k,
    )
    .unwrap();
    assert_eq!(k.voxels().iter().filter(|&&v| v != 0).count(), 1, "d² == r² is outside");
    // Radius 1 around a voxel corner: the 8 voxels around it (d² = 0.75).
    let mut k = DenseCanvas::new(cube());
    run(
        &Op::Sphere {
            center: [10.0, 0.0, 64.0],
            radius: 1.0,
            material: 1,
        },
        &mut k,
    )
    .unwrap();
    assert_eq!(
        k.voxels().iter().filter(|&&v| v != 0).count(),
        2,
        "clipped to 2 of the 8"
    );
    // A sphere far outside the world, and one swallowing it.
    let mut k = DenseCanvas::new(cube());
    run(
        &Op::Sphere {
            center: [-1e12, 5.0, 5.0],
            radius: 1e3,
            material: 1,
        },
        &mut k,
    )
    .unwrap();
    assert!(k.voxels().iter().all(|&v| v == 0));
    run(
        &Op::Sphere {
            center: [-1e9, 5.0, 5.0],
            radius: 2e9,
            material: 1,
        },
        &mut k,
    )
    .unwrap();
    assert!(k.voxels().iter().all(|&v| v == 1));
    run(
        &Op::Sphere {
            center: [1e300, 5.0, 5.0],
            radius: 1e300,
            material: 2,
        },
        &mut k,
    )
    .unwrap();
    for p in all() {
        let want = if brute_inside([1e300, 5.0, 5.0], 1e300, p) {
            2
        } else {
            1
        };
        assert_eq!(k.get(p), want);
    }
}

#[test]
fn sphere_iterates_only_its_bounding_box() {
    let big = WorldSize::new(1024, 1024, 1024).unwrap();
    let mut c = Counting { size: big, sets: 0 };
    let mut mats = materials(9);
    let mut models = ModelTable::default();
    let op = Op::Sphere {
        center: [512.0, 512.0, 512.0],
        radius: 64.0,
        material: 1,
    };
    let t = std::time::Instant::now();
    op.apply(0, &mut c, &mut mats, &mut models, &Limits::default()).unwrap();
    let dt = t.elapsed();
    // 4/3·π·64³ ≈ 1.098M voxels.
    assert!((1_090_000..1_105_000).contains(&c.sets), "{}", c.sets);
    eprintln!("sphere r=64: {} voxels in {dt:?}", c.sets);
}

#[test]
fn materials_are_checked() {
    let mut c = noisy(5, 40);
    let before = c.clone();
    let ops = [
        Op::Box {
            min: [0; 3],
            max: [1; 3],
            material: 10,
        },
        Op::Box {
            min: [0; 3],
            max: [0; 3],
            material: 10,
        },
        Op::Sphere {
            center: [0.0; 3],
            radius: 3.0,
            material: 33000,
        },
        Op::Paint {
            center: [0.0; 3],
            radius: 3.0,
            material: 12,
        },
        Op::FloodPaint {
            start: [0, 0, 0],
            material: 11,
            limit: 10,
        },
        Op::Set {
            voxels: vec![[0, 0, 0, 1], [1, 1, 1, 10]],
        },
        Op::Set {
            voxels: vec![[0, 0, 0, -1]],
        },
        Op::Set {
            voxels: vec![[0, 0, 0, 40000]],
        },
    ];
    for op in ops {
        let e = run(&op, &mut c).unwrap_err();
        assert!(matches!(e, EditError::Invalid { index: 3, .. }), "{e:?}");
        let msg = e.to_string();
        assert!(msg.starts_with(&format!("op 3 ({}): ", op.name())), "{msg}");
        assert!(msg.contains("material"), "{msg}");
    }
    let e = run(
        &Op::Paint {
            center: [0.0; 3],
            radius: 3.0,
            material: 0,
        },
        &mut c,
    )
    .unwrap_err();
    assert!(e.to_string().contains("paint with material 0"), "{e}");
    assert!(c == before);
}

#[test]
fn set_rejects_outside_and_later_entries_win() {
    let mut c = DenseCanvas::new(cube());
    for p in [[-1, 0, 0], [0, 64, 0], [0, 0, 64], [i64::MIN, 0, 0]] {
        let e = run(
            &Op::Set {
                voxels: vec![[1, 1, 1, 1], [p[0], p[1], p[2], 1]],
            },
            &mut c,
        )
        .unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, EditError::Invalid { .. }), "{msg}");
        assert!(
            msg.contains(&format!("{p:?}")) && msg.contains("outside the world"),
            "{msg}"
        );
    }
    assert!(c.voxels().iter().all(|&v| v == 0), "nothing written by a rejected set");
    run(
        &Op::Set {
            voxels: vec![[1, 2, 3, 1], [1, 2, 3, 2], [4, 4, 4, 3], [4, 4, 4, 0]],
        },
        &mut c,
    )
    .unwrap();
    assert_eq!(c.get([1, 2, 3]), 2);
    assert_eq!(c.get([4, 4, 4]), 0);
}

#[test]
fn shape_errors() {
    let mut c = DenseCanvas::new(cube());
    let bad = [
        Op::Box {
            min: [5, 0, 0],
            max: [4, 9, 9],
            material: 1,
        },
        Op::Copy {
            min: [0, 0, 9],
            max: [9, 9, 8],
            to: [0; 3],
        },
        Op::Sphere {
            center: [f64::NAN, 0.0, 0.0],
            radius: 1.0,
            material: 1,
        },
        Op::Sphere {
            center: [0.0; 3],
            radius: -1.0,
            material: 1,
        },
        Op::Sphere {
            center: [0.0; 3],
            radius: f64::INFINITY,
            material: 1,
        },
        Op::Paint {
            center: [0.0, f64::INFINITY, 0.0],
            radius: 1.0,
            material: 1,
        },
        Op::FloodPaint {
            start: [64, 0, 0],
            material: 1,
            limit: 10,
        },
        Op::FloodPaint {
            start: [0, 0, 0],
            material: 1,
            limit: 10,
        },
        Op::Place {
            model: "nope".into(),
            at: [0; 3],
        },
        Op::DefineMaterial {
            id: 0,
            kind: MaterialKind::Diffuse,
            albedo: [0.5; 3],
            emission: 0.0,
            roughness: 0.0,
        },
        Op::DefineMaterial {
            id: 40000,
            kind: MaterialKind::Diffuse,
            albedo: [0.5; 3],
            emission: 0.0,
            roughness: 0.0,
        },
        Op::DefineMaterial {
            id: 4,
            kind: MaterialKind::Diffuse,
            albedo: [1.5, 0.0, 0.0],
            emission: 0.0,
            roughness: 0.0,
        },
        Op::DefineModel {
            name: String::new(),
            size: [1; 3],
            voxels: vec![],
        },
        Op::DefineModel {
            name: "x".repeat(65),
            size: [1; 3],
            voxels: vec![],
        },
        Op::DefineModel {
            name: "m".into(),
            size: [0, 1, 1],
            voxels: vec![],
        },
        Op::DefineModel {
            name: "m".into(),
            size: [128, 1, 1],
            voxels: vec![],
        },
        Op::DefineModel {
            name: "m".into(),
            size: [2, 2, 2],
            voxels: vec![[2, 0, 0, 1]],
        },
        Op::DefineModel {
            name: "m".into(),
            size: [2, 2, 2],
            voxels: vec![[0, -1, 0, 1]],
        },
        Op::DefineModel {
            name: "m".into(),
            size: [2, 2, 2],
            voxels: vec![[0, 0, 0, 20]],
        },
        Op::SpawnEntity {
            id: 1,
            model: "m".into(),
            pos: [0.0; 3],
            rot: [0.0, 0.0, 0.0, 1.0],
        },
        Op::MoveEntity {
            id: 1,
            pos: [0.0, f64::NAN, 0.0],
            rot: [0.0, 0.0, 0.0, 1.0],
        },
        Op::MoveEntity {
            id: 1,
            pos: [0.0; 3],
            rot: [0.0; 4],
        },
        Op::MoveEntity {
            id: 1,
            pos: [0.0; 3],
            rot: [1e300, 0.0, 0.0, 1.0],
        },
    ];
    for op in bad {
        let e = run(&op, &mut c).unwrap_err();
        assert!(matches!(e, EditError::Invalid { index: 3, .. }), "{op:?}: {e:?}");
        assert!(e.to_string().starts_with(&format!("op 3 ({})", op.name())), "{e}");
    }
    assert!(c.voxels().iter().all(|&v| v == 0));
}

#[test]
fn limits() {
    let mut c = DenseCanvas::new(cube());
    let mut mats = materials(9);
    let mut models = ModelTable::default();
    let small = Limits {
        max_ops: 2,
        max_set_voxels: 2,
        max_fill_volume: 1000,
        max_flood_limit: 50,
        max_model_voxels: 8,
    };
    let sq = |n: i64| ([0i64; 3], [n, n, n]);
    let over = [
        Op::Set {
            voxels: vec![[0, 0, 0, 1]; 3],
        },
        Op::Box {
            min: sq(11).0,
            max: sq(11).1,
            material: 1,
        },
        Op::Sphere {
            center: [5.0; 3],
            radius: 6.0,
            material: 1,
        },
        Op::Paint {
            center: [5.0; 3],
            radius: 6.0,
            material: 1,
        },
        Op::Copy {
            min: sq(11).0,
            max: sq(11).1,
            to: [20; 3],
        },
        Op::FloodPaint {
            start: [0; 3],
            material: 1,
            limit: 51,
        },
        Op::DefineModel {
            name: "m".into(),
            size: [3, 3, 1],
            voxels: vec![],
        },
        Op::DefineModel {
            name: "m".into(),
            size: [2, 2, 2],
            voxels: vec![[0, 0, 0, 1]; 9],
        },
    ];
    for op in &over {
        let e = op.apply(1, &mut c, &mut mats, &mut models, &small).unwrap_err();
        assert!(matches!(e, EditError::Limit { index: 1, .. }), "{op:?}: {e:?}");
        assert!(
            e.to_string().starts_with(&format!("op 1 ({}): over limit", op.name())),
            "{e}"
        );
    }
    assert!(c.voxels().iter().all(|&v| v == 0));
    // Exactly at the limit (clipped volume counts): fine.
    let ok = [
        Op::Set {
            voxels: vec![[0, 0, 0, 1]; 2],
        },
        Op::Box {
            min: sq(10).0,
            max: sq(10).1,
            material: 1,
        },
        Op::Box {
            min: [-100, -100, -100],
            max: [10, 10, 10],
            material: 1,
        },
        Op::Sphere {
            center: [0.0; 3],
            radius: 10.0,
            material: 1,
        },
        Op::Sphere {
            center: [5.0; 3],
            radius: 5.0,
            material: 1,
        },
        Op::Copy {
            min: [-50, -50, -50],
            max: [10, 10, 10],
            to: [20; 3],
        },
        Op::DefineModel {
            name: "m".into(),
            size: [2, 2, 2],
            voxels: vec![[0, 0, 0, 1]; 8],
        },
    ];
    for op in &ok {
        op.apply(1, &mut c, &mut mats, &mut models, &small).unwrap();
    }
    // A place over the fill limit.
    models.insert("big".into(), Model::new([11, 11, 11], vec![1; 1331]).unwrap());
    let e = Op::Place {
        model: "big".into(),
        at: [0; 3],
    }
    .apply(1, &mut c, &mut mats, &mut models, &small);
    assert!(matches!(e, Err(EditError::Limit { .. })), "{e:?}");
    Op::Place {
        model: "big".into(),
        at: [-1, -1, -1],
    }
    .apply(1, &mut c, &mut mats, &mut models, &small)
    .unwrap();
    // Too many ops.
    let batch = Batch {
        ops: vec![Op::DespawnEntity { id: 1 }; 3],
    };
    let e = apply_batch(&batch, &mut c, &mut mats, &mut models, &small).unwrap_err();
    assert!(matches!(e, EditError::Limit { index: 2, .. }), "{e:?}");
}

#[test]
fn flood_limit_writes_nothing() {
    let mut c = DenseCanvas::new(cube());
    run(
        &Op::Box {
            min: [0; 3],
            max: [10, 10, 10],
            material: 1,
        },
        &mut c,
    )
    .unwrap();
    let before = c.clone();
    let e = run(
        &Op::FloodPaint {
            start: [3, 3, 3],
            material: 2,
            limit: 999,
        },
        &mut c,
    )
    .unwrap_err();
    assert!(matches!(e, EditError::Limit { .. }), "{e:?}");
    assert!(e.to_string().contains("more than 999"), "{e}");
    assert!(c == before);
    run(
        &Op::FloodPaint {
            start: [3, 3, 3],
            material: 2,
            limit: 1000,
        },
        &mut c,
    )
    .unwrap();
    assert_eq!(count(&c, 2), 1000);
    // Same material: a no-op, whatever the limit.
    run(
        &Op::FloodPaint {
            start: [3, 3, 3],
            material: 2,
            limit: 0,
        },
        &mut c,
    )
    .unwrap();
    // Erasing a region is allowed.
    run(
        &Op::FloodPaint {
            start: [3, 3, 3],
            material: 0,
            limit: 1000,
        },
        &mut c,
    )
    .unwrap();
    assert!(c.voxels().iter().all(|&v| v == 0));
}

#[test]
fn copy_reads_before_writing() {
    // Overlapping shift by one along x: a row 1,2,3,... becomes 1,1,2,3,...
    let mut c = DenseCanvas::new(cube());
    for x in 0..8 {
        c.set([x, 0, 0], (x % 9 + 1) as u16);
    }
    run(
        &Op::Copy {
            min: [0, 0, 0],
            max: [8, 1, 1],
            to: [1, 0, 0],
        },
        &mut c,
    )
    .unwrap();
    let row: Vec<u16> = (0..10).map(|x| c.get([x, 0, 0])).collect();
    assert_eq!(row, [1, 1, 2, 3, 4, 5, 6, 7, 8, 0]);
    // Extreme coordinates don't overflow; destinations outside the world are dropped.
    let before = c.clone();
    run(
        &Op::Copy {
            min: [i64::MIN; 3],
            max: [i64::MAX; 3],
            to: [i64::MAX; 3],
        },
        &mut c,
    )
    .unwrap();
    run(
        &Op::Copy {
            min: [i64::MIN, 0, 0],
            max: [i64::MAX, 1, 1],
            to: [0, 5, 5],
        },
        &mut c,
    )
    .unwrap();
    assert!(c == before);
    run(
        &Op::Copy {
            min: [-1, 0, 0],
            max: [5, 1, 1],
            to: [-3, 0, 0],
        },
        &mut c,
    )
    .unwrap();
    assert_eq!((0..6).map(|x| c.get([x, 0, 0])).collect::<Vec<_>>(), [2, 3, 4, 3, 4, 5]);
    let mut mats = materials(9);
    let mut models = ModelTable::default();
    let unlimited = Limits {
        max_fill_volume: u64::MAX,
        ..Limits::default()
    };
    Op::Copy {
        min: [i64::MIN, 0, 0],
        max: [i64::MAX, 1, 1],
        to: [i64::MAX, 5, 5],
    }
    .apply(0, &mut c, &mut mats, &mut models, &unlimited)
    .unwrap();
    Op::Copy {
        min: [-5, 0, 0],
        max: [3, 1, 1],
        to: [i64::MIN, 5, 5],
    }
    .apply(0, &mut c, &mut mats, &mut models, &unlimited)
    .unwrap();
}

#[test]
fn tables_within_a_batch() {
    let mut c = DenseCanvas::new(cube());
    let mut mats = MaterialTable::default();
    let mut models = ModelTable::default();
    let batch = Batch {
        ops: vec![
            Op::DefineMaterial {
                id: 2,
                kind: MaterialKind::Metal,
                albedo: [0.9; 3],
                emission: 0.0,
                roughness: 0.3,
            },
            Op::DefineModel {
                name: "pole".into(),
                size: [1, 3, 1],
                voxels: vec![[0, 0, 0, 2], [0, 2, 0, 2]],
            },
            Op::Place {
                model: "pole".into(),
                at: [5, 62, 5],
            },
        ],
    };
    apply_batch(&batch, &mut c, &mut mats, &mut models, &Limits::default()).unwrap();
    assert_eq!(mats.get(2).unwrap().kind, MaterialKind::Metal);
    assert!(mats.contains(1), "filler entry below the new id");
    assert_eq!(models.get("pole").unwrap().voxels(), &[2, 0, 2]);
    assert_eq!([c.get([5, 62, 5]), c.get([5, 63, 5])], [2, 0]);
    // A model whose material is unknown here can't be placed.
    let mut other = MaterialTable::default();
    let e = Op::Place {
        model: "pole".into(),
        at: [0; 3],
    }
    .apply(0, &mut c, &mut other, &mut models, &Limits::default());
    assert!(matches!(e, Err(EditError::Invalid { .. })), "{e:?}");
}

#[test]
fn entity_ops_are_unsupported_here() {
    let mut c = DenseCanvas::new(cube());
    let mut mats = materials(9);
    let mut models = ModelTable::default();
    models.insert("car".into(), Model::new([1, 1, 1], vec![1]).unwrap());
    for op in [
        Op::SpawnEntity {
            id: 1,
            model: "car".into(),
            pos: [1.0; 3],
            rot: [0.0, 0.0, 0.0, 2.0],
        },
        Op::MoveEntity {
            id: 1,
            pos: [-1.0; 3],
            rot: [0.1, 0.0, 0.0, 0.0],
        },
        Op::DespawnEntity { id: 1 },
    ] {
        assert!(op.is_entity_op());
        op.validate_entity(0, &models).unwrap();
        let e = op
            .apply(0, &mut c, &mut mats, &mut models, &Limits::default())
            .unwrap_err();
        assert!(matches!(e, EditError::Unsupported { .. }), "{e:?}");
        assert!(e.to_string().contains("entity ops are applied by the world"), "{e}");
    }
}

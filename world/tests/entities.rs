//! Dynamic entities against independent oracles: brute-force ray tests in each entity's
//! frame, the three traversal methods, instance records recomputed from the poses, fresh
//! worlds holding the same final entities, the static buffers of a world without entities,
//! from-scratch distance fields, mirrors following change records, undo, and world files.

mod common;

use common::{Raw, Rng, assert_aadf_valid, assert_canonical, random_world, rays};
use naadf_world::entity::pack::{InstanceRecord, RECORD_WORDS, conjugate, rotate};
use naadf_world::entity::{EntityTable, MAX_ENTITY_ID};
use naadf_world::ops::{Batch, EditError, Limits, Op};
use naadf_world::traverse::{
    DenseGrid, Hit, Method, Ray, Tracer, occluded_naadf, same_result, trace_naadf, trace_nodf,
};
use naadf_world::{World, WorldSize, file};

/// A model op: random solid voxels, a shell, or a solid block, of materials 1..=9.
fn random_model(rng: &mut Rng, name: &str, max_edge: u64) -> Op {
    let size = [0, 1, 2].map(|_| 1 + rng.below(max_edge) as u32);
    let kind = rng.below(3);
    let mut voxels = Vec::new();
    for z in 0..size[2] {
        for y in 0..size[1] {
            for x in 0..size[0] {
                let on_shell = [x, y, z].iter().zip(&size).any(|(&v, &s)| v == 0 || v + 1 == s);
                let solid = match kind {
                    0 => rng.below(3) == 0,
                    1 => on_shell && rng.below(5) != 0,
                    _ => true,
                };
                if solid {
                    voxels.push([x, y, z, 1 + rng.below(9) as u32].map(i64::from));
                }
            }
        }
    }
    Op::DefineModel {
        name: name.to_owned(),
        size,
        voxels,
    }
}

/// A random unit quaternion, or now and then an axis-aligned rotation.
fn random_rot(rng: &mut Rng) -> [f64; 4] {
    let s = std::f64::consts::FRAC_1_SQRT_2;
    match rng.below(6) {
        0 => [0.0, 0.0, 0.0, 1.0],
        1 => [0.0, s, 0.0, s],
        2 => [s, 0.0, 0.0, -s],
        _ => [0, 1, 2, 3].map(|_| rng.unit() * 2.0 - 1.0),
    }
}

fn random_pos(rng: &mut Rng, s: [u32; 3]) -> [f64; 3] {
    [0, 1, 2].map(|a| rng.unit() * f64::from(s[a] - 1))
}

fn apply(w: &mut World, ops: Vec<Op>) -> naadf_world::edit::Applied {
    w.apply(&Batch { ops }, &Limits::default())
        .unwrap_or_else(|e| panic!("batch rejected: {e}"))
}

/// A world with `models` random models and `n` entities spawned at random poses.
fn scene(size: WorldSize, seed: u64, models: usize, n: u32) -> (Raw, World) {
    let raw = random_world(size, seed);
    let mut w = raw.build();
    let mut rng = Rng(seed ^ 0xE7);
    let defs = (0..models)
        .map(|k| random_model(&mut rng, &format!("m{k}"), [6, 14, 30][k % 3]))
        .collect();
    apply(&mut w, defs);
    let mut ops = Vec::new();
    for id in 0..n {
        ops.push(Op::SpawnEntity {
            id: id * 3 + 1,
            model: format!("m{}", rng.below(models as u64)),
            pos: random_pos(&mut rng, size.voxels()),
            rot: random_rot(&mut rng),
        });
    }
    apply(&mut w, ops);
    (raw, w)
}

/// The same world without its entities (voxels untouched).
fn without_entities(w: &World) -> World {
    let mut v = w.clone();
    let ops = w
        .entity_table()
        .instances
        .keys()
        .map(|&id| Op::DespawnEntity { id })
        .collect();
    apply(&mut v, ops);
    v
}

/// Entry and exit times of `ray` through the box `[0, s)`, if it passes through.
fn slab(o: [f64; 3], d: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
    for a in 0..3 {
        if d[a] == 0.0 {
            if o[a] < lo[a] || o[a] >= hi[a] {
                return None;
            }
            continue;
        }
        let (p, q) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
        t0 = t0.max(p.min(q));
        t1 = t1.min(p.max(q));
    }
    (t0 < t1 && t1 > 0.0).then_some((t0.max(0.0), t1))
}

/// When the ray is inside the world `[0, s)`: from the origin (if inside) or the entry
/// through the box, to where it leaves.
fn world_window(ray: &Ray, s: [f64; 3]) -> Option<(f64, f64)> {
    let (o, d) = (ray.origin(), ray.dir());
    if (0..3).all(|a| o[a].floor() >= 0.0 && o[a].floor() < s[a]) {
        let out = (0..3)
            .filter(|&a| d[a] != 0.0)
            .map(|a| (if d[a] > 0.0 { s[a] } else { 0.0 } - o[a]) / d[a])
            .fold(f64::INFINITY, f64::min);
        return Some((0.0, out));
    }
    slab(o, d, [0.0; 3], s)
}

/// Brute force: the nearest entity voxel entered inside `[t_lo, t_hi)`, as (t, id, voxel),
/// testing every solid voxel of every entity with a slab test in the entity's frame.
fn brute_entity(w: &World, ray: &Ray, t_lo: f64, t_hi: f64) -> Option<(f64, u32, [u32; 3])> {
    let mut best: Option<(f64, u32, [u32; 3])> = None;
    let models = w.models();
    for (&id, pose) in &w.entity_table().instances {
        let m = models.get(&pose.model).unwrap();
        let inv = conjugate(pose.rot);
        let o = ray.origin();
        let ol = rotate(inv, [0, 1, 2].map(|a| o[a] - pose.pos[a]));
        let dl = rotate(inv, ray.dir());
        let s = m.size();
        for z in 0..s[2] {
            for y in 0..s[1] {
                for x in 0..s[0] {
                    let i = (x + s[0] * (y + s[1] * z)) as usize;
                    if m.voxels()[i] == 0 {
                        continue;
                    }
                    let lo = [x, y, z].map(f64::from);
                    let Some((t, _)) = slab(ol, dl, lo, lo.map(|v| v + 1.0)) else {
                        continue;
                    };
                    if t >= t_lo && t < t_hi && best.is_none_or(|b| (t, id) < (b.0, b.1)) {
                        best = Some((t, id, [x, y, z]));
                    }
                }
            }
        }
    }
    best
}

/// Checks one ray: the three methods agree exactly, the occlusion query says whether they
/// hit, and the result matches the brute-force oracle (world-only trace plus brute-force
/// entities). Returns whether an entity was hit.
fn check_ray(w: &World, world_only: &DenseGrid, grid: &DenseGrid, ray: &Ray) -> bool {
    let (a, b, c) = (trace_naadf(w, ray), trace_nodf(w, ray), grid.trace(ray));
    assert!(
        same_result(&a, &b) && same_result(&a, &c),
        "{ray:?}: naadf {a:?} / nodf {b:?} / grid {c:?}"
    );
    assert_eq!(
        occluded_naadf(w, ray),
        a.is_some(),
        "{ray:?}: occlusion and trace differ"
    );
    if let (Some(x), Some(y)) = (a, b) {
        assert!(x.steps <= y.steps, "AADF jumps never take more steps");
    }
    // The oracle.
    let s = w.size().voxels().map(f64::from);
    let world_hit = world_only.trace(ray);
    let Some((t_in, t_out)) = world_window(ray, s) else {
        // Misses the world, or only grazes it at an edge (where the event order decides).
        return false;
    };
    let t_end = world_hit.map_or(t_out, |h| h.t);
    let expect_entity = brute_entity(w, ray, t_in, t_end);
    match (expect_entity, a) {
        (Some((t, id, v)), Some(h)) => {
            // Ties (a voxel entered exactly at the world hit or at another voxel's time)
            // have no unique answer in floating point; random rays avoid them.
            if (t - t_end).abs() < 1e-9 {
                return false;
            }
            assert_eq!(
                h.entity,
                Some(id),
                "{ray:?}: brute force {expect_entity:?}, traced {h:?}"
            );
            assert!((h.t - t).abs() <= 1e-9 * t.max(1.0), "{ray:?}: t {} vs {t}", h.t);
            if h.voxel != v {
                // Another voxel entered at the same time (through a shared face or edge).
                let pose = w.entity(id).unwrap();
                let m = w.models().get(&pose.model).unwrap();
                let sz = m.size();
                let i = (h.voxel[0] + sz[0] * (h.voxel[1] + sz[1] * h.voxel[2])) as usize;
                assert_ne!(m.voxels()[i], 0, "{ray:?}: hit an empty entity voxel");
            }
            let pose = w.entity(id).unwrap();
            let m = w.models().get(&pose.model).unwrap();
            let sz = m.size();
            let i = (h.voxel[0] + sz[0] * (h.voxel[1] + sz[1] * h.voxel[2])) as usize;
            assert_eq!(h.material, m.voxels()[i], "{ray:?}: entity material");
            true
        }
        (None, got) => {
            assert!(
                same_result(&got, &world_hit),
                "{ray:?}: no entity by brute force, traced {got:?}, world {world_hit:?}"
            );
            false
        }
        (Some(e), None) => panic!("{ray:?}: brute force hits entity {e:?}, traced a miss"),
    }
}

/// Rays through an entity scene: random ones through the world; rays aimed at each
/// entity from near and far, and from up to 10^8.5 voxels away; fans of rays from one
/// origin toward each entity (neighbouring camera rays, which a batch walks as one group);
/// and adversarial ones, from inside an instance's grid, moving within a face plane of its
/// world box (grazing it), or along one of the box's edges.
fn scene_rays(w: &World, rng: &mut Rng, random: usize) -> Vec<Ray> {
    let mut out = rays(w.size().voxels(), rng, random);
    for (_, pose) in w.entity_table().instances.clone() {
        for _ in 0..40 {
            let target = [0, 1, 2].map(|a| pose.pos[a] + rng.unit() * 8.0 - 2.0);
            let from = [0, 1, 2].map(|a| target[a] + (rng.unit() * 2.0 - 1.0) * 40.0);
            out.extend(Ray::new(from, [0, 1, 2].map(|a| target[a] - from[a])));
        }
        // From far away: origins may lie up to 2^30 voxels out, far beyond where `f32`
        // (the hierarchy's walk) holds a position to a voxel.
        for k in 0..12 {
            let target = [0, 1, 2].map(|a| pose.pos[a] + rng.unit() * 8.0 - 2.0);
            let d = [0, 1, 2].map(|_| rng.unit() * 2.0 - 1.0);
            let far = 10f64.powf(3.0 + f64::from(k) * 0.5);
            out.extend(Ray::new([0, 1, 2].map(|a| target[a] - d[a] * far), d));
        }
        let from = [0, 1, 2].map(|a| pose.pos[a] + (rng.unit() * 2.0 - 1.0) * 30.0);
        for k in 0..48 {
            let target =
                [0, 1, 2].map(|a| pose.pos[a] + f64::from(k % 8) * 1.3 - 2.0 + f64::from(k / 8 * a as u32) * 0.9);
            out.extend(Ray::new(from, [0, 1, 2].map(|a| target[a] - from[a])));
        }
    }
    for (_, pose) in w.entity_table().instances.clone() {
        let size = w.models().get(&pose.model).unwrap().size().map(f64::from);
        let corners: Vec<[f64; 3]> = (0..8)
            .map(|c| {
                let p = rotate(pose.rot, [0, 1, 2].map(|a| if c >> a & 1 == 1 { size[a] } else { 0.0 }));
                [0, 1, 2].map(|a| pose.pos[a] + p[a])
            })
            .collect();
        let lo = [0, 1, 2].map(|a| corners.iter().map(|c| c[a]).fold(f64::INFINITY, f64::min));
        let hi = [0, 1, 2].map(|a| corners.iter().map(|c| c[a]).fold(f64::NEG_INFINITY, f64::max));
        for _ in 0..20 {
            let local = [0, 1, 2].map(|a| rng.unit() * size[a]);
            let p = rotate(pose.rot, local);
            let inside = [0, 1, 2].map(|a| pose.pos[a] + p[a]);
            let d = [0, 1, 2].map(|_| rng.unit() - 0.5);
            out.extend(Ray::new(inside, d));
            let axis = rng.below(3) as usize;
            let mut o = [0, 1, 2].map(|a| lo[a] - 3.0 + rng.unit() * (hi[a] - lo[a] + 6.0));
            o[axis] = if rng.unit() < 0.5 { lo[axis] } else { hi[axis] };
            let mut d = [0, 1, 2].map(|_| rng.unit() - 0.5);
            d[axis] = 0.0;
            if rng.unit() < 0.3 {
                // Along an edge: on two face planes, moving along the third axis.
                let b = (axis + 1) % 3;
                o[b] = if rng.unit() < 0.5 { lo[b] } else { hi[b] };
                d[b] = 0.0;
            }
            out.extend(Ray::new(o, d));
        }
    }
    out
}

#[test]
fn rays_through_entity_scenes_match_brute_force_and_the_methods_agree() {
    for seed in 0..5u64 {
        let size = common::size_for(seed, &[[64, 64, 64], [128, 64, 64], [64, 128, 64]]);
        let (raw, w) = scene(size, seed, 4, 8 + seed as u32 * 3);
        assert_aadf_valid(&raw, &w, "scene");
        let grid = DenseGrid::from_world(&w).unwrap();
        let world_only = DenseGrid::from_world(&without_entities(&w)).unwrap();
        let mut rng = Rng(seed + 100);
        let entity_hits: usize = scene_rays(&w, &mut rng, 1500)
            .iter()
            .map(|ray| usize::from(check_ray(&w, &world_only, &grid, ray)))
            .sum();
        assert!(entity_hits > 100, "seed {seed}: only {entity_hits} entity hits");
        // After growth, the same again.
        let mut w2 = w.clone();
        w2.grow_until_quiescent();
        assert_aadf_valid(&raw, &w2, "scene after growth");
        for ray in rays(size.voxels(), &mut rng, 300) {
            check_ray(&w2, &world_only, &grid, &ray);
        }
    }
}

/// Every method traces a slice of rays ([`Tracer::trace_many`], whose instance walks go as
/// batches, coherent groups and the rest apart) to exactly what it traces ray by ray
/// (which the test above holds to brute force), steps included; the rays cover the scene's
/// adversarial cases, and slices of every length split them differently.
#[test]
fn tracing_slices_of_rays_gives_what_tracing_each_gives() {
    for seed in 0..3u64 {
        let size = common::size_for(seed, &[[64, 64, 64], [128, 64, 64]]);
        let (_, w) = scene(size, seed, 4, 12);
        let rays = scene_rays(&w, &mut Rng(seed + 7), 2000);
        for method in Method::ALL {
            let tracer = Tracer::new(&w, method).unwrap();
            let one_by_one: Vec<Option<Hit>> = rays.iter().map(|r| tracer.trace(r)).collect();
            assert!(one_by_one.iter().flatten().filter(|h| h.entity.is_some()).count() > 100);
            for slice in [rays.len(), 1, 15, 1000, 1025] {
                let sliced: Vec<Option<Hit>> = rays.chunks(slice).flat_map(|c| tracer.trace_many(c)).collect();
                assert!(sliced == one_by_one, "{method:?}, slices of {slice}: results differ");
            }
        }
    }
}

/// A tracer for the static world alone sees, with every method and one ray at a time or
/// in slices, exactly the world without its entities (rebuilt without them), while the
/// full tracer does hit entities on the same rays.
#[test]
fn a_static_only_tracer_sees_the_world_without_its_entities() {
    let size = WorldSize::new(64, 64, 64).unwrap();
    let (_, w) = scene(size, 5, 4, 12);
    let bare = without_entities(&w);
    let rays = scene_rays(&w, &mut Rng(12), 1500);
    for method in Method::ALL {
        let bare_tracer = Tracer::new(&bare, method).unwrap();
        let oracle: Vec<Option<Hit>> = rays.iter().map(|r| bare_tracer.trace(r)).collect();
        let full = Tracer::new(&w, method).unwrap();
        assert!(rays.iter().filter_map(|r| full.trace(r)).any(|h| h.entity.is_some()));
        let static_only = full.static_only();
        let each: Vec<Option<Hit>> = rays.iter().map(|r| static_only.trace(r)).collect();
        assert!(each == oracle, "{method:?}: one by one");
        let sliced: Vec<Option<Hit>> = rays.chunks(700).flat_map(|c| static_only.trace_many(c)).collect();
        assert!(sliced == oracle, "{method:?}: in slices");
    }
}

/// Batches of small moves keep the hierarchy's shape and refit its boxes; rays through
/// the moved instances still match brute force after every batch.
/// Small moves refit the hierarchy derived last; after the third batch no ray is traced,
/// so the fourth batch's set is refitted from the second's, two buffers back.
#[test]
fn rays_match_brute_force_after_small_moves_refit_the_hierarchy() {
    let size = WorldSize::new(64, 64, 64).unwrap();
    let (_, mut w) = scene(size, 3, 3, 24);
    let world_only = DenseGrid::from_world(&without_entities(&w)).unwrap();
    let mut rng = Rng(33);
    for step in 0..6 {
        let moves = w
            .entity_table()
            .instances
            .iter()
            .map(|(&id, p)| Op::MoveEntity {
                id,
                pos: [0, 1, 2].map(|a| (p.pos[a] + rng.unit() - 0.5).clamp(0.0, 60.0)),
                rot: p.rot,
            })
            .collect();
        apply(&mut w, moves);
        if step == 2 {
            continue;
        }
        let grid = DenseGrid::from_world(&w).unwrap();
        let mut entity_hits = 0;
        for (_, pose) in w.entity_table().instances.clone() {
            for _ in 0..30 {
                let target = [0, 1, 2].map(|a| pose.pos[a] + rng.unit() * 8.0 - 2.0);
                let from = [0, 1, 2].map(|a| target[a] + (rng.unit() * 2.0 - 1.0) * 40.0);
                if let Ok(ray) = Ray::new(from, [0, 1, 2].map(|a| target[a] - from[a])) {
                    entity_hits += usize::from(check_ray(&w, &world_only, &grid, &ray));
                }
            }
        }
        assert!(entity_hits > 50, "batch {step}: only {entity_hits} entity hits");
    }
}

#[test]
fn an_entity_in_front_of_world_geometry_wins() {
    let size = WorldSize::new(64, 64, 64).unwrap();
    let mut raw = Raw::empty(size, 3);
    for x in 0..64 {
        for z in 0..64 {
            raw.set([x, 0, z], 1);
        }
    }
    let mut w = raw.build();
    apply(
        &mut w,
        vec![
            Op::DefineModel {
                name: "crate".into(),
                size: [2, 3, 4],
                voxels: vec![[0, 0, 0, 2], [1, 2, 3, 3]],
            },
            Op::SpawnEntity {
                id: 5,
                model: "crate".into(),
                pos: [10.0, 20.0, 10.0],
                rot: [0.0, 0.0, 0.0, 1.0],
            },
        ],
    );
    let grid = DenseGrid::from_world(&w).unwrap();
    let down = Ray::new([10.5, 40.0, 10.5], [0.0, -1.0, 0.0]).unwrap();
    for h in [trace_naadf(&w, &down), trace_nodf(&w, &down), grid.trace(&down)] {
        let h = h.unwrap();
        assert_eq!(
            (h.entity, h.voxel, h.normal, h.material, h.t),
            (Some(5), [0, 0, 0], [0, 1, 0], 2, 19.0),
            "{h:?}"
        );
    }
    // Next to the entity voxel the floor is hit.
    let beside = Ray::new([11.5, 40.0, 10.5], [0.0, -1.0, 0.0]).unwrap();
    let h = trace_naadf(&w, &beside).unwrap();
    assert_eq!((h.entity, h.voxel, h.t), (None, [11, 0, 10], 39.0));
    // Rotated 90° about y: local (1,2,3) lands at world pos + R·(1.5,2.5,3.5).
    let s = std::f64::consts::FRAC_1_SQRT_2;
    apply(
        &mut w,
        vec![Op::MoveEntity {
            id: 5,
            pos: [30.0, 5.0, 30.0],
            rot: [0.0, s, 0.0, s],
        }],
    );
    let rot = w.entity(5).unwrap().rot;
    let c = rotate(rot, [1.5, 2.5, 3.5]);
    let target = [30.0 + c[0], 5.0 + c[1], 30.0 + c[2]];
    let ray = Ray::new([target[0], 60.0, target[2]], [0.0, -1.0, 0.0]).unwrap();
    let grid = DenseGrid::from_world(&w).unwrap();
    for h in [trace_naadf(&w, &ray), trace_nodf(&w, &ray), grid.trace(&ray)] {
        let h = h.unwrap();
        assert_eq!((h.entity, h.voxel, h.material), (Some(5), [1, 2, 3], 3), "{h:?}");
        // Entered through local +y (the world's up is the local up under a y rotation).
        assert_eq!(h.normal, [0, 1, 0]);
        assert!((h.t - (60.0 - 8.0)).abs() < 1e-3, "{}", h.t);
    }
    // The old place is free again: the floor is hit there.
    let h = trace_naadf(&w, &down).unwrap();
    assert_eq!((h.entity, h.voxel), (None, [10, 0, 10]));
}

/// The instance buffer, recomputed from the poses: the record of each entity in the slot of
/// its id, zero slots between, ending after the highest id.
fn check_instance_buffer(w: &World) {
    let table = w.entity_table();
    let slots = table.instances.keys().last().map_or(0, |&id| id as usize + 1);
    let buf = w.entity_instances();
    assert_eq!(buf.len(), slots * RECORD_WORDS);
    for slot in 0..slots {
        let words = &buf[slot * RECORD_WORDS..][..RECORD_WORDS];
        match table.instances.get(&(slot as u32)) {
            None => assert!(words.iter().all(|&v| v == 0), "slot {slot} is not empty"),
            Some(pose) => {
                let r = InstanceRecord::unpack(words);
                assert_eq!(r.id, slot as u32);
                assert_eq!(r.size, w.models().get(&pose.model).unwrap().size());
                assert_eq!(r.position(), pose.pos);
                assert_eq!(conjugate(naadf_world::entity::pack::decode_quat(r.inv_rot)), pose.rot);
            }
        }
    }
}

/// The static buffers (chunks, chunk entity fields, blocks, voxels) of two worlds are
/// byte-identical.
fn assert_same_static(a: &World, b: &World, what: &str) {
    assert!(a.chunks() == b.chunks(), "{what}: chunk cells differ");
    assert!(
        a.chunk_entities() == b.chunk_entities(),
        "{what}: chunk entity fields differ"
    );
    assert!(a.blocks() == b.blocks(), "{what}: blocks differ");
    assert!(a.voxels() == b.voxels(), "{what}: voxels differ");
}

/// A world built fresh with `table`'s entities (same type order) over the same voxels.
fn fresh_with(raw: &Raw, models: &[Op], table: &EntityTable) -> World {
    let mut w = raw.build();
    apply(&mut w, models.to_vec());
    // Spawn one entity of every type first, in type order, so the types come out in the
    // same order; then the real ones.
    let mut ops = Vec::new();
    for (k, t) in table.types.iter().enumerate() {
        ops.push(Op::SpawnEntity {
            id: MAX_ENTITY_ID - k as u32,
            model: t.clone(),
            pos: [1.0; 3],
            rot: [0.0, 0.0, 0.0, 1.0],
        });
    }
    for (k, _) in table.types.iter().enumerate() {
        ops.push(Op::DespawnEntity {
            id: MAX_ENTITY_ID - k as u32,
        });
    }
    for (&id, p) in &table.instances {
        ops.push(Op::SpawnEntity {
            id,
            model: p.model.clone(),
            pos: p.pos,
            rot: p.rot,
        });
    }
    apply(&mut w, ops);
    w
}

#[test]
fn moves_leave_no_stale_fields_and_growth_converges() {
    let size = WorldSize::new(256, 64, 64).unwrap();
    let raw = random_world(size, 42);
    let mut rng = Rng(42);
    let models: Vec<Op> = (0..3).map(|k| random_model(&mut rng, &format!("m{k}"), 20)).collect();
    let mut w = raw.build();
    apply(&mut w, models.clone());
    let mut ids: Vec<u32> = Vec::new();
    for step in 0..40 {
        let mut ops = Vec::new();
        for _ in 0..1 + rng.below(4) {
            let op = match rng.below(5) {
                0 | 1 if !ids.is_empty() => {
                    let id = ids[rng.below(ids.len() as u64) as usize];
                    Op::MoveEntity {
                        id,
                        pos: random_pos(&mut rng, size.voxels()),
                        rot: random_rot(&mut rng),
                    }
                }
                2 if !ids.is_empty() => {
                    let k = rng.below(ids.len() as u64) as usize;
                    Op::DespawnEntity { id: ids.swap_remove(k) }
                }
                _ => {
                    let id = (0..).find(|i| !ids.contains(i)).unwrap();
                    ids.push(id);
                    Op::SpawnEntity {
                        id,
                        model: format!("m{}", rng.below(3)),
                        pos: random_pos(&mut rng, size.voxels()),
                        rot: random_rot(&mut rng),
                    }
                }
            };
            ops.push(op);
        }
        let applied = apply(&mut w, ops);
        let what = format!("step {step}");
        assert_eq!(w.digest(), w.digest_from_scratch(), "{what}: incremental digest");
        assert_eq!(applied.change.digest, w.digest());
        assert_aadf_valid(&raw, &w, &what);
        assert_canonical(&w, &what);
        check_instance_buffer(&w);
        if step % 3 == 0 {
            w.grow_distance_fields(rng.below(60) as usize);
            assert_aadf_valid(&raw, &w, &format!("{what} after growth"));
        }
        if step % 10 == 9 {
            // The same entities spawned directly: identical entity buffers.
            let fresh = fresh_with(&raw, &models, w.entity_table());
            assert_eq!(fresh.entity_table(), w.entity_table());
            assert_same_static(&fresh, &w, &what);
            assert_eq!(
                fresh.entity_instances(),
                w.entity_instances(),
                "{what}: instance buffer"
            );
            assert_eq!(
                fresh.entity_type_voxels(),
                w.entity_type_voxels(),
                "{what}: type buffer"
            );
            // Converged chunk AADFs equal a from-scratch build.
            let mut converged = w.clone();
            converged.grow_until_quiescent();
            let mut scratch = converged.clone();
            scratch.rebuild_chunk_aadf();
            assert!(converged.chunks() == scratch.chunks(), "{what}: converged AADFs differ");
            let mut fresh = fresh;
            fresh.grow_until_quiescent();
            assert!(
                fresh.chunks() == converged.chunks(),
                "{what}: fresh world's AADFs differ"
            );
            assert_eq!(fresh.digest(), converged.digest(), "{what}: digests differ");
            assert_aadf_valid(&raw, &converged, &format!("{what} converged"));
        }
    }
}

#[test]
fn entity_op_errors_reject_the_whole_batch() {
    let size = WorldSize::new(64, 64, 64).unwrap();
    let (_, mut w) = scene(size, 7, 2, 3);
    let before = (w.to_parts(), w.digest(), w.version());
    let spawn = |id: u32, model: &str, pos: [f64; 3], rot: [f64; 4]| Op::SpawnEntity {
        id,
        model: model.into(),
        pos,
        rot,
    };
    let id0 = 1; // spawned by `scene`
    let ok_rot = [0.0, 0.0, 0.0, 1.0];
    let cases: Vec<(Op, &str)> = vec![
        (spawn(id0, "m0", [1.0; 3], ok_rot), "already exists"),
        (spawn(MAX_ENTITY_ID + 1, "m0", [1.0; 3], ok_rot), "outside 0..=16382"),
        (spawn(500, "nope", [1.0; 3], ok_rot), "not defined"),
        (spawn(500, "m0", [-1.0, 1.0, 1.0], ok_rot), "pos"),
        (spawn(500, "m0", [1.0, 4096.0, 1.0], ok_rot), "pos"),
        (spawn(500, "m0", [16384.0, 1.0, 1.0], ok_rot), "pos"),
        (spawn(500, "m0", [1.0, f64::NAN, 1.0], ok_rot), "finite"),
        (spawn(500, "m0", [1.0; 3], [0.0; 4]), "non-zero"),
        (
            spawn(500, "m0", [1.0; 3], [f64::INFINITY, 0.0, 0.0, 1.0]),
            "non-zero finite",
        ),
        (spawn(500, "m0", [300.0, 1.0, 1.0], ok_rot), "entirely outside"),
        (
            Op::MoveEntity {
                id: 999,
                pos: [1.0; 3],
                rot: ok_rot,
            },
            "does not exist",
        ),
        (
            Op::MoveEntity {
                id: id0,
                pos: [1000.0, 1.0, 1.0],
                rot: ok_rot,
            },
            "entirely outside",
        ),
        (Op::DespawnEntity { id: 999 }, "does not exist"),
    ];
    for (op, want) in cases {
        let name = op.name();
        let batch = Batch {
            ops: vec![
                Op::Box {
                    min: [0; 3],
                    max: [8; 3],
                    material: 1,
                },
                spawn(600, "m1", [20.0; 3], ok_rot),
                op,
            ],
        };
        let e = w.apply(&batch, &Limits::default()).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, EditError::Invalid { index: 2, .. }), "{msg}");
        assert!(msg.contains(name) && msg.contains(want), "want {want:?}: {msg}");
        assert!(
            (w.to_parts(), w.digest(), w.version()) == before,
            "a rejected batch changed the world"
        );
    }
    // Any number of entities may share a place (the chunk lists' limit of 255 is gone):
    // the lowest id is hit.
    let mut w = Raw::empty(size, 3).build();
    let mut all = vec![Op::DefineModel {
        name: "tiny".into(),
        size: [1, 1, 1],
        voxels: vec![[0, 0, 0, 1]],
    }];
    all.extend((1000..1300).map(|id| spawn(id, "tiny", [40.5, 40.5, 40.5], ok_rot)));
    apply(&mut w, all);
    let down = Ray::new([40.7, 60.0, 40.7], [0.0, -1.0, 0.0]).unwrap();
    assert_eq!(trace_naadf(&w, &down).unwrap().entity, Some(1000));
}

#[test]
fn undo_and_redo_of_spawn_move_despawn() {
    let size = WorldSize::new(64, 64, 64).unwrap();
    let (_, mut w) = scene(size, 3, 2, 2);
    let start = w.entity_table().clone();
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let batches = [
        vec![
            Op::SpawnEntity {
                id: 100,
                model: "m0".into(),
                pos: [5.3, 6.1, 7.7],
                rot: [0.1, 0.2, 0.3, 0.9],
            },
            Op::Set {
                voxels: vec![[3, 3, 3, 2]],
            },
        ],
        vec![Op::MoveEntity {
            id: 100,
            pos: [30.0, 20.0, 10.0],
            rot: [0.0, s, 0.0, s],
        }],
        vec![Op::DespawnEntity { id: 1 }, Op::DespawnEntity { id: 100 }],
    ];
    let mut undos = Vec::new();
    let mut states = vec![w.entity_table().clone()];
    for b in batches {
        let u = apply(&mut w, b).undo;
        assert!(!u.entities.is_empty());
        undos.push(u);
        states.push(w.entity_table().clone());
    }
    // Undo in reverse order restores each earlier state; redo goes forward again.
    let mut redos = Vec::new();
    for (k, u) in undos.iter().enumerate().rev() {
        let ops = u.undo_batch(&w).ops;
        let redo = apply(&mut w, ops).undo;
        assert_eq!(w.entity_table().instances, states[k].instances, "undo {k}");
        redos.push(redo);
    }
    assert_eq!(w.entity_table().instances, start.instances);
    for (k, r) in redos.iter().rev().enumerate() {
        let ops = r.undo_batch(&w).ops;
        apply(&mut w, ops);
        assert_eq!(w.entity_table().instances, states[k + 1].instances, "redo {k}");
    }
    // Someone else moved the entity since: its undo leaves it alone.
    let u = apply(
        &mut w,
        vec![Op::SpawnEntity {
            id: 200,
            model: "m1".into(),
            pos: [9.0; 3],
            rot: [0.0, 0.0, 0.0, 1.0],
        }],
    )
    .undo;
    apply(
        &mut w,
        vec![Op::MoveEntity {
            id: 200,
            pos: [12.0; 3],
            rot: [0.0, 0.0, 0.0, 1.0],
        }],
    );
    assert!(u.undo_batch(&w).ops.is_empty());
    // A model change through despawn + spawn of the same id undoes as despawn + spawn.
    let u = apply(
        &mut w,
        vec![
            Op::DespawnEntity { id: 200 },
            Op::SpawnEntity {
                id: 200,
                model: "m0".into(),
                pos: [9.0; 3],
                rot: [0.0, 0.0, 0.0, 1.0],
            },
        ],
    )
    .undo;
    let before = w.entity(200).cloned();
    let ops = u.undo_batch(&w).ops;
    apply(&mut w, ops);
    assert_eq!(w.entity(200).unwrap().model, "m1");
    assert_ne!(w.entity(200).cloned(), before);
}

#[test]
fn mirrors_following_change_records_stay_identical() {
    let size = WorldSize::new(128, 64, 64).unwrap();
    let raw = random_world(size, 11);
    let mut server = raw.build();
    let mut mirror = raw.build();
    let mut rng = Rng(11);
    let mut batches = vec![
        (0..3)
            .map(|k| random_model(&mut rng, &format!("m{k}"), 16))
            .collect::<Vec<_>>(),
    ];
    let mut live: Vec<u32> = Vec::new();
    for _ in 0..25 {
        let mut ops = Vec::new();
        for _ in 0..1 + rng.below(3) {
            match rng.below(6) {
                0 if !live.is_empty() => ops.push(Op::DespawnEntity {
                    id: live.swap_remove(rng.below(live.len() as u64) as usize),
                }),
                1 | 2 if !live.is_empty() => ops.push(Op::MoveEntity {
                    id: live[rng.below(live.len() as u64) as usize],
                    pos: random_pos(&mut rng, size.voxels()),
                    rot: random_rot(&mut rng),
                }),
                3 => {
                    let c = random_pos(&mut rng, size.voxels());
                    ops.push(Op::Sphere {
                        center: c,
                        radius: rng.unit() * 12.0,
                        material: rng.below(4) as u16,
                    });
                }
                4 => {
                    let name = format!("m{}", rng.below(3));
                    ops.push(random_model(&mut rng, &name, 16));
                }
                _ => {
                    let id = (0..).find(|i| !live.contains(i)).unwrap();
                    live.push(id);
                    ops.push(Op::SpawnEntity {
                        id,
                        model: format!("m{}", rng.below(3)),
                        pos: random_pos(&mut rng, size.voxels()),
                        rot: random_rot(&mut rng),
                    });
                }
            }
        }
        batches.push(ops);
    }
    for ops in batches {
        let mut changes = vec![apply(&mut server, ops).change];
        changes.extend(server.grow_distance_fields(rng.below(100) as usize));
        common::follow(&server, &mut mirror, changes);
        assert_eq!(server.digest(), server.digest_from_scratch());
    }
    assert!(!server.entity_table().instances.is_empty());
}

#[test]
fn world_files_keep_entities() {
    let size = WorldSize::new(128, 64, 64).unwrap();
    let (_, mut w) = scene(size, 5, 3, 12);
    // Near-tie rotations too.
    let s = std::f64::consts::FRAC_1_SQRT_2;
    apply(
        &mut w,
        vec![
            Op::SpawnEntity {
                id: 900,
                model: "m0".into(),
                pos: [3.0, 3.0, 3.0],
                rot: [s, s, 0.0, 0.0],
            },
            Op::SpawnEntity {
                id: 901,
                model: "m1".into(),
                pos: [50.0, 3.0, 3.0],
                rot: [0.5, 0.5, 0.5, -0.5],
            },
        ],
    );
    for quiescent in [false, true] {
        if quiescent {
            w.grow_until_quiescent();
        }
        let mut bytes = Vec::new();
        file::write(&w, &mut bytes).unwrap();
        let back = file::read(&mut &bytes[..]).unwrap();
        assert!(back.to_parts() == w.to_parts());
        assert_eq!(back.digest(), w.digest());
        assert_eq!(back.entity_instances(), w.entity_instances());
        assert_eq!(back.entity_type_voxels(), w.entity_type_voxels());
        let mut again = Vec::new();
        file::write(&back, &mut again).unwrap();
        assert_eq!(again, bytes);
    }
    // Tampered entity tables are refused.
    let good = w.to_parts();
    let mut p = good.clone();
    p.entities.instances.get_mut(&900).unwrap().pos[0] += 0.001;
    assert!(World::from_parts(p).unwrap_err().to_string().contains("quantised"));
    let mut p = good.clone();
    p.entities.instances.get_mut(&900).unwrap().model = "nope".into();
    assert!(World::from_parts(p).is_err());
    let mut p = good.clone();
    p.chunk_entities[3] = 1 << 8 | 1;
    assert!(World::from_parts(p).unwrap_err().to_string().contains("entity field"));
    // The static world does not depend on the entities: a table without one is another
    // valid world.
    let mut p = good.clone();
    p.entities.instances.remove(&900);
    let fewer = World::from_parts(p).unwrap();
    assert_ne!(fewer.digest(), w.digest());
    assert_same_static(&fewer, &w, "one entity fewer");
}

#[test]
fn a_thousand_random_moves_leave_the_static_world_as_without_entities() {
    let size = WorldSize::new(256, 64, 64).unwrap();
    let raw = random_world(size, 7);
    let base = raw.build();
    let mut rng = Rng(7);
    let models: Vec<Op> = (0..3).map(|k| random_model(&mut rng, &format!("m{k}"), 12)).collect();
    let mut w = raw.build();
    apply(&mut w, models);
    let spawns = (0..50)
        .map(|id| Op::SpawnEntity {
            id,
            model: format!("m{}", id % 3),
            pos: random_pos(&mut rng, size.voxels()),
            rot: random_rot(&mut rng),
        })
        .collect();
    let change = apply(&mut w, spawns).change;
    assert!(change.quiescent && w.is_quiescent(), "spawning queues no growth");
    assert_same_static(&w, &base, "after spawning");
    for step in 0..20 {
        let moves = (0..50)
            .map(|_| Op::MoveEntity {
                id: rng.below(50) as u32,
                pos: random_pos(&mut rng, size.voxels()),
                rot: random_rot(&mut rng),
            })
            .collect();
        let change = apply(&mut w, moves).change;
        // A move writes its entities' records and nothing else.
        assert!(w.is_quiescent() && change.quiescent);
        assert!(
            change
                .writes
                .ranges()
                .iter()
                .all(|(id, _)| *id == naadf_world::digest::BufferId::EntityInstances)
        );
        assert_same_static(&w, &base, &format!("after move batch {step}"));
        check_instance_buffer(&w);
    }
    apply(&mut w, (0..50).map(|id| Op::DespawnEntity { id }).collect());
    assert!(w.entity_instances().is_empty());
    assert_same_static(&w, &base, "after despawning");
}

#[test]
fn hits_report_entity_local_coordinates_with_every_method() {
    // A thin plate rotated 45° about z, hit from above: local voxel and normal.
    let size = WorldSize::new(64, 64, 64).unwrap();
    let mut w = Raw::empty(size, 3).build();
    let (sn, cs) = (std::f64::consts::FRAC_PI_8.sin(), std::f64::consts::FRAC_PI_8.cos());
    apply(
        &mut w,
        vec![
            Op::DefineModel {
                name: "plate".into(),
                size: [8, 1, 8],
                voxels: (0..64).map(|i| [i % 8, 0, i / 8, 1 + i % 3]).collect(),
            },
            Op::SpawnEntity {
                id: 3,
                model: "plate".into(),
                pos: [20.0, 20.0, 20.0],
                rot: [0.0, 0.0, sn, cs],
            },
        ],
    );
    let grid = DenseGrid::from_world(&w).unwrap();
    let rot = w.entity(3).unwrap().rot;
    let mut rng = Rng(9);
    for _ in 0..200 {
        let local = [rng.unit() * 8.0, 1.0, rng.unit() * 8.0];
        let p = rotate(rot, local);
        let target = [20.0 + p[0], 20.0 + p[1], 20.0 + p[2]];
        let ray = Ray::new([target[0], 50.0, target[2]], [0.0, -1.0, 0.0]).unwrap();
        let hits: Vec<Option<Hit>> = vec![trace_naadf(&w, &ray), trace_nodf(&w, &ray), grid.trace(&ray)];
        let h = hits[0].unwrap();
        assert!(hits.iter().all(|x| same_result(x, &hits[0])));
        assert_eq!(h.entity, Some(3));
        // Entered through the local top, or through a local side face for rays that clip
        // the rotated plate's edge.
        assert!(h.voxel[1] == 0 && h.voxel[0] < 8 && h.voxel[2] < 8);
        assert!(h.normal == [0, 1, 0] || h.normal[1] == 0, "{h:?}");
        assert_eq!(h.material, (1 + (h.voxel[0] + 8 * h.voxel[2]) % 3) as u16);
    }
}

#[test]
fn ties_go_to_the_world_then_to_the_lowest_id() {
    let size = WorldSize::new(64, 64, 64).unwrap();
    let mut raw = Raw::empty(size, 3);
    raw.set([40, 5, 20], 3);
    let mut w = raw.build();
    let id = [0.0, 0.0, 0.0, 1.0];
    apply(
        &mut w,
        vec![
            // A long model whose only solid voxel is at its far end: met first along +x.
            Op::DefineModel {
                name: "long".into(),
                size: [40, 1, 1],
                voxels: vec![[39, 0, 0, 1]],
            },
            Op::DefineModel {
                name: "dot".into(),
                size: [1, 1, 1],
                voxels: vec![[0, 0, 0, 2]],
            },
            Op::SpawnEntity {
                id: 9,
                model: "long".into(),
                pos: [1.0, 9.0, 20.0],
                rot: id,
            },
            Op::SpawnEntity {
                id: 2,
                model: "dot".into(),
                pos: [40.0, 9.0, 20.0],
                rot: id,
            },
            Op::SpawnEntity {
                id: 1,
                model: "dot".into(),
                pos: [40.0, 5.0, 20.0],
                rot: id,
            },
        ],
    );
    let grid = DenseGrid::from_world(&w).unwrap();
    // Entities 9 and 2 both begin at x = 40: the lower id wins.
    let ray = Ray::new([0.5, 9.5, 20.5], [1.0, 0.0, 0.0]).unwrap();
    for h in [trace_naadf(&w, &ray), trace_nodf(&w, &ray), grid.trace(&ray)] {
        let h = h.unwrap();
        assert_eq!(
            (h.entity, h.voxel, h.t, h.material),
            (Some(2), [0, 0, 0], 39.5, 2),
            "{h:?}"
        );
    }
    // Entity 1 coincides with a world voxel: the world wins.
    let ray = Ray::new([0.5, 5.5, 20.5], [1.0, 0.0, 0.0]).unwrap();
    for h in [trace_naadf(&w, &ray), trace_nodf(&w, &ray), grid.trace(&ray)] {
        let h = h.unwrap();
        assert_eq!(
            (h.entity, h.voxel, h.t, h.material),
            (None, [40, 5, 20], 39.5, 3),
            "{h:?}"
        );
    }
}

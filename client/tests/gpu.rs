//! The GPU traversal and renderer against the CPU oracles (Mesa lavapipe in CI).
//!
//! - GPU hits for thousands of awkward rays equal the CPU's, with every traversal
//!   variant, on several generated worlds (edges, corners, thin walls, entities at odd
//!   rotations), and the SVO and SVDAG walks equal the CPU's walks of the same trees. A
//!   ray may differ only if it lies within [`TIE_EPS`] of a tie, as shown
//!   by a CPU trace of a nudged copy giving the GPU's answer, and at most 1 ray in 10,000.
//! - The `material` image and the first-hit buffer match the CPU raycast of every pixel.
//! - The pipelines follow whether the world has instances: a world traced without them hits
//!   entities spawned later, and local instances are hit as world entities are.
//! - GpuWorld buffers read back equal the world's after edits, also when split across
//!   bindings, and give the world's digest.

#[path = "../../world/tests/common/mod.rs"]
mod common;

use common::{Raw, Rng, adversarial, random_world, rays};
use naadf_client::Mode;
use naadf_client::gpu::{Gpu, GpuRay, GpuWorld, RayTracer, Renderer, Traversal};
use naadf_world::baselines::{Hybrid, HybridFormat, Svdag, Svo};
use naadf_world::camera::Camera;
use naadf_world::entity::chunk_range;
use naadf_world::entity::local::LocalInstances;
use naadf_world::fingerprint::ChunkChanges;
use naadf_world::material::MaterialKind;
use naadf_world::ops::{Batch, Limits, Op};
use naadf_world::preset::Preset;
use naadf_world::stats::WorldStats;
use naadf_world::traverse::{Hit, Method, Ray, same_result, trace_naadf};
use naadf_world::{World, WorldSize};
use std::sync::OnceLock;

/// How far (in voxels) a ray's origin may be nudged to explain a GPU/CPU difference.
const TIE_EPS: f64 = 1e-4;

/// One device for the whole test binary (lavapipe is slow to start), or `None` with a
/// message when the machine has no Vulkan or GL at all.
fn gpu() -> Option<&'static Gpu> {
    static GPU: OnceLock<Option<Gpu>> = OnceLock::new();
    GPU.get_or_init(|| match Gpu::new() {
        Ok(g) => Some(g),
        Err(e) => {
            eprintln!("skipping GPU tests: {e}");
            None
        }
    })
    .as_ref()
}

/// The ray rounded to what the GPU receives (f32 fraction and direction), so that CPU and
/// GPU trace the very same line. The GPU copy's direction is scaled by a power of two
/// (exact in f32) that varies with `i`: the GPU must not assume unit directions (camera
/// rays are not), and hit distances must come out the same.
fn exact_f32(i: usize, r: &Ray) -> (Ray, GpuRay) {
    let o = r.origin().map(|v| {
        let fl = v.floor();
        fl + f64::from(((v - fl) as f32).min(0.999_999_94))
    });
    let d = r.dir().map(|v| f64::from(v as f32));
    let ray = Ray::new(o, d).expect("valid ray");
    let scale = [1.0, 4.0, 0.125][i % 3];
    (
        ray,
        GpuRay {
            origin: o,
            dir: d.map(|v| v * scale),
        },
    )
}

/// Whether moving the origin of `ray` by at most TIE_EPS along some axis makes the CPU
/// trace `cpu` give the answer `accept` accepts: the ray is within TIE_EPS of a tie.
fn near_tie(cpu: &impl Fn(&Ray) -> Option<Hit>, ray: &Ray, accept: impl Fn(&Option<Hit>) -> bool) -> bool {
    let o = ray.origin();
    (0..3).any(|a| {
        [-TIE_EPS, -TIE_EPS / 10.0, TIE_EPS / 10.0, TIE_EPS].iter().any(|&e| {
            let mut p = o;
            p[a] += e;
            accept(&cpu(&Ray::new(p, ray.dir()).unwrap()))
        })
    })
}

/// A CPU trace: the oracle of one GPU traversal.
type CpuTrace<'a> = dyn Fn(&Ray) -> Option<Hit> + 'a;

/// [`exact_f32`] of each of `rays`: the CPU copies and the GPU copies.
fn exact_rays(rays: &[Ray]) -> (Vec<Ray>, Vec<GpuRay>) {
    rays.iter().enumerate().map(|(i, r)| exact_f32(i, r)).unzip()
}

/// Traces `rays` on the GPU with every traversal and compares with the CPU: the world's
/// methods with `trace_naadf`, the SVO, the SVDAG and the hybrid formats with the CPU walk
/// of the same structure (geometry only); returns (ray traces compared, traces that differed).
fn compare(gpu: &Gpu, world: &World, what: &str, rays: &[Ray]) -> (usize, usize) {
    let (cpu_rays, gpu_rays) = exact_rays(rays);
    let mut gw = GpuWorld::new(gpu, world).expect("upload");
    let mut tracer = RayTracer::new(gpu);
    // A world without solid voxels has no trees (the builds refuse it).
    let trees = Svo::build(world).ok().zip(Svdag::build(world).ok());
    let hybrids: Vec<Hybrid> = trees
        .iter()
        .flat_map(|(_, dag)| HybridFormat::ALL.map(|f| Hybrid::of(dag, f).expect("the test worlds fit in 2048³")))
        .collect();
    let mut compared = 0;
    let mut differed = 0;
    for traversal in Traversal::ALL {
        let cpu: Box<CpuTrace> = match (traversal, &trees) {
            (Traversal::Method(Method::Grid), _) => {
                gw.upload_grid(world).expect("grid");
                Box::new(|r| trace_naadf(world, r))
            }
            (Traversal::Method(_), _) => Box::new(|r| trace_naadf(world, r)),
            (Traversal::Svo, Some((svo, _))) => {
                gw.upload_svo(svo).expect("svo upload");
                Box::new(|r| svo.trace(r))
            }
            (Traversal::Svdag, Some((_, dag))) => {
                gw.upload_svdag(dag).expect("svdag upload");
                Box::new(|r| dag.trace(r))
            }
            (Traversal::Hybrid(f), Some(_)) => {
                let h = hybrids
                    .iter()
                    .find(|h| h.format() == Some(f))
                    .expect("both formats built");
                gw.upload_hybrid(h).expect("hybrid upload");
                // Each format's traversal walks its own upload only.
                let other = HybridFormat::ALL.into_iter().find(|&o| o != f).unwrap();
                assert!(
                    tracer
                        .trace(gpu, &gw, &gpu_rays[..1], Traversal::Hybrid(other))
                        .is_err()
                );
                Box::new(|r| h.trace(r))
            }
            (_, None) => {
                assert_eq!(
                    WorldStats::of(world).solid_voxels,
                    0,
                    "{what}: the trees failed to build"
                );
                continue;
            }
        };
        compared += rays.len();
        let got = tracer.trace(gpu, &gw, &gpu_rays, traversal).expect("trace");
        for (i, g) in got.iter().enumerate() {
            assert!(!g.exhausted, "{what}/{}: ray {i} ran out of steps", traversal.name());
            let expected = cpu(&cpu_rays[i]);
            if same_result(&expected, &g.hit) {
                continue;
            }
            assert!(
                near_tie(&cpu, &cpu_rays[i], |h| same_result(h, &g.hit)),
                "{what}/{}: ray {:?} dir {:?}: CPU {:?}, GPU {:?}, and no nudge within {TIE_EPS} explains it",
                traversal.name(),
                cpu_rays[i].origin(),
                cpu_rays[i].dir(),
                expected,
                g.hit
            );
            differed += 1;
        }
    }
    (compared, differed)
}

fn size(x: u32, y: u32, z: u32) -> WorldSize {
    WorldSize::new(x, y, z).unwrap()
}

/// A random world with a model spawned as entities at odd rotations.
fn entity_world(seed: u64) -> World {
    let mut w = random_world(size(64, 64, 64), seed).build();
    w.apply(&Batch { ops: entity_ops(seed) }, &Limits::default())
        .expect("entities");
    w
}

/// A model, "crate", spawned as 24 entities at random positions and odd rotations.
fn entity_ops(seed: u64) -> Vec<Op> {
    let mut rng = Rng(seed ^ 0x5EED);
    let mut voxels = Vec::new();
    for z in 0..7i64 {
        for y in 0..5i64 {
            for x in 0..9i64 {
                if (x + y + z) % 3 != 0 || x == 0 || y == 4 {
                    voxels.push([x, y, z, 1 + (x + z) % 9]);
                }
            }
        }
    }
    let mut ops = vec![Op::DefineModel {
        name: "crate".into(),
        size: [9, 5, 7],
        voxels,
    }];
    for id in 0..24 {
        ops.push(Op::SpawnEntity {
            id: id * 7 + 2,
            model: "crate".into(),
            pos: [0, 1, 2].map(|_| 4.0 + rng.unit() * 52.0),
            rot: [0, 1, 2, 3].map(|_| rng.unit() * 2.0 - 1.0),
        });
    }
    ops
}

/// The "crate" model of [`entity_ops`] spawned 28 times along the x axis, two voxels apart
/// (so the boxes overlap), above a random floor, with rays along the row from both ends and
/// slightly across it: each crosses more instance boxes than the GPU walk gathers before it
/// tests them (`INSTANCE_BATCH` in `shaders/trace.wgsl`).
fn entity_row() -> (World, Vec<Ray>) {
    let mut w = random_world(size(64, 64, 64), 5).build();
    let mut ops = entity_ops(0);
    ops.truncate(1);
    let mut rng = Rng(0x520);
    for i in 0..28u32 {
        ops.push(Op::SpawnEntity {
            id: 100 + i,
            model: "crate".into(),
            pos: [2.0 + 2.0 * f64::from(i), 40.0, 30.0],
            rot: [0, 1, 2, 3].map(|_| rng.unit() * 0.2 - 0.1).map(|v| v + 0.5),
        });
    }
    w.apply(&Batch { ops }, &Limits::default()).expect("entities");
    let mut rays = Vec::new();
    for k in 0..400 {
        let at = [40.5 + rng.unit() * 6.0, 30.5 + rng.unit() * 6.0];
        let across = [rng.unit() - 0.5, rng.unit() - 0.5].map(|v| v * 0.05);
        let (x, dx) = if k % 2 == 0 { (0.25, 1.0) } else { (63.75, -1.0) };
        rays.push(Ray::new([x, at[0], at[1]], [dx, across[0], across[1]]).expect("a ray"));
    }
    (w, rays)
}

#[test]
fn gpu_hits_equal_the_cpu_for_every_method() {
    let Some(gpu) = gpu() else { return };
    let mut worlds: Vec<(String, World)> = Vec::new();
    for seed in 0..3u64 {
        let s = [size(64, 64, 64), size(128, 64, 64), size(64, 128, 64)][seed as usize];
        worlds.push((format!("random {seed}"), random_world(s, seed + 11).build()));
    }
    for (name, raw) in adversarial(size(64, 64, 64)) {
        worlds.push((name.to_owned(), raw.build()));
    }
    for seed in 0..2 {
        worlds.push((format!("entities {seed}"), entity_world(seed)));
    }
    // Long enough for several raw cells of R(4³)G(7) (128 voxels a side), the middle two
    // empty: the hybrid walks skip whole raw cells and enter the next one's DAG.
    let mut long = Raw::empty(size(512, 64, 64), 3);
    for p in long.coords().collect::<Vec<_>>() {
        let tip = p[0] < 40 || p[0] >= 400;
        if tip && (p[0] * 7 + p[1] * 5 + p[2] * 3) % 13 < 2 {
            long.set(p, 1 + (p[1] % 3) as u16);
        }
    }
    worlds.push(("long".to_owned(), long.build()));
    let mut rng = Rng(7);
    let (mut total, mut differed) = (0, 0);
    for (name, world) in &worlds {
        let rays = rays(world.size().voxels(), &mut rng, 3000);
        let (n, d) = compare(gpu, world, name, &rays);
        total += n;
        differed += d;
    }
    let (row, row_rays) = entity_row();
    let entity_hits = row_rays
        .iter()
        .filter(|r| trace_naadf(&row, r).is_some_and(|h| h.entity.is_some()))
        .count();
    assert!(
        entity_hits * 2 > row_rays.len(),
        "{entity_hits} of the row's rays hit an entity"
    );
    let (n, d) = compare(gpu, &row, "entity row", &row_rays);
    total += n;
    differed += d;
    eprintln!("GPU vs CPU: {differed} of {total} ray traces differed (each within {TIE_EPS} of a tie)");
    assert!(
        differed * 10_000 <= total,
        "{differed} of {total} rays differ: more than 1 in 10,000"
    );
}

/// The sRGB encoding of a linear value, as an 8-bit channel (the oracle of `material`).
fn srgb8(c: f32) -> u8 {
    let c = f64::from(c.clamp(0.0, 1.0));
    let s = if c <= 0.0031308 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5).floor() as u8
}

/// What a `material` pixel and its first-hit record should hold for a CPU result: the
/// colour, the primary hit plane (docs/NAADF.md §10) and the entity id.
fn expected_pixel(world: &World, cpu: &Option<Hit>) -> ([u8; 4], u32, u32) {
    let Some(hit) = cpu else {
        return ([0, 0, 0, 255], 0x1FFFF, 0x3FFF);
    };
    let m = world.materials().get(hit.material).unwrap();
    let rgba = [srgb8(m.albedo[0]), srgb8(m.albedo[1]), srgb8(m.albedo[2]), 255];
    let plane = match hit.normal.iter().position(|&n| n != 0) {
        Some(a) => {
            let pos = hit.normal[a] > 0;
            let id = 2 * a as u32 + if pos { 2 } else { 1 };
            id | ((hit.voxel[a] + u32::from(pos)) & 0x3FFF) << 3
        }
        None => 7,
    };
    (rgba, plane, hit.entity.unwrap_or(0x3FFF))
}

#[test]
fn material_frames_match_the_cpu_raycast_of_every_pixel() {
    let Some(gpu) = gpu() else { return };
    let world = entity_world(5);
    let gw = GpuWorld::new(gpu, &world).unwrap();
    let mut renderer = Renderer::new(gpu);
    let cams = [
        r#"{"pos":[-20.5,80.25,-30.5],"yaw":40,"pitch":-30}"#,
        r#"{"pos":[32.1,20.3,32.7],"yaw":-135,"pitch":10,"fov_y":70}"#,
        r#"{"pos":[70.0,10.0,5.0],"yaw":-60,"pitch":5}"#,
    ];
    let (w, h) = (96, 64);
    let (mut total, mut differed, mut distances) = (0, 0, 0);
    for cam in cams {
        let camera = Camera::from_json(cam).unwrap();
        let basis = camera.basis();
        let frame = renderer
            .render(gpu, &gw, &camera, (w, h), Mode::Material, true)
            .unwrap();
        let gb = frame.gbuffer.as_ref().unwrap();
        for py in 0..h {
            for px in 0..w {
                let i = (px + py * w) as usize;
                let got = (&frame.rgba[4 * i..4 * i + 4], gb[i][0] >> 15, gb[i][0] & 0x3FFF);
                let matches = |cpu: &Option<Hit>| {
                    let (rgba, plane, entity) = expected_pixel(&world, cpu);
                    got.0.iter().zip(&rgba).all(|(a, b)| a.abs_diff(*b) <= 1) && got.1 == plane && got.2 == entity
                };
                let ray = camera.ray(&basis, px, py, w, h).unwrap();
                let cpu = trace_naadf(&world, &ray);
                total += 1;
                if matches(&cpu) {
                    // The record's distance (f16, along the unit direction; camera
                    // directions are not unit) is the CPU's, unless a mirror extended it.
                    if let Some(hit) =
                        cpu.filter(|h| world.materials().get(h.material).unwrap().kind != MaterialKind::Mirror)
                    {
                        let d = f64::from(half::f16::from_bits((gb[i][3] & 0x7FFF) as u16).to_f32());
                        assert!(
                            (d - hit.t).abs() <= 2e-3 * hit.t + 1e-3,
                            "{cam} pixel ({px},{py}): distance {d}, CPU {}",
                            hit.t
                        );
                        distances += 1;
                    }
                    continue;
                }
                // Only a pixel whose ray lies within a hair of a tie may differ.
                assert!(
                    near_tie(&|r: &Ray| trace_naadf(&world, r), &ray, matches),
                    "{cam} pixel ({px},{py}): GPU {got:?}, CPU {:?}",
                    expected_pixel(&world, &cpu)
                );
                differed += 1;
            }
        }
    }
    eprintln!("material frames: {differed} of {total} pixels differ from the CPU (each within {TIE_EPS} of a tie)");
    assert!(distances > total / 4, "only {distances} hit distances checked");
    assert!(differed <= 1 + total / 10_000, "{differed} of {total} pixels differ");
}

/// Asserts that the device copy holds `world`'s buffers byte for byte and gives its digest.
fn assert_mirrors(gpu: &Gpu, gw: &GpuWorld, world: &World, what: &str) {
    assert_eq!(gw.first_difference(gpu, world).unwrap(), None, "{what}");
    assert_eq!(gw.digest(gpu, world).unwrap(), world.digest(), "{what}");
}

#[test]
fn synced_buffers_equal_the_worlds_after_edits_also_when_split() {
    let Some(gpu) = gpu() else { return };
    let src = Preset::Test.source(Some(size(256, 64, 256)), 3).unwrap();
    let mut world = World::build(&*src, &|_| {}).unwrap();
    // Parts of one 64 KiB page force the larger buffers across several bindings.
    let mut split = GpuWorld::with_part_words(gpu, &world, 16 * 1024).unwrap();
    let mut whole = GpuWorld::new(gpu, &world).unwrap();
    let mut rng = Rng(99);
    for step in 0..12 {
        let c = [0, 1, 2].map(|a| rng.below([256, 64, 256][a]) as i64);
        let op = match step % 3 {
            0 => Op::Sphere {
                center: c.map(|v| v as f64),
                radius: 3.0 + rng.unit() * 12.0,
                material: rng.below(9) as u16,
            },
            1 => Op::Box {
                min: c,
                max: c.map(|v| v + 1 + rng.below(20) as i64),
                material: 1 + rng.below(8) as u16,
            },
            _ => Op::Set {
                voxels: vec![[c[0], c[1], c[2], rng.below(9) as i64]],
            },
        };
        world.apply(&Batch { ops: vec![op] }, &Limits::default()).unwrap();
        while !world.is_quiescent() {
            world.grow_distance_fields(1 << 20);
        }
        split.sync(&world).unwrap();
        whole.sync(&world).unwrap();
        assert_mirrors(gpu, &split, &world, &format!("split copy, step {step}"));
        assert_mirrors(gpu, &whole, &world, &format!("whole copy, step {step}"));
    }
    assert!(
        split.split().parts.iter().any(|&p| p > 1),
        "the test must split a buffer"
    );
    // Both copies trace alike.
    let mut tracer = RayTracer::new(gpu);
    let rays = exact_rays(&rays(world.size().voxels(), &mut rng, 500)).1;
    let a = tracer.trace(gpu, &split, &rays, Method::Naadf).unwrap();
    let b = tracer.trace(gpu, &whole, &rays, Method::Naadf).unwrap();
    assert_eq!(a, b);
}

/// Two copies never share a generation: a renderer that kept the generation of one (a GI
/// history, an irradiance cache, ROMA's maps) and is then shown the other learns that
/// everything changed, whichever copy was made first.
#[test]
fn another_copys_generation_reads_as_everything_changed() {
    let Some(gpu) = gpu() else { return };
    let src = Preset::Test.source(Some(size(64, 64, 64)), 3).unwrap();
    let world = World::build(&*src, &|_| {}).unwrap();
    let first = GpuWorld::new(gpu, &world).unwrap();
    let second = GpuWorld::new(gpu, &world).unwrap();
    assert_ne!(first.generation(), second.generation());
    assert_eq!(second.changes_since(first.generation()), ChunkChanges::Everything);
    assert_eq!(first.changes_since(second.generation()), ChunkChanges::Everything);
    assert_eq!(
        first.changes_since(first.generation()),
        ChunkChanges::Chunks(Vec::new())
    );
}

#[test]
fn a_synced_copy_logs_which_chunks_each_sync_changed() {
    let Some(gpu) = gpu() else { return };
    let src = Preset::Test.source(Some(size(256, 64, 256)), 3).unwrap();
    let mut world = World::build(&*src, &|_| {}).unwrap();
    let mut gw = GpuWorld::new(gpu, &world).unwrap();
    let start = gw.generation();
    assert_eq!(gw.changes_since(start), ChunkChanges::Chunks(Vec::new()));
    let mut rng = Rng(5);
    let mut expected = Vec::new();
    let mut after_first = start;
    for step in 0..4 {
        // One voxel per sync, set to a material it does not have.
        let p = [0, 1, 2].map(|a| rng.below([256, 64, 256][a]) as u32);
        let m = world.material_at(p) % 9 + 1;
        let op = Op::Set {
            voxels: vec![[p[0], p[1], p[2], u32::from(m)].map(i64::from)],
        };
        world.apply(&Batch { ops: vec![op] }, &Limits::default()).unwrap();
        // Distance fields grow over later syncs; they change nothing a ray sees.
        gw.sync(&world).unwrap();
        while !world.is_quiescent() {
            world.grow_distance_fields(1 << 20);
            gw.sync(&world).unwrap();
        }
        expected.push(world.size().chunk_index(p.map(|v| v / 16)) as u32);
        if step == 0 {
            after_first = gw.generation();
        }
    }
    let mut all = expected.clone();
    all.sort_unstable();
    all.dedup();
    assert_eq!(gw.changes_since(start), ChunkChanges::Chunks(all));
    let mut later = expected[1..].to_vec();
    later.sort_unstable();
    later.dedup();
    assert_eq!(gw.changes_since(after_first), ChunkChanges::Chunks(later));
    assert_eq!(gw.changes_since(gw.generation()), ChunkChanges::Chunks(Vec::new()));
    // A material changes the light of every chunk.
    let recolour = Op::DefineMaterial {
        id: 1,
        kind: MaterialKind::Diffuse,
        albedo: [0.1, 0.2, 0.3],
        emission: 0.0,
        roughness: 0.0,
    };
    let before = gw.generation();
    world.apply(&Batch { ops: vec![recolour] }, &Limits::default()).unwrap();
    gw.sync(&world).unwrap();
    assert_eq!(gw.changes_since(before), ChunkChanges::Everything);
    assert_eq!(gw.changes_since(start), ChunkChanges::Everything);
}

/// Traces `rays` (their CPU and GPU copies) on `gw` and asserts that each GPU hit equals
/// `truth`'s CPU trace (entity ids dropped unless `ids`) or lies within a tie of it; returns
/// how many of the CPU hits were on an entity.
fn assert_hits(
    gpu: &Gpu,
    tracer: &mut RayTracer,
    gw: &GpuWorld,
    truth: &World,
    rays: &(Vec<Ray>, Vec<GpuRay>),
    ids: bool,
    what: &str,
) -> usize {
    let cpu = |r: &Ray| trace_naadf(truth, r).map(|h| if ids { h } else { Hit { entity: None, ..h } });
    let got = tracer.trace(gpu, gw, &rays.1, Method::Naadf).unwrap();
    let mut on_entities = 0;
    for (i, (g, r)) in got.iter().zip(&rays.0).enumerate() {
        on_entities += usize::from(trace_naadf(truth, r).is_some_and(|h| h.entity.is_some()));
        let expected = cpu(r);
        assert!(
            same_result(&expected, &g.hit) || near_tie(&cpu, r, |h| same_result(h, &g.hit)),
            "{what}: ray {i}: CPU {expected:?}, GPU {:?}",
            g.hit
        );
    }
    on_entities
}

/// The device world's pipelines follow whether it has instances (shaders/trace.wgsl's
/// `HAS_INSTANCES`): entities spawned into a world traced without them are hit from the next
/// sync on, by the same tracer, and once they are despawned the world's hits come back. The
/// same holds on a device that builds each pipeline's other variant in the background (as
/// the viewer and render nodes do), whose switches take those builds.
#[test]
fn the_instance_walk_follows_the_worlds_instances() {
    let Some(gpu) = gpu() else { return };
    instance_walk_follows_the_instances(gpu);
    let background = Gpu::new().expect("a second device");
    background.prepare_instance_variants();
    instance_walk_follows_the_instances(&background);
}

fn instance_walk_follows_the_instances(gpu: &Gpu) {
    let mut world = random_world(size(64, 64, 64), 31).build();
    let mut gw = GpuWorld::new(gpu, &world).unwrap();
    let mut tracer = RayTracer::new(gpu);
    let rays = exact_rays(&rays(world.size().voxels(), &mut Rng(9), 3000));
    assert_eq!(
        assert_hits(gpu, &mut tracer, &gw, &world, &rays, true, "no entities"),
        0
    );
    let ops = entity_ops(31);
    let ids: Vec<u32> = ops
        .iter()
        .filter_map(|op| match op {
            Op::SpawnEntity { id, .. } => Some(*id),
            _ => None,
        })
        .collect();
    world.apply(&Batch { ops }, &Limits::default()).unwrap();
    gw.sync(&world).unwrap();
    assert!(
        assert_hits(gpu, &mut tracer, &gw, &world, &rays, true, "entities") > 100,
        "too few rays meet the entities to tell"
    );
    let despawn = ids.into_iter().map(|id| Op::DespawnEntity { id }).collect();
    world.apply(&Batch { ops: despawn }, &Limits::default()).unwrap();
    gw.sync(&world).unwrap();
    assert_eq!(assert_hits(gpu, &mut tracer, &gw, &world, &rays, true, "despawned"), 0);
}

/// Local instances (previews, markers) are hit exactly where the same model spawned as
/// world entities is, only without an entity id, also after the world's own instance and
/// type buffers grow under them; the mirrored buffers and the digest stay the world's; a
/// moved local marks its chunks for the light history; and without them the world's hits
/// come back.
#[test]
fn local_instances_are_hit_as_entities_are_but_stay_out_of_the_mirror() {
    let Some(gpu) = gpu() else { return };
    let mut world = random_world(size(64, 64, 64), 21).build();
    let mut oracle = world.clone();
    oracle
        .apply(&Batch { ops: entity_ops(21) }, &Limits::default())
        .unwrap();
    let mut locals = LocalInstances::default();
    let model = oracle.models().get("crate").unwrap().clone();
    locals.define_model("crate", model, world.materials()).unwrap();
    for (&id, pose) in &oracle.entity_table().instances {
        locals.place(id, "crate", pose.pos, pose.rot).unwrap();
    }
    let mut gw = GpuWorld::new(gpu, &world).unwrap();
    gw.set_locals(&locals);
    gw.sync(&world).unwrap();
    let mut tracer = RayTracer::new(gpu);
    let mut rng = Rng(3);
    let rays = exact_rays(&rays(world.size().voxels(), &mut rng, 3000));
    // Local instances carry no entity id.
    let mut check =
        |gw: &GpuWorld, truth: &World, what: &str| assert_hits(gpu, &mut tracer, gw, truth, &rays, false, what);
    assert!(
        check(&gw, &oracle, "locals") > 100,
        "too few rays meet the instances to tell"
    );
    assert_mirrors(gpu, &gw, &world, "with locals");
    assert_eq!(gw.digest(gpu, &world).unwrap(), world.digest());
    // The world's entity types and records grow under the locals, which move after them.
    let far = vec![
        Op::DefineModel {
            name: "post".into(),
            size: [1, 3, 1],
            voxels: (0..3).map(|y| [0, y, 0, 2]).collect(),
        },
        Op::SpawnEntity {
            id: 9000,
            model: "post".into(),
            pos: [1.5, 60.0, 1.5],
            rot: [0.0, 0.0, 0.0, 1.0],
        },
    ];
    for w in [&mut world, &mut oracle] {
        w.apply(&Batch { ops: far.clone() }, &Limits::default()).unwrap();
    }
    gw.sync(&world).unwrap();
    check(&gw, &oracle, "locals after the world's entities grew");
    assert_mirrors(gpu, &gw, &world, "with locals, grown");
    assert_eq!(gw.digest(gpu, &world).unwrap(), world.digest());
    // A moved local marks the chunks under its old and its new box.
    let before = gw.generation();
    let (&key, pose) = oracle.entity_table().instances.iter().next().unwrap();
    let (from, to, rot) = (pose.pos, [40.0, 40.0, 40.0], pose.rot);
    locals.place(key, "crate", to, rot).unwrap();
    gw.set_locals(&locals);
    gw.sync(&world).unwrap();
    let ChunkChanges::Chunks(changed) = gw.changes_since(before) else {
        panic!("a local move changes a few chunks, not everything")
    };
    for pos in [from, to] {
        let (lo, hi) = chunk_range(world.size(), [9, 5, 7], pos, rot).unwrap();
        for c in [lo, hi] {
            assert!(
                changed.contains(&(world.size().chunk_index(c) as u32)),
                "{pos:?}: {changed:?}"
            );
        }
    }
    // Without locals, the world's own hits.
    gw.set_locals(&LocalInstances::default());
    gw.sync(&world).unwrap();
    check(&gw, &world, "no locals");
}

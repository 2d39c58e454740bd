//! `--mode roma` against analytic answers and against itself (docs/RENDERING.md §3d).
//!
//! - An open floor's AO is 1, and under a uniform sky of radiance 1 it has radiance equal
//!   to its albedo.
//! - A floor point under a square roof of half-width a, h above the ray's origin, has the
//!   cosine-weighted occluded fraction F = (4/π)·s·atan(s), s = X/√(1+X²), X = a/h: its
//!   AO is 1 − F within 4 standard errors plus 0.01 (the roof's edge, sampled at rotated
//!   cell centres, moves by up to half a voxel).
//! - The sun's map casts the shadow a pillar casts.
//! - The same seed gives the same image.
//! - With a device: the GPU's first frame agrees with the CPU's pixel for pixel (the same
//!   random streams; a pixel may differ where f32 and f64 round a walk differently), and
//!   maps updated after an edit and a camera move equal maps built from scratch, bit for
//!   bit in the image, while writing only the tiles that changed.

mod scenes;

use naadf_client::gpu::{GpuWorld, Roma, Shot, Temporal};
use naadf_client::light::cpu::CpuPathTracer;
use naadf_client::light::roma::{CpuRoma, ORIGIN_OFFSET, RomaOptions};
use naadf_client::light::{Light, Sky, Sun};
use naadf_world::World;
use naadf_world::camera::Camera;
use scenes::{COURTYARD_CAMERA, FLOOR, GREY, apply, assert_gpu_matches_cpu, camera, courtyard, gpu, world, world_of};

/// The CPU's ROMA image of `world`: one sample per pixel per frame, `frames` frames averaged.
fn render(
    world: &World,
    cam: &Camera,
    size: (u32, u32),
    light: Light,
    options: RomaOptions,
    frames: u32,
) -> Vec<[f64; 3]> {
    let roma = CpuRoma::new(world, options, light, cam.pos).expect("ROMA maps");
    let tracer = CpuPathTracer::new(world, light, 7).with_tier(&roma);
    let mut out = Vec::new();
    for py in 0..size.1 {
        for px in 0..size.0 {
            out.push(tracer.estimate(cam, (px, py), size, 0..frames).mean);
        }
    }
    out
}

fn uniform(l: f32) -> Light {
    Light::new(Sky::Uniform([l; 3]), None, 3).unwrap()
}

#[test]
fn an_open_floor_sees_the_whole_sky() {
    let w = world(&[GREY, FLOOR]);
    let roma = CpuRoma::new(&w, RomaOptions::default(), uniform(1.0), [32.0, 30.0, 32.0]).unwrap();
    for p in [[32.0, 8.0, 32.0], [5.5, 8.0, 60.25], [63.0, 8.0, 1.0]] {
        assert_eq!(roma.ambient_occlusion(p, [0.0, 1.0, 0.0], 2000, 1), 1.0, "AO at {p:?}");
    }
    let cam = camera(r#"{"pos":[32,30,32],"yaw":0,"pitch":-89.9,"fov_y":60}"#);
    for px in render(&w, &cam, (12, 9), uniform(1.0), RomaOptions::default(), 4) {
        for c in px {
            assert!((c - 0.5).abs() < 1e-6, "floor radiance {c}, albedo 0.5");
        }
    }
}

/// The occluded fraction of a floor point under the centre of a square roof of half-width
/// `a`, `h` above it.
fn roof_fraction(a: f64, h: f64) -> f64 {
    let x = a / h;
    let s = x / (1.0 + x * x).sqrt();
    4.0 / std::f64::consts::PI * s * s.atan()
}

#[test]
fn a_point_under_a_square_roof_has_the_analytic_ao() {
    let (a, top) = (20, 28);
    let roof = format!(
        r#"{{"op":"box","min":[{},{top},{}],"max":[{},{},{}],"material":1}}"#,
        64 - a,
        64 - a,
        64 + a,
        top + 2,
        64 + a
    );
    let floor = r#"{"op":"box","min":[0,0,0],"max":[128,8,128],"material":1}"#;
    let w = world_of([128, 64, 128], &[GREY, floor, &roof]);
    let samples = 20_000;
    for directions in [4, 16] {
        let options = RomaOptions {
            directions,
            ao_range: 100.0,
        };
        let roma = CpuRoma::new(&w, options, uniform(1.0), [64.0, 20.0, 64.0]).unwrap();
        let ao = roma.ambient_occlusion([64.0, 8.0, 64.0], [0.0, 1.0, 0.0], samples, 3);
        // The ray starts one voxel off the floor.
        let h = f64::from(top - 8) - ORIGIN_OFFSET[0];
        let expected = 1.0 - roof_fraction(f64::from(a), h);
        let se = (ao * (1.0 - ao) / f64::from(samples)).sqrt();
        assert!(
            (ao - expected).abs() <= 4.0 * se + 0.01,
            "{directions} directions: AO {ao}, analytic {expected} (SE {se})"
        );
    }
    // A range short of the roof sees no roof.
    let short = RomaOptions {
        directions: 16,
        ao_range: 15.0,
    };
    let roma = CpuRoma::new(&w, short, uniform(1.0), [64.0, 20.0, 64.0]).unwrap();
    assert_eq!(roma.ambient_occlusion([64.0, 8.0, 64.0], [0.0, 1.0, 0.0], 2000, 3), 1.0);
}

#[test]
fn the_suns_map_casts_a_pillars_shadow() {
    let pillar = r#"{"op":"box","min":[30,8,30],"max":[34,40,34],"material":1}"#;
    let w = world(&[GREY, FLOOR, pillar]);
    // The sun from +X at 45°: the pillar's shadow falls toward −X.
    let sun = Sun::parse("90,45,2").unwrap();
    let light = Light::new(Sky::Uniform([0.0; 3]), Some(sun), 3).unwrap();
    let roma = CpuRoma::new(&w, RomaOptions::default(), light, [32.0, 30.0, 32.0]).unwrap();
    let tracer = CpuPathTracer::new(&w, light, 0).with_tier(&roma);
    let cam = camera(r#"{"pos":[20,60,32],"yaw":0,"pitch":-89.9,"fov_y":1}"#);
    let shade = tracer.estimate(&cam, (0, 0), (1, 1), 0..16).mean[0];
    assert_eq!(shade, 0.0, "the floor at x = 20 lies in the pillar's shadow");
    let lit_cam = camera(r#"{"pos":[50,60,32],"yaw":0,"pitch":-89.9,"fov_y":1}"#);
    let lit = tracer.estimate(&lit_cam, (0, 0), (1, 1), 0..16).mean[0];
    let expected = 0.5 / std::f64::consts::PI * 2.0 * 45f64.to_radians().sin();
    assert!(
        (lit - expected).abs() < 1e-3 * expected,
        "sunlit floor {lit}, expected {expected}"
    );
}

#[test]
fn the_same_seed_gives_the_same_image() {
    let pillar = r#"{"op":"box","min":[30,8,30],"max":[34,40,34],"material":1}"#;
    let w = world(&[GREY, FLOOR, pillar]);
    let cam = camera(r#"{"pos":[10,30,10],"yaw":225,"pitch":-30,"fov_y":60}"#);
    let light = Light::new(Sky::Physical, None, 3).unwrap();
    let a = render(&w, &cam, (8, 6), light, RomaOptions::default(), 2);
    let b = render(&w, &cam, (8, 6), light, RomaOptions::default(), 2);
    assert_eq!(a, b);
    assert!(a.iter().any(|p| p[0] > 0.0));
}

/// The first ROMA frame of `shot` of `gw` (a fresh history), with `roma`'s maps as they are.
fn first_frame(roma: &mut Roma, gw: &GpuWorld, shot: &Shot) -> Vec<[f32; 3]> {
    let gpu = gpu().expect("device");
    roma.swap_history(&mut None);
    roma.frame(gpu, gw, shot).expect("roma frame");
    roma.radiance(gpu).expect("radiance").rgb
}

#[test]
fn the_gpu_agrees_with_the_cpu() {
    let Some(gpu) = gpu() else { return };
    let w = courtyard(&[]);
    let cam = camera(COURTYARD_CAMERA);
    let size = (48, 36);
    let light = Light::new(Sky::Physical, Some(Sun::parse("120,40,3").unwrap()), 3).unwrap();
    let options = RomaOptions::default();
    let gw = GpuWorld::new(gpu, &w).unwrap();
    let mut roma = Roma::new(gpu);
    roma.set_options(options);
    let img = first_frame(&mut roma, &gw, &Shot::new(cam, size, light, 5));
    let cpu_roma = CpuRoma::new(&w, options, light, cam.pos).unwrap();
    let tracer = CpuPathTracer::new(&w, light, 5).with_tier(&cpu_roma);
    let pixels = (0..size.0 * size.1).map(|i| {
        let c = tracer.sample(&cam, (i % size.0, i / size.0), size, 0);
        (img[i as usize], c.to_array())
    });
    assert_gpu_matches_cpu(pixels, "pixels");
}

#[test]
fn updated_maps_equal_maps_built_afresh() {
    let Some(gpu) = gpu() else { return };
    let mut w = courtyard(&[]);
    let light = Light::new(Sky::Physical, None, 3).unwrap();
    let cam = camera(COURTYARD_CAMERA);
    let shot = Shot::new(cam, (32, 24), light, 1);
    let mut gw = GpuWorld::new(gpu, &w).unwrap();
    let mut kept = Roma::new(gpu);
    kept.set_options(RomaOptions {
        directions: 4,
        ao_range: 24.0,
    });
    first_frame(&mut kept, &gw, &shot);
    let all = kept.tiles_written();
    // Nothing changed: nothing is written.
    first_frame(&mut kept, &gw, &shot);
    assert_eq!(kept.tiles_written(), 0);
    // An edit under the roof, then a camera 40 voxels on (a level-0 window moves).
    apply(
        &mut w,
        &[r#"{"op":"box","min":[30,8,30],"max":[36,16,36],"material":1}"#],
    );
    gw.sync(&w).unwrap();
    let moved = Shot::new(
        camera(r#"{"pos":[72,30,2],"yaw":0,"pitch":-25,"fov_y":70}"#),
        (32, 24),
        light,
        1,
    );
    for shot in [shot, moved] {
        let updated = first_frame(&mut kept, &gw, &shot);
        assert!(
            kept.tiles_written() < all / 4,
            "{} of {all} tiles rewritten",
            kept.tiles_written()
        );
        let mut fresh = Roma::new(gpu);
        fresh.set_options(RomaOptions {
            directions: 4,
            ao_range: 24.0,
        });
        assert_eq!(updated, first_frame(&mut fresh, &gw, &shot));
    }
}

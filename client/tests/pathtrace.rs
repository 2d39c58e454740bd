//! The path tracers against analytic answers, against each other, and against themselves.
//!
//! - Scenes with a closed-form radiance (docs/RENDERING.md §3a): a diffuse floor under
//!   a uniform sky (a·L), the same floor lit only by the sun (a·E·sin(EL)/π, and 0 in the
//!   shadow of a black pillar, part of the world or an entity), a closed box of emissive walls (a·e·(1 − a^(B+1))/(1 − a)).
//!   Means over pixels are compared as |Δ| ≤ 4·SE + 1e-4·expected. Each scene runs on the
//!   CPU path tracer, and on the GPU when there is one.
//! - The GPU mean of single pixels of a scene with every material kind and the physical
//!   sky falls within the CPU estimate's confidence interval.
//! - Same seed, same bytes; sums added in several steps equal one step; an edit restarts
//!   the sums.

mod scenes;

use naadf_client::gpu::{Baseline, GpuWorld, PathTracer, Shot, Temporal};
use naadf_client::light::cpu::CpuPathTracer;
use naadf_client::light::hdr::Radiance;
use naadf_client::light::{Light, Sky, Sun};
use naadf_world::World;
use naadf_world::camera::Camera;
use naadf_world::ops::{Batch, Limits};
use naadf_world::traverse::trace_naadf;
use scenes::{FLOOR, GREY, SHOWCASE_CAMERA, camera, gpu, mse, showcase, world};

/// The frame of `light` at `size` and `spp`: the GPU's, and the CPU's (per pixel, the mean
/// of the same samples).
fn render(world: &World, cam: &Camera, size: (u32, u32), light: Light, spp: u32) -> Vec<(&'static str, Radiance)> {
    let cpu = CpuPathTracer::new(world, light, 0);
    let mut rgb = Vec::new();
    for py in 0..size.1 {
        for px in 0..size.0 {
            rgb.push(cpu.estimate(cam, (px, py), size, 0..spp).mean.map(|c| c as f32));
        }
    }
    let mut out = vec![(
        "CPU",
        Radiance {
            width: size.0,
            height: size.1,
            rgb,
        },
    )];
    if let Some(gpu) = gpu() {
        let gw = GpuWorld::new(gpu, world).expect("upload");
        let mut pt = PathTracer::new(gpu);
        let img = pt
            .render(gpu, &gw, &Shot::new(*cam, size, light, 0), spp, &mut |_| {})
            .expect("path trace");
        out.push(("GPU", img));
    }
    out
}

/// Asserts `|mean − expected| ≤ 4·SE + 1e-4·expected` on every channel.
fn assert_mean(what: &str, (mean, se): ([f64; 3], f64), expected: [f64; 3]) {
    for c in 0..3 {
        let tol = 4.0 * se + 1e-4 * expected[c].abs();
        assert!(
            (mean[c] - expected[c]).abs() <= tol.max(1e-6),
            "{what}: channel {c} mean {} expected {} (SE {se})",
            mean[c],
            expected[c]
        );
    }
}

#[test]
fn a_floor_under_a_uniform_sky_has_radiance_albedo_times_sky() {
    let w = world(&[GREY, FLOOR]);
    let cam = camera(r#"{"pos":[32,40,32],"yaw":0,"pitch":-89.9,"fov_y":60}"#);
    for bounces in [0, 1, 8] {
        let light = Light::new(Sky::parse("uniform:2").unwrap(), None, bounces).unwrap();
        let expected = if bounces == 0 { 0.0 } else { 0.5 * 2.0 };
        for (who, img) in render(&w, &cam, (16, 12), light, 4) {
            let m = img.mean_where(|_, _| true).unwrap();
            assert_mean(&format!("{who}, {bounces} bounces"), m, [expected; 3]);
        }
    }
}

#[test]
fn a_floor_lit_by_the_sun_has_the_cosine_law_radiance_and_a_black_shadow() {
    // The pillar that casts the shadow is part of the world, then an entity in the same
    // place (whose shadow rays leave the world and meet it on the instance walk).
    let voxels: Vec<String> = (0..8 * 32 * 8)
        .map(|i| format!("[{},{},{},2]", i % 8, i / 8 % 32, i / 256))
        .collect();
    let model = format!(
        r#"{{"op":"define_model","name":"pillar","size":[8,32,8],"voxels":[{}]}}"#,
        voxels.join(",")
    );
    let spawn = r#"{"op":"spawn_entity","id":1,"model":"pillar","pos":[28,8,28],"rot":[0,0,0,1]}"#;
    let pillar = r#"{"op":"box","min":[28,8,28],"max":[36,40,36],"material":2}"#;
    for caster in [vec![pillar], vec![model.as_str(), spawn]] {
        let mut ops = vec![
            GREY,
            r#"{"op":"define_material","id":2,"kind":"diffuse","albedo":[0,0,0]}"#,
            FLOOR,
        ];
        ops.extend(caster);
        sun_on_a_floor(&world(&ops));
    }
}

/// The sun test's checks on `w`: a grey floor and a black pillar of 8 × 32 × 8 voxels
/// standing on it at x, z = 28.
fn sun_on_a_floor(w: &World) {
    let (e, el) = (2.0, 45.0);
    // Seen from above, 1.25 voxels of floor per pixel.
    let cam = camera(r#"{"pos":[32,60,32],"yaw":0,"pitch":-89.9,"fov_y":60}"#);
    let size = (48, 48);
    let sun = Sun::parse(&format!("90,{el},{e}")).unwrap();
    let light = Light::new(Sky::parse("uniform:0").unwrap(), Some(sun), 8).unwrap();
    // Where each pixel's centre ray meets the floor's top (y = 8).
    let basis = cam.basis();
    let floor_point = |px: u32, py: u32| {
        let r = cam.ray(&basis, px, py, size.0, size.1).unwrap();
        let t = (8.0 - r.origin()[1]) / r.dir()[1];
        (r.origin()[0] + t * r.dir()[0], r.origin()[2] + t * r.dir()[2])
    };
    // The sun comes from +X at 45°: the 32-voxel pillar shades x ≤ 36 for z in [28, 36].
    // Pixels within 1.5 voxels of the shadow's edge are left out, and so are those whose
    // view of the floor the pillar's sides may hide (within 10.4 voxels of x = 32 or
    // z = 32 from this camera).
    let lit = |px, py| {
        let (x, z) = floor_point(px, py);
        !(21.0..=43.0).contains(&z) || x > 46.0
    };
    let shaded = |px, py| {
        let (x, z) = floor_point(px, py);
        (29.5..=34.5).contains(&z) && x < 34.5
    };
    let expected = 0.5 * e * f64::to_radians(el).sin() / std::f64::consts::PI;
    for (who, img) in render(w, &cam, size, light, 4) {
        assert_mean(
            &format!("{who}, lit floor"),
            img.mean_where(lit).unwrap(),
            [expected; 3],
        );
        let dark = img.mean_where(shaded).unwrap();
        assert_eq!(dark.0, [0.0; 3], "{who}: the shadow is black");
    }
}

#[test]
fn a_closed_box_of_emissive_walls_sums_its_bounces() {
    let (a, e) = (0.5, 2.0);
    let w = world(&[
        r#"{"op":"define_material","id":1,"kind":"emissive","albedo":[0.5,0.5,0.5],"emission":2}"#,
        r#"{"op":"box","min":[16,16,16],"max":[48,48,48],"material":1}"#,
        r#"{"op":"box","min":[20,20,20],"max":[44,44,44],"material":0}"#,
    ]);
    let cam = camera(r#"{"pos":[32.3,31.7,30.1],"yaw":20,"pitch":10}"#);
    for bounces in [0u32, 1, 3] {
        let light = Light::new(Sky::parse("uniform:5").unwrap(), None, bounces).unwrap();
        let expected = a * e * (1.0 - f64::powi(a, bounces as i32 + 1)) / (1.0 - a);
        for (who, img) in render(&w, &cam, (16, 12), light, 4) {
            assert_mean(
                &format!("{who}, {bounces} bounces"),
                img.mean_where(|_, _| true).unwrap(),
                [expected; 3],
            );
        }
    }
}

#[test]
fn gpu_pixels_fall_within_the_cpu_estimate() {
    let Some(gpu) = gpu() else { return };
    let w = showcase();
    let cam = camera(SHOWCASE_CAMERA);
    let size = (24, 16);
    let light = Light::new(Sky::Physical, None, 3).unwrap();
    let spp = 256;
    let gw = GpuWorld::new(gpu, &w).expect("upload");
    let img = PathTracer::new(gpu)
        .render(gpu, &gw, &Shot::new(cam, size, light, 0), spp, &mut |_| {})
        .expect("path trace");
    let cpu = CpuPathTracer::new(&w, light, 0);
    // One pixel of each thing in view: sky (material 0), floor, metal, emitter, mirror.
    let basis = cam.basis();
    let sees = |px, py| {
        let r = cam.ray(&basis, px, py, size.0, size.1).unwrap();
        trace_naadf(&w, &r).map_or(0, |h| h.material)
    };
    for material in 0..=4u16 {
        let (px, py) = (0..size.0 * size.1)
            .map(|i| (i % size.0, i / size.0))
            .find(|&(px, py)| sees(px, py) == material)
            .unwrap_or_else(|| panic!("material {material} is in view"));
        let est = cpu.estimate(&cam, (px, py), size, 0..spp);
        let got = img.rgb[(px + py * size.0) as usize].map(f64::from);
        for ((g, m), se) in got.iter().zip(est.mean).zip(est.standard_error) {
            assert!(
                (g - m).abs() <= 4.0 * se + 1e-4 * m.abs() + 1e-6,
                "pixel ({px}, {py}) of material {material}: GPU {got:?} vs CPU {:?} ± {:?}",
                est.mean,
                est.standard_error
            );
        }
    }
}

#[test]
fn the_gpu_path_tracer_is_deterministic_and_progressive() {
    let Some(gpu) = gpu() else { return };
    let w = showcase();
    let cam = camera(SHOWCASE_CAMERA);
    let size = (20, 12);
    let light = Light::new(Sky::Physical, None, 3).unwrap();
    let gw = GpuWorld::new(gpu, &w).expect("upload");
    let once = |seed: u32, spp: u32| {
        PathTracer::new(gpu)
            .render(gpu, &gw, &Shot::new(cam, size, light, seed), spp, &mut |_| {})
            .expect("path trace")
    };
    let a = once(0, 16);
    assert_eq!(a, once(0, 16), "same seed, same bytes");
    assert_ne!(a, once(1, 16), "another seed, other samples");
    assert!(a.rgb.iter().flatten().all(|c| c.is_finite() && *c >= 0.0));
    // 8 samples, then 8 more, add up to the same sums as 16 at once.
    let mut pt = PathTracer::new(gpu);
    let mut seen = Vec::new();
    pt.render(gpu, &gw, &Shot::new(cam, size, light, 0), 8, &mut |n| seen.push(n))
        .unwrap();
    assert_eq!(seen.last(), Some(&8));
    let b = pt
        .render(gpu, &gw, &Shot::new(cam, size, light, 0), 16, &mut |_| {})
        .unwrap();
    assert_eq!(pt.samples(), 16);
    assert_eq!(a, b, "progressive sums equal one-shot sums");
}

#[test]
fn an_edit_restarts_the_sums() {
    let Some(gpu) = gpu() else { return };
    let mut w = showcase();
    let cam = camera(SHOWCASE_CAMERA);
    let size = (16, 12);
    let light = Light::new(Sky::Physical, None, 2).unwrap();
    let mut slot = None;
    let mut pt = PathTracer::new(gpu);
    let before = {
        let gw = GpuWorld::follow(&mut slot, gpu, &w).unwrap();
        pt.render(gpu, gw, &Shot::new(cam, size, light, 0), 8, &mut |_| {})
            .unwrap()
    };
    let edit = r#"{"op":"box","min":[28,8,28],"max":[36,16,30],"material":3}"#;
    w.apply(&Batch::parse_line(edit).unwrap(), &Limits::default()).unwrap();
    let after = {
        let gw = GpuWorld::follow(&mut slot, gpu, &w).unwrap();
        pt.render(gpu, gw, &Shot::new(cam, size, light, 0), 8, &mut |_| {})
            .unwrap()
    };
    assert_ne!(before, after, "the edit shows");
    let fresh = PathTracer::new(gpu)
        .render(
            gpu,
            &GpuWorld::new(gpu, &w).unwrap(),
            &Shot::new(cam, size, light, 0),
            8,
            &mut |_| {},
        )
        .unwrap();
    assert_eq!(after, fresh, "after an edit the sums hold the new world only");
}

#[test]
fn bad_requests_are_errors() {
    let Some(gpu) = gpu() else { return };
    let w = showcase();
    let cam = camera(r#"{"pos":[32,20,14],"yaw":0,"pitch":-10}"#);
    let light = Light::new(Sky::Physical, None, 3).unwrap();
    let gw = GpuWorld::new(gpu, &w).unwrap();
    let mut pt = PathTracer::new(gpu);
    let mut run = |size, spp| pt.render(gpu, &gw, &Shot::new(cam, size, light, 0), spp, &mut |_| {});
    assert!(run((8, 8), 0).unwrap_err().to_string().contains("at least one sample"));
    assert!(run((20000, 8), 1).unwrap_err().to_string().contains("frame size"));
    assert!(run((0, 8), 1).is_err());
}

#[test]
fn the_baseline_keeps_an_exact_image_exact_and_converges_toward_the_path_tracer() {
    let Some(gpu) = gpu() else { return };
    // A floor under a uniform sky has no variance: every frame of the baseline is a·L, also
    // while the camera moves.
    let floor = world(&[GREY, FLOOR]);
    let light = Light::new(Sky::parse("uniform:2").unwrap(), None, 3).unwrap();
    let gw = GpuWorld::new(gpu, &floor).unwrap();
    let mut baseline = Baseline::new(gpu);
    for i in 0..6 {
        let cam = camera(&format!(
            r#"{{"pos":[{},40,32],"yaw":{},"pitch":-80,"fov_y":50}}"#,
            30 + i,
            2 * i
        ));
        baseline.frame(gpu, &gw, &Shot::new(cam, (16, 12), light, 0)).unwrap();
        let img = baseline.radiance(gpu).unwrap();
        assert!(
            img.rgb.iter().flatten().all(|c| (c - 1.0).abs() < 1e-5),
            "frame {i}: {:?}",
            img.rgb[0]
        );
    }
    assert_eq!(baseline.frames(), 6);

    // On a scene with variance, 32 frames are much closer to a 256-spp reference than the
    // first frame, and the same seed gives the same bytes.
    let w = showcase();
    let cam = camera(SHOWCASE_CAMERA);
    let size = (24, 16);
    let light = Light::new(Sky::Physical, None, 3).unwrap();
    let gw = GpuWorld::new(gpu, &w).unwrap();
    let reference = PathTracer::new(gpu)
        .render(gpu, &gw, &Shot::new(cam, size, light, 7), 256, &mut |_| {})
        .unwrap();
    let run = |frames: u32| {
        let mut b = Baseline::new(gpu);
        for _ in 0..frames {
            b.frame(gpu, &gw, &Shot::new(cam, size, light, 0)).unwrap();
        }
        b.radiance(gpu).unwrap()
    };
    let (first, later) = (run(1), run(32));
    let (e1, e32) = (mse(&first, &reference), mse(&later, &reference));
    assert!(e32 < 0.4 * e1, "MSE after 32 frames {e32} vs after 1 {e1}");
    assert_eq!(later, run(32), "same seed, same bytes");
}

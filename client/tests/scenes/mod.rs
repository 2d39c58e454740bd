//! Small worlds, cameras and measures shared by the lit-mode tests (`pathtrace.rs`,
//! `gi.rs`): the device (or `None` with a message), worlds built from ops, the scenes with
//! analytic answers, and the mean squared error between two images.

#![allow(dead_code)] // Each test binary uses its own part.

#[path = "../../../world/tests/common/mod.rs"]
mod common;

use common::Raw;
use naadf_client::gpu::Gpu;
use naadf_client::light::hdr::Radiance;
use naadf_world::camera::Camera;
use naadf_world::ops::{Batch, Limits};
use naadf_world::{World, WorldSize};
use std::sync::OnceLock;

/// One device for the whole test binary, or `None` with a message.
pub fn gpu() -> Option<&'static Gpu> {
    static GPU: OnceLock<Option<Gpu>> = OnceLock::new();
    GPU.get_or_init(|| match Gpu::new() {
        Ok(g) => Some(g),
        Err(e) => {
            eprintln!("skipping the GPU half of the lit-mode tests: {e}");
            None
        }
    })
    .as_ref()
}

/// Applies `ops` (JSON objects of the ops format) to `w` as one batch.
pub fn apply(w: &mut World, ops: &[&str]) {
    let batch = Batch::parse_line(&format!(r#"{{"batch":[{}]}}"#, ops.join(","))).expect("ops");
    w.apply(&batch, &Limits::default()).expect("apply");
}

/// A 64³ world made by `ops` from empty.
pub fn world(ops: &[&str]) -> World {
    world_of([64, 64, 64], ops)
}

/// A world of `size` voxels made by `ops` from empty.
pub fn world_of(size: [u32; 3], ops: &[&str]) -> World {
    let mut w = Raw::empty(WorldSize::new(size[0], size[1], size[2]).unwrap(), 1).build();
    apply(&mut w, ops);
    w
}

/// A camera from its JSON.
pub fn camera(json: &str) -> Camera {
    Camera::from_json(json).unwrap()
}

/// A floor 8 voxels thick over the whole world.
pub const FLOOR: &str = r#"{"op":"box","min":[0,0,0],"max":[64,8,64],"material":1}"#;
/// Material 1: grey diffuse, albedo 0.5.
pub const GREY: &str = r#"{"op":"define_material","id":1,"kind":"diffuse","albedo":[0.5,0.5,0.5]}"#;

/// Material 2: a rough copper metal.
pub const METAL: &str = r#"{"op":"define_material","id":2,"kind":"metal","albedo":[0.9,0.6,0.3],"roughness":0.3}"#;
/// Material 3: a warm emitter of strength 4.
pub const WARM_LAMP: &str = r#"{"op":"define_material","id":3,"kind":"emissive","albedo":[1,0.8,0.5],"emission":4}"#;
/// Material 4: a bluish mirror.
pub const MIRROR: &str = r#"{"op":"define_material","id":4,"kind":"mirror","albedo":[0.8,0.8,0.9]}"#;

/// Every material kind, an entity-free world lit by the physical sky and the sun.
pub fn showcase() -> World {
    world(&[
        GREY,
        METAL,
        WARM_LAMP,
        MIRROR,
        FLOOR,
        r#"{"op":"sphere","center":[26,14,40],"radius":6,"material":2}"#,
        r#"{"op":"box","min":[36,8,36],"max":[40,12,40],"material":3}"#,
        r#"{"op":"box","min":[20,8,50],"max":[44,28,51],"material":4}"#,
    ])
}

/// A floor with shade from a roof, a pillar's shadow, a metal sphere and a mirror wall,
/// and `extra` ops after them (the lighting tiers' GPU-against-CPU scenes).
pub fn courtyard(extra: &[&str]) -> World {
    let ops = [
        GREY,
        METAL,
        MIRROR,
        FLOOR,
        r#"{"op":"box","min":[20,20,20],"max":[44,22,44],"material":1}"#,
        r#"{"op":"box","min":[20,8,20],"max":[22,20,22],"material":1}"#,
        r#"{"op":"sphere","center":[48,14,40],"radius":5,"material":2}"#,
        r#"{"op":"box","min":[8,8,50],"max":[30,24,51],"material":4}"#,
    ];
    world(&[&ops[..], extra].concat())
}

/// The camera the courtyard tests look through.
pub const COURTYARD_CAMERA: &str = r#"{"pos":[32,30,2],"yaw":0,"pitch":-25,"fov_y":70}"#;

/// Checks GPU values against the CPU's for the same random streams: at most 2 % of them
/// may differ by more than 2·10⁻³ (relative, or absolute below 1) in a channel, where f32
/// and f64 round a ray differently, and the sums may differ by 1 %.
pub fn assert_gpu_matches_cpu(pairs: impl Iterator<Item = ([f32; 3], [f64; 3])>, what: &str) {
    let (mut n, mut differ, mut sum_gpu, mut sum_cpu) = (0, 0, 0.0, 0.0);
    for (g, c) in pairs {
        n += 1;
        sum_gpu += g.iter().map(|&v| f64::from(v)).sum::<f64>();
        sum_cpu += c.iter().sum::<f64>();
        if (0..3).any(|k| (f64::from(g[k]) - c[k]).abs() > 2e-3 * c[k].abs().max(1.0)) {
            differ += 1;
        }
    }
    eprintln!("{differ} of {n} {what} differ; sums GPU {sum_gpu:.4}, CPU {sum_cpu:.4}");
    assert!(n > 0 && differ * 50 <= n, "{differ} of {n} {what} differ");
    assert!(
        (sum_gpu - sum_cpu).abs() <= 0.01 * sum_cpu,
        "sums GPU {sum_gpu} vs CPU {sum_cpu}"
    );
}

/// The camera the showcase tests look through.
pub const SHOWCASE_CAMERA: &str = r#"{"pos":[32,20,14],"yaw":0,"pitch":-10,"fov_y":70}"#;

/// The mean squared difference of `a` from `reference` over the image and channels.
pub fn mse(a: &Radiance, reference: &Radiance) -> f64 {
    let sum: f64 = a
        .rgb
        .iter()
        .zip(&reference.rgb)
        .map(|(x, y)| (0..3).map(|c| f64::from(x[c] - y[c]).powi(2)).sum::<f64>())
        .sum();
    sum / (3 * a.rgb.len()) as f64
}

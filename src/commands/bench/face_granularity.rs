//! Why the irradiance cache keys voxel faces and not block faces (`bench gi
//! --face-samples`; docs/RENDERING.md §3e): the image error a block-face cache would add,
//! measured on the CPU against the noise of the estimates themselves.
//!
//! Each pixel's primary ray finds its diffuse world face; each visible face's irradiance is
//! estimated twice, from independent seeds, with `samples` samples. A block-face cache would
//! give every voxel face the mean of the visible voxel faces of its 4×4 block face: the
//! pixel-weighted relative difference of that mean from the face's own estimate is what the
//! coarser key costs, and the difference between the two seeds' estimates (over √2) is
//! the noise either carries.

use naadf_client::light::Light;
use naadf_client::light::irradiance::{CpuIrradiance, FaceKey};
use naadf_world::World;
use naadf_world::camera::Camera;
use naadf_world::material::MaterialKind;
use naadf_world::traverse::trace_naadf;
use rayon::prelude::*;
use serde::Serialize;
use std::collections::HashMap;

/// What the measurement found.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct FaceGranularity {
    /// Samples per estimate.
    pub samples: u32,
    /// Pixels whose primary ray meets a diffuse world face.
    pub pixels: usize,
    /// Distinct voxel faces they see.
    pub voxel_faces: usize,
    /// Distinct block faces (4×4 voxel faces) they see.
    pub block_faces: usize,
    /// Pixel-weighted mean |E(voxel face) − E(block face)| / mean E (luminance).
    pub block_error: f64,
    /// The same between two independent estimates of each voxel face, over √2: the noise
    /// of one estimate.
    pub noise: f64,
}

fn luminance([r, g, b]: [f64; 3]) -> f64 {
    0.2126 * r + 0.7152 * g + 0.0722 * b
}

/// Measures `world` seen by `camera` at `size` under `light`.
pub fn measure(world: &World, light: Light, camera: &Camera, size: (u32, u32), samples: u32) -> FaceGranularity {
    let basis = camera.basis();
    let keys: Vec<FaceKey> = (0..size.0 * size.1)
        .into_par_iter()
        .filter_map(|i| {
            let (px, py) = (i % size.0, i / size.0);
            let ray = camera
                .ray_through(&basis, f64::from(px) + 0.5, f64::from(py) + 0.5, size.0, size.1)
                .ok()?;
            let hit = trace_naadf(world, &ray)?;
            let m = world.materials().get(hit.material)?;
            let diffuse = !matches!(m.kind, MaterialKind::Mirror | MaterialKind::Metal);
            FaceKey::of(hit.voxel, hit.normal).filter(|_| diffuse && hit.entity.is_none())
        })
        .collect();
    let mut faces: Vec<FaceKey> = keys.clone();
    faces.sort_by_key(|k| (k.voxel, k.face));
    faces.dedup();
    let estimate = |seed: u32| -> HashMap<FaceKey, f64> {
        let cache = CpuIrradiance::new(world, light, seed, samples);
        faces
            .par_iter()
            .map(|&k| (k, luminance(cache.irradiance(k).to_array())))
            .collect()
    };
    let (first, second) = (estimate(0), estimate(1));
    let block = |k: &FaceKey| (k.voxel.map(|v| v / 4), k.face);
    let mut blocks: HashMap<([u32; 3], u32), (f64, u32)> = HashMap::new();
    for k in &faces {
        let b = blocks.entry(block(k)).or_default();
        b.0 += first[k];
        b.1 += 1;
    }
    let (mut total, mut coarse, mut noise) = (0.0, 0.0, 0.0);
    for k in &keys {
        let (sum, n) = blocks[&block(k)];
        total += first[k];
        coarse += (first[k] - sum / f64::from(n)).abs();
        noise += (first[k] - second[k]).abs();
    }
    let total = total.max(f64::MIN_POSITIVE);
    FaceGranularity {
        samples,
        pixels: keys.len(),
        voxel_faces: faces.len(),
        block_faces: blocks.len(),
        block_error: coarse / total,
        noise: noise / total / std::f64::consts::SQRT_2,
    }
}

//! Fixed, reproducible ray sets for benchmarks: primary rays from fixed cameras placed
//! relative to the world size, and cosine-distributed secondary rays from primary hits.

use crate::World;
use crate::camera::Camera;
use crate::cell;
use crate::size::WorldSize;
use crate::traverse::{Hit, Ray};

/// A camera that frames the world's solid content (the box of its non-empty chunks),
/// looking down at it at 20° from the front left with a 60° field of view, so that the sky
/// above the horizon is behind it; `None` for an empty world. Small models in a large padded world are out of the fixed cameras' view.
///
/// ```
/// use naadf_world::{World, preset::Preset, raysets::content_camera};
/// let src = Preset::Test.source(None, 1).unwrap();
/// let world = World::build(&*src, &|_| {}).unwrap();
/// assert!(content_camera(&world).is_some());
/// ```
pub fn content_camera(world: &World) -> Option<Camera> {
    let c = world.size().chunks();
    let (mut lo, mut hi) = ([u32::MAX; 3], [0u32; 3]);
    for z in 0..c[2] {
        for y in 0..c[1] {
            for x in 0..c[0] {
                if world.chunks()[world.size().chunk_index([x, y, z])] >> cell::STATE_SHIFT != cell::STATE_EMPTY {
                    for (a, v) in [x, y, z].into_iter().enumerate() {
                        (lo[a], hi[a]) = (lo[a].min(v), hi[a].max(v + 1));
                    }
                }
            }
        }
    }
    if hi[0] == 0 {
        return None;
    }
    let centre: [f64; 3] = std::array::from_fn(|a| 8.0 * f64::from(lo[a] + hi[a]));
    let radius = (0..3)
        .map(|a| (8.0 * f64::from(hi[a] - lo[a])).powi(2))
        .sum::<f64>()
        .sqrt();
    let (yaw, pitch, fov_y) = (45.0f64, -20.0f64, 60.0f64);
    let forward = [
        yaw.to_radians().sin() * pitch.to_radians().cos(),
        pitch.to_radians().sin(),
        yaw.to_radians().cos() * pitch.to_radians().cos(),
    ];
    // Far enough back that the box's bounding sphere fits the narrower (vertical) view.
    let distance = radius / (fov_y / 2.0).to_radians().sin();
    Some(Camera {
        pos: std::array::from_fn(|a| centre[a] - forward[a] * distance),
        yaw,
        pitch,
        fov_y,
    })
}

/// Four fixed cameras: above the world's middle height, looking across and down at it from
/// different sides.
pub fn fixed_cameras(size: WorldSize) -> Vec<Camera> {
    let s = size.voxels().map(f64::from);
    let at = |fx: f64, fy: f64, fz: f64| [fx * s[0], fy * s[1], fz * s[2]];
    vec![
        Camera {
            pos: at(0.5, 0.7, 0.05),
            yaw: 0.0,
            pitch: -15.0,
            fov_y: 70.0,
        },
        Camera {
            pos: at(0.95, 0.6, 0.5),
            yaw: -90.0,
            pitch: -10.0,
            fov_y: 70.0,
        },
        Camera {
            pos: at(0.2, 0.9, 0.8),
            yaw: 135.0,
            pitch: -35.0,
            fov_y: 70.0,
        },
        Camera {
            pos: at(0.5, 0.45, 0.5),
            yaw: 45.0,
            pitch: -5.0,
            fov_y: 90.0,
        },
    ]
}

/// Primary rays of every camera at `w × h` pixels, camera by camera, row by row (pixels
/// whose ray is invalid, i.e. cameras absurdly far away, are left out).
pub fn primary_rays(cameras: &[Camera], w: u32, h: u32) -> Vec<Ray> {
    cameras
        .iter()
        .flat_map(|c| {
            let b = c.basis();
            (0..h).flat_map(move |y| (0..w).filter_map(move |x| c.ray(&b, x, y, w, h).ok()))
        })
        .collect()
}

/// SplitMix64: a small, well-mixed deterministic generator for reproducible benchmark
/// inputs.
#[derive(Clone, Debug)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)` (53 bits).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform-ish in `0..n` (modulo bias is irrelevant for benchmark inputs).
    pub fn below(&mut self, n: u32) -> u32 {
        (self.next_u64() % u64::from(n.max(1))) as u32
    }
}

/// One cosine-distributed secondary ray per primary hit that has a face normal, leaving
/// the hit face (offset 1e-3 along the normal). Deterministic in `seed` and the hit order.
pub fn secondary_rays(primary: &[Ray], hits: &[Option<Hit>], seed: u64) -> Vec<Ray> {
    let mut out = Vec::new();
    for (i, (ray, hit)) in primary.iter().zip(hits).enumerate() {
        let Some(h) = hit else { continue };
        let Some(axis) = (0..3).find(|&a| h.normal[a] != 0) else {
            continue;
        };
        let n = h.normal.map(f64::from);
        let mut rng = SplitMix64(seed ^ (i as u64).wrapping_mul(0xD1B5_4A32_D192_ED03));
        let (u1, u2) = (rng.unit(), rng.unit());
        let (r, phi) = (u1.sqrt(), std::f64::consts::TAU * u2);
        // Tangent axes: the two axes other than the normal's.
        let (ta, tb) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut d = [0.0; 3];
        d[axis] = n[axis] * (1.0 - u1).max(0.0).sqrt();
        d[ta] = r * phi.cos();
        d[tb] = r * phi.sin();
        let o = ray.origin();
        let dir = ray.dir();
        let p: [f64; 3] = std::array::from_fn(|a| o[a] + dir[a] * h.t + n[a] * 1e-3);
        if let Ok(s) = Ray::new(p, d) {
            out.push(s);
        }
    }
    out
}

//! What the passes share about a frame: the [`Shot`] a lit renderer is asked for, the
//! camera's rays as the shaders take them ([`CameraRays`]), the frame-size check, and the
//! parameter structs made from them ([`FrameInfo`], [`LightInfo`]).

use super::context::{Gpu, GpuError};
use super::params::{FrameInfo, LightInfo};
use crate::light::{Light, Sky, Sun};
use naadf_world::camera::Camera;
use naadf_world::traverse::MAX_COORD;

/// Largest frame edge.
pub const MAX_EDGE: u32 = 16384;
/// The largest f32 below 1: an origin's fraction must stay in [0, 1).
const BELOW_ONE: f32 = 0.999_999_94;

/// What a lit frame is of: the view, the image size, the light and the seed of the random
/// streams. Every lit renderer ([`super::PathTracer`], [`super::Baseline`], [`super::Gi`])
/// takes one, and keeps the one of its newest frame to tell whether its history goes on.
///
/// ```
/// use naadf_client::gpu::Shot;
/// use naadf_client::light::{Light, Sky};
/// use naadf_world::camera::Camera;
/// let camera = Camera::from_json(r#"{"pos":[1,2,3],"yaw":0,"pitch":0,"fov_y":60}"#).unwrap();
/// let light = Light::new(Sky::Physical, None, 3).unwrap();
/// let shot = Shot::new(camera, (64, 48), light, 7);
/// let moved = Shot { camera: Camera { pos: [5.0, 2.0, 3.0], ..camera }, ..shot };
/// assert!(moved.continues(&shot));
/// assert!(!Shot { seed: 8, ..shot }.continues(&shot));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shot {
    /// The camera.
    pub camera: Camera,
    /// Image size in pixels (width, height).
    pub size: (u32, u32),
    /// The light model.
    pub light: Light,
    /// The seed of the per-sample random streams.
    pub seed: u32,
}

impl Shot {
    /// A shot of `camera` at `size` under `light`, with the random streams of `seed`.
    pub fn new(camera: Camera, size: (u32, u32), light: Light, seed: u32) -> Self {
        Shot {
            camera,
            size,
            light,
            seed,
        }
    }

    /// Whether a temporal history of `earlier` may go on with this shot: the same size,
    /// light and seed (the camera may move; the history is reprojected).
    pub fn continues(&self, earlier: &Shot) -> bool {
        (self.size, self.light, self.seed) == (earlier.size, earlier.light, earlier.seed)
    }
}

/// Checks a frame size against [`MAX_EDGE`] and against one storage binding of
/// `bytes_per_pixel` per pixel (0 for a caller that splits its arrays across bindings and
/// checks them itself); returns the pixel count.
pub(crate) fn check_frame_size(gpu: &Gpu, (width, height): (u32, u32), bytes_per_pixel: u64) -> Result<u64, GpuError> {
    let pixels = u64::from(width) * u64::from(height);
    if width == 0
        || height == 0
        || width > MAX_EDGE
        || height > MAX_EDGE
        || pixels * bytes_per_pixel > gpu.limits.max_storage_buffer_binding_size
    {
        return Err(GpuError::Unsupported(format!(
            "frame size {width}x{height}: each edge must be 1..={MAX_EDGE} and the frame small enough for one binding of the adapter ({} bytes)",
            gpu.limits.max_storage_buffer_binding_size
        )));
    }
    Ok(pixels)
}

/// The origin split as the shaders take it: integer part and `f32` fraction in [0, 1).
pub(crate) fn split_origin(o: [f64; 3]) -> ([i32; 3], [f32; 3]) {
    let int = o.map(|v| v.floor());
    let frac: [f32; 3] = std::array::from_fn(|a| ((o[a] - int[a]) as f32).min(BELOW_ONE));
    (int.map(|v| v as i32), frac)
}

/// A camera as the frame passes take it (docs/CAMERA.md): the position split into integer
/// and fraction, `forward`, and `right` and `up` scaled by `a·W/H` and `a`
/// (`a = tan(fov_y/2)`), so that a pass forms `dir = forward + sx·right + sy·up`.
pub(crate) struct CameraRays {
    pub int: [i32; 3],
    pub frac: [f32; 3],
    pub forward: [f32; 3],
    pub right: [f32; 3],
    pub up: [f32; 3],
}

impl CameraRays {
    /// The rays of `camera` for a `width × height` frame; fails for a position the shaders
    /// cannot hold.
    pub fn new(camera: &Camera, (width, height): (u32, u32)) -> Result<Self, GpuError> {
        // The shaders take the origin's floor as an i32: the CPU's ray range applies.
        if camera.pos.iter().any(|c| c.abs() > MAX_COORD) {
            return Err(GpuError::Unsupported(format!(
                "camera position {:?} is out of range (within ±2^30)",
                camera.pos
            )));
        }
        let basis = camera.basis();
        let a = (camera.fov_y.to_radians() / 2.0).tan();
        let aspect = f64::from(width) / f64::from(height);
        let (int, frac) = split_origin(camera.pos);
        let v3 = |v: [f64; 3], s: f64| v.map(|c| (c * s) as f32);
        Ok(CameraRays {
            int,
            frac,
            forward: v3(basis.forward, 1.0),
            right: v3(basis.right, a * aspect),
            up: v3(basis.up, a),
        })
    }
}

impl FrameInfo {
    /// The frame parameters of a lit pass: `rays` at `size`, sample number `sample` of `seed`, and
    /// whether a temporal pass has a history.
    pub(crate) fn new(rays: &CameraRays, size: (u32, u32), seed: u32, sample: u32, history: bool) -> Self {
        FrameInfo {
            cam_int: rays.int,
            width: size.0,
            cam_frac: rays.frac,
            height: size.1,
            forward: rays.forward,
            seed,
            right: rays.right,
            sample,
            up: rays.up,
            history: u32::from(history),
        }
    }
}

impl LightInfo {
    /// The parameters of `light`.
    pub fn new(light: &Light) -> Self {
        let sky_sun = light.sky_sun();
        let (sky, sky_physical) = match light.sky {
            Sky::Uniform(rgb) => (rgb, 0),
            Sky::Physical => ([sky_sun.irradiance as f32; 3], 1),
        };
        let sun = light.sun;
        LightInfo {
            sky,
            sky_physical,
            sun_dir: sky_sun.direction().map(|c| c as f32),
            sun_on: u32::from(sun.is_some()),
            sun_disc: sun.map_or(0.0, |s| s.disc_radiance() as f32),
            sun_weight: sun.map_or(0.0, |s| s.sample_weight() as f32),
            sun_omc: Sun::one_minus_cos() as f32,
            bounces: light.bounces,
        }
    }
}

//! The camera contract (docs/CAMERA.md): JSON `{"pos":[x,y,z],"yaw":deg,"pitch":deg,"fov_y":deg}`.
//!
//! forward = (sin yaw·cos pitch, sin pitch, cos yaw·cos pitch); right = normalize(cross(+Y,
//! forward)); up = cross(forward, right). At yaw 0 the camera looks along +Z with +X to the
//! right of the image. Pixel (px, py), (0, 0) top-left, W×H: a = tan(fov_y/2);
//! dir = normalize(forward + ((2(px+0.5)/W − 1)·a·W/H)·right + ((1 − 2(py+0.5)/H)·a)·up).

use crate::error::WorldError;
use crate::traverse::Ray;
use serde::{Deserialize, Serialize};

fn default_fov() -> f64 {
    90.0
}

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Position in world voxel coordinates.
    pub pos: [f64; 3],
    /// Yaw in degrees (0 looks along +Z).
    pub yaw: f64,
    /// Pitch in degrees, clamped to ±89.9.
    pub pitch: f64,
    /// Vertical field of view in degrees.
    #[serde(default = "default_fov")]
    pub fov_y: f64,
}

/// A camera's orthonormal frame.
#[derive(Clone, Copy, Debug)]
pub struct Basis {
    /// View direction.
    pub forward: [f64; 3],
    /// Image right.
    pub right: [f64; 3],
    /// Image up.
    pub up: [f64; 3],
}

fn normalize(v: [f64; 3]) -> [f64; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|c| c / l)
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

impl Camera {
    /// Parses camera JSON, validating the numbers.
    pub fn from_json(s: &str) -> Result<Self, WorldError> {
        let c: Camera = serde_json::from_str(s).map_err(|e| WorldError::InvalidRay(format!("camera JSON: {e}")))?;
        let finite = c.pos.iter().chain([&c.yaw, &c.pitch, &c.fov_y]).all(|v| v.is_finite());
        if !(finite && c.fov_y > 0.0 && c.fov_y < 180.0) {
            return Err(WorldError::InvalidRay(format!(
                "camera {s}: values must be finite and 0 < fov_y < 180"
            )));
        }
        Ok(c)
    }

    /// The camera frame.
    ///
    /// ```
    /// use naadf_world::camera::Camera;
    /// let b = Camera { pos: [0.0; 3], yaw: 0.0, pitch: 0.0, fov_y: 90.0 }.basis();
    /// assert_eq!(b.forward, [0.0, 0.0, 1.0]);
    /// assert_eq!(b.right, [1.0, 0.0, 0.0]);
    /// ```
    pub fn basis(&self) -> Basis {
        let (yaw, pitch) = (self.yaw.to_radians(), self.pitch.clamp(-89.9, 89.9).to_radians());
        let forward = [yaw.sin() * pitch.cos(), pitch.sin(), yaw.cos() * pitch.cos()];
        let right = normalize(cross([0.0, 1.0, 0.0], forward));
        let up = cross(forward, right);
        Basis { forward, right, up }
    }

    /// The primary ray through pixel `(px, py)` of a `w × h` image. Fails only for a
    /// position beyond [`crate::traverse::ray::MAX_COORD`].
    pub fn ray(&self, basis: &Basis, px: u32, py: u32, w: u32, h: u32) -> Result<Ray, WorldError> {
        self.ray_through(basis, f64::from(px) + 0.5, f64::from(py) + 0.5, w, h)
    }

    /// The ray through the image point `(x, y)` of a `w × h` image, in pixel units from the
    /// top-left corner (pixel `(px, py)` spans `[px, px + 1) × [py, py + 1)`; its centre is
    /// the contract's ray). Path tracers jitter inside the pixel with it.
    pub fn ray_through(&self, basis: &Basis, x: f64, y: f64, w: u32, h: u32) -> Result<Ray, WorldError> {
        let a = (self.fov_y.to_radians() / 2.0).tan();
        let sx = (2.0 * x / f64::from(w) - 1.0) * a * f64::from(w) / f64::from(h);
        let sy = (1.0 - 2.0 * y / f64::from(h)) * a;
        let d: [f64; 3] = std::array::from_fn(|i| basis.forward[i] + sx * basis.right[i] + sy * basis.up[i]);
        Ray::new(self.pos, normalize(d))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_corners_follow_the_contract() {
        let c = Camera::from_json(r#"{"pos":[1,2,3],"yaw":90,"pitch":0}"#).unwrap();
        assert_eq!(c.fov_y, 90.0);
        let b = c.basis();
        // Yaw 90 looks along +X; right is then −Z.
        assert!((b.forward[0] - 1.0).abs() < 1e-12 && (b.right[2] + 1.0).abs() < 1e-12);
        // The top-left pixel of a square image looks up and to the left.
        let r = c.ray(&b, 0, 0, 2, 2).unwrap();
        assert!(r.dir()[1] > 0.0 && r.dir()[2] > 0.0);
        assert!(Camera::from_json(r#"{"pos":[0,0],"yaw":0,"pitch":0}"#).is_err());
        assert!(Camera::from_json(r#"{"pos":[0,0,0],"yaw":0,"pitch":0,"fov_y":180}"#).is_err());
    }
}

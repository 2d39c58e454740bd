//! Fly-through camera control: held movement keys and mouse look turned into a
//! [`Camera`], with no window-system types so that it is tested on its own.

use naadf_world::camera::Camera;

/// A direction of movement bound to a key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Move {
    /// Along the view direction (W).
    Forward,
    /// Against it (S).
    Back,
    /// To the left (A).
    Left,
    /// To the right (D).
    Right,
    /// World up (Space).
    Up,
    /// World down (Shift).
    Down,
}

impl Move {
    fn bit(self) -> u8 {
        1 << self as u8
    }
}

/// Degrees of turn per pixel of mouse motion.
const DEGREES_PER_PIXEL: f64 = 0.15;
/// The pitch limit, short of straight up or down (where yaw is undefined).
const MAX_PITCH: f64 = 89.0;

/// A camera flown with held keys and mouse motion.
#[derive(Clone, Debug)]
pub struct Fly {
    /// The current camera.
    pub camera: Camera,
    /// Speed in voxels per second.
    pub speed: f64,
    held: u8,
}

impl Fly {
    /// Starts at `camera`, moving at `speed` voxels per second.
    pub fn new(camera: Camera, speed: f64) -> Self {
        Fly { camera, speed, held: 0 }
    }

    /// Records that the key for `m` went down or up.
    pub fn set(&mut self, m: Move, down: bool) {
        if down {
            self.held |= m.bit();
        } else {
            self.held &= !m.bit();
        }
    }

    /// Forgets every held key (the window lost focus: its key-up events go elsewhere).
    pub fn release_all(&mut self) {
        self.held = 0;
    }

    /// Turns by a mouse motion of `(dx, dy)` pixels: right turns right, down looks down.
    pub fn look(&mut self, dx: f64, dy: f64) {
        self.camera.yaw = (self.camera.yaw + dx * DEGREES_PER_PIXEL).rem_euclid(360.0);
        self.camera.pitch = (self.camera.pitch - dy * DEGREES_PER_PIXEL).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves for `dt` seconds with the keys held now; returns whether the camera moved.
    ///
    /// ```
    /// use naadf_client::viewer::{Fly, Move};
    /// use naadf_world::camera::Camera;
    /// let mut fly = Fly::new(Camera { pos: [0.0; 3], yaw: 0.0, pitch: 0.0, fov_y: 60.0 }, 10.0);
    /// fly.set(Move::Forward, true);
    /// assert!(fly.advance(0.5));
    /// assert!((fly.camera.pos[2] - 5.0).abs() < 1e-9); // yaw 0 looks along +Z
    /// ```
    pub fn advance(&mut self, dt: f64) -> bool {
        let axis = |plus: Move, minus: Move| {
            f64::from(u8::from(self.held & plus.bit() != 0)) - f64::from(u8::from(self.held & minus.bit() != 0))
        };
        let (f, r, u) = (
            axis(Move::Forward, Move::Back),
            axis(Move::Right, Move::Left),
            axis(Move::Up, Move::Down),
        );
        if f == 0.0 && r == 0.0 && u == 0.0 {
            return false;
        }
        let b = self.camera.basis();
        let step = self.speed * dt;
        for a in 0..3 {
            let world_up = if a == 1 { u } else { 0.0 };
            self.camera.pos[a] += step * (f * b.forward[a] + r * b.right[a] + world_up);
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fly() -> Fly {
        Fly::new(
            Camera {
                pos: [10.0, 20.0, 30.0],
                yaw: 0.0,
                pitch: 0.0,
                fov_y: 60.0,
            },
            4.0,
        )
    }

    #[test]
    fn keys_move_along_the_camera_basis() {
        let mut f = fly();
        assert!(!f.advance(1.0), "nothing held, nothing moves");
        f.set(Move::Right, true);
        f.set(Move::Up, true);
        assert!(f.advance(0.5));
        assert_eq!(f.camera.pos, [12.0, 22.0, 30.0]);
        f.set(Move::Right, false);
        f.set(Move::Left, true);
        f.set(Move::Down, true); // up and down cancel
        f.advance(1.0);
        assert_eq!(f.camera.pos, [8.0, 22.0, 30.0]);
        f.release_all();
        assert!(!f.advance(1.0));
    }

    #[test]
    fn mouse_right_turns_toward_the_right_vector_and_pitch_is_clamped() {
        let mut f = fly();
        let right = f.camera.basis().right;
        f.look(100.0, 0.0);
        let fwd = f.camera.basis().forward;
        assert!(
            fwd[0] * right[0] + fwd[2] * right[2] > 0.0,
            "turned toward the old right"
        );
        f.look(0.0, 1e6);
        assert_eq!(f.camera.pitch, -MAX_PITCH);
        f.look(-2400.0, 0.0);
        assert!((0.0..360.0).contains(&f.camera.yaw));
    }
}

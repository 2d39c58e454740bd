//! Other people on the frame: a named marker at each other client's camera and its pointer
//! voxel outlined, from the presence table the world stream carries (docs/PROTOCOL.md,
//! "Presence"), projected with the camera contract (docs/CAMERA.md).

use super::hud::Canvas;
use crate::frame::Frame;
use naadf_proto::v1::PresenceEntry;
use naadf_world::camera::Camera;

/// The markers' colour.
const CYAN: [u8; 3] = [0, 255, 255];

/// Where world point `p` lands on a `w × h` frame of `camera`, in pixels; `None` behind
/// the camera.
///
/// ```
/// use naadf_world::camera::Camera;
/// let camera = Camera { pos: [0.0, 0.0, 0.0], yaw: 0.0, pitch: 0.0, fov_y: 90.0 };
/// // Straight ahead lands in the centre; behind does not land at all.
/// assert_eq!(naadf_client::viewer::project(&camera, (100, 50), [0.0, 0.0, 10.0]), Some((50.0, 25.0)));
/// assert_eq!(naadf_client::viewer::project(&camera, (100, 50), [0.0, 0.0, -10.0]), None);
/// ```
pub fn project(camera: &Camera, (w, h): (u32, u32), p: [f64; 3]) -> Option<(f64, f64)> {
    let b = camera.basis();
    let d: [f64; 3] = std::array::from_fn(|i| p[i] - camera.pos[i]);
    let dot = |u: [f64; 3]| u[0] * d[0] + u[1] * d[1] + u[2] * d[2];
    let z = dot(b.forward);
    if z <= 1e-3 {
        return None;
    }
    let a = (camera.fov_y.to_radians() / 2.0).tan();
    let (w, h) = (f64::from(w), f64::from(h));
    let sx = dot(b.right) / (z * a * w / h);
    let sy = dot(b.up) / (z * a);
    Some(((sx + 1.0) / 2.0 * w, (1.0 - sy) / 2.0 * h))
}

/// Draws the entries of `others` (the table less this window's own session) over `frame`
/// seen from `camera`; returns how many markers landed on it.
pub fn draw_markers(frame: &mut Frame, camera: &Camera, others: &[PresenceEntry]) -> usize {
    let size = (frame.width, frame.height);
    let mut canvas = Canvas {
        rgba: &mut frame.rgba,
        width: size.0,
        height: size.1,
    };
    let mut drawn = 0;
    for e in others {
        if let [x, y, z] = e.pointer[..] {
            // The pointer voxel's eight corners, as dots.
            for c in 0..8 {
                let corner = [x + (c & 1), y + (c >> 1 & 1), z + (c >> 2 & 1)].map(|v| v as f64);
                if let Some((px, py)) = project(camera, size, corner) {
                    canvas.fill(px.max(0.0) as u32, py.max(0.0) as u32, 2, 2, CYAN);
                }
            }
        }
        let [x, y, z] = e.position[..] else { continue };
        let Some((px, py)) = project(camera, size, [x, y, z]) else {
            continue;
        };
        if px < 0.0 || py < 0.0 || px >= f64::from(size.0) || py >= f64::from(size.1) {
            continue;
        }
        let (px, py) = (px as u32, py as u32);
        canvas.fill(px.saturating_sub(3), py.saturating_sub(3), 7, 7, CYAN);
        let name = if e.name.is_empty() { &e.user } else { &e.name };
        canvas.text(px + 8, py.saturating_sub(20), name, [255; 3]);
        drawn += 1;
    }
    drawn
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_marker_lands_where_the_other_camera_is() {
        let camera = Camera {
            pos: [10.0, 10.0, 0.0],
            yaw: 0.0,
            pitch: 0.0,
            fov_y: 90.0,
        };
        let mut frame = Frame {
            width: 64,
            height: 32,
            rgba: vec![0; 64 * 32 * 4],
            gbuffer: None,
        };
        let ahead = PresenceEntry {
            name: "ada".into(),
            position: vec![10.0, 10.0, 20.0],
            ..PresenceEntry::default()
        };
        let behind = PresenceEntry {
            position: vec![10.0, 10.0, -20.0],
            ..ahead.clone()
        };
        assert_eq!(draw_markers(&mut frame, &camera, &[ahead, behind]), 1);
        let at = |x: usize, y: usize| &frame.rgba[(y * 64 + x) * 4..][..3];
        assert_eq!(at(32, 16), CYAN, "the marker is at the centre");
        assert_eq!(at(2, 30), [0, 0, 0], "nothing else is drawn there");
    }
}

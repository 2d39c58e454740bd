//! Other people in the view, from the presence table the world stream carries
//! (docs/PROTOCOL.md, "Presence"): a solid box at each other client's camera, as a local
//! instance the GPU draws and hits ([`place_markers`]), and over the frame its name and its
//! pointer voxel's corners, projected with the camera contract (docs/CAMERA.md).

use super::hud::{self, Canvas};
use crate::frame::Frame;
use naadf_proto::v1::PresenceEntry;
use naadf_world::World;
use naadf_world::camera::Camera;
use naadf_world::entity::local::LocalInstances;
use naadf_world::material::{MaterialKind, MaterialTable};
use naadf_world::model::Model;

/// The edge of a marker box in voxels: odd, so that the voxel holding the camera is its
/// centre.
const MARKER_EDGE: i64 = 3;

/// The materials a marker may take, in id order: the defined materials that neither emit
/// light nor mirror (diffuse and metal: a marker should show its own colour and must not
/// light the scene on one client alone), or every defined material when there is none of
/// those. The browser page picks from the same list.
///
/// ```
/// use naadf_client::viewer::marker_materials;
/// use naadf_world::material::{Material, MaterialKind, MaterialTable};
/// let lamp = Material { kind: MaterialKind::Emissive, emission: 4.0, ..Material::diffuse([1.0; 3]) };
/// let table = MaterialTable::from_materials(&[Material::diffuse([0.5; 3]), lamp, Material::diffuse([0.2; 3])]).unwrap();
/// assert_eq!(marker_materials(&table), [1, 3]);
/// assert_eq!(marker_materials(&MaterialTable::from_materials(&[lamp]).unwrap()), [1]);
/// ```
pub fn marker_materials(table: &MaterialTable) -> Vec<u16> {
    let defined = (1..table.len()).filter_map(|id| u16::try_from(id).ok());
    let plain: Vec<u16> = defined
        .clone()
        .filter(|&id| {
            table
                .get(id)
                .is_some_and(|m| matches!(m.kind, MaterialKind::Diffuse | MaterialKind::Metal))
        })
        .collect();
    if plain.is_empty() { defined.collect() } else { plain }
}

/// The material of the marker of presence session `session`, among `materials` (as
/// [`marker_materials`] lists them): the one at index `session` modulo their count, as the
/// browser page picks it, so a person has one colour everywhere; `None` when the list is
/// empty.
///
/// ```
/// use naadf_client::viewer::marker_material;
/// assert_eq!(marker_material(7, &[1, 3, 4]), Some(3)); // 7 mod 3 = 1 → the second
/// assert_eq!(marker_material(7, &[]), None);
/// ```
pub fn marker_material(session: u64, materials: &[u16]) -> Option<u16> {
    let n = materials.len() as u64;
    (n > 0).then(|| materials[(session % n) as usize])
}

/// The marker box `(min, size)` of a camera at `pos` in a world of `dims` voxels:
/// [`MARKER_EDGE`] voxels a side around the voxel holding `pos`, clipped to the world;
/// `None` when none of it is inside the world, when `pos` is not finite, or when `eye`
/// (this window's camera) is inside it (a box around the viewer would hide everything).
fn marker_box(pos: [f64; 3], dims: [u32; 3], eye: [f64; 3]) -> Option<([i64; 3], [i64; 3])> {
    if !plausible(pos) {
        return None;
    }
    let corner = unclipped_corner(pos);
    let min: [i64; 3] = std::array::from_fn(|a| corner[a].max(0));
    let max: [i64; 3] = std::array::from_fn(|a| (corner[a] + MARKER_EDGE).min(i64::from(dims[a])));
    if (0..3).any(|a| min[a] >= max[a]) {
        return None;
    }
    if (0..3).all(|a| eye[a] >= min[a] as f64 && eye[a] < max[a] as f64) {
        return None;
    }
    Some((min, std::array::from_fn(|a| max[a] - min[a])))
}

/// Whether a position another client published can be a camera: finite, and far inside the
/// range where voxel arithmetic stays exact (anything else gets neither box nor name).
fn plausible(pos: [f64; 3]) -> bool {
    pos.iter().all(|v| v.is_finite() && v.abs() < 1e15)
}

/// The lowest corner of the marker box of a [`plausible`] camera at `pos`, before clipping:
/// [`MARKER_EDGE`] voxels a side, centred on the voxel holding `pos`.
fn unclipped_corner(pos: [f64; 3]) -> [i64; 3] {
    pos.map(|v| v.floor() as i64 - MARKER_EDGE / 2)
}

/// Where the name of the [`plausible`] camera at `pos` is written: the middle of its marker
/// box's top face, before clipping, so that the name stands over the box.
fn label_anchor(pos: [f64; 3]) -> [f64; 3] {
    let corner = unclipped_corner(pos);
    let mid = |a: usize| corner[a] as f64 + MARKER_EDGE as f64 / 2.0;
    [mid(0), (corner[1] + MARKER_EDGE) as f64, mid(2)]
}

/// Adds a marker box for each entry of `others` (the table less this window's own session)
/// to `locals`, under keys from `first_key` up, in the order of their sessions; `eye` is
/// this window's camera. Returns how many were placed.
pub fn place_markers(
    locals: &mut LocalInstances,
    world: &World,
    others: &[PresenceEntry],
    eye: [f64; 3],
    first_key: u32,
) -> usize {
    let mut sorted: Vec<&PresenceEntry> = others.iter().collect();
    sorted.sort_by_key(|e| e.session);
    let materials = marker_materials(world.materials());
    let mut key = first_key;
    for e in sorted {
        let (&[x, y, z], Some(m)) = (&e.position[..], marker_material(e.session, &materials)) else {
            continue;
        };
        let Some((min, size)) = marker_box([x, y, z], world.size().voxels(), eye) else {
            continue;
        };
        let size = size.map(|v| v as u32);
        let name = format!("marker {}x{}x{} {m}", size[0], size[1], size[2]);
        let cells = size.iter().product::<u32>() as usize;
        let placed = Model::new(size, vec![m; cells])
            .map_err(|e| e.to_string())
            .and_then(|model| locals.define_model(&name, model, world.materials()))
            .and_then(|()| locals.place(key, &name, min.map(|v| v as f64), [0.0, 0.0, 0.0, 1.0]));
        if placed.is_ok() {
            key += 1;
        }
    }
    (key - first_key) as usize
}

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

/// Writes the names and pointer voxels of `others` (the table less this window's own
/// session) over `frame` seen from `camera` (the box at each camera is a local instance:
/// [`place_markers`]); returns how many names landed on it.
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
        if !plausible([x, y, z]) {
            continue;
        }
        let Some((px, py)) = project(camera, size, label_anchor([x, y, z])) else {
            continue;
        };
        // (Written so that a NaN would be left out too.)
        if !(px >= 0.0 && py >= 0.0 && px < f64::from(size.0) && py < f64::from(size.1)) {
            continue;
        }
        // Centred above the anchor, kept on the frame.
        let name = if e.name.is_empty() { &e.user } else { &e.name };
        let x0 = (px as u32).saturating_sub(hud::text_width(name) / 2);
        let y0 = (py as u32).saturating_sub(hud::CELL + 2);
        canvas.text(x0, y0, name, [255; 3]);
        drawn += 1;
    }
    drawn
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_name_lands_over_the_other_cameras_box() {
        let camera = Camera {
            pos: [10.0, 10.0, 0.0],
            yaw: 0.0,
            pitch: 0.0,
            fov_y: 90.0,
        };
        let mut frame = Frame {
            width: 64,
            height: 64,
            rgba: vec![0; 64 * 64 * 4],
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
        // Positions another client may send that get no name: not finite, or far beyond
        // any world (though one of them would project onto the frame).
        let hostile = [
            [f64::NAN, 10.0, 20.0],
            [f64::MAX, f64::MAX, f64::MAX],
            [-f64::MAX, 10.0, f64::MAX],
            [f64::INFINITY, 0.0, 1.0],
        ]
        .map(|p| PresenceEntry {
            position: p.to_vec(),
            ..ahead.clone()
        });
        let mut all = vec![ahead, behind];
        all.extend(hostile);
        assert_eq!(draw_markers(&mut frame, &camera, &all), 1);
        let lit = |x0: usize, x1: usize, y0: usize, y1: usize| {
            (y0..y1).any(|y| (x0..x1).any(|x| frame.rgba[(y * 64 + x) * 4..][..3] != [0, 0, 0]))
        };
        // The top of the box, (10.5, 12, 20.5), lands at about (32.8, 28.9): the name (three
        // 16-pixel cells) is written centred over it, from x 8 to 56 and y 10 to 26.
        assert!(lit(8, 56, 10, 26), "the name is written over the box");
        assert!(
            !lit(0, 8, 0, 64) && !lit(56, 64, 0, 64) && !lit(0, 64, 0, 10) && !lit(0, 64, 26, 64),
            "nothing else is drawn"
        );
    }

    #[test]
    fn markers_are_boxes_around_the_other_cameras_inside_the_world() {
        use naadf_world::preset::Preset;
        let src = Preset::Test.source(None, 1).unwrap();
        let world = World::build(&*src, &|_| {}).unwrap();
        let dims = world.size().voxels();
        let at = |session: u64, position: Vec<f64>| PresenceEntry {
            session,
            position,
            ..PresenceEntry::default()
        };
        let eye = [5.5, 60.5, 5.5];
        let others = [
            at(9, vec![20.5, 40.2, 30.9]),
            at(3, vec![0.2, 0.5, 1.5]),                        // at the corner: clipped
            at(4, vec![5.0, 60.0, 5.0]),                       // around this window's camera
            at(5, vec![-10.0, 40.0, 30.0]),                    // outside the world
            at(6, vec![f64::NAN, 40.0, 30.0]),                 // not a position
            at(7, vec![f64::from(dims[0]) + 0.5, 40.0, 30.0]), // one voxel outside
            at(8, vec![f64::from(dims[0]) - 0.5, f64::from(dims[1]) - 0.5, 1.0]), // at the far edge
        ];
        let mut locals = LocalInstances::default();
        assert_eq!(place_markers(&mut locals, &world, &others, eye, 1), 4);
        let materials = marker_materials(world.materials());
        // In the order of the sessions: 3, 7 (its clipped box reaches one voxel in), 8, 9.
        let expect = [
            (3, [0.0, 0.0, 0.0], [2, 2, 3]),
            (7, [f64::from(dims[0]) - 1.0, 39.0, 29.0], [1, 3, 3]),
            (8, [f64::from(dims[0]) - 2.0, f64::from(dims[1]) - 2.0, 0.0], [2, 2, 3]),
            (9, [19.0, 39.0, 29.0], [3, 3, 3]),
        ];
        for (k, (session, pos, size)) in expect.into_iter().enumerate() {
            let pose = locals.get(1 + k as u32).expect("placed");
            let m = marker_material(session, &materials).unwrap();
            assert_eq!(pose.pos, pos, "session {session}");
            assert_eq!(pose.model, format!("marker {}x{}x{} {m}", size[0], size[1], size[2]));
        }
    }
}

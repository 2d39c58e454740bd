//! What a click edits: the voxel under the crosshair (erase) or the empty voxel in front
//! of its face (place), found with the CPU traversal on the mirrored world and written as
//! one Ops JSON batch.

use naadf_world::World;
use naadf_world::camera::Camera;
use naadf_world::entity::local::LocalInstances;
use naadf_world::model::Model;
use naadf_world::traverse::{Hit, trace_naadf};

/// What a click does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Click {
    /// Left button: set the voxel under the crosshair to empty.
    Erase,
    /// Right button: set the voxel in front of the hit face to this material.
    Place(u16),
}

/// The edit a click at the centre of a `width × height` view from `camera` makes, as Ops
/// JSON; `None` when the crosshair shows the sky, an entity, or a face at the world's edge.
///
/// ```
/// use naadf_client::viewer::{Click, edit_for_click};
/// use naadf_world::{World, camera::Camera, preset::Preset};
/// let src = Preset::Test.source(None, 1).unwrap();
/// let world = World::build(&*src, &|_| {}).unwrap();
/// let s = world.size().voxels().map(f64::from);
/// // Straight down from above the middle of the world.
/// let cam = Camera { pos: [s[0] / 2.0, s[1] - 0.5, s[2] / 2.0], yaw: 0.0, pitch: -89.0, fov_y: 60.0 };
/// let ops = edit_for_click(&world, &cam, (64, 64), Click::Erase).unwrap();
/// assert!(ops.starts_with(r#"{"op":"set","voxels":[["#) && ops.ends_with(",0]]}"));
/// ```
pub fn edit_for_click(world: &World, camera: &Camera, size: (u32, u32), click: Click) -> Option<String> {
    let (target, material) = click_target(world, camera, size, click)?;
    Some(format!(
        r#"{{"op":"set","voxels":[[{},{},{},{material}]]}}"#,
        target[0], target[1], target[2]
    ))
}

/// The voxel a click edits and the material it gets: the voxel under the crosshair
/// (erase) or the empty voxel in front of its face (place).
fn click_target(world: &World, camera: &Camera, size: (u32, u32), click: Click) -> Option<([i64; 3], u16)> {
    let hit = centre_hit(world, camera, size)?;
    let v = hit.voxel.map(i64::from);
    let (target, material) = match click {
        Click::Erase => (v, 0),
        Click::Place(m) => (std::array::from_fn(|a| v[a] + i64::from(hit.normal[a])), m),
    };
    // A face hit from inside the voxel has no normal: placing there would overwrite it.
    if click != Click::Erase && target == v {
        return None;
    }
    world.size().contains(target).then_some((target, material))
}

/// The local model of the place preview.
const PREVIEW: &str = "place preview";

/// What a right click with `material` would place, shown before it is placed: a local
/// instance (drawn and hit by the GPU's rays, unknown to the world and to picking) of one
/// voxel of `material` where the voxel would go. Empty when a click would place nothing.
pub(crate) fn place_preview(world: &World, camera: &Camera, size: (u32, u32), material: u16) -> LocalInstances {
    let mut locals = LocalInstances::default();
    if let Some((target, m)) = click_target(world, camera, size, Click::Place(material)) {
        let voxel = Model::new([1, 1, 1], vec![m]).expect("a one-voxel model");
        // An undefined material places nothing, and shows nothing.
        if locals.define_model(PREVIEW, voxel, world.materials()).is_ok() {
            let placed = locals.place(0, PREVIEW, target.map(|v| v as f64), [0.0, 0.0, 0.0, 1.0]);
            debug_assert!(placed.is_ok(), "a voxel of the world packs");
        }
    }
    locals
}

/// The voxel of the world under the crosshair of a `width × height` view (`None` for the
/// sky or an entity): what the window publishes as its pointer.
pub(crate) fn pointed_voxel(world: &World, camera: &Camera, size: (u32, u32)) -> Option<[i64; 3]> {
    centre_hit(world, camera, size).map(|h| h.voxel.map(i64::from))
}

/// The world's hit under the crosshair, if it is not an entity's.
fn centre_hit(world: &World, camera: &Camera, (width, height): (u32, u32)) -> Option<Hit> {
    let ray = camera
        .ray(&camera.basis(), width / 2, height / 2, width.max(1), height.max(1))
        .ok()?;
    trace_naadf(world, &ray).filter(|h| h.entity.is_none())
}

#[cfg(test)]
mod tests {
    use super::*;
    use naadf_world::ops::{Batch, Limits, Op};
    use naadf_world::preset::Preset;

    /// A flat world: a floor of material 1 below y = 4, looked at from above.
    fn floor() -> (World, Camera) {
        let src = Preset::Test.source(None, 1).unwrap();
        let mut w = World::build(&*src, &|_| {}).unwrap();
        let s = w.size().voxels().map(i64::from);
        w.apply(
            &Batch {
                ops: vec![
                    Op::Box {
                        min: [0, 0, 0],
                        max: [s[0], s[1], s[2]],
                        material: 0,
                    },
                    Op::Box {
                        min: [0, 0, 0],
                        max: [s[0], 4, s[2]],
                        material: 1,
                    },
                ],
            },
            &Limits::default(),
        )
        .unwrap();
        let cam = Camera {
            pos: [10.5, 20.0, 10.5],
            yaw: 0.0,
            pitch: -89.0,
            fov_y: 60.0,
        };
        (w, cam)
    }

    #[test]
    fn erase_targets_the_hit_voxel_and_place_the_one_above() {
        let (w, cam) = floor();
        let erase = edit_for_click(&w, &cam, (65, 65), Click::Erase).unwrap();
        let place = edit_for_click(&w, &cam, (65, 65), Click::Place(3)).unwrap();
        // Pitch −89° drifts less than a voxel over 16 voxels of height.
        let parse = |s: &str| -> Vec<i64> {
            let v: serde_json::Value = serde_json::from_str(s).unwrap();
            v["voxels"][0]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_i64().unwrap())
                .collect()
        };
        let (e, p) = (parse(&erase), parse(&place));
        assert_eq!(e[1], 3, "top voxel of the floor");
        assert_eq!(e[3], 0);
        assert_eq!(p, vec![e[0], 4, e[2], 3], "the empty voxel above it");
    }

    #[test]
    fn the_sky_gives_no_edit() {
        let (w, mut cam) = floor();
        cam.pitch = 80.0;
        assert_eq!(edit_for_click(&w, &cam, (65, 65), Click::Erase), None);
    }

    #[test]
    fn the_preview_sits_where_a_place_click_would_set_its_voxel() {
        let (w, cam) = floor();
        let place = edit_for_click(&w, &cam, (65, 65), Click::Place(3)).unwrap();
        let locals = place_preview(&w, &cam, (65, 65), 3);
        assert_eq!(locals.len(), 1);
        let pose = locals.get(0).unwrap();
        let [x, y, z] = pose.pos;
        assert_eq!(place, format!(r#"{{"op":"set","voxels":[[{x},{y},{z},3]]}}"#));
        // Undefined materials and the sky show nothing.
        assert!(place_preview(&w, &cam, (65, 65), 999).is_empty());
        let mut up = cam;
        up.pitch = 80.0;
        assert!(place_preview(&w, &up, (65, 65), 3).is_empty());
    }
}

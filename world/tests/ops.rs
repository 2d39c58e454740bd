//! The ops layer from the outside: ops-JSON lines → batches → voxel writes, as the world,
//! the CLI and replay scripts use it (BRIEF §4).

use naadf_world::model::ModelTable;
use naadf_world::ops::{Batch, Canvas, DenseCanvas, EditError, Limits, Op, apply_batch};
use naadf_world::{Material, MaterialTable, WorldSize};
use std::collections::HashMap;

fn size() -> WorldSize {
    WorldSize::new(64, 128, 64).unwrap()
}

/// A batch overlay over a read-only base, the way the world applies a batch: writes go to
/// the overlay, reads see them; the base stays as it was until the caller commits.
struct Overlay<'a> {
    base: &'a DenseCanvas,
    writes: HashMap<[u32; 3], u16>,
}

impl Canvas for Overlay<'_> {
    fn size(&self) -> WorldSize {
        self.base.size()
    }
    fn get(&self, p: [u32; 3]) -> u16 {
        self.writes.get(&p).copied().unwrap_or_else(|| self.base.get(p))
    }
    fn set(&mut self, p: [u32; 3], material: u16) {
        self.writes.insert(p, material);
    }
}

/// Applies `line` through an overlay; on success commits it into `base`.
fn apply_line(
    line: &str,
    base: &mut DenseCanvas,
    materials: &mut MaterialTable,
    models: &mut ModelTable,
) -> Result<(), EditError> {
    let batch = Batch::parse_line(line)?;
    let (mut mats, mut mods) = (materials.clone(), models.clone());
    let writes = {
        let mut overlay = Overlay {
            base,
            writes: HashMap::new(),
        };
        apply_batch(&batch, &mut overlay, &mut mats, &mut mods, &Limits::default())?;
        overlay.writes
    };
    for (p, m) in writes {
        base.set(p, m);
    }
    *materials = mats;
    *models = mods;
    Ok(())
}

fn count(c: &DenseCanvas, m: u16) -> usize {
    c.voxels().iter().filter(|&&v| v == m).count()
}

#[test]
fn a_session_of_lines() {
    let mut world = DenseCanvas::new(size());
    let mut mats = MaterialTable::default();
    let mut models = ModelTable::default();
    let lines = [
        r#"{"batch":[{"op":"define_material","id":1,"kind":"diffuse","albedo":[0.5,0.5,0.5]},{"op":"define_material","id":2,"kind":"emissive","albedo":[1,0.9,0.7],"emission":20},{"op":"box","min":[0,0,0],"max":[64,8,64],"material":1}]}"#,
        r#"{"op":"sphere","center":[32,8,32],"radius":6,"material":0}"#,
        r#"{"op":"paint","center":[0,0,0],"radius":4,"material":2}"#,
        r#"{"op":"set","voxels":[[1,100,1,2],[2,100,1,1]]}"#,
        r#"{"op":"define_model","name":"lamp","size":[1,3,1],"voxels":[[0,0,0,1],[0,1,0,1],[0,2,0,2]]}"#,
        r#"{"op":"place","model":"lamp","at":[10,8,10]}"#,
        r#"{"op":"copy","min":[10,8,10],"max":[11,11,11],"to":[20,8,20]}"#,
        r#"{"op":"flood_paint","start":[5,100,1],"material":2,"limit":10}"#,
    ];
    let mut results = Vec::new();
    for line in lines {
        results.push(apply_line(line, &mut world, &mut mats, &mut models).map_err(|e| e.to_string()));
    }
    // The last line starts at an empty voxel.
    let last = results.pop().unwrap().unwrap_err();
    assert!(
        last.contains("op 0 (flood_paint)") && last.contains("empty voxel"),
        "{last}"
    );
    for r in results {
        r.unwrap();
    }
    assert!(mats.contains(2) && !mats.contains(3));
    assert_eq!(world.get([32, 7, 32]), 0, "carved by the sphere");
    assert_eq!(world.get([0, 0, 0]), 2, "painted");
    assert_eq!(world.get([0, 20, 0]), 0, "paint doesn't add voxels");
    assert_eq!([world.get([10, 10, 10]), world.get([20, 10, 20])], [2, 2]);
    assert_eq!([world.get([1, 100, 1]), world.get([2, 100, 1])], [2, 1]);
    // Flood from a lamp top: it and the copy's top aren't connected.
    apply_line(
        r#"{"op":"flood_paint","start":[10,10,10],"material":1,"limit":1}"#,
        &mut world,
        &mut mats,
        &mut models,
    )
    .unwrap();
    assert_eq!([world.get([10, 10, 10]), world.get([20, 10, 20])], [1, 2]);
}

#[test]
fn a_rejected_batch_changes_nothing() {
    let mut world = DenseCanvas::new(size());
    let mut mats = MaterialTable::from_materials(&[Material::diffuse([0.5; 3])]).unwrap();
    let mut models = ModelTable::default();
    let before = world.clone();
    // The second op names material 7, which nobody defined.
    let e = apply_line(
        r#"{"batch":[{"op":"box","min":[0,0,0],"max":[9,9,9],"material":1},{"op":"define_material","id":3,"kind":"metal","albedo":[1,1,1],"roughness":0.2},{"op":"sphere","center":[5,5,5],"radius":3,"material":7}]}"#,
        &mut world,
        &mut mats,
        &mut models,
    )
    .unwrap_err();
    let msg = e.to_string();
    assert!(
        matches!(
            e,
            EditError::Invalid {
                index: 2,
                op: "sphere",
                ..
            }
        ),
        "{msg}"
    );
    assert_eq!(msg, "op 2 (sphere): material 7 is not defined");
    assert!(world == before);
    assert!(!mats.contains(3), "the batch's table copy was discarded");

    // Out-of-world set: rejected whole, naming the coordinate.
    let e = apply_line(
        r#"{"op":"set","voxels":[[0,0,0,1],[64,0,0,1]]}"#,
        &mut world,
        &mut mats,
        &mut models,
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        "op 0 (set): voxel 1 at [64, 0, 0] lies outside the world 64×128×64"
    );
    assert!(world == before);
}

#[test]
fn flood_limit_leaves_the_world_alone() {
    let mut world = DenseCanvas::new(size());
    let mut mats = MaterialTable::from_materials(&[Material::diffuse([0.5; 3]); 2]).unwrap();
    let mut models = ModelTable::default();
    apply_line(
        r#"{"op":"box","min":[0,0,0],"max":[64,1,64],"material":1}"#,
        &mut world,
        &mut mats,
        &mut models,
    )
    .unwrap();
    let before = world.clone();
    let e = apply_line(
        r#"{"op":"flood_paint","start":[3,0,3],"material":2,"limit":4095}"#,
        &mut world,
        &mut mats,
        &mut models,
    )
    .unwrap_err();
    assert!(
        matches!(
            e,
            EditError::Limit {
                index: 0,
                op: "flood_paint",
                ..
            }
        ),
        "{e}"
    );
    assert!(world == before);
    apply_line(
        r#"{"op":"flood_paint","start":[3,0,3],"material":2,"limit":4096}"#,
        &mut world,
        &mut mats,
        &mut models,
    )
    .unwrap();
    assert_eq!(count(&world, 2), 4096);
}

#[test]
fn overlay_and_dense_agree() {
    // The same batch through an overlay and directly on a dense canvas.
    let line = r#"{"batch":[{"op":"define_material","id":4,"kind":"mirror","albedo":[1,1,1]},{"op":"sphere","center":[20.3,30.1,40.7],"radius":17.5,"material":4},{"op":"copy","min":[10,20,30],"max":[40,50,60],"to":[15,25,35]},{"op":"paint","center":[30,40,50],"radius":9,"material":2},{"op":"box","min":[-5,-5,-5],"max":[7,200,7],"material":0},{"op":"flood_paint","start":[20,30,40],"material":1,"limit":100000}]}"#;
    let mut mats = MaterialTable::from_materials(&[Material::diffuse([0.5; 3]); 2]).unwrap();
    let mut models = ModelTable::default();
    let mut via_overlay = DenseCanvas::new(size());
    apply_line(line, &mut via_overlay, &mut mats, &mut models).unwrap();
    let mut direct = DenseCanvas::new(size());
    let mut mats2 = MaterialTable::from_materials(&[Material::diffuse([0.5; 3]); 2]).unwrap();
    let batch = Batch::parse_line(line).unwrap();
    apply_batch(
        &batch,
        &mut direct,
        &mut mats2,
        &mut ModelTable::default(),
        &Limits::default(),
    )
    .unwrap();
    assert!(via_overlay == direct);
    assert_eq!(mats, mats2);
    assert!(count(&direct, 1) > 1000 && count(&direct, 2) > 0);
}

#[test]
fn canonical_lines() {
    let batch = Batch {
        ops: vec![
            Op::Box {
                min: [0, -1, 2],
                max: [3, 4, 5],
                material: 6,
            },
            Op::Sphere {
                center: [1.5, 2.0, -3.25],
                radius: 4.0,
                material: 0,
            },
            Op::SpawnEntity {
                id: 9,
                model: "car".into(),
                pos: [1.0, 2.0, 3.0],
                rot: [0.0, 0.0, 0.0, 1.0],
            },
        ],
    };
    let line = batch.to_json_line();
    assert_eq!(
        line,
        r#"{"batch":[{"op":"box","min":[0,-1,2],"max":[3,4,5],"material":6},{"op":"sphere","center":[1.5,2.0,-3.25],"radius":4.0,"material":0},{"op":"spawn_entity","id":9,"model":"car","pos":[1.0,2.0,3.0],"rot":[0.0,0.0,0.0,1.0]}]}"#
    );
    assert_eq!(Batch::parse_line(&line).unwrap(), batch);
    assert!(batch.has_entity_ops());
    // Entity ops are the world's: the canvas layer refuses them after checking their shape.
    let mut c = DenseCanvas::new(size());
    let e = apply_batch(
        &batch,
        &mut c,
        &mut MaterialTable::from_materials(&[Material::diffuse([0.5; 3]); 6]).unwrap(),
        &mut ModelTable::default(),
        &Limits::default(),
    )
    .unwrap_err();
    assert_eq!(e.to_string(), "op 2 (spawn_entity): model 'car' is not defined");
}

#[test]
fn parse_errors_name_the_problem() {
    for (line, want) in [
        (r#"{"op":"teleport","id":1}"#, "unknown variant `teleport`"),
        (
            r#"{"op":"box","min":[0,0,0],"max":[1,1,1],"material":1,"mat":2}"#,
            "unknown field `mat`",
        ),
        (
            r#"{"batch":[{"op":"box","min":[0,0],"max":[1,1,1],"material":1}]}"#,
            "op 0 (box)",
        ),
        (r#"{"op":"set","voxels":[[1,2,3,4]]"#, "EOF"),
    ] {
        let e = Batch::parse_line(line).unwrap_err();
        assert!(matches!(e, EditError::Parse(_)), "{e:?}");
        assert!(e.to_string().contains(want), "{line}: {e}");
    }
}

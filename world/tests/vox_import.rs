//! MagicaVoxel `.vox` import: files written with dot_vox itself, checked voxel by voxel
//! against an independent oracle (f64 matrices from dot_vox's own rotation decoding),
//! plus error cases, fuzzing, and the shared sample files when present.

use dot_vox::{
    Color, DEFAULT_INDEX_MAP, DEFAULT_PALETTE, Dict, DotVoxData, Frame, Layer, Model, SceneNode, ShapeModel, Size,
    Voxel,
};
use naadf_world::cell::CHUNK_VOXELS;
use naadf_world::import::vox::{TiledVox, VoxScene, import_vox};
use naadf_world::stats::WorldStats;
use naadf_world::{ChunkSource, MaterialKind, MaterialTable, World, WorldError, WorldSize};
use proptest::prelude::*;
use std::collections::HashMap;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

// ---------------------------------------------------------------------------------------
// Building files.

fn dict(pairs: &[(&str, &str)]) -> Dict {
    pairs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
}

/// A model; voxels given with their stored colour index (1..=255).
fn model(size: [u32; 3], voxels: &[([u8; 3], u8)]) -> Model {
    Model {
        size: Size {
            x: size[0],
            y: size[1],
            z: size[2],
        },
        voxels: voxels
            .iter()
            .map(|&([x, y, z], c)| Voxel { x, y, z, i: c - 1 })
            .collect(),
    }
}

/// A model with a deterministic pseudo-random fill (about half solid).
fn noisy_model(size: [u32; 3], seed: u32) -> Model {
    let mut v = Vec::new();
    let mut h = seed.wrapping_mul(0x9E37_79B9) | 1;
    for z in 0..size[2] {
        for y in 0..size[1] {
            for x in 0..size[0] {
                h ^= h << 13;
                h ^= h >> 17;
                h ^= h << 5;
                if h & 1 == 0 {
                    v.push(([x as u8, y as u8, z as u8], (h >> 8) as u8 % 255 + 1));
                }
            }
        }
    }
    model(size, &v)
}

fn trn(child: u32, frame: &[(&str, &str)]) -> SceneNode {
    trn_full(child, frame, &[], 0)
}

fn trn_full(child: u32, frame: &[(&str, &str)], attrs: &[(&str, &str)], layer: u32) -> SceneNode {
    SceneNode::Transform {
        attributes: dict(attrs),
        frames: vec![Frame::new(dict(frame))],
        child,
        layer_id: layer,
    }
}

fn grp(children: &[u32]) -> SceneNode {
    SceneNode::Group {
        attributes: Dict::new(),
        children: children.to_vec(),
    }
}

fn shp(model: u32) -> SceneNode {
    SceneNode::Shape {
        attributes: Dict::new(),
        models: vec![ShapeModel {
            model_id: model,
            attributes: Dict::new(),
        }],
    }
}

fn file(models: Vec<Model>, scenes: Vec<SceneNode>) -> DotVoxData {
    DotVoxData {
        version: 150,
        index_map: DEFAULT_INDEX_MAP.to_vec(),
        models,
        palette: DEFAULT_PALETTE.to_vec(),
        materials: vec![],
        scenes,
        layers: vec![],
    }
}

fn bytes(d: &DotVoxData) -> Vec<u8> {
    let mut out = Vec::new();
    d.write_vox(&mut out).unwrap();
    out
}

fn import(d: &DotVoxData) -> VoxScene {
    VoxScene::from_bytes(&bytes(d)).unwrap()
}

fn import_err(b: &[u8]) -> String {
    match VoxScene::from_bytes(b) {
        Err(WorldError::Import(m)) => m,
        other => panic!("expected an import error, got {other:?}"),
    }
}

// ---------------------------------------------------------------------------------------
// The oracle: MagicaVoxel's placement with f64 matrices from dot_vox's rotation decoding.

type Mat = [[f64; 3]; 3];
/// A placed model: its index and accumulated transform (`None`: no scene graph).
type Placed = (usize, Option<(Mat, [f64; 3])>);
const IDENT: Mat = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

fn mat_of(byte: u8) -> Mat {
    let cols = dot_vox::Rotation::from_byte(byte).to_cols_array_2d();
    std::array::from_fn(|r| std::array::from_fn(|c| f64::from(cols[c][r])))
}

fn mul(a: Mat, b: Mat) -> Mat {
    std::array::from_fn(|r| std::array::from_fn(|c| (0..3).map(|k| a[r][k] * b[k][c]).sum()))
}

fn mv(a: Mat, v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|r| (0..3).map(|k| a[r][k] * v[k]).sum())
}

fn is_hidden(d: &Dict) -> bool {
    d.get("_hidden").map(String::as_str) == Some("1")
}

/// Placements `(model, Some((M, t)))` in scene order.
fn oracle_placements(d: &DotVoxData) -> Vec<Placed> {
    if d.scenes.is_empty() {
        return (0..d.models.len()).map(|m| (m, None)).collect();
    }
    fn walk(d: &DotVoxData, n: u32, m: Mat, t: [f64; 3], out: &mut Vec<Placed>) {
        match &d.scenes[n as usize] {
            SceneNode::Transform {
                attributes,
                frames,
                child,
                layer_id,
            } => {
                let layer_hidden = d.layers.get(*layer_id as usize).is_some_and(|l| l.hidden());
                if is_hidden(attributes) || layer_hidden {
                    return;
                }
                let f = &frames[0].attributes;
                let r = f.get("_r").map_or(IDENT, |r| mat_of(r.parse().unwrap()));
                let lt: Vec<f64> = f
                    .get("_t")
                    .map_or(vec![0.0; 3], |s| s.split(' ').map(|p| p.parse().unwrap()).collect());
                let rt = mv(m, [lt[0], lt[1], lt[2]]);
                walk(d, *child, mul(m, r), std::array::from_fn(|i| rt[i] + t[i]), out);
            }
            SceneNode::Group { attributes, children } => {
                if !is_hidden(attributes) {
                    for &c in children {
                        walk(d, c, m, t, out);
                    }
                }
            }
            SceneNode::Shape { models, .. } => {
                out.push((models[0].model_id as usize, Some((m, t))));
            }
        }
    }
    let mut out = Vec::new();
    walk(d, 0, IDENT, [0.0; 3], &mut out);
    out
}

/// Vox-space voxel of model voxel `p` under a placement.
fn place(size: [u32; 3], p: [u32; 3], xf: Option<(Mat, [f64; 3])>) -> [i64; 3] {
    match xf {
        None => p.map(i64::from),
        Some((m, t)) => {
            let c: [f64; 3] = std::array::from_fn(|i| f64::from(p[i]) - f64::from(size[i] / 2) + 0.5);
            let w = mv(m, c);
            std::array::from_fn(|i| (w[i] + t[i]).floor() as i64)
        }
    }
}

/// The expected extent (world axes) and solid voxels (world axes, from the min corner).
fn oracle(d: &DotVoxData) -> ([u32; 3], HashMap<[u32; 3], u16>) {
    let swap = |v: [i64; 3]| [v[0], v[2], v[1]];
    let mut min = [i64::MAX; 3];
    let mut max = [i64::MIN; 3];
    let mut solid: Vec<([i64; 3], u16)> = Vec::new();
    for (k, xf) in oracle_placements(d) {
        let m = &d.models[k];
        let s = [m.size.x, m.size.y, m.size.z];
        for corner in 0..8 {
            let p = std::array::from_fn(|a| if corner >> a & 1 == 1 { s[a] - 1 } else { 0 });
            let w = swap(place(s, p, xf));
            for a in 0..3 {
                min[a] = min[a].min(w[a]);
                max[a] = max[a].max(w[a]);
            }
        }
        for v in &m.voxels {
            let w = swap(place(s, [v.x, v.y, v.z].map(u32::from), xf));
            solid.push((w, u16::from(v.i) + 1));
        }
    }
    let mut map = HashMap::new();
    for (w, c) in solid {
        map.insert(std::array::from_fn(|a| (w[a] - min[a]) as u32), c);
    }
    (std::array::from_fn(|a| (max[a] - min[a] + 1) as u32), map)
}

/// The brute-force reference source: the oracle's voxels rasterised into one dense volume
/// of the whole world, with no empty-chunk hints, so construction sees every chunk.
struct Dense {
    size: WorldSize,
    materials: MaterialTable,
    /// `x + sx·(y + sy·z)`.
    voxels: Vec<u16>,
}

impl Dense {
    fn rasterise(size: WorldSize, materials: MaterialTable, solid: &HashMap<[u32; 3], u16>) -> Self {
        let [sx, sy, sz] = size.voxels().map(|v| v as usize);
        let mut voxels = vec![0; sx * sy * sz];
        for (p, &m) in solid {
            voxels[p[0] as usize + sx * (p[1] as usize + sy * p[2] as usize)] = m;
        }
        Dense {
            size,
            materials,
            voxels,
        }
    }
}

impl ChunkSource for Dense {
    fn size(&self) -> WorldSize {
        self.size
    }

    fn materials(&self) -> MaterialTable {
        self.materials.clone()
    }

    fn fill_chunk(&self, c: [u32; 3], out: &mut [u16; CHUNK_VOXELS]) {
        let [sx, sy, _] = self.size.voxels().map(|v| v as usize);
        for (i, v) in out.iter_mut().enumerate() {
            let p: [usize; 3] = std::array::from_fn(|a| c[a] as usize * 16 + (i >> (4 * a) & 15));
            *v = self.voxels[p[0] + sx * (p[1] + sy * p[2])];
        }
    }
}

/// Builds the world and checks it voxel by voxel against the oracle (and the scene's own
/// `material_at`), and byte for byte (digest) against the world built from the oracle's
/// dense rasterisation.
fn check_against_oracle(d: &DotVoxData) -> (VoxScene, World) {
    let scene = import(d);
    let (extent, expected) = oracle(d);
    assert_eq!(scene.extent(), extent);
    let size = scene.world_size().unwrap();
    assert_eq!(size, WorldSize::round_up(extent[0], extent[1], extent[2]).unwrap());
    assert_eq!(ChunkSource::size(&scene), size);
    let world = World::build(&scene, &|_| {}).unwrap();
    let [sx, sy, sz] = size.voxels();
    for z in 0..sz {
        for y in 0..sy {
            for x in 0..sx {
                let want = expected.get(&[x, y, z]).copied().unwrap_or(0);
                assert_eq!(world.material_at([x, y, z]), want, "world voxel {x},{y},{z}");
                assert_eq!(scene.material_at([x, y, z]), want, "scene voxel {x},{y},{z}");
            }
        }
    }
    let dense = World::build(&Dense::rasterise(size, scene.materials(), &expected), &|_| {}).unwrap();
    assert_eq!(world.digest(), dense.digest(), "sparse and dense construction differ");
    (scene, world)
}

// ---------------------------------------------------------------------------------------
// Mapping.

#[test]
fn single_model_axis_swap() {
    let m = model(
        [5, 3, 7],
        &[
            ([0, 0, 0], 1),
            ([4, 0, 0], 2),
            ([0, 2, 0], 3),
            ([0, 0, 6], 4),
            ([3, 1, 5], 255),
        ],
    );
    let d = file(vec![m], vec![]);
    let (scene, world) = check_against_oracle(&d);
    assert_eq!(scene.extent(), [5, 7, 3]);
    assert_eq!(world.size(), WorldSize::new(64, 64, 64).unwrap());
    // vox (x, y, z) -> world (x, z, y), literally.
    assert_eq!(world.material_at([0, 0, 0]), 1);
    assert_eq!(world.material_at([4, 0, 0]), 2);
    assert_eq!(world.material_at([0, 0, 2]), 3);
    assert_eq!(world.material_at([0, 6, 0]), 4);
    assert_eq!(world.material_at([3, 5, 1]), 255);
    assert_eq!(world.material_at([0, 2, 0]), 0);
}

#[test]
fn large_model_spans_chunks() {
    let d = file(vec![noisy_model([70, 40, 33], 7)], vec![]);
    let (scene, world) = check_against_oracle(&d);
    assert_eq!(scene.extent(), [70, 33, 40]);
    assert_eq!(world.size().voxels(), [128, 64, 64]);
}

#[test]
fn models_without_scene_graph_overlap_later_wins() {
    let full = model(
        [2, 2, 2],
        &[
            ([0, 0, 0], 5),
            ([1, 0, 0], 5),
            ([0, 1, 0], 5),
            ([1, 1, 0], 5),
            ([0, 0, 1], 5),
            ([1, 0, 1], 5),
            ([0, 1, 1], 5),
            ([1, 1, 1], 5),
        ],
    );
    let sparse = model([3, 1, 1], &[([0, 0, 0], 9)]);
    let s = import(&file(vec![full, sparse], vec![]));
    assert_eq!(s.extent(), [3, 2, 2]);
    assert_eq!(s.material_at([0, 0, 0]), 9, "later solid voxel overwrites");
    assert_eq!(s.material_at([1, 0, 0]), 5, "later empty voxel does not erase");
    assert_eq!(s.material_at([2, 0, 0]), 0);
    let d = file(
        vec![model([1, 1, 1], &[([0, 0, 0], 9)]), model([1, 1, 1], &[([0, 0, 0], 3)])],
        vec![],
    );
    check_against_oracle(&d);
    assert_eq!(import(&d).material_at([0, 0, 0]), 3);
}

#[test]
fn scene_graph_translations_literal() {
    // Model 0 (3³, one voxel at its corner) at _t (10,0,0): pivot (1,1,1), so the voxel
    // is at vox (9,-1,-1). Model 1 (1³) at the origin. Scene box vox (0..11, -1..1, -1..1).
    let d = file(
        vec![model([3, 3, 3], &[([0, 0, 0], 7)]), model([1, 1, 1], &[([0, 0, 0], 8)])],
        vec![
            trn(1, &[]),
            grp(&[2, 4]),
            trn(3, &[("_t", "10 0 0")]),
            shp(0),
            trn(5, &[("_t", "0 0 0")]),
            shp(1),
        ],
    );
    let (scene, world) = check_against_oracle(&d);
    assert_eq!(scene.extent(), [12, 3, 3]);
    assert_eq!(scene.instance_count(), 2);
    assert_eq!(world.material_at([9, 0, 0]), 7);
    assert_eq!(world.material_at([0, 1, 1]), 8);
}

#[test]
fn scene_graph_rotation_literal() {
    // _r = 17: rows (-y, x, z), a quarter turn about z. A 3×1×1 bar (pivot x = 1) turns
    // into a bar along vox y at x = -1 (the reversed row shifts by one).
    let d = file(
        vec![model([3, 1, 1], &[([0, 0, 0], 1), ([2, 0, 0], 3)])],
        vec![trn(1, &[]), grp(&[2]), trn(3, &[("_r", "17")]), shp(0)],
    );
    let (scene, world) = check_against_oracle(&d);
    assert_eq!(scene.extent(), [1, 1, 3]);
    assert_eq!(world.material_at([0, 0, 0]), 1);
    assert_eq!(world.material_at([0, 0, 2]), 3);
}

#[test]
fn multi_model_scene_graph_with_rotations_and_nesting() {
    let d = file(
        vec![
            noisy_model([4, 3, 2], 1),
            noisy_model([5, 2, 3], 2),
            noisy_model([3, 4, 5], 3),
        ],
        vec![
            trn(1, &[]),
            grp(&[2, 4, 6, 10, 12]),
            trn(3, &[("_t", "10 0 0")]),
            shp(0),
            trn(5, &[("_t", "-5 3 2"), ("_r", "17")]),
            shp(1),
            // A nested group under a rotated, translated transform.
            trn(7, &[("_t", "0 20 -4"), ("_r", "24")]),
            grp(&[8]),
            trn(9, &[("_t", "3 1 0"), ("_r", "38")]),
            shp(2),
            // The same model again, mirrored in x.
            trn(11, &[("_t", "1 1 1"), ("_r", "20")]),
            shp(0),
            // Every row negative (a point reflection).
            trn(13, &[("_t", "-2 -7 9"), ("_r", "116")]),
            shp(2),
        ],
    );
    let (scene, _) = check_against_oracle(&d);
    assert_eq!(scene.instance_count(), 5);
}

#[test]
fn every_rotation_byte_matches_the_oracle() {
    let mut scenes = vec![trn(1, &[]), grp(&[])];
    let mut children = Vec::new();
    for b in 0..128u8 {
        let (c0, c1) = (b & 3, b >> 2 & 3);
        if c0 > 2 || c1 > 2 || c0 == c1 {
            continue;
        }
        let id = scenes.len() as u32;
        children.push(id);
        let t = format!(
            "{} {} {}",
            (b % 7) as i32 * 9 - 30,
            (b % 5) as i32 * 11,
            -(b as i32 % 3) * 13
        );
        scenes.push(trn(id + 1, &[("_t", &t), ("_r", &b.to_string())]));
        scenes.push(shp(u32::from(b) % 3));
    }
    assert_eq!(children.len(), 48);
    scenes[1] = grp(&children);
    let d = file(
        vec![
            noisy_model([4, 3, 2], 11),
            noisy_model([5, 2, 3], 12),
            noisy_model([3, 4, 6], 13),
        ],
        scenes,
    );
    let (scene, _) = check_against_oracle(&d);
    assert_eq!(scene.instance_count(), 48);
}

#[test]
fn hidden_nodes_and_layers_are_skipped() {
    let mut d = file(
        vec![
            model([1, 1, 1], &[([0, 0, 0], 1)]),
            model([1, 1, 1], &[([0, 0, 0], 2)]),
            model([1, 1, 1], &[([0, 0, 0], 3)]),
        ],
        vec![
            trn(1, &[]),
            grp(&[2, 4, 6]),
            trn_full(3, &[("_t", "5 0 0")], &[("_hidden", "1")], 0),
            shp(0),
            trn_full(5, &[("_t", "9 0 0")], &[], 1),
            shp(1),
            trn(7, &[("_t", "0 0 0")]),
            shp(2),
        ],
    );
    d.layers = vec![
        Layer {
            attributes: Dict::new(),
        },
        Layer {
            attributes: dict(&[("_hidden", "1")]),
        },
    ];
    let (scene, _) = check_against_oracle(&d);
    assert_eq!(scene.instance_count(), 1);
    assert_eq!(scene.extent(), [1, 1, 1]);
    assert_eq!(scene.material_at([0, 0, 0]), 3);
}

// ---------------------------------------------------------------------------------------
// Materials.

#[test]
fn palette_becomes_materials() {
    let mut d = file(vec![model([1, 1, 1], &[([0, 0, 0], 200)])], vec![]);
    d.palette = (0..256u32)
        .map(|i| Color {
            r: i as u8,
            g: (255 - i) as u8,
            b: (i * 7 % 256) as u8,
            a: 255,
        })
        .collect();
    d.materials = vec![
        dot_vox::Material {
            id: 7,
            properties: dict(&[("_type", "_emit"), ("_emit", "0.5"), ("_flux", "1")]),
        },
        dot_vox::Material {
            id: 8,
            properties: dict(&[("_type", "_emit"), ("_emit", "2")]),
        },
        dot_vox::Material {
            id: 9,
            properties: dict(&[("_type", "_metal"), ("_metal", "1"), ("_emit", "3")]),
        },
        dot_vox::Material {
            id: 10,
            properties: dict(&[("_type", "_emit"), ("_emit", "0")]),
        },
    ];
    let scene = import(&d);
    let t = scene.materials();
    assert_eq!(t.len(), 256, "entry 0 plus materials 1..=255");
    assert_eq!(ChunkSource::materials(&scene), t);
    let close = |a: f32, b: f32| (a - b).abs() <= 1e-3 * b.max(1.0) + 1e-4;
    for k in 1..=255u16 {
        let m = t.get(k).unwrap();
        let c = d.palette[usize::from(k) - 1];
        let want = [c.r, c.g, c.b].map(|v| (f32::from(v) / 255.0).powf(2.2));
        for ch in 0..3 {
            assert!(
                close(m.albedo[ch], want[ch]),
                "material {k}: {:?} vs {want:?}",
                m.albedo
            );
        }
        match k {
            7 => {
                assert_eq!(m.kind, MaterialKind::Emissive);
                assert!(close(m.emission, 0.5 * 4.0 * 5.0), "{}", m.emission);
            }
            8 => {
                assert_eq!(m.kind, MaterialKind::Emissive);
                assert!(close(m.emission, 10.0), "{}", m.emission);
            }
            _ => assert_eq!(m.kind, MaterialKind::Diffuse, "material {k}"),
        }
    }
    // The voxel keeps its stored colour index.
    assert_eq!(scene.material_at([0, 0, 0]), 200);
    let w = World::build(&scene, &|_| {}).unwrap();
    assert_eq!(w.material_at([0, 0, 0]), 200);
    assert_eq!(w.materials(), &t);
}

// ---------------------------------------------------------------------------------------
// Tiling and the file path.

/// Builds `scene` tiled into a world of `size` and checks every voxel: the scene repeats
/// with its extent as period in X and Z, and appears once in Y.
fn assert_tiles(scene: &VoxScene, size: WorldSize) {
    let e = scene.extent();
    let w = World::build(&TiledVox::new(scene.clone(), size), &|_| {}).unwrap();
    assert_eq!(w.size(), size);
    let [sx, sy, sz] = size.voxels();
    for z in 0..sz {
        for y in 0..sy {
            for x in 0..sx {
                let want = if y < e[1] {
                    scene.material_at([x % e[0], y, z % e[2]])
                } else {
                    0
                };
                assert_eq!(w.material_at([x, y, z]), want, "{x},{y},{z}");
            }
        }
    }
}

#[test]
fn tiled_scene_repeats_in_x_and_z() {
    let scene = import(&file(vec![noisy_model([5, 7, 3], 21)], vec![]));
    assert_eq!(scene.extent(), [5, 3, 7]);
    assert_tiles(&scene, WorldSize::new(128, 64, 64).unwrap());
}

#[test]
fn tiled_scene_with_wide_period() {
    let scene = import(&file(vec![noisy_model([40, 20, 17], 5)], vec![]));
    assert_tiles(&scene, WorldSize::new(128, 64, 128).unwrap());
}

#[test]
fn import_vox_from_a_file() {
    let d = file(vec![noisy_model([9, 8, 7], 4)], vec![]);
    let path = std::env::temp_dir().join(format!("naadf-vox-import-{}.vox", std::process::id()));
    std::fs::write(&path, bytes(&d)).unwrap();
    let chunks = std::sync::atomic::AtomicU64::new(0);
    let w = import_vox(&path, &|n| {
        chunks.fetch_max(n, std::sync::atomic::Ordering::Relaxed);
    })
    .unwrap();
    std::fs::remove_file(&path).ok();
    assert_eq!(chunks.into_inner(), 64);
    let direct = World::build(&import(&d), &|_| {}).unwrap();
    assert_eq!(w.digest(), direct.digest());
    let missing = Path::new("/nonexistent/naadf/missing.vox");
    assert!(matches!(VoxScene::open(missing), Err(WorldError::Io { .. })));
    assert!(matches!(import_vox(missing, &|_| {}), Err(WorldError::Io { .. })));
}

// ---------------------------------------------------------------------------------------
// Errors.

#[test]
fn clear_errors_for_bad_files() {
    assert!(import_err(b"").contains("VOX"));
    assert!(import_err(b"hello world, not a vox").contains("VOX"));
    assert!(import_err(b"VOX \x96\0\0\0").contains("malformed"));
    let e = import_err(&bytes(&file(vec![], vec![])));
    assert!(e.contains("no models"), "{e}");

    let e = import_err(&bytes(&file(vec![model([0, 1, 1], &[])], vec![])));
    assert!(e.contains("zero size"), "{e}");
    let e = import_err(&bytes(&file(vec![model([257, 1, 1], &[([0, 0, 0], 1)])], vec![])));
    assert!(e.contains("at most 256"), "{e}");
    let e = import_err(&bytes(&file(vec![model([2, 2, 2], &[([5, 0, 0], 1)])], vec![])));
    assert!(e.contains("outside its size"), "{e}");

    let one = || vec![model([1, 1, 1], &[([0, 0, 0], 1)])];
    let e = import_err(&bytes(&file(one(), vec![trn(1, &[]), shp(3)])));
    assert!(e.contains("refers to model 3"), "{e}");
    let e = import_err(&bytes(&file(one(), vec![trn(5, &[])])));
    assert!(e.contains("refers to node 5"), "{e}");
    for r in ["0", "3", "15", "300", "x"] {
        let e = import_err(&bytes(&file(one(), vec![trn(1, &[("_r", r)]), shp(0)])));
        assert!(e.contains("rotation"), "{r}: {e}");
    }
    for t in ["1 2", "a b c", "1 2 3 4", "5000000000 0 0"] {
        let e = import_err(&bytes(&file(one(), vec![trn(1, &[("_t", t)]), shp(0)])));
        assert!(e.contains("translation"), "{t}: {e}");
    }
    // Everything hidden.
    let e = import_err(&bytes(&file(
        one(),
        vec![trn_full(1, &[], &[("_hidden", "1")], 0), shp(0)],
    )));
    assert!(e.contains("no visible models"), "{e}");
}

#[test]
fn cyclic_and_exploding_scene_graphs_are_refused() {
    let one = || vec![model([1, 1, 1], &[([0, 0, 0], 1)])];
    let e = import_err(&bytes(&file(one(), vec![trn(1, &[]), grp(&[0])])));
    assert!(e.contains("cyclic"), "{e}");
    // 40 levels, each listing the next level twice: 2^40 paths.
    let mut scenes = Vec::new();
    for level in 0..40u32 {
        let id = 2 * level;
        scenes.push(trn(id + 1, &[]));
        scenes.push(grp(&[id + 2, id + 2]));
    }
    scenes.push(trn(81, &[]));
    scenes.push(shp(0));
    let e = import_err(&bytes(&file(one(), scenes)));
    assert!(e.contains("more than"), "{e}");
}

/// Two placements translated by `a` and `b`: of models 0 and 1, or twice of model 0 when
/// there is only one.
fn two_apart(models: Vec<Model>, a: &str, b: &str) -> DotVoxData {
    let second = (models.len() - 1).min(1) as u32;
    file(
        models,
        vec![
            trn(1, &[]),
            grp(&[2, 4]),
            trn(3, &[("_t", a)]),
            shp(0),
            trn(5, &[("_t", b)]),
            shp(second),
        ],
    )
}

#[test]
fn scenes_larger_than_the_largest_world_are_refused() {
    let one = || vec![model([1, 1, 1], &[([0, 0, 0], 1)])];
    let far = |t: &str| two_apart(one(), "0 0 0", t);
    let e = import_err(&bytes(&far("20000 0 0")));
    assert!(e.contains("larger than the largest world"), "{e}");
    assert!(e.contains("20001×1×1") && e.contains("16384×4096×16384"), "{e}");
    // The widest translations: an extent of 2³² per axis, which no 32-bit size can hold
    // (cast down, it wraps to 0 and the placements would lie outside the world they get).
    // Refused before anything is sized from it.
    let (lo, hi) = (i32::MIN, i32::MAX);
    let e = import_err(&bytes(&two_apart(
        one(),
        &format!("{lo} {lo} {lo}"),
        &format!("{hi} {hi} {hi}"),
    )));
    assert!(e.contains("4294967296×4294967296×4294967296"), "{e}");
    // vox z is world y, limited to 4096.
    let e = import_err(&bytes(&far("0 0 4096")));
    assert!(e.contains("larger than the largest world"), "{e}");
    // Just fits: 16384 in x, 4096 in y.
    let s = import(&far("16383 0 4095"));
    assert_eq!(s.extent(), [16384, 4096, 1]);
    assert_eq!(s.world_size().unwrap().voxels(), [16384, 4096, 64]);
    assert_eq!(s.material_at([16383, 4095, 0]), 1);
}

/// Two 8³ models 16000 voxels apart, from a file of under 4 KB: the empty space between
/// them costs only its chunk cells; block arrays and voxel groups exist only for the two
/// chunks the models touch.
#[test]
fn far_apart_models_build_only_their_chunks() {
    let d = two_apart(
        vec![noisy_model([8, 8, 8], 31), noisy_model([8, 8, 8], 32)],
        "0 0 0",
        "16000 0 0",
    );
    let b = bytes(&d);
    assert!(b.len() < 4096, "{} bytes", b.len());
    let path = std::env::temp_dir().join(format!("naadf-vox-far-{}.vox", std::process::id()));
    std::fs::write(&path, &b).unwrap();
    let start = std::time::Instant::now();
    let w = import_vox(&path, &|_| {});
    let took = start.elapsed();
    std::fs::remove_file(&path).ok();
    let w = w.unwrap();
    // A generous bound: the point is that it finishes, not how fast.
    assert!(took.as_secs() < 60, "{took:?}");

    let (extent, expected) = oracle(&d);
    assert_eq!(extent, [16008, 8, 8]);
    assert_eq!(w.size().voxels(), [16064, 64, 64]);
    // Both models, voxel by voxel, at their places (x 0..8 and 16000..16008).
    for x in (0..8).chain(16000..16008) {
        for y in 0..8 {
            for z in 0..8 {
                let want = expected.get(&[x, y, z]).copied().unwrap_or(0);
                assert_eq!(w.material_at([x, y, z]), want, "{x},{y},{z}");
            }
        }
    }
    // Nothing else: exactly the models' solid voxels, in two mixed chunks.
    let stats = WorldStats::of(&w);
    assert_eq!(stats.solid_voxels, expected.len() as u64);
    assert_eq!(stats.blocks, 2 * 64);
    // And the scene is sampled only there: every other chunk is reported empty up front.
    let scene = import(&d);
    let counted = Counting(&scene, AtomicUsize::new(0));
    assert_eq!(World::build(&counted, &|_| {}).unwrap().digest(), w.digest());
    assert_eq!(counted.1.into_inner(), 2);
}

/// A source that counts the chunks construction asks it to fill.
struct Counting<'a>(&'a VoxScene, AtomicUsize);

impl ChunkSource for Counting<'_> {
    fn size(&self) -> WorldSize {
        ChunkSource::size(self.0)
    }

    fn materials(&self) -> MaterialTable {
        ChunkSource::materials(self.0)
    }

    fn uniform_hint(&self, chunk: [u32; 3]) -> Option<u16> {
        self.0.uniform_hint(chunk)
    }

    fn fill_chunk(&self, chunk: [u32; 3], out: &mut [u16; CHUNK_VOXELS]) {
        self.1.fetch_add(1, Ordering::Relaxed);
        self.0.fill_chunk(chunk, out);
    }
}

#[test]
fn too_many_big_model_grids_are_refused_without_allocating() {
    // 300 distinct 256³ models (4.7 GiB of grids) from a few kilobytes.
    let models = (0..300).map(|_| model([256, 256, 256], &[])).collect();
    let e = import_err(&bytes(&file(models, vec![])));
    assert!(e.contains("MiB"), "{e}");
}

#[test]
fn deeply_nested_chunks_are_refused() {
    // 100000 nested chunks: a recursive parser would overflow the stack.
    let depth = 100_000usize;
    let mut b = b"VOX \x96\0\0\0".to_vec();
    for level in 0..depth {
        b.extend_from_slice(if level == 0 { b"MAIN" } else { b"NEST" });
        b.extend_from_slice(&0u32.to_le_bytes());
        let children = 12 * (depth - level - 1) as u32;
        b.extend_from_slice(&children.to_le_bytes());
    }
    let e = import_err(&b);
    assert!(e.contains("nested"), "{e}");
}

// ---------------------------------------------------------------------------------------
// Fuzzing.

/// Valid files to mutate.
fn seeds() -> Vec<Vec<u8>> {
    let mut with_mats = file(vec![noisy_model([6, 5, 4], 3)], vec![]);
    with_mats.materials = vec![dot_vox::Material {
        id: 3,
        properties: dict(&[("_type", "_emit"), ("_emit", "1.5"), ("_flux", "2")]),
    }];
    vec![
        bytes(&file(vec![noisy_model([4, 3, 5], 1)], vec![])),
        bytes(&with_mats),
        bytes(&file(
            vec![noisy_model([4, 3, 2], 1), noisy_model([5, 2, 3], 2)],
            vec![
                trn(1, &[]),
                grp(&[2, 4]),
                trn(3, &[("_t", "10 0 0"), ("_r", "17")]),
                shp(0),
                trn(5, &[("_t", "-5 3 2"), ("_r", "116")]),
                shp(1),
            ],
        )),
    ]
}

/// Imports `b`; when it succeeds and the world is small, builds it and checks that the
/// world agrees with the scene everywhere (exercises fill_chunk and uniform_hint).
fn import_and_check(b: &[u8]) {
    let Ok(scene) = VoxScene::from_bytes(b) else {
        return;
    };
    let size = scene.world_size().unwrap();
    if size.voxel_count() > 128 * 128 * 128 {
        return;
    }
    let w = World::build(&scene, &|_| {}).unwrap();
    let [sx, sy, sz] = size.voxels();
    for z in 0..sz {
        for y in 0..sy {
            for x in 0..sx {
                assert_eq!(w.material_at([x, y, z]), scene.material_at([x, y, z]));
            }
        }
    }
}

/// Mutations: overwrite a byte (6 in 8), plant an extreme 32-bit value (1 in 8), or
/// truncate (1 in 8).
fn mutate(mut b: Vec<u8>, edits: &[(usize, u8, u8)]) -> Vec<u8> {
    const BIG: [u32; 8] = [0, 1, 255, 256, 257, 0x7FFF_FFFF, 0x8000_0000, u32::MAX];
    for &(at, kind, val) in edits {
        if b.is_empty() {
            break;
        }
        let i = at % b.len();
        match kind % 8 {
            0..=5 => b[i] = val,
            6 => {
                let v = BIG[usize::from(val) % BIG.len()].to_le_bytes();
                let n = (b.len() - i).min(4);
                b[i..i + n].copy_from_slice(&v[..n]);
            }
            _ => b.truncate(i),
        }
    }
    b
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn garbage_never_panics(b in proptest::collection::vec(any::<u8>(), 0..2048)) {
        import_and_check(&b);
    }

    #[test]
    fn garbage_behind_a_header_never_panics(body in proptest::collection::vec(any::<u8>(), 0..2048)) {
        let mut b = b"VOX \x96\0\0\0MAIN\0\0\0\0".to_vec();
        b.extend_from_slice(&(body.len() as u32).to_le_bytes());
        b.extend_from_slice(&body);
        import_and_check(&b);
    }

    #[test]
    fn mutated_files_never_panic(
        seed in 0usize..3,
        edits in proptest::collection::vec((any::<usize>(), any::<u8>(), any::<u8>()), 1..12),
    ) {
        import_and_check(&mutate(seeds()[seed].clone(), &edits));
    }
}

// ---------------------------------------------------------------------------------------
// The shared sample files.

/// A small deterministic generator for the mutation loop.
struct XorShift(u64);
impl XorShift {
    fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

#[test]
fn shared_vox_files() {
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/data/vox"));
    if !dir.is_dir() {
        println!("skipping: ../shared/data/vox not found");
        return;
    }
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x.eq_ignore_ascii_case("vox")) {
                files.push(p);
            }
        }
    }
    files.sort();
    assert!(!files.is_empty(), "no .vox files under {}", dir.display());
    const MUTATIONS: usize = 200;
    let mut rng = XorShift(0x5EED_CAFE_F00D_1234);
    for path in &files {
        let name = path.strip_prefix(dir).unwrap().display().to_string();
        let raw = std::fs::read(path).unwrap();
        let scene = VoxScene::from_bytes(&raw).unwrap_or_else(|e| panic!("{name}: {e}"));
        let data = dot_vox::load_bytes(&raw).unwrap();
        let (extent, expected) = oracle(&data);
        assert_eq!(scene.extent(), extent, "{name}");
        let size = scene.world_size().unwrap();
        let built = size.voxel_count() <= 256 * 256 * 256;
        if built {
            let w = World::build(&scene, &|_| {}).unwrap();
            let [sx, sy, sz] = size.voxels();
            let mut solid = 0usize;
            for z in 0..sz {
                for y in 0..sy {
                    for x in 0..sx {
                        let want = expected.get(&[x, y, z]).copied().unwrap_or(0);
                        let got = w.material_at([x, y, z]);
                        assert_eq!(got, want, "{name}: voxel {x},{y},{z}");
                        solid += usize::from(got != 0);
                    }
                }
            }
            assert_eq!(solid, expected.len(), "{name}");
        }
        println!(
            "{name}: extent {:?}, {} placed models, world {}, {} solid voxels{}",
            scene.extent(),
            scene.instance_count(),
            size,
            expected.len(),
            if built { ", built and checked" } else { "" }
        );
        // Mutations: no panics, Ok or Err.
        let (mut ok, mut err) = (0, 0);
        for _ in 0..MUTATIONS {
            let n = 1 + rng.next_u64() as usize % 4;
            let edits: Vec<(usize, u8, u8)> = (0..n)
                .map(|_| {
                    let r = rng.next_u64();
                    // Bias toward the headers at the front, where sizes and counts live.
                    let at = if r & 1 == 0 {
                        (r >> 8) as usize % 256
                    } else {
                        (r >> 8) as usize
                    };
                    (at, (r >> 40) as u8, (r >> 48) as u8)
                })
                .collect();
            match VoxScene::from_bytes(&mutate(raw.clone(), &edits)) {
                Ok(_) => ok += 1,
                Err(_) => err += 1,
            }
        }
        println!("  {MUTATIONS} mutations: {ok} imported, {err} refused");
    }
}

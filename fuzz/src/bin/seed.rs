//! Writes generated seed inputs for every target: `seed <corpus dir>` creates
//! `<corpus dir>/<target>/gen-*`, in each target's input layout (mode byte first where the
//! target has one, see the harness). These make the corpora usable without any sample data;
//! `seed.sh` adds the real files when they are present.

use naadf_fuzz::{WAL_FORMAT, WAL_MAGIC, piece};
use naadf_proto::requests::{entity_pose, entity_spawn};
use naadf_proto::snapshot::{cache_of, compress_pages, group_pages};
use naadf_proto::v1::{
    DespawnEntitiesRequest, EditRequest, FrameRequest, JoinRequest, MoveEntitiesRequest, Page, SpawnEntitiesRequest,
    WorldMessage, world_message,
};
use naadf_server::data::wal::{Entry, Wal};
use naadf_world::digest::PAGE_BYTES;
use naadf_world::edit::BatchKind;
use naadf_world::file::{self, TRANSFERRED};
use naadf_world::preset::Preset;
use naadf_world::{World, WorldSize};
use prost::Message;
use std::path::{Path, PathBuf};

/// Ops lines covering every op kind (the server's `EditRequest.ops`).
const OPS: [&str; 9] = [
    r#"{"op":"box","min":[0,0,0],"max":[8,8,8],"material":2}"#,
    r#"{"batch":[{"op":"box","min":[0,0,0],"max":[8,8,8],"material":2},{"op":"sphere","center":[4,4,4],"radius":3,"material":0}]}"#,
    r#"{"op":"set","voxels":[[1,2,3,4],[5,6,7,0]]}"#,
    r#"{"op":"paint","center":[10,10,10],"radius":4,"material":5}"#,
    r#"{"op":"flood_paint","start":[1,1,1],"material":3,"limit":100}"#,
    r#"{"op":"copy","min":[0,0,0],"max":[4,4,4],"to":[10,10,10]}"#,
    r#"{"batch":[{"op":"define_model","name":"crate","size":[2,2,2],"voxels":[[0,0,0,1],[1,1,1,2]]},{"op":"place","model":"crate","at":[3,3,3]},{"op":"spawn_entity","id":1,"model":"crate","pos":[8,8,8],"rot":[0,0,0,1]}]}"#,
    r#"{"batch":[{"op":"move_entity","id":1,"pos":[9,8,8],"rot":[0,0.7071,0,0.7071]},{"op":"despawn_entity","id":1}]}"#,
    r#"{"op":"define_material","id":300,"kind":"metal","albedo":[1,0.5,0.25],"roughness":0.2}"#,
];

/// A replay script using every line kind.
const SCRIPT: &str = r#"# Two users build and one undoes.
{"camera":{"pos":[64,80,-40],"yaw":0,"pitch":-30}}
{"as_user":"alice"}
{"op":"sphere","center":[64,40,64],"radius":12,"material":2}
{"as_user":"bob"}
{"op":"box","min":[20,30,20],"max":[40,50,40],"material":3}
{"end_frame":true,"fps":10}
{"as_user":"alice"}
{"undo":true}
{"redo":true}
{"expect_digest":"3f0c1a2b4d5e6f70"}
{"render":{"size":[320,200],"mode":"material","out":"after-undo.png"}}
{"expect_image":{"file":"reference/after-undo.png","max_mean_abs_diff":0.5}}
{"random_edits":{"count":100,"seed":7}}
"#;

/// A HashDAG replay in its CSV form.
const CSV: &str = "SetLocation,1.455062,1.172321,1.486608
SetRotation,0.020911,0.000000,-0.999781,0.024776,0.999693,0.000518,0.999474,-0.024781,0.020905
EndFrame
EditSphere,2775,1328,2063,10,TRUE,,,,
EditSphere,2947,1328,2258,13,FALSE,,,,
EndFrame,,,,,,,,,
";

/// A camera as frame requests carry it.
const CAMERA: &str = r#"{"pos":[64,80,-40],"yaw":0,"pitch":-30,"fov_y":60}"#;

fn main() {
    let Some(dir) = std::env::args().nth(1) else {
        eprintln!("usage: seed <corpus dir>");
        std::process::exit(2);
    };
    let out = Out(PathBuf::from(dir));
    let world = small_world();

    vox(&out);

    let mut bytes = vec![0];
    file::write(&world, &mut bytes).expect("the world writes");
    out.put("world_file", "file", &bytes);
    let mut bytes = vec![1, 0, 0, 0];
    for id in TRANSFERRED {
        piece(&mut bytes, &world.buffer_bytes(id));
    }
    piece(&mut bytes, &world.entity_table().encode());
    out.put("world_file", "buffers", &bytes);

    wal(&out);

    for (i, line) in OPS.iter().enumerate() {
        out.put("ops", &i.to_string(), line.as_bytes());
    }

    out.put("replay", "script", &[&[0][..], SCRIPT.as_bytes()].concat());
    out.put("replay", "hashdag", &[&[1][..], CSV.as_bytes()].concat());

    proto(&out, &world);
    eprintln!("seeds written under {}", out.0.display());
}

/// Where the seeds go.
struct Out(PathBuf);

impl Out {
    fn put(&self, target: &str, name: &str, bytes: &[u8]) {
        let dir = self.0.join(target);
        std::fs::create_dir_all(&dir).expect("the corpus directory can be created");
        std::fs::write(dir.join(format!("gen-{name}")), bytes).expect("a seed can be written");
    }
}

/// The smallest world, from the test preset (so it has content).
fn small_world() -> World {
    let size = WorldSize::new(64, 64, 64).expect("valid size");
    let source = Preset::Test.source(Some(size), 7).expect("the test preset builds");
    World::build(&*source, &|_| {}).expect("the test world builds")
}

/// Two `.vox` files: one model, and a rotated and translated scene graph of two models.
fn vox(out: &Out) {
    use dot_vox::{
        DEFAULT_INDEX_MAP, DEFAULT_PALETTE, Dict, DotVoxData, Frame, Model, SceneNode, ShapeModel, Size, Voxel,
    };
    let model = |n: u32, salt: u8| Model {
        size: Size {
            x: n,
            y: n + 1,
            z: n + 2,
        },
        voxels: (0..n as u8)
            .map(|i| Voxel {
                x: i,
                y: i / 2,
                z: (i + salt) % (n as u8),
                i: i.wrapping_mul(37).wrapping_add(salt),
            })
            .collect(),
    };
    let dict = |pairs: &[(&str, &str)]| -> Dict { pairs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect() };
    let shape = |m: u32| SceneNode::Shape {
        attributes: Dict::new(),
        models: vec![ShapeModel {
            model_id: m,
            attributes: Dict::new(),
        }],
    };
    let transform = |child: u32, frame: &[(&str, &str)]| SceneNode::Transform {
        attributes: Dict::new(),
        frames: vec![Frame::new(dict(frame))],
        child,
        layer_id: 0,
    };
    let file = |models: Vec<Model>, scenes: Vec<SceneNode>| DotVoxData {
        version: 150,
        index_map: DEFAULT_INDEX_MAP.to_vec(),
        models,
        palette: DEFAULT_PALETTE.to_vec(),
        materials: vec![],
        scenes,
        layers: vec![],
    };
    let write = |name: &str, d: DotVoxData| {
        let mut bytes = Vec::new();
        d.write_vox(&mut bytes).expect("dot_vox writes");
        out.put("vox", name, &bytes);
    };
    write("single", file(vec![model(4, 1)], vec![]));
    write(
        "scene",
        file(
            vec![model(4, 1), model(6, 3)],
            vec![
                transform(1, &[]),
                SceneNode::Group {
                    attributes: Dict::new(),
                    children: vec![2, 4],
                },
                transform(3, &[("_r", "20"), ("_t", "5 -3 7")]),
                shape(0),
                transform(5, &[("_r", "98"), ("_t", "-10 2 0")]),
                shape(1),
            ],
        ),
    );
}

/// Log entries: an edit, an undo and a redo.
fn entries() -> Vec<Entry> {
    let kinds = [BatchKind::Edit, BatchKind::Undo, BatchKind::Redo];
    kinds
        .into_iter()
        .enumerate()
        .map(|(i, kind)| Entry {
            version: i as u64 + 1,
            user: "alice".into(),
            client_seq: i as u64 + 10,
            kind,
            ops: if kind == BatchKind::Edit {
                OPS[1].into()
            } else {
                r#"{"batch":[]}"#.into()
            },
        })
        .collect()
}

/// A segment written by the server's own log writer (whole-file mode), and the same
/// records as payloads for the harness to frame.
fn wal(out: &Out) {
    let dir = scratch_dir();
    let (mut log, replayed) = Wal::resume(&dir, Vec::new(), 0).expect("a fresh log opens");
    assert!(replayed.is_empty());
    for e in entries() {
        log.append(&e.frame()).expect("appends");
    }
    log.sync().expect("syncs");
    drop(log);
    let (_, path) = naadf_server::data::wal::segments(&dir).expect("lists").remove(0);
    let segment = std::fs::read(&path).expect("reads");
    out.put("wal", "segment", &[&[3, 0][..], &segment].concat());
    // The same file with a torn last record.
    out.put("wal", "torn", &[&[3, 0][..], &segment[..segment.len() - 5]].concat());
    let mut framed = vec![1, 0];
    for e in entries() {
        piece(&mut framed, &postcard::to_allocvec(&e).expect("serializes"));
    }
    framed.extend_from_slice(&[0, 0, 0]);
    out.put("wal", "payloads", &framed);
    // A header alone, in whole-file mode.
    let mut h = WAL_MAGIC.to_vec();
    h.extend_from_slice(&WAL_FORMAT.to_le_bytes());
    h.extend_from_slice(&0u64.to_le_bytes());
    out.put("wal", "header", &[&[2, 0][..], &h].concat());
    std::fs::remove_dir_all(&dir).expect("the scratch directory is removed");
}

/// An empty scratch directory for the log writer.
fn scratch_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("naadf-fuzz-seed-{}", std::process::id()));
    if Path::new(&dir).exists() {
        std::fs::remove_dir_all(&dir).expect("stale scratch directory is removed");
    }
    std::fs::create_dir_all(&dir).expect("scratch directory");
    dir
}

/// One seed per request kind the proto target decodes, and a whole snapshot.
fn proto(out: &Out, world: &World) {
    let put = |name: &str, mode: u8, m: &dyn Fn(&mut Vec<u8>)| {
        let mut bytes = vec![mode];
        m(&mut bytes);
        out.put("proto", name, &bytes);
    };
    for (i, line) in OPS.iter().enumerate() {
        put(&format!("edit-{i}"), 0, &|b| {
            EditRequest {
                ops: (*line).into(),
                client_seq: 3,
            }
            .encode(b)
            .expect("encodes")
        });
    }
    put("spawn", 1, &|b| {
        SpawnEntitiesRequest {
            entities: vec![entity_spawn(1, "crate", [1.0, 2.0, 3.0], [0.0, 0.0, 0.0, 1.0])],
            client_seq: 4,
        }
        .encode(b)
        .expect("encodes")
    });
    put("move", 2, &|b| {
        MoveEntitiesRequest {
            moves: vec![entity_pose(1, [4.0, 2.0, 3.0], [0.0, 0.6, 0.0, 0.8])],
            client_seq: 5,
        }
        .encode(b)
        .expect("encodes")
    });
    put("despawn", 3, &|b| {
        DespawnEntitiesRequest {
            ids: vec![1, 2],
            client_seq: 6,
        }
        .encode(b)
        .expect("encodes")
    });
    put("join", 4, &|b| {
        JoinRequest {
            protocol_version: naadf_proto::PROTOCOL_VERSION,
            cached: cache_of(world),
            resume: None,
            ..Default::default()
        }
        .encode(b)
        .expect("encodes")
    });
    put("frame", 5, &|b| {
        FrameRequest {
            camera: CAMERA.into(),
            width: 64,
            height: 48,
            mode: "albedo".into(),
            ..Default::default()
        }
        .encode(b)
        .expect("encodes")
    });
    // A whole snapshot as the server sends it: header, then every page.
    let mut pages = Vec::new();
    for id in TRANSFERRED {
        let bytes = world.buffer_bytes(id);
        let all: Vec<u32> = (0..bytes.len().div_ceil(PAGE_BYTES) as u32).collect();
        for g in group_pages(&all) {
            let slices: Vec<&[u8]> = g
                .iter()
                .map(|&k| &bytes[k as usize * PAGE_BYTES..((k as usize + 1) * PAGE_BYTES).min(bytes.len())])
                .collect();
            pages.push(Page {
                buffer: id as u32,
                indices: g,
                zstd: compress_pages(&slices),
            });
        }
    }
    let header = naadf_proto::snapshot::header_for(&world, pages.len() as u32);
    put("snapshot", 6, &|b| {
        let msg = |kind| WorldMessage { kind: Some(kind) };
        msg(world_message::Kind::Header(header.clone()))
            .encode_length_delimited(b)
            .expect("encodes");
        for p in &pages {
            msg(world_message::Kind::Page(p.clone()))
                .encode_length_delimited(b)
                .expect("encodes");
        }
    });
}

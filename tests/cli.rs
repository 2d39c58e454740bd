//! End-to-end tests of the `naadf` CLI: real processes, real files, worlds made in code.

mod support;

use std::path::Path;
use support::{fails, ok, p};

fn read_raw(path: &str) -> Vec<u16> {
    std::fs::read(path)
        .unwrap()
        .chunks_exact(2)
        .map(|b| u16::from_le_bytes([b[0], b[1]]))
        .collect()
}

#[test]
fn generate_info_export_raycast() {
    let dir = tempfile::tempdir().unwrap();
    let world = p(dir.path(), "t.naadf");
    let again = p(dir.path(), "t2.naadf");
    for out in [&world, &again] {
        ok(
            &[
                "generate",
                "--preset",
                "test",
                "--size",
                "64,64,128",
                "--seed",
                "5",
                "-o",
                out,
            ],
            None,
        );
    }
    let info: serde_json::Value = serde_json::from_str(&ok(&["info", &world, "--json"], None)).unwrap();
    assert_eq!(info["size"], serde_json::json!([64, 64, 128]));
    for key in ["solid_voxels", "chunks", "blocks", "voxel_groups"] {
        assert!(info[key].is_u64(), "info lacks {key}: {info}");
    }
    let bytes = &info["bytes"];
    let sum: u64 = ["chunks", "blocks", "voxels", "materials"]
        .iter()
        .map(|k| bytes[k].as_u64().unwrap())
        .sum();
    assert_eq!(bytes["total"].as_u64().unwrap(), sum);
    let digest = info["digest"].as_str().unwrap();
    assert!(digest.len() == 16 && digest.chars().all(|c| c.is_ascii_hexdigit() && !c.is_ascii_uppercase()));

    // The same generation gives the same digest.
    let info2: serde_json::Value = serde_json::from_str(&ok(&["info", &again, "--json"], None)).unwrap();
    assert_eq!(info2["digest"], info["digest"]);

    let raw_path = p(dir.path(), "t.bin");
    ok(&["export", &world, "--raw", &raw_path], None);
    let raw = read_raw(&raw_path);
    assert_eq!(raw.len(), 64 * 64 * 128);
    let solid = raw.iter().filter(|&&m| m != 0).count() as u64;
    assert_eq!(solid, info["solid_voxels"].as_u64().unwrap());

    // Rays: straight down every 3rd column, plus diagonals from outside.
    let mut rays = String::new();
    for x in (0..64).step_by(3) {
        for z in (0..128).step_by(5) {
            rays += &format!("{{\"o\":[{}.5,80,{}.5],\"d\":[0,-1,0]}}\n", x, z);
            rays += &format!("{{\"o\":[-10,70,{z}],\"d\":[1,-0.7,0.3]}}\n");
        }
    }
    let outs: Vec<String> = ["naadf", "nodf", "grid"]
        .iter()
        .map(|m| ok(&["raycast", &world, "--method", m], Some(&rays)))
        .collect();
    assert_eq!(outs[0], outs[1], "naadf and nodf differ");
    assert_eq!(outs[0], outs[2], "naadf and grid differ");
    let at = |v: &serde_json::Value| {
        let c: Vec<usize> = v
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_u64().unwrap() as usize)
            .collect();
        raw[c[0] + 64 * (c[1] + 64 * c[2])]
    };
    let mut hits = 0;
    for (line, ray) in outs[0].lines().zip(rays.lines()) {
        let h: serde_json::Value = serde_json::from_str(line).unwrap();
        if h["hit"] == true {
            hits += 1;
            assert_eq!(
                u64::from(at(&h["voxel"])),
                h["material"].as_u64().unwrap(),
                "{ray} -> {line}"
            );
            assert!(h["t"].as_f64().unwrap() >= 0.0);
        } else {
            assert_eq!(line, "{\"hit\":false}");
        }
    }
    assert!(hits > 100, "only {hits} hits");
}

/// A one-model .vox file written with dot_vox.
fn write_vox(path: &Path, size: (u32, u32, u32), voxels: &[(u8, u8, u8, u8)]) {
    let data = dot_vox::DotVoxData {
        version: 150,
        index_map: (0..=255).collect(),
        models: vec![dot_vox::Model {
            size: dot_vox::Size {
                x: size.0,
                y: size.1,
                z: size.2,
            },
            voxels: voxels
                .iter()
                .map(|&(x, y, z, i)| dot_vox::Voxel { x, y, z, i })
                .collect(),
        }],
        palette: (0..256)
            .map(|i| dot_vox::Color {
                r: i as u8,
                g: 255 - i as u8,
                b: 7,
                a: 255,
            })
            .collect(),
        materials: Vec::new(),
        scenes: Vec::new(),
        layers: Vec::new(),
    };
    let mut f = std::fs::File::create(path).unwrap();
    data.write_vox(&mut f).unwrap();
}

#[test]
fn import_vox_maps_axes_and_colour_indices() {
    let dir = tempfile::tempdir().unwrap();
    let vox = dir.path().join("m.vox");
    // vox (x, y, z) → world (x, z, y); dot_vox's `i` is the file's colour index minus one.
    let voxels = [(0, 0, 0, 0), (3, 1, 2, 4), (9, 7, 5, 254), (9, 0, 5, 10)];
    write_vox(&vox, (10, 8, 6), &voxels);
    let world = p(dir.path(), "m.naadf");
    ok(&["import", vox.to_str().unwrap(), "-o", &world], None);
    let info: serde_json::Value = serde_json::from_str(&ok(&["info", &world, "--json"], None)).unwrap();
    assert_eq!(info["size"], serde_json::json!([64, 64, 64]));
    assert_eq!(info["solid_voxels"], 4);
    let raw_path = p(dir.path(), "m.bin");
    ok(&["export", &world, "--raw", &raw_path], None);
    let raw = read_raw(&raw_path);
    for &(x, y, z, i) in &voxels {
        let (wx, wy, wz) = (x as usize, z as usize, y as usize);
        assert_eq!(raw[wx + 64 * (wy + 64 * wz)], u16::from(i) + 1, "vox voxel {x},{y},{z}");
    }
}

#[test]
fn errors_are_clean() {
    let dir = tempfile::tempdir().unwrap();
    fails(&["info", &p(dir.path(), "missing.naadf")], None, "error:");
    let junk = p(dir.path(), "junk.naadf");
    std::fs::write(&junk, b"this is not a world").unwrap();
    fails(&["info", &junk], None, "error:");
    let vox_junk = p(dir.path(), "junk.vox");
    std::fs::write(&vox_junk, b"VOX \x96\x00\x00\x00MAIN\xff\xff\xff\xff").unwrap();
    fails(&["import", &vox_junk, "-o", &p(dir.path(), "x.naadf")], None, "error:");
    fails(
        &["generate", "--preset", "nope", "-o", &p(dir.path(), "x.naadf")],
        None,
        "error:",
    );
    fails(
        &[
            "generate",
            "--preset",
            "test",
            "--size",
            "100,64,64",
            "-o",
            &p(dir.path(), "x.naadf"),
        ],
        None,
        "64",
    );

    let world = p(dir.path(), "t.naadf");
    ok(&["generate", "--preset", "test", "-o", &world], None);
    fails(
        &["raycast", &world],
        Some("{\"o\":[1,2,3],\"d\":[0,1,0]}\n{\"o\":[1,2]}\n"),
        "line 2",
    );
    fails(&["raycast", &world], Some("{\"o\":[1,2,3],\"d\":[0,0,0]}\n"), "line 1");
    fails(&["raycast", &world, "--method", "octree"], Some(""), "octree");
    // A truncated world file is rejected, not half-loaded.
    let bytes = std::fs::read(&world).unwrap();
    let cut = p(dir.path(), "cut.naadf");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    fails(&["info", &cut], None, "error:");

    // The ROMA settings: checked, and only for `--mode roma` (refused before any GPU work).
    let png = p(dir.path(), "x.png");
    let render = |mode: &'static str, extra: &[&str], why: &str| {
        let camera = r#"{"pos":[1,1,1],"yaw":0,"pitch":0}"#;
        let base = [
            "render", "--world", &world, "--camera", camera, "--mode", mode, "-o", &png,
        ];
        fails(&[&base[..], extra].concat(), None, why);
    };
    render(
        "roma",
        &["--roma-directions", "12"],
        "12 ROMA directions: give a square number",
    );
    render("roma", &["--ao-range", "0"], "AO range 0: must lie in (0, 256]");
    render("roma", &["--ao-range", "300"], "AO range 300");
    render(
        "pathtrace",
        &["--roma-directions", "4"],
        "--roma-directions does not apply to --mode pathtrace",
    );
    render(
        "baseline",
        &["--ao-range", "8"],
        "--ao-range does not apply to --mode baseline",
    );
    render(
        "gi",
        &["--roma-directions", "9"],
        "--roma-directions does not apply to --mode gi",
    );
    render(
        "albedo",
        &["--ao-range", "8"],
        "--ao-range applies to the lit modes only",
    );
    render(
        "irradiance",
        &["--ao-range", "8"],
        "--ao-range does not apply to --mode irradiance",
    );

    // The irradiance cache's ray budget: checked, and only for `--mode irradiance`.
    render(
        "irradiance",
        &["--irradiance-rays", "2"],
        "2 irradiance rays per frame: must lie in 4..=67108864",
    );
    render(
        "irradiance",
        &["--irradiance-rays", "67108865"],
        "67108865 irradiance rays",
    );
    render(
        "pathtrace",
        &["--irradiance-rays", "4096"],
        "--irradiance-rays does not apply to --mode pathtrace",
    );
    render(
        "roma",
        &["--irradiance-rays", "4096"],
        "--irradiance-rays does not apply to --mode roma",
    );
    render(
        "gi",
        &["--irradiance-rays", "4096"],
        "--irradiance-rays does not apply to --mode gi",
    );
    render(
        "albedo",
        &["--irradiance-rays", "4096"],
        "--irradiance-rays applies to the lit modes only",
    );
}

/// A `bench traverse` or `bench gpu` JSON report of 32 × 18 rays per camera: every
/// method measured on both ray sets.
fn bench_report(out: &str) -> serde_json::Value {
    let v: serde_json::Value = serde_json::from_str(out).unwrap();
    for set in ["primary", "secondary"] {
        for m in ["naadf", "nodf", "grid"] {
            assert!(v[set][m].as_f64().unwrap() > 0.0, "{set}.{m} missing: {v}");
        }
    }
    assert_eq!(v["rays"], 4 * 32 * 18);
    v
}

#[test]
fn bench_traverse_reports_the_contract() {
    let dir = tempfile::tempdir().unwrap();
    let world = p(dir.path(), "t.naadf");
    ok(&["generate", "--preset", "test", "-o", &world], None);
    let out = ok(
        &["bench", "traverse", &world, "--json", "--width", "32", "--height", "18"],
        None,
    );
    let v = bench_report(&out);
    assert!(v["threads"].as_u64().unwrap() >= 1);
    assert_eq!(v["mismatches"], 0);
    // With entities: every method agrees on the crowded world too, and the paired rounds
    // report a cost per method and ray set.
    let out = ok(
        &[
            "bench",
            "traverse",
            &world,
            "--json",
            "--width",
            "32",
            "--height",
            "18",
            "--entities",
            "40",
            "--rounds",
            "3",
        ],
        None,
    );
    let v = bench_report(&out);
    assert_eq!(v["mismatches"], 0);
    assert_eq!(v["with_entities"]["mismatches"], 0);
    assert_eq!(v["entity_cost"]["rounds"], 3);
    for m in ["naadf", "nodf"] {
        let median = v["entity_cost"]["median_percent"][m].as_array().unwrap();
        assert_eq!(median.len(), 3, "{v}");
        assert!(median.iter().all(|c| c.as_f64().unwrap().is_finite()), "{v}");
    }
}

#[test]
fn bench_paper_reports_every_structure_on_the_same_rays() {
    let dir = tempfile::tempdir().unwrap();
    let world = p(dir.path(), "t.naadf");
    ok(&["generate", "--preset", "test", "-o", &world], None);
    let out = ok(
        &[
            "bench", "paper", &world, "--json", "--width", "32", "--height", "18", "--rounds", "2",
        ],
        None,
    );
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for s in ["naadf", "svo", "svdag", "grid"] {
        let f = &v["structures"][s];
        assert!(f["bytes"].as_u64().unwrap() > 0, "{s}: {v}");
        assert!(
            f["primary"].as_f64().unwrap() > 0.0 && f["secondary"].as_f64().unwrap() > 0.0,
            "{s}: {v}"
        );
    }
    // The counts of docs/BASELINES.md: the grid is 2 bytes a voxel, naadf what `info` says.
    let info: serde_json::Value = serde_json::from_str(&ok(&["info", &world, "--json"], None)).unwrap();
    assert_eq!(v["structures"]["naadf"]["bytes"], info["bytes"]["total"]);
    let size = info["size"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_u64().unwrap())
        .product::<u64>();
    assert_eq!(v["structures"]["grid"]["bytes"].as_u64().unwrap(), 2 * size);
    assert!(v["rays"].as_u64().unwrap() > 4 * 32 * 18, "primary and secondary: {v}");
    // The hybrid formats: a raw grid of at least 8³ words, traced on the same rays.
    for h in ["R(4³)G(7)", "R(3³)G(8)"] {
        let f = &v["hybrid"][h];
        assert!(f["bytes"].as_u64().unwrap() > 4 << 9, "{h}: {v}");
        assert!(
            f["primary"].as_f64().unwrap() > 0.0 && f["build_ms"].as_f64().is_some(),
            "{h}: {v}"
        );
        assert!(v["naadf_speedup"][h][1].as_f64().unwrap() > 0.0, "{h}: {v}");
    }
    // A world longer than the formats' 2048 voxels: they are skipped, saying why; the
    // others still run.
    let long = p(dir.path(), "long.naadf");
    ok(
        &["generate", "--preset", "test", "--size", "4096,64,64", "-o", &long],
        None,
    );
    let out = ok(
        &[
            "bench", "paper", &long, "--json", "--width", "16", "--height", "9", "--rounds", "1",
        ],
        None,
    );
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for h in ["R(4³)G(7)", "R(3³)G(8)"] {
        let f = &v["hybrid"][h];
        assert!(f["primary"].is_null(), "{h}: {v}");
        assert!(
            f["skipped"]
                .as_str()
                .unwrap()
                .contains("less than the world's cube of 4096"),
            "{h}: {v}"
        );
    }
    assert!(v["structures"]["svdag"]["primary"].as_f64().unwrap() > 0.0, "{v}");
    fails(&["bench", "paper", &p(dir.path(), "missing.naadf")], None, "error:");
    fails(
        &["bench", "paper", &world, "--width", "0"],
        None,
        "--width and --height",
    );
    if !have_gpu(&world, dir.path()) {
        return;
    }
    // --gpu: the same structures on the GPU, checked against the CPU; --plot: the scatter.
    let png = p(dir.path(), "scatter.png");
    let out = ok(
        &[
            "bench", "paper", &world, "--json", "--width", "32", "--height", "18", "--rounds", "1", "--gpu", "--plot",
            &png,
        ],
        None,
    );
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for s in ["naadf", "svo", "svdag", "grid"] {
        let f = &v["gpu"]["structures"][s];
        assert!(f["primary"].as_f64().unwrap() > 0.0, "{s}: {v}");
        assert!(v["gpu"]["mismatches"][s].as_u64().unwrap() <= 1, "{s}: {v}");
    }
    let img = image::open(&png).expect("the scatter is a PNG").to_rgb8();
    assert!(img.width() >= 600 && img.height() >= 400);
    fails(
        &[
            "bench",
            "paper",
            &world,
            "--width",
            "8",
            "--height",
            "8",
            "--rounds",
            "1",
            "--plot",
            &p(dir.path(), "no/such/dir/x.png"),
        ],
        None,
        "error:",
    );
}

#[test]
fn apply_edits_offline_against_a_dense_oracle() {
    let dir = tempfile::tempdir().unwrap();
    let world = p(dir.path(), "t.naadf");
    ok(
        &[
            "generate", "--preset", "test", "--size", "64,64,64", "--seed", "2", "-o", &world,
        ],
        None,
    );
    let raw_path = p(dir.path(), "before.bin");
    ok(&["export", &world, "--raw", &raw_path], None);
    let mut expect = read_raw(&raw_path);
    let at = |x: usize, y: usize, z: usize| x + 64 * (y + 64 * z);
    let ops = [
        r#"{"op":"box","min":[-5,10,3],"max":[20,30,70],"material":2}"#,
        r#"{"op":"sphere","center":[40,40,40],"radius":9.5,"material":0}"#,
        r#"{"batch":[{"op":"set","voxels":[[1,2,3,1],[63,63,63,3]]},{"op":"box","min":[0,0,0],"max":[64,2,64],"material":0}]}"#,
    ];
    for z in 3..64 {
        for y in 10..30 {
            for x in 0..20 {
                expect[at(x, y, z)] = 2;
            }
        }
    }
    for z in 0..64 {
        for y in 0..64 {
            for x in 0..64 {
                let d = [x, y, z].map(|v| v as f64 + 0.5 - 40.0);
                if d.iter().map(|v| v * v).sum::<f64>() < 9.5 * 9.5 {
                    expect[at(x, y, z)] = 0;
                }
            }
        }
    }
    expect[at(1, 2, 3)] = 1;
    expect[at(63, 63, 63)] = 3;
    for z in 0..64 {
        for x in 0..64 {
            expect[at(x, 0, z)] = 0;
            expect[at(x, 1, z)] = 0;
        }
    }
    let ops_path = p(dir.path(), "ops.jsonl");
    std::fs::write(&ops_path, ops.join("\n")).unwrap();
    let out = p(dir.path(), "after.naadf");
    let summary: serde_json::Value =
        serde_json::from_str(&ok(&["apply", &world, "--ops", &ops_path, "-o", &out, "--json"], None)).unwrap();
    assert_eq!(summary["version"], 3);
    let after_raw = p(dir.path(), "after.bin");
    ok(&["export", &out, "--raw", &after_raw], None);
    assert!(
        read_raw(&after_raw) == expect,
        "applied world differs from the dense oracle"
    );

    // The same batches in two runs reach the same digest (quiescent states).
    let (first, second) = (p(dir.path(), "first.jsonl"), p(dir.path(), "second.jsonl"));
    std::fs::write(&first, ops[..2].join("\n")).unwrap();
    std::fs::write(&second, ops[2]).unwrap();
    let mid = p(dir.path(), "mid.naadf");
    ok(&["apply", &world, "--ops", &first, "-o", &mid], None);
    let two: serde_json::Value = serde_json::from_str(&ok(
        &[
            "apply",
            &mid,
            "--ops",
            &second,
            "-o",
            &p(dir.path(), "two.naadf"),
            "--json",
        ],
        None,
    ))
    .unwrap();
    assert_eq!(two["digest"], summary["digest"]);
    assert_eq!(two["version"], 3);

    // A bad line fails the whole run and writes nothing.
    let bad = p(dir.path(), "bad.jsonl");
    std::fs::write(
        &bad,
        format!(
            "{}\n{{\"op\":\"box\",\"min\":[0,0,0],\"max\":[1,1,1],\"material\":999}}\n",
            ops[0]
        ),
    )
    .unwrap();
    let never = p(dir.path(), "never.naadf");
    fails(&["apply", &world, "--ops", &bad, "-o", &never], None, "line 2");
    assert!(!Path::new(&never).exists());
}

#[test]
fn raycast_reports_entity_hits() {
    let dir = tempfile::tempdir().unwrap();
    let world = p(dir.path(), "t.naadf");
    ok(
        &["generate", "--preset", "test", "--size", "64,64,64", "-o", &world],
        None,
    );
    let ops = p(dir.path(), "ops.jsonl");
    std::fs::write(
        &ops,
        concat!(
            r#"{"op":"define_model","name":"cube","size":[2,2,2],"voxels":[[0,0,0,1],[1,0,0,1],[0,1,0,1],[1,1,0,1],[0,0,1,1],[1,0,1,1],[0,1,1,1],[1,1,1,1]]}"#,
            "\n",
            r#"{"op":"spawn_entity","id":7,"model":"cube","pos":[30,60,30],"rot":[0,0,0,1]}"#,
        ),
    )
    .unwrap();
    let out = p(dir.path(), "e.naadf");
    ok(&["apply", &world, "--ops", &ops, "-o", &out], None);
    let rays = "{\"o\":[31,63.9,31],\"d\":[0,-1,0]}\n";
    let lines: Vec<serde_json::Value> = ["naadf", "nodf", "grid"]
        .iter()
        .map(|m| serde_json::from_str(&ok(&["raycast", &out, "--method", m], Some(rays))).unwrap())
        .collect();
    for h in &lines {
        assert_eq!(h["entity"], 7, "{h}");
        assert_eq!(h["voxel"], serde_json::json!([1, 1, 1]), "entity-local voxel: {h}");
        assert!((h["t"].as_f64().unwrap() - 1.9).abs() < 1e-9, "{h}");
    }
}

/// Whether a GPU adapter (Mesa lavapipe in CI) is usable; prints why not.
///
/// The probe runs without `XDG_RUNTIME_DIR`, as on a fresh headless machine, and a render
/// that succeeds must print nothing that looks like an error (the graphics stack complains
/// about that variable unless `naadf` gives it a directory).
fn have_gpu(world: &str, dir: &Path) -> bool {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_naadf"))
        .args([
            "render",
            "--world",
            world,
            "--camera",
            r#"{"pos":[1,1,1],"yaw":0,"pitch":0}"#,
            "--size",
            "8x8",
            "-o",
            &p(dir, "probe.png"),
        ])
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() && err.contains("no usable GPU adapter") {
        eprintln!("skipping the GPU commands: {err}");
        return false;
    }
    assert!(out.status.success(), "render failed: {err}");
    assert!(!err.contains("error"), "a successful render printed an error: {err}");
    true
}

/// A view of the `test` preset that sees both the world and the sky.
const TEST_CAMERA: &str = r#"{"pos":[-10.5,70.25,-12.5],"yaw":45,"pitch":-35,"fov_y":60}"#;

/// The `test` preset written into `dir`, or `None` (with a message) without a GPU adapter.
fn gpu_test_world(dir: &Path) -> Option<String> {
    let world = p(dir, "t.naadf");
    ok(&["generate", "--preset", "test", "-o", &world], None);
    have_gpu(&world, dir).then_some(world)
}

#[test]
fn render_writes_the_image_and_first_hit_buffer() {
    let dir = tempfile::tempdir().unwrap();
    let Some(world) = gpu_test_world(dir.path()) else {
        return;
    };
    let camera = TEST_CAMERA;
    let (png, gb) = (p(dir.path(), "m.png"), p(dir.path(), "m.gb"));
    let out = ok(
        &[
            "render",
            "--world",
            &world,
            "--camera",
            camera,
            "--size",
            "64x40",
            "--mode",
            "material",
            "-o",
            &png,
            "--gbuffer",
            &gb,
            "--frames",
            "2",
            "--json",
        ],
        None,
    );
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!((v["width"].as_u64(), v["height"].as_u64()), (Some(64), Some(40)));
    assert_eq!(v["mode"], "material");
    let info: serde_json::Value = serde_json::from_str(&ok(&["info", &world, "--json"], None)).unwrap();
    assert_eq!(v["digest"], info["digest"]);

    let img = image::open(&png).unwrap().to_rgba8();
    assert_eq!(img.dimensions(), (64, 40));
    let bytes = std::fs::read(&gb).unwrap();
    assert_eq!(&bytes[..8], b"NAADFGB1");
    assert_eq!(bytes.len(), 16 + 16 * 64 * 40);
    assert_eq!(u32::from_le_bytes(bytes[8..12].try_into().unwrap()), 64);
    // Every pixel: a sky record (plane 0 = HIT_NOTHING) is black in material mode, a hit
    // is not (the test preset has no black material).
    let mut hits = 0;
    for (i, px) in img.pixels().enumerate() {
        let w0 = u32::from_le_bytes(bytes[16 + 16 * i..20 + 16 * i].try_into().unwrap());
        let sky = w0 >> 15 == 0x1FFFF;
        assert_eq!(sky, px.0[..3] == [0, 0, 0], "pixel {i}");
        hits += usize::from(!sky);
    }
    assert!(hits > 64 * 40 / 4, "the camera looks at the world");

    // The other modes render too, and differ from each other.
    let mut images = Vec::new();
    for mode in ["albedo", "normal", "steps"] {
        let out = p(dir.path(), &format!("{mode}.png"));
        ok(
            &[
                "render", "--world", &world, "--camera", camera, "--size", "64x40", "--mode", mode, "-o", &out,
            ],
            None,
        );
        images.push(image::open(&out).unwrap().to_rgba8().into_raw());
    }
    assert!(images[0] != images[1] && images[1] != images[2]);

    fails(
        &[
            "render", "--world", &world, "--camera", camera, "--mode", "sketch", "-o", &png,
        ],
        None,
        "unknown mode",
    );
    fails(
        &[
            "render", "--world", &world, "--camera", camera, "--size", "0x10", "-o", &png,
        ],
        None,
        "frame size",
    );
    fails(
        &["render", "--world", &world, "--camera", r#"{"pos":[1,2]}"#, "-o", &png],
        None,
        "error:",
    );
    let far = r#"{"pos":[1e12,0,0],"yaw":0,"pitch":0}"#;
    fails(
        &["render", "--world", &world, "--camera", far, "-o", &png],
        None,
        "out of range",
    );
}

/// Reads a PFM file: (width, height, RGB rows from the top).
fn read_pfm(path: &str) -> (u32, u32, Vec<[f32; 3]>) {
    let bytes = std::fs::read(path).unwrap();
    let mut lines = bytes.splitn(4, |&b| b == b'\n');
    assert_eq!(lines.next(), Some(&b"PF"[..]));
    let dims = String::from_utf8(lines.next().unwrap().to_vec()).unwrap();
    let (w, h) = dims.split_once(' ').unwrap();
    let (w, h): (u32, u32) = (w.parse().unwrap(), h.parse().unwrap());
    assert_eq!(lines.next(), Some(&b"-1.0"[..]), "little-endian scale");
    let data = lines.next().unwrap();
    assert_eq!(data.len(), 12 * (w * h) as usize);
    let px: Vec<[f32; 3]> = data
        .chunks_exact(12)
        .map(|c| std::array::from_fn(|i| f32::from_le_bytes(c[4 * i..4 * i + 4].try_into().unwrap())))
        .collect();
    // Rows are stored from the bottom up.
    let rows: Vec<Vec<[f32; 3]>> = px.chunks(w as usize).rev().map(<[_]>::to_vec).collect();
    (w, h, rows.concat())
}

#[test]
fn render_pathtrace_writes_radiance_and_refuses_bad_light() {
    let dir = tempfile::tempdir().unwrap();
    let Some(world) = gpu_test_world(dir.path()) else {
        return;
    };
    let camera = TEST_CAMERA;
    let (png, hdr) = (p(dir.path(), "pt.png"), p(dir.path(), "pt.pfm"));
    let run = |extra: &[&str]| {
        let mut args = vec![
            "render",
            "--world",
            &world,
            "--camera",
            camera,
            "--size",
            "24x16",
            "--mode",
            "pathtrace",
            "--spp",
            "4",
            "-o",
            &png,
            "--hdr",
            &hdr,
            "--json",
        ];
        args.extend_from_slice(extra);
        let v: serde_json::Value = serde_json::from_str(&ok(&args, None)).unwrap();
        assert_eq!((v["mode"].as_str(), v["spp"].as_u64()), (Some("pathtrace"), Some(4)));
        (read_pfm(&hdr), std::fs::read(&png).unwrap())
    };
    let ((w, h, radiance), first_png) = run(&[]);
    assert_eq!((w, h), (24, 16));
    assert!(radiance.iter().flatten().all(|c| c.is_finite() && *c >= 0.0));
    assert!(radiance.iter().any(|c| c[2] > 0.0), "the physical sky lights the frame");
    // The PNG is the tone-mapped radiance: brighter radiance, brighter pixel.
    let img = image::load_from_memory(&first_png).unwrap().to_rgba8();
    let (dark, bright) = (0..radiance.len())
        .map(|i| (radiance[i].iter().sum::<f32>(), i))
        .fold(((f32::MAX, 0), (0.0f32, 0)), |(lo, hi), (l, i)| {
            (if l < lo.0 { (l, i) } else { lo }, if l > hi.0 { (l, i) } else { hi })
        });
    let luma = |i: usize| {
        img.as_raw()[4 * i..4 * i + 3]
            .iter()
            .map(|&b| u32::from(b))
            .sum::<u32>()
    };
    assert!(luma(bright.1) > luma(dark.1));
    // The same seed gives the same bytes; another seed does not.
    assert_eq!(run(&[]).1, first_png);
    assert_ne!(run(&["--seed", "9"]).0.2, radiance);
    // A uniform sky with no bounces is seen as it is wherever the camera sees no world.
    let ((_, _, flat), _) = run(&["--sky", "uniform:0.25,0.5,1", "--bounces", "0"]);
    assert!(flat.contains(&[0.25, 0.5, 1.0]) && flat.contains(&[0.0; 3]));

    for (args, why) in [
        (&["--sky", "uniform:-1"][..], "radiance must lie"),
        (&["--sky", "cloudy"], "expected 'physical'"),
        (&["--sun", "0,30"], "expected 'off' or 'AZ,EL,E'"),
        (&["--sun", "0,91,1"], "elevation"),
        (&["--spp", "0"], "0 is not in 1.."),
        (&["--frames", "2"], "--frames does not apply to pathtrace"),
        (&["--exposure", "0"], "exposure 0: must be a positive"),
        (&["--bounces", "65"], "65 is not in 0..=64"),
        (&["--size", "20000x10"], "frame size"),
    ] {
        let mut all = vec![
            "render",
            "--world",
            &world,
            "--camera",
            camera,
            "--mode",
            "pathtrace",
            "-o",
            &png,
        ];
        all.extend_from_slice(args);
        fails(&all, None, why);
    }
    fails(
        &[
            "render", "--world", &world, "--camera", camera, "--sky", "physical", "-o", &png,
        ],
        None,
        "--sky applies to the lit modes only",
    );

    // The temporal modes follow a camera path and refuse what they do not take.
    let path = p(dir.path(), "path.jsonl");
    for mode in ["baseline", "gi"] {
        std::fs::write(&path, format!("{camera}\n\n{}\n", camera.replace("-10.5", "-9.5"))).unwrap();
        let base = [
            "render", "--world", &world, "--size", "24x16", "--mode", mode, "-o", &png,
        ];
        let out = ok(
            &[&base[..], &["--camera-path", &path, "--frames", "3", "--json"]].concat(),
            None,
        );
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!((v["mode"].as_str(), v["frames"].as_u64()), (Some(mode), Some(3)));
        std::fs::write(&path, "{\"pos\":[1,2]}\n").unwrap();
        fails(&[&base[..], &["--camera-path", &path]].concat(), None, "line 1");
        std::fs::write(&path, "\n").unwrap();
        fails(
            &[&base[..], &["--camera-path", &path]].concat(),
            None,
            "holds no camera",
        );
        fails(
            &[&base[..], &["--camera", camera, "--spp", "4"]].concat(),
            None,
            "--spp does not apply",
        );
    }
    fails(
        &["render", "--world", &world, "--camera-path", &path, "-o", &png],
        None,
        "--camera-path applies to the lit modes only",
    );

    // bench gi: references, the noise floor between them, baseline and gi after each frame
    // count (more baseline frames come closer to the reference; GI's quality is tested
    // in client/tests/gi.rs), the timing rounds and their ratios, GI's memory, the motion
    // poses and the edit response.
    let out = ok(
        &[
            "bench",
            "gi",
            &world,
            "--camera",
            camera,
            "--size",
            "24x16",
            "--reference-spp",
            "16",
            "--frames",
            "1,16",
            "--rounds",
            "1",
            "--timing-frames",
            "1",
            "--motion-spp",
            "4",
            "--json",
        ],
        None,
    );
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["reference_spp"], 16);
    assert!(v["noise_floor"]["flip"].as_f64().unwrap() > 0.0, "two seeds differ");
    let base = &v["modes"]["baseline"];
    let mse = |f: &str| base[f]["rel_mse"].as_f64().unwrap();
    assert!(mse("16") < mse("1"), "{base}");
    for mode in ["baseline", "gi"] {
        let m = &v["modes"][mode];
        assert!(m["16"]["flip"].as_f64().unwrap() > 0.0, "{mode}: {m}");
        assert!(v["flicker"][mode].as_f64().unwrap() >= 0.0);
        assert!(v["frame_ms"][mode]["median"].as_f64().unwrap() > 0.0);
        let [added, removed] = [0, 1].map(|k| v["edit_response"][mode][k].as_u64().unwrap());
        assert!(added >= 1 && removed >= 1, "{mode}: {}", v["edit_response"]);
    }
    assert!(v["ratios"]["gi/albedo"]["median"].as_f64().unwrap() > 0.0);
    assert_eq!(v["motion"].as_object().unwrap().len(), 3, "three poses");
    let memory = v["gi_memory"].as_array().unwrap();
    assert!(
        memory
            .iter()
            .any(|m| m[0] == "TAA samples" && m[1].as_u64() == Some(24 * 16 * 32 * 8))
    );
    fails(
        &["bench", "gi", &world, "--frames", "8,4", "--reference-spp", "1"],
        None,
        "increasing frame counts",
    );
    fails(
        &["bench", "gi", &world, "--spp", "4"],
        None,
        "--spp does not apply to bench gi",
    );
}

#[test]
fn bench_gpu_measures_every_variant_against_the_cpu() {
    let dir = tempfile::tempdir().unwrap();
    let world = p(dir.path(), "t.naadf");
    ok(&["generate", "--preset", "test", "-o", &world], None);
    if !have_gpu(&world, dir.path()) {
        return;
    }
    let out = ok(
        &[
            "bench", "gpu", &world, "--json", "--width", "32", "--height", "18", "--repeat", "1",
        ],
        None,
    );
    let v = bench_report(&out);
    for m in ["naadf", "nodf", "grid", "svo", "svdag"] {
        assert!(v["mismatches"][m].as_u64().unwrap() <= 1, "{m}: {v}");
        assert!(v["primary"][m].as_f64().unwrap() > 0.0, "{m}: {v}");
    }
}

/// Keeps `docs/CLI.md` equal to the real `--help` output of `naadf` and of every command and
/// subcommand (`bench` subcommands included), found by walking the help output itself.
///
/// Everything after the `BEGIN GENERATED` marker of `docs/CLI.md` is generated here; the
/// hand-written part above it is kept as it is. The test fails when the file is stale. Run
/// it with `NAADF_BLESS=1` to rewrite the file instead:
/// `NAADF_BLESS=1 cargo test --test cli cli_reference_is_up_to_date`.
///
/// The binary runs with an empty environment, so that variables such as `NAADF_SERVER`
/// (whose value clap would print) or `COLUMNS` cannot change the text.
#[test]
fn cli_reference_is_up_to_date() {
    const BEGIN: &str = "<!-- BEGIN GENERATED";
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/CLI.md");
    let generated = cli_reference();
    let bless = std::env::var_os("NAADF_BLESS").is_some_and(|v| !v.is_empty() && v != "0");
    let current = std::fs::read_to_string(&path).unwrap_or_default();
    let head = match current.find(BEGIN) {
        Some(at) => current[..at].to_string(),
        None => "# naadf command-line reference\n\n".to_string(),
    };
    let want = format!("{head}{generated}");
    if bless {
        if current != want {
            std::fs::write(&path, &want).unwrap();
            eprintln!("rewrote {}", path.display());
        }
        return;
    }
    assert!(
        current.contains(BEGIN),
        "{} lacks its generated part; run NAADF_BLESS=1 cargo test --test cli cli_reference_is_up_to_date",
        path.display()
    );
    if current != want {
        let diff = current
            .lines()
            .zip(want.lines())
            .position(|(a, b)| a != b)
            .unwrap_or_else(|| current.lines().count().min(want.lines().count()));
        panic!(
            "{} is stale (first difference at line {}: {:?} should be {:?}); \
             run NAADF_BLESS=1 cargo test --test cli cli_reference_is_up_to_date",
            path.display(),
            diff + 1,
            current.lines().nth(diff).unwrap_or("<end of file>"),
            want.lines().nth(diff).unwrap_or("<end of file>"),
        );
    }
}

/// `naadf <path> --help`, run with an empty environment; `None` if it fails.
fn help_text(path: &[String]) -> Option<String> {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_naadf"))
        .args(path)
        .arg("--help")
        .env_clear()
        .stdin(std::process::Stdio::null())
        .output()
        .expect("spawn naadf");
    if !out.status.success() {
        return None;
    }
    let text = String::from_utf8(out.stdout).expect("help is UTF-8");
    let lines: Vec<&str> = text.lines().map(str::trim_end).collect();
    Some(lines.join("\n").trim_end().to_string())
}

/// The subcommands a help text lists, with their one-line descriptions, in order: every
/// `  name  description` line under any heading (so grouped command lists work too), kept
/// only if `naadf <path> name --help` succeeds. `help` itself is left out.
fn listed_subcommands(path: &[String], help: &str) -> Vec<(String, String)> {
    let mut found: Vec<(String, String)> = Vec::new();
    for line in help.lines() {
        let Some(rest) = line.strip_prefix("  ") else { continue };
        let name: String = rest
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '-' || *c == '_')
            .collect();
        let after = &rest[name.len()..];
        if name.is_empty()
            || !name.starts_with(|c: char| c.is_ascii_lowercase())
            || name == "help"
            || !(after.is_empty() || after.starts_with("  "))
            || found.iter().any(|(n, _)| *n == name)
        {
            continue;
        }
        let mut sub = path.to_vec();
        sub.push(name.clone());
        if help_text(&sub).is_some() {
            found.push((name, after.trim().to_string()));
        }
    }
    found
}

/// The generated part of `docs/CLI.md`: an index, then each command's `--help`, depth first.
fn cli_reference() -> String {
    fn walk(path: Vec<String>, about: String, out: &mut Vec<(Vec<String>, String, String)>) {
        let help = help_text(&path).unwrap_or_else(|| panic!("naadf {} --help failed", path.join(" ")));
        let subs = listed_subcommands(&path, &help);
        out.push((path.clone(), about, help));
        for (name, about) in subs {
            let mut sub = path.clone();
            sub.push(name);
            walk(sub, about, out);
        }
    }
    let mut commands = Vec::new();
    walk(Vec::new(), String::new(), &mut commands);
    let title = |p: &[String]| {
        if p.is_empty() {
            "naadf".to_string()
        } else {
            format!("naadf {}", p.join(" "))
        }
    };
    let mut s = String::from(
        "<!-- BEGIN GENERATED by `cargo test --test cli cli_reference_is_up_to_date` from `naadf … --help`; \
         do not edit below this line, rewrite with NAADF_BLESS=1 -->\n\n## Commands\n\n",
    );
    for (path, about, _) in &commands {
        let t = title(path);
        let anchor = t.replace(' ', "-");
        let indent = "  ".repeat(path.len().saturating_sub(1));
        if path.is_empty() {
            s += &format!("- [`{t}`](#{anchor})\n");
        } else if about.is_empty() {
            s += &format!("{indent}- [`{t}`](#{anchor})\n");
        } else {
            s += &format!("{indent}- [`{t}`](#{anchor}): {about}\n");
        }
    }
    for (path, _, help) in &commands {
        s += &format!("\n## {}\n\n```text\n{help}\n```\n", title(path));
    }
    s
}

/// A scene file of a few hundred bytes whose two one-voxel models sit 4095 voxels apart in
/// x and z: it asks for a world of 4096 × 64 × 4096 voxels, 262144 chunks.
fn far_apart_scene(path: &Path) {
    use dot_vox::{
        DEFAULT_INDEX_MAP, DEFAULT_PALETTE, Dict, DotVoxData, Frame, Model, SceneNode, ShapeModel, Size, Voxel,
    };
    let one = Model {
        size: Size { x: 1, y: 1, z: 1 },
        voxels: vec![Voxel { x: 0, y: 0, z: 0, i: 0 }],
    };
    let trn = |child: u32, t: &str| SceneNode::Transform {
        attributes: Dict::new(),
        frames: vec![Frame::new(Dict::from([("_t".to_string(), t.to_string())]))],
        child,
        layer_id: 0,
    };
    let shp = || SceneNode::Shape {
        attributes: Dict::new(),
        models: vec![ShapeModel {
            model_id: 0,
            attributes: Dict::new(),
        }],
    };
    let scene = DotVoxData {
        version: 150,
        index_map: DEFAULT_INDEX_MAP.to_vec(),
        models: vec![one],
        palette: DEFAULT_PALETTE.to_vec(),
        materials: vec![],
        scenes: vec![
            trn(1, "0 0 0"),
            SceneNode::Group {
                attributes: Dict::new(),
                children: vec![2, 4],
            },
            trn(3, "0 0 0"),
            shp(),
            trn(5, "4095 4095 0"),
            shp(),
        ],
        layers: vec![],
    };
    let mut bytes = Vec::new();
    scene.write_vox(&mut bytes).unwrap();
    assert!(bytes.len() < 2048, "{} bytes", bytes.len());
    std::fs::write(path, bytes).unwrap();
}

/// A small file cannot make the CLI build a huge, mostly empty world: the size it asks
/// for is checked against `--max-chunks` before anything is built, and the refusal says
/// how to go on. Under a raised bound the same file builds.
#[test]
fn worlds_larger_than_max_chunks_are_refused_before_building() {
    let dir = tempfile::tempdir().unwrap();
    let (vox, out) = (p(dir.path(), "far.vox"), p(dir.path(), "far.naadf"));
    far_apart_scene(Path::new(&vox));
    let started = std::time::Instant::now();
    support::fails(
        &["import", &vox, "-o", &out, "--max-chunks", "100000"],
        None,
        "262144 chunks, more than --max-chunks 100000 allows",
    );
    support::fails(
        &["generate", "--preset", "test", "--size", "16384,4096,16384", "-o", &out],
        None,
        "268435456 chunks, more than --max-chunks 16777216 allows",
    );
    // Refused at once: building either world would take minutes (and 13 GB for the second).
    assert!(started.elapsed().as_secs() < 30, "{:?}", started.elapsed());
    assert!(!Path::new(&out).exists(), "nothing is written");
    support::fails(
        &["import", &vox, "-o", &out, "--max-chunks", "262143"],
        None,
        "pass --max-chunks 262144 to build it anyway",
    );
    let info: serde_json::Value = serde_json::from_str(&ok(
        &["import", &vox, "-o", &out, "--max-chunks", "262144", "--json"],
        None,
    ))
    .unwrap();
    assert_eq!(info["solid_voxels"], 2, "{info}");
}

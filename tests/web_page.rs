//! The browser page in a real browser: headless Chromium with WebGPU on SwiftShader, driven
//! by playwright-core through `web/tests/driver.mjs` (docs/WEB.md).
//!
//! These need Node and Chromium. `scripts/test.sh` installs both and sets
//! `NAADF_REQUIRE_BROWSER=1`, so that in CI a missing browser fails instead of skipping.

mod support;

use naadf_client::viewer::{marker_material, marker_materials};
use naadf_proto::v1::PresenceRequest;
use naadf_proto::v1::world_service_client::WorldServiceClient;
use naadf_world::digest::BufferId;
use naadf_world::file;
use naadf_world::fingerprint::{ChunkChanges, ChunkPrints, stale_words};
use serde_json::{Value, json};
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use support::{Server, ok, p, serve_world, start_world};

/// The repository's `web/`.
fn web() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("web")
}

/// Whether Node, playwright-core and Chromium are here; without them the tests skip with a
/// message, unless `NAADF_REQUIRE_BROWSER` is set.
fn browser_available() -> bool {
    let chromium = std::env::var("NAADF_CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into());
    let node = Command::new("node")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    let missing: Vec<&str> = [
        (!node).then_some("node"),
        (!web().join("node_modules/playwright-core").exists()).then_some("web/node_modules (npm ci in web/)"),
        (!Path::new(&chromium).exists()).then_some("chromium"),
    ]
    .into_iter()
    .flatten()
    .collect();
    if missing.is_empty() {
        return true;
    }
    assert!(
        std::env::var_os("NAADF_REQUIRE_BROWSER").is_none(),
        "the browser tests need {missing:?}"
    );
    eprintln!("SKIPPED: the browser tests need {missing:?} (scripts/test.sh installs them)");
    false
}

/// What every test starts from: a temporary directory, the path of the test world in it,
/// and a browser; `None` (the test skips) where the browser is missing.
fn fixture() -> Option<(tempfile::TempDir, String, Browser)> {
    if !browser_available() {
        return None;
    }
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    Some((dir, world, Browser::start()))
}

/// `web/tests/driver.mjs`: pages in one headless Chromium, driven a command at a time.
struct Browser {
    child: Child,
    input: ChildStdin,
    output: BufReader<ChildStdout>,
}

impl Browser {
    fn start() -> Browser {
        let mut child = Command::new("node")
            .arg(web().join("tests/driver.mjs"))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .expect("node");
        let input = child.stdin.take().unwrap();
        let output = BufReader::new(child.stdout.take().unwrap());
        Browser { child, input, output }
    }

    /// Runs one command; its value, or the driver's error.
    fn try_send(&mut self, cmd: Value) -> Result<Value, String> {
        writeln!(self.input, "{cmd}").unwrap();
        let mut line = String::new();
        self.output.read_line(&mut line).unwrap();
        let answer: Value = serde_json::from_str(&line).unwrap_or_else(|e| panic!("driver said {line:?}: {e}"));
        if answer["ok"] == true {
            Ok(answer["value"].clone())
        } else {
            Err(answer["error"].as_str().unwrap_or_default().to_owned())
        }
    }

    fn send(&mut self, cmd: Value) -> Value {
        let what = cmd.to_string();
        self.try_send(cmd).unwrap_or_else(|e| panic!("{what}: {e}"))
    }

    fn open(&mut self, id: &str, url: &str) {
        self.send(json!({"op": "open", "id": id, "url": url}));
    }

    /// Waits until `until` (JavaScript over `n`, the page's `window.naadf`) holds; the state.
    fn wait(&mut self, id: &str, until: &str, ms: u64) -> Value {
        self.send(json!({"op": "wait", "id": id, "until": until, "ms": ms}))
    }

    /// Runs `js` (an async function body over `n`) in page `id`.
    fn eval(&mut self, id: &str, js: &str) -> Value {
        self.send(json!({"op": "eval", "id": id, "js": js}))
    }
}

/// Edits a box of material 2 (6 × 6 × 6 voxels) onto the empty voxel under page `id`'s
/// pointer; returns the version the edit made.
fn box_at_pointer(browser: &mut Browser, id: &str) -> Value {
    let v = &browser.eval(id, "return n.pointer")["before"];
    let (x, y, z) = (v[0].as_i64().unwrap(), v[1].as_i64().unwrap(), v[2].as_i64().unwrap());
    let edit = format!(
        r#"{{"op":"box","min":[{},{y},{}],"max":[{},{},{}],"material":2}}"#,
        x - 3,
        z - 3,
        x + 3,
        y + 6,
        z + 3
    );
    browser.eval(id, &format!("return await n.edit({})", json!(edit)))
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// `s` for a URL's query.
fn encode(s: &str) -> String {
    s.bytes()
        .map(|b| match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'_' | b'.' | b'~' => (b as char).to_string(),
            _ => format!("%{b:02X}"),
        })
        .collect()
}

/// The page on `server`'s gRPC listener at `camera`, `size` and `mode`.
fn page_url(server: &Server, camera: &str, size: &str, mode: &str) -> String {
    format!("{}/?mode={mode}&size={size}&camera={}", server.url, encode(camera))
}

/// `naadf status --json` of `server`, once quiescent.
fn status(server: &Server) -> Value {
    serde_json::from_str(&ok(&["status", "--server", &server.url, "--json"], None)).unwrap()
}

/// The page's (version, growth step, digest) equal the server's.
fn assert_on_server(page: &Value, server: &Value) {
    for (field, key) in [
        ("version", "version"),
        ("growthSeq", "growth_seq"),
        ("digest", "digest"),
    ] {
        assert_eq!(page[field], server[key], "{field}: page {page} server {server}");
    }
}

/// Long enough for a native mirror's join and the distance fields to settle on a slow machine.
const SETTLE: std::time::Duration = std::time::Duration::from_secs(120);

/// A page that is live on a quiescent world and has drawn it.
const SETTLED: &str = "n.state === 'live' && n.quiescent && n.shownVersion === n.version && n.frameMs > 0";

/// The page joins a served world and ends on the server's version, growth step and
/// digest, having received as many bytes as the native mirror does; its `albedo` and
/// `material` frames at a camera and size from the URL equal
/// `naadf render` of the same camera and size, pixel for pixel.
#[test]
fn the_page_mirrors_the_world_and_draws_what_naadf_render_draws() {
    let Some((dir, world, mut browser)) = fixture() else {
        return;
    };
    let server = serve_world(dir.path(), &world, &[], &[]);
    let camera = r#"{"pos":[64.5,50.25,-20],"yaw":10,"pitch":-25,"fov_y":70}"#;
    for mode in ["albedo", "material"] {
        browser.open(mode, &page_url(&server, camera, "160x90", mode));
        let page = browser.wait(mode, SETTLED, 120_000);
        assert_eq!(page["mode"], mode);
        assert_on_server(&page, &status(&server));
        let native: Value = serde_json::from_str(&ok(
            &[
                "mirror",
                "--server",
                &server.url,
                "--once",
                "--json",
                "--no-cache",
                "-o",
                &p(dir.path(), "mirrored.naadf"),
            ],
            None,
        ))
        .unwrap();
        assert_eq!(
            page["snapshotBytes"], native["bytes"],
            "bytes at join: page {page}, native {native}"
        );
        same_frame_as_native(&mut browser, mode, &server, camera, "160x90", mode, dir.path());
    }
    server.stop();
}

/// Two pages edit together: A places a sphere with the sphere tool, B shows it within 1 s;
/// B lists A among the users and draws A's marker; A's undo reverts only A's batch, B's
/// edits stay; both end on the server's digest. The server's idle timeout is shorter than
/// the test, so the pages' streams (HTTP/1.1 gRPC-web) must count as in use throughout.
#[test]
fn two_pages_edit_together_and_see_each_other() {
    let Some((dir, world, mut browser)) = fixture() else {
        return;
    };
    let server = serve_world(dir.path(), &world, &["--idle-timeout", "3"], &[]);
    // B stands behind A, both looking along +Z down onto the terrain: A is in B's view.
    let a_cam = r#"{"pos":[64.5,60.5,30.5],"yaw":0,"pitch":-35,"fov_y":70}"#;
    let b_cam = r#"{"pos":[64.5,62.5,4.5],"yaw":0,"pitch":-20,"fov_y":70}"#;
    browser.open("a", &page_url(&server, a_cam, "96x54", "albedo"));
    browser.open("b", &page_url(&server, b_cam, "96x54", "albedo"));
    for id in ["a", "b"] {
        browser.wait(id, SETTLED, 120_000);
    }
    let a_name = browser.eval("a", "return n.name");
    let b = browser.wait(
        "b",
        &format!("n.users.includes({a_name}) && n.markers.some(m => m.name === {a_name})"),
        10_000,
    );
    assert_eq!(b["users"].as_array().unwrap().len(), 2, "{b}");
    // A's marker is a local instance that B's GPU draws at A's camera: B's frame differs
    // from `naadf render` of B's view (which knows no markers) in a few pixels, all of them
    // around where A's camera projects (its name is written over the box). A draws B's
    // marker too (behind A, out of view).
    browser.wait("a", "n.markerInstances === 1", 10_000);
    let b = browser.wait(
        "b",
        &format!("n.markerInstances === 1 && n.shownGeneration === n.generation() && {SETTLED}"),
        10_000,
    );
    assert_eq!(b["previewInstances"], 0, "{b}");
    // A's marker takes the material the native viewer picks for A's session: one of the
    // palette's that neither emits nor mirrors (the terrain's palette has both kinds).
    let a_session: u64 = browser
        .eval("a", "return n.presenceSession")
        .as_str()
        .unwrap()
        .parse()
        .unwrap();
    let table = file::load(Path::new(&world)).unwrap().materials().clone();
    let candidates = marker_materials(&table);
    assert!(
        candidates.len() + 1 < table.len(),
        "the palette has materials markers leave out"
    );
    assert_eq!(
        b["markerMaterials"],
        json!([marker_material(a_session, &candidates).unwrap()]),
        "{b}"
    );
    let marker = b["markers"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == a_name)
        .unwrap_or_else(|| panic!("A's marker in {b}"));
    let (mx, my) = (marker["x"].as_f64().unwrap(), marker["y"].as_f64().unwrap());
    // A's name is written in white on B's overlay, centred over the box: above A's camera
    // and about as far left of it as right.
    let label = browser.eval(
        "b",
        r#"const c = document.getElementById("overlay");
           const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
           let [x0, x1, y0, y1, count] = [Infinity, -Infinity, Infinity, -Infinity, 0];
           for (let i = 0; i < d.length; i += 4) {
             if (d[i] === 255 && d[i + 1] === 255 && d[i + 2] === 255 && d[i + 3] > 128) {
               const [x, y] = [(i / 4) % c.width, Math.floor(i / 4 / c.width)];
               [x0, x1, y0, y1, count] = [Math.min(x0, x), Math.max(x1, x), Math.min(y0, y), Math.max(y1, y), count + 1];
             }
           }
           return { x0, x1, y0, y1, count };"#,
    );
    let at = |k: &str| label[k].as_f64().unwrap_or(f64::NAN);
    assert!(at("count") > 0.0, "no name on B's overlay: {label}");
    assert!(at("y1") < my, "A's name ends above A's camera at ({mx}, {my}): {label}");
    assert!(
        ((at("x0") + at("x1") + 1.0) / 2.0 - mx).abs() <= 4.0,
        "A's name is centred over A's camera at ({mx}, {my}): {label}"
    );
    let (png, native) = page_and_native(
        &mut browser,
        "b",
        &server,
        b_cam,
        &["--size", "96x54", "--mode", "albedo"],
        dir.path(),
    );
    let (page, native) = (
        image::open(&png).unwrap().to_rgba8(),
        image::open(&native).unwrap().to_rgba8(),
    );
    assert_eq!(page.dimensions(), native.dimensions());
    let differing: Vec<(u32, u32)> = page
        .enumerate_pixels()
        .filter(|&(x, y, p)| p != native.get_pixel(x, y))
        .map(|(x, y, _)| (x, y))
        .collect();
    eprintln!(
        "A's marker: {} pixels differ, around ({mx:.1}, {my:.1})",
        differing.len()
    );
    // The 3-voxel box, about 25 voxels away, covers some 4 pixels a side.
    assert!(differing.len() >= 4, "A's marker changed {} pixels", differing.len());
    for &(x, y) in &differing {
        let (dx, dy) = (f64::from(x) + 0.5 - mx, f64::from(y) + 0.5 - my);
        assert!(
            dx.abs() <= 8.0 && dy.abs() <= 8.0,
            "pixel ({x}, {y}) differs, away from A's marker at ({mx}, {my})"
        );
    }
    // A position that cannot be a camera, 1e16 voxels straight along B's view, gets neither
    // box nor name on B, as in the native viewer; one in front of B, published after it,
    // gets both (so the overlay B drew knew of the far one).
    let presence_at = |session: u64, name: &str, position: [f64; 3]| PresenceRequest {
        session,
        name: name.into(),
        position: position.to_vec(),
        forward: vec![0.0, 0.0, 1.0],
        pointer: Vec::new(),
        tool: String::new(),
    };
    let far = 1e16;
    let along_b = [64.5, 62.5 + far * (-20f64).to_radians().tan(), 4.5 + far];
    tokio::runtime::Runtime::new().unwrap().block_on(async {
        let mut c = WorldServiceClient::connect(server.url.clone()).await.unwrap();
        c.publish(presence_at(4242, "far away", along_b)).await.unwrap();
        c.publish(presence_at(4243, "in front", [40.5, 50.5, 40.5]))
            .await
            .unwrap();
    });
    let b = browser.wait("b", "n.markers.some(m => m.name === 'in front')", 10_000);
    assert_eq!(b["users"].as_array().unwrap().len(), 4, "{b}");
    assert!(
        !b["markers"].as_array().unwrap().iter().any(|m| m["name"] == "far away"),
        "a name for a camera 1e16 voxels away: {b}"
    );
    assert_eq!(b["markerInstances"], 2, "{b}");

    // B edits first; then A places a sphere where its view's centre meets the terrain.
    let b_box = r#"{"op":"box","min":[10,40,10],"max":[14,44,14],"material":2}"#;
    browser.eval("b", &format!("return await n.edit({})", json!(b_box)));
    browser.send(json!({"op": "select", "id": "a", "selector": "#tool", "value": "sphere"}));
    browser.send(json!({"op": "fill", "id": "a", "selector": "#radius", "value": "3"}));
    let before = browser.eval("a", "return n.version");
    // The canvas's centre, where the sphere tool builds (the empty voxel before the hit).
    let aimed = browser.eval("a", "return n.pointer");
    let centre = &aimed["before"];
    browser.send(json!({"op": "click", "id": "a", "x": 0.5, "y": 0.5}));
    let a_state = browser.wait("a", &format!("n.version > {before}"), 10_000);
    let at = |v: &Value| format!("n.voxel({}, {}, {})", v[0], v[1], v[2]);
    assert_eq!(
        browser.eval("a", &format!("return {}", at(centre))),
        1,
        "A's sphere at {centre}"
    );
    let sphere_version = a_state["version"].as_u64().unwrap();
    let started = std::time::Instant::now();
    browser.wait("b", &format!("n.shownVersion >= {sphere_version}"), 10_000);
    let shown_after = started.elapsed();
    assert!(
        shown_after < std::time::Duration::from_secs(1),
        "B showed A's sphere {shown_after:?} after A's acknowledgement"
    );

    // The idle timeout passes with both streams open; they keep following.
    std::thread::sleep(std::time::Duration::from_secs(5));
    browser.eval("a", "return await n.undo()");
    let end = serde_json::from_str::<Value>(&ok(&["status", "--server", &server.url, "--json"], None)).unwrap();
    for id in ["a", "b"] {
        let page = browser.wait(id, &format!("n.version >= {} && {SETTLED}", end["version"]), 20_000);
        assert_on_server(&page, &status(&server));
        assert_eq!(page["joins"], 1, "{id} joined again: {page}");
        // B's box stays; A's sphere is gone.
        assert_eq!(browser.eval(id, "return n.voxel(11, 41, 11)"), 2, "{id}: B's box");
        assert_eq!(
            browser.eval(id, &format!("return {}", at(centre))),
            0,
            "{id}: A's sphere"
        );
    }

    // Touch: one finger dragged right turns A's view right; two fingers dragged up the
    // screen fly it forward. The link follows.
    let touch = r#"
        const c = document.getElementById("view");
        const at = (type, id, x, y) => c.dispatchEvent(new PointerEvent(type, { pointerId: id, pointerType: "touch", clientX: x, clientY: y, bubbles: true }));
        window.linked = () => JSON.parse(new URLSearchParams(location.search).get("camera"));
        window.drag = (fingers, dx, dy) => {
            for (let f = 0; f < fingers; f++) at("pointerdown", 10 + f, 300 + 40 * f, 200);
            for (let k = 1; k <= 10; k++) for (let f = 0; f < fingers; f++) at("pointermove", 10 + f, 300 + 40 * f + k * dx / 10, 200 + k * dy / 10);
            for (let f = 0; f < fingers; f++) at("pointerup", 10 + f, 300 + 40 * f + dx, 200 + dy);
        };
        return window.linked();"#;
    let before = browser.eval("a", touch);
    browser.eval("a", "window.drag(1, 100, 0); return 1");
    let yaw = before["yaw"].as_f64().unwrap() + 15.0;
    let turned = browser.wait("a", &format!("Math.abs(window.linked().yaw - {yaw}) < 1e-6"), 10_000);
    assert_eq!(turned["state"], "live");
    let turned = browser.eval("a", "return window.linked()");
    assert_eq!(turned["pos"], before["pos"], "one finger only looks");
    browser.eval("a", "window.drag(2, 0, -100); return 1");
    let moved = browser.wait(
        "a",
        &format!(
            "JSON.stringify(window.linked().pos) !== {}",
            json!(turned["pos"].to_string())
        ),
        10_000,
    );
    assert_eq!(moved["state"], "live");
    let moved = browser.eval("a", "return window.linked()");
    assert_eq!(moved["yaw"], turned["yaw"], "two fingers only fly");
    let (yaw, pitch) = (
        turned["yaw"].as_f64().unwrap().to_radians(),
        turned["pitch"].as_f64().unwrap().to_radians(),
    );
    let forward = [yaw.sin() * pitch.cos(), pitch.sin(), yaw.cos() * pitch.cos()];
    let along: f64 = (0..3)
        .map(|a| (moved["pos"][a].as_f64().unwrap() - turned["pos"][a].as_f64().unwrap()) * forward[a])
        .sum();
    assert!(along > 1.0, "flew {along} voxels forward");
    server.stop();
}

/// The voxel tool previews the voxel it would place as a local instance, drawn by the GPU
/// where the voxel would go: the frame with the preview differs from the one without and
/// equals, but for pixels on a tie, the frame after the click placed that voxel for real.
/// Picking does not see the preview (the click places where the preview stood).
#[test]
fn the_voxel_tool_previews_the_voxel_it_would_place() {
    let Some((dir, world, mut browser)) = fixture() else {
        return;
    };
    let server = serve_world(dir.path(), &world, &[], &[]);
    // Close to the ground, so that one voxel covers several pixels.
    let camera = r#"{"pos":[64.5,40.5,55.5],"yaw":0,"pitch":-35,"fov_y":70}"#;
    browser.open("a", &page_url(&server, camera, "192x108", "material"));
    browser.wait("a", SETTLED, 120_000);
    // The pointer at the canvas's centre.
    browser.eval(
        "a",
        r#"const c = document.getElementById("view"); const r = c.getBoundingClientRect();
           c.dispatchEvent(new MouseEvent("mousemove", { clientX: r.left + r.width / 2, clientY: r.top + r.height / 2, bubbles: true }));
           return 1"#,
    );
    let frame = |browser: &mut Browser, name: &str, tool: &str| {
        browser.send(json!({"op": "select", "id": "a", "selector": "#tool", "value": tool}));
        let boxes = usize::from(tool == "voxel");
        let shown =
            format!("n.previewInstances === {boxes} && n.shownGeneration === n.generation() && n.pointer !== null");
        browser.wait("a", &format!("{SETTLED} && {shown}"), 20_000);
        let png = p(dir.path(), &format!("{name}.png"));
        browser.send(json!({"op": "capture", "id": "a", "path": png}));
        image::open(&png).unwrap().to_rgba8()
    };
    let plain = frame(&mut browser, "plain", "erase");
    let aimed = browser.eval("a", "return n.pointer");
    // A material other than the one under the pointer, so that the preview shows.
    let material = browser.eval(
        "a",
        r##"const under = n.voxel(...n.pointer.voxel);
           const b = [...document.querySelectorAll("#palette button")].find((b) => b.title !== `material ${under}`);
           b.click();
           return Number(b.title.split(" ")[1]);"##,
    );
    let previewed = frame(&mut browser, "previewed", "voxel");
    let changed = plain.pixels().zip(previewed.pixels()).filter(|(a, b)| a != b).count();
    assert!(changed >= 4, "the preview changed {changed} pixels");
    // Place it, then look again without a preview.
    let before = browser.eval("a", "return n.version");
    browser.send(json!({"op": "click", "id": "a", "x": 0.5, "y": 0.5}));
    browser.wait("a", &format!("n.version > {before}"), 10_000);
    let target = &aimed["before"];
    let placed = browser.eval(
        "a",
        &format!("return n.voxel({}, {}, {})", target[0], target[1], target[2]),
    );
    assert_eq!(
        placed, material,
        "the click placed at {target}, where the preview stood"
    );
    let committed = frame(&mut browser, "committed", "erase");
    let differing = previewed
        .pixels()
        .zip(committed.pixels())
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        differing * 10 <= changed,
        "{differing} pixels differ between the preview and the placed voxel ({changed} changed)"
    );
    server.stop();
}

/// The server is killed with -9 and restarted on the same data and ports: the page
/// reconnects, resumes from what it holds without a snapshot, and keeps following; a reload
/// of the page then takes the world from its cache and downloads none of it.
#[test]
fn the_page_resumes_after_the_server_is_killed() {
    let Some((dir, world, mut browser)) = fixture() else {
        return;
    };
    let (grpc, http) = (support::free_addr(), support::free_addr());
    let listen = ["--grpc", grpc.as_str(), "--http", http.as_str()];
    let server = serve_world(dir.path(), &world, &listen, &[]);
    browser.open(
        "a",
        &page_url(&server, r#"{"pos":[64,60,-10],"yaw":0,"pitch":-30}"#, "64x36", "albedo"),
    );
    browser.wait("a", SETTLED, 120_000);
    let op = r#"{"op":"box","min":[20,40,20],"max":[24,44,24],"material":3}"#;
    ok(&["edit", "--server", &server.url, "--ops", "-"], Some(op));
    let before = browser.wait(
        "a",
        &format!("n.version === {} && {SETTLED}", status(&server)["version"]),
        20_000,
    );
    let received = before["bytesReceived"].as_u64().unwrap();
    server.kill9();

    browser.wait("a", "n.state === 'reconnecting'", 20_000);
    let server = serve_world(dir.path(), &world, &listen, &[]);
    let resumed = browser.wait(
        "a",
        &format!("n.state === 'live' && n.joins > {}", before["joins"]),
        30_000,
    );
    assert_eq!(
        resumed["snapshots"], 1,
        "the page resumed without a snapshot: {resumed}"
    );
    let op = r#"{"op":"sphere","center":[40,45,40],"radius":4,"material":2}"#;
    ok(&["edit", "--server", &server.url, "--ops", "-"], Some(op));
    let end = status(&server);
    let page = browser.wait("a", &format!("n.version === {} && {SETTLED}", end["version"]), 20_000);
    assert_on_server(&page, &status(&server));
    assert_eq!(page["snapshots"], 1, "{page}");
    let resumed_bytes = page["bytesReceived"].as_u64().unwrap() - received;
    assert!(
        resumed_bytes < 64 << 10,
        "the resume and an edit took {resumed_bytes} bytes"
    );

    // A reload rebuilds the world from the page's cache and downloads none of it again.
    std::thread::sleep(std::time::Duration::from_millis(1500)); // the cache is written within 1 s
    browser.send(json!({"op": "reload", "id": "a"}));
    let reloaded = browser.wait("a", SETTLED, 60_000);
    assert_on_server(&reloaded, &status(&server));
    assert_eq!(reloaded["snapshots"], 0, "{reloaded}");
    assert!(
        reloaded["snapshotBytes"].as_u64().unwrap() < 1024,
        "only a resume: {reloaded}"
    );
    server.stop();
}

/// With tokens: no token and a wrong token each ask for a token with the server's reason;
/// a viewer token shows the world with editing disabled, and its edits are refused; nothing
/// is edited.
#[test]
fn the_page_asks_for_a_token_and_refuses_viewers_edits() {
    let Some((dir, world, mut browser)) = fixture() else {
        return;
    };
    let tokens = [("NAADF_TOKENS", "vt=vera:viewer,et=edwin:editor")];
    let server = serve_world(dir.path(), &world, &[], &tokens);
    let version = support::naadf(&["status", "--server", &server.url, "--token", "vt", "--json"], None);
    let version: Value = serde_json::from_str(&String::from_utf8_lossy(&version.stdout)).unwrap();
    browser.open(
        "a",
        &page_url(&server, r#"{"pos":[64,60,-10],"yaw":0,"pitch":-30}"#, "64x36", "albedo"),
    );
    let asked = browser.wait("a", "n.state === 'need-token'", 30_000);
    assert!(!asked["message"].as_str().unwrap().is_empty(), "{asked}");
    assert!(
        browser.eval("a", "return !document.getElementById('token').hidden") == true,
        "the token form is shown"
    );
    let submit = |token: &str| {
        format!(
            "document.getElementById('token-value').value = {}; document.getElementById('token').requestSubmit(); return null",
            json!(token)
        )
    };
    browser.eval("a", &submit("wrong"));
    let wrong = browser.wait("a", "n.state === 'need-token' && n.joins >= 2", 30_000);
    assert!(wrong["message"].as_str().unwrap().contains("token"), "{wrong}");
    browser.eval("a", &submit("vt"));
    let viewer = browser.wait("a", &format!("n.role === 'viewer' && {SETTLED}"), 60_000);
    assert_on_server(&viewer, &version);
    assert!(
        browser.eval(
            "a",
            "return document.getElementById('tools').classList.contains('disabled')"
        ) == true,
        "the tools are disabled for a viewer"
    );
    let refused = browser.send(json!({"op": "eval", "id": "a", "js": "try { await n.edit('{\"op\":\"set\",\"voxels\":[[1,1,1,1]]}'); return 'applied'; } catch (e) { return String(e.message); }"}));
    assert!(
        refused.as_str().unwrap().contains("permission") || refused.as_str().unwrap().contains("viewer"),
        "{refused}"
    );
    let after = support::naadf(&["status", "--server", &server.url, "--token", "vt", "--json"], None);
    let after: Value = serde_json::from_str(&String::from_utf8_lossy(&after.stdout)).unwrap();
    assert_eq!(after["version"], version["version"], "nothing was edited");
    assert_eq!(browser.eval("a", "return sessionStorage.getItem('naadf.token')"), "vt");
    assert!(
        !browser
            .eval("a", "return location.href")
            .as_str()
            .unwrap()
            .contains("vt"),
        "the token is never in the URL"
    );
    server.stop();
}

/// A relay serves the page on its own gRPC listener, and forwards its edits upstream.
#[test]
fn a_relay_serves_the_page_and_forwards_its_edits() {
    let Some((dir, world, mut browser)) = fixture() else {
        return;
    };
    let server = serve_world(dir.path(), &world, &[], &[]);
    let relay = Server::relay(&server.url, &[], &dir.path().join("relay.log"));
    browser.open(
        "a",
        &page_url(&relay, r#"{"pos":[64,60,-10],"yaw":0,"pitch":-30}"#, "64x36", "albedo"),
    );
    browser.wait("a", SETTLED, 120_000);
    let version = browser.eval(
        "a",
        r#"return await n.edit('{"op":"box","min":[30,40,30],"max":[34,44,34],"material":2}')"#,
    );
    assert_eq!(status(&server)["version"], version, "the edit reached the server");
    let page = browser.wait("a", &format!("n.version === {version} && {SETTLED}"), 20_000);
    assert_on_server(&page, &status(&server));
    assert_eq!(browser.eval("a", "return n.voxel(31, 41, 31)"), 2);
    relay.stop();
    server.stop();
}

/// `pathtrace` adds one sample per pixel per frame while the view stays still; after N
/// samples the page's frame is `naadf render --mode pathtrace --spp N` of the same view (the
/// same samples of the same light model). The page tone-maps in JavaScript's `f64` where
/// the native renderer uses `f32`, and SwiftShader's `exp`, `pow` and trigonometry need not
/// round as lavapipe's do, so a channel may differ by a level (measured: 1 level, in 0.03%
/// of the channels): the test bounds the mean and the largest difference.
#[test]
fn the_path_tracer_accumulates_what_naadf_render_traces() {
    let Some((dir, world, mut browser)) = fixture() else {
        return;
    };
    let server = serve_world(dir.path(), &world, &[], &[]);
    let (png, native) = progressive_page_and_native(&mut browser, &server, "pathtrace", 8, &["--spp", "8"], dir.path());
    let (mean, most) = difference(&png, &native);
    eprintln!("pathtrace: mean channel difference {mean:.4}, largest {most}");
    assert!(mean < 0.01 && most <= 2, "mean {mean}, largest {most}");
    server.stop();
}

/// `roma` runs the native ROMA passes with maps kept as the native renderer keeps them:
/// the page's first sample is `naadf render --mode roma --frames 1` of the same view (the
/// same random streams, and a first frame is its sample). A sample's visibility is all or
/// nothing, so where SwiftShader and lavapipe round a column boundary differently a pixel
/// flips: the test bounds the mean difference and the share of channels that differ.
#[test]
fn the_roma_mode_draws_what_naadf_render_draws() {
    let Some((dir, world, mut browser)) = fixture() else {
        return;
    };
    let server = serve_world(dir.path(), &world, &[], &[]);
    let (png, native) = progressive_page_and_native(&mut browser, &server, "roma", 1, &["--frames", "1"], dir.path());
    let (mean, most) = difference(&png, &native);
    let share = share_off_by_more_than_2(&png, &native);
    eprintln!("roma: mean channel difference {mean:.4}, largest {most}, {share:.4} of channels off by more than 2");
    assert!(mean < 0.5 && share < 0.01, "mean {mean}, share {share}");
    server.stop();
}

/// `irradiance` runs the native irradiance cache's passes, its table kept as the native
/// renderer keeps it: the page's first irradiance frame, on a settled world with a new
/// cache, is `naadf render --mode irradiance --frames 1` of the same view. That frame lights
/// every diffuse world surface by gathering (no entry has samples yet), one sun sample and
/// one cosine ray each, so it is as deterministic as `roma`'s and bounded the same way.
/// Its update then samples every face the frame requested (the budget covers them all),
/// as the counters read back with the frame show; later frames light those faces from
/// their entries, and an edit clears the entries near it.
///
/// Measured on the test terrain: the first frame within a mean channel difference of
/// 0.0005, at most 1 level; it requested and keyed 1,636 faces (those it lit and those its
/// gathers met), the second frame 1,599, of which 1,197 new; the frame after an edit in
/// view 1,548, of which 1,205 without samples where it keyed only 15 anew.
#[test]
fn the_irradiance_mode_draws_what_naadf_render_draws() {
    let Some((dir, world, mut browser)) = fixture() else {
        return;
    };
    let server = serve_world(dir.path(), &world, &[], &[]);
    // The mode is offered in a link.
    browser.open("b", &page_url(&server, PROGRESSIVE_CAMERA, "64x36", "irradiance"));
    let b = browser.wait("b", "n.mode === 'irradiance'", 10_000);
    assert_eq!(b["message"], "", "the link's mode is accepted");
    browser.send(json!({"op": "close", "id": "b"}));

    // A settled world first, so that the cache's first frame is the page's first sample:
    // then `irradiance` from the page's mode list.
    browser.open(
        "a",
        &format!("{}&spp=1", page_url(&server, PROGRESSIVE_CAMERA, "64x36", "albedo")),
    );
    browser.wait("a", SETTLED, 120_000);
    browser.send(json!({"op": "select", "id": "a", "selector": "#mode", "value": "irradiance"}));
    let page = browser.wait(
        "a",
        "n.mode === 'irradiance' && n.samples === 1 && n.irradiance !== null",
        120_000,
    );
    let stats = &page["irradiance"];
    assert_eq!(stats["stamp"], 1, "a new cache: {stats}");
    let requested = stats["requested"].as_u64().unwrap();
    assert!(requested > 0, "{stats}");
    for counter in ["fresh", "samples", "keyed"] {
        assert_eq!(stats[counter].as_u64(), Some(requested), "{counter}: {stats}");
    }
    let (png, native) = page_and_native(
        &mut browser,
        "a",
        &server,
        PROGRESSIVE_CAMERA,
        &["--size", "64x36", "--mode", "irradiance", "--frames", "1"],
        dir.path(),
    );
    let (mean, most) = difference(&png, &native);
    let share = share_off_by_more_than_2(&png, &native);
    eprintln!(
        "irradiance: mean channel difference {mean:.4}, largest {most}, {share:.4} of channels off by more than 2"
    );
    assert!(mean < 0.5 && share < 0.01, "mean {mean}, share {share}");

    // A second frame of the same view (its pixels jittered elsewhere): the faces it meets
    // again have samples and light their pixels, the faces new to it are keyed and are
    // the only ones with none, and the budget still covers every request.
    browser.eval("a", "n.redraw()");
    let page = browser.wait("a", "n.samples === 2 && n.irradiance.stamp === 2", 120_000);
    let second = &page["irradiance"];
    let count = |name: &str| second[name].as_u64().unwrap();
    eprintln!("irradiance: frame 1 {stats}, frame 2 {second}");
    assert!(count("fresh") < count("requested"), "{second}");
    assert_eq!(count("keyed"), requested + count("fresh"), "{second}");
    assert_eq!(count("samples"), count("requested"), "{second}");

    // An edit in view, made while the page draws `albedo`: the next `irradiance` frame
    // clears the entries near the chunks it changed, so more of the faces it requests have
    // no samples than it keys anew (without the invalidation, exactly as many).
    browser.send(json!({"op": "select", "id": "a", "selector": "#mode", "value": "albedo"}));
    browser.wait(
        "a",
        "n.mode === 'albedo' && n.samples === 0 && n.pointer !== null",
        60_000,
    );
    let version = box_at_pointer(&mut browser, "a");
    browser.wait("a", &format!("n.shownVersion >= {version} && {SETTLED}"), 120_000);
    browser.send(json!({"op": "select", "id": "a", "selector": "#mode", "value": "irradiance"}));
    let page = browser.wait("a", "n.mode === 'irradiance' && n.irradiance.stamp === 3", 120_000);
    let third = &page["irradiance"];
    let count3 = |name: &str| third[name].as_u64().unwrap();
    eprintln!("irradiance: after an edit {third}");
    assert!(count3("keyed") >= count("keyed"), "the cache was kept: {third}");
    assert!(count3("fresh") > count3("keyed") - count("keyed"), "{third}");
    assert!(
        count3("fresh") < count3("requested"),
        "only the entries near the edit: {third}"
    );
    assert_eq!(count3("samples"), count3("requested"), "{third}");
    server.stop();
}

/// `gi` runs the native GI pipeline's passes; after N frames of a still view (`spp=N`),
/// the page's frame is `naadf render --mode gi --frames N` of the same view (within the
/// bound `gi_against_native` explains).
#[test]
fn the_gi_mode_draws_what_naadf_render_draws() {
    let Some((dir, world, mut browser)) = fixture() else {
        return;
    };
    let server = serve_world(dir.path(), &world, &[], &[]);
    let camera = r#"{"pos":[64.5,50.25,-20],"yaw":10,"pitch":-25,"fov_y":70}"#;
    gi_against_native(&mut browser, "a", &server, camera, dir.path());

    // An edit in view: the page names the chunks that show something else, which the GI's
    // history drops and fades the light of. The oracle: the native fingerprints of every
    // chunk of the world before and after, from a native mirror.
    let rt = tokio::runtime::Runtime::new().unwrap();
    let client = rt
        .block_on(naadf_client::Client::connect(&server.url, None, None))
        .unwrap();
    let mut session = rt.block_on(client.join(None)).unwrap();
    let before_version = browser.eval("a", "return n.version").as_u64().unwrap();
    let mut prints = ChunkPrints::new(rt.block_on(session.until_quiescent(before_version, SETTLE)).unwrap());
    let generation = browser.eval("a", "return n.generation()");
    let version = box_at_pointer(&mut browser, "a");
    let page = browser.wait(
        "a",
        &format!(
            "n.shownVersion >= {version} && n.samples === {GI_FRAMES} && n.quiescent && n.shownVersion === n.version"
        ),
        180_000,
    );
    let after = rt
        .block_on(session.until_quiescent(page["version"].as_u64().unwrap(), SETTLE))
        .unwrap();
    assert_eq!(after.version(), page["version"].as_u64().unwrap());
    // Every page of every buffer but the materials (the edit kept them) may have changed.
    let every_page: Vec<_> = BufferId::WORLD
        .iter()
        .filter(|&&id| id != BufferId::Materials)
        .map(|&id| (id, stale_words(&[], after.page_hashes(id))))
        .collect();
    let ChunkChanges::Chunks(expected) = prints.update(after, &every_page) else {
        panic!("a box edit changed everything");
    };
    let changed = browser.eval("a", &format!("return n.changedChunks({generation})"));
    assert!(!expected.is_empty());
    assert_eq!(changed, json!(expected), "the chunks the page found changed");
    server.stop();
}

/// Opens page `id` in `gi` at `camera` and 64×36, lets it draw `GI_FRAMES` frames of the
/// still view, and compares its frame with `naadf render --mode gi --frames` of the same
/// view.
///
/// Both are deterministic (each repeats itself exactly), and the first frame agrees within
/// a level. Later frames choose among samples (the ring's projection, the resampling's
/// reservoirs) by comparing floats, and SwiftShader's `exp`, `pow`, trigonometry and fused
/// multiply-adds need not round as lavapipe's do: a choice that flips changes a pixel by
/// up to a few tens of levels in that frame, and the TAA averages it down. Measured over a
/// close view of the test terrain: largest difference 18 levels after 2 frames, 10 after
/// 4, 5 after 8, 3 after 16, in at most 28 of 9,216 channels; every other channel within a
/// level. The bound below holds after 8 frames.
fn gi_against_native(browser: &mut Browser, id: &str, server: &Server, camera: &str, dir: &Path) {
    let frames = GI_FRAMES;
    browser.open(id, &format!("{}&spp={frames}", page_url(server, camera, "64x36", "gi")));
    let page = browser.wait(
        id,
        &format!("n.samples === {frames} && n.state === 'live' && n.quiescent && n.shownVersion === n.version"),
        180_000,
    );
    assert_eq!(page["mode"], "gi");
    let (png, native) = page_and_native(
        browser,
        id,
        server,
        camera,
        &["--size", "64x36", "--mode", "gi", "--frames", frames],
        dir,
    );
    let (mean, most) = difference(&png, &native);
    eprintln!("gi ({id}): mean channel difference {mean:.4}, largest {most}");
    assert!(mean < 0.02 && most <= 8, "mean {mean}, largest {most}");
}

/// Opens a 64 × 36 page in progressive `mode` (`pathtrace`, `roma`) with `spp` samples of
/// a still view, waits for them, and renders the same view with `naadf render --mode mode`
/// and `args`; returns the two PNGs' paths.
fn progressive_page_and_native(
    browser: &mut Browser,
    server: &Server,
    mode: &str,
    spp: u32,
    args: &[&str],
    dir: &Path,
) -> (String, String) {
    let camera = PROGRESSIVE_CAMERA;
    browser.open("a", &format!("{}&spp={spp}", page_url(server, camera, "64x36", mode)));
    let until = format!("n.samples === {spp} && n.state === 'live' && n.quiescent");
    let page = browser.wait("a", &until, 120_000);
    assert_eq!(page["mode"], mode);
    let mut native_args = vec!["--size", "64x36", "--mode", mode];
    native_args.extend(args);
    page_and_native(browser, "a", server, camera, &native_args, dir)
}

/// The view the progressive modes' comparisons draw.
const PROGRESSIVE_CAMERA: &str = r#"{"pos":[64.5,50.25,-20],"yaw":10,"pitch":-25,"fov_y":70}"#;

/// Frames of a still view the GI comparisons let the page draw.
const GI_FRAMES: &str = "8";

/// Captures page `id`'s frame, and renders `camera` with `naadf render` and `args` (size,
/// mode and the rest); returns the two PNGs' paths.
fn page_and_native(
    browser: &mut Browser,
    id: &str,
    server: &Server,
    camera: &str,
    args: &[&str],
    dir: &Path,
) -> (String, String) {
    let png = p(dir, &format!("page-{id}.png"));
    browser.send(json!({"op": "capture", "id": id, "path": png}));
    let native = p(dir, &format!("native-{id}.png"));
    let mut command = vec!["render", "--server", &server.url, "--camera", camera];
    command.extend(args);
    command.extend(["-o", &native]);
    ok(&command, None);
    (png, native)
}

/// The mean and the largest difference of two equally sized images' channels.
fn difference(a: &str, b: &str) -> (f64, i32) {
    let a = image::open(a).unwrap().to_rgba8();
    let b = image::open(b).unwrap().to_rgba8();
    assert_eq!(a.dimensions(), b.dimensions());
    let diffs: Vec<i32> = a
        .as_raw()
        .iter()
        .zip(b.as_raw())
        .map(|(x, y)| (i32::from(*x) - i32::from(*y)).abs())
        .collect();
    let mean = diffs.iter().sum::<i32>() as f64 / diffs.len() as f64;
    (mean, diffs.iter().max().copied().unwrap_or(0))
}

/// The share of two equally sized images' channels that differ by more than 2 levels.
fn share_off_by_more_than_2(a: &str, b: &str) -> f64 {
    let (a, b) = (image::open(a).unwrap().to_rgba8(), image::open(b).unwrap().to_rgba8());
    let off = a
        .as_raw()
        .iter()
        .zip(b.as_raw())
        .filter(|(x, y)| x.abs_diff(**y) > 2)
        .count();
    off as f64 / a.as_raw().len() as f64
}

/// With `--tls-cert`, the gRPC listener serves the page, its assets and gRPC-web over https
/// with the server's certificate, and the page works there (a secure context on any
/// address); the HTTP port's `/` sends browsers to it.
#[test]
fn the_page_is_served_over_https_with_the_servers_certificate() {
    let Some((dir, world, mut browser)) = fixture() else {
        return;
    };
    let pair = rcgen::generate_simple_self_signed(vec!["localhost".to_string()]).unwrap();
    let (cert, key) = (p(dir.path(), "cert.pem"), p(dir.path(), "key.pem"));
    std::fs::write(&cert, pair.cert.pem()).unwrap();
    std::fs::write(&key, pair.signing_key.serialize_pem()).unwrap();
    let server = serve_world(dir.path(), &world, &["--tls-cert", &cert, "--tls-key", &key], &[]);
    let port = server.url.rsplit(':').next().unwrap().to_owned();
    let redirect = redirect_of(&server.http, "/?mode=material");
    assert_eq!(redirect, format!("https://127.0.0.1:{port}/?mode=material"));
    let url = format!("https://localhost:{port}/?mode=albedo&size=64x36");
    browser.send(json!({"op": "open", "id": "a", "url": url, "insecure": true}));
    let page = browser.wait("a", SETTLED, 120_000);
    let https = format!("https://localhost:{port}");
    let status: Value =
        serde_json::from_str(&ok(&["status", "--server", &https, "--ca", &cert, "--json"], None)).unwrap();
    assert_on_server(&page, &status);
    server.stop();
}

/// The `Location` of the HTTP listener's answer to `GET path`.
fn redirect_of(http: &str, path: &str) -> String {
    use std::io::Read;
    let mut s = std::net::TcpStream::connect(http).unwrap();
    write!(s, "GET {path} HTTP/1.1\r\nHost: {http}\r\nConnection: close\r\n\r\n").unwrap();
    let mut head = String::new();
    s.read_to_string(&mut head).unwrap();
    assert!(head.starts_with("HTTP/1.1 307"), "{head}");
    head.lines()
        .find_map(|l| l.strip_prefix("location: "))
        .unwrap_or_else(|| panic!("no location in {head}"))
        .to_owned()
}

/// A world with entities: the page takes the entity buffers from the snapshot's pages
/// (a patch-form snapshot carries all eight buffers), draws the entities as `naadf render`
/// does, and follows their moves on the server's digest.
#[test]
fn the_page_draws_entities_and_follows_their_moves() {
    let Some((dir, world, mut browser)) = fixture() else {
        return;
    };
    let server = serve_world(dir.path(), &world, &[], &[]);
    let rt = tokio::runtime::Runtime::new().unwrap();
    let client = rt
        .block_on(naadf_client::Client::connect(&server.url, None, None))
        .unwrap();
    let (model, spawns) = support::crates();
    rt.block_on(async {
        client.edit(model, 1).await.unwrap();
        client.spawn_entities(&spawns, 2).await.unwrap();
    });
    let camera = r#"{"pos":[40.5,56.5,22.5],"yaw":0,"pitch":-35,"fov_y":70}"#;
    browser.open("a", &page_url(&server, camera, "96x54", "albedo"));
    let page = browser.wait("a", SETTLED, 120_000);
    assert_on_server(&page, &status(&server));
    assert_eq!(page["joins"], 1);
    let drawn = same_frame_as_native(&mut browser, "a", &server, camera, "96x54", "albedo", dir.path());
    let moved = naadf_client::Pose {
        id: 2,
        pos: [38.0, 51.0, 33.0],
        rot: [0.0, 0.0, 0.0, 1.0],
    };
    let version = rt.block_on(client.move_entities(&[moved], 3)).unwrap().version;
    let page = browser.wait("a", &format!("n.version >= {version} && {SETTLED}"), 20_000);
    assert_on_server(&page, &status(&server));
    let after = same_frame_as_native(&mut browser, "a", &server, camera, "96x54", "albedo", dir.path());
    assert_ne!(drawn, after, "the move shows");
    // The GI, whose passes read the entities' poses, too.
    gi_against_native(&mut browser, "g", &server, camera, dir.path());
    server.stop();
}

/// The page builds the instance hierarchy (its TypeScript port of the binned SAH build,
/// web/src/instances.ts) word for word as the native client does
/// (`naadf_world::entity::hierarchy_words`): rotated instances of every size over a large
/// world with empty slots between them, a few instances, one, many at one place (where the
/// build falls back to the median) and a row along one axis. And after a change of the
/// records it keeps the hierarchy the native client keeps: refitted after small moves,
/// built anew after moves anywhere and when the slots change.
#[test]
fn the_page_builds_the_instance_hierarchy_the_native_client_builds() {
    use naadf_world::entity::bvh::Bvh;
    use naadf_world::entity::pack::{InstanceRecord, quantise_pose};
    use naadf_world::entity::{REFIT_SLACK, hierarchy_words, instance_boxes};
    use naadf_world::raysets::SplitMix64;
    let Some((dir, world, mut browser)) = fixture() else {
        return;
    };
    let server = serve_world(dir.path(), &world, &[], &[]);
    browser.open("a", &format!("{}/", server.url));
    browser.wait("a", "true", 60_000);
    let mut rng = SplitMix64(35);
    let mut unit = move || rng.unit();
    // An instance's size, position and rotation.
    type Pose = ([u32; 3], [f64; 3], [f64; 4]);
    // An instance buffer with a record at each `Some` pose (slot = id) and empty slots at
    // each `None`.
    let buffer = |poses: Vec<Option<Pose>>| -> Vec<u32> {
        poses
            .into_iter()
            .enumerate()
            .flat_map(|(id, pose)| match pose {
                None => [0; 5],
                Some((size, pos, rot)) => {
                    let q = quantise_pose(pos, rot).expect("a pose in range");
                    InstanceRecord {
                        id: id as u32,
                        size,
                        voxel_start: 3,
                        pos: q.fixed,
                        inv_rot: q.inv_rot,
                    }
                    .pack()
                }
            })
            .collect()
    };
    let mut scattered = Vec::new();
    for k in 0..1200 {
        let size = [0; 3].map(|_| 1 + (unit() * 126.0) as u32);
        let pos = [unit() * 1000.0, unit() * 500.0, unit() * 2000.0];
        let rot = [0; 4].map(|_| unit() - 0.5);
        scattered.push((k % 7 != 3).then_some((size, pos, rot)));
    }
    let same_place = (0..40)
        .map(|_| Some(([8, 8, 8], [100.0, 50.0, 100.0], [0.0, 0.0, 0.0, 1.0])))
        .collect();
    let row = (0..33)
        .map(|k| {
            Some((
                [4, 4, 4],
                [10.0 + 6.0 * f64::from(k), 20.0, 30.0],
                [0.0, 0.3, 0.0, 0.95],
            ))
        })
        .collect();
    let few = scattered.iter().flatten().take(3).map(|&p| Some(p)).collect();
    let one = vec![None, scattered[0]];
    for (name, poses) in [
        ("scattered", scattered.clone()),
        ("same place", same_place),
        ("row", row),
        ("few", few),
        ("one", one),
    ] {
        let records = buffer(poses);
        let native = naadf_world::entity::hierarchy_words(&records);
        assert!(!native.is_empty(), "{name}");
        let page = browser.eval("a", &format!("return n.hierarchy({})", json!(records)));
        let page: Vec<u32> = serde_json::from_value(page).unwrap();
        assert_eq!(page.len(), native.len(), "{name}: nodes");
        let differing = page.iter().zip(&native).filter(|(a, b)| a != b).count();
        assert_eq!(differing, 0, "{name}: {differing} of {} words differ", native.len());
    }
    // The native rule (docs/FORMAT.md §5.10), restated over the hierarchy's public parts:
    // the same slots refit the hierarchy built for `previous`, kept while its expected
    // node visits stay within `REFIT_SLACK` of the build's.
    let slots = |records: &[u32]| -> Vec<u32> {
        (0..records.len() as u32 / 5)
            .filter(|&s| records[5 * s as usize + 4] != 0)
            .collect()
    };
    let kept_after = |previous: &[u32], records: &[u32]| -> Vec<u32> {
        let mut bvh = Bvh::build(&instance_boxes(previous));
        let built = bvh.expected_visits();
        if slots(previous) != slots(records) {
            return hierarchy_words(records);
        }
        bvh.refit(&instance_boxes(records));
        if bvh.expected_visits() > REFIT_SLACK * built {
            return hierarchy_words(records);
        }
        bvh.words(&slots(records))
    };
    let moved = |to: &dyn Fn(usize, [f64; 3]) -> [f64; 3]| -> Vec<Option<Pose>> {
        let poses = scattered.iter().enumerate();
        poses
            .map(|(k, p)| p.map(|(size, pos, rot)| (size, to(k, pos), rot)))
            .collect()
    };
    let before = buffer(scattered.clone());
    let small = buffer(moved(&|k, p| {
        [p[0] + 0.25 * (k % 5) as f64, p[1] + 0.5 * (k % 3) as f64, p[2]]
    }));
    let anywhere = buffer(moved(&|k, p| {
        [(p[0] + 290.0 * (k % 7) as f64) % 1000.0, p[1], (p[2] * 3.0) % 2000.0]
    }));
    let mut fewer = scattered.clone();
    fewer[10] = None;
    let fewer = buffer(fewer);
    for (name, records, refitted) in [
        ("small moves", &small, true),
        ("moves anywhere", &anywhere, false),
        ("a slot emptied", &fewer, false),
    ] {
        let native = kept_after(&before, records);
        // Each case takes the branch it is named for.
        assert_eq!(native != hierarchy_words(records), refitted, "{name}");
        let page = browser.eval(
            "a",
            &format!("return n.hierarchyAfter({}, {})", json!(before), json!(records)),
        );
        let page: Vec<u32> = serde_json::from_value(page).unwrap();
        assert!(
            page == native,
            "{name}: the page keeps another hierarchy than the native client"
        );
    }
    server.stop();
}

/// Captures page `id`'s frame and checks that it equals `naadf render` of the same view,
/// pixel for pixel; returns the frame.
fn same_frame_as_native(
    browser: &mut Browser,
    id: &str,
    server: &Server,
    camera: &str,
    size: &str,
    mode: &str,
    dir: &Path,
) -> image::RgbaImage {
    let (png, native) = page_and_native(browser, id, server, camera, &["--size", size, "--mode", mode], dir);
    let a = image::open(&png).unwrap().to_rgba8();
    let b = image::open(&native).unwrap().to_rgba8();
    assert_eq!(a.dimensions(), b.dimensions());
    let differing = a.pixels().zip(b.pixels()).filter(|(p, q)| p != q).count();
    assert_eq!(
        differing,
        0,
        "{mode}: {differing} of {} pixels differ from naadf render",
        a.width() * a.height()
    );
    a
}

/// A rate-limited edit is shown (the notice, `rateLimited`) and retried with the same
/// `client_seq`: every edit of a burst is applied exactly once.
#[test]
fn rate_limited_edits_are_retried_and_applied_once() {
    let Some((dir, world, mut browser)) = fixture() else {
        return;
    };
    let server = serve_world(dir.path(), &world, &["--rate", "1"], &[]);
    browser.open(
        "a",
        &page_url(&server, r#"{"pos":[64,60,-10],"yaw":0,"pitch":-30}"#, "64x36", "albedo"),
    );
    browser.wait("a", "n.state === 'live'", 60_000);
    let versions = browser.eval(
        "a",
        r#"const ops = [1, 2, 3, 4].map((x) => `{"op":"set","voxels":[[${x},50,1,1]]}`);
           return await Promise.all(ops.map((o) => n.edit(o)));"#,
    );
    let mut versions: Vec<u64> = versions
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    versions.sort_unstable();
    assert_eq!(versions, [1, 2, 3, 4], "each edit once");
    assert_eq!(status(&server)["version"], 4);
    let retried = browser.eval("a", "return n.rateLimited").as_u64().unwrap();
    assert!(retried > 0, "the burst met the limit and was retried");
    server.stop();
}

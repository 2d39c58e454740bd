//! Render nodes end to end: a real server, real `naadf render-node` processes on lavapipe,
//! frames requested with `naadf frame` and compared byte for byte with `naadf render
//! --world` of the same world at the same version.

mod support;

use naadf_client::Mode;
use naadf_client::error::Code;
use naadf_client::{Client, Error, NodeInfo};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use support::{http_get, http_get_bytes, naadf, ok, p, serve_world, start_world};

const TOKENS: &str = "adm=admin:admin,vw=viewer:viewer,nd=node:render-node";
const CAMERA: &str = r#"{"pos":[-10.5,70.25,-12.5],"yaw":45,"pitch":-35,"fov_y":60}"#;

/// A `naadf render-node` process, killed when dropped.
struct Node(Child);

impl Node {
    fn start(url: &str, log: &std::path::Path) -> Node {
        Self::start_with(url, log, &[])
    }

    /// [`Node::start`] with `extra` arguments.
    fn start_with(url: &str, log: &std::path::Path, extra: &[&str]) -> Node {
        let err = std::fs::File::create(log).unwrap();
        Node(
            Command::new(env!("CARGO_BIN_EXE_naadf"))
                .args(["render-node", "--server", url, "--token", "nd", "--retry", "0.2"])
                .args(extra)
                .env("RUST_LOG", "info")
                .stdout(Stdio::null())
                .stderr(err)
                .spawn()
                .unwrap(),
        )
    }
}

impl Drop for Node {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// `naadf frame` as the viewer; returns (success, stdout, stderr).
fn frame(url: &str, out: &str, mode: &str, min_version: u64) -> (bool, String, String) {
    frame_with(url, out, mode, min_version, &[])
}

/// [`frame`] with more arguments.
fn frame_with(url: &str, out: &str, mode: &str, min_version: u64, extra: &[&str]) -> (bool, String, String) {
    let version = min_version.to_string();
    let args = [
        "frame",
        "--server",
        url,
        "--token",
        "vw",
        "--camera",
        CAMERA,
        "--size",
        "96x64",
        "--mode",
        mode,
        "--min-version",
        &version,
        "-o",
        out,
        "--json",
    ];
    let o = naadf(&[&args[..], extra].concat(), None);
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// A world in `dir` and a server with tokens on it, or `None` (with a message) when the
/// machine has no GPU adapter, so no node could run.
fn started(dir: &std::path::Path) -> Option<(String, support::Server)> {
    let world = start_world(dir);
    let probe = naadf(
        &[
            "render",
            "--world",
            &world,
            "--camera",
            CAMERA,
            "--size",
            "8x8",
            "-o",
            &p(dir, "probe.png"),
        ],
        None,
    );
    if !probe.status.success() {
        eprintln!("skipping render nodes: {}", String::from_utf8_lossy(&probe.stderr));
        return None;
    }
    let server = serve_world(dir, &world, &[], &[("NAADF_TOKENS", TOKENS)]);
    Some((world, server))
}

/// `naadf render --world` of the same view.
fn local(world: &str, out: &str, mode: &str) -> Vec<u8> {
    local_with(world, out, mode, &[])
}

/// [`local`] with more arguments.
fn local_with(world: &str, out: &str, mode: &str, extra: &[&str]) -> Vec<u8> {
    let args = [
        "render", "--world", world, "--camera", CAMERA, "--size", "96x64", "--mode", mode, "-o", out,
    ];
    ok(&[&args[..], extra].concat(), None);
    std::fs::read(out).unwrap()
}

#[test]
fn frames_from_render_nodes_equal_local_renders() {
    let dir = tempfile::tempdir().unwrap();
    let Some((world, server)) = started(dir.path()) else {
        return;
    };
    let out = p(dir.path(), "remote.png");

    // No node yet: the request fails fast with UNAVAILABLE.
    let t0 = Instant::now();
    let (done, _, err) = frame(&server.url, &out, "material", 0);
    assert!(!done && err.contains("Unavailable"), "{err}");
    assert!(t0.elapsed() < Duration::from_secs(10), "not fast: {:?}", t0.elapsed());

    // A viewer may not register as a node.
    let rt = tokio::runtime::Runtime::new().unwrap();
    let refused = rt.block_on(async {
        let c = Client::connect(&server.url, Some("vw"), None).await.unwrap();
        let info = NodeInfo {
            adapter: "fake".into(),
            modes: vec![Mode::Albedo],
            max_size: (64, 64),
        };
        c.register_node(&info).await.unwrap_err()
    });
    assert!(
        matches!(
            refused,
            Error::Refused {
                code: Code::PermissionDenied,
                ..
            }
        ),
        "{refused:?}"
    );

    let node = Node::start(&server.url, &dir.path().join("node.log"));
    // Wait until the node has registered (its first frame arrives).
    let deadline = Instant::now() + Duration::from_secs(120);
    let summary = loop {
        let (done, stdout, err) = frame(&server.url, &out, "material", 0);
        if done {
            break stdout;
        }
        assert!(
            Instant::now() < deadline,
            "the node never served: {err}\n{}",
            std::fs::read_to_string(dir.path().join("node.log")).unwrap_or_default()
        );
        std::thread::sleep(Duration::from_millis(200));
    };
    let v: serde_json::Value = serde_json::from_str(&summary).unwrap();
    assert_eq!(v["version"], 0);
    assert!(
        !v["node"].as_str().unwrap().is_empty(),
        "the reply names the node's adapter"
    );
    for mode in ["material", "normal", "albedo"] {
        let (done, _, err) = frame(&server.url, &out, mode, 0);
        assert!(done, "{mode}: {err}");
        let want = local(&world, &p(dir.path(), &format!("local-{mode}.png")), mode);
        assert!(
            std::fs::read(&out).unwrap() == want,
            "{mode}: the node's frame differs from render --world"
        );
    }

    // The lit modes: a path-traced frame equals the local one; a camera stream's baseline
    // and gi frames continue one history on the node, so two requests of 2 frames give the
    // local render of 4 frames.
    let (done, _, err) = frame_with(&server.url, &out, "pathtrace", 0, &["--spp", "3", "--bounces", "2"]);
    assert!(done, "pathtrace: {err}");
    let want = local_with(
        &world,
        &p(dir.path(), "local-pt.png"),
        "pathtrace",
        &["--spp", "3", "--bounces", "2"],
    );
    assert!(
        std::fs::read(&out).unwrap() == want,
        "pathtrace: the node's frame differs"
    );
    for mode in ["baseline", "gi"] {
        let name = format!("viewer-{mode}");
        let stream = ["--frames", "2", "--stream", &name, "--sky", "uniform:0.5,0.7,1"];
        for _ in 0..2 {
            let (done, _, err) = frame_with(&server.url, &out, mode, 0, &stream);
            assert!(done, "{mode}: {err}");
        }
        let four = ["--frames", "4", "--sky", "uniform:0.5,0.7,1"];
        let want = local_with(&world, &p(dir.path(), &format!("local-{mode}.png")), mode, &four);
        assert!(
            std::fs::read(&out).unwrap() == want,
            "{mode}: the stream's history did not continue"
        );
    }
    let (done, _, err) = frame_with(&server.url, &out, "baseline", 0, &["--sky", "cloudy"]);
    assert!(!done && err.contains("sky 'cloudy'"), "{err}");

    // Over HTTP: the same frame, the same roles (a token is needed here), the node listed.
    let query = |token: &str| {
        let camera: String = CAMERA
            .bytes()
            .map(|b| {
                if b.is_ascii_alphanumeric() {
                    (b as char).to_string()
                } else {
                    format!("%{b:02X}")
                }
            })
            .collect();
        format!("/frame.png?camera={camera}&size=96x64&mode=material{token}")
    };
    let (code, _) = http_get_bytes(&server.http, &query(""));
    assert_eq!(code, 401, "no token");
    let (code, png) = http_get_bytes(&server.http, &query("&token=vw"));
    assert_eq!(code, 200);
    assert!(png == std::fs::read(p(dir.path(), "local-material.png")).unwrap());
    let (code, _) = http_get_bytes(&server.http, "/frame.png?camera=%7B%7D&token=vw");
    assert_eq!(code, 400, "a bad camera");
    // With tokens, the page wants one too; the metrics (aggregates) do not.
    assert_eq!(http_get(&server.http, "/status").0, 401);
    let (code, page) = http_get(&server.http, "/status?token=vw");
    assert_eq!(code, 200);
    let adapter = v["node"].as_str().unwrap().to_owned();
    assert!(page.contains("Render nodes") && page.contains(&adapter), "{page}");
    let (_, metrics) = http_get(&server.http, "/metrics");
    assert!(metrics.contains("naadf_frames_total{node=\"all\"}"), "{metrics}");
    assert!(metrics.contains("naadf_frame_seconds_bucket"));

    status_page_in_a_browser(&server.http, &adapter, dir.path());

    // Through a relay, frame requests go upstream with the caller's token, over gRPC and
    // over the relay's HTTP: the same frame, the same refusal without a token.
    let relay = support::Server::relay(&server.url, &["--token", "vw"], &dir.path().join("relay.log"));
    let (done, _, err) = frame(&relay.url, &out, "material", 0);
    assert!(done, "through the relay: {err}");
    assert!(std::fs::read(&out).unwrap() == std::fs::read(p(dir.path(), "local-material.png")).unwrap());
    assert_eq!(http_get_bytes(&relay.http, &query("")).0, 401, "no token at the relay");
    let (code, png) = http_get_bytes(&relay.http, &query("&token=vw"));
    assert_eq!(code, 200);
    assert!(png == std::fs::read(p(dir.path(), "local-material.png")).unwrap());
    relay.stop();

    // Freshness: a frame asked for at the edit's version shows the edit.
    let edit = r#"{"op":"sphere","center":[40,40,40],"radius":14,"material":4}"#;
    let ops = p(dir.path(), "edit.jsonl");
    std::fs::write(&ops, format!("{edit}\n")).unwrap();
    ok(
        &["edit", "--server", &server.url, "--token", "adm", "--ops", &ops],
        None,
    );
    let after = p(dir.path(), "after.naadf");
    ok(&["apply", &world, "--ops", &ops, "-o", &after], None);
    let (done, stdout, err) = frame(&server.url, &out, "material", 1);
    assert!(done, "{err}");
    let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(v["version"], 1);
    let want = local(&after, &p(dir.path(), "local-after.png"), "material");
    assert!(
        std::fs::read(&out).unwrap() == want,
        "the frame at version 1 shows the edit"
    );
    assert!(
        want != local(&world, &p(dir.path(), "local-before.png"), "material"),
        "the edit is visible"
    );

    // The node gone, requests fail fast again.
    drop(node);
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        let (done, _, err) = frame(&server.url, &out, "material", 0);
        if !done && err.contains("Unavailable") {
            break;
        }
        assert!(Instant::now() < deadline, "the dead node is still routed to: {err}");
        std::thread::sleep(Duration::from_millis(100));
    }
    server.stop();
}

/// Loads the status page in headless Chromium: the node is listed and the live frame
/// loads (its natural width reaches the DOM); a screenshot goes to the test's output.
fn status_page_in_a_browser(http: &str, adapter: &str, scratch: &std::path::Path) {
    if Command::new("chromium").arg("--version").output().is_err() {
        eprintln!("skipping the browser check: chromium is not installed (scripts/ensure-deps.sh installs it)");
        return;
    }
    // The page passes its token on to the live frame (this server has tokens).
    let url = format!("http://{http}/status?token=vw");
    let chromium = |extra: &[&str]| {
        let profile = tempfile::tempdir_in(scratch).unwrap();
        Command::new("chromium")
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                "--virtual-time-budget=10000",
                "--window-size=1000,1300",
            ])
            .arg(format!("--user-data-dir={}", profile.path().display()))
            .args(extra)
            .arg(&url)
            .output()
            .expect("run chromium")
    };
    let dom = chromium(&["--dump-dom"]);
    let dom = String::from_utf8_lossy(&dom.stdout);
    assert!(dom.contains(adapter), "the page lists the node: {dom}");
    let width = dom
        .split("data-live-width=\"")
        .nth(1)
        .and_then(|r| r.split('"').next())
        .and_then(|w| w.parse::<u32>().ok());
    assert_eq!(width, Some(480), "the live frame loaded: {dom}");
    let shot = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("status-page.png");
    chromium(&[&format!("--screenshot={}", shot.display())]);
    let png = std::fs::read(&shot).expect("a screenshot");
    assert!(png.len() > 1000);
    eprintln!("status page screenshot: {}", shot.display());
}

/// Two nodes; the one holding a slow request is killed: the request is served by the other.
#[test]
fn a_request_survives_the_death_of_its_node() {
    let dir = tempfile::tempdir().unwrap();
    let Some((_, server)) = started(dir.path()) else { return };
    // Rows of the status page's node table.
    let count_nodes = || {
        let page = http_get(&server.http, "/status?token=vw").1;
        let table = page
            .split("<table id=nodes>")
            .nth(1)
            .and_then(|t| t.split("</table>").next());
        table.map_or(0, |t| t.matches("<tr><td>").count())
    };
    let wait_for = |n: usize| {
        let deadline = Instant::now() + Duration::from_secs(120);
        while count_nodes() != n {
            assert!(Instant::now() < deadline, "{n} nodes never registered");
            std::thread::sleep(Duration::from_millis(100));
        }
    };
    // The first node registers first and so takes the first request (ties go to the
    // oldest node).
    let first = Node::start(&server.url, &dir.path().join("first.log"));
    wait_for(1);
    let second = Node::start(&server.url, &dir.path().join("second.log"));
    wait_for(2);
    let (url, out) = (server.url.clone(), p(dir.path(), "slow.png"));
    let request = std::thread::spawn(move || {
        naadf(
            &[
                "frame",
                "--server",
                &url,
                "--token",
                "vw",
                "--camera",
                CAMERA,
                "--size",
                "1600x1200",
                "--mode",
                "albedo",
                "-o",
                &out,
                "--json",
            ],
            None,
        )
    });
    std::thread::sleep(Duration::from_millis(400));
    drop(first);
    let o = request.join().unwrap();
    assert!(
        o.status.success(),
        "the request failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let img = image::open(p(dir.path(), "slow.png")).unwrap();
    assert_eq!((img.width(), img.height()), (1600, 1200));
    wait_for(1);
    // The frame came from the second node: the one left has served it.
    let page = http_get(&server.http, "/status?token=vw").1;
    let row = page
        .split("<table id=nodes>")
        .nth(1)
        .unwrap()
        .split("</table>")
        .next()
        .unwrap();
    assert!(
        row.contains("<td>0</td><td>1</td><td></td></tr>"),
        "in flight 0, frames 1: {row}"
    );
    drop(second);
    server.stop();
}

/// Two nodes and a stream of edits: a frame asked for at version v shows the world at the
/// version it is stamped with (v or later), byte for byte.
#[test]
fn frames_at_min_version_show_the_edits_with_two_nodes() {
    let dir = tempfile::tempdir().unwrap();
    let Some((world, server)) = started(dir.path()) else {
        return;
    };
    let _nodes = [
        Node::start(&server.url, &dir.path().join("a.log")),
        Node::start(&server.url, &dir.path().join("b.log")),
    ];
    // Ten spheres in view of the camera, one version each.
    let edits: Vec<String> = (0..10)
        .map(|i| {
            format!(
                r#"{{"op":"sphere","center":[{},{},{}],"radius":{},"material":{}}}"#,
                20 + 9 * i,
                30 + (i % 3) * 5,
                25 + 7 * i,
                4 + i % 4,
                1 + i % 7
            )
        })
        .collect();
    let (url, dir_path, stream) = (server.url.clone(), dir.path().to_owned(), edits.clone());
    let editor = std::thread::spawn(move || {
        for (i, e) in stream.iter().enumerate() {
            let f = p(&dir_path, &format!("edit{i}.jsonl"));
            std::fs::write(&f, format!("{e}\n")).unwrap();
            ok(&["edit", "--server", &url, "--token", "adm", "--ops", &f], None);
        }
    });
    for v in [2u64, 5, 9] {
        let out = p(dir.path(), &format!("v{v}.png"));
        let deadline = Instant::now() + Duration::from_secs(120);
        let stdout = loop {
            let (done, stdout, err) = frame(&server.url, &out, "material", v);
            if done {
                break stdout;
            }
            // Until both nodes have registered, a request may find none.
            assert!(err.contains("Unavailable") && Instant::now() < deadline, "{err}");
            std::thread::sleep(Duration::from_millis(200));
        };
        let shown: u64 = serde_json::from_str::<serde_json::Value>(&stdout).unwrap()["version"]
            .as_u64()
            .unwrap();
        assert!(shown >= v, "asked for {v}, got {shown}");
        // The world at the version the frame shows, applied offline and rendered locally.
        let ops = p(dir.path(), &format!("first{shown}.jsonl"));
        std::fs::write(&ops, edits[..shown as usize].join("\n") + "\n").unwrap();
        let at = p(dir.path(), &format!("at{shown}.naadf"));
        ok(&["apply", &world, "--ops", &ops, "-o", &at], None);
        let want = local(&at, &p(dir.path(), &format!("local{shown}.png")), "material");
        assert!(
            std::fs::read(&out).unwrap() == want,
            "the frame at version {shown} differs"
        );
    }
    editor.join().unwrap();
    server.stop();
}

/// A node re-registers by itself when its server restarts (on the same address), and its
/// `/health` says whether it is registered: 200 while it serves, 503 while the server is
/// away.
#[test]
fn a_node_reconnects_after_a_server_restart() {
    let dir = tempfile::tempdir().unwrap();
    let Some((world, server)) = started(dir.path()) else {
        return;
    };
    let url = server.url.clone();
    let grpc = url.trim_start_matches("http://").to_owned();
    let health = support::free_addr();
    let _node = Node::start_with(&url, &dir.path().join("node.log"), &["--http", &health]);
    let out = p(dir.path(), "f.png");
    let served = |what: &str| {
        let deadline = Instant::now() + Duration::from_secs(120);
        loop {
            let (done, _, err) = frame(&url, &out, "material", 0);
            if done {
                return;
            }
            assert!(Instant::now() < deadline, "{what}: {err}");
            std::thread::sleep(Duration::from_millis(200));
        }
    };
    let health_is = |code: u16| {
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            let (got, body) = http_get(&health, "/health");
            if got == code {
                return serde_json::from_str::<serde_json::Value>(&body).expect("JSON health");
            }
            assert!(Instant::now() < deadline, "health stayed {got} ({body}), not {code}");
            std::thread::sleep(Duration::from_millis(100));
        }
    };
    served("before the restart");
    let before = health_is(200);
    assert_eq!(before["registered"], true, "{before}");
    assert!(before["frames"].as_u64() >= Some(1), "the frame is counted: {before}");
    server.stop();
    let away = health_is(503);
    assert_eq!(away["status"], "unavailable", "{away}");
    let again = serve_world(dir.path(), &world, &["--grpc", &grpc], &[("NAADF_TOKENS", TOKENS)]);
    served("after the restart");
    assert_eq!(health_is(200)["registered"], true);
    again.stop();
}

/// Frame requests over HTTP from another machine need a token (no node is needed to see
/// the refusal: authentication comes before routing).
#[test]
fn an_unauthenticated_frame_request_off_loopback_is_refused() {
    // A non-loopback address of this machine, to reach the server as another host would.
    let Some(ip) = std::net::UdpSocket::bind("0.0.0.0:0")
        .and_then(|s| s.connect("192.0.2.1:9").map(|()| s))
        .and_then(|s| s.local_addr())
        .ok()
        .map(|a| a.ip())
        .filter(|ip| !ip.is_loopback() && !ip.is_unspecified())
    else {
        eprintln!("skipping: this machine has no non-loopback IPv4 address");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(
        dir.path(),
        &world,
        &["--http", "0.0.0.0:0"],
        &[("NAADF_TOKENS", TOKENS)],
    );
    let port = server.http.rsplit(':').next().unwrap();
    let remote = format!("{ip}:{port}");
    let path = "/frame.png?camera=%7B%22pos%22%3A%5B1%2C2%2C3%5D%2C%22yaw%22%3A0%2C%22pitch%22%3A0%7D&size=8x8";
    assert_eq!(http_get(&remote, path).0, 401, "no token from {ip}");
    assert_eq!(http_get(&remote, &format!("{path}&token=wrong")).0, 401);
    // With a token the request passes authentication and meets the missing node.
    assert_eq!(http_get(&remote, &format!("{path}&token=vw")).0, 503);
    server.stop();
}

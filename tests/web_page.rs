//! The browser page in a real browser: headless Chromium with WebGPU on SwiftShader, driven
//! by playwright-core through the scripts in `web/tests/` (docs/WEB.md).
//!
//! These need Node and Chromium. `scripts/test.sh` installs both and sets
//! `NAADF_REQUIRE_BROWSER=1`, so that in CI a missing browser fails instead of skipping.

mod support;

use std::path::{Path, PathBuf};
use std::process::Command;
use support::{Server, ok, serve_world, start_world};

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

/// Runs `node web/tests/SCRIPT ARGS` and parses the JSON line it prints.
fn drive(script: &str, args: &[&str]) -> serde_json::Value {
    let out = Command::new("node")
        .arg(web().join("tests").join(script))
        .args(args)
        .output()
        .expect("node");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{script} failed:\n{stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(stdout.trim()).unwrap_or_else(|e| panic!("{script} printed {stdout:?}: {e}\n{stderr}"))
}

/// The page's URL on `server`'s gRPC listener, with a query.
fn page_url(server: &Server, query: &str) -> String {
    format!("{}/?{query}", server.url)
}

fn encode(s: &str) -> String {
    s.bytes()
        .map(|b| match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'_' | b'.' | b'~' => (b as char).to_string(),
            _ => format!("%{b:02X}"),
        })
        .collect()
}

/// The page joins a served world and ends on the server's version, growth step and
/// digest; its `albedo` and `material` frames at a camera and size from the URL equal
/// `naadf render` of the same camera and size, pixel for pixel.
#[test]
fn the_page_mirrors_the_world_and_draws_what_naadf_render_draws() {
    if !browser_available() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(dir.path(), &world, &[], &[]);
    let camera = r#"{"pos":[64.5,50.25,-20],"yaw":10,"pitch":-25,"fov_y":70}"#;
    for mode in ["albedo", "material"] {
        let png = dir.path().join(format!("page-{mode}.png"));
        let query = format!("mode={mode}&size=160x90&camera={}", encode(camera));
        let page = drive("join.mjs", &[&page_url(&server, &query), png.to_str().unwrap()]);
        let status: serde_json::Value =
            serde_json::from_str(&ok(&["status", "--server", &server.url, "--json"], None)).unwrap();
        assert_eq!(page["state"], "live");
        assert_eq!(page["mode"], mode);
        for (field, key) in [
            ("version", "version"),
            ("growthSeq", "growth_seq"),
            ("digest", "digest"),
        ] {
            assert_eq!(page[field], status[key], "{field}: page {page} server {status}");
        }
        let native = dir.path().join(format!("native-{mode}.png"));
        ok(
            &[
                "render",
                "--server",
                &server.url,
                "--camera",
                camera,
                "--size",
                "160x90",
                "--mode",
                mode,
                "-o",
                native.to_str().unwrap(),
            ],
            None,
        );
        let a = image::open(&png).unwrap().to_rgba8();
        let b = image::open(&native).unwrap().to_rgba8();
        assert_eq!(a.dimensions(), b.dimensions());
        let differing = a.pixels().zip(b.pixels()).filter(|(p, q)| p != q).count();
        assert_eq!(
            differing,
            0,
            "{mode}: {differing} of {} pixels differ from naadf render",
            160 * 90
        );
    }
    server.stop();
}

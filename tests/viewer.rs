//! The windowed viewer in a real window on a virtual X display (Xvfb), following a real
//! server: it starts, renders the server's world with its HUD, and writes the screenshot.

mod support;

use std::process::Command;
use support::{p, serve_world, start_world};

#[test]
fn the_viewer_renders_a_server_world_in_a_window() {
    if Command::new("xvfb-run").arg("--help").output().is_err() {
        eprintln!("skipping the viewer test: xvfb-run is not installed (scripts/ensure-deps.sh installs it)");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(dir.path(), &world, &[], &[]);
    let shot = p(dir.path(), "shot.png");
    let out = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 800x600x24"])
        .arg(env!("CARGO_BIN_EXE_naadf"))
        .args([
            "view",
            "--server",
            &server.url,
            "--token",
            "viewer",
            "--size",
            "320x200",
        ])
        .args(["--frames", "4", "--screenshot", &shot, "--timeout", "120", "--json"])
        .output()
        .expect("run xvfb-run");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "the viewer failed: {stderr}");
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON summary");
    assert_eq!(summary["frames"], 4);
    assert_eq!(summary["version"], 0);
    assert_eq!(summary["digest"].as_str().unwrap().len(), 16, "{summary}");

    let img = image::open(&shot).expect("a PNG screenshot").to_rgba8();
    assert_eq!(img.dimensions(), (320, 200));
    // The world fills the view: many distinct colours, not a cleared or empty frame.
    let mut colours: Vec<[u8; 4]> = img.pixels().map(|p| p.0).collect();
    colours.sort_unstable();
    colours.dedup();
    assert!(colours.len() > 50, "only {} colours in the screenshot", colours.len());
    // The HUD's white text sits in the top-left corner.
    let white = (0..40)
        .flat_map(|y| (0..200).map(move |x| (x, y)))
        .filter(|&(x, y)| img.get_pixel(x, y).0[..3] == [255; 3]);
    assert!(white.count() > 30, "no HUD text");
    server.stop();
}

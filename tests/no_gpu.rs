//! The service without the renderer: `naadf` built with `--no-default-features` (no `gpu`
//! feature, so no wgpu, winit or nv-flip) still serves, relays, mirrors, edits, reports its
//! status and checks its data directory.
//!
//! `scripts/test.sh` builds that binary and names it in `NAADF_NO_GPU_BIN`; without the
//! variable the test says so and checks nothing.

mod support;

use std::path::PathBuf;
use support::{Server, ok, p};

#[test]
fn the_build_without_the_renderer_serves_relays_mirrors_and_checks_its_data() {
    let Some(bin) = std::env::var_os("NAADF_NO_GPU_BIN") else {
        eprintln!(
            "skipped: NAADF_NO_GPU_BIN is not set (scripts/test.sh builds `cargo build -p naadf --no-default-features` and sets it)"
        );
        return;
    };
    support::use_binary(PathBuf::from(bin));

    // It is the build without the renderer: the rendering commands are not there.
    let help = ok(&["--help"], None);
    for command in ["serve", "relay", "mirror", "edit", "status", "data", "frame"] {
        assert!(
            help.contains(&format!("  {command} ")),
            "{command} missing from:\n{help}"
        );
    }
    for command in ["render", "render-node", "view", "bench"] {
        assert!(!help.contains(&format!("  {command} ")), "{command} listed in:\n{help}");
    }
    support::fails(&["render", "--help"], None, "unrecognized subcommand");

    let dir = tempfile::tempdir().unwrap();
    let world = p(dir.path(), "t.naadf");
    ok(&["generate", "--preset", "test", "-o", &world], None);
    let data = p(dir.path(), "data");
    let server = Server::start(
        &["--world", &world, "--data", &data],
        &dir.path().join("server.log"),
        &[],
    );
    let relay = Server::relay(&server.url, &[], &dir.path().join("relay.log"));

    // An edit through the relay reaches the server, and a mirror of the relay sees it.
    let ops = p(dir.path(), "ops.jsonl");
    std::fs::write(
        &ops,
        "{\"op\":\"sphere\",\"center\":[20,20,20],\"radius\":5,\"material\":2}\n{\"op\":\"set\",\"voxels\":[[1,2,3,3]]}\n",
    )
    .unwrap();
    ok(&["edit", "--server", &relay.url, "--ops", &ops], None);
    let status: serde_json::Value =
        serde_json::from_str(&ok(&["status", "--server", &server.url, "--json"], None)).unwrap();
    assert_eq!(status["version"], 2, "{status}");
    let copy = p(dir.path(), "copy.naadf");
    ok(
        &[
            "mirror",
            "--server",
            &relay.url,
            "--once",
            "-o",
            &copy,
            "--no-cache",
            "--verify",
        ],
        None,
    );
    let mirrored: serde_json::Value = serde_json::from_str(&ok(&["info", &copy, "--json"], None)).unwrap();
    let served: serde_json::Value = serde_json::from_str(&ok(&["info", &world, "--json"], None)).unwrap();
    assert_eq!(mirrored["size"], served["size"]);
    assert_ne!(
        mirrored["digest"], served["digest"],
        "the mirror holds the edited world"
    );

    relay.stop();
    server.stop();
    let check = ok(&["data", "check", &data, "--json"], None);
    let check: serde_json::Value = serde_json::from_str(&check).unwrap();
    assert_eq!(check["serve"]["starts"], true, "{check}");
}

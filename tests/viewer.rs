//! The windowed viewer in a real window on a virtual X display (Xvfb), following a real
//! server: it starts, renders the server's world with its HUD, and writes the screenshot;
//! mouse clicks (sent with xdotool) become edits the server applies.

mod support;

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use support::{ok, p, serve_world, start_world};

/// One Xvfb server for the whole test, stopped (and waited for) when dropped.
///
/// The test starts Xvfb itself rather than through `xvfb-run`: `xvfb-run` kills its server
/// without waiting for it to go, and on a loaded two-core machine the second of two
/// sessions once found no X server to connect to. `-displayfd` lets the server pick a free
/// display and say which once it accepts connections, and `-noreset` keeps it from
/// resetting whenever its last client (an `xdotool` poll) disconnects while the viewer is
/// connecting.
struct VirtualDisplay {
    server: Child,
    display: String,
}

impl VirtualDisplay {
    /// Starts Xvfb with an 800×600 screen, or `None` when Xvfb is not installed.
    fn start() -> Option<Self> {
        let mut server = Command::new("Xvfb")
            .args([
                "-displayfd",
                "1",
                "-screen",
                "0",
                "800x600x24",
                "-noreset",
                "-nolisten",
                "tcp",
            ])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .ok()?;
        let mut line = String::new();
        BufReader::new(server.stdout.take().unwrap())
            .read_line(&mut line)
            .expect("read Xvfb's display");
        let number = line.trim();
        assert!(!number.is_empty(), "Xvfb exited before it named its display");
        Some(Self {
            display: format!(":{number}"),
            server,
        })
    }

    /// `naadf view` at 320×200 with a JSON summary on this display, run through `wrapper`
    /// (a script that drives it, or nothing).
    fn viewer(&self, wrapper: &[&str], url: &str, token: &str) -> Command {
        let mut argv = wrapper.to_vec();
        argv.push(env!("CARGO_BIN_EXE_naadf"));
        let mut c = Command::new(argv[0]);
        c.args(&argv[1..]);
        c.args(["view", "--server", url, "--token", token, "--size", "320x200", "--json"])
            .env("DISPLAY", &self.display)
            .env_remove("XAUTHORITY")
            .env_remove("WAYLAND_DISPLAY");
        c
    }
}

impl Drop for VirtualDisplay {
    fn drop(&mut self) {
        let _ = self.server.kill();
        let _ = self.server.wait();
    }
}

#[test]
fn the_viewer_renders_a_server_world_in_a_window() {
    let Some(display) = VirtualDisplay::start() else {
        eprintln!("skipping the viewer test: Xvfb is not installed (scripts/ensure-deps.sh installs it)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(dir.path(), &world, &[], &[]);
    let shot = p(dir.path(), "shot.png");
    let out = display
        .viewer(&[], &server.url, "viewer")
        .args(["--frames", "4", "--screenshot", &shot, "--timeout", "120"])
        .output()
        .expect("run the viewer");
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

    // Clicks: the first captures the mouse, then erase, place, select material 3, place;
    // two Escapes release the mouse and close the window.
    if Command::new("xdotool").arg("version").output().is_err() {
        eprintln!("skipping the viewer's click test: xdotool is not installed (scripts/ensure-deps.sh installs it)");
        server.stop();
        return;
    }
    let script = r#"
        timeout 300 "$@" > "$SUMMARY" &
        pid=$!
        # The title shows the version once the world has arrived.
        for i in $(seq 1200); do
            win=$(xdotool search --name '^naadf v[0-9]' 2>/dev/null | head -1)
            [ -n "$win" ] && break
            sleep 0.1
        done
        [ -n "$win" ] || { kill $pid; exit 3; }
        # No window manager runs on the virtual display: give the window the keyboard.
        xdotool windowfocus --sync "$win"
        xdotool mousemove --window "$win" 160 100
        for k in "click 1" "click 1" "click 3" "key 3" "click 3" "key Escape" "key Escape"; do
            xdotool $k
            sleep 0.4
        done
        wait $pid
    "#;
    let summary_path = p(dir.path(), "clicks.json");
    // Meanwhile another client watches the presence table for the window.
    let watcher = watch_presence(server.url.clone(), "viewer-test");
    let out = display
        .viewer(&["bash", "-c", script, "clicks"], &server.url, "editor")
        .env("SUMMARY", &summary_path)
        .env("NAADF_NAME", "viewer-test")
        .output()
        .expect("run the viewer");
    let entry = watcher.join().unwrap().expect("the window published its presence");
    assert_eq!(entry.position.len(), 3, "with its camera: {entry:?}");
    assert!(
        out.status.success(),
        "the clicking session failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&summary_path).unwrap()).unwrap();
    assert_eq!(summary["edits"], 3, "erase, place, place: {summary}");
    // Every edit was acknowledged before the window closed: the server is at version 3.
    let status: serde_json::Value = serde_json::from_str(&ok(
        &["status", "--server", &server.url, "--token", "admin", "--json"],
        None,
    ))
    .unwrap();
    assert_eq!(status["version"], 3, "{status}");
    server.stop();
}

/// Joins `url` with the presence table in a thread of its own and returns the first entry
/// named `name` (`None` after a minute).
fn watch_presence(url: String, name: &'static str) -> std::thread::JoinHandle<Option<naadf_proto::v1::PresenceEntry>> {
    std::thread::spawn(move || {
        let rt = tokio::runtime::Runtime::new().unwrap();
        rt.block_on(async {
            let client = naadf_client::Client::connect(&url, None, None).await.ok()?;
            let mut request = naadf_client::Mirror::new(None).join_request();
            request.presence = true;
            let mut stream = client.stream(request).await.ok()?;
            let found = async {
                while let Ok(Some(m)) = stream.message().await {
                    if let Some(naadf_proto::v1::world_message::Kind::Presence(p)) = m.kind
                        && let Some(e) = p.entries.into_iter().find(|e| e.name == name)
                    {
                        return Some(e);
                    }
                }
                None
            };
            tokio::time::timeout(std::time::Duration::from_secs(60), found)
                .await
                .ok()?
        })
    })
}

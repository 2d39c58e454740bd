//! End-to-end tests of the data directory under a hostile operator and crashes: the real
//! `naadf serve` killed with -9, files deleted or damaged behind its back, and
//! `naadf data check` / `naadf data repair` on what is left.

mod support;

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use support::{Server, naadf, ok, p, random_op, start_world};

/// Sends `n` random edits (one version each) to `server`.
fn edit(server: &Server, n: usize, seed: u64) {
    let mut rng = seed;
    let ops: String = (0..n).map(|_| random_op(&mut rng) + "\n").collect();
    ok(&["edit", "--server", &server.url, "--ops", "-"], Some(&ops));
}

/// The server's status as JSON, once it is quiescent.
fn quiescent_status(server: &Server) -> serde_json::Value {
    for _ in 0..600 {
        let s: serde_json::Value =
            serde_json::from_str(&ok(&["status", "--server", &server.url, "--json"], None)).unwrap();
        if s["quiescent"] == true {
            return s;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    panic!("the server did not become quiescent");
}

/// The names in `dir`, sorted.
fn names(dir: &str) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    v.sort();
    v
}

/// Every file in `dir` with its contents.
fn contents(dir: &str) -> BTreeMap<String, Vec<u8>> {
    names(dir)
        .into_iter()
        .map(|n| {
            let bytes = std::fs::read(Path::new(dir).join(&n)).unwrap();
            (n, bytes)
        })
        .collect()
}

/// Copies the flat directory `from` to `to`.
fn copy_dir(from: &str, to: &str) {
    std::fs::create_dir(to).unwrap();
    for n in names(from) {
        std::fs::copy(Path::new(from).join(&n), Path::new(to).join(&n)).unwrap();
    }
}

/// Waits until `dir` holds the snapshot at `version` as its newest, with its log segment,
/// at most the one snapshot before it (which checkpoints keep) and no snapshot write under
/// way (snapshots are written, and older ones pruned, on a helper thread).
fn wait_for_snapshot(dir: &str, version: u64) {
    let newest = format!("snapshot-{version:020}.naadf");
    let settled = |n: &[String]| {
        let worlds: Vec<&String> = n
            .iter()
            .filter(|x| x.starts_with("snapshot-") && x.ends_with(".naadf"))
            .collect();
        worlds.last() == Some(&&newest)
            && worlds.len() <= 2
            && n.contains(&format!("snapshot-{version:020}.state"))
            && n.contains(&format!("wal-{version:020}.log"))
            && !n.iter().any(|x| x.starts_with('.'))
    };
    let start = Instant::now();
    while !settled(&names(dir)) {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "no snapshot at {version}: {:?}",
            names(dir)
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// A server with `--checkpoint-every 5` that took 12 edits (`seed`), so that it wrote
/// snapshots 5 and 10, then was killed with -9: its data directory, its log file and its
/// quiescent status before the kill.
fn crashed_after_two_checkpoints(dir: &Path, seed: u64) -> (String, std::path::PathBuf, serde_json::Value) {
    let world = start_world(dir);
    let data = p(dir, "data");
    let log = dir.join("server.log");
    let server = Server::start(
        &["--world", &world, "--data", &data, "--checkpoint-every", "5"],
        &log,
        &[],
    );
    edit(&server, 12, seed);
    wait_for_snapshot(&data, 10);
    let before = quiescent_status(&server);
    server.kill9();
    (data, log, before)
}

/// Runs `naadf serve ARGS`, which must refuse: exit with an error, quickly. A server that
/// starts instead is killed and fails the test. Returns its stderr.
fn refused(args: &[&str]) -> String {
    let mut child = Command::new(env!("CARGO_BIN_EXE_naadf"))
        .args(["serve", "--grpc", "127.0.0.1:0", "--http", "127.0.0.1:0"])
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn naadf serve");
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("naadf serve {args:?} started on a directory it must refuse");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success() && !err.contains("panicked"), "{err}");
    err
}

/// A directory whose only snapshot lost a file (or both) is never taken for a new one:
/// the server refuses, says what it found and how to recover, and writes nothing there.
/// Both with the log starting at version 0 (where a new world would replay the log of
/// another) and after checkpoints (the previous snapshot, which they keep, removed too).
#[test]
fn a_directory_missing_its_snapshot_is_refused_untouched() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let world = start_world(dir);
    for (every, snapshot) in [("10000", 0u64), ("20", 40)] {
        let data = p(dir, &format!("data-{snapshot}"));
        let args = [
            "--world",
            world.as_str(),
            "--data",
            data.as_str(),
            "--checkpoint-every",
            every,
        ];
        let server = Server::start(&args, &dir.join("server.log"), &[]);
        edit(&server, 50, snapshot);
        wait_for_snapshot(&data, snapshot);
        server.kill9();
        let wal = format!("wal-{snapshot:020}.log (versions {}–50)", snapshot + 1);
        for missing in [&["state"][..], &["naadf"], &["naadf", "state"]] {
            let copy = p(dir, &format!("copy-{snapshot}-{}", missing.join("-")));
            copy_dir(&data, &copy);
            for ext in missing {
                std::fs::remove_file(Path::new(&copy).join(format!("snapshot-{snapshot:020}.{ext}"))).unwrap();
            }
            for older in names(&copy)
                .into_iter()
                .filter(|n| n.starts_with("snapshot-") && *n < format!("snapshot-{snapshot:020}"))
            {
                std::fs::remove_file(Path::new(&copy).join(older)).unwrap();
            }
            let before = contents(&copy);
            let err = refused(&["--world", &world, "--data", &copy]);
            for needle in ["refusing to start: data directory", &wal, "naadf data check"] {
                assert!(err.contains(needle), "missing {missing:?}: no '{needle}' in: {err}");
            }
            assert_eq!(
                contents(&copy),
                before,
                "missing {missing:?}: serve changed the directory"
            );

            let out = naadf(&["data", "check", &copy], None);
            let report = String::from_utf8_lossy(&out.stdout);
            assert!(!out.status.success(), "{report}");
            assert!(
                report.contains("serve would refuse") && report.contains(&wal),
                "{report}"
            );
            support::fails(&["data", "repair", &copy, "--apply"], None, "nothing was changed");
            assert_eq!(
                contents(&copy),
                before,
                "missing {missing:?}: repair changed the directory"
            );
        }
    }
}

/// What a crash leaves (a tail of zeros after the last record, a state file without its
/// world, temporary files of a snapshot write) is reported by `data check`, listed but
/// not touched by a dry-run `data repair`, cleaned by `data repair --apply`, and cleaned
/// just the same by a plain restart, which resumes the very same state.
#[test]
fn crash_leftovers_are_reported_repaired_and_cleaned_at_startup() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let (data, log, before) = crashed_after_two_checkpoints(dir, 3);
    let clean = names(&data);
    let segment = Path::new(&data).join(format!("wal-{:020}.log", 10));
    let intact = std::fs::metadata(&segment).unwrap().len();
    let mut bytes = std::fs::read(&segment).unwrap();
    bytes.extend([0; 100]);
    std::fs::write(&segment, &bytes).unwrap();
    let lone = format!("snapshot-{:020}.state", 15);
    std::fs::copy(
        Path::new(&data).join(format!("snapshot-{:020}.state", 10)),
        Path::new(&data).join(&lone),
    )
    .unwrap();
    for t in [
        format!(".snapshot-{:020}.naadf.tmp-1-0-0", 15),
        format!(".snapshot-{:020}.state.tmp-1-1-0", 10),
    ] {
        std::fs::write(Path::new(&data).join(t), b"partial").unwrap();
    }
    let restart = p(dir, "restart");
    copy_dir(&data, &restart);
    let damaged = contents(&data);

    let report = ok(&["data", "check", &data], None);
    for needle in [
        "torn write at the end: 100 bytes",
        &format!("{lone} (to quarantine/): snapshot 15 is incomplete"),
        "serve would resume from snapshot 10 and replay 2 logged record(s)",
    ] {
        assert!(report.contains(needle), "no '{needle}' in: {report}");
    }
    let json: serde_json::Value = serde_json::from_str(&ok(&["data", "check", &data, "--json"], None)).unwrap();
    assert_eq!(json["serve"]["starts"], true);
    assert_eq!(json["orphans"].as_array().unwrap().len(), 3, "{json}");
    assert_eq!(json["segments"][1]["torn"]["bytes"], 100, "{json}");

    let plan = ok(&["data", "repair", &data], None);
    assert_eq!(plan.lines().filter(|l| l.starts_with("  ")).count(), 4, "{plan}");
    assert_eq!(contents(&data), damaged, "a dry run changed the directory");
    let done = ok(&["data", "repair", &data, "--apply"], None);
    assert_eq!(done.lines().filter(|l| l.starts_with("done: ")).count(), 4, "{done}");
    // The temporary files are gone; the lone state, no temporary, is kept aside.
    let mut kept = clean.clone();
    kept.push("quarantine".into());
    kept.sort();
    assert_eq!(names(&data), kept);
    assert_eq!(names(&p(Path::new(&data), "quarantine")), std::slice::from_ref(&lone));
    assert_eq!(std::fs::metadata(&segment).unwrap().len(), intact);
    assert!(!ok(&["data", "check", &data], None).contains("orphans"));
    assert!(ok(&["data", "repair", &data], None).starts_with("nothing to repair"));

    // A restart on the untreated copy cleans up the same way and serves the same state.
    let server = Server::start(&["--data", &restart], &log, &[]);
    let after = quiescent_status(&server);
    assert_eq!(
        (&after["version"], &after["digest"]),
        (&before["version"], &before["digest"])
    );
    assert_eq!(names(&restart), kept);
    assert_eq!(names(&p(Path::new(&restart), "quarantine")), [lone]);
    server.stop();
}

/// A damaged newest snapshot does not strand a directory: checkpoints keep the previous
/// snapshot and the log after it, `data check` shows that road, `data repair` takes it
/// (moving the damaged snapshot into quarantine/), and the server resumes the exact state
/// it had. Until then the server refuses the directory without creating so much as a lock.
#[test]
fn a_damaged_newest_snapshot_is_passed_by_the_older_road() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let (data, log, before) = crashed_after_two_checkpoints(dir, 5);
    std::fs::remove_file(Path::new(&data).join("LOCK")).unwrap();
    let newest = Path::new(&data).join(format!("snapshot-{:020}.naadf", 10));
    let mut bytes = std::fs::read(&newest).unwrap();
    let at = bytes.len() - 1;
    bytes[at] ^= 0x40;
    std::fs::write(&newest, bytes).unwrap();
    let damaged = contents(&data);

    let err = refused(&["--data", &data]);
    assert!(
        err.contains("cannot be loaded") && err.contains("resumes from snapshot 5"),
        "{err}"
    );
    let out = naadf(&["data", "check", &data], None);
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(!out.status.success(), "{report}");
    assert!(
        report.contains("older road: snapshot 5 and 7 logged record(s)"),
        "{report}"
    );
    let plan = ok(&["data", "repair", &data], None);
    for needle in [
        &format!(
            "move snapshot-{:020}.naadf into quarantine/: snapshot 10 cannot be loaded",
            10
        ),
        "then serve would resume from snapshot 5 and replay 7 logged record(s)",
    ] {
        assert!(plan.contains(needle), "no '{needle}' in: {plan}");
    }
    assert_eq!(contents(&data), damaged, "refusals and dry runs changed the directory");

    ok(&["data", "repair", &data, "--apply"], None);
    let server = Server::start(&["--data", &data], &log, &[]);
    let after = quiescent_status(&server);
    assert_eq!(
        (&after["version"], &after["digest"]),
        (&before["version"], &before["digest"])
    );
    server.stop();
}

/// What is left of a served world (a server state in which requests were answered, without
/// its world or any log) is never taken for a first start's leftovers: repair changes
/// nothing and the server refuses, creating nothing.
#[test]
fn a_lone_state_of_a_served_world_is_never_started_anew() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let world = start_world(dir);
    let data = p(dir, "data");
    let server = Server::start(&["--world", &world, "--data", &data], &dir.join("server.log"), &[]);
    edit(&server, 5, 9);
    server.stop();
    let lone = p(dir, "lone");
    std::fs::create_dir(&lone).unwrap();
    let state = format!("snapshot-{:020}.state", 5);
    std::fs::copy(Path::new(&data).join(&state), Path::new(&lone).join(&state)).unwrap();
    let before = contents(&lone);
    support::fails(&["data", "repair", &lone, "--apply"], None, "nothing was changed");
    let err = refused(&["--data", &lone, "--world", &world]);
    assert!(err.contains(&format!("{state} without its .naadf")), "{err}");
    assert_eq!(contents(&lone), before, "the directory changed");
}

/// Records replayed after a crash count towards the next checkpoint, and a replay as long
/// as the checkpoint interval is checkpointed at once: crash after crash, the log stays
/// short.
#[test]
fn checkpoints_count_the_records_replayed_after_a_crash() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let world = start_world(dir);
    let data = p(dir, "data");
    let log = dir.join("server.log");
    let serve = |every: &str| {
        Server::start(
            &["--world", &world, "--data", &data, "--checkpoint-every", every],
            &log,
            &[],
        )
    };
    let server = serve("100");
    edit(&server, 3, 1);
    server.kill9();
    // 3 replayed + 2 new edits reach 5.
    let server = serve("5");
    edit(&server, 2, 2);
    wait_for_snapshot(&data, 5);
    edit(&server, 3, 3);
    server.kill9();
    // 3 replayed records alone reach 3: a snapshot follows without any edit.
    let server = serve("3");
    wait_for_snapshot(&data, 8);
    server.stop();
}

/// A damaged snapshot (a flipped byte, a truncated file) is judged alike by `data check`
/// and `data repair`: neither calls it fine, and repair changes nothing.
#[test]
fn check_and_repair_judge_a_damaged_snapshot_alike() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let world = start_world(dir);
    let data = p(dir, "data");
    let server = Server::start(&["--world", &world, "--data", &data], &dir.join("server.log"), &[]);
    edit(&server, 5, 7);
    server.kill9();
    let snapshot = |ext: &str| format!("snapshot-{:020}.{ext}", 0);
    /// Which file of the snapshot, and what happens to its bytes.
    type Damage = (&'static str, fn(&mut Vec<u8>));
    let damages: [Damage; 3] = [
        ("state", |b| *b.last_mut().unwrap() ^= 1),
        ("naadf", |b| b.truncate(b.len() / 2)),
        ("naadf", |b| {
            let at = b.len() - 1;
            b[at] ^= 0x40;
        }),
    ];
    for (k, (ext, damage)) in damages.into_iter().enumerate() {
        let copy = p(dir, &format!("copy-{k}"));
        copy_dir(&data, &copy);
        let path = Path::new(&copy).join(snapshot(ext));
        let mut bytes = std::fs::read(&path).unwrap();
        damage(&mut bytes);
        std::fs::write(&path, bytes).unwrap();
        let before = contents(&copy);
        let out = naadf(&["data", "check", &copy], None);
        let report = String::from_utf8_lossy(&out.stdout);
        assert!(!out.status.success(), "{ext} damage {k}: {report}");
        assert!(report.contains("cannot be loaded"), "{ext} damage {k}: {report}");
        support::fails(&["data", "repair", &copy], None, "cannot be loaded");
        support::fails(&["data", "repair", &copy, "--apply"], None, "nothing was changed");
        assert_eq!(
            contents(&copy),
            before,
            "{ext} damage {k}: repair changed the directory"
        );
    }
}

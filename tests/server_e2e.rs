//! End-to-end tests of the server: the real `naadf serve` binary, real mirror clients over
//! gRPC, and the offline `naadf apply` as the oracle.

mod support;

use naadf_client::error::Code;
use naadf_client::{Client, Ended, Error, Mirror, Pose};
use naadf_world::digest::BufferId;
use naadf_world::{World, file};
use std::ops::ControlFlow;
use std::path::Path;
use std::time::Duration;
use support::{Server, free_addr, ok, p, random_op, serve_world, start_world, wait_for};
use tokio::sync::watch;
use tokio::task::JoinHandle;

/// A server on a fresh data directory in `dir`, started from a fresh `start_world`, with
/// `extra` arguments; returns the world file and the server.
fn serve_fresh(dir: &Path, extra: &[&str]) -> (String, Server) {
    let world = start_world(dir);
    let server = serve_world(dir, &world, extra, &[]);
    (world, server)
}

async fn client(url: &str, token: &str) -> Client {
    Client::connect(url, Some(token), None).await.expect("connect")
}

/// (version, digest, quiescent) of a live mirror.
type Point = (u64, String, bool);

/// A mirror following the server in a task.
struct Follower {
    state: watch::Receiver<Option<Point>>,
    stop: watch::Sender<bool>,
    task: JoinHandle<Mirror>,
}

impl Follower {
    async fn start(url: &str, token: &str, cache: Option<World>) -> Follower {
        Follower::follow(client(url, token).await, cache).await
    }

    /// Joins through `client` and follows.
    async fn follow(client: Client, cache: Option<World>) -> Follower {
        let mut session = client.join(cache).await.expect("join");
        let (tx, state) = watch::channel(None);
        let (stop, mut stopped) = watch::channel(false);
        let task = tokio::spawn(async move {
            let stop = async move {
                let _ = stopped.changed().await;
            };
            let ended = session
                .follow(stop, |mirror| -> Result<ControlFlow<()>, Error> {
                    if let Some(w) = mirror.world().filter(|_| mirror.is_live()) {
                        let _ = tx.send(Some((w.version(), w.digest().to_string(), mirror.is_quiescent())));
                    }
                    Ok(ControlFlow::Continue(()))
                })
                .await
                .expect("mirror follows the stream");
            assert_eq!(ended, Ended::Stopped(()), "the stream ended early");
            session.into_mirror()
        });
        Follower { state, stop, task }
    }

    async fn finish(self) -> Mirror {
        let _ = self.stop.send(true);
        self.task.await.expect("mirror task")
    }
}

/// Waits until the server is quiescent and every follower shows its version and digest.
async fn converge(c: &Client, followers: &[&Follower]) -> Point {
    for _ in 0..1200 {
        let s = c.status().await.expect("status");
        if s.quiescent {
            let want = Some((s.version, s.digest.to_string(), true));
            if followers.iter().all(|f| *f.state.borrow() == want) {
                return (s.version, s.digest.to_string(), true);
            }
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    panic!("mirrors did not converge");
}

/// Asserts two worlds hold identical buffers.
fn same_buffers(a: &World, b: &World) {
    assert_eq!(a.digest(), b.digest());
    for id in BufferId::WORLD {
        assert!(a.buffer_bytes(id) == b.buffer_bytes(id), "buffer {id:?} differs");
    }
}

/// Eight mirrors and four concurrent editors: at quiescent checkpoints every mirror equals
/// the server, and at the end they equal an offline `naadf apply` of `export-log`'s output.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn mirrors_converge_with_the_server_and_the_offline_apply() {
    let dir = tempfile::tempdir().unwrap();
    let (world, server) = serve_fresh(dir.path(), &[]);
    let data = p(dir.path(), "data");
    let mut followers = Vec::new();
    for i in 0..8 {
        followers.push(Follower::start(&server.url, &format!("viewer{i}"), None).await);
    }
    let admin = client(&server.url, "admin").await;
    for round in 0..3u64 {
        let mut editors = Vec::new();
        for e in 0..4u64 {
            let url = server.url.clone();
            editors.push(tokio::spawn(async move {
                let c = client(&url, &format!("editor{e}")).await;
                let mut rng = round * 1000 + e;
                for k in 0..15 {
                    let ops = random_op(&mut rng);
                    let r = c.edit(ops.as_str(), round * 100 + k + 1).await;
                    r.unwrap_or_else(|e| panic!("{ops}: {e}"));
                }
            }));
        }
        for e in editors {
            e.await.unwrap();
        }
        let (version, digest, _) = converge(&admin, &followers.iter().collect::<Vec<_>>()).await;
        assert_eq!(version, (round + 1) * 60);
        eprintln!("checkpoint {round}: version {version} digest {digest}");
    }
    let mut mirrors = Vec::new();
    for f in followers {
        mirrors.push(f.finish().await.into_world().unwrap());
    }
    for m in &mirrors[1..] {
        same_buffers(&mirrors[0], m);
    }
    // The log read while the server runs starts from the starting world (no checkpoint
    // yet): replayed offline it gives the mirrored buffers exactly.
    let script = p(dir.path(), "log.jsonl");
    ok(&["export-log", &data, "-o", &script], None);
    assert_eq!(std::fs::read_to_string(&script).unwrap().lines().count(), 180);
    let offline = p(dir.path(), "offline.naadf");
    ok(&["apply", &world, "--ops", &script, "-o", &offline], None);
    same_buffers(&file::load(Path::new(&offline)).unwrap(), &mirrors[0]);
    server.stop();
}

/// Edits acknowledged before a `kill -9` survive the restart; retried requests keep their
/// versions across restarts; the restarted server equals an offline replay of its log.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn acknowledged_edits_survive_kill_9_and_retries_are_not_reapplied() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let data = p(dir.path(), "data");
    let log = dir.path().join("log");
    let args = ["--world", world.as_str(), "--data", data.as_str()];
    let server = Server::start(&args, &log, &[]);

    // Four editors write distinct voxels as fast as acknowledgements come; the server is
    // killed while they are in flight.
    let (acked_tx, mut acked_rx) = tokio::sync::mpsc::unbounded_channel();
    let mut editors = Vec::new();
    for e in 0..4u32 {
        let url = server.url.clone();
        let acked = acked_tx.clone();
        editors.push(tokio::spawn(async move {
            let c = client(&url, &format!("editor{e}")).await;
            for k in 0..2000u32 {
                let (x, y, z, m) = (k % 128, 40 + e * 4 + (k / 128) % 4, k / 512, 1 + (k % 5));
                let ops = format!(r#"{{"op":"set","voxels":[[{x},{y},{z},{m}]]}}"#);
                match c.edit(ops, u64::from(k) + 1).await {
                    Ok(r) => acked.send((e, k, [x, y, z, m], r.version)).unwrap(),
                    // The server was killed under the call: the typed error says so.
                    Err(Error::ConnectionLost(_)) => return,
                    Err(e) => panic!("an edit failed otherwise than by the kill: {e}"),
                }
            }
        }));
    }
    drop(acked_tx);
    let mut acked = Vec::new();
    while acked.len() < 150 {
        acked.push(acked_rx.recv().await.expect("edits are acknowledged"));
    }
    server.kill9();
    for e in editors {
        e.await.unwrap();
    }
    while let Ok(a) = acked_rx.try_recv() {
        acked.push(a);
    }

    let server = Server::start(&args, &log, &[]);
    let c = client(&server.url, "editor0").await;
    let s = c.status().await.unwrap();
    let last_acked = acked.iter().map(|a| a.3).max().unwrap();
    assert!(
        s.version >= last_acked,
        "version {} < acknowledged {last_acked}",
        s.version
    );
    // Every acknowledged voxel is there, unless a later acknowledged edit overwrote it.
    let out = p(dir.path(), "after.naadf");
    ok(
        &[
            "mirror",
            "--server",
            &server.url,
            "--once",
            "-o",
            &out,
            "--no-cache",
            "--verify",
        ],
        None,
    );
    let w = file::load(Path::new(&out)).unwrap();
    for (_, _, [x, y, z, m], v) in &acked {
        let later = acked.iter().any(|(_, _, q, v2)| q[..3] == [*x, *y, *z] && v2 > v);
        if !later {
            assert_eq!(
                w.material_at([*x, *y, *z]),
                *m as u16,
                "acknowledged voxel at version {v} lost"
            );
        }
    }
    // A retry of an acknowledged request gets its version back and changes nothing.
    let (e, k, [x, y, z, m], v) = acked[0];
    let c = client(&server.url, &format!("editor{e}")).await;
    let retry = format!(r#"{{"op":"set","voxels":[[{x},{y},{z},{m}]]}}"#);
    let r = c.edit(retry.as_str(), u64::from(k) + 1).await.unwrap();
    assert_eq!((r.version, r.duplicate), (v, true));
    let s2 = c.status().await.unwrap();
    assert_eq!((s2.version, s2.digest), (s.version, s.digest));

    // A graceful restart keeps the answer too, and so does the snapshot it writes.
    server.stop();
    let server = Server::start(&args, &log, &[]);
    let c = client(&server.url, &format!("editor{e}")).await;
    let r = c.edit(retry, u64::from(k) + 1).await.unwrap();
    assert_eq!((r.version, r.duplicate), (v, true));
    server.stop();

    // The restarted server's state is the starting world plus its log, replayed offline.
    let script = p(dir.path(), "log.jsonl");
    let base = p(dir.path(), "base.naadf");
    ok(&["export-log", &data, "-o", &script, "--base", &base], None);
    let replayed = p(dir.path(), "replayed.naadf");
    ok(&["apply", &base, "--ops", &script, "-o", &replayed], None);
    same_buffers(&file::load(Path::new(&replayed)).unwrap(), &w);
}

/// A mirror that rejoins with its cache after a few edits gets just the deltas it missed;
/// one whose cache predates what the server remembers (here: a server restart) gets only
/// the pages that differ. Both cost a small fraction of a full join.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn rejoining_costs_a_fraction_of_a_join() {
    let dir = tempfile::tempdir().unwrap();
    let world = p(dir.path(), "big.naadf");
    ok(
        &["generate", "--preset", "terrain", "--size", "512,128,512", "-o", &world],
        None,
    );
    let args = ["--world", world.as_str(), "--data", &p(dir.path(), "data")];
    let log = dir.path().join("log");
    let server = Server::start(&args, &log, &[]);
    let c = client(&server.url, "ed").await;
    let f = Follower::start(&server.url, "viewer", None).await;
    converge(&c, &[&f]).await;
    let first = f.finish().await;
    let full = first.stats.bytes;
    let mut seq = 0;
    let mut edits = async |c: &Client, n: u64| {
        for _ in 0..n {
            seq += 1;
            let ops = format!(
                r#"{{"op":"sphere","center":[{},60,200],"radius":3,"material":2}}"#,
                200 + 5 * (seq % 50)
            );
            c.edit(ops, seq).await.unwrap();
        }
    };
    edits(&c, 10).await;
    let f = Follower::start(&server.url, "viewer", first.into_world()).await;
    let point = converge(&c, &[&f]).await;
    let resumed = f.finish().await;
    let resume_bytes = resumed.stats.bytes;
    assert_eq!(resumed.stats.pages, 0, "resumed from deltas");
    assert_eq!(resumed.world().unwrap().digest().to_string(), point.1);

    // After a restart the server has no deltas from before it: the cache's pages are used.
    edits(&c, 10).await;
    server.stop();
    let server = Server::start(&args, &log, &[]);
    let c = client(&server.url, "ed").await;
    let f = Follower::start(&server.url, "viewer", resumed.into_world()).await;
    let point = converge(&c, &[&f]).await;
    let paged = f.finish().await;
    let page_bytes = paged.stats.bytes;
    assert!(paged.stats.pages > 0);
    assert_eq!(paged.world().unwrap().digest().to_string(), point.1);
    eprintln!("full join {full} B; resume after 10 edits {resume_bytes} B; pages after restart {page_bytes} B");
    assert!(resume_bytes * 100 < full, "resume {resume_bytes} B vs full {full} B");
    assert!(
        page_bytes * 4 < full,
        "cache-aware snapshot {page_bytes} B vs full {full} B"
    );
    server.stop();
}

/// A client that stops reading does not hold up the others: its stream is cut. When it
/// reads again it finds the stream ended with ABORTED, joins again announcing what it
/// holds, and ends equal to the server.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_slow_client_is_cut_and_does_not_stall_others() {
    let dir = tempfile::tempdir().unwrap();
    let (_, server) = serve_fresh(dir.path(), &["--slow-client-events", "16"]);
    let c = client(&server.url, "ed").await;
    // The slow client joins, then does not read.
    let mut slow_stream = support::stalled_client(&server.url).await;
    let mut slow_mirror = Mirror::new(None);
    let fast = Follower::start(&server.url, "fast", None).await;
    // Enough delta bytes to fill the slow client's transport buffers many times over.
    for k in 0..300u64 {
        let voxels: Vec<String> = (0..100)
            .map(|i| format!("[{},{},{},3]", i, 50 + k % 10, k % 128))
            .collect();
        let ops = format!(r#"{{"op":"set","voxels":[{}]}}"#, voxels.join(","));
        c.edit(ops, k + 1).await.unwrap();
        // The edits keep pace with the fast mirror: the next one goes once it shows this
        // one with its distance fields grown (an edit's growth steps are events of their
        // own, so a lead of a few versions could already be 16 events on a loaded
        // machine). So only a client that stops reading falls the 16 events behind that
        // cut it. A server stalled by the slow client stalls the fast one too, and this
        // wait fails.
        let mut seen = fast.state.clone();
        tokio::time::timeout(
            Duration::from_secs(60),
            seen.wait_for(|p| p.as_ref().is_some_and(|p| p.0 > k && p.2)),
        )
        .await
        .expect("the fast mirror keeps up")
        .expect("the fast mirror follows");
    }
    let point = converge(&c, &[&fast]).await;
    assert_eq!(point.0, 300, "the fast mirror kept up while the slow one did not read");
    // Now the slow client reads: what reached its transport, then the end of the stream.
    let ending = loop {
        let m = tokio::time::timeout(Duration::from_secs(60), slow_stream.message())
            .await
            .expect("slow stream moves");
        match m {
            Ok(Some(m)) => {
                slow_mirror.handle(&m).unwrap();
            }
            Ok(None) => panic!("the stream ended without a status"),
            Err(status) => break status,
        }
    };
    assert_eq!(ending.code(), Code::Aborted, "{ending:?}");
    assert!(
        slow_mirror.world().is_none_or(|w| w.version() < 300),
        "it was cut before the end"
    );
    // It joins again with what it holds and catches up.
    let slow = Follower::start(&server.url, "slow", slow_mirror.into_world()).await;
    let point = converge(&c, &[&slow]).await;
    let slow = slow.finish().await;
    assert_eq!(slow.world().unwrap().digest().to_string(), point.1);
    fast.finish().await;
    server.stop();
}

/// Undo and redo are per user: undoing one user's edit keeps another user's later edit.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn undo_and_redo_are_per_user_and_survive_reconnects() {
    let dir = tempfile::tempdir().unwrap();
    let (world, server) = serve_fresh(dir.path(), &[]);
    let f = Follower::start(&server.url, "viewer", None).await;
    let alice = client(&server.url, "alice").await;
    let bob = client(&server.url, "bob").await;
    let sphere = r#"{"op":"sphere","center":[64,60,64],"radius":6,"material":4}"#;
    alice.edit(sphere, 1).await.unwrap();
    let bob_set = r#"{"op":"set","voxels":[[64,60,64,5]]}"#;
    bob.edit(bob_set, 1).await.unwrap();
    // Alice reconnects, then undoes: her sphere goes, Bob's voxel stays.
    drop(alice);
    let alice = client(&server.url, "alice").await;
    let v = alice.undo(2).await.unwrap().version;
    assert_eq!(v, 3);
    let err = bob.redo(2).await.unwrap_err();
    assert!(
        matches!(
            err,
            Error::Refused {
                code: Code::FailedPrecondition,
                ..
            }
        ),
        "{err}"
    );
    converge(&bob, &[&f]).await;
    let mirror = f.finish().await;
    let w = mirror.world().unwrap();
    assert_eq!(w.material_at([64, 60, 64]), 5, "bob's voxel survives alice's undo");
    let start = file::load(Path::new(&world)).unwrap();
    assert_eq!(
        w.material_at([62, 60, 64]),
        start.material_at([62, 60, 64]),
        "alice's sphere is undone"
    );
    let f = Follower::start(&server.url, "viewer", mirror.into_world()).await;
    alice.redo(3).await.unwrap();
    converge(&bob, &[&f]).await;
    let w = f.finish().await.into_world().unwrap();
    assert_eq!(w.material_at([62, 60, 64]), 4, "redo brings the sphere back");
    server.stop();
}

/// Entity RPCs are batches like any other: spawned, moved and despawned entities reach the
/// mirrors, which stay equal to the server.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn entity_requests_reach_the_mirrors() {
    let dir = tempfile::tempdir().unwrap();
    let (_, server) = serve_fresh(dir.path(), &[]);
    let f = Follower::start(&server.url, "viewer", None).await;
    let c = client(&server.url, "admin").await;
    let (model, spawns) = support::crates();
    c.edit(model, 1).await.unwrap();
    c.spawn_entities(&spawns, 2).await.unwrap();
    let unrotated = [0.0, 0.0, 0.0, 1.0];
    let moved = Pose {
        id: 2,
        pos: [70.5, 55.25, 90.0],
        rot: unrotated,
    };
    c.move_entities(&[moved], 3).await.unwrap();
    c.despawn_entities(&[3], 4).await.unwrap();
    let bad = Pose {
        id: 9,
        pos: [1.0, 1.0, 1.0],
        rot: unrotated,
    };
    assert_eq!(
        c.move_entities(&[bad], 5).await.unwrap_err().code(),
        Some(Code::InvalidArgument)
    );
    let point = converge(&c, &[&f]).await;
    assert_eq!(point.0, 4);
    let w = f.finish().await.into_world().unwrap();
    assert!(w.entity(3).is_none());
    assert_eq!(w.entity(2).unwrap().pos, [70.5, 55.25, 90.0]);
    assert_eq!(w.entity(1).unwrap().model, "crate");
    server.stop();
}

/// With a certificate and key the server speaks TLS, and clients trusting the CA connect.
/// Rotating the files changes the certificate that new connections see, without a restart
/// and without breaking open streams: at once on SIGHUP, otherwise at the next poll. A
/// rotation caught halfway (the new certificate, the old key) is refused, and the old pair
/// stays in use.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn tls_certificates_rotate_without_a_restart() {
    let dir = tempfile::tempdir().unwrap();
    let pair = |name: &str| {
        let k = rcgen::generate_simple_self_signed(vec!["localhost".to_string()]).unwrap();
        let (cert, key) = (
            p(dir.path(), &format!("{name}.crt")),
            p(dir.path(), &format!("{name}.key")),
        );
        std::fs::write(&cert, k.cert.pem()).unwrap();
        std::fs::write(&key, k.signing_key.serialize_pem()).unwrap();
        (cert, key)
    };
    let (a, b) = (pair("a"), pair("b"));
    let (cert, key) = (p(dir.path(), "cert.pem"), p(dir.path(), "key.pem"));
    let install = |from: &str, to: &str| std::fs::copy(from, to).map(drop).unwrap();
    install(&a.0, &cert);
    install(&a.1, &key);
    let (_, server) = serve_fresh(dir.path(), &["--tls-cert", &cert, "--tls-key", &key]);
    let port = server.url.rsplit(':').next().unwrap();
    let url = format!("https://localhost:{port}");
    let served_by = |ca: &str| {
        let out = support::naadf(&["status", "--server", &url, "--ca", ca, "--json"], None);
        out.status.success()
    };
    assert!(served_by(&a.0) && !served_by(&b.0));
    // Without trusting the certificate, or without TLS, the call fails cleanly.
    support::fails(&["status", "--server", &url], None, "error");
    support::fails(&["status", "--server", &server.url], None, "error");
    // Plain text where a handshake belongs: the server closes that connection, and only it.
    {
        use std::io::{Read, Write};
        let mut raw = std::net::TcpStream::connect(server.url.trim_start_matches("http://")).unwrap();
        raw.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
        raw.write_all(b"GET / HTTP/1.1\r\nHost: x\r\n\r\n").unwrap();
        let mut rest = Vec::new();
        let _ = raw.read_to_end(&mut rest);
        assert!(!rest.starts_with(b"HTTP/"), "no plain answer: {rest:?}");
    }
    assert!(served_by(&a.0));

    // A mirror and an editor hold their connections through the rotations.
    let connect = |token: &'static str| Client::connect(&url, Some(token), Some(Path::new(&a.0)));
    let f = Follower::follow(connect("viewer").await.unwrap(), None).await;
    let editor = connect("editor").await.unwrap();
    let mut rng = 5;
    editor.edit(random_op(&mut rng).as_str(), 1).await.unwrap();
    assert_eq!(converge(&editor, &[&f]).await.0, 1);

    let metric = |name: &str| support::metric_value(&support::http_get(&server.http, "/metrics").1, name);
    // Halfway: B's certificate, A's key.
    install(&b.0, &cert);
    server.signal("HUP");
    let failures = wait_for(|| metric("naadf_tls_reload_failures_total"), |m| m == Some(1)).await;
    assert_eq!(failures, Some(1), "a refused reload");
    assert!(served_by(&a.0) && !served_by(&b.0), "A stays in use");
    install(&b.1, &key);
    server.signal("HUP");
    let reloads = wait_for(|| metric("naadf_tls_reloads_total"), |m| m == Some(1)).await;
    assert_eq!(reloads, Some(1), "the reload");
    assert!(served_by(&b.0) && !served_by(&a.0), "B is in use");
    editor.edit(random_op(&mut rng).as_str(), 2).await.unwrap();
    assert_eq!(converge(&editor, &[&f]).await.0, 2, "open streams go on");

    // No signal: the poll finds A back.
    install(&a.1, &key);
    install(&a.0, &cert);
    assert!(wait_for(|| served_by(&a.0), |served| served).await, "the polled reload");
    assert!(!served_by(&b.0));
    editor.edit(random_op(&mut rng).as_str(), 3).await.unwrap();
    assert_eq!(converge(&editor, &[&f]).await.0, 3);
    f.finish().await;
    let log = std::fs::read_to_string(&server.log).unwrap();
    assert!(log.contains("TLS certificate reloaded"), "{log}");
    assert!(log.contains("the previous one stays in use"), "{log}");
    server.stop();
}

/// Periodic snapshots truncate the log behind them, and a restart from snapshot plus log
/// gives the same version and digest as before.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn checkpoints_truncate_the_log_and_restarts_keep_the_digest() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let data = p(dir.path(), "data");
    let args = [
        "--world",
        world.as_str(),
        "--data",
        data.as_str(),
        "--checkpoint-every",
        "5",
    ];
    let log = dir.path().join("log");
    let server = Server::start(&args, &log, &[]);
    let c = client(&server.url, "ed").await;
    let mut rng = 77;
    for k in 0..12 {
        c.edit(random_op(&mut rng), k + 1).await.unwrap();
    }
    let f = Follower::start(&server.url, "viewer", None).await;
    let before = converge(&c, &[&f]).await;
    f.finish().await;
    assert_eq!(before.0, 12);
    // Snapshots land on a helper thread; wait for the one at version 10.
    let names = || -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(&data)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .filter(|n| n.starts_with("snapshot-") || n.starts_with("wal-"))
            .collect();
        v.sort();
        v
    };
    // Snapshot 0 and its segment are pruned; the previous snapshot, 5, stays with its log.
    let want: Vec<String> = [
        "snapshot-00000000000000000005.naadf",
        "snapshot-00000000000000000005.state",
        "snapshot-00000000000000000010.naadf",
        "snapshot-00000000000000000010.state",
        "wal-00000000000000000005.log",
        "wal-00000000000000000010.log",
    ]
    .map(String::from)
    .into();
    for _ in 0..200 {
        if names() == want {
            break;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    assert_eq!(names(), want);
    server.kill9();
    let server = Server::start(&args, &log, &[]);
    let c = client(&server.url, "ed").await;
    let s = c.status().await.unwrap();
    assert_eq!((s.version, s.digest.to_string(), s.quiescent), before);
    server.stop();
}

/// A client speaking another protocol version is refused with a clear status.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_incompatible_protocol_version_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (_, server) = serve_fresh(dir.path(), &[]);
    let c = client(&server.url, "viewer").await;
    let req = naadf_proto::v1::JoinRequest {
        protocol_version: 99,
        ..Default::default()
    };
    let err = c.stream(req).await.unwrap_err();
    let Error::Refused {
        code: Code::FailedPrecondition,
        message,
    } = &err
    else {
        panic!("expected a refusal: {err}");
    };
    assert!(message.contains("protocol 99"), "{message}");
    server.stop();
}

/// `naadf mirror` (following, without --once) outlives its server: killed with -9 and
/// started again on the same address and data, the server is joined again by the mirror,
/// which then follows the edits made after the restart to the server's quiescent state
/// without being sent a page again, and exits cleanly when interrupted. With
/// `--log-versions` it also says when it applied each version, in order.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_following_mirror_joins_again_after_the_server_restarts() {
    use std::io::BufRead;
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let grpc = free_addr();
    let server = serve_world(dir.path(), &world, &["--grpc", &grpc], &[]);
    let url = server.url.clone();
    let log = dir.path().join("mirror.log");
    let mut mirror = std::process::Command::new(env!("CARGO_BIN_EXE_naadf"))
        .args(["mirror", "--server", &url, "--json", "--no-cache", "--log-versions"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::fs::File::create(&log).unwrap())
        .spawn()
        .expect("spawn naadf mirror");
    // The quiescent points the mirror prints, read on a thread of their own, which keeps
    // the versions it logs as applied.
    let (tx, points) = std::sync::mpsc::channel::<serde_json::Value>();
    let stdout = mirror.stdout.take().unwrap();
    let applied = std::sync::Arc::new(std::sync::Mutex::new(Vec::<(u64, u64)>::new()));
    let logged = applied.clone();
    std::thread::spawn(move || {
        for line in std::io::BufReader::new(stdout).lines().map_while(Result::ok) {
            let v: serde_json::Value = serde_json::from_str(&line).expect("JSON lines");
            if let (Some(version), Some(at)) = (v["version"].as_u64(), v["applied_unix_ns"].as_u64()) {
                logged.lock().unwrap().push((version, at));
            } else if tx.send(v).is_err() {
                return;
            }
        }
    });
    let reaches = |s: &naadf_client::ServerStatus| loop {
        let v = points.recv_timeout(Duration::from_secs(120)).unwrap_or_else(|_| {
            panic!(
                "the mirror did not reach version {}: {}",
                s.version,
                std::fs::read_to_string(&log).unwrap_or_default()
            )
        });
        if v["version"] == s.version && v["digest"] == s.digest.to_string() {
            return v;
        }
    };
    let mut rng = 17;
    let edits = |from: u64, rng: &mut u64| {
        let ops: Vec<String> = (0..5).map(|_| random_op(rng)).collect();
        let url = url.clone();
        async move {
            let c = Client::connect(&url, None, None).await.unwrap();
            for (k, op) in ops.into_iter().enumerate() {
                c.edit(op, from + k as u64).await.expect("edit acknowledged");
            }
        }
    };
    edits(1, &mut rng).await;
    let first = reaches(&support::quiescent(&url).await);
    server.kill9();
    // Long enough for the mirror to see the loss and fail a re-join or two.
    tokio::time::sleep(Duration::from_millis(500)).await;
    let server = serve_world(dir.path(), &world, &["--grpc", &grpc], &[]);
    edits(6, &mut rng).await;
    let after = support::quiescent(&url).await;
    assert_eq!(after.version, 10, "the restart kept the five acknowledged edits");
    let last = reaches(&after);
    // The restarted server resumes the mirror from the state it recovered (the same as the
    // mirror's), so the re-join costs no page.
    assert_eq!(last["pages"], first["pages"], "pages sent again: {first} then {last}");
    assert_eq!(last["snapshots"], 1, "the re-join was a resume: {last}");
    let said = std::fs::read_to_string(&log).unwrap();
    assert!(said.contains("joining again"), "the mirror logs its re-join: {said}");
    std::process::Command::new("kill")
        .args(["-INT", &mirror.id().to_string()])
        .status()
        .unwrap();
    let status = mirror.wait().unwrap();
    assert!(status.success(), "the interrupted mirror exits cleanly: {status}");
    server.stop();
    let applied = applied.lock().unwrap();
    assert!(
        applied.windows(2).all(|w| w[0].0 < w[1].0 && w[0].1 <= w[1].1),
        "versions logged once each, in order: {applied:?}"
    );
    assert_eq!(applied.last().map(|a| a.0), Some(10), "{applied:?}");
}

//! End-to-end tests of the server's resource limits against clients that stall: bounded
//! memory for clients that stop reading, and connections that never finish.

mod support;

use naadf_client::{Client, Mirror};
use naadf_proto::v1::world_service_client::WorldServiceClient;
use std::time::{Duration, Instant};
use support::{Server, serve_world, stalled_client, start_world};
use tokio::sync::watch;

/// The server process's resident memory, in MiB.
fn rss_mib(pid: u32) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap();
    let kib: u64 = status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .expect("VmRSS in /proc/PID/status");
    kib / 1024
}

/// One metric's value from `/metrics`.
fn metric(server: &Server, name: &str) -> u64 {
    let (_, text) = support::http_get(&server.http, "/metrics");
    text.lines()
        .find_map(|l| l.strip_prefix(name)?.strip_prefix(' '))
        .and_then(|v| v.parse::<f64>().ok())
        .unwrap_or_else(|| panic!("{name} in /metrics"))
        .round() as u64
}

/// A `set` op of `n` voxels scattered over the 128×64×128 world with mixed materials:
/// its delta touches most pages, and its pages compress badly.
fn scattered_set(n: usize, seed: u64) -> String {
    let mut state = seed;
    let mut next = |m: u64| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 33) % m
    };
    let voxels: Vec<String> = (0..n)
        .map(|_| format!("[{},{},{},{}]", next(128), next(64), next(128), next(6)))
        .collect();
    format!(r#"{{"op":"set","voxels":[{}]}}"#, voxels.join(","))
}

/// A mirror that reads all the time; its version is published in the returned watch.
async fn live_client(url: &str) -> watch::Receiver<u64> {
    let channel = tonic::transport::Endpoint::from_shared(url.to_owned())
        .unwrap()
        .connect()
        .await
        .unwrap();
    // Messages of any size, as the real client takes them (a resync's may pass tonic's
    // default of 4 MiB).
    let mut raw = WorldServiceClient::new(channel).max_decoding_message_size(usize::MAX);
    let mut mirror = Mirror::new(None);
    let mut stream = raw.join(mirror.join_request()).await.unwrap().into_inner();
    let (tx, rx) = watch::channel(0);
    tokio::spawn(async move {
        loop {
            let m = match stream.message().await {
                Ok(Some(m)) => m,
                // Dropping `tx` fails the test's wait; say why the stream ended.
                end => {
                    eprintln!("the live client's stream ended: {end:?}");
                    return;
                }
            };
            if let Err(e) = mirror.handle(&m) {
                eprintln!("the live client's mirror refused a message: {e}");
                return;
            }
            if let Some(w) = mirror.world() {
                tx.send_replace(w.version());
            }
        }
    });
    rx
}

/// Clients that stop reading while a writer sends large batches cost the server a bounded
/// amount of memory: each is cut once it is more bytes behind than `--slow-client-bytes`
/// allows (long before the event bound), which releases its backlog at once although its
/// connection stays, and a live client keeps receiving every version promptly. (Each delta
/// is about 0.8 MiB; 60 of them.)
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn stalled_clients_hold_bounded_memory_and_live_clients_keep_up() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(
        dir.path(),
        &world,
        &[
            "--slow-client-events",
            "100000",
            "--slow-client-bytes",
            &(4u64 << 20).to_string(),
            "--slow-clients-total-bytes",
            &(16u64 << 20).to_string(),
            "--rate",
            "100000",
        ],
        &[],
    );
    let writer = Client::connect(&server.url, Some("writer"), None).await.unwrap();
    let mut stalled = Vec::new();
    for _ in 0..8 {
        stalled.push(stalled_client(&server.url).await);
    }
    let mut live = live_client(&server.url).await;
    tokio::time::sleep(Duration::from_secs(1)).await;
    let before = rss_mib(server.pid());
    let mut peak = before;
    let edits = 60u64;
    for k in 1..=edits {
        let version = writer.edit(scattered_set(200_000, k), k).await.unwrap().version;
        let seen = Instant::now();
        tokio::time::timeout(Duration::from_secs(20), live.wait_for(|&v| v >= version))
            .await
            .unwrap_or_else(|_| panic!("the live client did not see version {version} within 20 s"))
            .unwrap();
        assert!(seen.elapsed() < Duration::from_secs(20));
        peak = peak.max(rss_mib(server.pid()));
    }
    let sent = metric(&server, "naadf_bytes_sent_total");
    let resyncs = metric(&server, "naadf_resyncs_total");
    let backlog = metric(&server, "naadf_backlog_bytes");
    let max_client = metric(&server, "naadf_backlog_max_client_bytes");
    eprintln!(
        "RSS {before} MiB -> peak {peak} MiB; {} MiB sent; {resyncs} resyncs; backlog {backlog} B (max {max_client} B)",
        sent >> 20
    );
    assert!(resyncs >= 8, "every stalled client was cut ({resyncs} resyncs)");
    // A cut client holds nothing while its connection lives on: what is left is the live
    // client's, at most about a delta.
    assert!(
        backlog <= 2 << 20,
        "the cut clients' backlogs were released ({backlog} B left)"
    );
    assert!(
        max_client <= 8 << 20,
        "a client's backlog stays near its bound ({max_client} B)"
    );
    // The writes alone grow the server by about 190 MiB (undo history, recent deltas, the
    // allocator's pools); unbounded, the stalled clients add about 50 MiB each.
    assert!(
        peak < before + 400,
        "stalled clients pinned {} MiB (RSS {before} -> {peak} MiB)",
        peak - before
    );
    drop(stalled);
    server.stop();
}

/// Runs `f` on a thread; its result if it finishes within `limit`.
fn within<T: Send + 'static>(limit: Duration, f: impl FnOnce() -> T + Send + 'static) -> Option<T> {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(limit).ok()
}

/// Opens `n` connections to `addr` that each send `first` and then stall.
fn stalled_connections(addr: &str, n: usize, first: &[u8]) -> Vec<std::net::TcpStream> {
    use std::io::Write;
    (0..n)
        .map(|_| {
            let mut s = std::net::TcpStream::connect(addr).unwrap();
            s.write_all(first).unwrap();
            s
        })
        .collect()
}

/// Whether the server closed `s`: a read ends (EOF, or a reset) within `limit`.
fn closed_within(s: &mut std::net::TcpStream, limit: Duration) -> bool {
    use std::io::Read;
    s.set_read_timeout(Some(limit)).unwrap();
    let mut buf = [0u8; 4096];
    loop {
        match s.read(&mut buf) {
            Ok(0) => return true,
            Ok(_) => {}
            Err(e) => return e.kind() == std::io::ErrorKind::ConnectionReset,
        }
    }
}

/// Connections that never finish (an HTTP/2 preface and silence on the gRPC port, half an
/// HTTP request on the HTTP port), more of them than the server has file descriptors, do
/// not lock everyone out: the connection cap keeps descriptors free, stalled connections
/// are closed to make room or at the request deadline, and `naadf status` and `/health`
/// are served.
#[test]
fn stalled_connections_are_closed_and_do_not_lock_out_others() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(
        dir.path(),
        &world,
        &["--max-connections", "64", "--idle-timeout", "2"],
        &[],
    );
    let st = std::process::Command::new("prlimit")
        .args(["--pid", &server.pid().to_string(), "--nofile=256:256"])
        .status()
        .unwrap();
    assert!(st.success(), "prlimit");
    let grpc = server.url.trim_start_matches("http://").to_owned();
    let mut stalled = stalled_connections(&grpc, 150, b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n");
    stalled.extend(stalled_connections(
        &server.http,
        150,
        b"GET /health HTTP/1.1\r\nHost: x\r\n",
    ));

    let started = Instant::now();
    let url = server.url.clone();
    let status = within(Duration::from_secs(40), move || {
        support::naadf(&["status", "--server", &url, "--json"], None)
    })
    .expect("`naadf status` answered within 40 s");
    assert!(status.status.success(), "{}", String::from_utf8_lossy(&status.stderr));
    let http = server.http.clone();
    let (code, body) = within(Duration::from_secs(40), move || support::http_get(&http, "/health"))
        .expect("/health answered within 40 s");
    assert_eq!(code, 200, "{body}");
    eprintln!("served after {:?}", started.elapsed());

    for s in &mut stalled {
        assert!(
            closed_within(s, Duration::from_secs(30)),
            "a stalled connection was closed"
        );
    }
    let log = std::fs::read_to_string(&server.log).unwrap();
    let warnings = log.matches("cannot accept connections").count();
    assert!(
        warnings <= 10,
        "{warnings} accept warnings: logged per back-off period, not per attempt"
    );
    server.stop();
}

/// Connections that never make a request do not hold their slots: at the cap, a newcomer
/// closes the oldest of them at once (so `/health` and `status` answer with the cap full of
/// them), and those that stay past the request deadline are closed however busy they keep
/// their connection: a slowloris trickling a byte at a time, and an HTTP/2 client that
/// finished the handshake and answers every ping. A client that made a request stays.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn requestless_connections_make_room_and_meet_the_request_deadline() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(
        dir.path(),
        &world,
        &["--max-connections", "8", "--request-deadline", "1"],
        &[],
    );
    let grpc = server.url.trim_start_matches("http://").to_owned();
    let editor = Client::connect(&server.url, Some("ed"), None).await.unwrap();
    editor.status().await.unwrap();
    // Both listeners full of connections without a request.
    let mut stalled = stalled_connections(&grpc, 8, b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n");
    stalled.extend(stalled_connections(
        &server.http,
        8,
        b"GET /health HTTP/1.1\r\nHost: x\r\n",
    ));
    let started = Instant::now();
    let http = server.http.clone();
    let (code, _) = tokio::task::spawn_blocking(move || support::http_get(&http, "/health"))
        .await
        .unwrap();
    assert_eq!(code, 200);
    let status = Client::connect(&server.url, None, None).await.unwrap().status().await;
    assert!(status.is_ok(), "{status:?}");
    let answered = started.elapsed();
    assert!(
        answered < Duration::from_millis(900),
        "answered after {answered:?}: before the deadline freed anything"
    );

    // A slowloris and a silent HTTP/2 client are closed at the deadline.
    let mut slowloris = std::net::TcpStream::connect(&server.http).unwrap();
    let mut trickle = slowloris.try_clone().unwrap();
    std::thread::spawn(move || {
        use std::io::Write;
        let _ = trickle.write_all(b"GET /health HTTP/1.1\r\n");
        while trickle.write_all(b"x").is_ok() {
            std::thread::sleep(Duration::from_millis(100));
        }
    });
    let silent = tokio::net::TcpStream::connect(&grpc).await.unwrap();
    let (send, connection) = h2::client::handshake(silent).await.unwrap();
    let started = Instant::now();
    let silent_closed = tokio::time::timeout(Duration::from_secs(5), connection).await;
    assert!(silent_closed.is_ok(), "the silent HTTP/2 connection was closed");
    let after = started.elapsed();
    assert!(
        after > Duration::from_millis(500),
        "closed after {after:?}: not before its deadline"
    );
    drop(send);
    let slow_closed = tokio::task::spawn_blocking(move || closed_within(&mut slowloris, Duration::from_secs(5)))
        .await
        .unwrap();
    assert!(slow_closed, "the slowloris was closed");
    // The editor's connection made a request: the deadline does not apply to it.
    editor.edit(r#"{"op":"set","voxels":[[1,1,1,2]]}"#, 1).await.unwrap();
    drop(stalled);
    server.stop();
}

/// The idle timeout closes only silent peers: a joined client that gets no deltas for
/// longer than the timeout stays connected (it answers the server's keepalive pings) and
/// still receives the next delta.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn idle_live_clients_outlast_the_idle_timeout() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(dir.path(), &world, &["--idle-timeout", "1"], &[]);
    let mut live = live_client(&server.url).await;
    tokio::time::sleep(Duration::from_secs(4)).await;
    let writer = Client::connect(&server.url, Some("writer"), None).await.unwrap();
    let version = writer
        .edit(r#"{"op":"set","voxels":[[1,2,3,1]]}"#, 1)
        .await
        .unwrap()
        .version;
    tokio::time::timeout(Duration::from_secs(20), live.wait_for(|&v| v >= version))
        .await
        .expect("the idle client still receives deltas")
        .unwrap();
    server.stop();
}

/// A client that stops reading and then leaves frees its join at once: the task that
/// waited for room in its stream ends (`naadf_clients` drops to 0), and the server still
/// shuts down cleanly. (A stream dropped by the transport used to keep its queue alive, so
/// that task waited forever, holding the actor's mailbox open past shutdown.)
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_client_that_leaves_mid_snapshot_frees_its_join() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(dir.path(), &world, &[], &[]);
    let stalled = stalled_client(&server.url).await;
    let joined = Instant::now();
    while metric(&server, "naadf_clients") == 0 && joined.elapsed() < Duration::from_secs(10) {
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    assert_eq!(metric(&server, "naadf_clients"), 1);
    // Its stream's queue fills up with pages it never reads.
    tokio::time::sleep(Duration::from_millis(500)).await;
    drop(stalled);
    let left = Instant::now();
    while metric(&server, "naadf_clients") > 0 && left.elapsed() < Duration::from_secs(10) {
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    assert_eq!(metric(&server, "naadf_clients"), 0, "the join ended with its client");
    server.stop();
}

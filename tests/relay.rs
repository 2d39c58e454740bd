//! `naadf relay` against real `naadf serve` processes: a relay (and a relay of a relay)
//! passes on the server's stream byte for byte, forwards writes with the caller's token,
//! waits for an upstream that is not up yet, rides out an upstream crash, gives up an
//! upstream link that went silent, and never passes on a delta whose digest does not match.

mod support;

use naadf_client::mirror::{Mirror, Progress};
use naadf_client::{Client, WorldStream};
use naadf_proto::v1::{WorldMessage, world_message};
use naadf_server::metrics::Metrics;
use naadf_server::relay::gate::UpstreamAuth;
use naadf_server::relay::hub::{Hub, Input};
use naadf_server::relay::upstream::Upstream;
use naadf_server::stream::messages::Request;
use prost::Message;
use std::sync::Arc;
use std::time::Duration;
use support::{Server, free_addr, http_get, quiescent, random_op, serve_world, start_world, wait_for};
use tokio::sync::{Notify, broadcast, oneshot};

/// Long enough for a join and the distance fields to settle on a slow machine.
const SETTLE: Duration = Duration::from_secs(120);

/// A mirror following one raw stream, keeping every delta it applied as encoded bytes.
struct Follower {
    mirror: Mirror,
    stream: WorldStream,
    deltas: Vec<Vec<u8>>,
}

impl Follower {
    async fn join(client: &Client) -> Self {
        let mut mirror = Mirror::default();
        let stream = client.stream(mirror.join_request()).await.unwrap();
        Self {
            mirror,
            stream,
            deltas: Vec::new(),
        }
    }

    /// Applies messages until the mirror is quiescent at `version` or later.
    async fn until(&mut self, version: u64) -> (u64, naadf_world::digest::Digest) {
        let wait = async {
            loop {
                if self.mirror.is_quiescent() && self.mirror.world().unwrap().version() >= version {
                    let w = self.mirror.world().unwrap();
                    return (w.version(), w.digest());
                }
                let m = self.stream.message().await.unwrap().expect("the stream goes on");
                if self.mirror.handle(&m).unwrap() == Progress::Delta {
                    self.deltas.push(m.encode_to_vec());
                }
            }
        };
        tokio::time::timeout(SETTLE, wait).await.expect("settles in time")
    }
}

/// Waits until the relay's `/health` says it holds its upstream's world.
fn live(relay: &Server) {
    for _ in 0..1200 {
        if http_get(&relay.http, "/health").0 == 200 {
            return;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    panic!("the relay never got its upstream's world");
}

/// The user a delta message names.
fn delta_user(bytes: &[u8]) -> String {
    match WorldMessage::decode(bytes).unwrap().kind {
        Some(world_message::Kind::Delta(d)) => d.user,
        other => panic!("not a delta: {other:?}"),
    }
}

/// Clients of the server, of a relay and of a relay of that relay see the same deltas,
/// byte for byte, and end on the server's digest; edits sent through either relay reach
/// the server under the caller's own name.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn relays_pass_the_stream_on_byte_for_byte_and_forward_edits() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(dir.path(), &world, &[], &[]);
    let relay = Server::relay(&server.url, &[], &dir.path().join("relay.log"));
    let chained = Server::relay(&relay.url, &[], &dir.path().join("chained.log"));

    let urls = [&server.url, &relay.url, &chained.url];
    let mut followers = Vec::new();
    for (k, url) in urls.iter().enumerate() {
        let c = Client::connect(url, Some(&format!("viewer{k}")), None).await.unwrap();
        let mut f = Follower::join(&c).await;
        f.until(0).await;
        followers.push(f);
    }

    let mut rng = 11;
    let mut last = 0;
    for seq in 1..=12u64 {
        let k = (seq % 3) as usize;
        let c = Client::connect(urls[k], Some(&format!("editor{k}")), None)
            .await
            .unwrap();
        let ack = c.edit(random_op(&mut rng), seq).await.unwrap();
        assert!(ack.version > last, "versions grow: {ack:?} after {last}");
        last = ack.version;
    }
    let status = quiescent(&server.url).await;
    assert!(status.version >= last);
    let mut states = Vec::new();
    for f in &mut followers {
        states.push(f.until(status.version).await);
    }
    assert!(
        states.iter().all(|&s| s == (status.version, status.digest)),
        "{states:?} vs {status:?}"
    );
    let direct = &followers[0].deltas;
    assert!(direct.len() >= 12, "every edit came as a delta");
    for (k, f) in followers.iter().enumerate().skip(1) {
        assert!(f.deltas == *direct, "relay {k} changed the stream");
    }
    let users: Vec<String> = direct.iter().map(|d| delta_user(d)).filter(|u| !u.is_empty()).collect();
    for k in 0..3 {
        let n = users.iter().filter(|u| **u == format!("editor{k}")).count();
        assert_eq!(n, 4, "editor{k}'s edits under its own name: {users:?}");
    }
    // The relays report their own mirror and their clients.
    let relayed = Client::connect(&chained.url, None, None)
        .await
        .unwrap()
        .status()
        .await
        .unwrap();
    assert_eq!((relayed.version, relayed.digest), (status.version, status.digest));
    let (code, health) = http_get(&chained.http, "/health");
    assert_eq!(code, 200, "{health}");
    let (_, metrics) = http_get(&relay.http, "/metrics");
    assert!(
        metrics.lines().any(|l| l == "naadf_clients 2"),
        "a viewer and the chained relay:\n{metrics}"
    );
    assert!(metrics.contains("naadf_upstream_connected 1"), "{metrics}");
    drop(followers);
    chained.stop();
    relay.stop();
    server.stop();
}

/// A relay holds no tokens: the upstream decides every caller's role, edits go upstream
/// with the caller's token and `client_seq`, and a refusal comes back as the upstream gave it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_relay_widens_no_role_and_forwards_the_callers_token() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let tokens = [("NAADF_TOKENS", "rt=relay:viewer,vt=vera:viewer,et=edwin:editor")];
    let server = serve_world(dir.path(), &world, &[], &tokens);
    let relay = Server::relay(&server.url, &["--token", "rt"], &dir.path().join("relay.log"));
    live(&relay);

    let editor = Client::connect(&relay.url, Some("et"), None).await.unwrap();
    let me = editor.status().await.unwrap();
    assert_eq!((me.user.as_str(), me.role.as_str()), ("edwin", "editor"));
    let op = r#"{"op":"set","voxels":[[3,4,5,1]]}"#;
    let first = editor.edit(op, 7).await.unwrap();
    let again = editor.edit(op, 7).await.unwrap();
    assert!(
        !first.duplicate && again.duplicate,
        "the caller's client_seq went upstream"
    );
    assert_eq!(again.version, first.version);

    let viewer = Client::connect(&relay.url, Some("vt"), None).await.unwrap();
    let refused = viewer.edit(op, 1).await.unwrap_err();
    let direct = Client::connect(&server.url, Some("vt"), None)
        .await
        .unwrap()
        .edit(op, 2)
        .await
        .unwrap_err();
    assert_eq!(refused.code(), direct.code(), "{refused} vs {direct}");
    assert_eq!(refused.code(), Some(naadf_client::error::Code::PermissionDenied));
    let stranger = Client::connect(&relay.url, Some("nope"), None).await.unwrap();
    for e in [
        stranger.status().await.unwrap_err(),
        stranger.join(None).await.expect_err("a join with a bad token fails"),
        stranger.edit(op, 1).await.unwrap_err(),
    ] {
        assert_eq!(e.code(), Some(naadf_client::error::Code::Unauthenticated), "{e}");
    }
    assert_eq!(
        http_get(&relay.http, "/status").0,
        401,
        "the status page asks the upstream too"
    );
    assert_eq!(http_get(&relay.http, "/status?token=vt").0, 200);
    // The viewer reads the edit through the relay.
    let mut session = viewer.join(None).await.unwrap();
    let w = session.until_quiescent(first.version, SETTLE).await.unwrap();
    assert_eq!(w.version(), first.version);
    // A server with tokens refuses anonymous callers, so a relay in front of it admits
    // callers from other machines, and the upstream still decides who they are.
    let gate = UpstreamAuth::new(Upstream::new(&server.url, None, None, Duration::from_secs(20)).unwrap());
    let remote = Some("192.0.2.7:40000".parse().unwrap());
    gate.admit(remote).await.unwrap();
    let anonymous = gate.caller(&tonic::metadata::MetadataMap::new(), remote).await;
    assert_eq!(anonymous.unwrap_err().code(), tonic::Code::Unauthenticated);
    let mut md = tonic::metadata::MetadataMap::new();
    md.insert("authorization", "Bearer vt".parse().unwrap());
    assert_eq!(gate.caller(&md, remote).await.unwrap().user, "vera");
    relay.stop();
    server.stop();
}

/// A local address of this machine that is not loopback, if it has a route anywhere (no
/// packet is sent: connecting a UDP socket only picks the source address).
fn non_loopback_ip() -> Option<std::net::IpAddr> {
    let s = std::net::UdpSocket::bind("0.0.0.0:0").ok()?;
    s.connect("192.0.2.1:9").ok()?;
    Some(s.local_addr().ok()?.ip()).filter(|ip| !ip.is_loopback() && !ip.is_unspecified())
}

/// An open server (no tokens) makes every caller an admin and therefore serves loopback
/// only; a relay in front of it must not hand those rights to the network, so it refuses
/// every caller that is not on its own machine, token or not, on gRPC and HTTP alike.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_relay_in_front_of_an_open_server_admits_only_its_own_machine() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(dir.path(), &world, &[], &[]);
    let gate = UpstreamAuth::new(Upstream::new(&server.url, None, None, Duration::from_secs(20)).unwrap());
    let denied = tonic::Code::PermissionDenied;
    gate.admit(Some("127.0.0.1:40000".parse().unwrap())).await.unwrap();
    gate.admit(Some("[::1]:40000".parse().unwrap())).await.unwrap();
    for peer in [Some("192.0.2.7:40000".parse().unwrap()), None] {
        assert_eq!(gate.admit(peer).await.unwrap_err().code(), denied);
        let mut md = tonic::metadata::MetadataMap::new();
        md.insert("authorization", "Bearer any".parse().unwrap());
        assert_eq!(gate.caller(&md, peer).await.unwrap_err().code(), denied);
    }

    let relay = Server::relay(
        &server.url,
        &["--grpc", "0.0.0.0:0", "--http", "0.0.0.0:0"],
        &dir.path().join("relay.log"),
    );
    live(&relay);
    let port = |addr: &str| addr.rsplit(':').next().unwrap().parse::<u16>().unwrap();
    let (grpc_port, http_port) = (port(&relay.url), port(&relay.http));
    let local = Client::connect(&format!("http://127.0.0.1:{grpc_port}"), None, None)
        .await
        .unwrap();
    assert_eq!(
        local.status().await.unwrap().role,
        "admin",
        "loopback callers are served"
    );
    assert_eq!(http_get(&format!("127.0.0.1:{http_port}"), "/status").0, 200);
    let Some(ip) = non_loopback_ip() else {
        eprintln!("SKIPPED (part): this machine has no non-loopback address to call the relay from");
        relay.stop();
        server.stop();
        return;
    };
    let at = |port| std::net::SocketAddr::new(ip, port).to_string();
    let remote = Client::connect(&format!("http://{}", at(grpc_port)), Some("any"), None)
        .await
        .unwrap();
    let before = local.status().await.unwrap().version;
    let op = r#"{"op":"set","voxels":[[3,4,5,1]]}"#;
    for e in [
        remote.status().await.unwrap_err(),
        remote.join(None).await.expect_err("a join from another machine fails"),
        remote.edit(op, 1).await.unwrap_err(),
        remote.undo(1).await.unwrap_err(),
    ] {
        assert_eq!(e.code(), Some(naadf_client::error::Code::PermissionDenied), "{e}");
    }
    assert_eq!(http_get(&at(http_port), "/status?token=any").0, 403);
    assert_eq!(http_get(&at(http_port), "/frame.png?token=any").0, 403);
    let after = local.status().await.unwrap().version;
    assert_eq!(after, before, "nothing from the network reached the server");
    relay.stop();
    server.stop();
}

/// A relay whose upstream is not up yet says so in its log, reports itself unavailable,
/// and keeps trying; once the server is up, its clients get the server's world. When the
/// server is then killed and restarted, the relay re-joins by itself, its client keeps its
/// stream, and every acknowledged edit arrives.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_relay_waits_for_its_upstream_and_rides_out_a_crash() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let grpc = free_addr();
    let url = format!("http://{grpc}");
    let log = dir.path().join("relay.log");
    let relay = Server::relay(&url, &[], &log);
    let mut waited = 0;
    while !std::fs::read_to_string(&log).unwrap().contains("cannot join upstream") {
        std::thread::sleep(Duration::from_millis(100));
        waited += 1;
        assert!(waited < 300, "no retry logged");
    }
    assert_eq!(http_get(&relay.http, "/health").0, 503);

    let server = serve_world(dir.path(), &world, &["--grpc", &grpc], &[]);
    let c = Client::connect(&relay.url, Some("ed"), None).await.unwrap();
    let mut session = c.join(None).await.unwrap();
    session.until_quiescent(0, SETTLE).await.unwrap();
    let mut rng = 5;
    let mut acked = Vec::new();
    for seq in 1..=4 {
        acked.push(c.edit(random_op(&mut rng), seq).await.unwrap().version);
    }
    server.kill9();
    let server = serve_world(dir.path(), &world, &["--grpc", &grpc], &[]);
    // Edits through the relay work again once it reaches the new process.
    for seq in 5..=8 {
        let op = random_op(&mut rng);
        let ack = loop {
            match c.edit(op.clone(), seq).await {
                Ok(a) => break a,
                Err(e) if e.code() == Some(naadf_client::error::Code::Unavailable) => {
                    tokio::time::sleep(Duration::from_millis(100)).await
                }
                Err(e) => panic!("{e}"),
            }
        };
        acked.push(ack.version);
    }
    let last = *acked.iter().max().unwrap();
    let status = quiescent(&server.url).await;
    assert!(
        status.version >= last && acked.len() == 8,
        "every acknowledged edit survived: {acked:?}"
    );
    let w = session.until_quiescent(status.version, SETTLE).await.unwrap();
    assert_eq!((w.version(), w.digest()), (status.version, status.digest));
    let joins = metric(&relay, "naadf_upstream_joins_total");
    assert!(joins >= 2, "joined before and after the crash: {joins}");
    relay.stop();
    server.stop();
}

/// A loopback TCP proxy to `target` that can be frozen: while `frozen` holds true it
/// neither reads nor writes on any connection (new ones included), as a link that drops
/// every packet would look to both ends, without either seeing an error.
async fn freezable_proxy(target: String, frozen: tokio::sync::watch::Receiver<bool>) -> String {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    tokio::spawn(async move {
        while let Ok((inbound, _)) = listener.accept().await {
            let Ok(outbound) = tokio::net::TcpStream::connect(&target).await else {
                continue;
            };
            let (ri, wi) = inbound.into_split();
            let (ro, wo) = outbound.into_split();
            tokio::spawn(pipe(ri, wo, frozen.clone()));
            tokio::spawn(pipe(ro, wi, frozen.clone()));
        }
    });
    format!("http://{addr}")
}

/// Copies `from` to `to` while not `frozen`, until either side closes.
async fn pipe(
    mut from: tokio::net::tcp::OwnedReadHalf,
    mut to: tokio::net::tcp::OwnedWriteHalf,
    mut frozen: tokio::sync::watch::Receiver<bool>,
) {
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let mut buf = vec![0u8; 1 << 16];
    loop {
        if frozen.wait_for(|f| !f).await.is_err() {
            return;
        }
        let n = match from.read(&mut buf).await {
            Ok(0) | Err(_) => return,
            Ok(n) => n,
        };
        // What was read as the link froze waits for it to thaw.
        if frozen.wait_for(|f| !f).await.is_err() || to.write_all(&buf[..n]).await.is_err() {
            return;
        }
    }
}

/// The relay's `naadf_upstream_connected` and `naadf_upstream_joins_total`.
fn upstream_metrics(relay: &Server) -> (u64, u64) {
    (
        metric(relay, "naadf_upstream_connected"),
        metric(relay, "naadf_upstream_joins_total"),
    )
}

/// One of the relay's metrics, a whole number.
fn metric(relay: &Server, name: &str) -> u64 {
    let (_, metrics) = http_get(&relay.http, "/metrics");
    support::metric_value(&metrics, name).unwrap_or_else(|| panic!("no {name} in {metrics}"))
}

/// Waits up to 30 s for the relay's upstream metrics to satisfy `ok`; the last seen.
async fn wait_upstream(relay: &Server, ok: impl Fn((u64, u64)) -> bool) -> (u64, u64) {
    wait_for(|| upstream_metrics(relay), ok).await
}

/// A link that goes silent without an error (every packet dropped) is noticed by the
/// relay within its `--upstream-timeout`: it gives the connection up, reports itself
/// disconnected, shows its state ageing meanwhile, and re-joins once the link carries
/// packets again; its client keeps its stream and ends on the server's state, edits made
/// meanwhile included, and the relay shows itself current again.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_relay_gives_up_a_silent_upstream_and_rejoins() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(dir.path(), &world, &[], &[]);
    let (freeze, frozen) = tokio::sync::watch::channel(false);
    let target = server.url.trim_start_matches("http://").to_owned();
    let proxy = freezable_proxy(target, frozen).await;
    let relay = Server::relay(&proxy, &["--upstream-timeout", "1"], &dir.path().join("relay.log"));
    live(&relay);
    let c = Client::connect(&relay.url, None, None).await.unwrap();
    let mut session = c.join(None).await.unwrap();
    session.until_quiescent(0, SETTLE).await.unwrap();
    let (connected, joins) = wait_upstream(&relay, |(c, _)| c == 1).await;
    assert_eq!(connected, 1);

    freeze.send(true).unwrap();
    let direct = Client::connect(&server.url, None, None).await.unwrap();
    let mut rng = 9;
    for seq in 1..=3 {
        direct.edit(random_op(&mut rng), seq).await.unwrap();
    }
    let (connected, _) = wait_upstream(&relay, |(c, _)| c == 0).await;
    assert_eq!(connected, 0, "the relay noticed its upstream went silent");
    // Cut off, the relay does not pass for current: the age of its state keeps growing.
    let lag_ms = || metric(&relay, "naadf_upstream_lag_ms");
    let aged = wait_for(lag_ms, |ms| ms >= 2000).await;
    assert!(aged >= 2000, "the relay's state aged while cut off: {aged} ms");

    freeze.send(false).unwrap();
    let back = wait_upstream(&relay, |(c, j)| c == 1 && j > joins).await;
    assert!(
        back.0 == 1 && back.1 > joins,
        "re-joined after the link came back: {back:?}, {joins} joins before"
    );
    let status = quiescent(&server.url).await;
    let w = session.until_quiescent(status.version, SETTLE).await.unwrap();
    assert_eq!((w.version(), w.digest()), (status.version, status.digest));
    assert_eq!(wait_for(lag_ms, |ms| ms == 0).await, 0, "current again");
    relay.stop();
    server.stop();
}

/// Feeds the hub one upstream stream until it has published a state.
async fn feed_until_published(hub: &mut Hub, client: &Client, version: u64) -> WorldStream {
    let (reply, rx) = oneshot::channel();
    hub.handle(Input::Rejoin(reply));
    let (request, generation) = rx.await.unwrap();
    let mut stream = client.stream(request).await.unwrap();
    while hub.published().is_none_or(|(v, _)| v < version) {
        let m = stream.message().await.unwrap().unwrap();
        hub.handle(Input::Message(generation, m));
    }
    stream
}

/// A delta whose digest does not match is not passed on: the hub drops the stream, asks
/// for a re-join, ends its subscribers' streams once the re-join arrives at a state they
/// were not sent, and then publishes the server's state.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_digest_mismatch_is_not_passed_on_and_leads_to_a_rejoin() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(dir.path(), &world, &[], &[]);
    let client = Client::connect(&server.url, Some("ed"), None).await.unwrap();
    let rejoin = Arc::new(Notify::new());
    let metrics = Arc::new(Metrics::for_relay());
    let mut hub = Hub::new(1 << 30, 64, rejoin.clone(), metrics.clone(), Default::default());
    let mut stream = feed_until_published(&mut hub, &client, 0).await;
    let (reply, rx) = oneshot::channel();
    hub.handle(Input::Request(Request::Join { resume: None, reply }));
    let mut events = rx.await.unwrap().events;

    let good = client
        .edit(r#"{"op":"sphere","center":[40,30,40],"radius":6,"material":2}"#, 1)
        .await
        .unwrap();
    let bad = client
        .edit(r#"{"op":"sphere","center":[80,30,80],"radius":6,"material":3}"#, 2)
        .await
        .unwrap();
    let mut forwarded = 0;
    let mut tampered = false;
    while !tampered {
        let mut m = stream.message().await.unwrap().unwrap();
        if let Some(world_message::Kind::Delta(d)) = &mut m.kind {
            let version = naadf_world::edit::Record::decode(&d.change).unwrap().version;
            if version == bad.version {
                d.digest ^= 1;
                tampered = true;
            }
        }
        hub.handle(Input::Message(1, m.clone()));
        // The presence tables the hub asked for are passed on otherwise.
        let delta = matches!(m.kind, Some(world_message::Kind::Delta(_)));
        if delta && !tampered {
            let e = events.try_recv().expect("an accepted delta is published");
            assert!(e.message == m, "published as received");
            forwarded += 1;
        }
    }
    assert!(forwarded >= 1 && hub.published().unwrap().0 == good.version);
    assert!(
        matches!(events.try_recv(), Err(broadcast::error::TryRecvError::Empty)),
        "nothing passed on"
    );
    assert_eq!(metrics.upstream.rejected.get(), 1);
    tokio::time::timeout(Duration::from_secs(1), rejoin.notified())
        .await
        .expect("the hub asks for a re-join");
    // Whatever else the dropped stream brings is ignored.
    let (reply, rx) = oneshot::channel();
    hub.handle(Input::Request(Request::Join { resume: None, reply }));
    let mut rx = rx;
    assert!(
        rx.try_recv().is_err(),
        "joins wait while the mirror is past the published state"
    );

    feed_until_published(&mut hub, &client, bad.version).await;
    let status = client.status().await.unwrap();
    assert_eq!(hub.published(), Some((status.version, status.digest.0)));
    let late = rx.await.expect("the waiting join is answered after the re-join");
    assert_eq!((late.view.version, late.view.digest), (status.version, status.digest));
    assert!(
        matches!(events.try_recv(), Err(broadcast::error::TryRecvError::Closed)),
        "the earlier subscription ends, so its client is re-sent what changed"
    );
    server.stop();
}

/// When the upstream cannot resume the relay (here: a server with another history came
/// up on its address), the relay takes the new world and its clients get it as a resync in their own
/// streams: only the pages that differ, and the new digest.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_upstream_that_cannot_resume_the_relay_resyncs_its_clients_in_stream() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let grpc = free_addr();
    let server = serve_world(dir.path(), &world, &["--grpc", &grpc], &[]);
    let relay = Server::relay(&format!("http://{grpc}"), &[], &dir.path().join("relay.log"));
    let c = Client::connect(&relay.url, Some("ed"), None).await.unwrap();
    let mut session = c.join(None).await.unwrap();
    let seen = c
        .edit(r#"{"op":"sphere","center":[20,40,20],"radius":8,"material":2}"#, 1)
        .await
        .unwrap();
    session.until_quiescent(seen.version, SETTLE).await.unwrap();
    let pages_first = session.mirror().stats.pages;
    server.kill9();

    // Another data directory: the same start world with another edit at the same version,
    // which the upstream's history cannot lead the relay to.
    let other = dir.path().join("other");
    std::fs::create_dir(&other).unwrap();
    let server = serve_world(&other, &world, &["--grpc", &grpc], &[]);
    let direct = Client::connect(&server.url, Some("ed"), None).await.unwrap();
    direct
        .edit(r#"{"op":"sphere","center":[64,40,64],"radius":10,"material":4}"#, 1)
        .await
        .unwrap();
    let status = quiescent(&server.url).await;
    // The session was quiescent at this version already: follow until the new world.
    let arrived = |m: &Mirror| m.is_quiescent() && m.world().is_some_and(|w| w.digest() == status.digest);
    tokio::time::timeout(SETTLE, async {
        while !arrived(session.mirror()) {
            session.next().await.unwrap().expect("the stream goes on");
        }
    })
    .await
    .expect("the client reaches the new server's world");
    assert_eq!(session.mirror().world().unwrap().version(), status.version);
    let stats = session.mirror().stats;
    assert_eq!(stats.snapshots, 2, "one join, then one in-stream resync: {stats:?}");
    let resent = stats.pages - pages_first;
    assert!(
        resent > 0 && resent < pages_first,
        "only changed pages travel again: {resent} of {pages_first}"
    );
    relay.stop();
    server.stop();
}

/// A relay whose upstream refuses it the same way again and again (here an unknown token)
/// counts the refusals, stops asking every few seconds, and says why on `/health`, which
/// stays 200: a restart would not help.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_relay_refused_by_its_upstream_backs_off_and_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(dir.path(), &world, &[], &[("NAADF_TOKENS", "vt=vera:viewer")]);
    let relay = Server::relay(&server.url, &["--token", "revoked"], &dir.path().join("relay.log"));
    let mut health = (0, String::new());
    for _ in 0..300 {
        health = http_get(&relay.http, "/health");
        if health.1.contains("refused") {
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert_eq!(health.0, 200, "{health:?}");
    let v: serde_json::Value = serde_json::from_str(&health.1).unwrap();
    assert_eq!(v["upstream"], "refused", "{v}");
    let reason = v["reason"].as_str().unwrap_or_default();
    assert!(
        reason.contains("Unauthenticated") && reason.contains("unknown token"),
        "{v}"
    );
    let refusals = metric(&relay, "naadf_upstream_refusals_total");
    assert!(refusals >= 5, "{refusals} refusals");
    // It now waits at least 10 s before asking again (it asked every few seconds before).
    tokio::time::sleep(Duration::from_secs(8)).await;
    assert_eq!(metric(&relay, "naadf_upstream_refusals_total"), refusals);
    assert_eq!(http_get(&relay.http, "/health").0, 200);
}

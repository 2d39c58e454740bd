//! Presence end to end: what clients publish reaches every client that joined with
//! `presence`, stamped with the authenticated user, through a relay too; a flood is
//! coalesced; entries leave 5 s after their last update; and nothing of it is durable.

mod support;

use naadf_client::Mirror;
use naadf_proto::v1::world_service_client::WorldServiceClient;
use naadf_proto::v1::{PresenceEntry, PresenceRequest, StatusRequest, WorldMessage, world_message};
use std::time::{Duration, Instant};
use support::{Server, serve_world, start_world};
use tonic::service::Interceptor;
use tonic::service::interceptor::InterceptedService;
use tonic::transport::Channel;

const TOKENS: &str = "at=alice:editor,bt=bob:viewer,ct=carol:viewer,rt=relay:viewer";

/// A raw client sending `token`.
async fn raw(url: &str, token: &str) -> WorldServiceClient<InterceptedService<Channel, impl Interceptor + use<>>> {
    let channel = tonic::transport::Endpoint::from_shared(url.to_owned())
        .unwrap()
        .connect()
        .await
        .unwrap();
    let bearer: tonic::metadata::MetadataValue<_> = format!("Bearer {token}").parse().unwrap();
    WorldServiceClient::with_interceptor(channel, move |mut r: tonic::Request<()>| {
        r.metadata_mut().insert("authorization", bearer.clone());
        Ok(r)
    })
}

/// A publish of `name` for `session`, at `x`.
fn update(session: u64, name: &str, x: f64) -> PresenceRequest {
    PresenceRequest {
        session,
        name: name.into(),
        position: vec![x, 40.0, 10.0],
        forward: vec![0.0, 0.0, 1.0],
        pointer: vec![12, 30, 7],
        tool: "sphere".into(),
    }
}

/// A joined stream with presence, and the presence tables it received with when.
struct Watcher {
    stream: tonic::Streaming<WorldMessage>,
    tables: Vec<(Instant, Vec<PresenceEntry>)>,
}

impl Watcher {
    async fn join(url: &str, token: &str) -> Watcher {
        let mut request = Mirror::new(None).join_request();
        request.presence = true;
        let stream = raw(url, token).await.join(request).await.unwrap().into_inner();
        Watcher {
            stream,
            tables: Vec::new(),
        }
    }

    /// Reads until a table satisfies `wanted` (within 10 s); returns it.
    async fn until(&mut self, wanted: impl Fn(&[PresenceEntry]) -> bool) -> Vec<PresenceEntry> {
        let read = async {
            loop {
                let m = self.stream.message().await.unwrap().expect("the stream goes on");
                if let Some(world_message::Kind::Presence(p)) = m.kind {
                    self.tables.push((Instant::now(), p.entries.clone()));
                    if wanted(&p.entries) {
                        return p.entries;
                    }
                }
            }
        };
        tokio::time::timeout(Duration::from_secs(10), read)
            .await
            .expect("the wanted presence table came")
    }
}

fn names(entries: &[PresenceEntry]) -> Vec<(&str, &str)> {
    entries.iter().map(|e| (e.user.as_str(), e.name.as_str())).collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn presence_reaches_every_watcher_coalesced_stamped_and_never_durable() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(dir.path(), &world, &[], &[("NAADF_TOKENS", TOKENS)]);
    let relay = Server::relay(&server.url, &["--token", "rt"], &dir.path().join("relay.log"));
    let state = async |url: &str| {
        let s = raw(url, "ct")
            .await
            .status(StatusRequest {})
            .await
            .unwrap()
            .into_inner();
        (s.version, s.digest)
    };
    let before = state(&server.url).await;
    let mut carol = Watcher::join(&server.url, "ct").await;
    let mut via_relay = Watcher::join(&relay.url, "ct").await;

    // Alice publishes to the server, Bob (a viewer) through the relay; a name claims
    // nothing: the user is the token's.
    let mut alice = raw(&server.url, "at").await;
    alice.publish(update(1, "Alice", 5.0)).await.unwrap();
    let mut bob = raw(&relay.url, "bt").await;
    bob.publish(update(2, "alice", 9.0)).await.unwrap();
    let both = |e: &[PresenceEntry]| e.len() == 2;
    let seen = carol.until(both).await;
    assert_eq!(names(&seen), [("alice", "Alice"), ("bob", "alice")]);
    assert_eq!(seen[0].position, [5.0, 40.0, 10.0]);
    assert_eq!(
        (seen[0].pointer.as_slice(), seen[0].tool.as_str()),
        (&[12, 30, 7][..], "sphere")
    );
    assert_eq!(names(&via_relay.until(both).await), names(&seen));

    // A flood is coalesced: a thousand updates reach the watchers as a few tables, the
    // last of them holding the last update.
    let started = Instant::now();
    for k in 0..1000 {
        alice.publish(update(1, "Alice", f64::from(k))).await.unwrap();
    }
    let flood = started.elapsed();
    let last = carol
        .until(|e| e.iter().any(|x| x.position.first() == Some(&999.0)))
        .await;
    assert_eq!(last.len(), 2);
    let during = carol.tables.iter().filter(|(t, _)| *t >= started).count();
    let most = (flood.as_secs_f64() / 0.1).ceil() as usize + 2;
    eprintln!("1000 updates in {flood:?} reached the watcher as {during} tables");
    assert!(
        during <= most,
        "{during} tables for a flood of {flood:?}: not coalesced"
    );

    // Refusals: bad coordinates, no token.
    let mut bad = update(1, "Alice", 0.0);
    bad.position = vec![f64::INFINITY, 0.0, 0.0];
    assert_eq!(
        alice.publish(bad).await.unwrap_err().code(),
        tonic::Code::InvalidArgument
    );
    let mut anonymous = WorldServiceClient::connect(server.url.clone()).await.unwrap();
    let refused = anonymous.publish(update(3, "mallory", 0.0)).await.unwrap_err();
    assert_eq!(refused.code(), tonic::Code::Unauthenticated);

    // Entries leave 5 s after their last update: Bob's first, then Alice's.
    let gone = carol.until(|e| e.is_empty()).await;
    assert!(gone.is_empty());
    let lasted = started.elapsed();
    assert!(
        lasted >= Duration::from_secs(5) && lasted < Duration::from_secs(8),
        "the table emptied {lasted:?} after the flood began"
    );
    via_relay.until(|e| e.is_empty()).await;

    // Nothing of it is durable: the world is where it was.
    assert_eq!(state(&server.url).await, before);
    relay.stop();
    server.stop();
}

//! The typed client (`naadf_client::Client`) against a real `naadf serve` process: the page
//! cache round trip, and the errors a caller must tell apart.

mod support;

use naadf_client::error::Code;
use naadf_client::{Client, Error, PageCache};
use std::time::Duration;
use support::{random_op, serve_world, start_world};

/// Long enough for a join and the distance fields to settle on a slow machine.
const SETTLE: Duration = Duration::from_secs(120);

/// A mirror saved to the page cache and loaded again rejoins with only the deltas it
/// missed, and ends equal to the server; a cache that cannot be read is ignored.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_page_cache_round_trips_and_makes_a_rejoin_cheap() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(dir.path(), &world, &[], &[]);
    let c = Client::connect(&server.url, Some("ed"), None).await.unwrap();
    let cache_dir = dir.path().join("cache");
    let cache = PageCache::for_server(Some(&cache_dir), &server.url).unwrap();
    let other = PageCache::for_server(Some(&cache_dir), "http://127.0.0.1:1").unwrap();
    assert_ne!(cache.path(), other.path(), "each server has its own file");
    assert!(cache.load().is_none(), "no cache yet");

    let mut first = c.join(cache.load()).await.unwrap();
    let saved = first.until_quiescent(0, SETTLE).await.unwrap().digest();
    cache.save(first.mirror().world().unwrap()).unwrap();
    assert!(first.mirror().stats.pages > 0, "a join without a cache gets pages");
    drop(first);

    let mut rng = 3;
    let mut last = 0;
    for seq in 1..=5 {
        last = c.edit(random_op(&mut rng), seq).await.unwrap().version;
    }
    let loaded = cache.load().expect("the cache reads back");
    assert_eq!(loaded.digest(), saved);
    let mut again = c.join(Some(loaded)).await.unwrap();
    let (version, digest) = {
        let w = again.until_quiescent(last, SETTLE).await.unwrap();
        (w.version(), w.digest())
    };
    let s = c.status().await.unwrap();
    assert_eq!((version, digest), (s.version, s.digest));
    let stats = again.mirror().stats;
    assert_eq!(stats.pages, 0, "resumed from the deltas after the cached version");
    assert!(stats.deltas >= 5, "the five edits came as deltas: {stats:?}");

    std::fs::write(cache.path(), b"not a world").unwrap();
    assert!(cache.load().is_none(), "a broken cache is ignored");
    server.stop();
}

/// A client refuses a world larger than its limit as soon as the snapshot's header
/// announces it, with an error that says so; the same client with the default limit joins.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_world_over_the_client_limit_is_refused_at_the_header() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(dir.path(), &world, &[], &[]);
    let c = Client::connect(&server.url, Some("ed"), None).await.unwrap();
    let mut small = c.clone().with_max_world_bytes(4096).join(None).await.unwrap();
    let e = small.until_quiescent(0, SETTLE).await.unwrap_err();
    assert!(e.to_string().contains("more than the 4096 this client accepts"), "{e}");
    assert_eq!(small.mirror().stats.pages, 0, "refused before any page");
    let mut fits = c.join(None).await.unwrap();
    let s = c.status().await.unwrap();
    assert_eq!(fits.until_quiescent(0, SETTLE).await.unwrap().digest(), s.digest);
    server.stop();
}

/// Refusals, rate limits, timeouts and lost connections are different errors; after a
/// restart on the same address, the same client and session carry on.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn errors_tell_refusals_rate_limits_timeouts_and_lost_connections_apart() {
    let dir = tempfile::tempdir().unwrap();
    let world = start_world(dir.path());
    let server = serve_world(dir.path(), &world, &["--rate", "2"], &[]);
    let c = Client::connect(&server.url, None, None).await.unwrap();

    let e = c.edit(r#"{"op":"set","voxels":[[1,999,1,1]]}"#, 0).await.unwrap_err();
    assert!(
        matches!(&e, Error::Refused { code: Code::InvalidArgument, message } if message.contains("outside")),
        "{e:?}"
    );
    let mut limited = None;
    for x in 0..10 {
        if let Err(e) = c.edit(format!(r#"{{"op":"set","voxels":[[{x},1,1,1]]}}"#), 0).await {
            limited = Some(e);
            break;
        }
    }
    let limited = limited.expect("a burst over the rate is refused");
    assert!(matches!(limited, Error::RateLimited(_)), "{limited:?}");
    assert_eq!(limited.code(), Some(Code::ResourceExhausted));
    assert!(
        limited.to_string().starts_with("server refused: ResourceExhausted: "),
        "{limited}"
    );

    let mut session = c.join(None).await.unwrap();
    let at = session.until_quiescent(0, SETTLE).await.unwrap().version();
    let e = session
        .until_quiescent(at + 1, Duration::from_millis(300))
        .await
        .unwrap_err();
    assert!(matches!(e, Error::Timeout(_)), "{e:?}");

    // The server dies under a live stream and a connected client.
    let grpc = server.url.trim_start_matches("http://").to_owned();
    server.kill9();
    let e = session.until_quiescent(at + 1, SETTLE).await.unwrap_err();
    assert!(matches!(e, Error::ConnectionLost(_)), "the stream: {e:?}");
    let e = c.status().await.unwrap_err();
    assert!(matches!(e, Error::ConnectionLost(_)), "a call: {e:?}");
    assert!(e.to_string().starts_with("connection lost: "), "{e}");

    // Back on the same address: the client reconnects by itself, the session rejoins
    // with the world it holds.
    let server = serve_world(dir.path(), &world, &["--grpc", &grpc], &[]);
    let restarted = c.status().await.expect("the client reconnects").version;
    session.rejoin().await.unwrap();
    let (version, digest) = {
        let w = session.until_quiescent(restarted, SETTLE).await.unwrap();
        (w.version(), w.digest())
    };
    let s = c.status().await.unwrap();
    assert_eq!((version, digest), (s.version, s.digest));
    server.stop();
}

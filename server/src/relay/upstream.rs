//! The relay's link to its upstream (a server or another relay): one lazily connected
//! channel, the relay's own calls on it (its join, the lag poll), callers' calls forwarded
//! with their own metadata, and the loop that follows the upstream stream and re-joins
//! with backoff whenever it breaks.

use super::hub::Input;
use crate::metrics::Metrics;
use crate::stream::messages::Request;
use naadf_proto::backoff::{Backoff, Retries};
use naadf_proto::v1::StatusRequest;
use naadf_proto::v1::world_service_client::WorldServiceClient;
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::sync::{Notify, mpsc, oneshot, watch};
use tonic::codec::CompressionEncoding;
use tonic::metadata::{AsciiMetadataValue, MetadataMap};
use tonic::transport::Channel;

/// The waits before re-joining a broken upstream: 100 ms, doubling up to 5 s, jittered so
/// that relays cut off together do not all return at the same instant.
const REJOIN_BACKOFF: Backoff = Backoff::new(Duration::from_millis(100), Duration::from_secs(5)).jittered();
/// The waits once the upstream refuses the relay the same way again and again (a revoked
/// token, a protocol mismatch): 10 s, doubling up to 5 min. A restart would not help.
const REFUSED_BACKOFF: Backoff = Backoff::new(Duration::from_secs(10), Duration::from_secs(300)).jittered();
/// How often the relay asks the upstream for its version (the lag metrics).
const LAG_POLL: Duration = Duration::from_secs(1);

/// Metadata keys that belong to one hop's transport, not to the caller: the relay decodes
/// a request and encodes it anew, so they are not forwarded.
const HOP_KEYS: [&str; 3] = ["grpc-encoding", "grpc-accept-encoding", "content-length"];

/// The upstream: where it is and how the relay calls it.
#[derive(Clone, Debug)]
pub struct Upstream {
    /// Its URL.
    pub url: String,
    client: WorldServiceClient<Channel>,
    /// The relay's own `authorization` value, if it has a token.
    token: Option<AsciiMetadataValue>,
}

impl Upstream {
    /// The upstream at `url` (trusting `ca`, PEM bytes, for TLS), called with the relay's
    /// `token`; a connection silent for `timeout` is given up. Nothing connects yet: the
    /// channel connects on first use and again after it breaks.
    pub fn new(url: &str, ca: Option<Vec<u8>>, token: Option<&str>, timeout: Duration) -> Result<Self, String> {
        let endpoint = naadf_proto::endpoint::endpoint(url, ca).map_err(|e| e.to_string())?;
        let channel = naadf_proto::endpoint::with_silence_limit(endpoint, timeout).connect_lazy();
        let token = token
            .map(|t| format!("Bearer {t}").parse::<AsciiMetadataValue>())
            .transpose()
            .map_err(|_| "the upstream token must be visible ASCII".to_owned())?;
        Ok(Self {
            url: url.to_owned(),
            client: WorldServiceClient::new(channel)
                .max_decoding_message_size(usize::MAX)
                .accept_compressed(CompressionEncoding::Zstd),
            token,
        })
    }

    /// A client for calls on the upstream.
    pub fn client(&self) -> WorldServiceClient<Channel> {
        self.client.clone()
    }

    /// `message` as the relay's own request (with its token).
    pub fn own<T>(&self, message: T) -> tonic::Request<T> {
        let mut r = tonic::Request::new(message);
        if let Some(t) = &self.token {
            r.metadata_mut().insert("authorization", t.clone());
        }
        r
    }

    /// A caller's request, to send upstream with the caller's metadata (its token, its
    /// deadline) and without this hop's transport keys.
    pub fn forwarded<T>(r: tonic::Request<T>) -> tonic::Request<T> {
        let (mut metadata, _, message) = r.into_parts();
        for key in HOP_KEYS {
            metadata.remove(key);
        }
        tonic::Request::from_parts(metadata, Default::default(), message)
    }

    /// `message` with only the `authorization` of `caller`: for checking a caller's token,
    /// and for requests made over HTTP, whose other headers are no gRPC metadata.
    pub fn as_caller<T>(caller: &MetadataMap, message: T) -> tonic::Request<T> {
        let mut r = tonic::Request::new(message);
        if let Some(v) = caller.get("authorization") {
            r.metadata_mut().insert("authorization", v.clone());
        }
        r
    }
}

/// A failed upstream call as the relay's caller sees it: a status the upstream sent,
/// unchanged; a failure tonic made here from the transport (the upstream is down, or the
/// connection broke), UNAVAILABLE, which callers retry (with the same `client_seq`, so an
/// edit the upstream applied before the break is not applied twice).
pub fn upstream_error(s: tonic::Status) -> tonic::Status {
    match std::error::Error::source(&s) {
        Some(cause) => tonic::Status::unavailable(format!(
            "the relay's upstream is out of reach: {}: {cause}",
            s.message()
        )),
        None => s,
    }
}

/// The upstream's refusal in `s`, as `CODE: message`: a status the upstream sent that
/// asking again will not change; `None` for a transport failure or a passing condition.
fn refusal(s: &tonic::Status) -> Option<String> {
    use tonic::Code;
    let lasting = matches!(
        s.code(),
        Code::Unauthenticated
            | Code::PermissionDenied
            | Code::FailedPrecondition
            | Code::InvalidArgument
            | Code::Unimplemented
    );
    (lasting && std::error::Error::source(s).is_none()).then(|| format!("{:?}: {}", s.code(), s.message()))
}

/// Follows the upstream stream until `shutdown`: asks the hub for a join request, joins,
/// and hands every message to the hub; when the stream breaks, ends, or the hub refuses
/// it (`rejoin`), joins again after a pause of `REJOIN_BACKOFF`, which starts over once
/// a message arrives. When the upstream refuses the same way `SAME_REFUSALS` times in a
/// row, the pauses are `REFUSED_BACKOFF`'s, and the metrics (and so `/health`) carry the
/// refusal until a join succeeds.
pub async fn follow(
    upstream: Upstream,
    hub: mpsc::Sender<Input>,
    rejoin: Arc<Notify>,
    metrics: Arc<Metrics>,
    mut shutdown: watch::Receiver<bool>,
) {
    let mut retries = Retries::new(REJOIN_BACKOFF, REFUSED_BACKOFF);
    let mut failures = 0u32;
    loop {
        let (reply, rx) = oneshot::channel();
        if hub.send(Input::Rejoin(reply)).await.is_err() {
            return;
        }
        let Ok((request, generation)) = rx.await else { return };
        let (why, refused) = match upstream.client().join(upstream.own(request)).await {
            Ok(stream) => {
                tracing::info!(upstream = %upstream.url, "joined upstream");
                metrics.upstream.joins.inc();
                metrics.upstream.set_refused(None);
                let mut stream = stream.into_inner();
                loop {
                    tokio::select! {
                        m = stream.message() => match m {
                            Ok(Some(m)) => {
                                retries.reset();
                                failures = 0;
                                if hub.send(Input::Message(generation, m)).await.is_err() {
                                    return;
                                }
                            }
                            Ok(None) => break ("the upstream ended the stream".to_owned(), None),
                            Err(s) => break (format!("the upstream stream broke: {}", s.message()), refusal(&s)),
                        },
                        _ = rejoin.notified() => break ("the stream was refused".to_owned(), None),
                        _ = shutdown.changed() => return,
                    }
                }
            }
            Err(s) => (
                format!("cannot join upstream: {} ({:?})", s.message(), s.code()),
                refusal(&s),
            ),
        };
        metrics.upstream.connected.set(0);
        if refused.is_some() {
            metrics.upstream.refusals.inc();
        }
        failures += 1;
        let pause = retries.after(refused.as_deref());
        metrics.upstream.set_refused(retries.refused());
        // The first failures are expected (a restart, a short cut) and logged as
        // warnings; a link that stays down is an error every attempt, and one the upstream
        // keeps refusing is retried (and logged) rarely.
        if failures <= 3 {
            tracing::warn!(upstream = %upstream.url, retry_in = ?pause, "{why}; re-joining");
        } else {
            tracing::error!(upstream = %upstream.url, retry_in = ?pause, failures, "{why}; re-joining");
        }
        tokio::select! {
            _ = tokio::time::sleep(pause) => {}
            _ = shutdown.changed() => return,
        }
    }
}

/// Keeps the lag metrics current until `shutdown`: every `LAG_POLL` the upstream's
/// version against the hub's. The lag in ms is the age of the relay's state: the time
/// since the last poll whose upstream version the relay holds now (0 while it holds the
/// upstream's current version). It grows while the upstream cannot be asked, whose lag in
/// versions then keeps its last value: a relay cut off from its upstream shows as ever
/// further behind rather than as current.
pub async fn poll_lag(
    upstream: Upstream,
    hub: mpsc::Sender<Request>,
    metrics: Arc<Metrics>,
    mut shutdown: watch::Receiver<bool>,
) {
    // When the relay was last known to hold the upstream's version of the time, and the
    // polls it has not caught up with yet, oldest first: (when, the upstream's version
    // then).
    let mut current_at = Instant::now();
    let mut polls: std::collections::VecDeque<(Instant, u64)> = std::collections::VecDeque::new();
    loop {
        tokio::select! {
            _ = tokio::time::sleep(LAG_POLL) => {}
            _ = shutdown.changed() => return,
        }
        let asked = Instant::now();
        // A call that hangs on a dead link counts as no answer.
        let mut client = upstream.client();
        let call = client.status(upstream.own(StatusRequest {}));
        let mut caught_up = false;
        if let Ok(Ok(up)) = tokio::time::timeout(LAG_POLL, call).await {
            let theirs = up.into_inner().version;
            let mine = crate::stream::messages::status(&hub).await.map_or(0, |s| s.version);
            polls.push_back((asked, theirs));
            while let Some(&(when, _)) = polls.front().filter(|&&(_, v)| v <= mine) {
                current_at = when;
                polls.pop_front();
            }
            // Far behind, keep only the newest polls (dropping older ones can only make
            // the age read longer, never shorter).
            while polls.len() > 64 {
                polls.pop_front();
            }
            metrics.upstream.lag_versions.set(theirs.saturating_sub(mine) as i64);
            caught_up = polls.is_empty();
        }
        let age = if caught_up {
            Duration::ZERO
        } else {
            current_at.elapsed()
        };
        metrics.upstream.lag_ms.set(age.as_millis() as i64);
    }
}

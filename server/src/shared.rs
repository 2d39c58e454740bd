//! [`Shared`]: what the gRPC service, the join tasks and the HTTP side of a server (or a
//! relay) share — metrics, the page cache, tokens and roles, the edit rate limiter, the
//! render router, the presence table — and the [`SlowClientLimits`] the join tasks
//! enforce.

use crate::data::pages;
use crate::metrics;
use crate::net::auth;
use crate::render_router;
use crate::stream::presence::Presence;
use governor::{DefaultKeyedRateLimiter, Quota};
use std::num::NonZeroU32;
use std::sync::Arc;
use tokio::sync::watch;

/// What the service, the join tasks and the HTTP side share.
pub struct Shared {
    /// The Prometheus metrics the HTTP side exports.
    pub metrics: Arc<metrics::Metrics>,
    /// Clients and recent edits for the status page.
    pub activity: Arc<metrics::Activity>,
    /// Compressed snapshot pages.
    pub page_cache: pages::PageCache,
    /// Tokens and roles.
    pub auth: auth::Auth,
    /// Per-user edit rate limiter.
    pub limiter: DefaultKeyedRateLimiter<String>,
    /// The configured rate (edits per second per user).
    pub rate: u32,
    /// Becomes true when the server shuts down (join streams end).
    pub shutdown: watch::Receiver<bool>,
    /// Registered render nodes and the frame requests routed to them.
    pub router: render_router::Router,
    /// How many bytes clients may fall behind before their streams are cut.
    pub slow_clients: SlowClientLimits,
    /// Who is here: the presence table the join tasks pass on.
    pub presence: Arc<Presence>,
}

impl Shared {
    /// Shared state with a per-user limit of `rate` edits per second (bursts of `rate`).
    pub fn new(auth: auth::Auth, rate: u32, shutdown: watch::Receiver<bool>) -> Self {
        Self::with_metrics(auth, rate, shutdown, Arc::default())
    }

    /// Shared state as [`Shared::new`] makes it, exporting `metrics`.
    pub fn with_metrics(
        auth: auth::Auth,
        rate: u32,
        shutdown: watch::Receiver<bool>,
        metrics: Arc<metrics::Metrics>,
    ) -> Self {
        let rate = rate.max(1);
        Self {
            router: render_router::Router::new(render_router::DEFAULT_QUEUE, metrics.clone()),
            metrics,
            activity: Arc::default(),
            page_cache: pages::PageCache::default(),
            auth,
            limiter: DefaultKeyedRateLimiter::keyed(Quota::per_second(NonZeroU32::new(rate).expect("rate ≥ 1"))),
            rate,
            shutdown,
            slow_clients: SlowClientLimits::default(),
            presence: Arc::default(),
        }
    }
}

/// How far behind clients may fall, in bytes, before their streams are cut (see [`crate::stream::join`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SlowClientLimits {
    /// Most bytes one client may have pending: published deltas it has not taken yet
    /// plus messages queued in its stream that its transport has not taken yet.
    pub client_bytes: u64,
    /// Most bytes the subscribed clients may have pending together; over it, every one
    /// that is not reading (more than a sixteenth of `client_bytes` queued in its stream
    /// that its transport has not taken) is cut too. A client cut holds nothing.
    pub total_bytes: u64,
}

impl Default for SlowClientLimits {
    /// 64 MiB per client, 512 MiB in all.
    fn default() -> Self {
        Self {
            client_bytes: 64 << 20,
            total_bytes: 512 << 20,
        }
    }
}

impl SlowClientLimits {
    /// Whether a client with `mine` bytes pending, `queued` of them in its stream, while
    /// all clients have `total`, is cut. A client that keeps reading has its stream's
    /// queue taken as soon as it is filled, so only its newest deltas are pending.
    pub(crate) fn exceeded(&self, mine: u64, queued: u64, total: u64) -> bool {
        mine > self.client_bytes || (total > self.total_bytes && queued > self.client_bytes / 16)
    }
}

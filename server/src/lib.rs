//! # naadf-server
//!
//! The authoritative server (`naadf serve`): one world actor applies every edit in one total
//! order; a committer makes batches durable (write-ahead log with group commit) before it
//! publishes their deltas and acknowledges them; each joined client gets a cache-aware
//! snapshot and then every delta over gRPC. axum serves health, metrics and a status page.
//!
//! Where to start reading: [`serve`] wires everything; [`actor`] is the world's owner;
//! [`committer`] the durability point; [`join`] one client's stream; [`messages`] what these
//! three hand each other.
//!
//! ```text
//! gRPC Edit ──▶ service (auth, roles, rate) ──▶ actor (apply, undo, growth) ──▶ committer
//!                                                                        │ WAL append + fsync
//!                                       join tasks ◀── broadcast deltas ◀┘ then ack the sender
//! ```

#![warn(missing_docs)]

pub mod actor;
pub mod auth;
pub mod committer;
pub mod conn;
pub mod frontend;
pub mod fsck;
pub mod growth;
pub mod http;
pub mod join;
pub mod layout;
pub mod messages;
pub mod metrics;
pub mod pages;
pub mod publisher;
pub mod relay;
pub mod render_router;
pub(crate) mod serve;
pub mod service;
pub mod store;
pub mod tls;
pub mod wal;

pub use serve::{Bound, DEFAULT_DATA, DEFAULT_GRPC, DEFAULT_HTTP, ServerConfig, serve};

use actor::{Request, StatusInfo};
use governor::{DefaultKeyedRateLimiter, Quota};
use std::num::NonZeroU32;
use std::sync::Arc;
use tokio::sync::{mpsc, oneshot, watch};

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
    /// How many bytes clients may fall behind before they are re-sent a snapshot.
    pub slow_clients: join::SlowClientLimits,
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
            slow_clients: join::SlowClientLimits::default(),
        }
    }
}

/// Asks the actor for its state (`None` when it is gone).
pub async fn status(actor: &mpsc::Sender<Request>) -> Option<StatusInfo> {
    let (reply, rx) = oneshot::channel();
    actor.send(Request::Status { reply }).await.ok()?;
    rx.await.ok()
}

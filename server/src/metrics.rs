//! Prometheus metrics (`/metrics`) and the activity the status page shows.

use prometheus_client::encoding::EncodeLabelSet;
use prometheus_client::encoding::text::encode;
use prometheus_client::metrics::counter::Counter;
use prometheus_client::metrics::family::Family;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::metrics::histogram::{Histogram, exponential_buckets};
use prometheus_client::registry::Registry;
use std::collections::{BTreeMap, HashMap, VecDeque};
use std::sync::Mutex;
use std::sync::atomic::AtomicU64;
use std::time::SystemTime;

/// Recent edits the status page lists.
const RECENT_EDITS: usize = 32;

/// The label of the frame metrics: a render node's id, or `all` for the totals.
#[derive(Clone, Debug, Hash, PartialEq, Eq, EncodeLabelSet)]
pub struct NodeLabel {
    /// Node id (as registered), or `all`.
    pub node: String,
}

/// Histograms of frame latency (1 ms to about 33 s).
type LatencyFamily = Family<NodeLabel, Histogram, fn() -> Histogram>;

fn latency_histogram() -> Histogram {
    Histogram::new(exponential_buckets(0.001, 2.0, 16))
}

/// The server's metrics.
#[derive(Debug)]
pub struct Metrics {
    registry: Registry,
    /// Clients joined now.
    pub clients: Gauge,
    /// The current edit version.
    pub version: Gauge,
    /// Applied edit batches (rate() gives edits per second).
    pub edits: Counter,
    /// Refused edit requests.
    pub refused: Counter,
    /// Bytes of stream messages sent to clients.
    pub bytes_sent: Counter,
    /// Snapshots re-sent to clients that fell behind.
    pub resyncs: Counter,
    /// Background growth steps published.
    pub growth_steps: Counter,
    /// WAL fsync latency, seconds.
    pub fsync: Histogram,
    /// Snapshots written.
    pub snapshots: Counter,
    /// TLS certificate reloads that took effect ([`crate::net::tls`]).
    pub tls_reloads: Counter,
    /// TLS certificate reloads that failed (the previous certificate stayed in use).
    pub tls_reload_failures: Counter,
    /// Frames served, per render node and in total (rate() gives frames per second).
    pub frames: Family<NodeLabel, Counter>,
    /// Frame latency as the requester sees it (routing, waiting and rendering), seconds.
    pub frame_seconds: LatencyFamily,
    /// Frame jobs in flight (the render queue's depth), per node and in total.
    pub frames_in_flight: Family<NodeLabel, Gauge>,
    /// The joined clients' backlogs (what the stream gauges below report).
    pub backlogs: Backlogs,
    /// Relays only: what following the upstream costs ([`Metrics::for_relay`]).
    pub upstream: UpstreamMetrics,
    /// The sum of the clients' backlogs, bytes (set when rendered).
    backlog_bytes: Gauge,
    /// The largest client backlog, bytes (set when rendered).
    backlog_max_client_bytes: Gauge,
}

/// Each joined client's backlog: bytes published or queued for it that it has not read
/// yet (see [`crate::stream::join`]), by a handle from [`Backlogs::register`].
#[derive(Debug, Default)]
pub struct Backlogs {
    inner: Mutex<BacklogTable>,
}

#[derive(Debug, Default)]
struct BacklogTable {
    /// Each client's backlog and whether it is subscribed.
    clients: HashMap<u64, (u64, bool)>,
    /// The sum over subscribed clients.
    subscribed: u64,
    next: u64,
}

impl Backlogs {
    /// A handle for a new client, with an empty backlog.
    pub fn register(&self) -> u64 {
        let mut t = self.inner.lock().expect("backlog lock");
        t.next += 1;
        let id = t.next;
        t.clients.insert(id, (0, false));
        id
    }

    /// Sets client `id`'s backlog and whether it is `subscribed` (a client that is not holds
    /// only what is queued in its stream, which cutting it cannot release); returns the sum
    /// over the subscribed clients.
    pub fn set(&self, id: u64, bytes: u64, subscribed: bool) -> u64 {
        let mut t = self.inner.lock().expect("backlog lock");
        if let Some((old, true)) = t.clients.insert(id, (bytes, subscribed)) {
            t.subscribed -= old;
        }
        if subscribed {
            t.subscribed += bytes;
        }
        t.subscribed
    }

    /// Forgets client `id`.
    pub fn remove(&self, id: u64) {
        let mut t = self.inner.lock().expect("backlog lock");
        if let Some((old, true)) = t.clients.remove(&id) {
            t.subscribed -= old;
        }
    }

    /// The sum of all backlogs and the largest one.
    fn totals(&self) -> (u64, u64) {
        let t = self.inner.lock().expect("backlog lock");
        let bytes = t.clients.values().map(|&(b, _)| b);
        (bytes.clone().sum(), bytes.max().unwrap_or(0))
    }
}

impl Metrics {
    /// Records a frame served by `node` in `seconds`.
    pub fn frame_served(&self, node: u64, seconds: f64) {
        for label in [node.to_string(), "all".to_owned()] {
            let l = NodeLabel { node: label };
            self.frames.get_or_create(&l).inc();
            self.frame_seconds.get_or_create(&l).observe(seconds);
        }
    }

    /// Sets the jobs in flight of `node` and in total.
    pub fn in_flight(&self, node: u64, jobs: usize, total: usize) {
        let set = |label: String, v: usize| {
            self.frames_in_flight
                .get_or_create(&NodeLabel { node: label })
                .set(v as i64);
        };
        set(node.to_string(), jobs);
        set("all".to_owned(), total);
    }
}

impl Default for Metrics {
    fn default() -> Self {
        let mut registry = Registry::with_prefix("naadf");
        let m = Metrics {
            clients: Gauge::default(),
            version: Gauge::default(),
            edits: Counter::default(),
            refused: Counter::default(),
            bytes_sent: Counter::default(),
            resyncs: Counter::default(),
            growth_steps: Counter::default(),
            fsync: Histogram::new(exponential_buckets(0.000_05, 2.0, 16)),
            snapshots: Counter::default(),
            tls_reloads: Counter::default(),
            tls_reload_failures: Counter::default(),
            frames: Family::default(),
            frame_seconds: LatencyFamily::new_with_constructor(latency_histogram),
            frames_in_flight: Family::default(),
            backlogs: Backlogs::default(),
            upstream: UpstreamMetrics::default(),
            backlog_bytes: Gauge::default(),
            backlog_max_client_bytes: Gauge::default(),
            registry: Registry::default(),
        };
        registry.register("clients", "Clients joined now", m.clients.clone());
        registry.register("version", "Current edit version", m.version.clone());
        registry.register("edits", "Applied edit batches", m.edits.clone());
        registry.register(
            "refused_requests",
            "Refused edit requests (auth, role, parse, limits, invalid ops)",
            m.refused.clone(),
        );
        registry.register(
            "bytes_sent",
            "Bytes of stream messages sent to clients",
            m.bytes_sent.clone(),
        );
        registry.register(
            "resyncs",
            "Snapshots re-sent to clients that fell behind",
            m.resyncs.clone(),
        );
        registry.register(
            "growth_steps",
            "Background distance-field growth steps published",
            m.growth_steps.clone(),
        );
        registry.register("wal_fsync_seconds", "Write-ahead log fsync latency", m.fsync.clone());
        registry.register("snapshots", "Snapshots written", m.snapshots.clone());
        registry.register(
            "tls_reloads",
            "TLS certificate reloads that took effect",
            m.tls_reloads.clone(),
        );
        registry.register(
            "tls_reload_failures",
            "TLS certificate reloads that failed (the previous certificate stays in use)",
            m.tls_reload_failures.clone(),
        );
        registry.register("frames", "Frames served by render nodes", m.frames.clone());
        registry.register(
            "frame_seconds",
            "Frame latency seen by requesters (routing, waiting, rendering)",
            m.frame_seconds.clone(),
        );
        registry.register(
            "frames_in_flight",
            "Frame jobs sent to render nodes and not answered yet",
            m.frames_in_flight.clone(),
        );
        registry.register(
            "backlog_bytes",
            "Bytes published or queued for clients that they have not read, summed over clients",
            m.backlog_bytes.clone(),
        );
        registry.register(
            "backlog_max_client_bytes",
            "The largest backlog of one client, bytes",
            m.backlog_max_client_bytes.clone(),
        );
        Metrics { registry, ..m }
    }
}

/// A relay's view of its upstream: how far behind it is and how often it had to re-join.
#[derive(Debug, Default)]
pub struct UpstreamMetrics {
    /// Whether the upstream stream is live now (1) or being re-joined (0).
    pub connected: Gauge,
    /// The upstream's version minus the relay's, as last polled.
    pub lag_versions: Gauge,
    /// The age of the relay's state, ms: the time since the last poll of the upstream
    /// whose version the relay holds (0 when it holds the upstream's current version;
    /// growing while the upstream cannot be asked).
    pub lag_ms: Gauge,
    /// Upstream streams joined (the first one included).
    pub joins: Counter,
    /// Upstream streams given up because a message did not apply or its digest did not
    /// match: nothing of them was passed on.
    pub rejected: Counter,
    /// Joins the upstream refused (an unknown token, a protocol mismatch, ...).
    pub refusals: Counter,
    /// The refusal the upstream answered every recent join with, once it came often enough
    /// in a row that the relay waits long between attempts; `/health` reports it.
    refused: std::sync::Mutex<Option<String>>,
}

impl UpstreamMetrics {
    /// Records the refusal the upstream keeps answering with (`None`: none, or a join
    /// succeeded).
    pub fn set_refused(&self, why: Option<&str>) {
        *self.refused.lock().unwrap_or_else(|e| e.into_inner()) = why.map(str::to_owned);
    }

    /// The refusal the upstream keeps answering with, if any.
    pub fn refused(&self) -> Option<String> {
        self.refused.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }
}

impl Metrics {
    /// The metrics of a relay: the server's, plus the `upstream_*` family.
    pub fn for_relay() -> Self {
        let mut m = Self::default();
        let u = &m.upstream;
        let r = &mut m.registry;
        r.register(
            "upstream_connected",
            "Whether the upstream stream is live",
            u.connected.clone(),
        );
        r.register(
            "upstream_lag_versions",
            "The upstream's version minus this relay's, as last polled",
            u.lag_versions.clone(),
        );
        r.register(
            "upstream_lag_ms",
            "Time since the last poll of the upstream whose version this relay holds, ms",
            u.lag_ms.clone(),
        );
        r.register("upstream_joins", "Upstream streams joined", u.joins.clone());
        r.register(
            "upstream_rejected",
            "Upstream streams dropped on a bad message or digest mismatch (nothing passed on)",
            u.rejected.clone(),
        );
        r.register(
            "upstream_refusals",
            "Joins the upstream refused (unknown token, protocol mismatch, ...)",
            u.refusals.clone(),
        );
        m
    }

    /// The Prometheus text exposition of every metric.
    pub fn render(&self) -> String {
        let (total, max) = self.backlogs.totals();
        self.backlog_bytes.set(total as i64);
        self.backlog_max_client_bytes.set(max as i64);
        let mut out = String::new();
        encode(&mut out, &self.registry).expect("writing to a String cannot fail");
        out
    }
}

/// One recent edit.
#[derive(Clone, Debug)]
pub struct RecentEdit {
    /// The version it produced.
    pub version: u64,
    /// Who sent it.
    pub user: String,
    /// When it was applied.
    pub at: SystemTime,
    /// The ops, shortened.
    pub summary: String,
}

/// One joined client.
#[derive(Clone, Debug)]
pub struct ClientInfo {
    /// The user.
    pub user: String,
    /// When it joined.
    pub since: SystemTime,
}

/// Activity for the status page.
#[derive(Debug, Default)]
pub struct Activity {
    recent: Mutex<VecDeque<RecentEdit>>,
    clients: Mutex<BTreeMap<u64, ClientInfo>>,
    next_client: AtomicU64,
}

impl Activity {
    /// Notes an applied edit.
    pub fn edit(&self, version: u64, user: &str, ops: &str) {
        let mut summary: String = ops.chars().take(120).collect();
        if summary.len() < ops.len() {
            summary.push('…');
        }
        let mut r = self.recent.lock().expect("activity lock");
        r.push_front(RecentEdit {
            version,
            user: user.to_owned(),
            at: SystemTime::now(),
            summary,
        });
        r.truncate(RECENT_EDITS);
    }

    /// Registers a joined client; returns its handle for [`Activity::left`].
    pub fn joined(&self, user: &str) -> u64 {
        let id = self.next_client.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.clients.lock().expect("activity lock").insert(
            id,
            ClientInfo {
                user: user.to_owned(),
                since: SystemTime::now(),
            },
        );
        id
    }

    /// Removes a client.
    pub fn left(&self, id: u64) {
        self.clients.lock().expect("activity lock").remove(&id);
    }

    /// The recent edits, newest first.
    pub fn recent(&self) -> Vec<RecentEdit> {
        self.recent.lock().expect("activity lock").iter().cloned().collect()
    }

    /// The joined clients.
    pub fn clients(&self) -> Vec<ClientInfo> {
        self.clients.lock().expect("activity lock").values().cloned().collect()
    }
}

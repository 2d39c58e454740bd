//! Wiring: data directory recovery, the actor and committer threads, the gRPC and HTTP
//! listeners, periodic checkpoints and graceful shutdown.

use crate::data::fsck::Verdict;
use crate::data::state::ServerState;
use crate::data::store::{DataDir, StoreError};
use crate::data::wal::{Entry, Wal};
use crate::net::addresses::Bound;
use crate::net::auth::Auth;
use crate::net::frontend::Frontend;
use crate::net::http;
use crate::net::http::Backend;
use crate::net::service::WorldServer;
use crate::shared::Shared;
use crate::stream::actor::Actor;
use crate::stream::committer::Committer;
use crate::stream::messages::Request;
use crate::stream::publisher::Publisher;
use anyhow::{Result, bail};
use naadf_proto::v1::world_service_server::WorldServiceServer;
use naadf_world::World;
use naadf_world::ops::Limits;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::{mpsc, oneshot, watch};

/// Everything `naadf serve` can configure.
#[derive(Clone, Debug)]
pub struct ServerConfig {
    /// Where it listens, and its clients' limits.
    pub frontend: Frontend,
    /// Data directory (snapshots and write-ahead log).
    pub data: PathBuf,
    /// Tokens and roles (empty: open, loopback only).
    pub auth: Auth,
    /// Per-request edit limits.
    pub limits: Limits,
    /// Edits per second per user.
    pub rate: u32,
    /// Write a snapshot after this many edits.
    pub checkpoint_every: u64,
    /// And at least this often while edits arrive.
    pub checkpoint_interval: Duration,
    /// Whether bearer tokens may travel in cleartext (a non-loopback bind without TLS, or
    /// HTTP on a non-loopback address) without a warning at startup
    /// ([`ServerConfig::cleartext_warning`]).
    pub insecure: bool,
}

/// The default data directory.
pub const DEFAULT_DATA: &str = "naadf-data";

impl Default for ServerConfig {
    /// The documented defaults (docs/PROTOCOL.md): gRPC on [`DEFAULT_GRPC`](crate::DEFAULT_GRPC), HTTP on
    /// [`DEFAULT_HTTP`](crate::DEFAULT_HTTP), data in [`DEFAULT_DATA`], open (no tokens).
    fn default() -> Self {
        Self {
            frontend: Frontend::default(),
            data: PathBuf::from(DEFAULT_DATA),
            auth: Auth::open(),
            limits: Limits::default(),
            rate: 1000,
            checkpoint_every: 10_000,
            checkpoint_interval: Duration::from_secs(300),
            insecure: false,
        }
    }
}

impl ServerConfig {
    /// Why bearer tokens would travel in cleartext on another machine's network: tokens are
    /// configured and gRPC listens on a non-loopback address without TLS, or HTTP (never
    /// TLS) does. `None` when they would not, or when [`ServerConfig::insecure`] accepts it.
    pub fn cleartext_warning(&self) -> Option<String> {
        if self.auth.is_open() || self.insecure {
            return None;
        }
        let exposed = self.frontend.cleartext_listeners();
        (!exposed.is_empty()).then(|| {
            format!(
                "bearer tokens travel in cleartext: {}; anyone on the network path can read them. \
                 Serve behind TLS (--tls-cert/--tls-key for gRPC, a TLS proxy for HTTP), bind \
                 loopback, or pass --insecure to accept this",
                exposed.join(" and ")
            )
        })
    }

    /// The defaults, with the data directory `data`.
    pub fn new(data: PathBuf) -> Self {
        Self {
            data,
            ..Self::default()
        }
    }
}

/// What recovery hands the server.
struct Recovered {
    /// The locked data directory.
    data: DataDir,
    /// The world at the snapshot (or the initial world).
    world: World,
    /// The server state at the snapshot.
    state: ServerState,
    /// The log, open for appending.
    wal: Wal,
    /// The logged batches after the snapshot, to replay.
    entries: Vec<Entry>,
}

/// Opens the data directory `dir` as [`fsck`](crate::data::fsck) judges it: the newest complete
/// snapshot and the log after it (temporaries removed, other orphans moved into the
/// quarantine, a torn tail cut off), or a new directory started from `initial()`. A
/// directory it refuses is left untouched.
fn recover(dir: &Path, initial: impl FnOnce() -> Result<World>) -> Result<Recovered> {
    let (data, inspection, loaded) = DataDir::open(dir)?;
    match inspection.verdict() {
        Verdict::Resume { snapshot, records } => {
            tracing::info!(version = snapshot, records, dir = %dir.display(), "resuming from snapshot");
            let (world, state) = loaded.expect("DataDir::open loads the snapshot it resumes from");
            for orphan in inspection.orphans() {
                tracing::warn!(file = %orphan.path.display(), "{orphan}");
                orphan.settle()?;
            }
            let (wal, entries) = Wal::resume(dir, inspection.into_log(snapshot)?, snapshot)?;
            Ok(Recovered {
                data,
                world,
                state,
                wal,
                entries,
            })
        }
        Verdict::New => {
            let world = initial()?;
            let state = ServerState {
                version: world.version(),
                ..ServerState::default()
            };
            data.save(&world.to_parts(), &state)?;
            let (wal, _) = Wal::resume(dir, Vec::new(), world.version())?;
            tracing::info!(version = world.version(), dir = %dir.display(), "started a new data directory");
            Ok(Recovered {
                data,
                world,
                state,
                wal,
                entries: Vec::new(),
            })
        }
        Verdict::Refuse(r) => Err(StoreError::Refused(Box::new(r)).into()),
    }
}

/// Runs the server until `shutdown` resolves, then stops accepting, ends the streams and
/// writes a final snapshot. `initial` supplies the world of a fresh data directory;
/// `ready` is told the bound addresses.
pub async fn serve(
    config: ServerConfig,
    initial: impl FnOnce() -> Result<World> + Send + 'static,
    ready: impl FnOnce(Bound),
    shutdown: impl std::future::Future<Output = ()>,
) -> Result<()> {
    if let Some(w) = config.cleartext_warning() {
        tracing::warn!("{w}");
    }
    if config.auth.is_open() {
        let f = &config.frontend;
        if !f.grpc.ip().is_loopback() || !f.http.ip().is_loopback() {
            bail!(
                "refusing to serve on a non-loopback address ({} / {}) without tokens: \
                 configure --auth FILE or NAADF_TOKENS",
                f.grpc,
                f.http
            );
        }
        tracing::warn!("no tokens configured: serving open (every caller is an admin) on loopback only");
    }
    let Recovered {
        data,
        world,
        state,
        wal,
        entries,
    } = {
        let dir = config.data.clone();
        tokio::task::spawn_blocking(move || recover(&dir, initial)).await??
    };
    let data = Arc::new(data);
    let (shutdown_tx, shutdown_rx) = watch::channel(false);
    let shared = Arc::new(Shared {
        slow_clients: config.frontend.slow_clients,
        ..Shared::new(config.auth.clone(), config.rate, shutdown_rx)
    });
    tokio::spawn(shared.presence.clone().run(shared.shutdown.clone()));

    let (out_tx, out_rx) = mpsc::channel(4096);
    let mut actor = Actor::new(
        world,
        state,
        config.limits.clone(),
        out_tx,
        &shared,
        config.checkpoint_every,
    );
    let replayed = entries.len();
    let actor = tokio::task::spawn_blocking(move || -> Result<Actor> {
        for e in &entries {
            actor.replay(e).map_err(anyhow::Error::msg)?;
        }
        actor.settle();
        Ok(actor)
    })
    .await??;
    tracing::info!(replayed, "write-ahead log replayed");

    let initial = (actor.world().version(), actor.world().digest().0);
    let committer = Committer {
        wal,
        data: data.clone(),
        publisher: Publisher::new(initial, config.frontend.slow_client_events),
        metrics: shared.metrics.clone(),
    };
    let committer = std::thread::Builder::new()
        .name("naadf-committer".into())
        .spawn(move || committer.run(out_rx))?;
    let (req_tx, req_rx) = mpsc::channel::<Request>(1024);
    let notify = req_tx.downgrade();
    // The actor's parallel work (page rehashing, clamps) gets a rayon pool of its own, so
    // it never queues behind snapshot compression for joining clients on the global pool.
    let pool = rayon::ThreadPoolBuilder::new()
        .thread_name(|i| format!("naadf-actor-{i}"))
        .build()?;
    let actor = std::thread::Builder::new()
        .name("naadf-actor".into())
        .spawn(move || pool.install(|| actor.run(req_rx, notify)))?;
    // The actor counts replayed records towards its next checkpoint; a replay as long as a
    // whole interval gets one at once, so that crash after crash cannot grow the log that
    // every start replays.
    if replayed as u64 >= config.checkpoint_every {
        req_tx.send(Request::Checkpoint { reply: None }).await?;
    }

    let svc = WorldServiceServer::new(WorldServer::new(shared.clone(), req_tx.clone()));
    let routes = http::router(shared.clone(), req_tx.clone(), Backend::Server(config.auth.clone()));
    let (bound, grpc, http) = config
        .frontend
        .start(svc, routes, Some(&shared.auth), &shared.metrics, &shutdown_tx)
        .await?;
    let ticker = {
        let actor = req_tx.clone();
        let every = config.checkpoint_interval;
        tokio::spawn(async move {
            let mut last = None;
            loop {
                tokio::time::sleep(every).await;
                let Some(s) = crate::stream::messages::status(&actor).await else {
                    return;
                };
                if last != Some(s.version) {
                    last = Some(s.version);
                    let _ = actor.send(Request::Checkpoint { reply: None }).await;
                }
            }
        })
    };
    ready(bound);

    shutdown.await;
    tracing::info!("shutting down");
    let _ = shutdown_tx.send(true);
    ticker.abort();
    let _ = tokio::time::timeout(Duration::from_secs(10), grpc).await;
    let _ = tokio::time::timeout(Duration::from_secs(5), http).await;
    let (reply, rx) = oneshot::channel();
    req_tx.send(Request::Checkpoint { reply: Some(reply) }).await?;
    match rx.await {
        Ok(Ok(v)) => tracing::info!(version = v, "final snapshot written"),
        Ok(Err(e)) => tracing::error!("final snapshot failed: {e}"),
        Err(_) => tracing::error!("final snapshot was not written"),
    }
    drop(req_tx);
    drop(shared);
    tokio::task::spawn_blocking(move || {
        let _ = actor.join();
        let _ = committer.join();
    })
    .await?;
    Ok(())
}

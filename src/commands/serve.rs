//! `naadf serve [--world FILE | --generate PRESET] [--data DIR] [--grpc ADDR] [--http ADDR]`

use super::generate::{PresetArgs, generate, parse_size};
use super::remote::block_on;
use super::{BuildLimit, load_world, print_json};
use anyhow::{Context, Result};
use naadf_server::auth::Auth;
use naadf_server::frontend::Frontend;
use naadf_server::{Bound, ServerConfig};
use naadf_world::WorldSize;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

/// Arguments of `serve`.
#[derive(clap::Args)]
pub struct Args {
    /// Start a new data directory from this world file.
    #[arg(long, conflicts_with = "generate")]
    world: Option<PathBuf>,
    /// Start a new data directory from this preset (`terrain`, `test`, `tiled:<file.vox>`).
    #[arg(long)]
    generate: Option<String>,
    /// Size `X,Y,Z` of a generated world (default: the preset's).
    #[arg(long, value_parser = parse_size, requires = "generate")]
    size: Option<WorldSize>,
    /// Seed of a generated world.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    limit: BuildLimit,
    /// Data directory: snapshots and the write-ahead log. An existing one is resumed (and
    /// --world / --generate are ignored).
    #[arg(long, default_value = naadf_server::DEFAULT_DATA)]
    data: PathBuf,
    /// gRPC listen address.
    #[arg(long, default_value = naadf_server::DEFAULT_GRPC)]
    grpc: SocketAddr,
    /// HTTP listen address (/health, /metrics, status page).
    #[arg(long, default_value = naadf_server::DEFAULT_HTTP)]
    http: SocketAddr,
    /// Token file (TOML, `[[token]]` entries with token, user, role); tokens in the
    /// NAADF_TOKENS environment variable (`TOKEN=user:role,...`) are added.
    #[arg(long)]
    auth: Option<PathBuf>,
    /// Accept that bearer tokens travel in cleartext: serve gRPC without TLS, or HTTP, on a
    /// non-loopback address without the startup warning.
    #[arg(long)]
    insecure: bool,
    /// Edits per second per user.
    #[arg(long, default_value_t = ServerConfig::default().rate)]
    rate: u32,
    #[command(flatten)]
    limits: super::EditLimitArgs,
    /// Write a snapshot after this many edits.
    #[arg(long, default_value_t = ServerConfig::default().checkpoint_every)]
    checkpoint_every: u64,
    /// And at least this often (seconds) while edits arrive.
    #[arg(long, default_value_t = ServerConfig::default().checkpoint_interval.as_secs())]
    checkpoint_secs: u64,
    #[command(flatten)]
    listening: ListenArgs,
    /// Print the bound addresses as one JSON line on stdout once serving.
    #[arg(long)]
    json: bool,
}

/// How a server or a relay listens and how far its clients may fall behind: the options
/// `serve` and `relay` share.
#[derive(clap::Args)]
pub struct ListenArgs {
    /// TLS certificate chain (PEM); needs --tls-key. Read again every 10 s and on SIGHUP:
    /// a changed pair that loads serves the connections opened after it.
    #[arg(long, requires = "tls_key")]
    pub tls_cert: Option<PathBuf>,
    /// TLS private key (PEM); needs --tls-cert.
    #[arg(long, requires = "tls_cert")]
    pub tls_key: Option<PathBuf>,
    /// Largest request message, in bytes.
    #[arg(long, default_value_t = Frontend::default().max_message_bytes)]
    pub max_message_bytes: usize,
    /// Deltas a client may fall behind before it is re-sent a snapshot.
    #[arg(long, default_value_t = Frontend::default().slow_client_events)]
    pub slow_client_events: usize,
    /// Bytes a client may fall behind (deltas it has not read) before it is re-sent a
    /// snapshot.
    #[arg(long, default_value_t = Frontend::default().slow_clients.client_bytes)]
    pub slow_client_bytes: u64,
    /// Bytes the subscribed clients together may fall behind; over it, every one that is
    /// not reading and is more than a sixteenth of --slow-client-bytes behind is re-sent a
    /// snapshot.
    #[arg(long, default_value_t = Frontend::default().slow_clients.total_bytes)]
    pub slow_clients_total_bytes: u64,
    /// Most connections open at a time on each listener (gRPC and HTTP); more wait until
    /// one closes. Keep twice this under the process's file descriptor limit.
    #[arg(long, default_value_t = Frontend::default().connections.max_connections)]
    pub max_connections: usize,
    /// Close a connection whose peer sent nothing for this many seconds (unfinished
    /// handshakes and requests, dead peers); gRPC connections are pinged at a third of it,
    /// so live ones stay open.
    #[arg(long, default_value_t = Frontend::default().connections.idle_timeout.as_secs_f64())]
    pub idle_timeout: f64,
}

impl ListenArgs {
    /// The client-facing settings, listening on `grpc` and `http`.
    pub fn frontend(&self, grpc: SocketAddr, http: SocketAddr) -> Result<Frontend> {
        Ok(Frontend {
            grpc,
            http,
            tls: self.tls_cert.clone().zip(self.tls_key.clone()),
            max_message_bytes: self.max_message_bytes,
            connections: naadf_server::conn::ConnLimits {
                max_connections: self.max_connections.max(1),
                idle_timeout: super::seconds(self.idle_timeout, "--idle-timeout")?.max(Duration::from_millis(100)),
            },
            slow_client_events: self.slow_client_events,
            slow_clients: naadf_server::join::SlowClientLimits {
                client_bytes: self.slow_client_bytes,
                total_bytes: self.slow_clients_total_bytes,
            },
        })
    }
}

/// Runs the server until Ctrl-C or SIGTERM.
pub fn run(a: Args) -> Result<()> {
    let mut auth = match &a.auth {
        Some(p) => Auth::from_file(p).map_err(anyhow::Error::msg)?,
        None => Auth::open(),
    };
    if let Ok(v) = std::env::var("NAADF_TOKENS") {
        auth.merge(Auth::from_env_value(&v).map_err(anyhow::Error::msg)?)
            .map_err(anyhow::Error::msg)?;
    }
    let mut config = ServerConfig::new(a.data.clone());
    config.frontend = a.listening.frontend(a.grpc, a.http)?;
    config.auth = auth;
    config.rate = a.rate;
    config.limits = a.limits.limits();
    config.checkpoint_every = a.checkpoint_every.max(1);
    config.checkpoint_interval = Duration::from_secs(a.checkpoint_secs.max(1));
    config.insecure = a.insecure;
    if let Some(w) = config.cleartext_warning() {
        eprintln!("WARNING: {w}");
    }
    let (world, preset) = (a.world.clone(), a.generate.clone());
    let (size, seed, limit) = (a.size, a.seed, a.limit);
    let initial = move || match world {
        Some(p) => load_world(&p),
        None => generate(&PresetArgs {
            preset: preset.unwrap_or_else(|| "terrain".into()),
            size,
            seed,
            limit,
        }),
    };
    let json = a.json;
    block_on(async move {
        naadf_server::serve(
            config,
            initial,
            announce(json),
            shutdown_signal().context("cannot install the signal handlers")?,
        )
        .await
        .context("server failed")
    })
}

/// What a server or relay does once it listens: with `json`, print its bound addresses as
/// one JSON line (`{"grpc": ADDR, "http": ADDR}`), which scripts and tests wait for.
pub fn announce(json: bool) -> impl FnOnce(Bound) {
    move |b: Bound| {
        if json {
            let _ = print_json(&serde_json::json!({
                "grpc": b.grpc.to_string(),
                "http": b.http.to_string(),
            }));
        }
    }
}

/// A future that resolves on Ctrl-C or SIGTERM. The handlers are installed now, before the
/// server announces its addresses: a signal sent right after the announcement must stop
/// the server cleanly, not find the default action (death by the signal) still in place.
pub fn shutdown_signal() -> std::io::Result<impl std::future::Future<Output = ()>> {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{SignalKind, signal};
        let mut term = signal(SignalKind::terminate())?;
        let mut interrupt = signal(SignalKind::interrupt())?;
        Ok(async move {
            tokio::select! {
                _ = term.recv() => {}
                _ = interrupt.recv() => {}
            }
        })
    }
    #[cfg(not(unix))]
    Ok(async {
        let _ = tokio::signal::ctrl_c().await;
    })
}

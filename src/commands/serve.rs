//! `naadf serve [--world FILE | --generate PRESET] [--data DIR] [--grpc ADDR] [--http ADDR]`

use super::args::{ListenArgs, PresetArgs, parse_size};
use super::remote::block_on;
use super::{BuildLimit, announce, load_world, shutdown_signal};
use anyhow::{Context, Result};
use naadf_server::ServerConfig;
use naadf_server::net::auth::Auth;
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
    /// gRPC listen address (gRPC, gRPC-web and the browser page at /).
    #[arg(long, default_value = naadf_server::DEFAULT_GRPC)]
    grpc: SocketAddr,
    /// HTTP listen address (/health, /metrics, /status, /frame.png; / redirects to the page).
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
        None => PresetArgs {
            preset: preset.unwrap_or_else(|| "terrain".into()),
            size,
            seed,
            limit,
        }
        .generate(),
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

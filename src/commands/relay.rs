//! `naadf relay --upstream URL [--grpc ADDR] [--http ADDR] [--token T]`

use super::args::ListenArgs;
use super::remote::block_on_threads;
use super::{announce, shutdown_signal};
use anyhow::{Context, Result};
use naadf_server::relay::{DEFAULT_RELAY_GRPC, DEFAULT_RELAY_HTTP, DEFAULT_UPSTREAM_TIMEOUT, RelayConfig, relay};
use std::net::SocketAddr;
use std::path::PathBuf;

/// Arguments of `relay`.
#[derive(clap::Args)]
pub struct Args {
    /// The upstream to mirror: a server's or another relay's gRPC URL (`http://HOST:PORT`,
    /// or `https://` with TLS).
    #[arg(long, env = "NAADF_UPSTREAM")]
    upstream: String,
    /// The relay's own token for joining the upstream (a viewer's will do). Callers' tokens
    /// are checked by the upstream, never here.
    #[arg(long, env = "NAADF_TOKEN", hide_env_values = true)]
    token: Option<String>,
    /// CA certificate (PEM) to trust for an `https://` upstream, besides the system roots.
    #[arg(long)]
    ca: Option<PathBuf>,
    /// gRPC listen address (gRPC, gRPC-web and the browser page at /).
    #[arg(long, default_value = DEFAULT_RELAY_GRPC)]
    grpc: SocketAddr,
    /// HTTP listen address (/health, /metrics, /status, /frame.png; / redirects to the page).
    #[arg(long, default_value = DEFAULT_RELAY_HTTP)]
    http: SocketAddr,
    /// The largest world, in bytes of buffers, to accept from the upstream.
    #[arg(long, value_name = "BYTES", default_value_t = naadf_client::DEFAULT_MAX_WORLD_BYTES)]
    max_world_bytes: u64,
    /// Threads serving its clients (their streams and forwarded calls): 1 runs them all on
    /// one thread, which spends the least on handing work between threads, so a relay
    /// delivers its many small sends soonest on a busy machine; 0 takes one per CPU. Grow a
    /// deployment with more relays rather than more threads. Applying the upstream's
    /// stream has a thread of its own either way.
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Give up the upstream connection, and re-join, when it stays silent this many
    /// seconds (keepalive pings go out after half of it): how soon a cut link is noticed.
    #[arg(long, value_name = "SECS", default_value_t = DEFAULT_UPSTREAM_TIMEOUT.as_secs_f64())]
    upstream_timeout: f64,
    #[command(flatten)]
    listening: ListenArgs,
    /// Print the bound addresses as one JSON line on stdout once listening.
    #[arg(long)]
    json: bool,
}

/// Runs the relay until Ctrl-C or SIGTERM.
pub fn run(a: Args) -> Result<()> {
    let mut config = RelayConfig::new(&a.upstream);
    config.token = a.token.clone();
    config.ca = a.ca.clone();
    config.frontend = a.listening.frontend(a.grpc, a.http)?;
    config.max_world_bytes = a.max_world_bytes;
    config.upstream_timeout = super::seconds(a.upstream_timeout, "--upstream-timeout")?;
    let json = a.json;
    block_on_threads(a.threads, async move {
        relay(
            config,
            announce(json),
            shutdown_signal().context("cannot install the signal handlers")?,
        )
        .await
        .context("relay failed")
    })
}

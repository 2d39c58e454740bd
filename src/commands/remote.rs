//! What every command that talks to a server shares: the server URL, the token, the CA
//! certificate, and the async runtime.

use anyhow::Result;
use naadf_client::{Client, ServerAddress};
use std::path::PathBuf;

/// How to reach a server.
#[derive(clap::Args, Clone, Debug)]
pub struct ServerArgs {
    /// Server URL (`http://HOST:PORT`, or `https://` with TLS).
    #[arg(long, env = "NAADF_SERVER", default_value_t = format!("http://{}", naadf_server::DEFAULT_GRPC))]
    pub server: String,
    /// Bearer token sent with every call.
    #[arg(long, env = "NAADF_TOKEN", hide_env_values = true)]
    pub token: Option<String>,
    /// CA certificate (PEM) to trust for `https://` servers, besides the system roots.
    #[arg(long)]
    pub ca: Option<PathBuf>,
    /// The largest world, in bytes of buffers, to accept from the server: a snapshot that
    /// announces more is refused before anything is allocated.
    #[arg(long, value_name = "BYTES", default_value_t = naadf_client::DEFAULT_MAX_WORLD_BYTES)]
    pub max_world_bytes: u64,
}

impl ServerArgs {
    /// Where these arguments point.
    pub fn address(&self) -> ServerAddress {
        ServerAddress {
            url: self.server.clone(),
            token: self.token.clone(),
            ca: self.ca.clone(),
            max_world_bytes: self.max_world_bytes,
        }
    }

    /// Connects.
    pub async fn connect(&self) -> Result<Client> {
        Ok(self.address().connect().await?)
    }
}

/// Runs `f` on a multi-threaded tokio runtime (a worker per CPU).
pub fn block_on<T>(f: impl std::future::Future<Output = Result<T>>) -> Result<T> {
    block_on_threads(0, f)
}

/// Runs `f` on a tokio runtime of `threads` workers: 1 runs every task on this thread (a
/// current-thread runtime), 0 takes a worker per CPU.
pub fn block_on_threads<T>(threads: usize, f: impl std::future::Future<Output = Result<T>>) -> Result<T> {
    let mut builder = match threads {
        1 => tokio::runtime::Builder::new_current_thread(),
        _ => tokio::runtime::Builder::new_multi_thread(),
    };
    if threads > 1 {
        builder.worker_threads(threads);
    }
    builder.enable_all().build()?.block_on(f)
}

/// Joins `server` (announcing `cache`, so that only changed pages come) and returns its
/// world once the mirror is at `min_version` or later and quiescent, failing after
/// `timeout`.
#[cfg(feature = "gpu")]
pub async fn quiescent_world(
    server: &ServerArgs,
    cache: Option<naadf_world::World>,
    min_version: u64,
    timeout: std::time::Duration,
) -> Result<naadf_world::World> {
    let mut session = server.connect().await?.join(cache).await?;
    session.until_quiescent(min_version, timeout).await?;
    Ok(session.into_world().expect("a quiescent mirror holds a world"))
}

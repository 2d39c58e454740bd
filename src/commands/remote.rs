//! What every command that talks to a server shares: the server URL, the token, the CA
//! certificate, and the async runtime.

use anyhow::Result;
use naadf_client::Client;
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
}

impl ServerArgs {
    /// Connects.
    pub async fn connect(&self) -> Result<Client> {
        Ok(naadf_client::connect(&self.server, self.token.as_deref(), self.ca.as_deref()).await?)
    }
}

/// Runs `f` on a multi-threaded tokio runtime.
pub fn block_on<T>(f: impl std::future::Future<Output = Result<T>>) -> Result<T> {
    tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()?
        .block_on(f)
}

/// A gRPC status as an error whose message names the code.
pub fn status_error(s: tonic::Status) -> anyhow::Error {
    anyhow::anyhow!("server refused: {:?}: {}", s.code(), s.message())
}

/// Joins `server` (announcing `cache`, so that only changed pages come) and follows its
/// stream until the mirror is live, at `min_version` or later, and quiescent, or `timeout`
/// passes; returns that world.
pub async fn quiescent_world(
    server: &ServerArgs,
    cache: Option<naadf_world::World>,
    min_version: u64,
    timeout: std::time::Duration,
) -> Result<naadf_world::World> {
    use naadf_client::{Ended, Mirror};
    use std::ops::ControlFlow;
    let mut client = server.connect().await?;
    let mut mirror = Mirror::new(cache);
    let mut stream = client
        .join(mirror.join_request())
        .await
        .map_err(status_error)?
        .into_inner();
    let ended = mirror
        .follow(
            &mut stream,
            tokio::time::sleep(timeout),
            |m| -> Result<ControlFlow<()>> {
                let at = m.world().is_some_and(|w| w.version() >= min_version);
                Ok(if m.is_live() && m.is_quiescent() && at {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                })
            },
        )
        .await?;
    match ended {
        Ended::Stopped(()) => anyhow::bail!(
            "timed out after {} s before the server was quiescent",
            timeout.as_secs_f64()
        ),
        Ended::Stream => anyhow::bail!("the server ended the stream before it was quiescent"),
        _ => mirror
            .into_world()
            .ok_or_else(|| anyhow::anyhow!("the server sent no world")),
    }
}

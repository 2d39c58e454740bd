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

//! Reaching a server: `http://` or `https://` URLs, an optional CA certificate for TLS, and
//! the `authorization: Bearer <token>` metadata on every call. [`Client`](crate::Client)
//! builds on this; nothing here knows the service's calls.

use crate::error::ConnectError;
use naadf_proto::endpoint::EndpointError;
use naadf_proto::v1::world_service_client::WorldServiceClient;
use std::path::Path;
use tonic::codec::CompressionEncoding;
use tonic::metadata::AsciiMetadataValue;
use tonic::service::Interceptor;
use tonic::service::interceptor::InterceptedService;
use tonic::transport::Channel;

/// Adds the bearer token to every request.
#[derive(Clone, Debug)]
pub(crate) struct Token(Option<AsciiMetadataValue>);

impl Interceptor for Token {
    fn call(&mut self, mut r: tonic::Request<()>) -> Result<tonic::Request<()>, tonic::Status> {
        if let Some(v) = &self.0 {
            r.metadata_mut().insert("authorization", v.clone());
        }
        Ok(r)
    }
}

/// The generated world-service client, sending the token with every call: what a
/// [`Client`](crate::Client) wraps.
pub(crate) type RawClient = WorldServiceClient<InterceptedService<Channel, Token>>;

/// Connects to `url`, trusting `ca` (PEM) for TLS in addition to the system roots, and
/// sending `token` with every call. The channel reconnects by itself after the connection
/// breaks, so one stays usable across server restarts.
pub(crate) async fn connect(url: &str, token: Option<&str>, ca: Option<&Path>) -> Result<RawClient, ConnectError> {
    let ca = match ca {
        Some(ca) => Some(std::fs::read(ca).map_err(|e| ConnectError::Ca(ca.display().to_string(), e))?),
        None => None,
    };
    let channel = naadf_proto::endpoint::endpoint(url, ca)
        .map_err(|e| match e {
            EndpointError::Url(url, why) => ConnectError::Url(url, why),
            EndpointError::Tls(url, e) => ConnectError::Transport(url, e),
        })?
        .connect()
        .await
        .map_err(|e| ConnectError::Transport(url.into(), e))?;
    let token = match token {
        Some(t) => Some(
            format!("Bearer {t}")
                .parse::<AsciiMetadataValue>()
                .map_err(|_| ConnectError::Token)?,
        ),
        None => None,
    };
    Ok(WorldServiceClient::with_interceptor(channel, Token(token))
        .max_decoding_message_size(usize::MAX)
        .accept_compressed(CompressionEncoding::Zstd))
}

/// A `client_seq` to start a session's edits from: microseconds since the Unix epoch, so
/// that a new session of the same user never repeats an earlier session's numbers (the
/// server would answer a repeat as a retry and not apply it).
pub fn session_client_seq() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(1, |d| d.as_micros() as u64)
}

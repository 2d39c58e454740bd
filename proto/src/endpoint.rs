//! The channel every caller of the service opens: `http://` or `https://` URLs, an optional
//! extra CA certificate for TLS, `TCP_NODELAY` (deltas are small writes behind bigger
//! ones; Nagle's algorithm would hold them for the peer's delayed ACK), and HTTP/2
//! keepalive pings while a call is open, so that a stream over a dead link (a cut cable, a
//! peer's machine gone) fails within [`DEFAULT_SILENCE_LIMIT`] instead of hanging until TCP
//! gives up, minutes later. Clients and relays both connect through [`endpoint`].

use std::time::Duration;
use tonic::transport::{Certificate, ClientTlsConfig, Endpoint};

/// How long a connection with an open call may go without hearing from its peer before
/// it is given up: after half of it with nothing received a ping goes out, and the peer
/// has the other half to answer.
pub const DEFAULT_SILENCE_LIMIT: Duration = Duration::from_secs(20);

/// The shortest silence limit [`with_silence_limit`] applies: a connection needs a round
/// trip or two to be made at all.
pub const MIN_SILENCE_LIMIT: Duration = Duration::from_millis(100);

/// Why no endpoint could be made from a URL.
#[derive(Debug, thiserror::Error)]
pub enum EndpointError {
    /// The URL does not parse as a URI.
    #[error("bad server URL '{0}': {1}")]
    Url(String, String),
    /// The TLS settings were refused.
    #[error("cannot set up TLS for '{0}': {1}")]
    Tls(String, tonic::transport::Error),
}

/// The endpoint for `url`, trusting `ca` (PEM bytes) for TLS besides the system roots,
/// giving up a connection that stays silent for [`DEFAULT_SILENCE_LIMIT`] while a call is
/// open ([`with_silence_limit`] changes that). Nothing connects yet: [`Endpoint::connect`]
/// or [`Endpoint::connect_lazy`] does.
///
/// ```
/// let ep = naadf_proto::endpoint::endpoint("http://127.0.0.1:50051", None).unwrap();
/// assert_eq!(ep.uri().port_u16(), Some(50051));
/// assert!(naadf_proto::endpoint::endpoint("not a url", None).is_err());
/// ```
pub fn endpoint(url: &str, ca: Option<Vec<u8>>) -> Result<Endpoint, EndpointError> {
    let mut ep = Endpoint::from_shared(url.to_owned()).map_err(|e| EndpointError::Url(url.into(), e.to_string()))?;
    if url.starts_with("https://") {
        let mut tls = ClientTlsConfig::new().with_native_roots();
        if let Some(pem) = ca {
            tls = tls.ca_certificate(Certificate::from_pem(pem));
        }
        ep = ep.tls_config(tls).map_err(|e| EndpointError::Tls(url.into(), e))?;
    }
    Ok(with_silence_limit(ep.tcp_nodelay(true), DEFAULT_SILENCE_LIMIT))
}

/// `ep`, giving up a connection whose peer stays silent for `limit` while a call is open
/// (a keepalive ping after `limit / 2` without a frame received, and `limit / 2` for its
/// answer), and a connection attempt that has not connected within `limit` (over a dead
/// link the SYN's own retries would stretch over minutes). Idle connections are not
/// pinged: servers close those on their own terms. A `limit` under
/// [`MIN_SILENCE_LIMIT`] counts as that: no connection could be made at all.
///
/// ```
/// use std::time::Duration;
/// let ep = naadf_proto::endpoint::endpoint("http://127.0.0.1:50051", None).unwrap();
/// let ep = naadf_proto::endpoint::with_silence_limit(ep, Duration::from_secs(4));
/// assert_eq!(ep.uri().host(), Some("127.0.0.1"));
/// ```
pub fn with_silence_limit(ep: Endpoint, limit: Duration) -> Endpoint {
    let limit = limit.max(MIN_SILENCE_LIMIT);
    let half = limit / 2;
    ep.connect_timeout(limit)
        .http2_keep_alive_interval(half)
        .keep_alive_timeout(half)
        .keep_alive_while_idle(false)
}

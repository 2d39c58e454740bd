//! The channel every caller of the service opens: `http://` or `https://` URLs, an optional
//! extra CA certificate for TLS, and `TCP_NODELAY` (deltas are small writes behind bigger
//! ones; Nagle's algorithm would hold them for the peer's delayed ACK). Clients and relays
//! both connect through [`endpoint`].

use tonic::transport::{Certificate, ClientTlsConfig, Endpoint};

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

/// The endpoint for `url`, trusting `ca` (PEM bytes) for TLS besides the system roots.
/// Nothing connects yet: [`Endpoint::connect`] or [`Endpoint::connect_lazy`] does.
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
    Ok(ep.tcp_nodelay(true))
}

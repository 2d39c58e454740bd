//! Where a server or a relay listens: the documented default addresses, and the addresses
//! a running one is bound to ([`Bound`]).

use std::net::SocketAddr;

/// The default gRPC listen address.
pub const DEFAULT_GRPC: &str = "127.0.0.1:50051";
/// The default HTTP listen address.
pub const DEFAULT_HTTP: &str = "127.0.0.1:8080";

/// The addresses a running server listens on.
#[derive(Clone, Copy, Debug)]
pub struct Bound {
    /// gRPC.
    pub grpc: SocketAddr,
    /// HTTP.
    pub http: SocketAddr,
}

//! How clients reach a server or a relay.
//!
//! - [`addresses`]: the default listen addresses and the bound ones;
//! - [`frontend`]: the listeners a server or relay starts (gRPC with reflection and
//!   keepalive, HTTP) and their limits;
//! - [`conn`]: what both listeners do with a connection (the cap, the idle timeout, the
//!   accept loop);
//! - [`tls`]: the gRPC listener's TLS, with certificates that reload while serving;
//! - [`service`]: the gRPC world service (tokens, roles, rates, then the actor);
//! - [`http`]: health, metrics, the status page and frames over HTTP;
//! - [`auth`]: tokens, users and roles.

pub mod addresses;
pub mod auth;
pub mod conn;
pub mod frontend;
pub mod http;
pub mod service;
pub mod tls;

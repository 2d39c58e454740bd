//! How clients reach a server or a relay.
//!
//! - [`addresses`]: the default listen addresses and the bound ones;
//! - [`frontend`]: the listeners a server or relay starts (gRPC with reflection and
//!   keepalive, HTTP) and their limits;
//! - [`conn`]: what both listeners do with a connection (the caps, the request deadline,
//!   the idle timeout, making room, the accept loop);
//! - [`head`]: whether a connection's bytes hold a complete request head yet;
//! - [`http_serve`]: the HTTP connections, served with the routes of [`http`];
//! - [`page`]: the browser page on the gRPC listener, and the HTTP listener's way there;
//! - [`tls`]: the gRPC listener's TLS, with certificates that reload while serving;
//! - [`service`]: the gRPC world service (tokens, roles, rates, then the actor);
//! - [`http`]: health, metrics, the status page and frames over HTTP;
//! - [`auth`]: tokens, users and roles.

pub mod addresses;
pub mod auth;
pub mod conn;
pub mod frontend;
pub mod head;
pub mod http;
pub mod http_serve;
pub mod page;
pub mod service;
pub mod tls;

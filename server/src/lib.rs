//! # naadf-server
//!
//! The authoritative server (`naadf serve`): one world actor applies every edit in one total
//! order; a committer makes batches durable (write-ahead log with group commit) before it
//! publishes their deltas and acknowledges them; each joined client gets a cache-aware
//! snapshot and then every delta over gRPC. axum serves health, metrics and a status page.
//!
//! Where to start reading: [`serve`] wires everything. The modules are grouped by what they
//! serve:
//! - [`stream`]: the world's total order and its stream — [`stream::actor`], the world's
//!   owner; [`stream::committer`], the durability point; [`stream::join`], one client's
//!   stream; [`stream::messages`], what they hand each other;
//! - [`data`]: the data directory — the write-ahead log, snapshots, the one judgement of a
//!   directory ([`data::fsck`]) and the snapshot pages;
//! - [`net`]: how clients reach the server — listeners, connections, TLS, the gRPC service,
//!   HTTP, tokens and roles;
//! - [`relay`]: `naadf relay`, which serves a mirror of another server through the same
//!   stream and network code;
//! - beside them [`shared`] (what the service, join tasks and HTTP side share),
//!   [`metrics`] and [`render_router`] (frames routed to render nodes).
//!
//! ```text
//! gRPC Edit ──▶ service (auth, roles, rate) ──▶ actor (apply, undo, growth) ──▶ committer
//!                                                                        │ WAL append + fsync
//!                                       join tasks ◀── broadcast deltas ◀┘ then ack the sender
//! ```

#![warn(missing_docs)]

pub mod data;
pub mod metrics;
pub mod net;
pub mod relay;
pub mod render_router;
pub(crate) mod serve;
pub mod shared;
pub mod stream;

pub use net::addresses::{Bound, DEFAULT_GRPC, DEFAULT_HTTP};
pub use serve::{DEFAULT_DATA, ServerConfig, serve};
pub use shared::Shared;

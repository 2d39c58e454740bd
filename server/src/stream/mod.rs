//! The world's one total order and the stream that carries it to clients.
//!
//! - [`actor`]: the one thread that owns the world and applies every request in order;
//! - [`growth`]: the thread that grows distance fields in the background for the actor;
//! - [`committer`]: the durability point — WAL append and fsync, then publish and answer;
//! - [`publisher`]: the published change stream that join tasks follow (a relay's hub
//!   publishes through it too);
//! - [`join`]: one client's stream — snapshot or resume, then every delta;
//! - [`feed`]: that stream as the gRPC server reads it, which a fall behind cuts at once;
//! - [`messages`]: what they hand each other, the actor's mailbox included;
//! - [`presence`]: who is here and where they look, passed on to the clients that ask,
//!   never durable.

pub mod actor;
pub mod committer;
pub mod feed;
pub mod growth;
pub mod join;
pub mod messages;
pub mod presence;
pub mod publisher;

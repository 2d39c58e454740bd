//! # naadf-client
//!
//! Clients of the naadf server. [`Client`] is the one way to talk to a server: every call
//! of the world service as a typed method, failing with a typed [`Error`].
//!
//! ```no_run
//! # async fn demo() -> Result<(), naadf_client::Error> {
//! use naadf_client::Client;
//! use std::time::Duration;
//! let client = Client::connect("http://127.0.0.1:50051", Some("token"), None).await?;
//! let ack = client.edit(r#"{"op":"sphere","center":[40,40,40],"radius":6,"material":2}"#, 0).await?;
//! let mut session = client.join(None).await?;
//! let world = session.until_quiescent(ack.version, Duration::from_secs(60)).await?;
//! println!("version {} digest {}", world.version(), world.digest());
//! # Ok(()) }
//! ```
//!
//! The modules:
//!
//! - [`client`]: [`Client`], [`ServerAddress`] and the typed requests and replies (edits,
//!   status, frames, a render node's [`Registration`] and its jobs);
//! - [`connect`]: channels (plain or TLS) and the bearer token every call carries, beneath
//!   [`Client`];
//! - [`frame`]: what a frame is apart from any renderer: its [`Mode`], the request
//!   ([`FrameSpec`]) and the pixels ([`Frame`]);
//! - [`error`]: [`Error`], which tells a lost connection from a refusal, a rate limit and a
//!   mirror that broke, and [`ConnectError`], why no connection could be made;
//! - [`session`]: [`Session`], a joined world stream applied to a mirror that it keeps
//!   current, and [`WorldStream`], the stream alone;
//! - [`mirror`]: the CPU mirror, which applies the stream's messages to local buffers and
//!   checks every digest (no I/O of its own); the basis of the GPU client, and defined in
//!   `naadf-proto` so that relays hold the same one;
//! - [`patch`]: the patch form of deltas (the bytes each change wrote), for mirrors
//!   without the edit engine, and what a delta costs in each form;
//! - [`cache`]: [`PageCache`], the mirrored world on disk, so that rejoining after a restart
//!   costs only what changed;
//! - [`node`]: [`node::RenderNode`], which keeps a render node registered and serving the
//!   server's frame jobs with any renderer;
//! - `gpu` (feature `gpu`, on by default): the GPU mirror (`gpu::GpuWorld`), the WGSL
//!   traversal, the renderer and the path tracer;
//! - [`light`]: the light model of the lit modes (sky, sun, materials, bounces), its CPU
//!   path tracer and radiance images;
//! - `viewer` (feature `gpu`): the interactive window (winit) that flies through a server's
//!   world and edits it.
//!
//! Without the `gpu` feature the crate compiles no wgpu, winit or nv-flip: programs that
//! only mirror, edit or relay embed the client without the renderer.

#![warn(missing_docs)]

pub mod cache;
pub mod client;
pub mod connect;
pub mod error;
pub mod frame;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod light;
pub use naadf_proto::mirror;
pub use naadf_proto::patch;
/// The stream's messages, as [`Client::stream`] yields them raw.
pub use naadf_proto::v1::{WorldMessage, world_message};
pub mod node;
pub mod session;
#[cfg(feature = "gpu")]
pub mod viewer;

pub use cache::PageCache;
pub use client::{
    Ack, Client, FrameImage, Job, NodeInfo, Pose, PresenceUpdate, Registration, RenderedFrame, ServerAddress,
    ServerStatus, Spawn,
};
pub use error::{ConnectError, Error};
pub use frame::{Frame, FrameSpec, Mode};
pub use mirror::{DEFAULT_MAX_WORLD_BYTES, Mirror, MirrorError, Progress, StreamedEdit};
/// The pauses between attempts to reach a server that is out of reach.
pub use naadf_proto::backoff::Backoff;
pub use session::{Ended, MessageKind, Session, WorldStream};

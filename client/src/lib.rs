//! # naadf-client
//!
//! Clients of the naadf server:
//!
//! - [`connect`]: channels (plain or TLS) and the bearer-token interceptor every call uses;
//! - [`mirror`]: the CPU mirror, which applies the world stream to local buffers, checks
//!   every digest, and keeps a page cache on disk so that rejoining is cheap. It is the
//!   basis of the GPU client and of relays;
//! - [`gpu`]: the GPU mirror ([`gpu::GpuWorld`]), the WGSL traversal and the renderer;
//! - [`viewer`]: the interactive window (winit) that flies through a server's world and
//!   edits it.

pub mod connect;
pub mod gpu;
pub mod mirror;
pub mod viewer;

pub use connect::{Client, connect};
pub use mirror::{Ended, Mirror, MirrorError, Progress, StreamedEdit};

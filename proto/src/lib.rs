//! # naadf-proto
//!
//! The gRPC wire of the naadf service: the protobuf definitions in
//! `proto/naadf/v1/naadf.proto` (documented field by field), the tonic code generated from
//! them with protox (no `protoc` needed), and the conversions between wire messages and
//! `naadf-world` types:
//!
//! - [`snapshot`]: snapshot pages (64 KiB pages of the transferred buffers, zstd) and the
//!   assembly of a world from a header, cached buffers and received pages;
//! - [`requests`]: entity RPCs to and from edit batches;
//! - [`mirror`]: a world kept byte-identical to a server's by applying its stream (what
//!   clients and relays hold);
//! - [`patch`]: the patch form of deltas, the bytes a change wrote (for mirrors without
//!   the edit engine);
//! - [`endpoint`]: the channel settings every caller of the service uses (TLS, no delay);
//! - [`backoff`]: the doubling pauses between attempts to reach a peer that is out of reach.
//!
//! The stream itself is specified in the `.proto` file: a `Header`, the pages the client
//! lacks, then one `Delta` per change, each carrying the digest after it.

#![warn(missing_docs)]

pub mod backoff;
pub mod endpoint;
pub mod mirror;
pub mod patch;
pub mod requests;
pub mod snapshot;

/// The generated messages, client and server of package `naadf.v1`.
#[allow(missing_docs, clippy::all, clippy::pedantic)]
pub mod v1 {
    tonic::include_proto!("naadf.v1");
}

/// The encoded `FileDescriptorSet` of the protocol, for server reflection.
pub const FILE_DESCRIPTOR_SET: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/naadf_descriptor.bin"));

/// The protocol version this build speaks; `Join` refuses other versions. Version 2: the
/// instance buffer holds one record per entity id and the chunk entity buffer stays zero
/// (entities live outside the static world; docs/PROTOCOL.md).
pub const PROTOCOL_VERSION: u32 = 2;

/// The render modes a `FrameRequest` may name (render nodes advertise a subset); the
/// server refuses any other with INVALID_ARGUMENT.
pub const FRAME_MODES: [&str; 9] = [
    "albedo",
    "material",
    "normal",
    "steps",
    "pathtrace",
    "baseline",
    "gi",
    "roma",
    "irradiance",
];

/// Most samples per pixel a `FrameRequest` may ask for.
pub const MAX_FRAME_SPP: u32 = 4096;
/// Most frames a `FrameRequest` may ask a node to render before answering.
pub const MAX_FRAME_FRAMES: u32 = 1024;
/// Longest `sky`, `sun` or `stream` string of a `FrameRequest`, in bytes.
pub const MAX_FRAME_STRING: usize = 128;

/// The response metadata key of a RESOURCE_EXHAUSTED refusal that a retry may pass (the
/// caller is over its rate limit, or the render queue is full): milliseconds to wait before
/// retrying. A RESOURCE_EXHAUSTED refusal without it (a batch over the edit limits) fails
/// the same way on every retry.
pub const RETRY_AFTER_MS: &str = "retry-after-ms";

/// How long the server waits for a frame whose request names no deadline (`timeout_ms`
/// 0); a render node drops a job it has not rendered by then.
pub const DEFAULT_FRAME_DEADLINE: std::time::Duration = std::time::Duration::from_secs(30);

/// Errors in wire data: a message that does not describe a valid world or request.
#[derive(Debug, thiserror::Error)]
pub enum WireError {
    /// A field is missing, out of range or inconsistent.
    #[error("bad message: {0}")]
    Bad(String),
    /// The world the messages describe failed validation.
    #[error(transparent)]
    World(#[from] naadf_world::WorldError),
}

/// Shorthand for a [`WireError::Bad`].
pub(crate) fn bad(msg: impl Into<String>) -> WireError {
    WireError::Bad(msg.into())
}

//! # naadf-proto
//!
//! The gRPC wire of the naadf service: `.proto` definitions compiled with protox and
//! tonic, and conversions between wire messages and `naadf-world` types.
//!
//! This crate is reserved in the workspace layout (BRIEF §2); the wire protocol is built
//! together with the server, so it exports nothing yet.

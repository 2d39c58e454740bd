//! # naadf-server
//!
//! The authoritative server: the world actor, gRPC streaming of world deltas, edits,
//! persistence (WAL + snapshots), auth, limits, metrics and render routing.
//!
//! This crate is reserved in the workspace layout (BRIEF §2) and exports nothing yet.

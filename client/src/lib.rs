//! # naadf-client
//!
//! Render clients: the CPU stream mirror, the wgpu GPU mirror, the render pipeline, the
//! headless render node and the windowed viewer.
//!
//! This crate is reserved in the workspace layout (BRIEF §2) and exports nothing yet.

//! # naadf-world
//!
//! The NAADF world model: a voxel world stored as nested 4³ cells (voxels → blocks →
//! chunks) with axis-aligned distance fields (AADFs) in the empty cells.
//!
//! The buffers of [`World`] are exactly the GPU buffers that render clients mirror, byte
//! for byte. This crate is pure Rust: no async runtime, no GPU.
//!
//! Where to start reading:
//! - [`cell`]: the bit layouts of chunk, block and voxel cells;
//! - [`build`]: construction from raw voxels, chunk by chunk;
//! - [`aadf`]: the distance fields;
//! - [`traverse`]: CPU ray traversal (three methods that must agree exactly);
//! - [`edit`] and [`entity`]: edit batches, dynamic entities;
//! - [`digest`]: the paged 64-bit digest clients use to verify their mirror;
//! - [`file`](mod@file): the `.naadf` world file.
//!
//! ```
//! use naadf_world::preset::Preset;
//! use naadf_world::traverse::{trace_naadf, Ray};
//! use naadf_world::{World, WorldSize};
//!
//! let size = WorldSize::new(64, 64, 64).unwrap();
//! let source = Preset::parse("test").unwrap().source(Some(size), 7).unwrap();
//! let world = World::build(&*source, &|_chunks_done| {}).unwrap();
//! assert_eq!(world.size(), size);
//! let hit = trace_naadf(&world, &Ray::new([32.5, 63.5, 32.5], [0.0, -1.0, 0.0]).unwrap());
//! assert!(hit.is_some_and(|h| h.material != 0));
//! println!("digest {}", world.digest());
//! ```

#![warn(missing_docs)]

pub mod aadf;
pub mod baselines;
pub mod build;
pub mod camera;
pub mod cell;
pub mod dedup;
pub mod digest;
pub mod edit;
pub mod entity;
pub mod error;
pub mod file;
pub mod fingerprint;
pub mod hash;
pub mod import;
pub mod material;
pub mod model;
pub mod ops;
mod prefix;
pub mod preset;
pub mod raysets;
pub mod replay;
pub mod size;
pub mod stats;
pub mod traverse;
mod world;

pub use build::ChunkSource;
pub use error::WorldError;
pub use material::{Material, MaterialKind, MaterialTable};
pub use size::WorldSize;
pub use world::World;

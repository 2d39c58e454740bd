//! Importers: MagicaVoxel `.vox` scenes ([`vox`]).

pub mod vox;
mod vox_graph;

pub use vox::{TiledVox, VoxScene, import_vox};

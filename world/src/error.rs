//! Errors of the world model.

use thiserror::Error;

/// Everything that can go wrong when building, loading, importing or querying a world.
#[derive(Debug, Error)]
pub enum WorldError {
    /// A world size that is not whole chunk groups, or too large.
    #[error("invalid world size {0}")]
    InvalidSize(String),
    /// A material id outside 1..=32767, or one the material table does not define.
    #[error("invalid material: {0}")]
    InvalidMaterial(String),
    /// A buffer would outgrow its 30-bit pointers.
    #[error("world too complex: {0}")]
    Capacity(String),
    /// A world file that cannot be read.
    #[error("bad world file: {0}")]
    BadFile(String),
    /// A model file (e.g. MagicaVoxel `.vox`) that cannot be imported.
    #[error("cannot import: {0}")]
    Import(String),
    /// An unknown or malformed preset name.
    #[error("unknown preset: {0}")]
    Preset(String),
    /// A ray with a zero or non-finite direction or origin.
    #[error("invalid ray: {0}")]
    InvalidRay(String),
    /// An I/O error, with the path or action that failed.
    #[error("{context}: {source}")]
    Io {
        /// What was being done.
        context: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
}

impl WorldError {
    /// Wraps an I/O error with what was being done.
    pub fn io(context: impl Into<String>, source: std::io::Error) -> Self {
        WorldError::Io {
            context: context.into(),
            source,
        }
    }
}

//! [`ServerState`]: what a snapshot keeps beside its world (the undo histories and the
//! answers to retried requests), and its file, `snapshot-<version>.state`.
//!
//! The file is `NAADFSTA`, the xxh3-64 of the payload (little-endian), then the payload:
//! the state in postcard.

use crate::data::layout::StoreError;
use naadf_world::edit::Histories;
use naadf_world::hash::xxh3_64;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Magic of a state file.
const STATE_MAGIC: &[u8; 8] = b"NAADFSTA";

/// Server state persisted beside each world snapshot.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ServerState {
    /// The version the state belongs to.
    pub version: u64,
    /// Undo/redo histories and answered client sequence numbers.
    pub histories: Histories,
}

impl ServerState {
    /// The state file's bytes.
    pub fn encode(&self) -> Vec<u8> {
        let payload = postcard::to_allocvec(self).expect("state serializes");
        let mut bytes = STATE_MAGIC.to_vec();
        bytes.extend_from_slice(&xxh3_64(&payload).to_le_bytes());
        bytes.extend_from_slice(&payload);
        bytes
    }

    /// Reads the state file at `path`, checking its magic and checksum.
    pub fn read(path: &Path) -> Result<ServerState, StoreError> {
        let bytes = std::fs::read(path).map_err(|e| StoreError::Io(format!("cannot read {}", path.display()), e))?;
        let bad = |m: &str| StoreError::BadState(path.to_owned(), m.to_owned());
        if bytes.len() < 16 || &bytes[..8] != STATE_MAGIC {
            return Err(bad("not a naadf state file"));
        }
        let sum = u64::from_le_bytes(bytes[8..16].try_into().expect("8 bytes"));
        if xxh3_64(&bytes[16..]) != sum {
            return Err(bad("checksum mismatch (the file is corrupt)"));
        }
        postcard::from_bytes(&bytes[16..]).map_err(|e| bad(&e.to_string()))
    }

    /// Whether no request was ever answered in it: the state a server writes for the
    /// world it starts a new directory with.
    pub fn is_blank(&self) -> bool {
        self.histories == Histories::default()
    }
}

//! The data directory: what makes the world durable and how it is read back.
//!
//! - [`wal`]: the write-ahead log's segments (append, group fsync, replay, torn tails);
//! - [`store`]: the directory as a whole — snapshots and their state, opening, recovery,
//!   checkpoints;
//! - [`fsck`]: the one judgement of a directory (start new, resume, or refuse; what
//!   `naadf data repair` changes), which opening and `naadf data check` share;
//! - [`state`]: the server state a snapshot keeps beside its world, and its file;
//! - [`layout`]: what `store` and `fsck` share beneath both — file names, the lock, errors,
//!   the quarantine;
//! - [`pages`]: the current snapshot's pages and the shared cache of compressed page groups.

pub mod fsck;
pub mod layout;
pub mod pages;
pub mod state;
pub mod store;
pub mod wal;

//! Replay scripts (docs/REPLAY.md): edit sessions written down as JSON Lines, and the
//! converters that produce them.
//!
//! - [`script`]: the script format and its parser;
//! - [`hashdag`]: HashDAG CSV edit replays turned into script lines;
//! - [`random`]: deterministic random edits (`random_edits` lines).
//!
//! Running a script (against a world in-process or a live server) is the CLI's
//! `naadf replay`; this module is the part both paths share.

pub mod hashdag;
pub mod random;
pub mod script;

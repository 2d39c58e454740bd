//! The CPU mirror: a world kept byte-identical to the server's by applying its stream.
//!
//! A join delivers a header and the snapshot pages the mirror lacks (its cache is its
//! current world, announced as page hashes); the mirror assembles the world and checks the
//! header's digest. Each delta is a change record the mirror applies with
//! [`World::apply_record`], the same code the server ran, and its digest must match. A
//! mismatch is an error: the mirror never silently diverges.
//!
//! The mirror does no I/O: a client's session reads the stream and feeds it, and so does a
//! relay, which republishes what its mirror accepted; a program that reads the stream
//! itself calls [`Mirror::handle`].

pub use crate::snapshot::DEFAULT_MAX_WORLD_BYTES;
use crate::snapshot::{Assembly, buffers_of, cache_of};
use crate::v1::{DeltaForm, JoinRequest, PresenceEntry, ResumePoint, WorldMessage, world_message};
use crate::{PROTOCOL_VERSION, WireError};
use naadf_world::World;
use naadf_world::digest::Digest;
use naadf_world::edit::{ChangeSet, Record};
use naadf_world::ops::{Batch, Limits};
use prost::Message;

/// What a message did to the mirror.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Progress {
    /// A snapshot started or continued.
    Snapshot,
    /// A snapshot completed: the mirror holds the world.
    Ready,
    /// A delta was applied.
    Delta,
    /// The presence table arrived ([`Mirror::presence`]).
    Presence,
}

/// Errors of the mirror.
#[derive(Debug, thiserror::Error)]
pub enum MirrorError {
    /// The stream broke the protocol (a malformed or out-of-order message).
    #[error("protocol error: {0}")]
    Protocol(String),
    /// A snapshot did not assemble into a valid world.
    #[error(transparent)]
    Snapshot(#[from] WireError),
    /// After a delta the mirror's digest differs from the server's.
    #[error("digest mismatch at version {version} step {growth_seq}: mirror {mirror}, server {server}")]
    Diverged {
        /// Version.
        version: u64,
        /// Growth sub-step.
        growth_seq: u32,
        /// The mirror's digest.
        mirror: Digest,
        /// The server's.
        server: Digest,
    },
}

/// Counters of what the mirror received.
#[derive(Clone, Copy, Debug, Default)]
pub struct Stats {
    /// Encoded bytes of all messages.
    pub bytes: u64,
    /// Snapshot pages.
    pub pages: u64,
    /// Snapshots (headers), including re-sent ones.
    pub snapshots: u64,
    /// Deltas.
    pub deltas: u64,
}

/// An edit batch the stream delivered: what a recorder writes down.
#[derive(Clone, Debug, PartialEq)]
pub struct StreamedEdit {
    /// The version it produced.
    pub version: u64,
    /// The user whose request it was (empty from a server that does not say).
    pub user: String,
    /// The batch as the server applied it (undo and redo as their content batches).
    pub batch: Batch,
}

/// A mirrored world.
#[derive(Debug)]
pub struct Mirror {
    world: Option<World>,
    assembly: Option<Assembly>,
    quiescent: bool,
    growth_seq: u32,
    /// Keep the latest edit batch ([`Mirror::keep_edits`]); off by default, since it costs
    /// a copy of every batch.
    keep_edits: bool,
    last_edit: Option<StreamedEdit>,
    /// The change the latest delta applied.
    last_change: Option<ChangeSet>,
    /// The latest presence table.
    presence: Vec<PresenceEntry>,
    /// The most bytes of buffers a snapshot may need ([`Mirror::with_max_world_bytes`]).
    max_world_bytes: u64,
    /// What was received so far.
    pub stats: Stats,
}

impl Default for Mirror {
    fn default() -> Self {
        Self::new(None)
    }
}

impl Mirror {
    /// A mirror starting from `cache` (a world from an earlier session, or none).
    pub fn new(mut cache: Option<World>) -> Self {
        // A cache may be a clone, sized to the byte: give it room before deltas arrive.
        if let Some(w) = &mut cache {
            w.reserve_headroom();
        }
        Self {
            world: cache,
            assembly: None,
            quiescent: false,
            growth_seq: 0,
            keep_edits: false,
            last_edit: None,
            last_change: None,
            presence: Vec::new(),
            max_world_bytes: DEFAULT_MAX_WORLD_BYTES,
            stats: Stats::default(),
        }
    }

    /// Refuses snapshots whose buffers need more than `bytes` in all (default
    /// [`DEFAULT_MAX_WORLD_BYTES`]), before allocating them: a header of a few bytes may
    /// announce gigabytes.
    pub fn with_max_world_bytes(mut self, bytes: u64) -> Self {
        self.max_world_bytes = bytes;
        self
    }

    /// Starts a new stream: forgets the one in progress (a partial snapshot, and the
    /// quiescent flag, which the new stream's header sets again) and returns the join
    /// request announcing the mirror's world as its cache.
    pub fn join_request(&mut self) -> JoinRequest {
        self.assembly = None;
        self.quiescent = false;
        JoinRequest {
            protocol_version: PROTOCOL_VERSION,
            cached: self.world.as_ref().map(cache_of).unwrap_or_default(),
            resume: self.world.as_ref().map(|w| ResumePoint {
                version: w.version(),
                digest: w.digest().0,
            }),
            delta_form: DeltaForm::Record.into(),
            presence: false,
        }
    }

    /// The mirrored world, once a snapshot has completed (during a re-sent snapshot, the
    /// previous state).
    pub fn world(&self) -> Option<&World> {
        self.world.as_ref()
    }

    /// Takes the world out of the mirror.
    pub fn into_world(self) -> Option<World> {
        self.world
    }

    /// Whether the mirror is live (a snapshot completed and none is in progress).
    pub fn is_live(&self) -> bool {
        self.world.is_some() && self.assembly.is_none()
    }

    /// Whether the server reported the current state quiescent.
    pub fn is_quiescent(&self) -> bool {
        self.is_live() && self.quiescent
    }

    /// Makes the mirror keep the latest edit batch for [`Mirror::last_edit`] (recorders).
    pub fn keep_edits(&mut self) {
        self.keep_edits = true;
    }

    /// The latest presence table the stream carried (empty unless the join asked for it):
    /// who is here, where they look, what they point at.
    pub fn presence(&self) -> &[PresenceEntry] {
        &self.presence
    }

    /// The change the latest delta applied (its writes, for a relay's patch-form deltas);
    /// none before the first delta.
    pub fn last_change(&self) -> Option<&ChangeSet> {
        self.last_change.as_ref()
    }

    /// The latest edit batch applied from a delta, when [`Mirror::keep_edits`] was asked
    /// for (growth steps and snapshots leave it).
    pub fn last_edit(&self) -> Option<&StreamedEdit> {
        self.last_edit.as_ref()
    }

    /// The server's growth sub-step of the current state.
    pub fn growth_seq(&self) -> u32 {
        self.growth_seq
    }

    /// Applies one stream message.
    pub fn handle(&mut self, m: &WorldMessage) -> Result<Progress, MirrorError> {
        self.stats.bytes += m.encoded_len() as u64;
        let proto = |s: &str| MirrorError::Protocol(s.to_owned());
        match m.kind.as_ref().ok_or_else(|| proto("empty message"))? {
            world_message::Kind::Header(h) => {
                if h.protocol_version != PROTOCOL_VERSION {
                    return Err(MirrorError::Protocol(format!(
                        "server speaks protocol {}, this client {PROTOCOL_VERSION}",
                        h.protocol_version
                    )));
                }
                if h.resume {
                    // The server resumes from the state this mirror announced.
                    let w = self
                        .world
                        .as_ref()
                        .ok_or_else(|| proto("a resume without a cached world"))?;
                    if h.pages != 0 || w.version() != h.version || w.digest().0 != h.digest {
                        return Err(MirrorError::Protocol(format!(
                            "resume at version {} digest {}, but this mirror holds version {} digest {}",
                            h.version,
                            Digest(h.digest),
                            w.version(),
                            w.digest()
                        )));
                    }
                    self.assembly = None;
                    self.quiescent = h.quiescent;
                    return Ok(Progress::Ready);
                }
                self.stats.snapshots += 1;
                let cache = self.world.as_ref().map(buffers_of).unwrap_or_default();
                self.assembly = Some(Assembly::start(h.clone(), cache, self.max_world_bytes)?);
                self.finish_if_complete()
            }
            world_message::Kind::Page(p) => {
                self.stats.pages += 1;
                self.assembly
                    .as_mut()
                    .ok_or_else(|| proto("a page outside a snapshot"))?
                    .page(p)?;
                self.finish_if_complete()
            }
            world_message::Kind::Presence(p) => {
                self.presence = p.entries.clone();
                Ok(Progress::Presence)
            }
            world_message::Kind::Delta(d) => {
                self.stats.deltas += 1;
                if self.assembly.is_some() {
                    return Err(proto("a delta inside a snapshot"));
                }
                let world = self
                    .world
                    .as_mut()
                    .ok_or_else(|| proto("a delta before any snapshot"))?;
                let decoded = Record::decode(&d.change).map_err(|e| MirrorError::Protocol(e.to_string()))?;
                let cs = world
                    .apply_record(decoded.version, &decoded.record, &Limits::unbounded())
                    .map_err(|e| MirrorError::Protocol(format!("cannot apply delta: {e}")))?;
                let server = Digest(d.digest);
                if cs.digest != server {
                    return Err(MirrorError::Diverged {
                        version: decoded.version,
                        growth_seq: decoded.growth_seq,
                        mirror: cs.digest,
                        server,
                    });
                }
                if let (true, Record::Batch(batch), 0) = (self.keep_edits, &decoded.record, decoded.growth_seq) {
                    self.last_edit = Some(StreamedEdit {
                        version: decoded.version,
                        user: d.user.clone(),
                        batch: batch.clone(),
                    });
                }
                self.quiescent = decoded.quiescent;
                self.growth_seq = decoded.growth_seq;
                // The server's step and flag: a mirror runs no growth of its own, so its
                // world's own idea of them is not the server's.
                self.last_change = Some(ChangeSet {
                    growth_seq: decoded.growth_seq,
                    quiescent: decoded.quiescent,
                    ..cs
                });
                Ok(Progress::Delta)
            }
        }
    }

    fn finish_if_complete(&mut self) -> Result<Progress, MirrorError> {
        if !self.assembly.as_ref().is_some_and(Assembly::is_complete) {
            return Ok(Progress::Snapshot);
        }
        let a = self.assembly.take().expect("assembly in progress");
        let (quiescent, growth_seq) = (a.header().quiescent, a.header().growth_seq);
        self.world = Some(a.finish()?);
        self.quiescent = quiescent;
        self.growth_seq = growth_seq;
        Ok(Progress::Ready)
    }
}

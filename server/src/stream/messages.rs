//! What the actor, the committer, the growth thread and the join tasks hand each other.
//! Everyone asks the actor through its mailbox ([`Request`]: edits, joins, status, the
//! growth thread's "done"); the actor sends [`Outgoing`] items to the committer in the
//! world's total order; the committer publishes each change as an [`Event`] to every join
//! task's [`Subscription`], and answers edit requests with an [`EditResult`] once their
//! batch is durable.

use crate::data::pages::{PAGED, PageChange, SnapshotView};
use crate::data::state::ServerState;
use naadf_proto::v1::{Delta, DeltaForm, EditReply, Patch, WorldMessage, world_message};
use naadf_world::file::WorldParts;
use naadf_world::ops::Batch;
use std::sync::Arc;
use tokio::sync::{broadcast, mpsc, oneshot, watch};
use tonic::Status;

/// The answer to an edit request: the version its batch produced (or the earlier answer,
/// for a retried request), or the gRPC status it was refused with.
pub type EditResult = Result<EditReply, Status>;

/// One published change, as every join task forwards it.
#[derive(Debug)]
pub struct Event {
    /// Edit version after the change.
    pub version: u64,
    /// Growth sub-step.
    pub growth_seq: u32,
    /// The digest after the change.
    pub digest: u64,
    /// The `Delta` message in the record form.
    pub message: WorldMessage,
    /// The same change as a `Delta` in the patch form.
    pub patch: WorldMessage,
    /// The snapshot pages the change altered.
    pub changes: Vec<PageChange>,
    /// The buffers' lengths after it, by id.
    pub lens: [usize; PAGED],
}

impl Event {
    /// Approximate bytes the event holds (for bounding the history of recent deltas and
    /// the backlog of slow clients).
    pub fn size(&self) -> usize {
        use prost::Message;
        self.message.encoded_len() + self.patch.encoded_len() + 16 * self.changes.len() + 64
    }

    /// The `Delta` message in `form`.
    pub fn delta(&self, form: DeltaForm) -> &WorldMessage {
        match form {
            DeltaForm::Record => &self.message,
            DeltaForm::Patch => &self.patch,
        }
    }
}

/// The `Delta` message of a change in the patch form: `patch`, the digest after it and the
/// user whose request it was.
pub fn patch_delta(patch: Patch, digest: u64, user: &str) -> WorldMessage {
    WorldMessage {
        kind: Some(world_message::Kind::Delta(Delta {
            change: Vec::new(),
            digest,
            user: user.to_owned(),
            patch: Some(patch),
        })),
    }
}

/// What a join gets: a snapshot, the subscription to everything published after it, and,
/// when the client's cached state is recent enough, the deltas from that state to the
/// snapshot (then no pages need to travel).
#[derive(Debug)]
pub struct Subscription {
    /// The state at the join.
    pub view: Arc<SnapshotView>,
    /// Everything published after it.
    pub events: broadcast::Receiver<Arc<Event>>,
    /// The deltas from the client's state to `view`, if the server still has them all.
    pub catch_up: Option<Vec<Arc<Event>>>,
    /// Bytes ([`Event::size`]) published before the subscription: the subscriber's
    /// position in the published stream, to measure how far behind `head` it is.
    pub start: u64,
    /// Bytes published so far, kept current by the committer.
    pub head: watch::Receiver<u64>,
}

/// What the actor hands to the committer.
#[derive(Debug)]
pub enum Outgoing {
    /// An applied batch: log it, then publish and acknowledge it.
    Batch {
        /// The framed log record.
        frame: Vec<u8>,
        /// The delta to publish.
        event: Arc<Event>,
        /// The sender's answer.
        reply: oneshot::Sender<EditResult>,
    },
    /// A growth step: publish it.
    Growth {
        /// The delta to publish.
        event: Arc<Event>,
    },
    /// An answer that needs no log record (a retried request), given in order.
    Ack {
        /// Where the answer goes.
        reply: oneshot::Sender<EditResult>,
        /// The answer: for a retry, the version the original request produced.
        result: EditResult,
    },
    /// A join: subscribe after everything before it is published.
    Join {
        /// The snapshot at this point.
        view: Arc<SnapshotView>,
        /// The state the client holds, if any: `(version, digest)`.
        resume: Option<(u64, u64)>,
        /// Where the subscription goes.
        reply: oneshot::Sender<Subscription>,
    },
    /// A checkpoint: start a new log segment and write the snapshot.
    Checkpoint {
        /// The world at the checkpoint.
        parts: Box<WorldParts>,
        /// The server state at the checkpoint.
        state: Box<ServerState>,
        /// Answered once the snapshot is durable.
        reply: Option<oneshot::Sender<Result<u64, String>>>,
    },
}

/// What an edit request asks for.
#[derive(Debug)]
pub enum Action {
    /// Apply this batch.
    Batch(Batch),
    /// Undo the caller's latest edit.
    Undo,
    /// Redo the caller's latest undo.
    Redo,
}

/// A request to the actor.
#[derive(Debug)]
pub enum Request {
    /// An edit, entity request, undo or redo.
    Edit {
        /// The caller's user name.
        user: String,
        /// The request's client sequence number (0: none).
        client_seq: u64,
        /// What to do.
        action: Action,
        /// Where the answer goes (after the batch is durable).
        reply: oneshot::Sender<EditResult>,
    },
    /// A snapshot and a subscription to the changes after it.
    Join {
        /// The state the client holds, if any: `(version, digest)`.
        resume: Option<(u64, u64)>,
        /// Where the snapshot and subscription go.
        reply: oneshot::Sender<Subscription>,
    },
    /// The world's current version, growth sub-step and digest (answered at once, without
    /// waiting for durability).
    Status {
        /// Where the answer goes.
        reply: oneshot::Sender<StatusInfo>,
    },
    /// The growth thread finished its task.
    Grown,
    /// Converge growth, then write a snapshot and truncate the log behind it.
    Checkpoint {
        /// Answered with the snapshot's version once it is durable.
        reply: Option<oneshot::Sender<Result<u64, String>>>,
    },
}

/// The actor's state as `Status` reports it.
#[derive(Clone, Debug)]
pub struct StatusInfo {
    /// World size in voxels.
    pub size: [u32; 3],
    /// Edit version: the number of batches applied so far.
    pub version: u64,
    /// Growth sub-step: background distance-field steps published since that batch.
    pub growth_seq: u32,
    /// No distance-field work queued: the world stays as it is until the next edit.
    pub quiescent: bool,
    /// The world digest at `(version, growth_seq)`.
    pub digest: naadf_world::digest::Digest,
}

/// Asks the actor (or a relay's hub, which answers the same mailbox) for its state; `None`
/// when it is gone.
pub async fn status(actor: &mpsc::Sender<Request>) -> Option<StatusInfo> {
    let (reply, rx) = oneshot::channel();
    actor.send(Request::Status { reply }).await.ok()?;
    rx.await.ok()
}

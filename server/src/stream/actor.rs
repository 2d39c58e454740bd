//! The world actor: the one thread that owns the world and applies every request in one
//! total order. Between requests it runs background distance-field growth.
//!
//! The actor never waits for disk or network. Everything it produces (applied batches with
//! their log records, growth steps, acknowledgements, join subscriptions, checkpoints) goes
//! in order to the [committer](crate::stream::committer), which makes batches durable before it
//! publishes them or answers their senders.

use crate::data::pages::{PageStore, SnapshotView};
use crate::data::state::ServerState;
use crate::data::wal::Entry;
use crate::metrics::Metrics;
use crate::stream::growth::GrowthWorker;
use crate::stream::messages::{Action, EditResult, Event, Outgoing, Request, StatusInfo, patch_delta};
use naadf_proto::patch::PatchMaker;
use naadf_proto::v1::{Delta, EditReply, WorldMessage, world_message};
use naadf_world::World;
use naadf_world::edit::{BatchKind, ChangeSet, GrowthTask, Histories};
use naadf_world::ops::{Batch, EditError, Limits};
use std::sync::Arc;
use tokio::sync::{mpsc, oneshot};
use tonic::Status;

/// The owner of the world: applies edits, undo and redo in one total order, keeps the
/// snapshot pages and per-user histories current, and runs distance-field growth on a
/// thread of its own between requests.
pub struct Actor {
    world: World,
    histories: Histories,
    pages: PageStore,
    /// Makes each change's patch-form delta.
    patches: PatchMaker,
    limits: Limits,
    out: mpsc::Sender<Outgoing>,
    metrics: Arc<Metrics>,
    activity: Arc<crate::metrics::Activity>,
    view: Option<Arc<SnapshotView>>,
    checkpoint_every: u64,
    since_checkpoint: u64,
    /// The thread running background growth (started by [`Actor::run`]).
    growth: Option<GrowthWorker>,
}

/// The gRPC status for an edit error.
pub fn edit_status(e: &EditError) -> Status {
    match e {
        EditError::Limit { .. } => Status::resource_exhausted(e.to_string()),
        _ => Status::invalid_argument(e.to_string()),
    }
}

impl Actor {
    /// An actor for `world` (quiescent or not) with the persisted `state`.
    pub fn new(
        world: World,
        state: ServerState,
        limits: Limits,
        out: mpsc::Sender<Outgoing>,
        shared: &crate::shared::Shared,
        checkpoint_every: u64,
    ) -> Self {
        let pages = PageStore::new(&world);
        shared.metrics.version.set(world.version() as i64);
        Self {
            patches: PatchMaker::new(&world),
            world,
            histories: state.histories,
            pages,
            limits,
            out,
            metrics: shared.metrics.clone(),
            activity: shared.activity.clone(),
            view: None,
            checkpoint_every,
            since_checkpoint: 0,
            growth: None,
        }
    }

    /// Re-applies a logged batch at startup (rebuilding undo history and retry answers).
    pub fn replay(&mut self, e: &Entry) -> Result<(), String> {
        let batch = Batch::parse_line(&e.ops).map_err(|err| format!("log entry {}: {err}", e.version))?;
        let applied = self
            .world
            .apply(&batch, &Limits::unbounded())
            .map_err(|err| format!("log entry {}: {err}", e.version))?;
        if applied.change.version != e.version {
            return Err(format!(
                "log entry {} replayed as version {}",
                e.version, applied.change.version
            ));
        }
        self.histories
            .record(&e.user, e.client_seq, e.kind, e.version, applied.undo);
        // Checkpoints count from the snapshot, not from this process's start: otherwise a
        // server that crashes often would never write one.
        self.since_checkpoint += 1;
        Ok(())
    }

    /// The world (for wiring and tests; only the actor thread mutates it).
    pub fn world(&self) -> &World {
        &self.world
    }

    /// Runs growth until quiescent without publishing (after replay, before serving).
    pub fn settle(&mut self) {
        self.world.grow_until_quiescent();
        self.pages = PageStore::new(&self.world);
        self.metrics.version.set(self.world.version() as i64);
    }

    /// Runs the actor until every request sender is gone. Distance-field growth runs on a
    /// thread of its own (on a copy of what it reads), so edits never wait for it; the
    /// thread reports back through the request queue.
    pub fn run(mut self, mut rx: mpsc::Receiver<Request>, notify: mpsc::WeakSender<Request>) {
        self.growth = Some(GrowthWorker::start(notify));
        loop {
            self.start_growth();
            match rx.blocking_recv() {
                Some(r) => self.handle(r),
                None => break,
            }
        }
        self.collect_growth(true);
    }

    fn start_growth(&mut self) {
        let Some(worker) = self.growth.as_mut().filter(|w| !w.is_busy()) else {
            return;
        };
        if let Some(task) = self.world.start_growth()
            && let Some(finished) = worker.submit(task)
        {
            self.publish_task(finished);
        }
    }

    /// Publishes the growth task: with `wait`, takes it back at once (finishing it here if
    /// the thread stopped it early); without, only once the thread is done with it.
    fn collect_growth(&mut self, wait: bool) {
        if let Some(task) = self.growth.as_mut().and_then(|g| g.collect(wait)) {
            self.publish_task(task);
        }
    }

    fn publish_task(&mut self, task: GrowthTask) {
        let cs = self.world.finish_growth(task);
        self.publish_growth(&cs);
    }

    fn publish_growth(&mut self, cs: &ChangeSet) {
        self.metrics.growth_steps.inc();
        let event = self.event(cs, "");
        self.send(Outgoing::Growth { event });
    }

    fn send(&self, o: Outgoing) {
        // The committer only stops when the process is going down.
        let _ = self.out.blocking_send(o);
    }

    /// The event publishing change set `cs`, made by `user`'s request (empty for growth
    /// steps); the page store is updated on the way.
    fn event(&mut self, cs: &ChangeSet, user: &str) -> Arc<Event> {
        self.view = None;
        let changes = self.pages.update(&self.world);
        Arc::new(Event {
            version: cs.version,
            growth_seq: cs.growth_seq,
            digest: cs.digest.0,
            message: WorldMessage {
                kind: Some(world_message::Kind::Delta(Delta {
                    change: cs.encode(),
                    digest: cs.digest.0,
                    user: user.to_owned(),
                    patch: None,
                })),
            },
            patch: patch_delta(self.patches.patch(&self.world, cs), cs.digest.0, user),
            changes,
            lens: self.pages.lens(),
        })
    }

    fn handle(&mut self, req: Request) {
        match req {
            Request::Edit {
                user,
                client_seq,
                action,
                reply,
            } => self.edit(user, client_seq, action, reply),
            Request::Join { resume, reply } => {
                let view = self.view().clone();
                self.send(Outgoing::Join { view, resume, reply });
            }
            Request::Status { reply } => {
                let _ = reply.send(StatusInfo {
                    size: self.world.size().voxels(),
                    version: self.world.version(),
                    growth_seq: self.world.growth_seq(),
                    quiescent: self.world.is_quiescent(),
                    digest: self.world.digest(),
                });
            }
            Request::Grown => self.collect_growth(false),
            Request::Checkpoint { reply } => self.checkpoint(reply),
        }
    }

    fn view(&mut self) -> &Arc<SnapshotView> {
        let w = &self.world;
        self.view.get_or_insert_with(|| {
            Arc::new(SnapshotView {
                size: w.size().voxels(),
                version: w.version(),
                growth_seq: w.growth_seq(),
                quiescent: w.is_quiescent(),
                digest: w.digest(),
                lens: self.pages.lens(),
                pages: self.pages.pages(),
                entity_table: w.entity_table().encode(),
            })
        })
    }

    fn edit(&mut self, user: String, client_seq: u64, action: Action, reply: oneshot::Sender<EditResult>) {
        if let Some(version) = self.histories.answered(&user, client_seq) {
            // Answered once it is durable: the original may still be in the committer's queue.
            self.send(Outgoing::Ack {
                reply,
                result: Ok(EditReply {
                    version,
                    duplicate: true,
                }),
            });
            return;
        }
        let (batch, kind) = match action {
            Action::Batch(b) => (b, BatchKind::Edit),
            history => {
                let redo = !matches!(history, Action::Undo);
                match self.histories.history_batch(&user, redo, &self.world) {
                    Ok(found) => found,
                    Err(why) => {
                        let _ = reply.send(Err(Status::failed_precondition(why)));
                        return;
                    }
                }
            }
        };
        let applied = match self.world.apply(&batch, &self.limits) {
            Ok(a) => a,
            Err(e) => {
                let _ = reply.send(Err(edit_status(&e)));
                return;
            }
        };
        let version = applied.change.version;
        self.histories.record(&user, client_seq, kind, version, applied.undo);
        let ops = batch.to_json_line();
        self.activity.edit(version, &user, &ops);
        let entry = Entry {
            version,
            user,
            client_seq,
            kind,
            ops,
        };
        let event = self.event(&applied.change, &entry.user);
        self.metrics.edits.inc();
        self.metrics.version.set(version as i64);
        self.send(Outgoing::Batch {
            frame: entry.frame(),
            event,
            reply,
        });
        self.since_checkpoint += 1;
        if self.since_checkpoint >= self.checkpoint_every {
            self.checkpoint(None);
        }
    }

    fn checkpoint(&mut self, reply: Option<oneshot::Sender<Result<u64, String>>>) {
        self.collect_growth(true);
        for cs in self.world.grow_until_quiescent() {
            self.publish_growth(&cs);
        }
        self.since_checkpoint = 0;
        let state = ServerState {
            version: self.world.version(),
            histories: self.histories.clone(),
        };
        self.send(Outgoing::Checkpoint {
            parts: Box::new(self.world.to_parts()),
            state: Box::new(state),
            reply,
        });
    }
}

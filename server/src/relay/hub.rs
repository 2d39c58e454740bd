//! The hub: a relay's counterpart of the server's actor and committer. It owns the mirror
//! of the upstream world, applies every upstream message to it (each delta's digest
//! checked), and publishes what it accepted to its own join tasks, which serve it exactly
//! as a server's do. It answers the same [`Request`]s the server's actor does, so the
//! server's join tasks and HTTP pages work on a relay unchanged.
//!
//! Nothing the mirror refused is passed on: a message that does not apply, or a delta
//! whose digest differs, ends that upstream stream, and the hub asks the link for a new
//! one. The re-join announces the mirror's pages as its cache, so only the pages that
//! differ travel again. When the state a re-join arrives at does not follow from what was
//! published (the upstream could not resume the relay), every subscription ends and each
//! client is re-sent, in its own stream, the pages it lacks.

use crate::data::pages::{PageStore, SnapshotView};
use crate::metrics::Metrics;
use crate::stream::messages::{Event, Request, StatusInfo, Subscription, patch_delta};
use crate::stream::presence::Presence;
use crate::stream::publisher::Publisher;
use naadf_proto::mirror::{Mirror, Progress};
use naadf_proto::patch::PatchMaker;
use naadf_proto::v1::{JoinRequest, WorldMessage, world_message};
use std::sync::Arc;
use tokio::sync::{Notify, mpsc, oneshot};
use tonic::Status;

/// What the hub is handed.
#[derive(Debug)]
pub enum Input {
    /// A request, as the server's actor takes them (joins and status; edits never come).
    Request(Request),
    /// The link opens a new upstream stream: the join request to send (announcing the
    /// mirror's state) and the stream's generation, which its messages carry.
    Rejoin(oneshot::Sender<(JoinRequest, u64)>),
    /// A message of the upstream stream of this generation.
    Message(u64, WorldMessage),
}

/// A join waiting for the first state: the state its client holds, and where its
/// subscription goes.
type WaitingJoin = (Option<(u64, u64)>, oneshot::Sender<Subscription>);

/// The relay's mirror and what it publishes (see the module docs).
pub struct Hub {
    mirror: Mirror,
    /// The pages of the published state (once a first snapshot completed).
    pages: Option<PageStore>,
    /// Makes the patch-form deltas from the mirror's changes (set with the pages).
    patches: Option<PatchMaker>,
    publisher: Option<Publisher>,
    /// The published state: `(version, digest)`.
    published: (u64, u64),
    view: Option<Arc<SnapshotView>>,
    /// Joins that arrived before the first snapshot completed.
    waiting: Vec<WaitingJoin>,
    /// The generation of the upstream stream being followed.
    generation: u64,
    /// The current stream broke the protocol: its messages are ignored until the next.
    rejected: bool,
    /// Wakes the link to open a new upstream stream.
    rejoin: Arc<Notify>,
    metrics: Arc<Metrics>,
    /// How many deltas a client may fall behind (the broadcast's capacity).
    capacity: usize,
    /// The relay's presence table: the upstream's, passed on.
    presence: Arc<Presence>,
}

impl Hub {
    /// A hub whose mirror accepts worlds of up to `max_world_bytes`, whose clients may fall
    /// `capacity` deltas behind, which wakes `rejoin` when a stream must be given up, and
    /// which passes the upstream's presence table on to `presence`.
    pub fn new(
        max_world_bytes: u64,
        capacity: usize,
        rejoin: Arc<Notify>,
        metrics: Arc<Metrics>,
        presence: Arc<Presence>,
    ) -> Self {
        Self {
            mirror: Mirror::default().with_max_world_bytes(max_world_bytes),
            pages: None,
            patches: None,
            publisher: None,
            published: (0, 0),
            view: None,
            waiting: Vec::new(),
            generation: 0,
            rejected: false,
            rejoin,
            metrics,
            capacity,
            presence,
        }
    }

    /// Runs until every sender of `rx` is gone.
    pub fn run(mut self, mut rx: mpsc::Receiver<Input>) {
        while let Some(input) = rx.blocking_recv() {
            self.handle(input);
        }
    }

    /// Handles one input.
    pub fn handle(&mut self, input: Input) {
        match input {
            Input::Request(r) => self.request(r),
            Input::Rejoin(reply) => {
                self.generation += 1;
                self.rejected = false;
                let request = JoinRequest {
                    presence: true,
                    ..self.mirror.join_request()
                };
                let _ = reply.send((request, self.generation));
            }
            Input::Message(generation, m) => {
                if generation == self.generation && !self.rejected {
                    self.message(&m);
                }
            }
        }
    }

    /// The published state, `(version, digest)`, once there is one.
    pub fn published(&self) -> Option<(u64, u64)> {
        self.publisher.as_ref().map(|_| self.published)
    }

    fn request(&mut self, r: Request) {
        match r {
            Request::Join { resume, reply } => match &self.publisher {
                // A refused stream may have left the mirror past the published state:
                // joins wait for the re-join.
                Some(_) if !self.rejected => {
                    let view = self.view();
                    let publisher = self.publisher.as_ref().expect("publisher");
                    let _ = reply.send(publisher.subscribe(view, resume));
                }
                _ => self.waiting.push((resume, reply)),
            },
            Request::Status { reply } => {
                // Before the first snapshot there is nothing to report: the caller sees
                // the relay as unavailable.
                if let (Some(w), true) = (self.mirror.world(), self.publisher.is_some()) {
                    let _ = reply.send(StatusInfo {
                        size: w.size().voxels(),
                        version: self.published.0,
                        growth_seq: self.mirror.growth_seq(),
                        quiescent: self.mirror.is_quiescent(),
                        digest: naadf_world::digest::Digest(self.published.1),
                    });
                }
            }
            Request::Edit { reply, .. } => {
                let _ = reply.send(Err(Status::unimplemented("a relay forwards edits upstream")));
            }
            Request::Checkpoint { reply } => {
                if let Some(r) = reply {
                    let _ = r.send(Err("a relay keeps no data directory".into()));
                }
            }
            Request::Grown => {}
        }
    }

    fn message(&mut self, m: &WorldMessage) {
        match self.mirror.handle(m) {
            Err(e) => {
                tracing::error!("upstream stream refused: {e}; re-joining, and nothing of it is passed on");
                self.metrics.upstream.rejected.inc();
                self.rejected = true;
                self.rejoin.notify_one();
            }
            Ok(Progress::Snapshot) => {}
            Ok(Progress::Delta) => self.publish_delta(m),
            Ok(Progress::Ready) => self.ready(),
            Ok(Progress::Presence) => self.presence.replace(self.mirror.presence().to_vec()),
        }
    }

    /// The mirror's state: `(version, digest)`.
    fn state(&self) -> (u64, u64) {
        let w = self.mirror.world().expect("a live mirror has a world");
        (w.version(), w.digest().0)
    }

    /// Publishes the delta `m`, which the mirror has just accepted, exactly as received.
    fn publish_delta(&mut self, m: &WorldMessage) {
        let (Some(pages), Some(publisher)) = (self.pages.as_mut(), self.publisher.as_mut()) else {
            return;
        };
        let world = self.mirror.world().expect("a live mirror has a world");
        let changes = pages.update(world);
        let change = self.mirror.last_change().expect("a delta was applied");
        let patches = self.patches.as_mut().expect("set with the pages");
        let user = match &m.kind {
            Some(world_message::Kind::Delta(d)) => d.user.as_str(),
            _ => "",
        };
        let event = Arc::new(Event {
            version: world.version(),
            growth_seq: self.mirror.growth_seq(),
            digest: world.digest().0,
            message: m.clone(),
            patch: patch_delta(patches.patch(world, change), world.digest().0, user),
            changes,
            lens: pages.lens(),
        });
        self.published = (event.version, event.digest);
        self.view = None;
        self.metrics.version.set(event.version as i64);
        publisher.publish(event);
    }

    /// A snapshot completed, or a resume was accepted: the mirror is live again.
    fn ready(&mut self) {
        self.metrics.upstream.connected.set(1);
        let state = self.state();
        let world = self.mirror.world().expect("a live mirror has a world");
        self.view = None;
        self.metrics.version.set(state.0 as i64);
        // Patches follow the mirror's buffers from here on, whatever the re-join changed.
        self.patches = Some(PatchMaker::new(world));
        match (&mut self.pages, &mut self.publisher) {
            (Some(pages), Some(publisher)) => {
                let changed = !pages.update(world).is_empty();
                if changed || state != self.published {
                    tracing::info!(
                        version = state.0,
                        "upstream could not resume this relay; re-sending its clients what changed"
                    );
                    publisher.restart(state);
                }
            }
            _ => {
                self.pages = Some(PageStore::new(world));
                self.publisher = Some(Publisher::new(state, self.capacity));
            }
        }
        self.published = state;
        for (resume, reply) in std::mem::take(&mut self.waiting) {
            self.request(Request::Join { resume, reply });
        }
    }

    fn view(&mut self) -> Arc<SnapshotView> {
        let (w, pages) = (
            self.mirror.world().expect("a live mirror has a world"),
            self.pages.as_ref().expect("pages"),
        );
        let (quiescent, growth_seq) = (self.mirror.is_quiescent(), self.mirror.growth_seq());
        self.view
            .get_or_insert_with(|| {
                Arc::new(SnapshotView {
                    size: w.size().voxels(),
                    version: w.version(),
                    growth_seq,
                    quiescent,
                    digest: w.digest(),
                    lens: pages.lens(),
                    pages: pages.pages(),
                    entity_table: w.entity_table().encode(),
                })
            })
            .clone()
    }
}

//! One client's world stream: the cache-aware snapshot, then every delta in order, until
//! the client leaves or falls behind.
//!
//! The task knows which page hashes the client holds: those of its cache, then those of
//! every snapshot and delta it was sent. A client falls behind when it is more deltas
//! behind than the broadcast holds, or more bytes than the
//! [`SlowClientLimits`](crate::shared::SlowClientLimits) allow; its stream is then cut
//! ([`FELL_BEHIND`]): everything queued for it is dropped at once and the stream ends with
//! `ABORTED`, so the actor and the other clients never wait for a slow one and a client
//! that does not read pins nothing. The client joins again announcing what it holds.
//! When the published stream starts over at a state that does not follow (a relay's
//! upstream could not resume it), the task instead sends, in the same stream, a fresh
//! header and the pages whose hash differs from what the client holds.

use crate::data::pages::{PAGED, SnapshotView, StoredPage, paged_buffers};
use crate::shared::Shared;
use crate::stream::feed::{Feed, Item, feed};
use crate::stream::messages::Request;
use crate::stream::messages::{Event, Subscription};
use crate::stream::presence::Table;
use naadf_proto::PROTOCOL_VERSION;
use naadf_proto::snapshot::group_pages;
use naadf_proto::v1::{
    BufferLength, CachedBuffer, DeltaForm, Header, JoinRequest, Page, Presence, WorldMessage, world_message,
};
use naadf_world::digest::PAGE_BYTES;
use naadf_world::file::TRANSFERRED;
use prost::Message;
use std::collections::VecDeque;
use std::sync::Arc;
use tokio::sync::{broadcast, mpsc, oneshot, watch};
use tonic::Status;

/// Most page hashes a join request may announce (far more than the largest world has).
pub const MAX_CACHED_PAGES: usize = 1 << 22;

/// The page hashes a client holds, by buffer id.
pub type ClientPages = [Vec<u64>; PAGED];

/// Checks and arranges a join request's cache.
pub fn client_pages(cached: &[CachedBuffer]) -> Result<ClientPages, Status> {
    let mut out: ClientPages = Default::default();
    let total: usize = cached.iter().map(|c| c.page_hashes.len()).sum();
    if total > MAX_CACHED_PAGES {
        return Err(Status::invalid_argument(format!(
            "the cache lists {total} pages; at most {MAX_CACHED_PAGES} are accepted"
        )));
    }
    for c in cached {
        let slot = out.get_mut(c.buffer as usize).ok_or_else(|| {
            Status::invalid_argument(format!(
                "the cache names buffer {}, which is not a world buffer",
                c.buffer
            ))
        })?;
        *slot = c.page_hashes.clone();
    }
    Ok(out)
}

/// Messages buffered per client stream before the join task waits for the client.
const STREAM_BUFFER: usize = 64;

/// The message of the `ABORTED` status that ends the stream of a client that fell behind.
pub const FELL_BEHIND: &str = "this client fell behind the world stream; join again announcing the world it holds";

/// Starts streaming the world to `user`, who sent `req`: checks the protocol version and
/// the announced cache, then spawns the task that runs `run` (counted in the metrics and
/// on the status page) and returns the stream it feeds.
pub fn start(
    shared: Arc<Shared>,
    actor: mpsc::Sender<Request>,
    user: String,
    req: JoinRequest,
) -> Result<Feed, Status> {
    if req.protocol_version != PROTOCOL_VERSION {
        return Err(Status::failed_precondition(format!(
            "client speaks protocol {}, this server speaks {PROTOCOL_VERSION}; upgrade the client",
            req.protocol_version
        )));
    }
    let held = client_pages(&req.cached)?;
    let form = DeltaForm::try_from(req.delta_form)
        .map_err(|_| Status::invalid_argument(format!("unknown delta form {}", req.delta_form)))?;
    let resume = req.resume.map(|r| (r.version, r.digest));
    let presence = req.presence.then(|| {
        // The table as it is now goes out after the snapshot, then every change.
        let mut table = shared.presence.subscribe();
        table.mark_changed();
        table
    });
    let (tx, rx, cut) = feed(STREAM_BUFFER);
    tokio::spawn(async move {
        let id = shared.activity.joined(&user);
        shared.metrics.clients.inc();
        // The outbox (the queue's sender) lives until after a cut: were it dropped first,
        // the transport could find the queue closed and end the stream without the status.
        let mut out = Outbox::new(shared.clone(), tx, form);
        // Shutdown ends the task wherever it waits (for room in a stream nobody reads, say):
        // it holds a sender of the actor's mailbox, which the actor outlives only until the
        // last sender is gone.
        let mut shutdown = shared.shutdown.clone();
        let ended = tokio::select! {
            ended = run(&shared, actor, held, resume, presence, &mut out) => ended,
            _ = shutdown.wait_for(|&down| down) => Ok(()),
        };
        if let Err(Stop::Behind(behind)) = ended {
            tracing::info!(behind, "client fell behind; ending its stream");
            shared.metrics.resyncs.inc();
            cut.end(Status::aborted(FELL_BEHIND));
        }
        shared.metrics.clients.dec();
        shared.activity.left(id);
    });
    Ok(rx)
}

/// Streams the world to one client through `out` until it leaves, the server shuts down
/// (both `Ok`) or the client falls behind. `resume` is the state the client's cache holds,
/// `(version, digest)`; `presence`, the presence table, if the client asked for it.
async fn run(
    shared: &Shared,
    actor: mpsc::Sender<Request>,
    mut held: ClientPages,
    resume: Option<(u64, u64)>,
    mut presence: Option<watch::Receiver<Table>>,
    out: &mut Outbox,
) -> Result<(), Stop> {
    let mut shutdown = shared.shutdown.clone();
    let mut resync = false;
    loop {
        if resync {
            shared.metrics.resyncs.inc();
            // The new snapshot and subscription start once the client has read everything
            // queued for it (or, not reading, is cut meanwhile by its bound).
            tokio::select! {
                room = out.tx.reserve_many(out.tx.max_capacity()) => if room.is_err() { return Ok(()) },
                _ = shutdown.changed() => return Ok(()),
            }
        }
        let from = resume.filter(|_| !resync);
        let Some(sub) = subscribe(&actor, from).await else {
            return Ok(());
        };
        out.attach(sub.events, sub.start, sub.head);
        match (sub.catch_up, from) {
            (Some(events), Some((version, digest))) => {
                send_catch_up(out, &sub.view, version, digest, &events, &mut held).await?
            }
            _ => send_snapshot(out, &sub.view, &mut held, resync).await?,
        };
        // Forward deltas until the publisher starts over (the subscription is dropped).
        while let Some(rx) = out.events.as_mut() {
            let next = tokio::select! {
                r = rx.recv() => r,
                _ = shutdown.changed() => return Ok(()),
                // The client went away while nothing was being sent.
                _ = out.tx.closed() => return Ok(()),
                table = next_table(&mut presence) => {
                    out.send(table).await?;
                    continue;
                }
            };
            match next {
                Ok(ev) => {
                    out.pos += ev.size() as u64;
                    track(&mut held, &ev);
                    out.send_delta(&ev).await?;
                }
                // More deltas behind than the broadcast holds.
                Err(broadcast::error::RecvError::Lagged(_)) => {
                    return Err(Stop::Behind(out.head.borrow().saturating_sub(out.pos)));
                }
                // The publisher started over at a state that does not follow from what
                // was published (a relay whose upstream could not resume it), or is gone
                // (then the next subscription finds no actor and the stream ends).
                Err(broadcast::error::RecvError::Closed) => out.detach(),
            }
        }
        resync = true;
    }
}

/// The presence table once it changed, as a stream message; never without `presence`.
async fn next_table(presence: &mut Option<watch::Receiver<Table>>) -> WorldMessage {
    let Some(table) = presence else {
        return std::future::pending().await;
    };
    if table.changed().await.is_err() {
        // The table is gone with the server: nothing more to send.
        return std::future::pending().await;
    }
    let entries = table.borrow_and_update().to_vec();
    message(world_message::Kind::Presence(Presence { entries }))
}

/// Why a client's stream stops early.
enum Stop {
    /// The client went away, or the server is shutting down.
    Gone,
    /// The client fell behind, this many bytes: its stream is cut.
    Behind(u64),
}

/// The sizes of the messages handed to a client's stream, oldest first.
#[derive(Default)]
struct Queue {
    sizes: VecDeque<u64>,
    bytes: u64,
}

impl Queue {
    /// Bytes still queued in `tx`: the stream's transport has taken the oldest messages.
    fn pending(&mut self, tx: &mpsc::Sender<Item>) -> u64 {
        let queued = tx.max_capacity() - tx.capacity();
        while self.sizes.len() > queued {
            self.bytes -= self.sizes.pop_front().expect("non-empty");
        }
        self.bytes
    }
}

/// One client's stream and its backlog. What a client that does not read pins is the
/// published deltas it has not taken from its subscription (the broadcast keeps each one
/// until every subscriber has taken it) plus the messages queued in its stream; the
/// transport beyond holds at most about one more message. Once the backlog is over the
/// [`SlowClientLimits`], sending stops with [`Stop::Behind`] and the stream is cut, which
/// releases both.
struct Outbox {
    shared: Arc<Shared>,
    tx: mpsc::Sender<Item>,
    queue: Queue,
    /// The subscription, while the client keeps up.
    events: Option<broadcast::Receiver<Arc<Event>>>,
    /// Published bytes up to the subscription's position.
    pos: u64,
    /// Published bytes in all.
    head: watch::Receiver<u64>,
    /// The handle of this client's backlog in the metrics.
    id: u64,
    /// The form of the deltas the client asked for.
    form: DeltaForm,
}

impl Outbox {
    fn new(shared: Arc<Shared>, tx: mpsc::Sender<Item>, form: DeltaForm) -> Self {
        let id = shared.metrics.backlogs.register();
        Self {
            shared,
            tx,
            form,
            queue: Queue::default(),
            events: None,
            pos: 0,
            head: watch::channel(0).1,
            id,
        }
    }

    /// Follows a new subscription, at position `start`.
    fn attach(&mut self, events: broadcast::Receiver<Arc<Event>>, start: u64, head: watch::Receiver<u64>) {
        self.events = Some(events);
        self.pos = start;
        self.head = head;
    }

    /// Drops the subscription, releasing the deltas it pins; what is queued stays.
    fn detach(&mut self) {
        self.events = None;
        self.shared.metrics.backlogs.set(self.id, self.queue.bytes, false);
    }

    /// Queues the delta of `ev` in the client's form, as [`Outbox::send`] does.
    async fn send_delta(&mut self, ev: &Event) -> Result<(), Stop> {
        self.send(ev.delta(self.form).clone()).await
    }

    /// Queues `m` once the stream has room, or stops with [`Stop::Behind`] if the backlog
    /// goes over the limits first.
    async fn send(&mut self, m: WorldMessage) -> Result<(), Stop> {
        let size = m.encoded_len() as u64;
        let Self {
            shared,
            tx,
            queue,
            events,
            pos,
            head,
            id,
            ..
        } = self;
        let permit = if events.is_none() {
            tx.reserve().await
        } else {
            let limits = shared.slow_clients;
            let mut behind = 0;
            // Only whether it came matters: the value borrowed from the watch is not `Send`.
            let over = async {
                head.wait_for(|&h| {
                    let queued = queue.pending(tx);
                    behind = h.saturating_sub(*pos) + queued + size;
                    limits.exceeded(behind, queued, shared.metrics.backlogs.set(*id, behind, true))
                })
                .await
                .is_ok()
            };
            // The bound is checked first: a stream with room must not take more than it
            // allows either.
            let room = tokio::select! {
                biased;
                published = over => if published {
                    None
                } else {
                    // The committer is gone: nothing more gets published.
                    Some(tx.reserve().await)
                },
                room = tx.reserve() => Some(room),
            };
            room.ok_or(Stop::Behind(behind))?
        }
        .map_err(|_| Stop::Gone)?;
        self.shared.metrics.bytes_sent.inc_by(size);
        permit.send(Ok(m));
        self.queue.sizes.push_back(size);
        self.queue.bytes += size;
        let mut behind = self.queue.pending(&self.tx);
        let subscribed = self.events.is_some();
        if subscribed {
            behind += self.head.borrow().saturating_sub(self.pos);
        }
        self.shared.metrics.backlogs.set(self.id, behind, subscribed);
        Ok(())
    }
}

impl Drop for Outbox {
    fn drop(&mut self) {
        self.shared.metrics.backlogs.remove(self.id);
    }
}

async fn subscribe(actor: &mpsc::Sender<Request>, resume: Option<(u64, u64)>) -> Option<Subscription> {
    let (reply, rx) = oneshot::channel();
    actor.send(Request::Join { resume, reply }).await.ok()?;
    rx.await.ok()
}

/// Resumes a client from its cached state: a header naming that state, then the deltas
/// from it to the view.
async fn send_catch_up(
    out: &mut Outbox,
    view: &SnapshotView,
    version: u64,
    digest: u64,
    events: &[Arc<Event>],
    held: &mut ClientPages,
) -> Result<(), Stop> {
    let header = Header {
        protocol_version: PROTOCOL_VERSION,
        size: view.size.to_vec(),
        version,
        growth_seq: 0,
        quiescent: events.is_empty() && view.quiescent,
        digest,
        buffers: Vec::new(),
        entity_table: Vec::new(),
        pages: 0,
        resync: false,
        resume: true,
    };
    out.send(message(world_message::Kind::Header(header))).await?;
    for ev in events {
        track(held, ev);
        out.send_delta(ev).await?;
    }
    Ok(())
}

/// Updates the client's page hashes with a delta it is being sent.
fn track(held: &mut ClientPages, ev: &Event) {
    for &(slot, k, h) in &ev.changes {
        let v = &mut held[slot as usize];
        if v.len() <= k as usize {
            v.resize(k as usize + 1, 0);
        }
        v[k as usize] = h;
    }
    for (v, len) in held.iter_mut().zip(ev.lens) {
        v.truncate(len.div_ceil(PAGE_BYTES));
    }
}

/// A stream message.
fn message(kind: world_message::Kind) -> WorldMessage {
    WorldMessage { kind: Some(kind) }
}

/// Sends the header and the pages of `view` the client lacks, of the buffers its form is
/// sent ([`paged_buffers`]); afterwards the client holds exactly the view's pages of them.
async fn send_snapshot(
    out: &mut Outbox,
    view: &Arc<SnapshotView>,
    held: &mut ClientPages,
    resync: bool,
) -> Result<(), Stop> {
    let sent = paged_buffers(out.form);
    let mut groups = Vec::new();
    for &id in sent {
        let (slot, pages) = (id as usize, &view.pages[id as usize]);
        let wanted: Vec<u32> = (0..pages.len())
            .filter(|&k| held[slot].get(k) != Some(&pages[k].hash))
            .map(|k| k as u32)
            .collect();
        groups.extend(group_pages(&wanted).into_iter().map(|g| (slot, g)));
    }
    let header = Header {
        protocol_version: PROTOCOL_VERSION,
        size: view.size.to_vec(),
        version: view.version,
        growth_seq: view.growth_seq,
        quiescent: view.quiescent,
        digest: view.digest.0,
        // The entity buffers are listed only when they hold anything, so that the snapshot
        // of a world without entities is the same bytes in both forms.
        buffers: sent
            .iter()
            .filter(|&&id| view.lens[id as usize] > 0 || TRANSFERRED.contains(&id))
            .map(|&id| BufferLength {
                buffer: id as u32,
                bytes: view.lens[id as usize] as u64,
            })
            .collect(),
        entity_table: view.entity_table.clone(),
        pages: groups.len() as u32,
        resync,
        resume: false,
    };
    out.send(message(world_message::Kind::Header(header))).await?;
    // Compress (or fetch from the shared cache) off the async threads, a few groups at a
    // time so that sending starts early.
    for part in groups.chunks(8) {
        let part = part.to_vec();
        let (s, v) = (out.shared.clone(), view.clone());
        let frames = tokio::task::spawn_blocking(move || {
            let pages: Vec<Vec<&StoredPage>> = part
                .iter()
                .map(|(slot, g)| g.iter().map(|&k| &v.pages[*slot][k as usize]).collect())
                .collect();
            let frames = s.page_cache.frames(&pages, &v);
            part.into_iter().zip(frames).collect::<Vec<_>>()
        })
        .await
        .map_err(|_| Stop::Gone)?;
        for ((slot, indices), frame) in frames {
            let page = Page {
                buffer: slot as u32,
                indices,
                zstd: frame.as_ref().clone(),
            };
            out.send(message(world_message::Kind::Page(page))).await?;
        }
    }
    for &id in sent {
        held[id as usize] = view.pages[id as usize].iter().map(|p| p.hash).collect();
    }
    Ok(())
}

//! One client's world stream: the cache-aware snapshot, then every delta in order, and a
//! fresh cache-aware snapshot in the same stream when the client falls behind.
//!
//! The task knows which page hashes the client holds: those of its cache, then those of
//! every snapshot and delta it was sent. When the subscription lags (the client stopped
//! reading while the bounded broadcast moved on), the task takes a new snapshot and sends
//! only the pages whose hash differs from what the client holds, so the actor and the other
//! clients never wait for a slow one.

use crate::Shared;
use crate::actor::Request;
use crate::messages::{Event, Subscription};
use crate::pages::{SnapshotView, StoredPage};
use naadf_proto::PROTOCOL_VERSION;
use naadf_proto::snapshot::{buffer_lengths, group_pages};
use naadf_proto::v1::{CachedBuffer, Header, Page, WorldMessage, world_message};
use naadf_world::digest::PAGE_BYTES;
use naadf_world::file::TRANSFERRED;
use prost::Message;
use std::sync::Arc;
use tokio::sync::{broadcast, mpsc, oneshot};
use tonic::Status;

/// Most page hashes a join request may announce (far more than the largest world has).
pub const MAX_CACHED_PAGES: usize = 1 << 22;

/// The page hashes a client holds, per transferred buffer.
pub type ClientPages = [Vec<u64>; 6];

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
        let slot = naadf_proto::snapshot::slot_of(c.buffer).map_err(|e| Status::invalid_argument(e.to_string()))?;
        out[slot] = c.page_hashes.clone();
    }
    Ok(out)
}

/// Streams the world to one client until it leaves or the server shuts down. `resume` is
/// the state the client's cache holds, `(version, digest)`.
pub async fn run(
    shared: Arc<Shared>,
    actor: mpsc::Sender<Request>,
    mut held: ClientPages,
    resume: Option<(u64, u64)>,
    tx: mpsc::Sender<Result<WorldMessage, Status>>,
) {
    let mut shutdown = shared.shutdown.clone();
    let Some(sub) = subscribe(&actor, resume).await else {
        return;
    };
    let mut rx = sub.events;
    let started = match (sub.catch_up, resume) {
        (Some(events), Some((version, digest))) => {
            send_catch_up(&shared, &sub.view, version, digest, &events, &mut held, &tx).await
        }
        _ => send_snapshot(&shared, &sub.view, &mut held, false, &tx).await,
    };
    if started.is_err() {
        return;
    }
    loop {
        let next = tokio::select! {
            r = rx.recv() => r,
            _ = shutdown.changed() => return,
            // The client went away while nothing was being sent.
            _ = tx.closed() => return,
        };
        match next {
            Ok(ev) => {
                track(&mut held, &ev);
                if send(&shared, &tx, ev.message.clone()).await.is_err() {
                    return;
                }
            }
            Err(broadcast::error::RecvError::Lagged(missed)) => {
                tracing::info!(missed, "client fell behind; re-sending a snapshot");
                shared.metrics.resyncs.inc();
                let Some(sub) = subscribe(&actor, None).await else {
                    return;
                };
                rx = sub.events;
                if send_snapshot(&shared, &sub.view, &mut held, true, &tx).await.is_err() {
                    return;
                }
            }
            Err(broadcast::error::RecvError::Closed) => return,
        }
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
    shared: &Arc<Shared>,
    view: &SnapshotView,
    version: u64,
    digest: u64,
    events: &[Arc<Event>],
    held: &mut ClientPages,
    tx: &mpsc::Sender<Result<WorldMessage, Status>>,
) -> Result<(), ()> {
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
    send(shared, tx, message(world_message::Kind::Header(header))).await?;
    for ev in events {
        track(held, ev);
        send(shared, tx, ev.message.clone()).await?;
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

async fn send(shared: &Shared, tx: &mpsc::Sender<Result<WorldMessage, Status>>, m: WorldMessage) -> Result<(), ()> {
    shared.metrics.bytes_sent.inc_by(m.encoded_len() as u64);
    tx.send(Ok(m)).await.map_err(|_| ())
}

/// Sends the header and the pages of `view` the client lacks; afterwards the client holds
/// exactly the view's pages.
async fn send_snapshot(
    shared: &Arc<Shared>,
    view: &Arc<SnapshotView>,
    held: &mut ClientPages,
    resync: bool,
    tx: &mpsc::Sender<Result<WorldMessage, Status>>,
) -> Result<(), ()> {
    let mut groups = Vec::new();
    for (slot, pages) in view.pages.iter().enumerate() {
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
        buffers: buffer_lengths(view.lens),
        entity_table: view.entity_table.clone(),
        pages: groups.len() as u32,
        resync,
        resume: false,
    };
    send(shared, tx, message(world_message::Kind::Header(header))).await?;
    // Compress (or fetch from the shared cache) off the async threads, a few groups at a
    // time so that sending starts early.
    for part in groups.chunks(8) {
        let part = part.to_vec();
        let (s, v) = (shared.clone(), view.clone());
        let frames = tokio::task::spawn_blocking(move || {
            let pages: Vec<Vec<&StoredPage>> = part
                .iter()
                .map(|(slot, g)| g.iter().map(|&k| &v.pages[*slot][k as usize]).collect())
                .collect();
            let frames = s.page_cache.frames(&pages, &v);
            part.into_iter().zip(frames).collect::<Vec<_>>()
        })
        .await
        .map_err(|_| ())?;
        for ((slot, indices), frame) in frames {
            let page = Page {
                buffer: TRANSFERRED[slot] as u32,
                indices,
                zstd: frame.as_ref().clone(),
            };
            send(shared, tx, message(world_message::Kind::Page(page))).await?;
        }
    }
    for (slot, pages) in view.pages.iter().enumerate() {
        held[slot] = pages.iter().map(|p| p.hash).collect();
    }
    Ok(())
}

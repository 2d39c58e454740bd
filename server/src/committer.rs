//! The committer: makes batches durable (group commit), then publishes and acknowledges
//! everything the actor produced, in the actor's order.
//!
//! It takes whatever has queued up, appends all log records of the group, fsyncs once, and
//! only then broadcasts the deltas and answers the senders. Growth steps, duplicate-retry
//! answers and join subscriptions travel through the same queue, so they can never
//! overtake a batch that is not durable yet: a join's snapshot and its subscription line
//! up exactly with the published sequence.
//!
//! A log that cannot be written stops the process: the actor has already applied the
//! batches in memory, and continuing would publish versions that a restart would lose.

use crate::messages::{Event, Outgoing, Subscription};
use crate::metrics::Metrics;
use crate::pages::SnapshotView;
use crate::store::DataDir;
use crate::wal::Wal;
use naadf_proto::v1::EditReply;
use std::sync::Arc;
use std::time::Instant;
use tokio::sync::{broadcast, mpsc, watch};

/// Most queued items committed as one group.
const MAX_GROUP: usize = 1024;

/// Most recent deltas kept for resuming clients.
const HISTORY_EVENTS: usize = 8192;
/// Most bytes of recent deltas kept for resuming clients.
const HISTORY_BYTES: usize = 32 << 20;

/// The recent deltas, for resuming clients.
#[derive(Debug)]
struct History {
    /// The state before the oldest kept delta: `(version, digest)`.
    base: (u64, u64),
    events: std::collections::VecDeque<Arc<Event>>,
    bytes: usize,
}

impl History {
    fn push(&mut self, e: &Arc<Event>) {
        self.bytes += e.size();
        self.events.push_back(e.clone());
        while self.events.len() > HISTORY_EVENTS || self.bytes > HISTORY_BYTES {
            let old = self.events.pop_front().expect("non-empty");
            self.bytes -= old.size();
            self.base = (old.version, old.digest);
        }
    }

    /// The deltas after the state `(version, digest)`, if that state is `view` itself or
    /// still in the history.
    fn after(&self, (version, digest): (u64, u64), view: &SnapshotView) -> Option<Vec<Arc<Event>>> {
        if view.version == version && view.digest.0 == digest {
            return Some(Vec::new());
        }
        let from = match self
            .events
            .iter()
            .rposition(|e| e.version == version && e.digest == digest)
        {
            Some(at) => at + 1,
            None if self.base == (version, digest) => 0,
            None => return None,
        };
        Some(self.events.range(from..).cloned().collect())
    }
}

/// The durability point between the actor and everyone else: the only writer of the log and
/// of snapshots, and the only publisher of deltas and edit answers (see the module docs).
pub struct Committer {
    /// The write-ahead log every applied batch is appended to (and synced) before it is
    /// published.
    pub wal: Wal,
    /// The data directory (snapshots).
    pub data: Arc<DataDir>,
    /// Where deltas are published.
    pub events: broadcast::Sender<Arc<Event>>,
    /// Where fsync latencies and written snapshots are counted.
    pub metrics: Arc<Metrics>,
    /// The state the server starts from: `(version, digest)`.
    pub initial: (u64, u64),
}

fn fatal(what: &str, e: impl std::fmt::Display) -> ! {
    tracing::error!("{what}: {e}; stopping so that a restart recovers the durable state");
    std::process::exit(70);
}

impl Committer {
    /// Runs until the actor is gone, then waits for a snapshot still being written.
    pub fn run(mut self, mut rx: mpsc::Receiver<Outgoing>) {
        let mut writer: Option<std::thread::JoinHandle<()>> = None;
        let mut history = History {
            base: self.initial,
            events: Default::default(),
            bytes: 0,
        };
        // Bytes published so far: join tasks measure their backlog against it.
        let (head, _) = watch::channel(0u64);
        while let Some(first) = rx.blocking_recv() {
            let mut group = vec![first];
            while group.len() < MAX_GROUP {
                match rx.try_recv() {
                    Ok(o) => group.push(o),
                    Err(_) => break,
                }
            }
            // 1. Log records in order; a checkpoint starts a new segment at its place.
            let mut logged = false;
            for o in &group {
                match o {
                    Outgoing::Batch { frame, .. } => {
                        self.wal.append(frame).unwrap_or_else(|e| fatal("write-ahead log", e));
                        logged = true;
                    }
                    Outgoing::Checkpoint { parts, .. } => {
                        self.wal
                            .rotate(parts.version)
                            .unwrap_or_else(|e| fatal("write-ahead log", e));
                    }
                    _ => {}
                }
            }
            // 2. One fsync for the group.
            if logged {
                let t = Instant::now();
                self.wal.sync().unwrap_or_else(|e| fatal("write-ahead log", e));
                self.metrics.fsync.observe(t.elapsed().as_secs_f64());
            }
            // 3. Publish and answer, in order.
            for o in group {
                match o {
                    Outgoing::Batch { event, reply, .. } => {
                        let version = event.version;
                        history.push(&event);
                        head.send_modify(|h| *h += event.size() as u64);
                        let _ = self.events.send(event);
                        let _ = reply.send(Ok(EditReply {
                            version,
                            duplicate: false,
                        }));
                    }
                    Outgoing::Growth { event } => {
                        history.push(&event);
                        head.send_modify(|h| *h += event.size() as u64);
                        let _ = self.events.send(event);
                    }
                    Outgoing::Ack { reply, result } => {
                        let _ = reply.send(result);
                    }
                    Outgoing::Join { view, resume, reply } => {
                        let catch_up = resume.and_then(|r| history.after(r, &view));
                        let _ = reply.send(Subscription {
                            events: self.events.subscribe(),
                            catch_up,
                            view,
                            start: *head.borrow(),
                            head: head.subscribe(),
                        });
                    }
                    Outgoing::Checkpoint { parts, state, reply } => {
                        // One snapshot at a time; the log keeps going meanwhile.
                        if let Some(w) = writer.take() {
                            let _ = w.join();
                        }
                        let data = self.data.clone();
                        let metrics = self.metrics.clone();
                        writer = Some(std::thread::spawn(move || {
                            let version = parts.version;
                            let t = Instant::now();
                            let result = data
                                .save(&parts, &state)
                                .and_then(|()| data.prune(version))
                                .map(|()| version)
                                .map_err(|e| e.to_string());
                            match &result {
                                Ok(_) => {
                                    metrics.snapshots.inc();
                                    tracing::info!(version, secs = t.elapsed().as_secs_f64(), "snapshot written");
                                }
                                Err(e) => tracing::error!(version, "snapshot failed: {e}"),
                            }
                            if let Some(r) = reply {
                                let _ = r.send(result);
                            }
                        }));
                    }
                }
            }
        }
        if let Some(w) = writer {
            let _ = w.join();
        }
    }
}

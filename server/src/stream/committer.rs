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

use crate::data::store::DataDir;
use crate::data::wal::Wal;
use crate::metrics::Metrics;
use crate::stream::messages::Outgoing;
use crate::stream::publisher::Publisher;
use naadf_proto::v1::EditReply;
use std::sync::Arc;
use std::time::Instant;
use tokio::sync::mpsc;

/// Most queued items committed as one group.
const MAX_GROUP: usize = 1024;

/// The durability point between the actor and everyone else: the only writer of the log and
/// of snapshots, and the only publisher of deltas and edit answers (see the module docs).
pub struct Committer {
    /// The write-ahead log every applied batch is appended to (and synced) before it is
    /// published.
    pub wal: Wal,
    /// The data directory (snapshots).
    pub data: Arc<DataDir>,
    /// Where deltas are published.
    pub publisher: Publisher,
    /// Where fsync latencies and written snapshots are counted.
    pub metrics: Arc<Metrics>,
}

fn fatal(what: &str, e: impl std::fmt::Display) -> ! {
    tracing::error!("{what}: {e}; stopping so that a restart recovers the durable state");
    std::process::exit(70);
}

impl Committer {
    /// Runs until the actor is gone, then waits for a snapshot still being written.
    pub fn run(mut self, mut rx: mpsc::Receiver<Outgoing>) {
        let mut writer: Option<std::thread::JoinHandle<()>> = None;
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
                        self.publisher.publish(event);
                        let _ = reply.send(Ok(EditReply {
                            version,
                            duplicate: false,
                        }));
                    }
                    Outgoing::Growth { event } => self.publisher.publish(event),
                    Outgoing::Ack { reply, result } => {
                        let _ = reply.send(result);
                    }
                    Outgoing::Join { view, resume, reply } => {
                        let _ = reply.send(self.publisher.subscribe(view, resume));
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

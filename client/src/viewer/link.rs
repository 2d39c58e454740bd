//! [`Link`]: the viewer's connection to the server. The world stream, status polls,
//! presence and edit replies run on a small tokio runtime and reach the window's thread as [`Event`]s;
//! the world itself is only touched on that thread.

use super::error::ViewerError;
use crate::client::{Client, PresenceUpdate, ServerAddress};
use crate::connect::session_client_seq;
use naadf_proto::v1::{JoinRequest, WorldMessage};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::time::Duration;

/// How often the server's status (client count) is asked for.
const STATUS_PERIOD: Duration = Duration::from_secs(1);

/// What the network side reports to the window.
#[derive(Debug)]
pub enum Event {
    /// A message of the world stream, to apply in order.
    Message(Box<WorldMessage>),
    /// The stream ended: why, and whether rejoining is pointless (the join itself was
    /// refused for authentication, permission or protocol reasons).
    StreamEnded {
        /// The reason.
        why: String,
        /// A refusal that a retry would meet again.
        fatal: bool,
    },
    /// Clients connected to the server, from the latest status poll.
    Clients(u32),
    /// An edit was acknowledged at this version, or failed with this message.
    Edited(Result<u64, String>),
}

/// The connection: one client shared by the stream, status and edit tasks.
pub struct Link {
    runtime: tokio::runtime::Runtime,
    client: Client,
    next_seq: Arc<AtomicU64>,
    /// Edits sent and not yet answered.
    pending: Arc<AtomicUsize>,
    notify: Arc<dyn Fn(Event) + Send + Sync>,
}

impl Link {
    /// Connects; every event goes to `notify` (called on the runtime's threads).
    pub fn connect(
        server: &ServerAddress,
        notify: impl Fn(Event) + Send + Sync + 'static,
    ) -> Result<Self, ViewerError> {
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
            .map_err(ViewerError::Runtime)?;
        let client = runtime.block_on(server.connect())?;
        let notify: Arc<dyn Fn(Event) + Send + Sync> = Arc::new(notify);
        let (c, n) = (client.clone(), notify.clone());
        runtime.spawn(async move {
            let mut tick = tokio::time::interval(STATUS_PERIOD);
            loop {
                tick.tick().await;
                if let Ok(s) = c.status().await {
                    n(Event::Clients(s.clients));
                }
            }
        });
        Ok(Link {
            runtime,
            client,
            next_seq: Arc::new(AtomicU64::new(session_client_seq())),
            pending: Arc::new(AtomicUsize::new(0)),
            notify,
        })
    }

    /// Joins with `request` (the mirror's cache) and forwards the stream until it ends.
    pub fn join(&self, request: JoinRequest) {
        let (c, n) = (self.client.clone(), self.notify.clone());
        self.runtime.spawn(async move {
            let ended = |why: String, fatal| Event::StreamEnded { why, fatal };
            let mut stream = match c.stream(request).await {
                Ok(s) => s,
                Err(e) => {
                    use tonic::Code::{FailedPrecondition, PermissionDenied, Unauthenticated};
                    let fatal = matches!(e.code(), Some(Unauthenticated | PermissionDenied | FailedPrecondition));
                    return n(ended(e.to_string(), fatal));
                }
            };
            loop {
                match stream.message().await {
                    Ok(Some(m)) => n(Event::Message(Box::new(m))),
                    Ok(None) => return n(ended("the server ended the stream".into(), false)),
                    Err(e) => return n(ended(e.to_string(), false)),
                }
            }
        });
    }

    /// Sends `ops` (Ops JSON, one batch) as an edit; the reply arrives as [`Event::Edited`].
    pub fn edit(&self, ops: String) {
        let (c, n) = (self.client.clone(), self.notify.clone());
        let client_seq = self.next_seq.fetch_add(1, Ordering::Relaxed);
        let pending = self.pending.clone();
        pending.fetch_add(1, Ordering::SeqCst);
        self.runtime.spawn(async move {
            let reply = c.edit(ops, client_seq).await;
            n(Event::Edited(reply.map(|a| a.version).map_err(|e| e.to_string())));
            pending.fetch_sub(1, Ordering::SeqCst);
        });
    }

    /// Publishes where the window looks (docs/PROTOCOL.md, "Presence"); a failure only
    /// leaves the others with an older entry.
    pub fn publish(&self, update: PresenceUpdate) {
        let c = self.client.clone();
        self.runtime.spawn(async move {
            if let Err(e) = c.publish(&update).await {
                tracing::debug!("presence not published: {e}");
            }
        });
    }

    /// Waits up to `limit` for the edits in flight to be answered, so that closing the
    /// window does not drop a click the user just made; returns how many are still open.
    pub fn finish_edits(&self, limit: Duration) -> usize {
        let deadline = std::time::Instant::now() + limit;
        while self.pending.load(Ordering::SeqCst) > 0 && std::time::Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(10));
        }
        self.pending.load(Ordering::SeqCst)
    }
}

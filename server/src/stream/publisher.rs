//! The published change stream: the broadcast every join task follows, the recent deltas
//! kept for resuming clients, and the byte position join tasks measure their backlog by.
//!
//! The server's [committer](crate::stream::committer) publishes each change once it is durable; a
//! [relay](crate::relay) publishes each change its mirror accepted from upstream. Both
//! answer joins with [`Publisher::subscribe`] at the point of the stream the join's
//! snapshot shows, so that a snapshot and its subscription line up exactly.

use crate::data::pages::SnapshotView;
use crate::stream::messages::{Event, Subscription};
use std::collections::VecDeque;
use std::sync::Arc;
use tokio::sync::{broadcast, watch};

/// Most recent deltas kept for resuming clients.
const HISTORY_EVENTS: usize = 8192;
/// Most bytes of recent deltas kept for resuming clients.
const HISTORY_BYTES: usize = 32 << 20;

/// The recent deltas, for resuming clients.
#[derive(Debug)]
struct History {
    /// The state before the oldest kept delta: `(version, digest)`.
    base: (u64, u64),
    events: VecDeque<Arc<Event>>,
    bytes: usize,
}

impl History {
    fn new(base: (u64, u64)) -> Self {
        Self {
            base,
            events: VecDeque::new(),
            bytes: 0,
        }
    }

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

/// Where changes are published, in order, to every subscribed join task.
#[derive(Debug)]
pub struct Publisher {
    events: broadcast::Sender<Arc<Event>>,
    /// How many deltas a subscriber may fall behind before it lags.
    capacity: usize,
    history: History,
    /// Bytes ([`Event::size`]) published so far.
    head: watch::Sender<u64>,
}

impl Publisher {
    /// A publisher starting at the state `(version, digest)`, whose subscribers may fall
    /// `capacity` deltas behind before they are re-sent a snapshot.
    pub fn new(initial: (u64, u64), capacity: usize) -> Self {
        let capacity = capacity.max(16);
        Self {
            events: broadcast::channel(capacity).0,
            capacity,
            history: History::new(initial),
            head: watch::channel(0).0,
        }
    }

    /// Publishes `event` to every subscriber and keeps it for resuming clients.
    pub fn publish(&mut self, event: Arc<Event>) {
        self.history.push(&event);
        self.head.send_modify(|h| *h += event.size() as u64);
        // No subscriber is not an error: the event is kept in the history all the same.
        let _ = self.events.send(event);
    }

    /// A subscription to everything published from now on, with the snapshot `view` of the
    /// state now; when the joining client holds `resume` and the history still reaches
    /// back to it, the deltas from there to `view` come with it.
    pub fn subscribe(&self, view: Arc<SnapshotView>, resume: Option<(u64, u64)>) -> Subscription {
        let catch_up = resume.and_then(|r| self.history.after(r, &view));
        Subscription {
            events: self.events.subscribe(),
            catch_up,
            view,
            start: *self.head.borrow(),
            head: self.head.subscribe(),
        }
    }

    /// Starts over at the state `(version, digest)`, which does not follow from what was
    /// published: the history is dropped and every subscription ends, so that each join
    /// task re-sends its client a snapshot (only the pages it lacks) in the same stream.
    pub fn restart(&mut self, state: (u64, u64)) {
        self.history = History::new(state);
        self.events = broadcast::channel(self.capacity).0;
    }
}

//! [`Feed`]: one client's world stream as the gRPC server reads it, and the [`Cut`] with
//! which its join task ends it at once.
//!
//! The join task queues messages in a bounded channel that the transport drains as the
//! client grants flow-control window. A client that stops reading leaves that queue full,
//! and the transport never polls the stream again while it waits for window, so an error
//! pushed behind the queue would never be read and the queued messages (tens of MiB of
//! pages) would stay for as long as the connection lives. [`Cut::end`] drops the queue
//! itself instead: what the client had not been handed is gone at once, and the next poll
//! of the stream (once the client reads again, or never) yields the ending status.

use naadf_proto::v1::WorldMessage;
use std::pin::Pin;
use std::sync::{Arc, Mutex, PoisonError};
use std::task::{Context, Poll, Waker};
use tokio::sync::mpsc;
use tokio_stream::Stream;
use tonic::Status;

/// What a client's stream carries.
pub type Item = Result<WorldMessage, Status>;

/// The stream handed to the gRPC server: the queued messages in order, and after a
/// [`Cut::end`] its status, then the end.
pub struct Feed {
    slot: Arc<Mutex<Slot>>,
}

/// Ends a [`Feed`] from the join task.
pub struct Cut {
    slot: Arc<Mutex<Slot>>,
}

/// The queue while the stream runs, the status once it was cut.
struct Slot {
    queue: Option<mpsc::Receiver<Item>>,
    ending: Option<Status>,
    /// The transport's waker while it waits for a message, woken by a cut.
    waker: Option<Waker>,
}

/// A queue of `capacity` messages: its sender, the stream that reads it, and its cut.
pub fn feed(capacity: usize) -> (mpsc::Sender<Item>, Feed, Cut) {
    let (tx, rx) = mpsc::channel(capacity);
    let slot = Arc::new(Mutex::new(Slot {
        queue: Some(rx),
        ending: None,
        waker: None,
    }));
    (tx, Feed { slot: slot.clone() }, Cut { slot })
}

/// The slot, also after a panic elsewhere while it was held (it holds no invariant that a
/// panic could break halfway).
fn lock(slot: &Mutex<Slot>) -> std::sync::MutexGuard<'_, Slot> {
    slot.lock().unwrap_or_else(PoisonError::into_inner)
}

impl Cut {
    /// Drops every message still queued and makes `status` the stream's last item; the
    /// queue's sender fails from now on.
    pub fn end(&self, status: Status) {
        let (queue, waker) = {
            let mut slot = lock(&self.slot);
            slot.ending = Some(status);
            (slot.queue.take(), slot.waker.take())
        };
        // Dropped outside the lock: the queued messages may be many and large.
        drop(queue);
        if let Some(w) = waker {
            w.wake();
        }
    }
}

impl Stream for Feed {
    type Item = Item;

    fn poll_next(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Option<Item>> {
        let mut slot = lock(&self.slot);
        let Slot { queue, ending, waker } = &mut *slot;
        match queue {
            Some(rx) => {
                let next = rx.poll_recv(cx);
                if next.is_pending() && !waker.as_ref().is_some_and(|w| w.will_wake(cx.waker())) {
                    *waker = Some(cx.waker().clone());
                }
                next
            }
            None => Poll::Ready(ending.take().map(Err)),
        }
    }
}

impl Drop for Feed {
    /// The transport dropped the stream (the client left): the queue goes with it, so the
    /// join task's sender fails and its wait for room ends, instead of waiting for a reader
    /// that will never come (the [`Cut`] keeps the slot alive).
    fn drop(&mut self) {
        let queue = lock(&self.slot).queue.take();
        drop(queue);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use naadf_proto::v1::{Header, world_message};
    use tokio_stream::StreamExt;

    fn message(version: u64) -> WorldMessage {
        WorldMessage {
            kind: Some(world_message::Kind::Header(Header {
                version,
                ..Default::default()
            })),
        }
    }

    #[tokio::test]
    async fn a_cut_drops_what_is_queued_and_ends_with_its_status() {
        let (tx, mut feed, cut) = feed(4);
        for v in 0..4 {
            tx.send(Ok(message(v))).await.unwrap();
        }
        assert_eq!(feed.next().await.unwrap().unwrap(), message(0));
        assert_eq!(tx.capacity(), 1, "three messages queued");
        cut.end(Status::aborted("fell behind"));
        // The three are gone at the cut, before anyone reads the stream again.
        assert_eq!(tx.capacity(), 4, "nothing queued after the cut");
        assert!(tx.send(Ok(message(5))).await.is_err(), "the sender fails after a cut");
        let ending = feed.next().await.unwrap().unwrap_err();
        assert_eq!((ending.code(), ending.message()), (tonic::Code::Aborted, "fell behind"));
        assert!(feed.next().await.is_none());
    }

    #[tokio::test]
    async fn a_dropped_stream_fails_its_sender_and_frees_its_queue() {
        let (tx, feed, _cut) = feed(2);
        tx.send(Ok(message(0))).await.unwrap();
        tx.send(Ok(message(1))).await.unwrap();
        let waiting = tokio::spawn({
            let tx = tx.clone();
            async move { tx.reserve().await.is_err() }
        });
        tokio::task::yield_now().await;
        drop(feed);
        assert!(waiting.await.unwrap(), "a sender waiting for room fails");
        assert!(tx.is_closed());
        assert_eq!(tx.capacity(), 2, "the queued messages are freed");
    }

    #[tokio::test]
    async fn a_cut_wakes_a_waiting_stream() {
        let (_tx, mut feed, cut) = feed(1);
        let reader = tokio::spawn(async move { feed.next().await.map(|r| r.unwrap_err().code()) });
        tokio::task::yield_now().await;
        cut.end(Status::aborted("behind"));
        assert_eq!(reader.await.unwrap(), Some(tonic::Code::Aborted));
    }
}

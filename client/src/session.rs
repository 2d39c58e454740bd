//! [`Session`]: a joined world stream and the [`Mirror`] it keeps current — what every
//! program that follows a server's world runs: step by step ([`Session::next`]), until
//! the world settles ([`Session::until_quiescent`]), or until told to stop
//! ([`Session::follow`]). [`WorldStream`] is the stream alone, for programs that apply or
//! pass on the messages themselves.

use crate::connect::RawClient;
use crate::error::Error;
use crate::mirror::{Mirror, Progress};
use naadf_proto::v1::{JoinRequest, WorldMessage, world_message};
use naadf_world::World;
use naadf_world::edit::Record;
use std::future::Future;
use std::ops::ControlFlow;
use std::time::Duration;

/// The world stream of one join, not applied to anything.
#[derive(Debug)]
pub struct WorldStream(tonic::Streaming<WorldMessage>);

impl WorldStream {
    /// Opens the world stream with `request`.
    pub(crate) async fn open(raw: &RawClient, request: JoinRequest) -> Result<Self, Error> {
        Ok(Self(raw.clone().join(request).await?.into_inner()))
    }

    /// The next message; `None` once the server ended the stream. Cancel-safe.
    pub async fn message(&mut self) -> Result<Option<WorldMessage>, Error> {
        Ok(self.0.message().await?)
    }
}

/// What a raw stream message carries, for a receiver that does not apply it (the fan-out
/// benchmark's receive-only clients), without naming the wire types.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MessageKind {
    /// A snapshot's header, with the number of pages that follow.
    Header {
        /// Pages of the snapshot.
        pages: u32,
    },
    /// One page of a snapshot.
    Page,
    /// A change, with the version and growth sub-step it produced.
    Delta {
        /// The version.
        version: u64,
        /// The growth sub-step within it (0: the edit itself).
        growth_seq: u32,
    },
    /// The presence table.
    Presence,
    /// A message this client does not know (from a newer server).
    Unknown,
}

impl MessageKind {
    /// What `message` carries; an error for a delta whose record does not decode.
    pub fn of(message: &WorldMessage) -> Result<Self, Error> {
        Ok(match &message.kind {
            Some(world_message::Kind::Header(h)) => MessageKind::Header { pages: h.pages },
            Some(world_message::Kind::Page(_)) => MessageKind::Page,
            Some(world_message::Kind::Presence(_)) => MessageKind::Presence,
            Some(world_message::Kind::Delta(d)) => match &d.patch {
                Some(p) => MessageKind::Delta {
                    version: p.version,
                    growth_seq: p.growth_seq,
                },
                None => {
                    let r =
                        Record::decode(&d.change).map_err(|e| Error::Malformed(format!("a delta's record: {e}")))?;
                    MessageKind::Delta {
                        version: r.version,
                        growth_seq: r.growth_seq,
                    }
                }
            },
            None => MessageKind::Unknown,
        })
    }
}

/// How [`Session::follow`] ended.
#[derive(Debug, PartialEq, Eq)]
pub enum Ended<T> {
    /// The server ended the stream.
    Stream,
    /// The `stop` future resolved, with this value.
    Stopped(T),
    /// The `seen` callback asked to stop.
    Done,
}

/// A mirror following a server's world stream ([`Client::join`](crate::Client::join)).
///
/// ```no_run
/// # async fn demo() -> Result<(), naadf_client::Error> {
/// use naadf_client::{Client, Ended};
/// use std::ops::ControlFlow;
/// let client = Client::connect("http://127.0.0.1:50051", None, None).await?;
/// let mut session = client.join(None).await?;
/// // Print every quiescent state until Ctrl-C.
/// let ended = session
///     .follow(tokio::signal::ctrl_c(), |m| -> Result<_, naadf_client::Error> {
///         if let Some(w) = m.world().filter(|_| m.is_quiescent()) {
///             println!("version {} digest {}", w.version(), w.digest());
///         }
///         Ok(ControlFlow::Continue(()))
///     })
///     .await?;
/// assert!(matches!(ended, Ended::Stopped(_) | Ended::Stream));
/// # Ok(()) }
/// ```
#[derive(Debug)]
pub struct Session {
    raw: RawClient,
    stream: WorldStream,
    mirror: Mirror,
}

impl Session {
    /// Joins with `cache` as the mirror's world, accepting worlds of up to
    /// `max_world_bytes` ([`Mirror::with_max_world_bytes`]).
    pub(crate) async fn start(raw: RawClient, cache: Option<World>, max_world_bytes: u64) -> Result<Self, Error> {
        let mut mirror = Mirror::new(cache).with_max_world_bytes(max_world_bytes);
        let stream = WorldStream::open(&raw, mirror.join_request()).await?;
        Ok(Self { raw, stream, mirror })
    }

    /// The mirror.
    pub fn mirror(&self) -> &Mirror {
        &self.mirror
    }

    /// Takes the mirror out.
    pub fn into_mirror(self) -> Mirror {
        self.mirror
    }

    /// Takes the mirrored world out (none before the first snapshot completed).
    pub fn into_world(self) -> Option<World> {
        self.mirror.into_world()
    }

    /// Keeps the latest edit batch for [`Mirror::last_edit`] (recorders). Call it before
    /// reading the stream to see every batch.
    pub fn keep_edits(&mut self) {
        self.mirror.keep_edits();
    }

    /// Joins again on the same connection (which reconnects by itself), after the stream
    /// ended or failed, announcing the mirror's world: the server resumes it with the
    /// deltas it missed, or sends only the pages that differ. On failure the session keeps
    /// its world for the next attempt.
    pub async fn rejoin(&mut self) -> Result<(), Error> {
        self.stream = WorldStream::open(&self.raw, self.mirror.join_request()).await?;
        Ok(())
    }

    /// Reads and applies the next message: what it did, or `None` once the server ended
    /// the stream. Cancel-safe: a message is applied in full or not read.
    pub async fn next(&mut self) -> Result<Option<Progress>, Error> {
        match self.stream.message().await? {
            Some(m) => Ok(Some(self.mirror.handle(&m)?)),
            None => Ok(None),
        }
    }

    /// Follows the stream until the mirror is live, at `min_version` or later, and
    /// quiescent (at once if it is already), and returns that world; fails with
    /// [`Error::Timeout`] after `timeout` and [`Error::StreamEnded`] if the server ends the
    /// stream first.
    pub async fn until_quiescent(&mut self, min_version: u64, timeout: Duration) -> Result<&World, Error> {
        let reached = |m: &Mirror| m.is_quiescent() && m.world().is_some_and(|w| w.version() >= min_version);
        let wait = async {
            while !reached(&self.mirror) {
                if self.next().await?.is_none() {
                    return Err(Error::StreamEnded);
                }
            }
            Ok(())
        };
        tokio::time::timeout(timeout, wait)
            .await
            .map_err(|_| Error::Timeout(timeout))??;
        Ok(self.mirror.world().expect("a quiescent mirror holds a world"))
    }

    /// Applies the stream until the server ends it, `stop` resolves, or `seen` — called
    /// with the mirror after every message — breaks. Errors of the stream, the mirror and
    /// `seen` end it too.
    pub async fn follow<T, E: From<Error>>(
        &mut self,
        stop: impl Future<Output = T>,
        mut seen: impl FnMut(&Mirror) -> Result<ControlFlow<()>, E>,
    ) -> Result<Ended<T>, E> {
        tokio::pin!(stop);
        loop {
            let progress = tokio::select! {
                p = self.next() => p?,
                v = &mut stop => return Ok(Ended::Stopped(v)),
            };
            if progress.is_none() {
                return Ok(Ended::Stream);
            }
            if seen(&self.mirror)?.is_break() {
                return Ok(Ended::Done);
            }
        }
    }
}

//! Accepted connections, for both listeners: at most a set number at a time, each held to
//! a deadline to be useful and to an idle timeout, room made for newcomers by closing the
//! oldest connection that has not been useful yet, and an accept loop that backs off
//! instead of spinning when the process runs out of file descriptors.
//!
//! A peer that opens a connection and then stalls (an HTTP/2 preface and silence, half an
//! HTTP request trickled a byte at a time, a handshake and nothing but ping answers) would
//! otherwise hold its descriptor, and its place under the cap, for as long as it likes;
//! a few hundred of them lock everyone out. So:
//! - a connection must deliver a complete request head within the **request deadline**
//!   ([`ConnLimits::request_deadline`]), whatever else it sends: bytes, pings and
//!   handshakes do not count ([`HeadScan`] says when a head is complete);
//! - once it has, it is closed only when its peer sends nothing for the **idle timeout**;
//!   live HTTP/2 connections stay busy through the keepalive pings the gRPC server sends
//!   at a third of the timeout (see [`keepalive`]), which the peer must answer;
//! - when a listener is at its cap, the next connection it accepts closes the **oldest
//!   connection without a complete request head** ([`Acceptor::accept`]), so stalled peers
//!   cannot keep a newcomer waiting in the listen backlog.
//!
//! The caps come from the process's descriptor limit unless set ([`Caps::for_fd_limit`]).

use crate::net::head::HeadScan;
use std::collections::VecDeque;
use std::io;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::{Arc, Mutex, PoisonError, Weak};
use std::task::{Context, Poll, Waker};
use std::time::{Duration, Instant};
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{OwnedSemaphorePermit, Semaphore};
use tokio::time::Sleep;

/// How long the accept loop pauses when the process is out of descriptors.
const BACKOFF: Duration = Duration::from_millis(250);
/// Out-of-descriptor errors are logged at most this often.
const WARN_EVERY: Duration = Duration::from_secs(10);

/// A spawned listener's task.
pub(crate) type Listening = tokio::task::JoinHandle<Result<(), Box<dyn std::error::Error + Send + Sync>>>;

/// The connection settings both listeners share.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ConnLimits {
    /// Most connections open at a time on each listener; `None`: [`Caps::for_fd_limit`].
    pub max_connections: Option<usize>,
    /// A connection whose peer sends nothing for this long is closed.
    pub idle_timeout: Duration,
    /// A connection that has not delivered a complete request head this long after it was
    /// accepted is closed.
    pub request_deadline: Duration,
}

impl Default for ConnLimits {
    /// Caps from the descriptor limit, 60 s idle timeout, 10 s request deadline.
    fn default() -> Self {
        Self {
            max_connections: None,
            idle_timeout: Duration::from_secs(60),
            request_deadline: Duration::from_secs(10),
        }
    }
}

/// Descriptors kept back from the connection caps for everything else the process opens:
/// the data directory's files, the listeners, the runtime, a relay's upstream connection.
pub const RESERVED_FDS: u64 = 64;
/// The largest caps the descriptor limit yields, gRPC and HTTP.
const MOST_GRPC: usize = 16384;
const MOST_HTTP: usize = 4096;

/// The connection caps of the two listeners.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Caps {
    /// Most gRPC connections.
    pub grpc: usize,
    /// Most HTTP connections.
    pub http: usize,
}

impl Caps {
    /// The caps for a process that may hold `fd_limit` descriptors: of the limit less
    /// [`RESERVED_FDS`], a quarter for HTTP and the rest for gRPC (at most 4096 and 16384,
    /// at least 2 each). Both caps full, and one connection more on each listener (the one
    /// accepted while room is made for it), still leave the reserve, so `accept` never
    /// fails for want of descriptors, and `/health` has descriptors of its own however
    /// full the gRPC side is.
    ///
    /// ```
    /// use naadf_server::net::conn::Caps;
    /// assert_eq!(Caps::for_fd_limit(256), Caps { grpc: 144, http: 48 });
    /// assert_eq!(Caps::for_fd_limit(1024), Caps { grpc: 720, http: 240 });
    /// assert_eq!(Caps::for_fd_limit(1 << 20), Caps { grpc: 16384, http: 4096 });
    /// ```
    pub fn for_fd_limit(fd_limit: u64) -> Caps {
        let budget = usize::try_from(fd_limit.saturating_sub(RESERVED_FDS)).unwrap_or(usize::MAX);
        let http = budget / 4;
        Caps {
            grpc: (budget - http).clamp(2, MOST_GRPC),
            http: http.clamp(2, MOST_HTTP),
        }
    }

    /// The caps `limits` sets, or the ones the process's descriptor limit allows (after
    /// raising its soft limit to the hard one, as far as the system lets it). A cap set
    /// above what the limit allows is kept, with a warning.
    pub fn resolve(limits: &ConnLimits) -> Caps {
        let fd_limit = raise_fd_limit();
        let fitting = Caps::for_fd_limit(fd_limit);
        match limits.max_connections {
            None => fitting,
            Some(n) => {
                let n = n.max(1);
                if (2 * n as u64).saturating_add(RESERVED_FDS) > fd_limit {
                    tracing::warn!(
                        max_connections = n,
                        fd_limit,
                        "--max-connections {n} on each listener does not fit the descriptor limit {fd_limit}; \
                         accepting will fail while it is reached (the default would be {} gRPC, {} HTTP)",
                        fitting.grpc,
                        fitting.http
                    );
                }
                Caps { grpc: n, http: n }
            }
        }
    }
}

/// Raises the process's soft descriptor limit to its hard limit; returns the soft limit
/// in force afterwards (`u64::MAX` for none).
fn raise_fd_limit() -> u64 {
    use rustix::process::{Resource, getrlimit, setrlimit};
    let limit = getrlimit(Resource::Nofile);
    if limit.current != limit.maximum {
        let raised = rustix::process::Rlimit {
            current: limit.maximum,
            maximum: limit.maximum,
        };
        if setrlimit(Resource::Nofile, raised).is_ok() {
            return limit.maximum.unwrap_or(u64::MAX);
        }
    }
    limit.current.unwrap_or(u64::MAX)
}

/// The HTTP/2 keepalive ping interval and timeout for `idle_timeout`: pings keep a live
/// connection's peer sending well within the timeout, and a peer that does not answer
/// is dropped.
pub fn keepalive(idle_timeout: Duration) -> Duration {
    idle_timeout / 3
}

/// Whether a connection has been useful yet, shared by the connection, the reader of its
/// plaintext ([`Watched`]) and its listener's [`Acceptor`].
#[derive(Debug, Default)]
pub struct Usage {
    state: AtomicU8,
    /// The connection's reader while it waits and may be evicted.
    waker: Mutex<Option<Waker>>,
}

/// No complete request head yet.
const WAITING: u8 = 0;
/// A complete request head arrived.
const USED: u8 = 1;
/// Closed to make room before a request head arrived.
const EVICTED: u8 = 2;

impl Usage {
    /// Whether a complete request head arrived.
    pub fn is_used(&self) -> bool {
        self.state.load(Ordering::Acquire) == USED
    }

    fn is_evicted(&self) -> bool {
        self.state.load(Ordering::Acquire) == EVICTED
    }

    fn is_waiting(&self) -> bool {
        self.state.load(Ordering::Acquire) == WAITING
    }

    /// Records that a complete request head arrived (unless the connection was evicted).
    fn mark_used(&self) {
        if self
            .state
            .compare_exchange(WAITING, USED, Ordering::AcqRel, Ordering::Acquire)
            .is_ok()
        {
            self.waker.lock().unwrap_or_else(PoisonError::into_inner).take();
        }
    }

    /// Closes a connection still waiting for its first request head: its next read fails.
    /// False if it is no longer waiting.
    fn evict(&self) -> bool {
        let evicted = self
            .state
            .compare_exchange(WAITING, EVICTED, Ordering::AcqRel, Ordering::Acquire)
            .is_ok();
        if evicted && let Some(w) = self.waker.lock().unwrap_or_else(PoisonError::into_inner).take() {
            w.wake();
        }
        evicted
    }

    /// Wakes `waker` when the connection is evicted.
    fn wake_on_eviction(&self, waker: &Waker) {
        let mut slot = self.waker.lock().unwrap_or_else(PoisonError::into_inner);
        if !slot.as_ref().is_some_and(|w| w.will_wake(waker)) {
            *slot = Some(waker.clone());
        }
    }
}

/// A listener that hands out [`Conn`]s within its cap and [`ConnLimits`].
pub struct Acceptor {
    listener: TcpListener,
    permits: Arc<Semaphore>,
    limits: ConnLimits,
    nodelay: bool,
    /// The connections handed out that may still be waiting for a request head, oldest
    /// first (pruned as it goes).
    waiting: VecDeque<Weak<Usage>>,
    cap: usize,
    /// When out-of-descriptor errors were last logged, and how many came since.
    warned: Option<Instant>,
    unlogged: u64,
}

impl Acceptor {
    /// Accepts on `listener`, at most `cap` connections at a time, within `limits`,
    /// setting `TCP_NODELAY` on each connection if `nodelay`.
    pub fn new(listener: TcpListener, cap: usize, limits: ConnLimits, nodelay: bool) -> Self {
        let cap = cap.max(1);
        Self {
            listener,
            permits: Arc::new(Semaphore::new(cap)),
            limits,
            nodelay,
            waiting: VecDeque::new(),
            cap,
            warned: None,
            unlogged: 0,
        }
    }

    /// The next connection. At the cap, the oldest connection without a complete request
    /// head is closed to make room for it; if every open connection has had one, it waits
    /// until one closes.
    pub async fn accept(&mut self) -> (Conn, SocketAddr) {
        let (io, peer) = self.next_socket().await;
        let permit = match self.permits.clone().try_acquire_owned() {
            Ok(permit) => permit,
            Err(_) => {
                if self.evict_oldest_waiting() {
                    tracing::debug!(%peer, "closed the oldest connection without a request to make room");
                }
                self.permits.clone().acquire_owned().await.expect("never closed")
            }
        };
        if self.nodelay {
            let _ = io.set_nodelay(true);
        }
        let conn = Conn::new(io, self.limits, permit);
        if self.waiting.len() >= 2 * self.cap {
            self.waiting.retain(|u| u.upgrade().is_some_and(|u| u.is_waiting()));
        }
        self.waiting.push_back(Arc::downgrade(&conn.usage));
        (conn, peer)
    }

    /// Evicts the oldest connection still waiting for its first request head, if any.
    fn evict_oldest_waiting(&mut self) -> bool {
        while let Some(oldest) = self.waiting.pop_front() {
            if oldest.upgrade().is_some_and(|u| u.evict()) {
                return true;
            }
        }
        false
    }

    /// The next accepted socket, pausing while the process is out of descriptors.
    async fn next_socket(&mut self) -> (TcpStream, SocketAddr) {
        loop {
            match self.listener.accept().await {
                Ok(accepted) => return accepted,
                Err(e) if out_of_descriptors(&e) => {
                    // Retrying at once would fail again and spin; connections closing
                    // (idle ones time out) free descriptors meanwhile.
                    self.unlogged += 1;
                    if self.warned.is_none_or(|t| t.elapsed() >= WARN_EVERY) {
                        tracing::warn!(
                            failed = self.unlogged,
                            "cannot accept connections: {e}; retrying every {BACKOFF:?}"
                        );
                        self.warned = Some(Instant::now());
                        self.unlogged = 0;
                    }
                    tokio::time::sleep(BACKOFF).await;
                }
                // A peer that left before it was accepted, and the like.
                Err(e) => tracing::debug!("accept failed: {e}"),
            }
        }
    }

    /// The address it listens on.
    pub fn local_addr(&self) -> io::Result<SocketAddr> {
        self.listener.local_addr()
    }
}

/// EMFILE, ENFILE, ENOBUFS, ENOMEM (Linux's numbers): errors of this process or system, not
/// of the peer.
fn out_of_descriptors(e: &io::Error) -> bool {
    matches!(e.raw_os_error(), Some(23 | 24 | 105 | 12))
}

/// An accepted connection: holds its place under the cap until dropped, and fails reads
/// once it is past its request deadline without a complete request head, once it has been
/// idle for the idle timeout, or once it was evicted.
///
/// It is in use while its peer sends, and while the peer takes what is written to it: an
/// HTTP/1 response that streams for minutes (a browser's `Join` over gRPC-web, which has
/// no pings to answer) keeps its connection. A peer that stops reading stops the writes
/// as soon as the socket's buffers are full, so it still times out.
pub struct Conn {
    io: TcpStream,
    idle: Duration,
    /// When the peer last sent something, or took bytes written to it.
    last_active: tokio::time::Instant,
    /// When the request deadline runs out.
    request_by: tokio::time::Instant,
    /// The earlier of the two that applies, armed while a read waits.
    deadline: Pin<Box<Sleep>>,
    usage: Arc<Usage>,
    _permit: OwnedSemaphorePermit,
}

impl Conn {
    fn new(io: TcpStream, limits: ConnLimits, permit: OwnedSemaphorePermit) -> Self {
        let now = tokio::time::Instant::now();
        let request_by = now + limits.request_deadline;
        Self {
            io,
            idle: limits.idle_timeout,
            last_active: now,
            request_by,
            deadline: Box::pin(tokio::time::sleep_until(request_by.min(now + limits.idle_timeout))),
            usage: Arc::default(),
            _permit: permit,
        }
    }

    /// The TCP stream.
    pub fn get_ref(&self) -> &TcpStream {
        &self.io
    }

    /// Whether it has been useful: shared with the reader of its plaintext.
    pub fn usage(&self) -> Arc<Usage> {
        self.usage.clone()
    }

    /// When a waiting read fails, and why.
    fn due(&self) -> (tokio::time::Instant, &'static str) {
        let idle = self.last_active + self.idle;
        if !self.usage.is_used() && self.request_by < idle {
            (self.request_by, "no complete request within the request deadline")
        } else {
            (idle, "the connection was idle for the idle timeout")
        }
    }
}

/// The error of a read on an evicted connection.
fn evicted() -> io::Error {
    io::Error::new(
        io::ErrorKind::ConnectionAborted,
        "closed to make room: no complete request yet",
    )
}

impl AsyncRead for Conn {
    fn poll_read(mut self: Pin<&mut Self>, cx: &mut Context<'_>, buf: &mut ReadBuf<'_>) -> Poll<io::Result<()>> {
        if self.usage.is_evicted() {
            return Poll::Ready(Err(evicted()));
        }
        let before = buf.filled().len();
        match Pin::new(&mut self.io).poll_read(cx, buf) {
            Poll::Ready(Ok(())) if buf.filled().len() > before => {
                // The deadline is moved when a read next waits, not on every read.
                self.last_active = tokio::time::Instant::now();
                Poll::Ready(Ok(()))
            }
            Poll::Pending => {
                if !self.usage.is_used() {
                    self.usage.wake_on_eviction(cx.waker());
                    if self.usage.is_evicted() {
                        return Poll::Ready(Err(evicted()));
                    }
                }
                let (due, why) = self.due();
                if self.deadline.deadline() != due {
                    self.deadline.as_mut().reset(due);
                }
                match self.deadline.as_mut().poll(cx) {
                    Poll::Ready(()) => Poll::Ready(Err(io::Error::new(io::ErrorKind::TimedOut, why))),
                    Poll::Pending => Poll::Pending,
                }
            }
            other => other,
        }
    }
}

/// Implements `AsyncWrite` for a wrapper by handing every call to its field `$io`; with
/// `$note`, the results of writes pass through that method first.
macro_rules! write_through {
    ($io:ident $(, $note:ident)?) => {
        fn poll_write(mut self: Pin<&mut Self>, cx: &mut Context<'_>, buf: &[u8]) -> Poll<io::Result<usize>> {
            let written = Pin::new(&mut self.$io).poll_write(cx, buf);
            $(let written = self.$note(written);)?
            written
        }

        fn poll_write_vectored(
            mut self: Pin<&mut Self>,
            cx: &mut Context<'_>,
            bufs: &[io::IoSlice<'_>],
        ) -> Poll<io::Result<usize>> {
            let written = Pin::new(&mut self.$io).poll_write_vectored(cx, bufs);
            $(let written = self.$note(written);)?
            written
        }

        fn is_write_vectored(&self) -> bool {
            self.$io.is_write_vectored()
        }

        fn poll_flush(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
            Pin::new(&mut self.$io).poll_flush(cx)
        }

        fn poll_shutdown(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
            Pin::new(&mut self.$io).poll_shutdown(cx)
        }
    };
}

impl Conn {
    /// Notes a write that the socket took as activity.
    fn wrote(&mut self, written: Poll<io::Result<usize>>) -> Poll<io::Result<usize>> {
        if let Poll::Ready(Ok(n)) = written
            && n > 0
        {
            self.last_active = tokio::time::Instant::now();
        }
        written
    }
}

impl AsyncWrite for Conn {
    write_through!(io, wrote);
}

/// A connection's plaintext (the [`Conn`] itself, or the TLS stream over it) as the HTTP
/// server reads it: scanned until its first complete request head, which makes the
/// connection [`Usage::is_used`].
pub struct Watched<IO> {
    io: IO,
    usage: Arc<Usage>,
    /// The scan, until it found a head.
    scan: Option<HeadScan>,
}

impl<IO> Watched<IO> {
    /// Watches `io`, the plaintext of the connection whose usage is `usage`.
    pub fn new(io: IO, usage: Arc<Usage>) -> Self {
        Self {
            io,
            usage,
            scan: Some(HeadScan::default()),
        }
    }

    /// The plaintext stream.
    pub fn get_ref(&self) -> &IO {
        &self.io
    }
}

impl<IO: AsyncRead + Unpin> AsyncRead for Watched<IO> {
    fn poll_read(mut self: Pin<&mut Self>, cx: &mut Context<'_>, buf: &mut ReadBuf<'_>) -> Poll<io::Result<()>> {
        let before = buf.filled().len();
        let read = Pin::new(&mut self.io).poll_read(cx, buf);
        let this = &mut *self;
        if let (Poll::Ready(Ok(())), Some(scan)) = (&read, &mut this.scan)
            && scan.feed(&buf.filled()[before..])
        {
            this.usage.mark_used();
            this.scan = None;
        }
        read
    }
}

impl<IO: AsyncWrite + Unpin> AsyncWrite for Watched<IO> {
    write_through!(io);
}

impl tonic::transport::server::Connected for Conn {
    type ConnectInfo = tonic::transport::server::TcpConnectInfo;

    fn connect_info(&self) -> Self::ConnectInfo {
        self.io.connect_info()
    }
}

impl<IO: tonic::transport::server::Connected> tonic::transport::server::Connected for Watched<IO> {
    type ConnectInfo = IO::ConnectInfo;

    fn connect_info(&self) -> Self::ConnectInfo {
        self.io.connect_info()
    }
}

/// The connections of `acceptor`, each passed through `open` (a TLS handshake, say) and
/// [`Watched`], as the stream the gRPC server takes. Each `open` runs in a task of its own,
/// so a slow peer delays no one else; a connection whose `open` fails is dropped here
/// (logged at debug level), not handed to the server.
pub fn incoming<T, F, Fut>(
    mut acceptor: Acceptor,
    open: F,
) -> tokio_stream::wrappers::ReceiverStream<io::Result<Watched<T>>>
where
    T: Send + 'static,
    F: Fn(Conn) -> Fut + Send + 'static,
    Fut: Future<Output = io::Result<T>> + Send + 'static,
{
    let (tx, rx) = tokio::sync::mpsc::channel(1);
    tokio::spawn(async move {
        loop {
            let (conn, peer) = tokio::select! {
                accepted = acceptor.accept() => accepted,
                // The server stopped taking connections.
                _ = tx.closed() => return,
            };
            let usage = conn.usage();
            let opening = open(conn);
            let tx = tx.clone();
            tokio::spawn(async move {
                match opening.await {
                    Ok(io) => {
                        let _ = tx.send(Ok(Watched::new(io, usage))).await;
                    }
                    Err(e) => tracing::debug!(%peer, "connection not opened: {e}"),
                }
            });
        }
    });
    tokio_stream::wrappers::ReceiverStream::new(rx)
}

#[cfg(test)]
mod tests {
    use super::*;
    use tokio::io::{AsyncReadExt, AsyncWriteExt};

    /// An acceptor on a free loopback port, at most `cap` connections, with a request
    /// deadline of `deadline` and an idle timeout of a minute.
    async fn acceptor(cap: usize, deadline: Duration) -> Acceptor {
        let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
        let limits = ConnLimits {
            max_connections: Some(cap),
            idle_timeout: Duration::from_secs(60),
            request_deadline: deadline,
        };
        Acceptor::new(listener, cap, limits, false)
    }

    /// A client connection to `acceptor`, sending `first`, and the server's side of it.
    async fn connect(acceptor: &mut Acceptor, first: &[u8]) -> (TcpStream, Watched<Conn>) {
        let mut client = TcpStream::connect(acceptor.local_addr().unwrap()).await.unwrap();
        client.write_all(first).await.unwrap();
        let (conn, _) = acceptor.accept().await;
        let usage = conn.usage();
        (client, Watched::new(conn, usage))
    }

    /// Reads the server's side until it fails or `limit` passes: the failure's kind.
    async fn read_fails(server: &mut Watched<Conn>, limit: Duration) -> Option<io::ErrorKind> {
        let mut buf = [0u8; 256];
        tokio::time::timeout(limit, async {
            loop {
                match server.read(&mut buf).await {
                    Ok(0) => return io::ErrorKind::UnexpectedEof,
                    Ok(_) => {}
                    Err(e) => return e.kind(),
                }
            }
        })
        .await
        .ok()
    }

    #[tokio::test]
    async fn a_trickled_request_is_closed_at_the_request_deadline() {
        let mut acceptor = acceptor(4, Duration::from_millis(300)).await;
        let (mut slow, mut server) = connect(&mut acceptor, b"GET /health HTTP/1.1\r\n").await;
        // A byte every 50 ms: never idle, never a complete head.
        let trickle = tokio::spawn(async move {
            for _ in 0..100 {
                tokio::time::sleep(Duration::from_millis(50)).await;
                if slow.write_all(b"x").await.is_err() {
                    return;
                }
            }
        });
        let started = Instant::now();
        assert_eq!(
            read_fails(&mut server, Duration::from_secs(3)).await,
            Some(io::ErrorKind::TimedOut)
        );
        assert!(started.elapsed() < Duration::from_secs(2), "{:?}", started.elapsed());
        trickle.abort();

        // A complete head in time: the deadline no longer applies, only the idle timeout.
        let (_client, mut server) = connect(&mut acceptor, b"GET /health HTTP/1.1\r\n\r\n").await;
        assert_eq!(
            read_fails(&mut server, Duration::from_secs(1)).await,
            None,
            "still open"
        );
        assert!(server.usage.is_used());
    }

    #[tokio::test]
    async fn at_the_cap_the_oldest_connection_without_a_request_makes_room() {
        let mut acceptor = acceptor(3, Duration::from_secs(60)).await;
        let (_c1, mut used) = connect(&mut acceptor, b"GET / HTTP/1.1\r\n\r\n").await;
        let (_c2, mut oldest_waiting) = connect(&mut acceptor, b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n").await;
        let (_c3, mut newer_waiting) = connect(&mut acceptor, b"GET / HTTP/1.1\r\n").await;
        // The scans have to see the bytes: read what each sent.
        for conn in [&mut used, &mut oldest_waiting, &mut newer_waiting] {
            assert_eq!(read_fails(conn, Duration::from_millis(100)).await, None);
        }
        // A fourth: the oldest waiting one is closed for it, the others stay.
        let accepting = tokio::spawn(async move {
            let got = connect(&mut acceptor, b"").await;
            (acceptor, got)
        });
        assert_eq!(
            read_fails(&mut oldest_waiting, Duration::from_secs(2)).await,
            Some(io::ErrorKind::ConnectionAborted)
        );
        drop(oldest_waiting);
        let (mut acceptor, _fourth) = tokio::time::timeout(Duration::from_secs(2), accepting)
            .await
            .expect("accepted once room was made")
            .unwrap();
        assert_eq!(read_fails(&mut used, Duration::from_millis(100)).await, None);
        assert_eq!(read_fails(&mut newer_waiting, Duration::from_millis(100)).await, None);
        // At the cap with only used connections (and the newest waiting ones), the next
        // eviction takes the next oldest waiting one.
        assert!(acceptor.evict_oldest_waiting());
        assert_eq!(
            read_fails(&mut newer_waiting, Duration::from_secs(1)).await,
            Some(io::ErrorKind::ConnectionAborted)
        );
    }
}

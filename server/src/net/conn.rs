//! Accepted connections, for both listeners: at most a configured number at a time, each
//! closed once its peer has sent nothing for the idle timeout, and an accept loop that
//! backs off instead of spinning when the process runs out of file descriptors.
//!
//! A peer that opens a connection and then stalls (an HTTP/2 preface and silence, half an
//! HTTP request, a client that stopped) would otherwise hold its descriptor forever; enough
//! of them exhaust the process's descriptors and nobody is served. The idle timeout frees
//! them; live HTTP/2 connections stay busy through the keepalive pings the gRPC server sends
//! at a third of the timeout (see [`keepalive`]), which the peer must answer.

use std::io;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::Arc;
use std::task::{Context, Poll};
use std::time::{Duration, Instant};
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{OwnedSemaphorePermit, Semaphore};
use tokio::time::Sleep;

/// How long the accept loop pauses when the process is out of descriptors.
const BACKOFF: Duration = Duration::from_millis(250);
/// Out-of-descriptor errors are logged at most this often.
const WARN_EVERY: Duration = Duration::from_secs(10);

/// The connection limits of one listener.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ConnLimits {
    /// Most connections open at a time; more wait in the listen backlog.
    pub max_connections: usize,
    /// A connection whose peer sends nothing for this long is closed.
    pub idle_timeout: Duration,
}

impl Default for ConnLimits {
    /// 512 connections per listener, 60 s idle timeout.
    fn default() -> Self {
        Self {
            max_connections: 512,
            idle_timeout: Duration::from_secs(60),
        }
    }
}

/// The HTTP/2 keepalive ping interval and timeout for `idle_timeout`: pings keep a live
/// connection's peer sending well within the timeout, and a peer that does not answer
/// is dropped.
pub fn keepalive(idle_timeout: Duration) -> Duration {
    idle_timeout / 3
}

/// A listener that hands out [`Conn`]s within [`ConnLimits`].
pub struct Acceptor {
    listener: TcpListener,
    permits: Arc<Semaphore>,
    limits: ConnLimits,
    nodelay: bool,
    /// When out-of-descriptor errors were last logged, and how many came since.
    warned: Option<Instant>,
    unlogged: u64,
}

impl Acceptor {
    /// Accepts on `listener` within `limits`, setting `TCP_NODELAY` on each connection if
    /// `nodelay`.
    pub fn new(listener: TcpListener, limits: ConnLimits, nodelay: bool) -> Self {
        Self {
            listener,
            permits: Arc::new(Semaphore::new(limits.max_connections.max(1))),
            limits,
            nodelay,
            warned: None,
            unlogged: 0,
        }
    }

    /// The next connection, once one is below the limit and a peer connects.
    pub async fn accept(&mut self) -> (Conn, SocketAddr) {
        let permit = self.permits.clone().acquire_owned().await.expect("never closed");
        loop {
            match self.listener.accept().await {
                Ok((io, peer)) => {
                    if self.nodelay {
                        let _ = io.set_nodelay(true);
                    }
                    return (Conn::new(io, self.limits.idle_timeout, permit), peer);
                }
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
}

/// EMFILE, ENFILE, ENOBUFS, ENOMEM (Linux's numbers): errors of this process or system, not
/// of the peer.
fn out_of_descriptors(e: &io::Error) -> bool {
    matches!(e.raw_os_error(), Some(23 | 24 | 105 | 12))
}

impl axum::serve::Listener for Acceptor {
    type Io = Conn;
    type Addr = SocketAddr;

    async fn accept(&mut self) -> (Conn, SocketAddr) {
        Acceptor::accept(self).await
    }

    fn local_addr(&self) -> io::Result<SocketAddr> {
        self.listener.local_addr()
    }
}

/// An accepted connection: holds its place under the connection limit until dropped, and
/// fails reads once the peer has sent nothing for the idle timeout.
pub struct Conn {
    io: TcpStream,
    idle: Duration,
    deadline: Pin<Box<Sleep>>,
    _permit: OwnedSemaphorePermit,
}

impl Conn {
    fn new(io: TcpStream, idle: Duration, permit: OwnedSemaphorePermit) -> Self {
        Self {
            io,
            idle,
            deadline: Box::pin(tokio::time::sleep(idle)),
            _permit: permit,
        }
    }

    /// The TCP stream.
    pub fn get_ref(&self) -> &TcpStream {
        &self.io
    }
}

impl AsyncRead for Conn {
    fn poll_read(mut self: Pin<&mut Self>, cx: &mut Context<'_>, buf: &mut ReadBuf<'_>) -> Poll<io::Result<()>> {
        let before = buf.filled().len();
        match Pin::new(&mut self.io).poll_read(cx, buf) {
            Poll::Ready(Ok(())) if buf.filled().len() > before => {
                let next = tokio::time::Instant::now() + self.idle;
                self.deadline.as_mut().reset(next);
                Poll::Ready(Ok(()))
            }
            Poll::Pending => match self.deadline.as_mut().poll(cx) {
                Poll::Ready(()) => Poll::Ready(Err(io::Error::new(
                    io::ErrorKind::TimedOut,
                    "the peer sent nothing for the idle timeout",
                ))),
                Poll::Pending => Poll::Pending,
            },
            other => other,
        }
    }
}

impl AsyncWrite for Conn {
    fn poll_write(mut self: Pin<&mut Self>, cx: &mut Context<'_>, buf: &[u8]) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.io).poll_write(cx, buf)
    }

    fn poll_write_vectored(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        bufs: &[io::IoSlice<'_>],
    ) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.io).poll_write_vectored(cx, bufs)
    }

    fn is_write_vectored(&self) -> bool {
        self.io.is_write_vectored()
    }

    fn poll_flush(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.io).poll_flush(cx)
    }

    fn poll_shutdown(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.io).poll_shutdown(cx)
    }
}

impl tonic::transport::server::Connected for Conn {
    type ConnectInfo = tonic::transport::server::TcpConnectInfo;

    fn connect_info(&self) -> Self::ConnectInfo {
        self.io.connect_info()
    }
}

/// The connections of `acceptor`, each passed through `open` (a TLS handshake, say), as
/// the stream the gRPC server takes. Each `open` runs in a task of its own, so a slow peer
/// delays no one else; a connection whose `open` fails is dropped here (logged at debug
/// level), not handed to the server.
pub fn incoming<T, F, Fut>(mut acceptor: Acceptor, open: F) -> tokio_stream::wrappers::ReceiverStream<io::Result<T>>
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
            let opening = open(conn);
            let tx = tx.clone();
            tokio::spawn(async move {
                match opening.await {
                    Ok(io) => {
                        let _ = tx.send(Ok(io)).await;
                    }
                    Err(e) => tracing::debug!(%peer, "connection not opened: {e}"),
                }
            });
        }
    });
    tokio_stream::wrappers::ReceiverStream::new(rx)
}

//! How a server or a relay faces its clients: where it listens (gRPC with reflection for
//! whom [`Reflection`] says, keepalive, connection limits and optional TLS; HTTP), the
//! message and connection
//! limits, and how far its clients may fall behind. `naadf serve` and `naadf relay` share
//! all of it.

use crate::metrics::Metrics;
use crate::net::addresses::{Bound, DEFAULT_GRPC, DEFAULT_HTTP};
use crate::net::auth::Auth;
use crate::net::conn::{Acceptor, Caps, ConnLimits, Listening, incoming};
use crate::net::page::PageHome;
use crate::net::tls::ReloadingCert;
use crate::shared::SlowClientLimits;
use anyhow::{Context, Result};
use naadf_proto::FILE_DESCRIPTOR_SET;
use naadf_proto::v1::world_service_server::{WorldService, WorldServiceServer};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;
use tokio::io::{AsyncRead, AsyncWrite};
use tokio::sync::watch;
use tokio_stream::wrappers::ReceiverStream;
use tonic::codec::CompressionEncoding;
use tonic::service::RoutesBuilder;
use tonic::service::interceptor::InterceptedService;
use tonic::transport::Server;
use tonic::transport::server::{Connected, Router};
use tonic_web::GrpcWebLayer;

/// The client-facing settings a server and a relay share.
#[derive(Clone, Debug)]
pub struct Frontend {
    /// gRPC listen address.
    pub grpc: SocketAddr,
    /// HTTP listen address.
    pub http: SocketAddr,
    /// TLS certificate and key (PEM) for gRPC, if any, reloaded when they change (see
    /// [`crate::net::tls`]). HTTP never has TLS of its own.
    pub tls: Option<(PathBuf, PathBuf)>,
    /// Largest gRPC message accepted, in bytes.
    pub max_message_bytes: usize,
    /// Open connections per listener, their request deadline and their idle timeout.
    pub connections: ConnLimits,
    /// Deltas a client may fall behind before it is re-sent a snapshot.
    pub slow_client_events: usize,
    /// Bytes a client, and all clients together, may fall behind before they are re-sent
    /// a snapshot.
    pub slow_clients: SlowClientLimits,
    /// Who may use gRPC server reflection; `None`: [`Reflection::Token`] on a server with
    /// tokens, [`Reflection::Open`] otherwise.
    pub reflection: Option<Reflection>,
}

/// Who may use gRPC server reflection (the service list and the `.proto` descriptors that
/// generic tools such as grpcurl read).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reflection {
    /// Anyone.
    Open,
    /// Callers with a token the server knows (any role).
    Token,
    /// Nobody: reflection is not served.
    Off,
}

/// Who reflection answers on one server, [`Reflection`] resolved against its tokens.
enum ReflectionGate<'a> {
    /// Anyone.
    Anyone,
    /// The callers this table knows.
    Tokens(&'a Auth),
    /// Nobody.
    Nobody,
}

impl Reflection {
    /// Parses `open`, `token` or `off`.
    pub fn parse(s: &str) -> Result<Reflection, String> {
        match s {
            "open" => Ok(Reflection::Open),
            "token" => Ok(Reflection::Token),
            "off" => Ok(Reflection::Off),
            _ => Err(format!("'{s}' is not open, token or off")),
        }
    }
}

impl Default for Frontend {
    /// A server's documented defaults (docs/PROTOCOL.md): gRPC on [`DEFAULT_GRPC`], HTTP
    /// on [`DEFAULT_HTTP`], no TLS, 16 MiB messages.
    fn default() -> Self {
        Self {
            grpc: DEFAULT_GRPC.parse().expect("address"),
            http: DEFAULT_HTTP.parse().expect("address"),
            tls: None,
            max_message_bytes: 16 << 20,
            connections: ConnLimits::default(),
            slow_client_events: 4096,
            slow_clients: SlowClientLimits::default(),
            reflection: None,
        }
    }
}

impl Frontend {
    /// The listeners on which bearer tokens would cross a network in cleartext: gRPC on a
    /// non-loopback address without TLS, and HTTP on one (it has no TLS).
    ///
    /// ```
    /// use naadf_server::net::frontend::Frontend;
    /// let mut f = Frontend::default();
    /// assert!(f.cleartext_listeners().is_empty(), "loopback by default");
    /// f.grpc = "0.0.0.0:50051".parse().unwrap();
    /// assert_eq!(f.cleartext_listeners(), ["gRPC on 0.0.0.0:50051 without TLS"]);
    /// f.tls = Some(("cert.pem".into(), "key.pem".into()));
    /// assert!(f.cleartext_listeners().is_empty());
    /// ```
    pub fn cleartext_listeners(&self) -> Vec<String> {
        [("gRPC", self.grpc, self.tls.is_none()), ("HTTP", self.http, true)]
            .into_iter()
            .filter(|(_, addr, plain)| *plain && !addr.ip().is_loopback())
            .map(|(what, addr, _)| format!("{what} on {addr} without TLS"))
            .collect()
    }

    /// Who may use reflection on a server whose token table is `auth` (`None`: a relay,
    /// which holds no tokens).
    fn reflection_for<'a>(&self, auth: Option<&'a Auth>) -> Result<ReflectionGate<'a>> {
        let tokens = auth.filter(|a| !a.is_open());
        match (self.reflection, tokens) {
            (Some(Reflection::Token), None) if auth.is_none() => {
                anyhow::bail!("--reflection token needs the server's tokens; a relay holds none (use open or off)")
            }
            (Some(Reflection::Token), None) => {
                anyhow::bail!("--reflection token needs tokens (--auth or NAADF_TOKENS); this server has none")
            }
            (Some(Reflection::Token), Some(t)) | (None, Some(t)) => Ok(ReflectionGate::Tokens(t)),
            (Some(Reflection::Open), _) | (None, None) => Ok(ReflectionGate::Anyone),
            (Some(Reflection::Off), _) => Ok(ReflectionGate::Nobody),
        }
    }

    /// Binds both listeners and serves `svc` (with gRPC-web and the browser page, see
    /// [`crate::net::page`]) and `http_routes` until `shutdown` turns true; with
    /// TLS, the certificate is reloaded as [`crate::net::tls`] describes, counted in `metrics`.
    /// `auth` is the server's token table (`None` for a relay), which reflection may ask.
    pub(crate) async fn start<S: WorldService>(
        &self,
        svc: WorldServiceServer<S>,
        http_routes: axum::Router,
        auth: Option<&Auth>,
        metrics: &Arc<Metrics>,
        shutdown: &watch::Sender<bool>,
    ) -> Result<(Bound, Listening, Listening)> {
        let reflection = self.reflection_for(auth)?;
        // Read before binding: a bad certificate fails the start, not the first handshake.
        let tls = match &self.tls {
            Some((cert, key)) => Some(Arc::new(ReloadingCert::load(cert, key)?)),
            None => None,
        };
        let grpc_listener = tokio::net::TcpListener::bind(self.grpc)
            .await
            .with_context(|| format!("cannot listen on {}", self.grpc))?;
        let http_listener = tokio::net::TcpListener::bind(self.http)
            .await
            .with_context(|| format!("cannot listen on {}", self.http))?;
        let bound = Bound {
            grpc: grpc_listener.local_addr()?,
            http: http_listener.local_addr()?,
        };
        tracing::info!(grpc = %bound.grpc, http = %bound.http, "serving");
        let home = PageHome {
            grpc: bound.grpc,
            tls: self.tls.is_some(),
        };
        tracing::info!("the browser page: {}", home.url(None, None));

        let reflection_v1 = tonic_reflection::server::Builder::configure()
            .register_encoded_file_descriptor_set(FILE_DESCRIPTOR_SET)
            .build_v1()?;
        let reflection_v1alpha = tonic_reflection::server::Builder::configure()
            .register_encoded_file_descriptor_set(FILE_DESCRIPTOR_SET)
            .build_v1alpha()?;
        let svc = svc
            .max_decoding_message_size(self.max_message_bytes)
            .max_encoding_message_size(usize::MAX)
            .accept_compressed(CompressionEncoding::Zstd);
        let keepalive = crate::net::conn::keepalive(self.connections.idle_timeout);
        let mut services = RoutesBuilder::default();
        services.add_service(svc);
        match reflection {
            ReflectionGate::Anyone => {
                services.add_service(reflection_v1).add_service(reflection_v1alpha);
            }
            ReflectionGate::Tokens(auth) => {
                // Any caller the token table knows; the refusal is the one every call gets.
                let auth = auth.clone();
                let check = move |req: tonic::Request<()>| auth.caller(req.metadata()).map(|_| req);
                services
                    .add_service(InterceptedService::new(reflection_v1, check.clone()))
                    .add_service(InterceptedService::new(reflection_v1alpha, check));
            }
            ReflectionGate::Nobody => {}
        }
        // gRPC-web (browsers) wraps the services only: it answers any other HTTP/1 request
        // with 400, so the page's routes are merged after it.
        let routes = services
            .routes()
            .into_axum_router()
            .layer(GrpcWebLayer::new())
            .merge(crate::net::page::routes());
        let router = Server::builder()
            .accept_http1(true)
            .http2_keepalive_interval(Some(keepalive))
            .http2_keepalive_timeout(Some(keepalive))
            .add_routes(routes.into());
        let mut stop = shutdown.subscribe();
        let stopped = async move {
            let _ = stop.wait_for(|s| *s).await;
        };
        let caps = Caps::resolve(&self.connections);
        tracing::info!(grpc = caps.grpc, http = caps.http, "connection caps");
        let acceptor = grpc_acceptor(grpc_listener, caps.grpc, self.connections);
        let grpc = match tls {
            Some(cert) => {
                let tls = cert.acceptor()?;
                let timeout = self.connections.request_deadline;
                cert.watch(metrics.clone(), shutdown.subscribe());
                let incoming = incoming(acceptor, move |conn| {
                    crate::net::tls::handshake(tls.clone(), conn, timeout)
                });
                serve_grpc(router, incoming, stopped)
            }
            None => serve_grpc(router, incoming(acceptor, |conn| std::future::ready(Ok(conn))), stopped),
        };
        let http = crate::net::http_serve::serve(
            Acceptor::new(http_listener, caps.http, self.connections, false),
            http_routes.merge(home.redirect_route()),
            self.connections.request_deadline,
            shutdown.subscribe(),
        );
        Ok((bound, grpc, http))
    }
}

/// Serves `router` on the connections `incoming` hands over until `stopped`, in a task of
/// its own.
fn serve_grpc<IO>(
    router: Router,
    incoming: ReceiverStream<std::io::Result<IO>>,
    stopped: impl Future<Output = ()> + Send + 'static,
) -> Listening
where
    IO: AsyncRead + AsyncWrite + Connected + Unpin + Send + 'static,
    IO::ConnectInfo: Clone + Send + Sync + 'static,
{
    tokio::spawn(async move {
        router
            .serve_with_incoming_shutdown(incoming, stopped)
            .await
            .map_err(Into::into)
    })
}

/// The gRPC listener's acceptor: at most `cap` connections within `limits`, with
/// `TCP_NODELAY` set (tonic applies its own `tcp_nodelay` only to listeners it binds
/// itself). Deltas are small writes right behind bigger ones; without it, Nagle's
/// algorithm holds them until the client's delayed ACK, up to 40 ms on Linux, for every
/// client at once.
fn grpc_acceptor(listener: tokio::net::TcpListener, cap: usize, limits: ConnLimits) -> Acceptor {
    Acceptor::new(listener, cap, limits, true)
}

#[cfg(test)]
mod tests {
    use tokio_stream::StreamExt;

    #[tokio::test]
    async fn accepted_grpc_connections_send_without_delay() {
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let addr = listener.local_addr().unwrap();
        let acceptor = super::grpc_acceptor(listener, 4, Default::default());
        let mut incoming = crate::net::conn::incoming(acceptor, |c| std::future::ready(Ok(c)));
        let _client = tokio::net::TcpStream::connect(addr).await.unwrap();
        let accepted = incoming.next().await.unwrap().unwrap();
        assert!(accepted.get_ref().get_ref().nodelay().unwrap());
    }
}

//! Serving the HTTP routes on the connections an [`Acceptor`] hands out: HTTP/1 and
//! HTTP/2, with every HTTP/1 request head held to the request deadline.
//!
//! This is `axum::serve` with two things it does not offer: the connections are the
//! listener's own [`Watched`] ones (so the first request head of each is seen, and a
//! connection without one may be closed to make room), and hyper's header timer is set,
//! so that a peer trickling a later request head a byte at a time is closed too.

use crate::net::conn::{Acceptor, Listening, Watched};
use axum::extract::ConnectInfo;
use hyper_util::rt::{TokioExecutor, TokioIo, TokioTimer};
use hyper_util::server::conn::auto::Builder;
use hyper_util::server::graceful::GracefulShutdown;
use hyper_util::service::TowerToHyperService;
use std::time::Duration;
use tokio::sync::watch;
use tower_layer::Layer;

/// Serves `routes` on the connections of `acceptor` until `shutdown` turns true, then lets
/// the requests under way finish; handlers see the peer as `ConnectInfo<SocketAddr>`.
pub(crate) fn serve(
    mut acceptor: Acceptor,
    routes: axum::Router,
    request_deadline: Duration,
    mut shutdown: watch::Receiver<bool>,
) -> Listening {
    tokio::spawn(async move {
        let mut builder = Builder::new(TokioExecutor::new());
        builder
            .http1()
            .timer(TokioTimer::new())
            .header_read_timeout(request_deadline);
        let graceful = GracefulShutdown::new();
        loop {
            let (conn, peer) = tokio::select! {
                accepted = acceptor.accept() => accepted,
                _ = shutdown.wait_for(|s| *s) => break,
            };
            let usage = conn.usage();
            let io = TokioIo::new(Watched::new(conn, usage));
            let service = TowerToHyperService::new(axum::Extension(ConnectInfo(peer)).layer(routes.clone()));
            let serving = graceful.watch(builder.serve_connection_with_upgrades(io, service).into_owned());
            tokio::spawn(async move {
                if let Err(e) = serving.await {
                    tracing::debug!(%peer, "HTTP connection ended: {e}");
                }
            });
        }
        graceful.shutdown().await;
        Ok(())
    })
}

//! `naadf relay`: a mirror of a server (or of another relay) that serves the read side of
//! the same gRPC API to its own clients, so that the server pays for one stream per relay
//! instead of one per viewer.
//!
//! ```text
//! upstream Join stream ──▶ upstream::follow ──▶ hub (mirror: apply, check digest) ──▶ Publisher
//!                                                   ▲ Join / Status                   │
//! clients ──▶ RelayService ── join::start ──────────┘              join tasks ◀────────┘
//!             └── Edit, Undo, Redo, entities, RenderFrame ──▶ forwarded upstream as they came
//! ```
//!
//! - [`hub`] owns the mirror and publishes exactly the messages it accepted; the server's
//!   own [`join`](crate::stream::join) tasks serve them, resume included.
//! - [`upstream`] follows the upstream stream and re-joins with backoff; it also forwards
//!   callers' requests with their own metadata.
//! - [`gate`] asks the upstream who a caller is: a relay holds no tokens.
//! - [`service`] is the gRPC service.

pub mod gate;
pub mod hub;
pub mod service;
pub mod upstream;

use crate::net::addresses::Bound;
use crate::net::auth::Auth;
use crate::net::frontend::Frontend;
use crate::net::http;
use crate::net::http::Backend;
use crate::shared::Shared;
use anyhow::{Context, Result};
use naadf_proto::v1::world_service_server::WorldServiceServer;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::{Notify, mpsc, watch};

/// Everything `naadf relay` can configure.
#[derive(Clone, Debug)]
pub struct RelayConfig {
    /// The upstream's gRPC URL (`http://` or `https://`).
    pub upstream: String,
    /// A CA certificate (PEM file) to trust for an `https://` upstream.
    pub ca: Option<PathBuf>,
    /// The relay's own token for its upstream join (any role that may join).
    pub token: Option<String>,
    /// Where it listens, and its clients' limits.
    pub frontend: Frontend,
    /// The largest world, in bytes of buffers, to accept from the upstream.
    pub max_world_bytes: u64,
    /// How long the upstream connection may stay silent before the relay gives it up and
    /// re-joins (keepalive pings go out after half of it): a cut link is noticed in this
    /// time, and `upstream_connected` drops to 0 meanwhile.
    pub upstream_timeout: Duration,
}

/// The default gRPC listen address of a relay.
pub const DEFAULT_RELAY_GRPC: &str = "127.0.0.1:50061";
/// The default HTTP listen address of a relay.
pub const DEFAULT_RELAY_HTTP: &str = "127.0.0.1:8081";
/// How long a relay's upstream connection may stay silent by default: the limit every
/// client channel has.
pub const DEFAULT_UPSTREAM_TIMEOUT: Duration = naadf_proto::endpoint::DEFAULT_SILENCE_LIMIT;

impl RelayConfig {
    /// The documented defaults, following `upstream`.
    pub fn new(upstream: &str) -> Self {
        Self {
            upstream: upstream.to_owned(),
            ca: None,
            token: None,
            frontend: Frontend {
                grpc: DEFAULT_RELAY_GRPC.parse().expect("address"),
                http: DEFAULT_RELAY_HTTP.parse().expect("address"),
                ..Frontend::default()
            },
            max_world_bytes: naadf_proto::snapshot::DEFAULT_MAX_WORLD_BYTES,
            upstream_timeout: DEFAULT_UPSTREAM_TIMEOUT,
        }
    }

    /// Why callers' bearer tokens would cross a network in cleartext through this relay:
    /// its gRPC listens on a non-loopback address without TLS, its HTTP (never TLS) does,
    /// or its upstream is a non-loopback `http://` URL (forwarded requests carry the
    /// callers' tokens). `None` when none of these holds.
    pub fn cleartext_warning(&self) -> Option<String> {
        let mut exposed = self.frontend.cleartext_listeners();
        let uri = self.upstream.parse::<tonic::transport::Uri>().ok();
        let loopback = |host: &str| {
            let ip = host.trim_start_matches('[').trim_end_matches(']');
            host == "localhost" || ip.parse::<std::net::IpAddr>().is_ok_and(|ip| ip.is_loopback())
        };
        if let Some(uri) = uri.filter(|u| u.scheme_str() == Some("http"))
            && !uri.host().is_some_and(loopback)
        {
            exposed.push(format!("the upstream {} over plain HTTP/2", self.upstream));
        }
        (!exposed.is_empty()).then(|| {
            format!(
                "bearer tokens may travel in cleartext: {}; anyone on the network path can read them \
                 (use TLS: --tls-cert/--tls-key here, an https:// upstream)",
                exposed.join(", ")
            )
        })
    }
}

/// Runs a relay until `shutdown` resolves. `ready` is told the bound addresses as soon as
/// the relay listens, before its upstream answers: clients that join meanwhile wait for
/// the first snapshot.
pub async fn relay(
    config: RelayConfig,
    ready: impl FnOnce(Bound),
    shutdown: impl std::future::Future<Output = ()>,
) -> Result<()> {
    if let Some(w) = config.cleartext_warning() {
        tracing::warn!("{w}");
    }
    let ca = match &config.ca {
        Some(p) => Some(std::fs::read(p).with_context(|| format!("cannot read {}", p.display()))?),
        None => None,
    };
    let upstream = upstream::Upstream::new(&config.upstream, ca, config.token.as_deref(), config.upstream_timeout)
        .map_err(anyhow::Error::msg)?;
    let (shutdown_tx, shutdown_rx) = watch::channel(false);
    let metrics = Arc::new(crate::metrics::Metrics::for_relay());
    // Tokens are the upstream's business; the relay's own token set stays empty and is
    // never consulted (the service and the pages ask the upstream through the gate).
    let shared = Arc::new(Shared {
        slow_clients: config.frontend.slow_clients,
        ..Shared::with_metrics(Auth::open(), 1, shutdown_rx.clone(), metrics.clone())
    });

    let rejoin = Arc::new(Notify::new());
    let (hub_tx, hub_rx) = mpsc::channel(1024);
    let hub = hub::Hub::new(
        config.max_world_bytes,
        config.frontend.slow_client_events,
        rejoin.clone(),
        metrics.clone(),
        shared.presence.clone(),
    );
    let hub = std::thread::Builder::new()
        .name("naadf-relay-hub".into())
        .spawn(move || hub.run(hub_rx))?;
    // Join tasks and the pages speak to the hub as they would to the server's actor.
    let (req_tx, mut req_rx) = mpsc::channel(1024);
    {
        let hub_tx = hub_tx.clone();
        tokio::spawn(async move {
            while let Some(r) = req_rx.recv().await {
                if hub_tx.send(hub::Input::Request(r)).await.is_err() {
                    return;
                }
            }
        });
    }
    let follower = tokio::spawn(upstream::follow(
        upstream.clone(),
        hub_tx,
        rejoin,
        metrics.clone(),
        shutdown_rx.clone(),
    ));
    let poller = tokio::spawn(upstream::poll_lag(
        upstream.clone(),
        req_tx.clone(),
        metrics.clone(),
        shutdown_rx.clone(),
    ));

    let auth = Arc::new(gate::UpstreamAuth::new(upstream.clone()));
    let svc = WorldServiceServer::new(service::RelayService::new(
        shared.clone(),
        req_tx.clone(),
        upstream.clone(),
        auth.clone(),
    ));
    let routes = http::router(
        shared.clone(),
        req_tx.clone(),
        Backend::Relay {
            auth,
            upstream: upstream.clone(),
        },
    );
    let (bound, grpc, http) = config.frontend.start(svc, routes, None, &metrics, &shutdown_tx).await?;
    tracing::info!(upstream = %config.upstream, "relaying");
    ready(bound);

    shutdown.await;
    tracing::info!("shutting down");
    let _ = shutdown_tx.send(true);
    let _ = tokio::time::timeout(Duration::from_secs(10), grpc).await;
    let _ = tokio::time::timeout(Duration::from_secs(5), http).await;
    let _ = follower.await;
    let _ = poller.await;
    drop(req_tx);
    drop(shared);
    tokio::task::spawn_blocking(move || {
        let _ = hub.join();
    })
    .await?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cleartext_is_named_only_off_loopback() {
        let mut c = RelayConfig::new("http://127.0.0.1:50051");
        assert_eq!(c.cleartext_warning(), None);
        c.upstream = "http://[::1]:50051".into();
        assert_eq!(c.cleartext_warning(), None);
        c.upstream = "https://world.example:443".into();
        assert_eq!(c.cleartext_warning(), None);
        c.upstream = "http://world.example:50051".into();
        assert!(
            c.cleartext_warning()
                .unwrap()
                .contains("the upstream http://world.example:50051")
        );
        c.upstream = "http://localhost:50051".into();
        c.frontend.grpc = "0.0.0.0:50061".parse().unwrap();
        let w = c.cleartext_warning().unwrap();
        assert!(
            w.contains("gRPC on 0.0.0.0:50061") && !w.contains("the upstream"),
            "{w}"
        );
        c.frontend.tls = Some(("c".into(), "k".into()));
        assert_eq!(c.cleartext_warning(), None);
    }
}

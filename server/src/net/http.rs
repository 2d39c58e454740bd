//! The HTTP side (axum): `/health`, `/metrics` (Prometheus text format), `/frame.png`
//! (a frame from the render nodes) and a small HTML status page with the world, the joined
//! clients, the render nodes, a live frame and the recent edits.
//!
//! With tokens configured, everything but `/health` and `/metrics` wants one (any role),
//! from `Authorization: Bearer` or `?token=` (browsers cannot send headers for a page or an
//! `<img>`): the page names users and shows their edits. `/health` says only whether the
//! server is up and at which version; `/metrics` holds aggregates only.

use crate::net::auth::{Auth, Caller};
use crate::relay::gate::UpstreamAuth;
use crate::relay::upstream::{Upstream, upstream_error};
use crate::shared::Shared;
use crate::stream::messages::Request;
use axum::Router;
use axum::extract::rejection::QueryRejection;
use axum::extract::{ConnectInfo, Query, State};
use axum::http::{HeaderMap, StatusCode, header};
use axum::response::{Html, IntoResponse, Json, Response};
use axum::routing::get;
use naadf_proto::v1::FrameRequest;
use naadf_world::ops::{MAX_QUOTED_CHARS, clip_input};
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::SystemTime;
use tokio::sync::mpsc;
use tonic::Status;

#[derive(Clone)]
struct App {
    shared: Arc<Shared>,
    actor: mpsc::Sender<Request>,
    backend: Backend,
}

/// Who decides callers' roles and who renders `/frame.png`: a server's own tokens and
/// render nodes, or a relay's upstream (a relay holds no tokens and takes no nodes).
#[derive(Clone, Debug)]
pub enum Backend {
    /// A server: the tokens configured here, frames from the render router.
    Server(Auth),
    /// A relay: callers as the upstream sees them, frames asked of the upstream with the
    /// caller's token.
    Relay {
        /// The upstream's answers about tokens.
        auth: Arc<UpstreamAuth>,
        /// Where frame requests go.
        upstream: Upstream,
    },
}

impl Backend {
    /// The caller of a request from `peer` with these metadata.
    async fn caller(&self, md: &tonic::metadata::MetadataMap, peer: SocketAddr) -> Result<Caller, Status> {
        match self {
            Backend::Server(auth) => auth.caller(md),
            Backend::Relay { auth, .. } => auth.caller(md, Some(peer)).await,
        }
    }

    /// A frame for a caller with these credentials.
    async fn render(
        &self,
        shared: &Shared,
        md: &tonic::metadata::MetadataMap,
        req: FrameRequest,
    ) -> Result<naadf_proto::v1::FrameReply, Status> {
        match self {
            Backend::Server(_) => shared.router.render(req).await,
            Backend::Relay { upstream, .. } => {
                // Only the caller's token travels: the rest are this HTTP request's headers.
                let request = Upstream::as_caller(md, req);
                let reply = upstream.client().render_frame(request).await;
                reply.map(tonic::Response::into_inner).map_err(upstream_error)
            }
        }
    }
}

/// The HTTP routes; `actor` answers status requests, `backend` decides who callers are
/// and renders frames.
pub fn router(shared: Arc<Shared>, actor: mpsc::Sender<Request>, backend: Backend) -> Router {
    Router::new()
        .route("/health", get(health))
        .route("/metrics", get(metrics))
        .route("/frame.png", get(frame_png))
        .route("/status", get(status_page))
        .with_state(App { shared, actor, backend })
}

async fn health(State(app): State<App>) -> impl IntoResponse {
    // A relay whose upstream keeps refusing it says so, and stays healthy: a restart would
    // not help (the refusal is the upstream's, about the relay's token or protocol).
    let refused = app.shared.metrics.upstream.refused();
    let mut body = match crate::stream::messages::status(&app.actor).await {
        Some(s) => serde_json::json!({
            "status": "ok",
            "version": s.version,
            "quiescent": s.quiescent,
            "digest": s.digest.to_string(),
        }),
        None if refused.is_some() => serde_json::json!({"status": "waiting for the upstream"}),
        // Shutting down, or a relay that has no world from its upstream yet.
        None => {
            return (
                StatusCode::SERVICE_UNAVAILABLE,
                Json(serde_json::json!({"status": "unavailable"})),
            );
        }
    };
    if let Some(why) = refused {
        body["upstream"] = "refused".into();
        body["reason"] = why.into();
    }
    (StatusCode::OK, Json(body))
}

/// `GET /metrics`: aggregates only (no user names, no edit contents), so it needs no
/// token, like `/health`: scrapers should not need a credential.
async fn metrics(State(app): State<App>) -> Response {
    (
        [(
            header::CONTENT_TYPE,
            "application/openmetrics-text; version=1.0.0; charset=utf-8",
        )],
        app.shared.metrics.render(),
    )
        .into_response()
}

/// The `token` query parameter that every authenticated route accepts.
#[derive(serde::Deserialize)]
struct Token {
    token: Option<String>,
}

/// The `?token=` of a request, or why the query holds none that can be read (extracted
/// apart from a route's other parameters, so that authentication comes first).
type TokenQuery = Result<Query<Token>, QueryRejection>;

/// A request's credentials as gRPC metadata: its `Authorization` header, replaced by
/// `?token=` when the query has one.
fn credentials(headers: HeaderMap, token: TokenQuery) -> Result<tonic::metadata::MetadataMap, Status> {
    let mut md = tonic::metadata::MetadataMap::from_headers(headers);
    let Query(Token { token }) =
        token.map_err(|e| Status::unauthenticated(format!("the token query: {}", e.body_text())))?;
    if let Some(t) = token {
        let v = format!("Bearer {t}")
            .parse()
            .map_err(|_| Status::unauthenticated("the token must be visible ASCII"))?;
        md.insert("authorization", v);
    }
    Ok(md)
}

/// The query of `/frame.png` (its token is read apart, see [`TokenQuery`]).
#[derive(serde::Deserialize)]
struct FrameQuery {
    /// Camera JSON.
    camera: String,
    /// `WxH` (default 640x360).
    size: Option<String>,
    /// Render mode (default albedo).
    mode: Option<String>,
    /// Oldest version the frame may show.
    min_version: Option<u64>,
    /// The lit modes' options, as in `FrameRequest` (docs/RENDERING.md).
    spp: Option<u32>,
    frames: Option<u32>,
    seed: Option<u32>,
    bounces: Option<u32>,
    sky: Option<String>,
    sun: Option<String>,
    exposure: Option<f32>,
    stream: Option<String>,
    roma_directions: Option<u32>,
    ao_range: Option<f32>,
    irradiance_rays: Option<u32>,
}

impl FrameQuery {
    /// The `RenderFrame` request of the query, with its size parsed.
    fn request(self, (width, height): (u32, u32)) -> FrameRequest {
        FrameRequest {
            camera: self.camera,
            width,
            height,
            mode: self.mode.unwrap_or_else(|| "albedo".into()),
            min_version: self.min_version.unwrap_or(0),
            raw: false,
            timeout_ms: 0,
            spp: self.spp.unwrap_or(0),
            frames: self.frames.unwrap_or(0),
            seed: self.seed.unwrap_or(0),
            bounces: self.bounces,
            sky: self.sky.unwrap_or_default(),
            sun: self.sun.unwrap_or_default(),
            exposure: self.exposure.unwrap_or(0.0),
            stream: self.stream.unwrap_or_default(),
            roma_directions: self.roma_directions,
            ao_range: self.ao_range,
            irradiance_rays: self.irradiance_rays,
        }
    }
}

/// A gRPC status as an HTTP status and message.
fn http_error(s: &Status) -> Response {
    use tonic::Code;
    let code = match s.code() {
        Code::InvalidArgument => StatusCode::BAD_REQUEST,
        Code::Unauthenticated => StatusCode::UNAUTHORIZED,
        Code::PermissionDenied => StatusCode::FORBIDDEN,
        Code::ResourceExhausted => StatusCode::TOO_MANY_REQUESTS,
        Code::DeadlineExceeded => StatusCode::GATEWAY_TIMEOUT,
        Code::FailedPrecondition => StatusCode::UNPROCESSABLE_ENTITY,
        Code::Unavailable => StatusCode::SERVICE_UNAVAILABLE,
        _ => StatusCode::INTERNAL_SERVER_ERROR,
    };
    (code, format!("{}\n", s.message())).into_response()
}

/// `GET /frame.png?camera=<json>&size=WxH&mode=M[&min_version=n][&token=T]`, plus the lit
/// modes' `spp`, `frames`, `seed`, `bounces`, `sky`, `sun`, `exposure` and `stream`,
/// `roma`'s `roma_directions` and `ao_range`, and `irradiance`'s `irradiance_rays`: the same
/// request, roles and errors as `RenderFrame`. The token comes from `Authorization: Bearer`
/// or the query; a request without one from another machine is refused even in open mode.
/// Authentication comes first: a caller without a valid token learns nothing about the
/// other parameters.
async fn frame_png(
    State(app): State<App>,
    ConnectInfo(peer): ConnectInfo<SocketAddr>,
    headers: HeaderMap,
    token: TokenQuery,
    q: Result<Query<FrameQuery>, QueryRejection>,
) -> Response {
    let md = credentials(headers, token).and_then(|md| {
        if !md.contains_key("authorization") && !peer.ip().is_loopback() {
            return Err(Status::unauthenticated(
                "a frame request from another machine needs a token",
            ));
        }
        Ok(md)
    });
    let md = match md {
        Ok(md) => md,
        Err(s) => return http_error(&s),
    };
    if let Err(s) = app.backend.caller(&md, peer).await {
        return http_error(&s);
    }
    let q = match q {
        Ok(Query(q)) => q,
        Err(e) => return http_error(&Status::invalid_argument(e.body_text())),
    };
    let size = q.size.as_deref().unwrap_or("640x360");
    let Some((w, h)) = size
        .split_once(['x', 'X'])
        .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)))
    else {
        return http_error(&Status::invalid_argument(format!(
            "size '{}': expected WxH",
            clip_input(size, MAX_QUOTED_CHARS)
        )));
    };
    let req = q.request((w, h));
    if let Err(s) = crate::net::service::check_frame(&req) {
        return http_error(&s);
    }
    match app.backend.render(&app.shared, &md, req).await {
        Ok(r) => (
            [
                (header::CONTENT_TYPE, "image/png".to_owned()),
                (header::CACHE_CONTROL, "no-store".to_owned()),
                (
                    header::HeaderName::from_static("x-naadf-version"),
                    r.version.to_string(),
                ),
            ],
            r.image,
        )
            .into_response(),
        Err(s) => http_error(&s),
    }
}

fn ago(t: SystemTime) -> String {
    let s = SystemTime::now().duration_since(t).map_or(0, |d| d.as_secs());
    format!("{s} s ago")
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// Percent-encodes `s` for a URL query value.
fn url_escape(s: &str) -> String {
    s.bytes()
        .map(|b| match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'_' | b'.' | b'~' => (b as char).to_string(),
            _ => format!("%{b:02X}"),
        })
        .collect()
}

/// The status page; its `?token=` (on servers with tokens) is passed on to its live frame.
async fn status_page(
    State(app): State<App>,
    ConnectInfo(peer): ConnectInfo<SocketAddr>,
    headers: HeaderMap,
    token: TokenQuery,
) -> Response {
    let page_token = token.as_ref().ok().and_then(|Query(t)| t.token.clone());
    // Any role will do.
    let caller = match credentials(headers, token) {
        Ok(md) => app.backend.caller(&md, peer).await,
        Err(s) => Err(s),
    };
    if let Err(s) = caller {
        return http_error(&s);
    }
    let Some(s) = crate::stream::messages::status(&app.actor).await else {
        return Html("<p>shutting down</p>".to_owned()).into_response();
    };
    let mut clients = String::new();
    for c in app.shared.activity.clients() {
        clients += &format!("<tr><td>{}</td><td>{}</td></tr>", escape(&c.user), ago(c.since));
    }
    let mut nodes = String::new();
    for n in app.shared.router.nodes() {
        nodes += &format!(
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            n.id,
            escape(&n.user),
            escape(&n.adapter),
            n.inflight,
            n.served,
            escape(&n.last_error)
        );
    }
    let size = naadf_world::WorldSize::new(s.size[0], s.size[1], s.size[2]).ok();
    let camera = size
        .and_then(|sz| naadf_world::raysets::fixed_cameras(sz).first().copied())
        .and_then(|c| serde_json::to_string(&c).ok())
        .unwrap_or_default();
    let token = page_token
        .map(|t| format!("&token={}", url_escape(&t)))
        .unwrap_or_default();
    let live = format!(
        "/frame.png?size=480x270&mode=albedo&camera={}{token}",
        url_escape(&camera)
    );
    let mut edits = String::new();
    for e in app.shared.activity.recent() {
        edits += &format!(
            "<tr><td>{}</td><td>{}</td><td>{}</td><td><code>{}</code></td></tr>",
            e.version,
            escape(&e.user),
            ago(e.at),
            escape(&e.summary)
        );
    }
    Html(format!(
        "<!doctype html><html><head><meta charset=utf-8><title>naadf</title>\
         <style>body{{font-family:sans-serif;margin:2em}}td,th{{padding:2px 10px;text-align:left}}</style></head><body>\
         <h1>naadf server</h1>\
         <table><tr><th>world</th><td>{}×{}×{} voxels</td></tr>\
         <tr><th>version</th><td>{} (growth step {})</td></tr>\
         <tr><th>digest</th><td><code>{}</code></td></tr>\
         <tr><th>quiescent</th><td>{}</td></tr></table>\
         <h2>Clients ({})</h2><table><tr><th>user</th><th>joined</th></tr>{clients}</table>\
         <h2>Render nodes</h2><table id=nodes><tr><th>id</th><th>user</th><th>adapter</th><th>in flight</th>\
         <th>frames</th><th>last error</th></tr>{nodes}</table>\
         <h2>Live frame</h2><p><img id=live alt=\"no render node yet\" src=\"{live}\" width=480 height=270></p>\
         <script>const live=document.getElementById('live');const src=live.src;\
         live.onload=()=>{{document.body.dataset.liveWidth=live.naturalWidth;}};\
         if(live.complete&&live.naturalWidth){{document.body.dataset.liveWidth=live.naturalWidth;}}\
         setInterval(()=>{{live.src=src+'&t='+Date.now();}},2000);</script>\
         <h2>Recent edits</h2><table><tr><th>version</th><th>user</th><th>when</th><th>ops</th></tr>{edits}</table>\
         <p><a href=/metrics>metrics</a> · <a href=/health>health</a></p></body></html>",
        s.size[0],
        s.size[1],
        s.size[2],
        s.version,
        s.growth_seq,
        s.digest,
        s.quiescent,
        app.shared.activity.clients().len(),
    ))
    .into_response()
}

#[cfg(test)]
mod tests {
    use super::FrameQuery;
    use axum::extract::Query;
    use axum::http::Uri;

    fn request(query: &str) -> naadf_proto::v1::FrameRequest {
        let uri: Uri = format!("/frame.png?{query}").parse().unwrap();
        let Query(q) = Query::<FrameQuery>::try_from_uri(&uri).unwrap();
        q.request((8, 6))
    }

    #[test]
    fn the_frame_query_carries_the_lit_options() {
        let r = request("camera=%7B%7D&mode=roma&bounces=2&exposure=0.5&roma_directions=9&ao_range=48.5");
        assert_eq!((r.camera.as_str(), r.mode.as_str()), ("{}", "roma"));
        assert_eq!((r.width, r.height, r.bounces, r.exposure), (8, 6, Some(2), 0.5));
        assert_eq!((r.roma_directions, r.ao_range), (Some(9), Some(48.5)));
        let r = request("camera=%7B%7D&mode=irradiance&irradiance_rays=4096");
        assert_eq!((r.mode.as_str(), r.irradiance_rays), ("irradiance", Some(4096)));
        // Absent, they stay absent: the render node takes its defaults.
        let r = request("camera=%7B%7D");
        assert_eq!((r.mode.as_str(), r.roma_directions, r.ao_range), ("albedo", None, None));
        assert_eq!(r.irradiance_rays, None);
        // A value that is not a number is a bad query, not a request.
        for bad in ["roma_directions=many", "irradiance_rays=many", "irradiance_rays=-1"] {
            let uri: Uri = format!("/frame.png?camera=%7B%7D&{bad}").parse().unwrap();
            assert!(Query::<FrameQuery>::try_from_uri(&uri).is_err(), "{bad}");
        }
    }
}

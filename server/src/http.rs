//! The HTTP side (axum): `/health`, `/metrics` (Prometheus text format) and a small HTML
//! status page with the world, the joined clients and the recent edits.

use crate::Shared;
use crate::actor::Request;
use axum::Router;
use axum::extract::State;
use axum::http::{StatusCode, header};
use axum::response::{Html, IntoResponse, Json};
use axum::routing::get;
use std::sync::Arc;
use std::time::SystemTime;
use tokio::sync::mpsc;

#[derive(Clone)]
struct App {
    shared: Arc<Shared>,
    actor: mpsc::Sender<Request>,
}

/// The HTTP routes.
pub fn router(shared: Arc<Shared>, actor: mpsc::Sender<Request>) -> Router {
    Router::new()
        .route("/health", get(health))
        .route("/metrics", get(metrics))
        .route("/", get(status_page))
        .with_state(App { shared, actor })
}

async fn health(State(app): State<App>) -> impl IntoResponse {
    match crate::status(&app.actor).await {
        Some(s) => (
            StatusCode::OK,
            Json(serde_json::json!({
                "status": "ok",
                "version": s.version,
                "quiescent": s.quiescent,
                "digest": s.digest.to_string(),
            })),
        ),
        None => (
            StatusCode::SERVICE_UNAVAILABLE,
            Json(serde_json::json!({"status": "shutting down"})),
        ),
    }
}

async fn metrics(State(app): State<App>) -> impl IntoResponse {
    (
        [(
            header::CONTENT_TYPE,
            "application/openmetrics-text; version=1.0.0; charset=utf-8",
        )],
        app.shared.metrics.render(),
    )
}

fn ago(t: SystemTime) -> String {
    let s = SystemTime::now().duration_since(t).map_or(0, |d| d.as_secs());
    format!("{s} s ago")
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

async fn status_page(State(app): State<App>) -> impl IntoResponse {
    let Some(s) = crate::status(&app.actor).await else {
        return Html("<p>shutting down</p>".to_owned());
    };
    let mut clients = String::new();
    for c in app.shared.activity.clients() {
        clients += &format!("<tr><td>{}</td><td>{}</td></tr>", escape(&c.user), ago(c.since));
    }
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
}

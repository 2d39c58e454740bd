//! The browser page (`web/`, built into `web/dist`): embedded in the binary and served on
//! the **gRPC listener**, beside gRPC-web, so that the page and its calls share one origin
//! (no CORS) and one certificate; and the HTTP listener's `/`, which sends a browser there.
//!
//! The page and its assets are public: they hold no world data. Every call the page makes
//! is a gRPC-web call, with the same tokens and roles as any other client.

use axum::Router;
use axum::http::{HeaderMap, HeaderValue, StatusCode, Uri, header};
use axum::response::{IntoResponse, Redirect, Response};
use axum::routing::get;
use std::net::SocketAddr;

/// The built page, `web/dist`: `index.html` and the content-hashed files under `assets/`.
#[derive(rust_embed::RustEmbed)]
#[folder = "../web/dist"]
struct Bundle;

/// What the page may load: its own origin only. WebAssembly compiled from its own bytes
/// (the digest's xxh3) needs `wasm-unsafe-eval`; inline styles are the HUD's.
const CONTENT_SECURITY_POLICY: &str = "default-src 'self'; script-src 'self' 'wasm-unsafe-eval'; \
     style-src 'self' 'unsafe-inline'; img-src 'self' data: blob:; connect-src 'self'; \
     object-src 'none'; base-uri 'none'; frame-ancestors 'none'";

/// The page's routes: `/` (and `/index.html`) and `/assets/…`. They are merged beside the
/// gRPC services, outside the gRPC-web layer (which answers plain HTTP/1 requests with
/// 400).
pub(crate) fn routes() -> Router {
    Router::new()
        .route("/", get(index))
        .route("/index.html", get(index))
        .route("/assets/{*file}", get(asset))
}

/// The page itself. It names its assets by their content hash, so it is never cached
/// stale: `no-cache` makes the browser ask again each time.
async fn index() -> Response {
    serve("index.html", "no-cache")
}

/// A content-hashed asset: cached for good.
async fn asset(uri: Uri) -> Response {
    let path = uri.path().trim_start_matches('/');
    serve(path, "public, max-age=31536000, immutable")
}

/// The embedded file `path` with `cache_control`, or 404.
fn serve(path: &str, cache_control: &'static str) -> Response {
    let Some(file) = Bundle::get(path) else {
        return (StatusCode::NOT_FOUND, "no such file\n").into_response();
    };
    let mime = file.metadata.mimetype();
    let mut response = file.data.into_owned().into_response();
    let h = response.headers_mut();
    if let Ok(v) = HeaderValue::from_str(mime) {
        h.insert(header::CONTENT_TYPE, v);
    }
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static(cache_control));
    h.insert(
        header::CONTENT_SECURITY_POLICY,
        HeaderValue::from_static(CONTENT_SECURITY_POLICY),
    );
    h.insert(header::X_CONTENT_TYPE_OPTIONS, HeaderValue::from_static("nosniff"));
    response
}

/// Where the page lives: the gRPC listener's port, over https when it has TLS.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PageHome {
    /// The gRPC listener's bound address.
    pub grpc: SocketAddr,
    /// Whether it serves TLS.
    pub tls: bool,
}

impl PageHome {
    /// The page's URL for a browser that reached the HTTP listener under `host` (its
    /// `Host` header: the same name, the gRPC listener's port), keeping `query`. Without
    /// a usable `Host`, the gRPC listener's own address (loopback for an unspecified
    /// one).
    pub fn url(&self, host: Option<&str>, query: Option<&str>) -> String {
        let name = host
            .and_then(|h| h.parse::<axum::http::uri::Authority>().ok())
            .map(|a| a.host().to_owned())
            .filter(|h| !h.is_empty())
            .unwrap_or_else(|| {
                let ip = match self.grpc.ip() {
                    ip if ip.is_unspecified() && ip.is_ipv4() => std::net::Ipv4Addr::LOCALHOST.into(),
                    ip if ip.is_unspecified() => std::net::Ipv6Addr::LOCALHOST.into(),
                    ip => ip,
                };
                SocketAddr::new(ip, 0).to_string().trim_end_matches(":0").to_owned()
            });
        let scheme = if self.tls { "https" } else { "http" };
        let query = query
            .filter(|q| !q.is_empty())
            .map(|q| format!("?{q}"))
            .unwrap_or_default();
        format!("{scheme}://{name}:{}/{query}", self.grpc.port())
    }

    /// The HTTP listener's `/`: a redirect to the page.
    pub fn redirect_route(self) -> Router {
        Router::new().route(
            "/",
            get(move |headers: HeaderMap, uri: Uri| async move {
                let host = headers.get(header::HOST).and_then(|h| h.to_str().ok());
                Redirect::temporary(&self.url(host, uri.query()))
            }),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::PageHome;

    #[test]
    fn the_page_is_on_the_grpc_port_under_the_name_the_browser_used() {
        let home = PageHome {
            grpc: "0.0.0.0:50051".parse().unwrap(),
            tls: true,
        };
        assert_eq!(
            home.url(Some("example.org:8080"), Some("mode=gi&size=64x64")),
            "https://example.org:50051/?mode=gi&size=64x64"
        );
        assert_eq!(home.url(Some("[::1]:8080"), None), "https://[::1]:50051/");
        assert_eq!(home.url(None, Some("")), "https://127.0.0.1:50051/");
        let plain = PageHome {
            grpc: "127.0.0.1:4000".parse().unwrap(),
            tls: false,
        };
        assert_eq!(plain.url(Some("localhost"), None), "http://localhost:4000/");
    }

    #[test]
    fn the_bundle_holds_the_page() {
        let index = super::Bundle::get("index.html").expect("web/dist/index.html is embedded");
        let html = String::from_utf8_lossy(&index.data);
        assert!(html.contains("/assets/"), "the page loads its script from /assets/");
    }

    /// The committed bundle was built from the committed sources: `web/build-inputs.sha256`
    /// (written by `npm run build`) matches every source, generated and built file, and
    /// lists them all.
    #[test]
    fn the_built_page_is_up_to_date() {
        let web = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../web");
        let manifest = std::fs::read_to_string(web.join("build-inputs.sha256")).expect("web/build-inputs.sha256");
        let rebuild =
            "the page is stale: run `npm ci && npm run build` in web/ (Node >= 20; docs/WEB.md) and commit the result";
        let mut listed = std::collections::BTreeSet::new();
        for line in manifest.lines() {
            let (hash, path) = line.split_once("  ").expect("sha256sum lines");
            let bytes =
                std::fs::read(web.join(path)).unwrap_or_else(|_| panic!("{path} is listed but missing; {rebuild}"));
            let actual = ring::digest::digest(&ring::digest::SHA256, &bytes);
            let hex: String = actual.as_ref().iter().map(|b| format!("{b:02x}")).collect();
            assert_eq!(hex, hash, "{path} changed since the page was built; {rebuild}");
            listed.insert(path.to_owned());
        }
        for dir in ["src", "dist"] {
            for path in files_under(&web, dir) {
                assert!(listed.contains(&path), "{path} is not in the build; {rebuild}");
            }
        }
    }

    /// The files under `web/dir`, as paths relative to `web`.
    fn files_under(web: &std::path::Path, dir: &str) -> Vec<String> {
        let mut out = Vec::new();
        let mut todo = vec![dir.to_owned()];
        while let Some(d) = todo.pop() {
            for entry in std::fs::read_dir(web.join(&d)).unwrap() {
                let entry = entry.unwrap();
                let path = format!("{d}/{}", entry.file_name().to_string_lossy());
                if entry.file_type().unwrap().is_dir() {
                    todo.push(path);
                } else {
                    out.push(path);
                }
            }
        }
        out
    }
}

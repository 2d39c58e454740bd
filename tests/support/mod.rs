//! What the end-to-end tests share: running the real `naadf` binary, and a real server
//! process on ephemeral ports.
#![allow(dead_code)] // each test binary uses a different part

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::sync::OnceLock;
use std::time::Duration;

/// The binary the helpers run, when a test chose one other than the one Cargo built.
static BINARY: OnceLock<PathBuf> = OnceLock::new();

/// Makes every helper run `path` instead of the `naadf` Cargo built for the tests (the
/// build without the `gpu` feature, say). Call it first, once.
pub fn use_binary(path: PathBuf) {
    BINARY
        .set(path)
        .expect("the binary is chosen once, before anything runs");
}

/// The `naadf` binary the helpers run.
pub fn binary() -> &'static Path {
    BINARY.get_or_init(|| PathBuf::from(env!("CARGO_BIN_EXE_naadf")))
}

/// Runs `naadf` with `args`, feeding `stdin`.
pub fn naadf(args: &[&str], stdin: Option<&str>) -> Output {
    let mut child = Command::new(binary())
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn naadf");
    let mut input = child.stdin.take().unwrap();
    if let Some(s) = stdin {
        input.write_all(s.as_bytes()).unwrap();
    }
    drop(input);
    child.wait_with_output().unwrap()
}

/// Runs a command that must succeed; returns its stdout.
pub fn ok(args: &[&str], stdin: Option<&str>) -> String {
    let out = naadf(args, stdin);
    assert!(
        out.status.success(),
        "naadf {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// Runs a command that must fail cleanly: non-zero exit, a message, no panic.
pub fn fails(args: &[&str], stdin: Option<&str>, needle: &str) {
    let out = naadf(args, stdin);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "naadf {args:?} should fail");
    assert!(!err.contains("panicked"), "naadf {args:?} panicked: {err}");
    assert!(err.contains(needle), "naadf {args:?}: expected '{needle}' in: {err}");
}

/// `dir/name` as a string.
pub fn p(dir: &Path, name: &str) -> String {
    dir.join(name).to_str().unwrap().to_string()
}

/// A `naadf serve` (or `naadf relay`) process on ephemeral loopback ports.
pub struct Server {
    child: Child,
    /// gRPC URL (`http://127.0.0.1:PORT`).
    pub url: String,
    /// HTTP address (`127.0.0.1:PORT`).
    pub http: String,
    /// Where its log goes.
    pub log: PathBuf,
}

impl Server {
    /// Starts `naadf serve ARGS` (plus `--json`, and ephemeral loopback ports unless ARGS
    /// name `--grpc` or `--http`) and waits until it serves; `log` receives its stderr
    /// (appended, so restarts keep the history).
    pub fn start(args: &[&str], log: &Path, envs: &[(&str, &str)]) -> Server {
        Self::launch("serve", args, log, envs)
    }

    /// Starts `naadf relay --upstream UPSTREAM ARGS` the same way.
    pub fn relay(upstream: &str, args: &[&str], log: &Path) -> Server {
        let mut all = vec!["--upstream", upstream];
        all.extend_from_slice(args);
        Self::launch("relay", &all, log, &[])
    }

    /// Starts `naadf COMMAND --json ARGS` as [`Server::start`] describes.
    fn launch(command_name: &str, args: &[&str], log: &Path, envs: &[(&str, &str)]) -> Server {
        let err = std::fs::OpenOptions::new().create(true).append(true).open(log).unwrap();
        let mut command = Command::new(binary());
        command.arg(command_name).arg("--json");
        for flag in ["--grpc", "--http"] {
            if !args.contains(&flag) {
                command.args([flag, "127.0.0.1:0"]);
            }
        }
        let mut child = command
            .args(args)
            .envs(envs.iter().copied())
            .env("RUST_LOG", "info")
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::from(err))
            .spawn()
            .expect("spawn naadf");
        let stdout = child.stdout.take().unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let mut line = String::new();
            let _ = BufReader::new(stdout).read_line(&mut line);
            let _ = tx.send(line);
        });
        let line = rx.recv_timeout(Duration::from_secs(300)).unwrap_or_default();
        let Ok(v) = serde_json::from_str::<serde_json::Value>(&line) else {
            let _ = child.kill();
            panic!(
                "server did not start: {}",
                std::fs::read_to_string(log).unwrap_or_default()
            );
        };
        Server {
            child,
            url: format!("http://{}", v["grpc"].as_str().unwrap()),
            http: v["http"].as_str().unwrap().to_string(),
            log: log.to_owned(),
        }
    }

    /// The process id.
    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// `kill -9`.
    pub fn kill9(mut self) {
        self.child.kill().unwrap();
        self.child.wait().unwrap();
    }

    /// Sends signal `name` (`TERM`, `HUP`, ...).
    pub fn signal(&self, name: &str) {
        let st = Command::new("kill")
            .args([&format!("-{name}"), &self.child.id().to_string()])
            .status()
            .unwrap();
        assert!(st.success());
    }

    /// SIGTERM, then waits for a clean exit.
    pub fn stop(mut self) {
        self.signal("TERM");
        let status = self.child.wait().unwrap();
        assert!(
            status.success(),
            "server exited with {status}: {}",
            std::fs::read_to_string(&self.log).unwrap_or_default()
        );
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// `naadf serve --world WORLD --data DIR/data EXTRA` with `envs`, logging to
/// `DIR/server.log` (so restarts on the same directory resume the same data).
pub fn serve_world(dir: &Path, world: &str, extra: &[&str], envs: &[(&str, &str)]) -> Server {
    let data = p(dir, "data");
    let mut args = vec!["--world", world, "--data", data.as_str()];
    args.extend_from_slice(extra);
    Server::start(&args, &dir.join("server.log"), envs)
}

/// An HTTP GET on loopback (status line and body as text), without a client library.
pub fn http_get(addr: &str, path: &str) -> (u16, String) {
    let (code, body) = http_get_bytes(addr, path);
    (code, String::from_utf8_lossy(&body).into_owned())
}

/// An HTTP GET on loopback: the status code and the body bytes (responses with a
/// content length, as the server's are).
pub fn http_get_bytes(addr: &str, path: &str) -> (u16, Vec<u8>) {
    use std::io::Read;
    let mut s = std::net::TcpStream::connect(addr).unwrap();
    write!(s, "GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n").unwrap();
    let mut buf = Vec::new();
    s.read_to_end(&mut buf).unwrap();
    let split = buf.windows(4).position(|w| w == b"\r\n\r\n").unwrap_or(buf.len());
    let head = String::from_utf8_lossy(&buf[..split]);
    let code = head.split_whitespace().nth(1).unwrap().parse().unwrap();
    (code, buf.get(split + 4..).unwrap_or_default().to_vec())
}

/// The value of metric `name` (a whole number) in a Prometheus text page, if it is there.
pub fn metric_value(page: &str, name: &str) -> Option<u64> {
    page.lines()
        .find_map(|l| l.strip_prefix(name)?.strip_prefix(' ')?.trim().parse().ok())
}

/// Waits up to 30 s for what `read` reads to satisfy `ok`; the last read.
pub async fn wait_for<T: Copy>(read: impl Fn() -> T, ok: impl Fn(T) -> bool) -> T {
    for _ in 0..300 {
        let m = read();
        if ok(m) {
            return m;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    read()
}

/// A free loopback address, `127.0.0.1:PORT` (bound, then released): for a server that
/// must come back on the same address, or a listener a command is told to open.
pub fn free_addr() -> String {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    format!("127.0.0.1:{port}")
}

/// The server's state once it is quiescent.
pub async fn quiescent(url: &str) -> naadf_client::ServerStatus {
    let c = naadf_client::Client::connect(url, None, None).await.unwrap();
    for _ in 0..1200 {
        let s = c.status().await.unwrap();
        if s.quiescent {
            return s;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    panic!("the server did not settle");
}

/// A 128×64×128 terrain world file in `dir`.
pub fn start_world(dir: &Path) -> String {
    let w = p(dir, "start.naadf");
    ok(
        &[
            "generate",
            "--preset",
            "terrain",
            "--size",
            "128,64,128",
            "--seed",
            "5",
            "-o",
            &w,
        ],
        None,
    );
    w
}

/// A deterministic random op inside a 128×64×128 world (SplitMix64 stream).
pub fn random_op(state: &mut u64) -> String {
    let mut next = |n: u64| {
        *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = *state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        (z ^ (z >> 31)) % n
    };
    let (x, y, z) = (next(128), next(64), next(128));
    let m = next(6);
    match next(4) {
        0 => format!(
            r#"{{"op":"set","voxels":[[{x},{y},{z},{m}],[{},{y},{z},{}]]}}"#,
            (x + 1) % 128,
            next(4) + 1
        ),
        1 => format!(
            r#"{{"op":"sphere","center":[{x},{y},{z}],"radius":{},"material":{m}}}"#,
            1 + next(8)
        ),
        2 => format!(
            r#"{{"op":"box","min":[{x},{y},{z}],"max":[{},{},{}],"material":{m}}}"#,
            x + next(12),
            y + next(12),
            z + next(12)
        ),
        _ => format!(
            r#"{{"op":"paint","center":[{x},{y},{z}],"radius":{},"material":{}}}"#,
            1 + next(6),
            m.max(1)
        ),
    }
}

/// A client that joins and then never reads. Small HTTP/2 windows keep its transport
/// from taking megabytes first, so what it pins is what the server queues for it.
pub async fn stalled_client(url: &str) -> tonic::Streaming<naadf_proto::v1::WorldMessage> {
    let channel = tonic::transport::Endpoint::from_shared(url.to_owned())
        .unwrap()
        .initial_stream_window_size(Some(65_535))
        .initial_connection_window_size(Some(65_535))
        .connect()
        .await
        .unwrap();
    let mut raw = naadf_proto::v1::world_service_client::WorldServiceClient::new(channel);
    raw.join(naadf_client::Mirror::new(None).join_request())
        .await
        .unwrap()
        .into_inner()
}

/// The `define_model` op of a small "crate" model, and three crates of it to spawn (ids
/// 1–3, rotated 45° about y), as the entity tests use them.
pub fn crates() -> (&'static str, Vec<naadf_client::Spawn>) {
    let model = r#"{"op":"define_model","name":"crate","size":[3,2,3],"voxels":[[0,0,0,2],[1,1,1,3],[2,0,2,4]]}"#;
    let rot = [0.0, 0.38268343236508984, 0.0, 0.9238795325112867];
    let spawns = (1..=3)
        .map(|id| naadf_client::Spawn {
            model: "crate".into(),
            pose: naadf_client::Pose {
                id,
                pos: [20.0 * f64::from(id), 50.0, 30.0],
                rot,
            },
        })
        .collect();
    (model, spawns)
}

//! `naadf bench flood`: a server under a descriptor limit, flooded with connections that
//! hold a descriptor and never make a request, while a mirror and an editor that connected
//! before keep working and newcomers ask for `/health` and `status`.
//!
//! The flood, by default the one the service is held to (docs/RELIABILITY.md):
//! - HTTP/2 prefaces to the gRPC port, then silence;
//! - partial HTTP requests to the HTTP port, then silence;
//! - HTTP/2 connections to the gRPC port that finish the handshake and answer every ping,
//!   but send no request;
//! - slowloris clients on the HTTP port: a partial request, then a byte every 5 s.
//!
//! With `--reconnect`, every flood connection the server closes is opened again at once.
//! Reported: how long `/health` and `status` take from a new connection (probed every
//! second), the editor's acknowledgement latency, whether the mirror received every
//! version, and how many flood connections the server closed.

use super::shared::{Latency, Proc, http_get};
use super::stream::{points, voxel_op};
use crate::commands::args::PresetArgs;
use crate::commands::print_json;
use crate::commands::remote::block_on;
use anyhow::{Context, Result, bail};
use naadf_client::Client;
use serde::Serialize;
use std::process::Command;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};
use tokio::io::AsyncWriteExt;
use tokio::net::TcpStream;

/// Arguments of `bench flood`.
#[derive(clap::Args)]
pub struct FloodArgs {
    #[command(flatten)]
    preset: PresetArgs,
    /// The server's descriptor limit (soft and hard), set with `prlimit`.
    #[arg(long, default_value_t = 256)]
    nofile: u64,
    /// HTTP/2 prefaces to the gRPC port.
    #[arg(long, default_value_t = 200)]
    prefaces: usize,
    /// Partial HTTP requests to the HTTP port.
    #[arg(long, default_value_t = 200)]
    partial: usize,
    /// HTTP/2 connections that answer pings but send no request.
    #[arg(long, default_value_t = 20)]
    silent_h2: usize,
    /// Slowloris clients on the HTTP port.
    #[arg(long, default_value_t = 50)]
    slowloris: usize,
    /// Reopen every flood connection the server closes.
    #[arg(long)]
    reconnect: bool,
    /// Seconds of flood (with probes and edits).
    #[arg(long, default_value_t = 30.0)]
    seconds: f64,
    /// Extra `naadf serve` arguments (for instance `--max-connections=100`); none: the
    /// defaults.
    #[arg(long, allow_hyphen_values = true, value_delimiter = ' ')]
    serve_args: Vec<String>,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

/// What one run measured.
#[derive(Serialize)]
struct Report {
    nofile: u64,
    serve_args: Vec<String>,
    flood: [usize; 4],
    reconnect: bool,
    seconds: f64,
    health_ms: Latency,
    status_ms: Latency,
    /// Probes that failed, or got no answer within 30 s.
    failed_probes: usize,
    ack_ms: Latency,
    edits: u64,
    /// Whether the mirror ended at the editor's last version with no error.
    mirror_complete: bool,
    /// Flood connections the server closed.
    flood_closed: u64,
    /// Whether the target held: probes within 5 s, acknowledgements within 2 s, the mirror
    /// complete.
    target_held: bool,
}

/// The kinds of flood connection.
#[derive(Clone, Copy)]
enum Flood {
    Preface,
    Partial,
    SilentH2,
    Slowloris,
}

/// One flood connection, reopened after the server closes it if `reconnect`; counts
/// closures in `closed`.
async fn flood(kind: Flood, addr: String, reconnect: bool, closed: Arc<AtomicU64>) {
    loop {
        let Ok(s) = TcpStream::connect(&addr).await else {
            tokio::time::sleep(Duration::from_millis(100)).await;
            continue;
        };
        match kind {
            Flood::Preface => hold(s, b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n", None).await,
            Flood::Partial => hold(s, b"GET /health HTTP/1.1\r\nHost: x\r\n", None).await,
            Flood::Slowloris => hold(s, b"GET /health HTTP/1.1\r\nHost: x\r\n", Some(Duration::from_secs(5))).await,
            Flood::SilentH2 => {
                // The connection answers pings and settings until the server closes it;
                // the request handle is kept, or the client would close it itself.
                if let Ok((send, connection)) = h2::client::handshake(s).await {
                    let _ = connection.await;
                    drop(send);
                }
            }
        }
        closed.fetch_add(1, Ordering::Relaxed);
        if !reconnect {
            return;
        }
    }
}

/// Sends `first`, then a byte every `trickle` (or nothing), until the server closes the
/// connection.
async fn hold(mut s: TcpStream, first: &[u8], trickle: Option<Duration>) {
    use tokio::io::AsyncReadExt;
    if s.write_all(first).await.is_err() {
        return;
    }
    let (mut r, mut w) = s.split();
    let reading = async {
        let mut buf = [0u8; 1024];
        while matches!(r.read(&mut buf).await, Ok(n) if n > 0) {}
    };
    let writing = async {
        match trickle {
            Some(every) => loop {
                tokio::time::sleep(every).await;
                if w.write_all(b"x").await.is_err() {
                    return;
                }
            },
            None => std::future::pending().await,
        }
    };
    tokio::select! {
        () = reading => {}
        () = writing => {}
    }
}

/// Runs the benchmark.
pub fn run(a: FloodArgs) -> Result<()> {
    let world = a.preset.generate()?;
    let pts = points(&world, 1024, a.preset.seed);
    let dir = tempfile::tempdir()?;
    let file = dir.path().join("world.naadf");
    naadf_world::file::write(&world, &mut std::io::BufWriter::new(std::fs::File::create(&file)?))?;
    drop(world);
    let mut serve = Command::new("prlimit");
    serve
        .arg(format!("--nofile={0}:{0}", a.nofile))
        .arg(std::env::current_exe()?)
        .args([
            "serve",
            "--json",
            "--grpc",
            "127.0.0.1:0",
            "--http",
            "127.0.0.1:0",
            "--rate",
            "1000",
        ])
        .arg("--data")
        .arg(dir.path().join("data"))
        .arg("--world")
        .arg(&file)
        .args(a.serve_args.iter().filter(|s| !s.is_empty()));
    let server = Proc::start(serve).context("cannot start the server under prlimit (util-linux)")?;
    let (url, http) = server.addresses()?;
    let grpc = url.trim_start_matches("http://").to_owned();
    let report = block_on(async {
        // The mirror and the editor connect before the flood, and have made a request (a
        // connection that has not is one of the flood to the server).
        let editor = Client::connect(&url, None, None).await?;
        editor.status().await?;
        let mut session = Client::connect(&url, None, None).await?.join(None).await?;
        session.until_quiescent(0, Duration::from_secs(60)).await?;
        let (seen_tx, seen) = tokio::sync::watch::channel(0u64);
        let mirror = tokio::spawn(async move {
            let result = session
                .follow(std::future::pending::<()>(), |m| -> Result<std::ops::ControlFlow<()>> {
                    if let Some(w) = m.world() {
                        seen_tx.send_replace(w.version());
                    }
                    Ok(std::ops::ControlFlow::Continue(()))
                })
                .await;
            result.map(|_| ())
        });

        let closed = Arc::new(AtomicU64::new(0));
        let kinds = [
            (Flood::Preface, a.prefaces, &grpc),
            (Flood::Partial, a.partial, &http),
            (Flood::SilentH2, a.silent_h2, &grpc),
            (Flood::Slowloris, a.slowloris, &http),
        ];
        let mut flooding = Vec::new();
        for (kind, n, addr) in kinds {
            for _ in 0..n {
                flooding.push(tokio::spawn(flood(kind, addr.clone(), a.reconnect, closed.clone())));
            }
        }
        tokio::time::sleep(Duration::from_millis(500)).await;
        eprintln!("flood open: {} connections", flooding.len());

        let started = Instant::now();
        let run_for = Duration::from_secs_f64(a.seconds);
        let probing = probe(url.clone(), http.clone(), run_for);
        let editing = async {
            let mut acks = Vec::new();
            let mut last = 0;
            let mut k = 0;
            while started.elapsed() < run_for {
                let sent = Instant::now();
                last = editor.edit(voxel_op(pts[k % pts.len()], k), 0).await?.version;
                acks.push(sent.elapsed().as_secs_f64() * 1e3);
                k += 1;
                tokio::time::sleep(Duration::from_millis(200)).await;
            }
            anyhow::Ok((acks, last))
        };
        let ((health, status, failed_probes), edited) = tokio::join!(probing, editing);
        let (acks, last) = edited?;
        let mut seen = seen;
        let reached = tokio::time::timeout(Duration::from_secs(10), seen.wait_for(|&v| v >= last)).await;
        let mirror_complete = matches!(reached, Ok(Ok(_))) && !mirror.is_finished();
        mirror.abort();
        for f in &flooding {
            f.abort();
        }
        let health_ms = Latency::of(health);
        let status_ms = Latency::of(status);
        let ack_ms = Latency::of(acks.clone());
        let target_held = failed_probes == 0
            && health_ms.max < 5000.0
            && status_ms.max < 5000.0
            && ack_ms.max < 2000.0
            && mirror_complete;
        anyhow::Ok(Report {
            nofile: a.nofile,
            serve_args: a.serve_args.clone(),
            flood: [a.prefaces, a.partial, a.silent_h2, a.slowloris],
            reconnect: a.reconnect,
            seconds: a.seconds,
            health_ms,
            status_ms,
            failed_probes,
            ack_ms,
            edits: acks.len() as u64,
            mirror_complete,
            flood_closed: closed.load(Ordering::Relaxed),
            target_held,
        })
    })?;
    drop(server);
    if a.json {
        print_json(&report)?;
    } else {
        let s = |x: &Latency| format!("p50 {:.1} ms, p99 {:.1} ms, max {:.1} ms", x.p50, x.p99, x.max);
        println!("/health from a new connection: {}", s(&report.health_ms));
        println!("status from a new connection:  {}", s(&report.status_ms));
        println!(
            "edit acknowledgements:         {} ({} edits)",
            s(&report.ack_ms),
            report.edits
        );
        println!(
            "mirror complete: {}; failed probes: {}; flood connections closed: {}",
            report.mirror_complete, report.failed_probes, report.flood_closed
        );
        println!("target held: {}", report.target_held);
    }
    if !report.target_held {
        bail!("the target did not hold");
    }
    Ok(())
}

/// Asks `/health` (HTTP) and `status` (gRPC), each from a new connection, once a second
/// for `run_for`: their latencies in ms, and how many failed or got no answer within 30 s.
async fn probe(url: String, http: String, run_for: Duration) -> (Vec<f64>, Vec<f64>, usize) {
    let limit = Duration::from_secs(30);
    let (mut health, mut status, mut failed) = (Vec::new(), Vec::new(), 0);
    let started = Instant::now();
    while started.elapsed() < run_for {
        let round = Instant::now();
        let t = Instant::now();
        let h = http.clone();
        let answered = tokio::time::timeout(limit, tokio::task::spawn_blocking(move || http_get(&h, "/health"))).await;
        match answered {
            Ok(Ok(Some(_))) => health.push(t.elapsed().as_secs_f64() * 1e3),
            _ => failed += 1,
        }
        let t = Instant::now();
        let asked =
            tokio::time::timeout(limit, async { Client::connect(&url, None, None).await?.status().await }).await;
        match asked {
            Ok(Ok(_)) => status.push(t.elapsed().as_secs_f64() * 1e3),
            _ => failed += 1,
        }
        tokio::time::sleep(Duration::from_secs(1).saturating_sub(round.elapsed())).await;
    }
    (health, status, failed)
}

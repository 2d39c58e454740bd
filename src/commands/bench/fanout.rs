//! `naadf bench fanout`: a server, relays and many receive-only clients, each a process of
//! its own, as they would run on separate machines. For each relay count and client count:
//! edit → received latency (p50, p99) at every client, the server's CPU and bytes out per
//! client, and the relays' CPU per client.
//!
//! A receive-only client (`naadf bench fanout-client`, hidden) joins, then decodes and
//! timestamps every delta without applying it, so that what is measured is the fan-out,
//! not the clients' own work. A few full mirrors ride along and check every digest. Edits
//! go to the server at a fixed rate from this process; clients sit behind the relays
//! round-robin (or on the server with no relay). Latency compares wall clocks of processes
//! on one machine.

use super::shared::{Proc, http_get, percentile};
use super::stream::{Editor, points, voxel_op};
use crate::commands::args::PresetArgs;
use crate::commands::print_json;
use crate::commands::remote::block_on;
use anyhow::{Context, Result, bail};
use naadf_client::{Client, MessageKind, Mirror};
use serde::Serialize;
use std::collections::HashMap;
use std::io::Write;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// Arguments of `bench fanout`.
#[derive(clap::Args)]
pub struct FanoutArgs {
    #[command(flatten)]
    preset: PresetArgs,
    /// Receive-only client counts.
    #[arg(long, value_delimiter = ',', default_value = "16,64,256")]
    clients: Vec<usize>,
    /// Relay counts (0: the clients join the server).
    #[arg(long, value_delimiter = ',', default_value = "0,1,4")]
    relays: Vec<usize>,
    /// Edits per second.
    #[arg(long, default_value_t = 200)]
    rate: u32,
    /// Seconds of edits per run.
    #[arg(long, default_value_t = 5.0)]
    seconds: f64,
    /// Each relay's client threads (`naadf relay --threads`).
    #[arg(long, default_value_t = 1)]
    relay_threads: usize,
    /// Full mirrors riding along (digests checked), besides the receive-only clients.
    #[arg(long, default_value_t = 2)]
    mirrors: usize,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

/// Arguments of the hidden `bench fanout-client`.
#[derive(clap::Args)]
pub struct FanoutClientArgs {
    /// Server or relay URL.
    #[arg(long)]
    server: String,
    /// Apply the stream to a mirror and check every digest (a full mirror).
    #[arg(long)]
    mirror: bool,
}

/// One run's figures.
#[derive(Serialize)]
struct RunReport {
    relays: usize,
    clients: usize,
    edits: usize,
    /// Edit sent → delta received at a client, over every client and edit.
    p50_ms: f64,
    p99_ms: f64,
    max_ms: f64,
    /// (client, edit) pairs never received.
    missing: usize,
    /// Server CPU seconds per second of the run, per client.
    server_cpu_per_client: f64,
    /// Bytes of stream messages the server sent during the run, per client.
    server_bytes_per_client: f64,
    /// The relays' CPU seconds per second of the run, together, per client.
    relay_cpu_per_client: f64,
    /// The full mirrors ended on the server's digest.
    mirrors_agree: bool,
}

#[derive(Serialize)]
struct Report {
    rate: u32,
    seconds: f64,
    relay_threads: usize,
    runs: Vec<RunReport>,
}

/// Microseconds since the Unix epoch: comparable across processes on one machine.
fn unix_micros() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_micros() as u64)
}

/// Runs one receive-only client (or full mirror) until its standard input closes, then
/// prints `version micros` for the first delta of every version, and `digest D` for a
/// mirror. It prints `ready` once its snapshot is complete.
pub fn client(a: FanoutClientArgs) -> Result<()> {
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().build()?;
    rt.block_on(async move {
        let client = Client::connect(&a.server, None, None).await?;
        let mut mirror = Mirror::default();
        let mut stream = client.stream(mirror.join_request()).await?;
        let (closed_tx, mut closed) = tokio::sync::oneshot::channel();
        std::thread::spawn(move || {
            let _ = std::io::copy(&mut std::io::stdin().lock(), &mut std::io::sink());
            let _ = closed_tx.send(());
        });
        let mut pages_left: Option<u32> = None;
        let mut ready = false;
        let mut times: Vec<(u64, u64)> = Vec::new();
        loop {
            let m = tokio::select! {
                m = stream.message() => match m? { Some(m) => m, None => break },
                _ = &mut closed => break,
            };
            let now = unix_micros();
            if a.mirror {
                mirror.handle(&m)?;
            }
            match MessageKind::of(&m)? {
                MessageKind::Header { pages } => pages_left = Some(pages),
                MessageKind::Page => pages_left = pages_left.map(|p| p.saturating_sub(1)),
                MessageKind::Delta { version, growth_seq } => {
                    if growth_seq == 0 && times.last().is_none_or(|&(v, _)| v < version) {
                        times.push((version, now));
                    }
                }
                MessageKind::Presence | MessageKind::Unknown => {}
            }
            if !ready && pages_left == Some(0) {
                ready = true;
                println!("ready");
                std::io::stdout().flush()?;
            }
        }
        let mut out = std::io::stdout().lock();
        for (v, t) in times {
            writeln!(out, "{v} {t}")?;
        }
        if let Some(w) = mirror.world().filter(|_| a.mirror) {
            writeln!(out, "digest {}", w.digest())?;
        }
        writeln!(out, "end")?;
        Ok(())
    })
}

/// The server's `naadf_bytes_sent_total`.
fn bytes_sent(http: &str) -> Result<u64> {
    let metrics = http_get(http, "/metrics").context("no metrics")?;
    metrics
        .lines()
        .find_map(|l| l.strip_prefix("naadf_bytes_sent_total "))
        .and_then(|v| v.parse().ok())
        .context("no naadf_bytes_sent_total")
}

/// Runs the benchmark.
pub fn run(a: FanoutArgs) -> Result<()> {
    let world = a.preset.generate()?;
    let pts = points(&world, 4096, a.preset.seed);
    let dir = tempfile::tempdir()?;
    let file = dir.path().join("world.naadf");
    naadf_world::file::write(&world, &mut std::io::BufWriter::new(std::fs::File::create(&file)?))?;
    drop(world);
    let mut runs = Vec::new();
    for &relays in &a.relays {
        for &clients in &a.clients {
            let data = dir.path().join(format!("data-{relays}-{clients}"));
            let r = one_run(&a, &file, &data, relays, clients, &pts)?;
            eprintln!(
                "{relays} relays, {clients} clients: p50 {:.1} ms, p99 {:.1} ms, missing {}, server {:.0} B/client",
                r.p50_ms, r.p99_ms, r.missing, r.server_bytes_per_client
            );
            runs.push(r);
        }
    }
    let report = Report {
        rate: a.rate,
        seconds: a.seconds,
        relay_threads: a.relay_threads,
        runs,
    };
    if a.json {
        return print_json(&report);
    }
    println!(
        "{:>6} {:>7} {:>6} {:>8} {:>8} {:>8} {:>7} {:>14} {:>14} {:>14} {:>7}",
        "relays",
        "clients",
        "edits",
        "p50 ms",
        "p99 ms",
        "max ms",
        "missing",
        "srv CPU/client",
        "srv B/client",
        "relay CPU/cl",
        "digests"
    );
    for r in &report.runs {
        println!(
            "{:>6} {:>7} {:>6} {:>8.1} {:>8.1} {:>8.1} {:>7} {:>14.5} {:>14.0} {:>14.5} {:>7}",
            r.relays,
            r.clients,
            r.edits,
            r.p50_ms,
            r.p99_ms,
            r.max_ms,
            r.missing,
            r.server_cpu_per_client,
            r.server_bytes_per_client,
            r.relay_cpu_per_client,
            if r.mirrors_agree { "ok" } else { "DIFFER" }
        );
    }
    Ok(())
}

fn one_run(
    a: &FanoutArgs,
    file: &std::path::Path,
    data: &std::path::Path,
    relays: usize,
    clients: usize,
    pts: &[[u32; 3]],
) -> Result<RunReport> {
    let (file, data) = (file.to_str().context("path")?, data.to_str().context("path")?);
    let server = Proc::spawn(&[
        "serve",
        "--json",
        "--world",
        file,
        "--data",
        data,
        "--grpc",
        "127.0.0.1:0",
        "--http",
        "127.0.0.1:0",
        "--rate",
        "1000000",
        "--checkpoint-every",
        "1000000000",
        "--max-connections",
        "4096",
    ])?;
    let (server_url, server_http) = server.addresses()?;
    let mut relay_procs = Vec::new();
    let mut upstreams = Vec::new();
    for _ in 0..relays {
        let p = Proc::spawn(&[
            "relay",
            "--json",
            "--upstream",
            &server_url,
            "--grpc",
            "127.0.0.1:0",
            "--http",
            "127.0.0.1:0",
            "--max-connections",
            "4096",
            "--threads",
            &a.relay_threads.to_string(),
        ])?;
        let (url, http) = p.addresses()?;
        let t = Instant::now();
        while http_get(&http, "/health").is_none() {
            if t.elapsed() > Duration::from_secs(600) {
                bail!("a relay never got the world");
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        upstreams.push(url);
        relay_procs.push(p);
    }
    if upstreams.is_empty() {
        upstreams.push(server_url.clone());
    }
    let mut receivers = Vec::new();
    for k in 0..clients + a.mirrors {
        let url = &upstreams[k % upstreams.len()];
        let mut args = vec!["bench", "fanout-client", "--server", url.as_str()];
        if k >= clients {
            args.push("--mirror");
        }
        receivers.push(Proc::spawn(&args)?);
    }
    for r in &receivers {
        let line = r.line(Duration::from_secs(600))?;
        if line != "ready" {
            bail!("a client said '{line}' instead of ready");
        }
    }

    let started = Instant::now();
    let server_cpu = server.cpu_ns();
    let relay_cpu: u64 = relay_procs.iter().map(Proc::cpu_ns).sum();
    let bytes_before = bytes_sent(&server_http)?;
    let sent = block_on(async {
        let editor = Editor::connect(&server_url).await?;
        let n = (f64::from(a.rate) * a.seconds).round() as usize;
        let mut ticker = tokio::time::interval(Duration::from_secs_f64(1.0 / f64::from(a.rate.max(1))));
        let mut tasks = Vec::with_capacity(n);
        for k in 0..n {
            ticker.tick().await;
            let op = voxel_op(pts[k % pts.len()], k);
            tasks.push(editor.spawn(|c| async move {
                let at = unix_micros();
                c.edit(op, 0).await.map(|ack| (ack.version, at))
            }));
        }
        let mut sent = HashMap::new();
        for t in tasks {
            let (version, at) = t.await??;
            sent.insert(version, at);
        }
        // Every client has had time to take the last delta once the server is quiescent
        // and a moment has passed.
        let t = Instant::now();
        while !editor.quiescent().await? && t.elapsed() < Duration::from_secs(60) {
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
        tokio::time::sleep(Duration::from_secs(1)).await;
        Ok(sent)
    })?;
    let elapsed = started.elapsed().as_secs_f64();
    let server_cpu = (server.cpu_ns() - server_cpu) as f64 / 1e9 / elapsed;
    let relay_cpu = (relay_procs.iter().map(Proc::cpu_ns).sum::<u64>() - relay_cpu) as f64 / 1e9 / elapsed;
    let server_bytes = bytes_sent(&server_http)? - bytes_before;
    let status = block_on(async { Ok(Client::connect(&server_url, None, None).await?.status().await?) })?;

    for r in &mut receivers {
        r.close_stdin();
    }
    let mut latencies = Vec::new();
    let mut missing = 0;
    let mut mirrors_agree = true;
    for (k, r) in receivers.iter().enumerate() {
        let mut seen = HashMap::new();
        let mut digest = None;
        loop {
            let line = r.line(Duration::from_secs(120))?;
            if line == "end" {
                break;
            }
            if let Some(d) = line.strip_prefix("digest ") {
                digest = Some(d.to_owned());
            } else if let Some((v, t)) = line.split_once(' ') {
                seen.insert(v.parse::<u64>()?, t.parse::<u64>()?);
            }
        }
        if k >= clients {
            mirrors_agree &= digest == Some(status.digest.to_string());
            continue;
        }
        for (v, at) in &sent {
            match seen.get(v) {
                Some(t) => latencies.push(t.saturating_sub(*at) as f64 / 1000.0),
                None => missing += 1,
            }
        }
    }
    latencies.sort_by(f64::total_cmp);
    Ok(RunReport {
        relays,
        clients,
        edits: sent.len(),
        p50_ms: percentile(&latencies, 0.5),
        p99_ms: percentile(&latencies, 0.99),
        max_ms: latencies.last().copied().unwrap_or(f64::NAN),
        missing,
        server_cpu_per_client: server_cpu / clients as f64,
        server_bytes_per_client: server_bytes as f64 / clients as f64,
        relay_cpu_per_client: relay_cpu / clients as f64,
        mirrors_agree,
    })
}

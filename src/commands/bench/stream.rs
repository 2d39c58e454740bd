//! `naadf bench stream`: the server under load, in one process on loopback — join time and
//! bytes, rejoin cost, edit-to-every-client latency with 8/16/64 mirrors, bytes on the wire
//! per single-voxel edit (counted at the TCP level), sustained durable edits per second, and
//! the CPU time of an edit in each group of threads ([`super::cpu`]).

use super::applied::{Applied, caught_up};
use super::cpu::{Sample, UnitUsage};
use super::mirror_process::MirrorProcess;
use super::shared::{percentile, surface};
use crate::commands::args::PresetArgs;
use crate::commands::print_json;
use crate::commands::remote::block_on;
use anyhow::{Context, Result, bail};
use naadf_client::{Client, Mirror};
use naadf_server::{Bound, ServerConfig};
use naadf_world::World;
use naadf_world::raysets::SplitMix64;
use serde::Serialize;
use std::collections::{BTreeMap, HashMap};
use std::net::SocketAddr;
use std::ops::ControlFlow;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};
use tokio::io::AsyncWriteExt;
use tokio::sync::{oneshot, watch};

/// Arguments of `bench stream`.
#[derive(clap::Args)]
pub struct StreamArgs {
    #[command(flatten)]
    preset: PresetArgs,
    /// Mirror-client counts for the latency runs.
    #[arg(long, value_delimiter = ',', default_value = "8,16,64")]
    clients: Vec<usize>,
    /// Edits per second in the latency runs.
    #[arg(long, default_value_t = 200)]
    rate: u32,
    /// Seconds per latency run.
    #[arg(long, default_value_t = 5.0)]
    seconds: f64,
    /// Seconds of the sustained-load run.
    #[arg(long, default_value_t = 5.0)]
    sustain_seconds: f64,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct JoinReport {
    seconds: f64,
    bytes: u64,
    world_file_bytes: u64,
    ratio_to_file: f64,
    rejoin_after_100_edits_bytes: u64,
    rejoin_ratio: f64,
}

/// One latency run ([`latency_run`]).
#[derive(Serialize)]
pub(super) struct LatencyReport {
    clients: usize,
    /// Whether each mirror ran in a process of its own.
    mirror_processes: bool,
    edits: usize,
    rate: u32,
    pub(super) p50_ms: f64,
    pub(super) p99_ms: f64,
    pub(super) max_ms: f64,
    /// Edit sent → acknowledged (durable), the server's share of the latency.
    pub(super) ack_p50_ms: f64,
    pub(super) ack_p99_ms: f64,
    pub(super) incomplete: usize,
    /// CPU time per edit by thread group, from the first edit sent until every mirror
    /// applied the last (`clients` holds the mirrors in this process; mirrors in processes
    /// of their own count together as `mirror_processes`).
    pub(super) cpu_per_edit: BTreeMap<String, UnitUsage>,
}

#[derive(Serialize)]
struct Report {
    join: JoinReport,
    latency: Vec<LatencyReport>,
    wire_bytes_per_voxel_edit: f64,
    delta_message_bytes_per_voxel_edit: f64,
    sustained_edits_per_second: f64,
    /// CPU time per durable edit in the sustained run, by thread group.
    sustained_cpu_per_edit: BTreeMap<String, UnitUsage>,
    threads: usize,
}

/// A server running in this process on ephemeral ports, with a scratch data directory.
///
/// It runs on a tokio runtime of its own, on its own threads: the in-process mirrors do
/// milliseconds of CPU work per delta, and on a shared runtime they would hold up the
/// server's tasks cooperatively, which remote clients never do.
pub(super) struct LocalServer {
    bound: Bound,
    stop: Option<oneshot::Sender<()>>,
    thread: std::thread::JoinHandle<Result<()>>,
    _data: tempfile::TempDir,
}

impl LocalServer {
    pub(super) async fn start(world: World) -> Result<Self> {
        let data = tempfile::tempdir()?;
        let mut config = ServerConfig::new(data.path().join("data"));
        config.frontend.grpc = "127.0.0.1:0".parse()?;
        config.frontend.http = "127.0.0.1:0".parse()?;
        config.rate = 1_000_000;
        config.checkpoint_every = u64::MAX;
        config.frontend.slow_client_events = 1 << 16;
        let (stop, stopped) = oneshot::channel::<()>();
        let (ready_tx, ready_rx) = oneshot::channel();
        let thread = std::thread::spawn(move || {
            tokio::runtime::Builder::new_multi_thread()
                .worker_threads(2)
                .thread_name("server")
                .enable_all()
                .build()?
                .block_on(naadf_server::serve(
                    config,
                    move || Ok(world),
                    move |b| {
                        let _ = ready_tx.send(b);
                    },
                    async move {
                        let _ = stopped.await;
                    },
                ))
        });
        let bound = ready_rx.await.context("server did not start")?;
        Ok(Self {
            bound,
            stop: Some(stop),
            thread,
            _data: data,
        })
    }

    pub(super) fn url(&self) -> String {
        format!("http://{}", self.bound.grpc)
    }

    pub(super) async fn shutdown(mut self) -> Result<()> {
        if let Some(s) = self.stop.take() {
            let _ = s.send(());
        }
        tokio::task::spawn_blocking(move || self.thread.join())
            .await?
            .map_err(|_| anyhow::anyhow!("the server thread panicked"))?
    }
}

/// Joins and follows; records when each version was applied. Returns once `stop` is set.
struct Follower {
    applied: watch::Receiver<Option<u64>>,
    /// Message bytes received so far.
    bytes: Arc<AtomicU64>,
    stop: watch::Sender<bool>,
    task: tokio::task::JoinHandle<Result<(Mirror, Applied)>>,
}

async fn follow(url: &str, cache: Option<World>) -> Result<Follower> {
    let mut session = Client::connect(url, None, None).await?.join(cache).await?;
    let (applied_tx, applied) = watch::channel(None);
    let (stop, mut stopped) = watch::channel(false);
    let bytes = Arc::new(AtomicU64::new(0));
    let received = bytes.clone();
    let task = tokio::spawn(async move {
        let mut times = Vec::new();
        let stop = async move {
            let _ = stopped.changed().await;
        };
        session
            .follow(stop, |mirror| -> Result<ControlFlow<()>> {
                received.store(mirror.stats.bytes, Ordering::Relaxed);
                if let Some(w) = mirror.world().filter(|_| mirror.is_live()) {
                    let v = w.version();
                    if times.last().is_none_or(|&(last, _)| last < v) {
                        times.push((v, Instant::now()));
                    }
                    let _ = applied_tx.send(Some(v));
                }
                Ok(ControlFlow::Continue(()))
            })
            .await?;
        Ok((session.into_mirror(), times))
    });
    Ok(Follower {
        applied,
        bytes,
        stop,
        task,
    })
}

impl Follower {
    async fn wait_for(&mut self, version: u64) -> Result<()> {
        caught_up(&mut self.applied, version).await
    }

    async fn finish(self) -> Result<(Mirror, Applied)> {
        let _ = self.stop.send(true);
        self.task.await?
    }
}

/// The mirrors a latency run follows with.
#[derive(Clone, Copy, Debug)]
pub(super) struct Mirrors {
    /// How many.
    pub count: usize,
    /// Each in a `naadf mirror` process of its own, rather than in this process.
    pub processes: bool,
}

/// One mirror of a latency run.
enum Following {
    InProcess(Follower),
    Process(MirrorProcess),
}

impl Following {
    /// Starts a mirror of `url`: in this process from `cache`, or in a process of its own.
    async fn start(url: &str, cache: &Option<World>, process: bool) -> Result<Self> {
        Ok(if process {
            Following::Process(MirrorProcess::spawn(url)?)
        } else {
            Following::InProcess(follow(url, cache.clone()).await?)
        })
    }

    async fn wait_for(&mut self, version: u64) -> Result<()> {
        match self {
            Following::InProcess(f) => f.wait_for(version).await,
            Following::Process(p) => p.wait_for(version).await,
        }
    }

    /// The CPU time of a mirror in a process of its own (`None` in this process, where
    /// [`Sample`] counts it among the threads).
    fn process_cpu_ns(&self) -> Option<u64> {
        match self {
            Following::InProcess(_) => None,
            Following::Process(p) => p.cpu_ns(),
        }
    }

    async fn finish(self) -> Result<Applied> {
        match self {
            Following::InProcess(f) => Ok(f.finish().await?.1),
            Following::Process(p) => p.finish().await,
        }
    }
}

/// A TCP proxy counting the bytes the server sends to the client.
async fn counting_proxy(target: SocketAddr, count: Arc<AtomicU64>) -> Result<SocketAddr> {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await?;
    let addr = listener.local_addr()?;
    tokio::spawn(async move {
        while let Ok((inbound, _)) = listener.accept().await {
            let count = count.clone();
            tokio::spawn(async move {
                let Ok(outbound) = tokio::net::TcpStream::connect(target).await else {
                    return;
                };
                let _ = inbound.set_nodelay(true);
                let _ = outbound.set_nodelay(true);
                let (mut ri, mut wi) = inbound.into_split();
                let (mut ro, mut wo) = outbound.into_split();
                let up = tokio::spawn(async move { tokio::io::copy(&mut ri, &mut wo).await });
                let mut buf = vec![0u8; 1 << 16];
                loop {
                    use tokio::io::AsyncReadExt;
                    let n = match ro.read(&mut buf).await {
                        Ok(0) | Err(_) => break,
                        Ok(n) => n,
                    };
                    count.fetch_add(n as u64, Ordering::Relaxed);
                    if wi.write_all(&buf[..n]).await.is_err() {
                        break;
                    }
                }
                up.abort();
            });
        }
    });
    Ok(addr)
}

/// Surface points to edit at.
pub(super) fn points(world: &World, n: usize, seed: u64) -> Vec<[u32; 3]> {
    let size = world.size().voxels();
    let mut rng = SplitMix64(seed);
    let mut out = Vec::new();
    while out.len() < n {
        if let Some(p) = surface(world, rng.below(size[0]), rng.below(size[2])) {
            out.push(p);
        }
    }
    out
}

pub(super) fn voxel_op(p: [u32; 3], k: usize) -> String {
    format!(
        r#"{{"op":"set","voxels":[[{},{},{},{}]]}}"#,
        p[0],
        p[1] + 1,
        p[2],
        2 * (k % 2)
    )
}

async fn edit(c: &Client, ops: String) -> Result<u64> {
    Ok(c.edit(ops, 0).await?.version)
}

/// The editing client, on a tokio runtime of its own (one thread, `editor`), as the server
/// is: on the mirrors' runtime its requests and acknowledgements would queue behind their
/// work on every delta, which a remote editor never does.
pub(super) struct Editor {
    client: Client,
    /// Taken by `Drop`, which must not block inside the benchmark's runtime.
    rt: Option<tokio::runtime::Runtime>,
}

impl Editor {
    pub(super) async fn connect(url: &str) -> Result<Self> {
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .thread_name("editor")
            .enable_all()
            .build()?;
        let url = url.to_owned();
        // Connecting there puts the connection's own task on the editor's thread too.
        let client = rt
            .spawn(async move { Client::connect(&url, None, None).await })
            .await??;
        Ok(Self { client, rt: Some(rt) })
    }

    /// Runs `f` with the client on the editor's thread.
    pub(super) fn spawn<T, F>(&self, f: impl FnOnce(Client) -> F) -> tokio::task::JoinHandle<T>
    where
        T: Send + 'static,
        F: std::future::Future<Output = T> + Send + 'static,
    {
        let rt = self.rt.as_ref().expect("the runtime lives until drop");
        rt.spawn(f(self.client.clone()))
    }

    /// Applies one edit; returns its version.
    async fn edit(&self, ops: String) -> Result<u64> {
        self.spawn(|c| async move { edit(&c, ops).await }).await?
    }

    pub(super) async fn quiescent(&self) -> Result<bool> {
        Ok(self.spawn(|c| async move { c.status().await }).await??.quiescent)
    }
}

impl Drop for Editor {
    fn drop(&mut self) {
        if let Some(rt) = self.rt.take() {
            rt.shutdown_background();
        }
    }
}

/// Runs the benchmark.
pub fn run(a: StreamArgs) -> Result<()> {
    let world = a.preset.generate()?;
    let file_bytes = {
        let mut counter = CountingWriter(0);
        naadf_world::file::write(&world, &mut counter)?;
        counter.0
    };
    let pts = points(&world, 4096, a.preset.seed);
    block_on(async move {
        let server = LocalServer::start(world).await?;
        let url = server.url();
        let editor = Editor::connect(&url).await?;

        // Join: a fresh client, no cache.
        let t = Instant::now();
        let mut f = follow(&url, None).await?;
        f.wait_for(0).await?;
        let join_seconds = t.elapsed().as_secs_f64();
        let (mirror, _) = f.finish().await?;
        let join_bytes = mirror.stats.bytes;
        // Rejoin after 100 small edits.
        let mut last = 0;
        for (k, p) in pts.iter().take(100).enumerate() {
            last = editor.edit(voxel_op(*p, k)).await?;
        }
        let mut f = follow(&url, mirror.into_world()).await?;
        f.wait_for(last).await?;
        let (mirror, _) = f.finish().await?;
        let rejoin_bytes = mirror.stats.bytes;
        let join = JoinReport {
            seconds: join_seconds,
            bytes: join_bytes,
            world_file_bytes: file_bytes,
            ratio_to_file: join_bytes as f64 / file_bytes as f64,
            rejoin_after_100_edits_bytes: rejoin_bytes,
            rejoin_ratio: rejoin_bytes as f64 / join_bytes as f64,
        };
        eprintln!(
            "join: {join_seconds:.2} s, {join_bytes} B ({:.3}× the world file); rejoin {rejoin_bytes} B",
            join.ratio_to_file
        );

        // Bytes on the wire per single-voxel edit, through a counting proxy.
        let count = Arc::new(AtomicU64::new(0));
        let proxy = counting_proxy(server.bound.grpc, count.clone()).await?;
        let mut f = follow(&format!("http://{proxy}"), mirror.into_world()).await?;
        f.wait_for(last).await?;
        let (before, msg_before) = (count.load(Ordering::Relaxed), f.bytes.load(Ordering::Relaxed));
        let n = 1000;
        for k in 0..n {
            last = editor.edit(voxel_op(pts[(100 + k) % pts.len()], k + 1)).await?;
        }
        f.wait_for(last).await?;
        tokio::time::sleep(Duration::from_millis(200)).await;
        let wire = (count.load(Ordering::Relaxed) - before) as f64 / n as f64;
        let delta_msg = (f.bytes.load(Ordering::Relaxed) - msg_before) as f64 / n as f64;
        let (mirror, _) = f.finish().await?;
        eprintln!("wire: {wire:.1} B per single-voxel edit on TCP (framing included), {delta_msg:.1} B as messages");
        let cache = mirror.into_world();

        // Let the distance-field growth queued by the edits so far finish first.
        let t = Instant::now();
        while !editor.quiescent().await? {
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
        eprintln!("growth backlog drained in {:.2} s", t.elapsed().as_secs_f64());

        // Latency with N mirrors at a fixed edit rate (spheres of radius ≤ 8).
        let mut latency = Vec::new();
        for (run, &clients) in a.clients.iter().enumerate() {
            let edits = (f64::from(a.rate) * a.seconds) as usize;
            // Each run edits new places: repeating a run's edits would make them no-ops.
            let first = run * edits;
            let pts = pts.clone();
            let mirrors = Mirrors {
                count: clients,
                processes: false,
            };
            let r = latency_run(&url, &cache, &editor, mirrors, a.rate, edits, &mut last, move |c, k| {
                let p = pts[((first + k) * 7 + 3) % pts.len()];
                let r = 1 + (first + k) % 8;
                let ops = format!(
                    r#"{{"op":"sphere","center":[{},{},{}],"radius":{r},"material":{}}}"#,
                    p[0],
                    p[1],
                    p[2],
                    ((first + k) % 3) * 2
                );
                async move { edit(&c, ops).await }
            })
            .await?;
            eprintln!(
                "latency, {clients} clients: p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms (acknowledged: p50 {:.2} ms, p99 {:.2} ms)",
                r.p50_ms, r.p99_ms, r.max_ms, r.ack_p50_ms, r.ack_p99_ms
            );
            eprintln!("  CPU per edit: {}", describe(&r.cpu_per_edit));
            latency.push(r);
        }

        // Sustained durable edits per second: 32 requests in flight, single voxels.
        let stop_at = Instant::now() + Duration::from_secs_f64(a.sustain_seconds);
        let done = Arc::new(AtomicU64::new(0));
        let mut workers = Vec::new();
        for w in 0..32usize {
            let done = done.clone();
            let pts = pts.clone();
            workers.push(editor.spawn(|c| async move {
                let mut k = w;
                while Instant::now() < stop_at {
                    edit(&c, voxel_op(pts[k % pts.len()], k)).await?;
                    done.fetch_add(1, Ordering::Relaxed);
                    k += 32;
                }
                anyhow::Ok(())
            }));
        }
        let t = Instant::now();
        let cpu_before = Sample::now();
        for w in workers {
            w.await??;
        }
        let edits = done.load(Ordering::Relaxed);
        let sustained = edits as f64 / t.elapsed().as_secs_f64();
        let sustained_cpu = Sample::now().per_unit_since(&cpu_before, edits.max(1) as f64);
        eprintln!("sustained: {sustained:.0} durable edits/s");
        eprintln!("  CPU per edit: {}", describe(&sustained_cpu));
        server.shutdown().await?;

        let report = Report {
            join,
            latency,
            wire_bytes_per_voxel_edit: wire,
            delta_message_bytes_per_voxel_edit: delta_msg,
            sustained_edits_per_second: sustained,
            sustained_cpu_per_edit: sustained_cpu,
            threads: rayon::current_num_threads(),
        };
        if a.json {
            print_json(&report)?;
        }
        if report.join.seconds.is_nan() {
            bail!("no join measured");
        }
        Ok(())
    })
}

/// Edit-to-every-mirror latency: `mirrors` join (in this process from `cache`) and catch up to
/// `last`; then `count` requests go out through `editor` at `rate` a second, request `k`
/// sent by `request(client, k)`, which returns the version it made. Each version's latency
/// runs from sending it to the last mirror applying it. `last` becomes the newest version.
#[allow(clippy::too_many_arguments)]
pub(super) async fn latency_run<F, Fut>(
    url: &str,
    cache: &Option<World>,
    editor: &Editor,
    mirrors: Mirrors,
    rate: u32,
    count: usize,
    last: &mut u64,
    request: F,
) -> Result<LatencyReport>
where
    F: Fn(Client, usize) -> Fut,
    Fut: std::future::Future<Output = Result<u64>> + Send + 'static,
{
    let mut followers = Vec::new();
    for _ in 0..mirrors.count {
        followers.push(Following::start(url, cache, mirrors.processes).await?);
    }
    for f in &mut followers {
        f.wait_for(*last).await?;
    }
    let cpu_before = Sample::now();
    let mirrors_cpu = |followers: &[Following]| followers.iter().filter_map(Following::process_cpu_ns).sum::<u64>();
    let mirrors_before = mirrors_cpu(&followers);
    let start = tokio::time::Instant::now();
    let mut sent = Vec::new();
    for k in 0..count {
        tokio::time::sleep_until(start + Duration::from_secs_f64(k as f64 / f64::from(rate))).await;
        sent.push(editor.spawn(|c| {
            let sent = request(c, k);
            async move {
                let t0 = Instant::now();
                sent.await.map(|v| (v, t0, t0.elapsed()))
            }
        }));
    }
    let mut sent_at = HashMap::new();
    let mut acks = Vec::new();
    for s in sent {
        let (v, t0, ack) = s.await??;
        sent_at.insert(v, t0);
        acks.push(ack.as_secs_f64() * 1e3);
        *last = (*last).max(v);
    }
    acks.sort_by(f64::total_cmp);
    for f in &mut followers {
        f.wait_for(*last).await?;
    }
    let mut cpu = Sample::now().per_unit_since(&cpu_before, count as f64);
    if mirrors.processes {
        let ns = mirrors_cpu(&followers).saturating_sub(mirrors_before);
        cpu.insert(
            "mirror_processes".to_owned(),
            UnitUsage {
                cpu_ms: ns as f64 / 1e6 / count as f64,
                wait_ms: f64::NAN,
            },
        );
    }
    let mut done: HashMap<u64, Instant> = HashMap::new();
    let mut incomplete = 0;
    for f in followers {
        let times = f.finish().await?;
        let seen: HashMap<u64, Instant> = times.into_iter().collect();
        for &v in sent_at.keys() {
            match seen.get(&v) {
                Some(&t) => {
                    let e = done.entry(v).or_insert(t);
                    *e = (*e).max(t);
                }
                None => incomplete += 1,
            }
        }
    }
    let mut ms: Vec<f64> = sent_at
        .iter()
        .filter_map(|(v, t0)| done.get(v).map(|t| t.duration_since(*t0).as_secs_f64() * 1e3))
        .collect();
    ms.sort_by(f64::total_cmp);
    Ok(LatencyReport {
        clients: mirrors.count,
        mirror_processes: mirrors.processes,
        edits: count,
        rate,
        p50_ms: percentile(&ms, 0.5),
        p99_ms: percentile(&ms, 0.99),
        max_ms: ms.last().copied().unwrap_or(f64::NAN),
        ack_p50_ms: percentile(&acks, 0.5),
        ack_p99_ms: percentile(&acks, 0.99),
        incomplete,
        cpu_per_edit: cpu,
    })
}

/// "group 0.123 ms (wait 0.010 ms), ..." for a log line.
pub(super) fn describe(usage: &BTreeMap<String, UnitUsage>) -> String {
    usage
        .iter()
        .map(|(g, u)| {
            if u.wait_ms.is_nan() {
                format!("{g} {:.3} ms", u.cpu_ms)
            } else {
                format!("{g} {:.3} ms (waiting {:.3} ms)", u.cpu_ms, u.wait_ms)
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Counts bytes written.
struct CountingWriter(u64);

impl std::io::Write for CountingWriter {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0 += b.len() as u64;
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

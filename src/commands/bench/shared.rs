//! What the benchmarks share: percentiles and medians, the ratio report, the surface of a
//! world column, the entity model, and the processes (a server, its clients) a benchmark
//! starts and asks over HTTP.

use super::cpu::process_ns_of;
use anyhow::{Context, Result};
use naadf_world::World;
use naadf_world::ops::Op;
use naadf_world::traverse::{Ray, trace_naadf};
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Write};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

/// The first solid voxel below the top of the world at column (x, z), if any.
pub fn surface(world: &World, x: u32, z: u32) -> Option<[u32; 3]> {
    let top = f64::from(world.size().voxels()[1]) - 0.5;
    let ray = Ray::new([f64::from(x) + 0.5, top, f64::from(z) + 0.5], [0.0, -1.0, 0.0]).ok()?;
    trace_naadf(world, &ray).map(|h| h.voxel)
}

/// The `q` quantile (0–1) of `sorted`, by nearest rank; NaN when empty.
pub fn percentile(sorted: &[f64], q: f64) -> f64 {
    sorted
        .get(((sorted.len() as f64 - 1.0) * q).round() as usize)
        .copied()
        .unwrap_or(f64::NAN)
}

/// The median of `values` (nearest rank) and their lowest and highest; NaN when empty.
pub fn median_range(values: &[f64]) -> (f64, [f64; 2]) {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let (lo, hi) = (v.first().copied(), v.last().copied());
    (percentile(&v, 0.5), [lo.unwrap_or(f64::NAN), hi.unwrap_or(f64::NAN)])
}

/// Prints `naadf`'s speed-up over every other method measured, from Mrays/s per method.
pub fn print_ratios(prefix: &str, primary: &BTreeMap<&str, f64>, secondary: &BTreeMap<&str, f64>) {
    let ratio = |set: &BTreeMap<&str, f64>, other: &str| set.get(other).map_or(f64::NAN, |o| set["naadf"] / o);
    for &other in primary.keys().filter(|&&m| m != "naadf") {
        println!(
            "{prefix}naadf/{other}: primary {:.1}×, secondary {:.1}×",
            ratio(primary, other),
            ratio(secondary, other)
        );
    }
}

/// Defines the 8³ hollow-box model used by entity benchmarks.
pub fn entity_model_op() -> Op {
    let mut voxels = Vec::new();
    for z in 0..8i64 {
        for y in 0..8i64 {
            for x in 0..8i64 {
                if [x, y, z].iter().any(|&c| c == 0 || c == 7) {
                    voxels.push([x, y, z, 1]);
                }
            }
        }
    }
    Op::DefineModel {
        name: "bench_box".into(),
        size: [8, 8, 8],
        voxels,
    }
}

/// Latency percentiles and the largest latency, in milliseconds.
#[derive(serde::Serialize)]
pub struct Latency {
    /// The median.
    pub p50: f64,
    /// The 99th percentile.
    pub p99: f64,
    /// The largest.
    pub max: f64,
}

impl Latency {
    /// The latencies `ms` (in any order) summed up.
    pub fn of(mut ms: Vec<f64>) -> Latency {
        ms.sort_by(f64::total_cmp);
        Latency {
            p50: percentile(&ms, 0.5),
            p99: percentile(&ms, 0.99),
            max: ms.last().copied().unwrap_or(f64::NAN),
        }
    }
}

/// A child process and the lines of its standard output.
pub struct Proc {
    child: Child,
    lines: mpsc::Receiver<String>,
    stdin: Option<ChildStdin>,
}

impl Proc {
    /// Starts this program with `args`.
    pub fn spawn(args: &[&str]) -> Result<Self> {
        let mut command = Command::new(std::env::current_exe()?);
        command.args(args);
        Self::start(command)
    }

    /// Starts `command`, its output piped (line by line) and its errors dropped.
    pub fn start(mut command: Command) -> Result<Self> {
        let mut child = command
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .context("cannot start a process")?;
        let stdout = child.stdout.take().expect("piped");
        let (tx, lines) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines() {
                let Ok(line) = line else { break };
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        let stdin = child.stdin.take();
        Ok(Self { child, lines, stdin })
    }

    /// Closes its standard input (which tells a fanout client to stop).
    pub fn close_stdin(&mut self) {
        self.stdin = None;
    }

    /// The next line it printed, waiting at most `timeout`.
    pub fn line(&self, timeout: Duration) -> Result<String> {
        self.lines.recv_timeout(timeout).context("a process did not answer")
    }

    /// The addresses a `serve --json` or `relay --json` prints.
    pub fn addresses(&self) -> Result<(String, String)> {
        let v: serde_json::Value = serde_json::from_str(&self.line(Duration::from_secs(600))?)?;
        let field = |k: &str| v[k].as_str().map(str::to_owned).context("no address");
        Ok((format!("http://{}", field("grpc")?), field("http")?))
    }

    /// The CPU time it used so far.
    pub fn cpu_ns(&self) -> u64 {
        process_ns_of(&self.child.id().to_string()).unwrap_or(0)
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// An HTTP GET on loopback: the body, if the status is 200.
pub fn http_get(addr: &str, path: &str) -> Option<String> {
    use std::io::Read;
    let mut s = std::net::TcpStream::connect(addr).ok()?;
    write!(s, "GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n").ok()?;
    let mut buf = String::new();
    s.read_to_string(&mut buf).ok()?;
    let (head, body) = buf.split_once("\r\n\r\n")?;
    head.contains(" 200 ").then(|| body.to_owned())
}

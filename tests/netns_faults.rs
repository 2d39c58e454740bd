//! The service across hosts, with faults: a server and two relays, each in a network
//! namespace of its own, joined by links with 20 ms delay and 1 % loss each way (carried
//! through this process, see `netns`), mirrors behind each relay. Clients edit through
//! both relays; one relay's upstream link is cut (its packets vanish) until the relay has
//! noticed by itself and then mended; the server is killed with SIGKILL and restarted.
//! Afterwards every acknowledged edit is in the world and every mirror is on the server's
//! quiescent digest, on the stream it first joined.
//!
//! It needs root, `ip` (iproute2) and `/dev/net/tun`; where namespaces cannot be made it
//! says so and passes without running. It makes only its own namespaces and devices (named
//! after this process) and removes them, and every process it started, when it ends.

mod netns;
mod support;

use netns::ip;
use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

const NAADF: &str = env!("CARGO_BIN_EXE_naadf");
const TOKENS: &str = "rt=relay:viewer,vt=vera:viewer,et=edwin:editor";
/// Each relay's HTTP address, inside its namespace.
const RELAY_HTTP: &str = "127.0.0.1:8081";
/// How long a relay's upstream may stay silent before it re-joins (short, so that the
/// cut below is noticed within it).
const UPSTREAM_TIMEOUT_S: &str = "2";

/// The links' character: 20 ms each way and 1 % of packets lost.
const SHAPE: netns::Shape = netns::Shape {
    delay: Duration::from_millis(20),
    loss_one_in: 100,
};

/// The namespaces and links of one run; removed on drop.
struct Net {
    names: Vec<String>,
    /// Link k - 1 joins the server's namespace to relay k's.
    wires: Vec<netns::Wire>,
}

impl Net {
    /// `server`, `relay1` and `relay2` namespaces; `10.77.k.1` (server side) ↔ `10.77.k.2`
    /// (relay k) on link k, shaped by [`SHAPE`].
    fn make(tag: &str) -> Result<Self, String> {
        let mut net = Self {
            names: Vec::new(),
            wires: Vec::new(),
        };
        for role in ["s", "r1", "r2"] {
            let ns = format!("naadf-{tag}-{role}");
            ip(&["netns", "add", &ns])?;
            net.names.push(ns.clone());
            ip(&["-n", &ns, "link", "set", "lo", "up"])?;
        }
        for k in 1..=2 {
            let (a, b) = (format!("nf{tag}s{k}"), format!("nf{tag}r{k}"));
            let (addr_a, addr_b) = (format!("10.77.{k}.1"), format!("10.77.{k}.2"));
            let server_end = netns::End {
                dev: &a,
                ns: &net.names[0],
                addr: &addr_a,
            };
            let relay_end = netns::End {
                dev: &b,
                ns: &net.names[k],
                addr: &addr_b,
            };
            net.wires
                .push(netns::Wire::new(server_end, relay_end, SHAPE, k as u64)?);
        }
        Ok(net)
    }
}

impl Drop for Net {
    fn drop(&mut self) {
        // The wires first: their devices go with them, then the empty namespaces.
        self.wires.clear();
        for ns in &self.names {
            let _ = ip(&["netns", "del", ns]);
        }
    }
}

/// Relay `k`'s `naadf_upstream_connected` and `naadf_upstream_joins_total`, from its
/// `/metrics` inside its namespace.
fn upstream_metrics(net: &Net, k: usize) -> Option<(u64, u64)> {
    let metrics = netns::http_get(&net.names[k], RELAY_HTTP, "/metrics").ok()?;
    let value = |name| support::metric_value(&metrics, name);
    Some((value("naadf_upstream_connected")?, value("naadf_upstream_joins_total")?))
}

/// Waits up to `limit` for relay `k`'s upstream metrics to satisfy `ok`; the last seen.
fn wait_upstream(net: &Net, k: usize, limit: Duration, ok: impl Fn((u64, u64)) -> bool) -> Option<(u64, u64)> {
    let t = Instant::now();
    loop {
        let m = upstream_metrics(net, k);
        if m.is_some_and(&ok) || t.elapsed() > limit {
            return m;
        }
        std::thread::sleep(Duration::from_millis(200));
    }
}

/// A `naadf` process in a namespace, its stdout lines on a channel; killed on drop.
struct Proc {
    child: Child,
    lines: mpsc::Receiver<String>,
}

impl Proc {
    fn start(ns: &str, args: &[&str], log: &std::path::Path) -> Self {
        let err = std::fs::OpenOptions::new().create(true).append(true).open(log).unwrap();
        let mut child = Command::new("ip")
            .args(["netns", "exec", ns, NAADF])
            .args(args)
            .env("NAADF_TOKENS", TOKENS)
            .env("RUST_LOG", "info")
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::from(err))
            .spawn()
            .unwrap();
        let stdout = child.stdout.take().unwrap();
        let (tx, lines) = mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        Self { child, lines }
    }

    /// The next JSON line.
    fn json(&self, timeout: Duration) -> serde_json::Value {
        let line = self.lines.recv_timeout(timeout).expect("a line from the process");
        serde_json::from_str(&line).unwrap()
    }

    fn kill9(mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Runs `naadf ARGS` in `ns` to the end; its stdout.
fn run_in(ns: &str, args: &[&str]) -> String {
    let out = Command::new("ip")
        .args(["netns", "exec", ns, NAADF])
        .args(args)
        .env_remove("NAADF_TOKENS")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "naadf {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// Sends `ops` through the relay at `url` in `ns` as the editor; the acknowledged versions.
fn edit_through(ns: &str, url: &str, ops: &[String], dir: &std::path::Path, name: &str) -> Vec<u64> {
    let file = dir.join(name);
    std::fs::write(&file, ops.join("\n") + "\n").unwrap();
    let out = run_in(
        ns,
        &[
            "edit",
            "--server",
            url,
            "--token",
            "et",
            "--ops",
            file.to_str().unwrap(),
            "--retry-for",
            "60",
        ],
    );
    out.lines().map(|l| l.trim().parse().unwrap()).collect()
}

#[test]
fn relays_survive_a_cut_link_and_a_killed_server_across_namespaces() {
    let tag = format!("{}", std::process::id() % 100_000);
    let net = match Net::make(&tag) {
        Ok(n) => n,
        Err(why) => {
            eprintln!(
                "SKIPPED: cannot make network namespaces and TUN links here ({why}); needs root, iproute2 and /dev/net/tun"
            );
            return;
        }
    };
    let dir = tempfile::tempdir().unwrap();
    let world = support::start_world(dir.path());
    let data = dir.path().join("data");
    let serve_args = [
        "serve",
        "--json",
        "--world",
        world.as_str(),
        "--data",
        data.to_str().unwrap(),
        "--grpc",
        "0.0.0.0:50051",
        "--http",
        "127.0.0.1:8080",
        "--insecure",
    ];
    let server_log = dir.path().join("server.log");
    let server = Proc::start(&net.names[0], &serve_args, &server_log);
    server.json(Duration::from_secs(300));
    // The links are shaped: a connect takes a round trip, two delays.
    let rtt = netns::connect_time(&net.names[1], "10.77.1.1:50051").unwrap();
    assert!(rtt >= 2 * SHAPE.delay, "a connect across link 1 took {rtt:?}");

    let mut relays = Vec::new();
    let mut mirrors = Vec::new();
    for k in 1..=2 {
        let upstream = format!("http://10.77.{k}.1:50051");
        let args = [
            "relay",
            "--json",
            "--upstream",
            &upstream,
            "--token",
            "rt",
            "--grpc",
            "127.0.0.1:50061",
            "--http",
            RELAY_HTTP,
            "--upstream-timeout",
            UPSTREAM_TIMEOUT_S,
        ];
        let relay = Proc::start(&net.names[k], &args, &dir.path().join(format!("relay{k}.log")));
        relay.json(Duration::from_secs(60));
        relays.push(relay);
        for m in 0..2 {
            let log = dir.path().join(format!("mirror{k}{m}.log"));
            let args = [
                "mirror",
                "--json",
                "--no-cache",
                "--server",
                "http://127.0.0.1:50061",
                "--token",
                "vt",
            ];
            mirrors.push(Proc::start(&net.names[k], &args, &log));
        }
    }

    let mut rng = 21;
    let mut ops = |n: usize| (0..n).map(|_| support::random_op(&mut rng)).collect::<Vec<_>>();
    let url = "http://127.0.0.1:50061";
    let mut acked = Vec::new();
    acked.extend(edit_through(&net.names[1], url, &ops(10), dir.path(), "a.jsonl"));
    acked.extend(edit_through(&net.names[2], url, &ops(10), dir.path(), "b.jsonl"));

    // Relay 1's link is cut (every packet dropped, no error anywhere) while edits go
    // through relay 2. The relay notices the silence by itself, within its upstream
    // timeout, and re-joins once the link is back.
    let (_, joins_before) =
        wait_upstream(&net, 1, Duration::from_secs(30), |(c, _)| c == 1).expect("relay 1's metrics");
    net.wires[0].set_cut(true);
    acked.extend(edit_through(&net.names[2], url, &ops(10), dir.path(), "c.jsonl"));
    let noticed = wait_upstream(&net, 1, Duration::from_secs(30), |(c, _)| c == 0);
    assert_eq!(noticed.map(|m| m.0), Some(0), "relay 1 saw its upstream go silent");
    net.wires[0].set_cut(false);
    let back = wait_upstream(&net, 1, Duration::from_secs(60), |(c, j)| c == 1 && j > joins_before);
    assert!(
        back.is_some_and(|(c, j)| c == 1 && j > joins_before),
        "relay 1 re-joined after the cut: {back:?}, {joins_before} joins before"
    );

    // The server dies without a goodbye and comes back on the same data directory; the
    // editors retry through the relays until it is back.
    server.kill9();
    let server = Proc::start(&net.names[0], &serve_args, &server_log);
    acked.extend(edit_through(&net.names[1], url, &ops(10), dir.path(), "d.jsonl"));
    acked.extend(edit_through(&net.names[2], url, &ops(10), dir.path(), "e.jsonl"));
    server.json(Duration::from_secs(300));

    // Every acknowledged edit is in: versions count batches, each applied once.
    let status = loop {
        let s: serde_json::Value = serde_json::from_str(&run_in(
            &net.names[0],
            &[
                "status",
                "--json",
                "--server",
                "http://127.0.0.1:50051",
                "--token",
                "vt",
            ],
        ))
        .unwrap();
        if s["quiescent"] == true {
            break s;
        }
        std::thread::sleep(Duration::from_millis(200));
    };
    acked.sort_unstable();
    assert_eq!(
        acked,
        (1..=50).collect::<Vec<u64>>(),
        "every edit acknowledged once, in order"
    );
    assert_eq!(status["version"], 50, "{status}");

    // Every mirror ends on the server's quiescent state, on the stream it started with.
    let digest = status["digest"].as_str().unwrap().to_owned();
    for (k, m) in mirrors.iter_mut().enumerate() {
        let t = Instant::now();
        loop {
            let left = Duration::from_secs(120).saturating_sub(t.elapsed());
            let s = m.json(left);
            if s["version"] == 50 && s["digest"] == digest.as_str() {
                break;
            }
        }
        assert!(
            m.child.try_wait().unwrap().is_none(),
            "mirror {k} still follows the stream it joined"
        );
    }
    drop(mirrors);
    drop(relays);
    drop(server);
}

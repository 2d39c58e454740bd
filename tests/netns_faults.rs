//! The service across hosts, with faults: a server and two relays, each in a network
//! namespace of its own joined by veth links (with 20 ms delay and 1 % loss where the
//! kernel has netem), mirrors behind each relay. Clients edit through both relays; one
//! relay's upstream link is cut for a few seconds; the server is killed with SIGKILL and
//! restarted. Afterwards every acknowledged edit is in the world and every mirror is on the
//! server's quiescent digest.
//!
//! It needs root and `ip` (iproute2); where namespaces cannot be made it says so and
//! passes without running. It makes only its own namespaces (named after this process) and
//! removes them, and every process it started, when it ends.

mod support;

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

const NAADF: &str = env!("CARGO_BIN_EXE_naadf");
const TOKENS: &str = "rt=relay:viewer,vt=vera:viewer,et=edwin:editor";

/// Runs `ip ARGS`; its error output when it fails.
fn ip(args: &[&str]) -> Result<(), String> {
    let out = Command::new("ip").args(args).output().map_err(|e| e.to_string())?;
    if out.status.success() {
        Ok(())
    } else {
        Err(String::from_utf8_lossy(&out.stderr).trim().to_owned())
    }
}

/// The namespaces and links of one run; removed on drop (a namespace takes its veth ends
/// with it).
struct Net {
    names: Vec<String>,
}

impl Net {
    /// `server`, `relay1` and `relay2` namespaces; `10.77.k.1` (server side) ↔ `10.77.k.2`
    /// (relay k) on veth pair k.
    fn make(tag: &str) -> Result<Self, String> {
        let mut net = Self { names: Vec::new() };
        for role in ["s", "r1", "r2"] {
            let ns = format!("naadf-{tag}-{role}");
            ip(&["netns", "add", &ns])?;
            net.names.push(ns.clone());
            ip(&["-n", &ns, "link", "set", "lo", "up"])?;
        }
        for k in 1..=2 {
            let (a, b) = (format!("nf{tag}s{k}"), format!("nf{tag}r{k}"));
            ip(&["link", "add", &a, "type", "veth", "peer", "name", &b])?;
            ip(&["link", "set", &a, "netns", &net.names[0]])?;
            ip(&["link", "set", &b, "netns", &net.names[k]])?;
            ip(&[
                "-n",
                &net.names[0],
                "addr",
                "add",
                &format!("10.77.{k}.1/24"),
                "dev",
                &a,
            ])?;
            ip(&[
                "-n",
                &net.names[k],
                "addr",
                "add",
                &format!("10.77.{k}.2/24"),
                "dev",
                &b,
            ])?;
            ip(&["-n", &net.names[0], "link", "set", &a, "up"])?;
            ip(&["-n", &net.names[k], "link", "set", &b, "up"])?;
        }
        Ok(net)
    }

    /// Adds 20 ms delay and 1 % loss to both ends of both links; false where the kernel
    /// has no netem.
    fn shape(&self, tag: &str) -> bool {
        (1..=2).all(|k| {
            [(0, format!("nf{tag}s{k}")), (k, format!("nf{tag}r{k}"))]
                .iter()
                .all(|(n, dev)| {
                    Command::new("ip")
                        .args(["netns", "exec", &self.names[*n], "tc", "qdisc", "add", "dev", dev])
                        .args(["root", "netem", "delay", "20ms", "loss", "1%"])
                        .stderr(Stdio::null())
                        .status()
                        .is_ok_and(|s| s.success())
                })
        })
    }

    /// Takes relay `k`'s end of its link down or up.
    fn link(&self, tag: &str, k: usize, up: bool) {
        let dev = format!("nf{tag}r{k}");
        ip(&[
            "-n",
            &self.names[k],
            "link",
            "set",
            &dev,
            if up { "up" } else { "down" },
        ])
        .unwrap();
    }
}

impl Drop for Net {
    fn drop(&mut self) {
        for ns in &self.names {
            let _ = ip(&["netns", "del", ns]);
        }
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
            eprintln!("SKIPPED: cannot make network namespaces and veth links here ({why}); needs root and iproute2");
            return;
        }
    };
    if !net.shape(&tag) {
        eprintln!("note: no netem in this kernel; the links run without the 20 ms delay and 1 % loss");
    }
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

    // Relay 1 loses its upstream for a few seconds while edits go through relay 2.
    net.link(&tag, 1, false);
    acked.extend(edit_through(&net.names[2], url, &ops(10), dir.path(), "c.jsonl"));
    std::thread::sleep(Duration::from_secs(3));
    net.link(&tag, 1, true);

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

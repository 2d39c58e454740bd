//! Network namespaces for tests: links between them carried through this process (a
//! [`Wire`]: delay, loss, and a cut on demand, as `tc netem` and a pulled cable would
//! give), and plain HTTP requests made from inside a namespace ([`http_get`]).
//!
//! A wire is a TUN device in each of two namespaces and two threads per direction here:
//! one reads each packet the kernel routes into one end and either drops it (a seeded
//! share of them, or all while the link is cut) or queues it; the other writes it into
//! the far end once the delay has passed. The losses are real packet losses: TCP sees the
//! delay in its round trips and retransmits what went missing. It needs root and
//! `/dev/net/tun`, not the kernel's netem module, which many kernels lack.

use std::fs::{File, OpenOptions};
use std::io::{Read, Write};
use std::os::fd::AsRawFd;
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, mpsc};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Runs `ip ARGS`; its error output when it fails.
pub fn ip(args: &[&str]) -> Result<(), String> {
    let out = Command::new("ip").args(args).output().map_err(|e| e.to_string())?;
    if out.status.success() {
        Ok(())
    } else {
        Err(String::from_utf8_lossy(&out.stderr).trim().to_owned())
    }
}

/// One end of a wire: the TUN device's name, the namespace it is moved to, and its
/// address there (the other end's address is its point-to-point peer).
pub struct End<'a> {
    pub dev: &'a str,
    pub ns: &'a str,
    pub addr: &'a str,
}

/// A link's character: the one-way delay, and one packet in `loss_one_in` dropped in
/// each direction (0: none).
#[derive(Clone, Copy, Debug)]
pub struct Shape {
    pub delay: Duration,
    pub loss_one_in: u32,
}

/// A point-to-point link between two namespaces; it goes away on drop (its devices with
/// it).
pub struct Wire {
    cut: Arc<AtomicBool>,
    stop: Arc<AtomicBool>,
    threads: Vec<JoinHandle<()>>,
}

/// How long a thread of the wire waits for work before it looks at `stop` again.
const TICK: Duration = Duration::from_millis(50);

impl Wire {
    /// Makes the link `a` ↔ `b` with `shape`; `seed` picks which packets are lost.
    pub fn new(a: End, b: End, shape: Shape, seed: u64) -> Result<Self, String> {
        let (fa, fb) = (Arc::new(open_tun(a.dev)?), Arc::new(open_tun(b.dev)?));
        for (end, peer) in [(&a, &b), (&b, &a)] {
            ip(&["link", "set", end.dev, "netns", end.ns])?;
            ip(&["-n", end.ns, "addr", "add", end.addr, "peer", peer.addr, "dev", end.dev])?;
            ip(&["-n", end.ns, "link", "set", end.dev, "up"])?;
        }
        let mut wire = Self {
            cut: Arc::new(AtomicBool::new(false)),
            stop: Arc::new(AtomicBool::new(false)),
            threads: Vec::new(),
        };
        wire.carry(fa.clone(), fb.clone(), shape, seed);
        wire.carry(fb, fa, shape, seed ^ 0x9e37_79b9_7f4a_7c15);
        Ok(wire)
    }

    /// Cuts the link (every packet either way is dropped) or mends it.
    pub fn set_cut(&self, cut: bool) {
        self.cut.store(cut, Ordering::SeqCst);
    }

    /// Starts carrying packets from `from` to `to`.
    fn carry(&mut self, from: Arc<File>, to: Arc<File>, shape: Shape, seed: u64) {
        let (tx, rx) = mpsc::channel::<(Instant, Vec<u8>)>();
        let (cut, stop) = (self.cut.clone(), self.stop.clone());
        self.threads.push(std::thread::spawn(move || {
            let mut rng = seed | 1;
            let mut buf = vec![0u8; 65_536];
            while !stop.load(Ordering::SeqCst) {
                if !readable(&from, TICK) {
                    continue;
                }
                let Ok(n) = (&*from).read(&mut buf) else { continue };
                // xorshift64: a fixed sequence of losses for a seed.
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                let lost = shape.loss_one_in > 0 && rng.is_multiple_of(u64::from(shape.loss_one_in));
                if !lost
                    && !cut.load(Ordering::SeqCst)
                    && tx.send((Instant::now() + shape.delay, buf[..n].to_vec())).is_err()
                {
                    return;
                }
            }
        }));
        let stop = self.stop.clone();
        self.threads.push(std::thread::spawn(move || {
            while !stop.load(Ordering::SeqCst) {
                // Every packet waits the same delay, so the queue is in order of release.
                let Ok((at, packet)) = rx.recv_timeout(TICK) else {
                    continue;
                };
                std::thread::sleep(at.saturating_duration_since(Instant::now()));
                // A device that is down refuses the write: that packet is lost too.
                let _ = (&*to).write(&packet);
            }
        }));
    }
}

impl Drop for Wire {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

/// A TUN device named `name` (IP packets, no extra header), in this process's namespace
/// until moved; it lives as long as the file.
fn open_tun(name: &str) -> Result<File, String> {
    let file = OpenOptions::new()
        .read(true)
        .write(true)
        .open("/dev/net/tun")
        .map_err(|e| format!("/dev/net/tun: {e}"))?;
    // SAFETY: `ifreq` is plain data, for which all zeroes is a valid value.
    let mut ifr: libc::ifreq = unsafe { std::mem::zeroed() };
    for (d, s) in ifr.ifr_name.iter_mut().zip(name.bytes()) {
        *d = s as libc::c_char;
    }
    ifr.ifr_ifru.ifru_flags = (libc::IFF_TUN | libc::IFF_NO_PI) as libc::c_short;
    // SAFETY: TUNSETIFF reads and writes one `ifreq`, which `ifr` is, on an open TUN file.
    if unsafe { libc::ioctl(file.as_raw_fd(), libc::TUNSETIFF, &mut ifr) } < 0 {
        return Err(format!(
            "cannot make TUN device {name}: {}",
            std::io::Error::last_os_error()
        ));
    }
    Ok(file)
}

/// Whether `file` has data to read within `timeout`.
fn readable(file: &File, timeout: Duration) -> bool {
    let mut fd = libc::pollfd {
        fd: file.as_raw_fd(),
        events: libc::POLLIN,
        revents: 0,
    };
    // SAFETY: one valid `pollfd` for an open descriptor.
    unsafe { libc::poll(&mut fd, 1, timeout.as_millis() as libc::c_int) > 0 }
}

/// Runs `f` on a thread that has entered the network namespace `ns` (a network namespace
/// belongs to a thread, so the rest of the process stays where it is).
pub fn in_namespace<T: Send + 'static>(
    ns: &str,
    f: impl FnOnce() -> Result<T, String> + Send + 'static,
) -> Result<T, String> {
    let netns = File::open(format!("/run/netns/{ns}")).map_err(|e| format!("namespace {ns}: {e}"))?;
    std::thread::spawn(move || {
        // SAFETY: setns on an open network namespace file; it applies to this thread only.
        if unsafe { libc::setns(netns.as_raw_fd(), libc::CLONE_NEWNET) } != 0 {
            return Err(format!(
                "cannot enter the namespace: {}",
                std::io::Error::last_os_error()
            ));
        }
        f()
    })
    .join()
    .map_err(|_| "the thread in the namespace panicked".to_owned())?
}

/// `GET path` over HTTP/1.0 to `addr` from inside the namespace `ns`: the response body,
/// or why not.
pub fn http_get(ns: &str, addr: &str, path: &str) -> Result<String, String> {
    let (addr, path) = (addr.to_owned(), path.to_owned());
    in_namespace(ns, move || {
        let mut s = std::net::TcpStream::connect(&addr).map_err(|e| format!("{addr}: {e}"))?;
        s.set_read_timeout(Some(Duration::from_secs(10)))
            .map_err(|e| e.to_string())?;
        write!(s, "GET {path} HTTP/1.0\r\nHost: {addr}\r\n\r\n").map_err(|e| e.to_string())?;
        let mut response = String::new();
        s.read_to_string(&mut response).map_err(|e| e.to_string())?;
        let (head, body) = response.split_once("\r\n\r\n").ok_or("no HTTP response")?;
        if head.split_whitespace().nth(1) != Some("200") {
            return Err(format!("GET {path}: {}", head.lines().next().unwrap_or("")));
        }
        Ok(body.to_owned())
    })
}

/// How long a TCP connect from inside `ns` to `addr` takes: one round trip.
pub fn connect_time(ns: &str, addr: &str) -> Result<Duration, String> {
    let addr = addr.to_owned();
    in_namespace(ns, move || {
        let t = Instant::now();
        std::net::TcpStream::connect(&addr).map_err(|e| format!("{addr}: {e}"))?;
        Ok(t.elapsed())
    })
}

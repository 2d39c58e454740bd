//! Where a benchmark's CPU time goes, by thread: the process's threads read from
//! `/proc/self/task` (Linux), grouped by what their names say they do.
//!
//! Each thread's `schedstat` gives the nanoseconds it ran on a CPU and the nanoseconds it
//! waited, runnable, for one (the run-queue delay, which is what a competing load adds).
//! Threads that exit take their figures with them, so the process total (from
//! `/proc/self/stat`, which keeps them) is read too, and the difference reported as
//! `exited`.

use serde::Serialize;
use std::collections::BTreeMap;

/// The thread groups of an in-process server and its clients, by thread-name prefix; the
/// first match wins, and a thread matching none belongs to `clients`.
const GROUPS: [(&str, &str); 6] = [
    ("naadf-growth", "growth"),
    // `bench stream`'s editing client.
    ("editor", "editor"),
    ("naadf-committer", "committer"),
    // The actor thread and its rayon pool (`naadf-actor-N`).
    ("naadf-actor", "actor"),
    // The server's tokio runtime: gRPC, the join streams, HTTP.
    ("server", "server_io"),
    // tokio's default name: the benchmark's own runtime, where the mirrors run.
    ("tokio-rt", "clients"),
];

/// CPU time of one group of threads.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Usage {
    /// Time on a CPU, in nanoseconds.
    pub run_ns: u64,
    /// Time runnable but waiting for a CPU, in nanoseconds.
    pub wait_ns: u64,
}

/// A reading of every live thread's CPU time, by group, plus the process total.
#[derive(Clone, Debug, Default)]
pub struct Sample {
    groups: BTreeMap<&'static str, Usage>,
    total_ns: u64,
}

fn group_of(name: &str) -> &'static str {
    GROUPS
        .iter()
        .find(|(prefix, _)| name.starts_with(prefix))
        .map_or("clients", |&(_, g)| g)
}

/// The process's user plus system time in nanoseconds, exited threads included.
fn process_ns() -> Option<u64> {
    process_ns_of("self")
}

/// The user plus system time of process `pid` (`self` for this one) in nanoseconds, its
/// exited threads included; `None` where `/proc` is not available.
pub fn process_ns_of(pid: &str) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command name may hold spaces and parentheses: fields restart after the last ')'.
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    // utime and stime are fields 14 and 15 of the whole line, 12 and 13 after the name.
    let ticks: u64 = f.get(11)?.parse::<u64>().ok()? + f.get(12)?.parse::<u64>().ok()?;
    // The kernel reports them in USER_HZ, 100 on every Linux configuration in use.
    Some(ticks * 10_000_000)
}

impl Sample {
    /// Reads every thread of this process; empty where `/proc` is not available.
    pub fn now() -> Self {
        let mut s = Sample::default();
        let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
            return s;
        };
        for t in tasks.flatten() {
            let dir = t.path();
            let (Ok(name), Ok(stat)) = (
                std::fs::read_to_string(dir.join("comm")),
                std::fs::read_to_string(dir.join("schedstat")),
            ) else {
                continue;
            };
            let mut f = stat.split_whitespace().map(|v| v.parse::<u64>().unwrap_or(0));
            let (run, wait) = (f.next().unwrap_or(0), f.next().unwrap_or(0));
            let u = s.groups.entry(group_of(name.trim())).or_default();
            u.run_ns += run;
            u.wait_ns += wait;
        }
        s.total_ns = process_ns().unwrap_or(0);
        s
    }

    /// CPU milliseconds per unit of work (`per` units) by group since `earlier`, with
    /// `exited` for threads that ended in between and `total` for the process.
    ///
    /// Threads that start in between count from zero; a thread that existed at `earlier` but
    /// not now counts in `exited`.
    pub fn per_unit_since(&self, earlier: &Sample, per: f64) -> BTreeMap<String, UnitUsage> {
        let mut out = BTreeMap::new();
        let mut live_ns = 0u64;
        for (g, u) in &self.groups {
            let before = earlier.groups.get(g).copied().unwrap_or_default();
            let run = u.run_ns.saturating_sub(before.run_ns);
            live_ns += run;
            out.insert(
                (*g).to_owned(),
                UnitUsage {
                    cpu_ms: run as f64 / 1e6 / per,
                    wait_ms: u.wait_ns.saturating_sub(before.wait_ns) as f64 / 1e6 / per,
                },
            );
        }
        let total = self.total_ns.saturating_sub(earlier.total_ns);
        out.insert(
            "exited".to_owned(),
            UnitUsage {
                cpu_ms: total.saturating_sub(live_ns) as f64 / 1e6 / per,
                wait_ms: f64::NAN,
            },
        );
        out.insert(
            "total".to_owned(),
            UnitUsage {
                cpu_ms: total as f64 / 1e6 / per,
                wait_ms: f64::NAN,
            },
        );
        out
    }
}

/// One group's CPU time per unit of work.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct UnitUsage {
    /// Milliseconds on a CPU.
    pub cpu_ms: f64,
    /// Milliseconds runnable but waiting for a CPU (NaN where unknown).
    pub wait_ms: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thread_names_map_to_groups() {
        assert_eq!(group_of("naadf-actor"), "actor");
        assert_eq!(group_of("naadf-actor-1"), "actor");
        assert_eq!(group_of("naadf-growth"), "growth");
        assert_eq!(group_of("server"), "server_io");
        assert_eq!(group_of("editor"), "editor");
        assert_eq!(group_of("tokio-rt-worker"), "clients");
        assert_eq!(group_of("naadf"), "clients");
    }

    #[test]
    fn a_busy_thread_shows_in_its_group() {
        let before = Sample::now();
        std::thread::Builder::new()
            .name("naadf-growth".into())
            .spawn(move || {
                // Works until its time shows (the thread stays alive while it is sampled:
                // at exit its time would move to `exited`); a wrong grouping never shows.
                let t = std::time::Instant::now();
                let mut x = 0u64;
                loop {
                    for _ in 0..1_000_000 {
                        x = std::hint::black_box(x.wrapping_mul(31).wrapping_add(7));
                    }
                    let per = Sample::now().per_unit_since(&before, 1.0);
                    if per["growth"].cpu_ms > 20.0 {
                        return x;
                    }
                    assert!(t.elapsed().as_secs() < 60, "no growth time after 60 s: {per:?}");
                }
            })
            .unwrap()
            .join()
            .unwrap();
    }
}

//! [`Presence`]: who is here, where they look and what they point at, so that people
//! editing together see each other. Never durable: not in the log, a record, the digest or
//! a snapshot.
//!
//! Each client publishes its latest state with a unary call; the table keeps only the
//! latest per (user, session), so a client that publishes a thousand times a second costs
//! one entry. A ticker sends the table to the join tasks of the clients that asked for it
//! at most every [`TICK`], only when it changed, and drops entries [`TTL`] after their last
//! update. A relay holds no table of its own: it forwards publishes upstream and passes
//! the upstream's table on ([`Presence::replace`]).

use naadf_proto::v1::{PresenceEntry, PresenceRequest};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};
use tokio::sync::watch;
use tonic::Status;

/// How long an entry lives after its last update.
pub const TTL: Duration = Duration::from_secs(5);
/// How often the table is sent at most.
pub const TICK: Duration = Duration::from_millis(100);
/// Most characters of a name, and of a tool, that are kept.
const MAX_NAME: usize = 64;
const MAX_TOOL: usize = 32;
/// Most sessions one user may have in the table, and most entries in all.
const MAX_SESSIONS_PER_USER: usize = 16;
const MAX_ENTRIES: usize = 4096;

/// The table every join task that asked for presence forwards.
pub type Table = Arc<Vec<PresenceEntry>>;

/// The presence table of a server or a relay.
pub struct Presence {
    entries: Mutex<Entries>,
    table: watch::Sender<Table>,
}

#[derive(Default)]
struct Entries {
    /// The latest entry per (user, session), with when it came.
    latest: HashMap<(String, u64), (PresenceEntry, Instant)>,
    /// Changed since the table was last sent.
    changed: bool,
}

impl Default for Presence {
    fn default() -> Self {
        Self {
            entries: Mutex::default(),
            table: watch::channel(Table::default()).0,
        }
    }
}

/// Keeps the first `max` characters of `s`.
fn clip(s: &str, max: usize) -> String {
    s.chars().take(max).collect()
}

/// Checks a coordinate list: empty, or three finite numbers.
fn three<T: Copy>(v: &[T], finite: impl Fn(T) -> bool, what: &str) -> Result<(), Status> {
    if v.is_empty() || (v.len() == 3 && v.iter().all(|&x| finite(x))) {
        Ok(())
    } else {
        Err(Status::invalid_argument(format!(
            "presence {what}: give three finite numbers or none"
        )))
    }
}

impl Presence {
    /// Takes `req` from `user` (`None` on a server without tokens, where the name stands
    /// alone), replacing that session's earlier entry.
    pub fn publish(&self, user: Option<&str>, req: PresenceRequest) -> Result<(), Status> {
        three(&req.position, f64::is_finite, "position")?;
        three(&req.forward, f64::is_finite, "forward")?;
        three(&req.pointer, |_| true, "pointer")?;
        let user = user.unwrap_or_default().to_owned();
        let entry = PresenceEntry {
            user: user.clone(),
            session: req.session,
            name: clip(&req.name, MAX_NAME),
            position: req.position,
            forward: req.forward,
            pointer: req.pointer,
            tool: clip(&req.tool, MAX_TOOL),
            age_ms: 0,
        };
        let mut e = self.entries.lock().unwrap_or_else(PoisonError::into_inner);
        let key = (user, req.session);
        if !e.latest.contains_key(&key) {
            let mine = e.latest.keys().filter(|(u, _)| *u == key.0).count();
            if mine >= MAX_SESSIONS_PER_USER || e.latest.len() >= MAX_ENTRIES {
                return Err(Status::resource_exhausted(format!(
                    "the presence table is full (at most {MAX_SESSIONS_PER_USER} sessions per user, \
                     {MAX_ENTRIES} in all)"
                )));
            }
        }
        e.latest.insert(key, (entry, Instant::now()));
        e.changed = true;
        Ok(())
    }

    /// Replaces the whole table with `entries` and sends it at once (a relay passing its
    /// upstream's table on).
    pub fn replace(&self, entries: Vec<PresenceEntry>) {
        self.table.send_replace(Arc::new(entries));
    }

    /// The table, as it changes.
    pub fn subscribe(&self) -> watch::Receiver<Table> {
        self.table.subscribe()
    }

    /// Drops expired entries and sends the table if it changed.
    fn tick(&self) {
        let now = Instant::now();
        let mut e = self.entries.lock().unwrap_or_else(PoisonError::into_inner);
        let before = e.latest.len();
        e.latest.retain(|_, (_, at)| now.duration_since(*at) < TTL);
        if !e.changed && e.latest.len() == before {
            return;
        }
        e.changed = false;
        let mut table: Vec<PresenceEntry> = e
            .latest
            .values()
            .map(|(entry, at)| PresenceEntry {
                age_ms: now.duration_since(*at).as_millis().try_into().unwrap_or(u32::MAX),
                ..entry.clone()
            })
            .collect();
        drop(e);
        table.sort_by(|a, b| (&a.user, a.session, &a.name).cmp(&(&b.user, b.session, &b.name)));
        self.table.send_replace(Arc::new(table));
    }

    /// Runs the ticker until `shutdown` turns true.
    pub async fn run(self: Arc<Self>, mut shutdown: watch::Receiver<bool>) {
        let mut every = tokio::time::interval(TICK);
        every.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        loop {
            tokio::select! {
                _ = every.tick() => self.tick(),
                _ = shutdown.wait_for(|s| *s) => return,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn req(session: u64, name: &str) -> PresenceRequest {
        PresenceRequest {
            session,
            name: name.into(),
            position: vec![1.0, 2.0, 3.0],
            ..Default::default()
        }
    }

    #[test]
    fn the_latest_entry_per_session_is_sent_once_per_change() {
        let p = Presence::default();
        let mut rx = p.subscribe();
        for k in 0..1000 {
            p.publish(Some("alice"), req(7, &format!("a{k}"))).unwrap();
        }
        p.publish(None, req(7, "b")).unwrap();
        p.tick();
        assert!(rx.has_changed().unwrap());
        let table = rx.borrow_and_update().clone();
        let names: Vec<(&str, &str)> = table.iter().map(|e| (e.user.as_str(), e.name.as_str())).collect();
        assert_eq!(names, [("", "b"), ("alice", "a999")], "one entry per user and session");
        p.tick();
        assert!(!rx.has_changed().unwrap(), "nothing changed: nothing sent");
    }

    #[test]
    fn bad_coordinates_and_a_full_table_are_refused() {
        let p = Presence::default();
        let mut bad = req(1, "x");
        bad.position = vec![f64::NAN, 0.0, 0.0];
        assert_eq!(p.publish(None, bad).unwrap_err().code(), tonic::Code::InvalidArgument);
        bad = req(1, "x");
        bad.pointer = vec![1, 2];
        assert_eq!(p.publish(None, bad).unwrap_err().code(), tonic::Code::InvalidArgument);
        for s in 0..MAX_SESSIONS_PER_USER as u64 {
            p.publish(Some("bob"), req(s, "bob")).unwrap();
        }
        let full = p.publish(Some("bob"), req(99, "bob")).unwrap_err();
        assert_eq!(full.code(), tonic::Code::ResourceExhausted);
        p.publish(Some("bob"), req(3, "bob again")).unwrap();
        let long = "n".repeat(500);
        p.publish(Some("carol"), req(1, &long)).unwrap();
        p.tick();
        let table = p.subscribe().borrow().clone();
        assert!(table.iter().all(|e| e.name.chars().count() <= MAX_NAME));
    }
}

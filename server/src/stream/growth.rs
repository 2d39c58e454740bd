//! The background growth thread: runs the actor's distance-field growth tasks one at a
//! time, on a thread that lives as long as the actor, at the lowest priority of its
//! scheduling class (nice 19), so that it runs on what edits, acknowledgements and
//! streaming leave.
//!
//! One long-lived thread (rather than one per task) keeps a task's start cheap, and keeps
//! the work on one named thread, `naadf-growth`, where profilers and `bench stream`'s CPU
//! accounting find it.
//!
//! The actor sometimes must wait for growth (a checkpoint, shutdown). Then it asks for the
//! task back ([`GrowthWorker::collect`]): the thread stops at the next phase and skips its
//! pause, and the actor finishes the task itself, at its own priority. The thread must
//! still get the CPU to notice, which is why it is not `SCHED_IDLE` (that policy would
//! make it preempted at once by any waking thread, but can starve it for as long as the
//! machine is saturated, and the actor with it).

use crate::stream::messages::Request;
use naadf_world::edit::GrowthTask;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc as std_mpsc;
use std::time::{Duration, Instant};
use tokio::sync::mpsc;

/// The thread's name (and its rayon pool's).
pub const THREAD_NAME: &str = "naadf-growth";

/// The pause after a growth task before the next may start: edits coalesce into one task,
/// so that under a steady edit stream growth takes about a fifth of one core (a task of the
/// default world takes 100–200 ms), and fields regrow within about a second of an edit.
/// Every task recomputes a region of 34 chunks around its seeds, however few they are, so
/// fewer, larger tasks repeat less work (`bench stream`: 1.2 ms of growth CPU per edit with
/// a 400 ms pause, 0.8 ms with this one).
const GROWTH_PAUSE: Duration = Duration::from_millis(1000);

/// Gives the calling thread the lowest priority of its scheduling class (nice 19 on Linux).
fn run_in_background() {
    if let Err(e) = thread_priority::set_current_thread_priority(thread_priority::ThreadPriority::Min) {
        tracing::debug!("background growth keeps its priority: {e:?}");
    }
}

/// The handle the actor keeps: hands tasks to the thread and takes them back.
pub struct GrowthWorker {
    tasks: Option<std_mpsc::Sender<GrowthTask>>,
    done: std_mpsc::Receiver<GrowthTask>,
    /// Whether a task was handed over and not yet taken back.
    busy: bool,
    /// Set while the actor waits for the task: the thread stops at the next phase and
    /// skips its pause.
    hurry: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl GrowthWorker {
    /// Starts the thread. After each task (and the pause) it sends [`Request::Grown`] to
    /// `notify`, so that the actor collects the result between requests. Where no thread
    /// can be started, [`GrowthWorker::submit`] runs tasks on the caller's thread.
    pub fn start(notify: mpsc::WeakSender<Request>) -> Self {
        let (tasks, inbox) = std_mpsc::channel::<GrowthTask>();
        let (outbox, done) = std_mpsc::channel();
        let hurry = Arc::new(AtomicBool::new(false));
        let hurried = hurry.clone();
        let thread = std::thread::Builder::new().name(THREAD_NAME.into()).spawn(move || {
            run_in_background();
            // One core at most: growth is never what a client waits for.
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .thread_name(|_| THREAD_NAME.into())
                .start_handler(|_| run_in_background())
                .build();
            let stop = || hurried.load(Ordering::Acquire);
            for mut task in inbox {
                match &pool {
                    Ok(pool) => pool.install(|| task.run_until(stop)),
                    Err(_) => task.run_until(stop),
                };
                // Edits that arrive meanwhile queue seeds for one coalesced next task.
                let end = Instant::now() + GROWTH_PAUSE;
                while !stop() {
                    let now = Instant::now();
                    if now >= end {
                        break;
                    }
                    std::thread::park_timeout(end - now);
                }
                if outbox.send(task).is_err() {
                    return;
                }
                if let Some(tx) = notify.upgrade() {
                    let _ = tx.blocking_send(Request::Grown);
                }
            }
        });
        let thread = match thread {
            Ok(t) => Some(t),
            Err(e) => {
                tracing::warn!("cannot start the growth thread ({e}): growth runs between requests");
                None
            }
        };
        Self {
            tasks: thread.is_some().then_some(tasks),
            done,
            busy: false,
            hurry,
            thread,
        }
    }

    /// Whether a task is running (or finished and not yet taken back).
    pub fn is_busy(&self) -> bool {
        self.busy
    }

    /// Hands a task to the thread. The caller checks [`GrowthWorker::is_busy`] first: one
    /// task at a time. Without a thread the task runs here, and comes back finished.
    #[must_use = "a task that comes back finished must be published"]
    pub fn submit(&mut self, mut task: GrowthTask) -> Option<GrowthTask> {
        debug_assert!(!self.busy, "one growth task at a time");
        if let Some(tx) = &self.tasks {
            match tx.send(task) {
                Ok(()) => {
                    self.busy = true;
                    return None;
                }
                // The thread is gone (it panicked): growth goes on here.
                Err(std_mpsc::SendError(back)) => task = back,
            }
        }
        task.run();
        Some(task)
    }

    /// Takes back the task: if `wait`, at once (the thread stops at its next phase, and
    /// the task may come back unfinished: [`naadf_world::World::finish_growth`] runs the
    /// rest); else only if it is done. `None` when no task was handed over, or (without
    /// `wait`) it still runs.
    ///
    /// [`Request::Grown`] follows each result, but a result may have been taken already
    /// (a checkpoint takes it early), so that request takes only a ready result: waiting
    /// there could block the actor on the next task.
    pub fn collect(&mut self, wait: bool) -> Option<GrowthTask> {
        if !self.busy {
            return None;
        }
        let task = if wait {
            self.hurry.store(true, Ordering::Release);
            if let Some(t) = &self.thread {
                t.thread().unpark();
            }
            let task = self.done.recv().expect("the growth thread does not panic");
            self.hurry.store(false, Ordering::Release);
            Some(task)
        } else {
            self.done.try_recv().ok()
        };
        self.busy = task.is_none();
        task
    }
}

impl Drop for GrowthWorker {
    fn drop(&mut self) {
        // Closing the task channel ends the thread's loop; hurrying ends its pause.
        self.tasks = None;
        self.hurry.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            t.thread().unpark();
            let _ = t.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use naadf_world::ops::{Batch, Limits};
    use naadf_world::preset::Preset;
    use naadf_world::{World, WorldSize};

    /// A world with growth queued: a box emptied through the terrain.
    fn world_with_growth() -> World {
        let size = WorldSize::new(512, 128, 512).unwrap();
        let mut w = World::build(&*Preset::Terrain.source(Some(size), 4).unwrap(), &|_| {}).unwrap();
        let dig = Batch::parse_line(r#"{"op":"box","min":[100,0,100],"max":[300,100,300],"material":0}"#).unwrap();
        w.apply(&dig, &Limits::default()).unwrap();
        assert!(!w.is_quiescent());
        w
    }

    /// Taken back at once while it runs or pauses (as a checkpoint does), a task may come
    /// back unfinished; the world finishes it, and ends as if it had grown in place.
    #[test]
    fn a_task_taken_back_early_still_converges() {
        let mut in_place = world_with_growth();
        in_place.grow_until_quiescent();
        for wait_ms in [0, 5, 50] {
            let (tx, _rx) = mpsc::channel(4);
            let mut worker = GrowthWorker::start(tx.downgrade());
            let mut w = world_with_growth();
            let task = w.start_growth().expect("growth is queued");
            assert!(worker.submit(task).is_none(), "the thread takes it");
            assert!(worker.is_busy());
            std::thread::sleep(Duration::from_millis(wait_ms));
            let task = worker.collect(true).expect("the task comes back");
            assert!(!worker.is_busy());
            w.finish_growth(task);
            w.grow_until_quiescent();
            assert_eq!(w.digest(), in_place.digest(), "taken back after {wait_ms} ms");
            drop(tx);
        }
    }
}

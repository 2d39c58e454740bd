//! Edits: applying batches of ops atomically, keeping the structure canonical and the
//! distance fields safe, background chunk-AADF growth, change sets, undo records and the
//! per-user undo histories built from them.
//!
//! One batch → one new version → one [`ChangeSet`]. The change set's [`Record`] is compact
//! (a single-voxel edit is a dozen bytes): a mirror expands it into the exact buffer writes
//! by running the same code ([`World::apply_record`]), because every write an edit makes is
//! a deterministic function of the previous buffers and the batch. Background growth
//! publishes its chunk writes explicitly, as sub-steps `(version, growth_seq)`.
//!
//! Entity ops (spawn, move, despawn) change a working copy of the entity table, in batch
//! order with the voxel ops; after the batch the entity buffers are rebuilt from the table
//! ([`crate::entity`]), and chunks that gain or lose entities are invalidated exactly like
//! chunks whose emptiness flips (they stop or start being free).

mod commit;
mod history;
mod invalidate;
mod overlay;
mod record;
mod undo;
mod writes;

pub use history::{BatchKind, Histories, MAX_SEQS, MAX_UNDO, MAX_UNDO_VOXELS};
pub use record::{Decoded, Record};
pub use undo::UndoRecord;
pub use writes::Writes;

pub use crate::aadf::GrowthTask;
use crate::aadf::{Growth, GrowthJob};
use crate::digest::{BufferId, Digest};
use crate::entity::{self, Entities, EntityTable};
use crate::ops::{self, Batch, EditError, Limits};
use crate::world::World;
use overlay::Overlay;

/// What one applied batch or growth step changed.
#[derive(Clone, Debug, PartialEq)]
pub struct ChangeSet {
    /// The version after the change (growth steps keep the version of the last batch).
    pub version: u64,
    /// 0 for the batch itself; 1, 2, … for the growth steps published after it.
    pub growth_seq: u32,
    /// Whether the world is quiescent afterwards (no distance-field work queued).
    pub quiescent: bool,
    /// The compact record a mirror applies.
    pub record: Record,
    /// The buffer writes the change made (word ranges).
    pub writes: Writes,
    /// The world digest after the change.
    pub digest: Digest,
}

impl ChangeSet {
    /// The compact encoding of this change (see [`Record::encode`]).
    pub fn encode(&self) -> Vec<u8> {
        self.record.encode(self.version, self.growth_seq, self.quiescent)
    }
}

/// The result of applying a batch.
#[derive(Clone, Debug)]
pub struct Applied {
    /// The change set of the new version.
    pub change: ChangeSet,
    /// What undoing the batch needs.
    pub undo: UndoRecord,
}

impl World {
    /// Applies a batch atomically: on any error the world is untouched. Returns the new
    /// version's change set and the undo record.
    pub fn apply(&mut self, batch: &Batch, limits: &Limits) -> Result<Applied, EditError> {
        self.apply_batch(batch, limits, true)
    }

    /// [`World::apply`], with the undo record left empty unless `undo` (a mirror applying
    /// the server's records keeps no history, and the diff costs a pass over every
    /// touched chunk).
    fn apply_batch(&mut self, batch: &Batch, limits: &Limits, undo: bool) -> Result<Applied, EditError> {
        let mut materials = self.materials.clone();
        let mut models = self.models.clone();
        let mut overlay = Overlay::new(self);
        // Entity ops change a working copy of the entity table, in batch order with the
        // voxel and table ops (which go through the ops layer as in `ops::apply_batch`).
        let mut table: Option<EntityTable> = None;
        let mut last_entity_op = None;
        // The models checked for entities since the tables last changed.
        let mut fit = entity::FitModels::default();
        batch.check_size(limits)?;
        for (i, op) in batch.ops.iter().enumerate() {
            if op.is_entity_op() {
                let t = table.get_or_insert_with(|| self.entities.table.clone());
                entity::apply_op(i, op, t, &models, &materials, self.size, &mut fit)?;
                last_entity_op = Some(i);
            } else {
                op.apply(i, &mut overlay, &mut materials, &mut models, limits)?;
                fit = entity::FitModels::default();
            }
        }
        let touched = overlay.into_touched();
        self.check_capacity(touched.len()).map_err(|e| EditError::Limit {
            index: 0,
            op: batch.ops.first().map_or("batch", |o| o.name()),
            reason: e.to_string(),
        })?;
        // The entity buffers follow the entity table and the models of the types.
        let types_changed = || {
            self.entities
                .table
                .types
                .iter()
                .any(|n| models.get(n) != self.models.get(n))
        };
        let entities = if table.is_some() || types_changed() {
            let table = table.unwrap_or_else(|| self.entities.table.clone());
            let index = last_entity_op
                .or_else(|| batch.ops.iter().rposition(|o| matches!(o, ops::Op::DefineModel { .. })))
                .unwrap_or(0);
            let e = self
                .entities
                .rebuild(table, &self.models, &models)
                .map_err(|e| EditError::Limit {
                    index,
                    op: batch.ops.get(index).map_or("batch", |o| o.name()),
                    reason: e.0,
                })?;
            Some(e)
        } else {
            None
        };

        let undo = if undo {
            UndoRecord::diff(self, &touched, entities.as_ref().map(|e| &e.table))
        } else {
            UndoRecord::default()
        };
        let mut w = Writes::default();
        if materials != self.materials {
            self.materials = materials;
            w.push(BufferId::Materials, 0, self.materials.words().len());
        }
        if models != self.models {
            self.models = models;
            w.push(BufferId::Models, 0, 0);
        }
        // The touched chunks, whose freedom (empty) may flip. Entities never touch the
        // static world.
        let mut check: Vec<usize> = touched.iter().map(|t| t.index).collect();
        check.sort_unstable();
        check.dedup();
        let was_free: Vec<bool> = check.iter().map(|&i| self.chunk_is_free(i)).collect();
        for t in &touched {
            self.commit_chunk(t, &mut w).expect("validated batches commit");
        }
        if let Some(e) = entities {
            self.install_entities(e, &mut w);
        }
        let mut blocked = Vec::new();
        let mut changed = Vec::new();
        for (&i, &free) in check.iter().zip(&was_free) {
            if free != self.chunk_is_free(i) {
                changed.push(i as u32);
                if free {
                    blocked.push(i);
                }
            }
        }
        self.clamp_around(&blocked, &mut w);
        self.version += 1;
        self.growth.seq = 0;
        if self.growth.job.is_some() || self.growth.detached {
            // The running job saw the old content: its fields are clamped when it
            // publishes, and the flipped chunks seed the next job.
            self.growth.pending.extend(changed);
            self.growth.blocked.extend(blocked);
        } else {
            self.growth.seeds.extend(changed);
        }
        let record = Record::of_batch(batch);
        Ok(Applied {
            change: self.publish(record, w),
            undo,
        })
    }

    /// Replaces the entity state with a rebuilt one: the instance and type buffers (only
    /// their changed words are recorded).
    fn install_entities(&mut self, e: Entities, w: &mut Writes) {
        diff_buffer(BufferId::EntityInstances, &self.entities.instances, &e.instances, w);
        diff_buffer(BufferId::EntityTypes, &self.entities.type_voxels, &e.type_voxels, w);
        self.entities = e;
    }

    /// Rehashes the written pages and wraps the writes into a change set.
    fn publish(&mut self, record: Record, mut w: Writes) -> ChangeSet {
        w.normalize();
        for id in BufferId::WORLD {
            let len = self.buffer_bytes(id).len();
            let ranges: Vec<std::ops::Range<usize>> = w
                .ranges()
                .iter()
                .filter(|(rid, _)| *rid == id)
                .map(|(_, r)| match id {
                    // Tables are rewritten whole.
                    BufferId::Materials | BufferId::Models => 0..len,
                    _ => (4 * r.start as usize).min(len)..(4 * r.end as usize).min(len),
                })
                .collect();
            if !ranges.is_empty() {
                self.touch_digest(id, &ranges);
            }
        }
        ChangeSet {
            version: self.version,
            growth_seq: self.growth.seq,
            quiescent: self.is_quiescent(),
            record,
            writes: w,
            digest: self.digest(),
        }
    }

    /// The growth sub-step of the latest change (0 right after a batch).
    pub fn growth_seq(&self) -> u32 {
        self.growth.seq
    }

    /// Whether no distance-field work is queued.
    pub fn is_quiescent(&self) -> bool {
        self.growth.seeds.is_empty() && self.growth.pending.is_empty()
    }

    /// Runs up to `budget` (level, axis) phases of background chunk-AADF growth. Returns a
    /// change set when a recomputation converges and its chunk writes are published (the
    /// last one is marked quiescent); `None` while work is still in progress or when there
    /// is none. Deterministic, and the converged fields equal a from-scratch build.
    pub fn grow_distance_fields(&mut self, budget: usize) -> Option<ChangeSet> {
        if self.growth.seeds.is_empty() || self.growth.detached {
            return None;
        }
        if self.growth.job.is_none() {
            self.growth.job = Some(self.new_growth_job());
        }
        let size = self.size;
        let job = self.growth.job.as_mut().expect("job exists");
        let mut done = job.is_done();
        for _ in 0..budget {
            if done {
                break;
            }
            done = job.step(size);
        }
        if !done {
            return None;
        }
        let job = self.growth.job.take().expect("job exists");
        Some(self.publish_growth(&job))
    }

    /// Starts the queued growth work as a task that runs without the world (on another
    /// thread, say), or `None` when there is none or a job is already running. Until
    /// [`World::finish_growth`] takes the task back, edits queue their seeds for the next
    /// job, exactly as while [`World::grow_distance_fields`] works in steps.
    pub fn start_growth(&mut self) -> Option<GrowthTask> {
        if self.growth.seeds.is_empty() || self.growth.detached || self.growth.job.is_some() {
            return None;
        }
        self.growth.detached = true;
        Some(GrowthTask {
            size: self.size,
            seeds: self.growth.seeds.clone(),
            chunks: self.chunks.clone(),
            job: None,
        })
    }

    /// Publishes a task from [`World::start_growth`] (running it to the end first if
    /// [`GrowthTask::run`] has not).
    pub fn finish_growth(&mut self, mut task: GrowthTask) -> ChangeSet {
        task.run();
        self.growth.detached = false;
        self.publish_growth(task.job.as_ref().expect("a run task has a job"))
    }

    /// A job recomputing the region around the current seeds, on a copy of the chunks.
    fn new_growth_job(&self) -> GrowthJob {
        GrowthJob::around(self.size, &self.growth.seeds, self.chunks.clone())
    }

    /// Publishes a converged job: its fields where the chunks are still free, clamped
    /// around the chunks that stopped being free while it ran. The seeds queued meanwhile
    /// become the next job's.
    fn publish_growth(&mut self, job: &GrowthJob) -> ChangeSet {
        let mut w = Writes::default();
        let mut written = Vec::new();
        for &i in job.region() {
            let v = job.value(i);
            // A chunk that stopped being free since the job started keeps its cell.
            if self.chunks[i as usize] != v && self.chunk_is_free(i as usize) {
                self.chunks[i as usize] = v;
                written.push(i);
                w.push(BufferId::Chunks, i as usize, 1);
            }
        }
        let blocked = std::mem::take(&mut self.growth.blocked);
        let mut clamped = Writes::default();
        self.clamp_around(&blocked, &mut clamped);
        for (_, r) in clamped.ranges() {
            written.extend(r.clone());
            w.push(BufferId::Chunks, r.start as usize, (r.end - r.start) as usize);
        }
        written.sort_unstable();
        written.dedup();
        let writes = written.iter().map(|&i| (i, self.chunks[i as usize])).collect();
        self.growth.seeds = std::mem::take(&mut self.growth.pending);
        self.growth.seq += 1;
        self.publish(Record::Chunks(writes), w)
    }

    /// Runs background growth until the world is quiescent; returns the change sets.
    pub fn grow_until_quiescent(&mut self) -> Vec<ChangeSet> {
        let mut out = Vec::new();
        while !self.is_quiescent() {
            out.extend(self.grow_distance_fields(usize::MAX));
        }
        out
    }

    /// Applies a change record made by another copy of this world (a mirror following the
    /// authoritative server). Batches must be the next version; chunk writes may only
    /// touch free chunks with empty cells.
    pub fn apply_record(&mut self, version: u64, record: &Record, limits: &Limits) -> Result<ChangeSet, EditError> {
        let bad = |reason: String| EditError::Invalid {
            index: 0,
            op: "record",
            reason,
        };
        match record {
            Record::Batch(batch) => {
                if version != self.version + 1 {
                    return Err(bad(format!(
                        "record for version {version}, but this world is at {}",
                        self.version
                    )));
                }
                Ok(self.apply_batch(batch, limits, false)?.change)
            }
            Record::Chunks(writes) => {
                if version != self.version {
                    return Err(bad(format!(
                        "growth for version {version}, but this world is at {}",
                        self.version
                    )));
                }
                let n = self.chunks.len();
                if let Some(&(i, v)) = writes
                    .iter()
                    .find(|&&(i, v)| i as usize >= n || v >> 30 != 0 || !self.chunk_is_free(i as usize))
                {
                    return Err(bad(format!("chunk write ({i}, {v:#x}) does not fit this world")));
                }
                let mut w = Writes::default();
                for &(i, v) in writes {
                    self.chunks[i as usize] = v;
                    w.push(BufferId::Chunks, i as usize, 1);
                }
                // A mirror never grows its own fields: it drops its copy of the queue and
                // follows the quiescent flags of the changes it is sent.
                self.growth = Growth {
                    seq: self.growth.seq + 1,
                    ..Growth::default()
                };
                Ok(self.publish(record.clone(), w))
            }
        }
    }

    /// The digest recomputed from scratch over every buffer (a test oracle for the
    /// incremental one).
    pub fn digest_from_scratch(&self) -> Digest {
        BufferId::WORLD.iter().fold(Digest::default(), |d, &id| {
            d ^ crate::digest::digest_of(id, &self.buffer_bytes(id))
        })
    }
}

/// Records the words of `old` that `new` changes, and a change of length, as runs: a run
/// absorbs a gap of up to [`BRIDGE`] unchanged words, which cost less than a run of its own
/// (so a move of scattered entities writes just their records).
fn diff_buffer(id: BufferId, old: &[u32], new: &[u32], w: &mut Writes) {
    if old == new {
        return;
    }
    let common = old.len().min(new.len());
    let mut run: Option<(usize, usize)> = None;
    let mut extend = |k: usize, end: usize, w: &mut Writes| match run {
        Some((s, e)) if k <= e + BRIDGE => run = Some((s, end)),
        Some((s, e)) => {
            w.push(id, s, e - s);
            run = Some((k, end));
        }
        None => run = Some((k, end)),
    };
    for k in (0..common).filter(|&k| old[k] != new[k]) {
        extend(k, k + 1, w);
    }
    if old.len() != new.len() {
        // The new tail (empty when the buffer shrank: the length alone changed).
        extend(common, new.len(), w);
    }
    if let Some((s, e)) = run {
        w.push(id, s, e - s);
    }
}

/// Unchanged words a run of [`diff_buffer`] bridges.
const BRIDGE: usize = 3;

//! Edits: applying batches of ops atomically, keeping the structure canonical and the
//! distance fields safe, background chunk-AADF growth, change sets and undo records.
//!
//! One batch → one new version → one [`ChangeSet`]. The change set's [`Record`] is compact
//! (a single-voxel edit is a dozen bytes): a mirror expands it into the exact buffer writes
//! by running the same code ([`World::apply_record`]), because every write an edit makes is
//! a deterministic function of the previous buffers and the batch. Background growth
//! publishes its chunk writes explicitly, as sub-steps `(version, growth_seq)`.

mod commit;
mod invalidate;
mod overlay;
mod record;
mod undo;
mod writes;

pub use invalidate::REGROW_RADIUS;
pub use record::{Decoded, Record};
pub use undo::UndoRecord;
pub use writes::Writes;

use crate::aadf::{GrowthJob, chunk_is_free};
use crate::digest::{BufferId, Digest};
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

/// Background chunk-AADF growth: the chunks whose freedom changed since the world last
/// converged, and the job recomputing the region around them.
#[derive(Clone, Debug, Default)]
pub struct Growth {
    seeds: Vec<u32>,
    job: Option<GrowthJob>,
    seq: u32,
}

impl World {
    /// Applies a batch atomically: on any error the world is untouched. Returns the new
    /// version's change set and the undo record.
    pub fn apply(&mut self, batch: &Batch, limits: &Limits) -> Result<Applied, EditError> {
        if let Some((index, op)) = batch.ops.iter().enumerate().find(|(_, op)| {
            matches!(
                op,
                ops::Op::SpawnEntity { .. } | ops::Op::MoveEntity { .. } | ops::Op::DespawnEntity { .. }
            )
        }) {
            return Err(EditError::Unsupported {
                index,
                op: op.name(),
                reason: "entities are not supported by this world model yet".into(),
            });
        }
        let mut materials = self.materials.clone();
        let mut models = self.models.clone();
        let mut overlay = Overlay::new(self);
        ops::apply_batch(batch, &mut overlay, &mut materials, &mut models, limits)?;
        let touched = overlay.into_touched();
        self.check_capacity(touched.len()).map_err(|e| EditError::Limit {
            index: 0,
            op: batch.ops.first().map_or("batch", |o| o.name()),
            reason: e.to_string(),
        })?;

        let undo = UndoRecord::diff(self, &touched);
        let mut w = Writes::default();
        if materials != self.materials {
            self.materials = materials;
            w.push(BufferId::Materials, 0, self.materials.words().len());
        }
        if models != self.models {
            self.models = models;
            w.push(BufferId::Models, 0, 0);
        }
        let mut blocked = Vec::new();
        let mut changed = Vec::new();
        for t in &touched {
            let was_free = self.chunk_is_free(t.index);
            let flipped = self.commit_chunk(t, &mut w).expect("validated batches commit");
            if flipped {
                changed.push(t.index as u32);
                if was_free {
                    blocked.push(t.index);
                }
            }
        }
        self.clamp_around(&blocked, &mut w);
        self.version += 1;
        self.growth.seq = 0;
        if !changed.is_empty() {
            self.growth.seeds.extend(changed);
            // Any job in progress saw the old content: start over with all seeds.
            self.growth.job = None;
        }
        let record = Record::of_batch(batch);
        Ok(Applied {
            change: self.publish(record, w),
            undo,
        })
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

    /// Whether no distance-field work is queued.
    pub fn is_quiescent(&self) -> bool {
        self.growth.seeds.is_empty()
    }

    /// Runs up to `budget` (level, axis) phases of background chunk-AADF growth. Returns a
    /// change set when a recomputation converges and its chunk writes are published (the
    /// last one is marked quiescent); `None` while work is still in progress or when there
    /// is none. Deterministic, and the converged fields equal a from-scratch build.
    pub fn grow_distance_fields(&mut self, budget: usize) -> Option<ChangeSet> {
        if self.growth.seeds.is_empty() {
            return None;
        }
        let size = self.size;
        let job = self.growth.job.get_or_insert_with(|| {
            let region = invalidate::regrow_region(size, &self.growth.seeds, |i| {
                chunk_is_free(self.chunks[i], self.chunk_entities[i])
            });
            GrowthJob::new(self.chunks.clone(), region)
        });
        let mut done = job.is_done();
        for _ in 0..budget {
            if done {
                break;
            }
            done = job.step(size, &self.chunk_entities);
        }
        if !done {
            return None;
        }
        let job = self.growth.job.take().expect("job exists");
        self.growth.seeds.clear();
        let mut writes = Vec::new();
        let mut w = Writes::default();
        for &i in job.region() {
            let v = job.value(i);
            if self.chunks[i as usize] != v {
                self.chunks[i as usize] = v;
                writes.push((i, v));
                w.push(BufferId::Chunks, i as usize, 1);
            }
        }
        self.growth.seq += 1;
        Some(self.publish(Record::Chunks(writes), w))
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
                Ok(self.apply(batch, limits)?.change)
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
                self.growth.seq += 1;
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

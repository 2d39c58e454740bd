//! The patch form of a delta: what a change wrote, byte for byte, so that a mirror without
//! the edit engine (a browser, a program in another language) can follow the world by
//! copying bytes. docs/PROTOCOL.md, "The patch form", specifies it.
//!
//! The runs cover exactly the byte ranges the world's digest was updated for (the writes of
//! the [`ChangeSet`], tables whole), so copying them reproduces every byte the digest
//! covers. A server and a relay that applied the same change make the same patch.

use crate::v1::{BufferLength, Delta, Patch, Run, Runs};
use naadf_world::World;
use naadf_world::digest::BufferId;
use naadf_world::edit::ChangeSet;
use prost::Message;

/// The zstd level of compressed runs (the level snapshot pages use).
const LEVEL: i32 = 3;
/// Runs shorter than this, encoded, are not worth a zstd frame (its header and the
/// compressor's set-up cost more than they could save).
const MIN_COMPRESSED: usize = 128;

/// Makes the patches of a world's changes, remembering its buffers' lengths between them.
pub struct PatchMaker {
    lens: [usize; 8],
    /// Kept between patches: making a compressor costs more than compressing a small run.
    zstd: zstd::bulk::Compressor<'static>,
}

impl PatchMaker {
    /// Follows `world` from its current state.
    pub fn new(world: &World) -> Self {
        Self {
            lens: BufferId::WORLD.map(|id| world.buffer_bytes(id).len()),
            zstd: zstd::bulk::Compressor::new(LEVEL).expect("a zstd compressor"),
        }
    }

    /// The patch of `change`, which `world` has just applied (the patches of all changes
    /// since [`PatchMaker::new`] must be made in order).
    pub fn patch(&mut self, world: &World, change: &ChangeSet) -> Patch {
        let mut lengths = Vec::new();
        for (k, id) in BufferId::WORLD.into_iter().enumerate() {
            // The model table is an encoding made on request: its length changes only
            // when the table is rewritten, which the writes say.
            let models_written = || change.writes.ranges().iter().any(|(w, _)| *w == BufferId::Models);
            if id == BufferId::Models && !models_written() {
                continue;
            }
            let len = world.buffer_bytes(id).len();
            if len != self.lens[k] {
                self.lens[k] = len;
                lengths.push(BufferLength {
                    buffer: id as u32,
                    bytes: len as u64,
                });
            }
        }
        let mut runs: Vec<Run> = Vec::new();
        for (id, words) in change.writes.ranges() {
            let bytes = world.buffer_bytes(*id);
            let range = match id {
                // Tables are rewritten whole, once.
                BufferId::Materials | BufferId::Models => {
                    if runs.last().is_some_and(|r| r.buffer == *id as u32) {
                        continue;
                    }
                    0..bytes.len()
                }
                _ => (4 * words.start as usize).min(bytes.len())..(4 * words.end as usize).min(bytes.len()),
            };
            if !range.is_empty() {
                runs.push(Run {
                    buffer: *id as u32,
                    offset: range.start as u64,
                    bytes: bytes[range].to_vec(),
                });
            }
        }
        let plain = Runs { runs };
        let encoded = plain.encode_to_vec();
        let zstd = if encoded.len() >= MIN_COMPRESSED {
            self.zstd.compress(&encoded).expect("compressing into memory")
        } else {
            Vec::new()
        };
        let (runs, zstd) = if !zstd.is_empty() && zstd.len() < encoded.len() {
            (Vec::new(), zstd)
        } else {
            (plain.runs, Vec::new())
        };
        Patch {
            version: change.version,
            growth_seq: change.growth_seq,
            quiescent: change.quiescent,
            lengths,
            runs,
            zstd,
        }
    }
}

/// The encoded sizes, in bytes, of the `Delta` of `change` in the record form and in the
/// patch form, `patch` being its patch, with no user: what a client of each form receives
/// for it.
pub fn delta_sizes(change: &ChangeSet, patch: Patch) -> [usize; 2] {
    let record = Delta {
        change: change.encode(),
        digest: change.digest.0,
        ..Delta::default()
    };
    let patch = Delta {
        digest: change.digest.0,
        patch: Some(patch),
        ..Delta::default()
    };
    [record.encoded_len(), patch.encoded_len()]
}

#[cfg(test)]
mod tests {
    use super::*;
    use naadf_world::ops::{Batch, Limits, Op};
    use naadf_world::preset::Preset;
    use naadf_world::raysets::SplitMix64;
    use naadf_world::size::WorldSize;

    /// A move of many entities is a few bytes per entity in both forms: at most 16 in the
    /// record form (plus 32 of header) and at most 20 in the patch form.
    #[test]
    fn a_move_of_a_thousand_entities_is_small_in_both_forms() {
        let size = WorldSize::new(512, 128, 512).unwrap();
        let mut world = World::build(&*Preset::Test.source(Some(size), 1).unwrap(), &|_| {}).unwrap();
        let mut rng = SplitMix64(3);
        let pose = |rng: &mut SplitMix64| {
            (
                [rng.unit() * 500.0, rng.unit() * 100.0, rng.unit() * 500.0],
                [rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5],
            )
        };
        let mut ops = vec![Op::DefineModel {
            name: "crate".into(),
            size: [8, 8, 8],
            voxels: vec![[0, 0, 0, 1], [7, 7, 7, 2]],
        }];
        for id in 0..1000 {
            let (pos, rot) = pose(&mut rng);
            ops.push(Op::SpawnEntity {
                id,
                model: "crate".into(),
                pos,
                rot,
            });
        }
        world.apply(&Batch { ops }, &Limits::default()).unwrap();
        let mut maker = PatchMaker::new(&world);
        let moves = (0..1000)
            .map(|id| {
                let (pos, rot) = pose(&mut rng);
                Op::MoveEntity { id, pos, rot }
            })
            .collect();
        let change = world.apply(&Batch { ops: moves }, &Limits::default()).unwrap().change;
        let patch = maker.patch(&world, &change);
        let [record, patch] = delta_sizes(&change, patch);
        assert!(record <= 1000 * 16 + 32, "record form: {record} bytes");
        assert!(patch <= 1000 * 20, "patch form: {patch} bytes");
    }
}

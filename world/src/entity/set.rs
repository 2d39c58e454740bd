//! [`InstanceSet`]: what a ray test reads of the instances, derived from the instance
//! buffer on every machine (neither mirrored nor digested): each live record, its boxes,
//! and the hierarchy over their world boxes.
//!
//! A set is derived when a machine first needs it after the instance buffer changed (a ray
//! test, or the hierarchy for a device), so that a machine that only applies moves never
//! derives one. When the same slots hold instances as in the set derived last, that set's
//! hierarchy is refitted rather than built: about ten times cheaper, and as good while the
//! moves are small. Moves anywhere make a refitted shape far worse (BENCHMARKS.md, "Entities
//! as instances": 163 expected node visits against 9 for 1,000 entities), so a refit is
//! kept only while its [`Bvh::expected_visits`] stays within [`REFIT_SLACK`] of the build
//! it came from; otherwise the hierarchy is built anew. The shape thus depends on the
//! history of moves, and of when sets were derived, which changes how many boxes a ray
//! tests, never what it hits.

use super::bounds::Bounds;
use super::bvh::{Aabb, Bvh};
use super::pack::{InstanceRecord, RECORD_WORDS};

/// How many times the expected node visits of the build it came from a refitted hierarchy
/// may reach before it is built anew.
pub const REFIT_SLACK: f64 = 1.25;

/// The live instances of an instance buffer, in slot (id) order, and their hierarchy.
#[derive(Clone, Debug, Default)]
pub(crate) struct InstanceSet {
    /// Per instance: its record.
    pub records: Vec<[u32; RECORD_WORDS]>,
    /// Per instance: its slot in the instance buffer (its id).
    pub slots: Vec<u32>,
    /// Per instance: its padded world and oriented boxes.
    pub bounds: Vec<Bounds>,
    /// The hierarchy over the world boxes; its primitives index the lists above.
    pub bvh: Bvh,
    /// The expected node visits of the hierarchy when it was last built (not refitted).
    built_visits: f64,
}

impl InstanceSet {
    /// The set of the instance buffer `words`: a slot whose record has a zero size word
    /// holds no instance.
    pub fn of_buffer(words: &[u32]) -> Self {
        let mut set = Self::records_of(words);
        set.build(&set.world_boxes());
        set
    }

    /// The set of the instance buffer `words`, which replaces this one: when the same slots
    /// hold instances, with this hierarchy refitted to their new boxes if that keeps it
    /// within [`REFIT_SLACK`] of its build.
    pub fn moved_to(&self, words: &[u32]) -> Self {
        let mut set = Self::records_of(words);
        let boxes = set.world_boxes();
        if set.slots != self.slots || self.is_empty() {
            set.build(&boxes);
            return set;
        }
        set.bvh = self.bvh.clone();
        set.bvh.refit(&boxes);
        set.built_visits = self.built_visits;
        if set.bvh.expected_visits() > REFIT_SLACK * self.built_visits {
            set.build(&boxes);
        }
        set
    }

    /// The live records of `words`, with their boxes, and no hierarchy yet.
    fn records_of(words: &[u32]) -> Self {
        let mut set = InstanceSet::default();
        for (slot, w) in words.chunks_exact(RECORD_WORDS).enumerate() {
            if w[4] == 0 {
                continue;
            }
            let rec = InstanceRecord::unpack(w);
            set.records.push(w.try_into().expect("five words"));
            set.slots.push(slot as u32);
            set.bounds.push(Bounds::of(&rec));
        }
        set
    }

    fn world_boxes(&self) -> Vec<Aabb> {
        self.bounds.iter().map(Bounds::world_box).collect()
    }

    /// The world boxes of the live records of `words`.
    pub fn boxes_of(words: &[u32]) -> Vec<Aabb> {
        Self::records_of(words).world_boxes()
    }

    /// Builds the hierarchy anew over `boxes` (this set's world boxes).
    fn build(&mut self, boxes: &[Aabb]) {
        self.bvh = Bvh::build(boxes);
        self.built_visits = self.bvh.expected_visits();
    }

    /// Whether there is no instance.
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// The packed hierarchy the GPU walks ([`Bvh::words`], leaves as slots).
    pub fn hierarchy_words(&self) -> Vec<u32> {
        self.bvh.words(&self.slots)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::entity::pack::quantise_pose;
    use crate::raysets::SplitMix64;

    /// An instance buffer of `n` 4³ instances at `pos(k)`, unrotated.
    fn buffer(n: u32, pos: impl Fn(u32) -> [f64; 3]) -> Vec<u32> {
        (0..n)
            .flat_map(|id| {
                let q = quantise_pose(pos(id), [0.0, 0.0, 0.0, 1.0]).unwrap();
                InstanceRecord {
                    id,
                    size: [4, 4, 4],
                    voxel_start: 0,
                    pos: q.fixed,
                    inv_rot: q.inv_rot,
                }
                .pack()
            })
            .collect()
    }

    #[test]
    fn small_moves_refit_the_hierarchy_and_moves_anywhere_rebuild_it() {
        let spread = |seed: u64| {
            move |id: u32| {
                let mut r = SplitMix64(seed << 20 | u64::from(id));
                [0, 1, 2].map(|_| 8.0 + r.unit() * 900.0)
            }
        };
        let first = InstanceSet::of_buffer(&buffer(500, spread(1)));
        // Half a voxel along x: the refit is as good as the build, and kept.
        let nudged = buffer(500, |id| {
            let p = spread(1)(id);
            [p[0] + 0.5, p[1], p[2]]
        });
        let moved = first.moved_to(&nudged);
        let mut refit = first.bvh.clone();
        refit.refit(&moved.world_boxes());
        assert_eq!(moved.bvh, refit);
        // Everywhere else: the refit would be far worse, so the hierarchy is built anew.
        let scattered = buffer(500, spread(2));
        let rebuilt = moved.moved_to(&scattered);
        assert_eq!(rebuilt.bvh, Bvh::build(&rebuilt.world_boxes()));
        // Another set of slots is always built anew.
        let fewer = first.moved_to(&nudged[..5 * 400]);
        assert_eq!(fewer.bvh, Bvh::build(&fewer.world_boxes()));
    }
}

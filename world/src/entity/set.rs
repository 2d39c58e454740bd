//! [`InstanceSet`]: what a ray test reads of the instances, derived from the instance
//! buffer on every machine (neither mirrored nor digested): each live record, its boxes,
//! and the hierarchy over their world boxes.

use super::bounds::Bounds;
use super::bvh::{Aabb, Bvh};
use super::pack::{InstanceRecord, RECORD_WORDS};

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
}

impl InstanceSet {
    /// The set of the instance buffer `words`: a slot whose record has a zero size word
    /// holds no instance.
    pub fn of_buffer(words: &[u32]) -> Self {
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
        let boxes: Vec<Aabb> = set.bounds.iter().map(Bounds::world_box).collect();
        set.bvh = Bvh::build(&boxes);
        set
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

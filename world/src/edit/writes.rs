//! The buffer writes of one change: what a GPU mirror uploads and the digest rehashes.

use crate::digest::BufferId;
use std::ops::Range;

/// Word ranges written per buffer (material and model tables count as rewritten whole).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Writes {
    ranges: Vec<(BufferId, Range<u32>)>,
}

impl Writes {
    /// Records a write of `len` words at word `start` of buffer `id`.
    pub fn push(&mut self, id: BufferId, start: usize, len: usize) {
        self.ranges.push((id, start as u32..(start + len) as u32));
    }

    /// Sorts and merges overlapping or touching ranges.
    pub fn normalize(&mut self) {
        self.ranges.sort_by_key(|(id, r)| (*id, r.start, r.end));
        let mut out: Vec<(BufferId, Range<u32>)> = Vec::with_capacity(self.ranges.len());
        for (id, r) in self.ranges.drain(..) {
            match out.last_mut() {
                Some((lid, lr)) if *lid == id && r.start <= lr.end => lr.end = lr.end.max(r.end),
                _ => out.push((id, r)),
            }
        }
        self.ranges = out;
    }

    /// The ranges, by buffer then position (after [`Writes::normalize`]).
    pub fn ranges(&self) -> &[(BufferId, Range<u32>)] {
        &self.ranges
    }

    /// Whether nothing was written.
    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// Total words written.
    pub fn words(&self) -> u64 {
        self.ranges.iter().map(|(_, r)| u64::from(r.end - r.start)).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merges_touching_ranges_per_buffer() {
        let mut w = Writes::default();
        w.push(BufferId::Blocks, 64, 64);
        w.push(BufferId::Chunks, 5, 1);
        w.push(BufferId::Blocks, 0, 64);
        w.push(BufferId::Chunks, 7, 1);
        w.normalize();
        assert_eq!(
            w.ranges(),
            &[
                (BufferId::Chunks, 5..6),
                (BufferId::Chunks, 7..8),
                (BufferId::Blocks, 0..128)
            ]
        );
        assert_eq!(w.words(), 130);
    }
}

//! The world digest (docs/FORMAT.md §8): 64 bits, kept incrementally in O(changed pages).
//!
//! Every mirrored buffer and table, taken at its logical length, is cut into 64 KiB pages
//! (the last one may be short). Page `k` of buffer `id` contributes
//! `xxh3_64(id as u32 LE ‖ k as u32 LE ‖ page bytes)`, and all contributions combine by
//! XOR. Empty buffers contribute nothing; the version is not included. The digest prints as
//! 16 lowercase hex digits.

use crate::hash::Xxh3;
use rayon::prelude::*;
use std::fmt;
use std::ops::BitXor;
use std::str::FromStr;

/// Bytes per digest page.
pub const PAGE_BYTES: usize = 64 * 1024;

/// Identifies each digested buffer or table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[repr(u32)]
pub enum BufferId {
    /// `chunks` (u32 LE).
    Chunks = 0,
    /// `chunk_entities` (u32 LE).
    ChunkEntities = 1,
    /// `blocks` (u32 LE).
    Blocks = 2,
    /// `voxels` (u32 LE).
    Voxels = 3,
    /// The material table: 16 bytes per entry.
    Materials = 4,
    /// The model table in its canonical encoding.
    Models = 5,
    /// The entity-type buffer: every type's dense voxel grid (u32 LE, [`crate::entity`]).
    EntityTypes = 6,
    /// The entity instance buffer: each entity's 5-word record in the slot of its id (u32 LE).
    EntityInstances = 7,
}

impl BufferId {
    /// Every buffer and table of a world, in id order.
    pub const WORLD: [BufferId; 8] = [
        BufferId::Chunks,
        BufferId::ChunkEntities,
        BufferId::Blocks,
        BufferId::Voxels,
        BufferId::Materials,
        BufferId::Models,
        BufferId::EntityTypes,
        BufferId::EntityInstances,
    ];
}

/// A 64-bit world digest.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Digest(pub u64);

impl BitXor for Digest {
    type Output = Digest;
    fn bitxor(self, rhs: Digest) -> Digest {
        Digest(self.0 ^ rhs.0)
    }
}

impl fmt::Display for Digest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:016x}", self.0)
    }
}

impl FromStr for Digest {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s.len() != 16 || !s.bytes().all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b)) {
            return Err(format!("'{s}' is not 16 lowercase hex digits"));
        }
        u64::from_str_radix(s, 16).map(Digest).map_err(|e| e.to_string())
    }
}

/// The contribution of one page.
pub fn page_hash(id: BufferId, page: usize, bytes: &[u8]) -> u64 {
    let mut h = Xxh3::new();
    h.update(&(id as u32).to_le_bytes());
    h.update(&(page as u32).to_le_bytes());
    h.update(bytes);
    h.digest()
}

/// Above this many dirty pages, an update rehashes them on the thread pool.
const PARALLEL_PAGES: usize = 16;

/// The contribution of a whole buffer (all its pages, in parallel).
///
/// ```
/// use naadf_world::digest::{digest_of, BufferId, Digest};
/// assert_eq!(digest_of(BufferId::Chunks, &[]), Digest(0));
/// ```
pub fn digest_of(id: BufferId, bytes: &[u8]) -> Digest {
    Digest(
        bytes
            .par_chunks(PAGE_BYTES)
            .enumerate()
            .map(|(k, p)| page_hash(id, k, p))
            .reduce(|| 0, |a, b| a ^ b),
    )
}

/// An incrementally maintained digest: remembers every page's hash so that a change costs
/// only the pages it touches.
#[derive(Clone, Debug, Default)]
pub struct PagedDigest {
    /// Per buffer: its byte length and its page hashes.
    buffers: std::collections::BTreeMap<BufferId, (usize, Vec<u64>)>,
    total: u64,
}

impl PagedDigest {
    /// The current digest.
    pub fn digest(&self) -> Digest {
        Digest(self.total)
    }

    /// The hash of every page of buffer `id`, in page order (empty if never recorded).
    pub fn page_hashes(&self, id: BufferId) -> &[u64] {
        self.buffers.get(&id).map_or(&[], |(_, pages)| pages.as_slice())
    }

    /// The byte length of buffer `id` as last recorded.
    pub fn len(&self, id: BufferId) -> usize {
        self.buffers.get(&id).map_or(0, |(len, _)| *len)
    }

    /// Records that buffer `id` now holds `bytes`, of which only the byte range `dirty`
    /// (plus any change of length) differs from what was last recorded.
    pub fn update(&mut self, id: BufferId, bytes: &[u8], dirty: std::ops::Range<usize>) {
        self.update_ranges(id, bytes, std::slice::from_ref(&dirty));
    }

    /// [`PagedDigest::update`] for several dirty byte ranges at once; the pages they touch
    /// are rehashed in parallel.
    pub fn update_ranges(&mut self, id: BufferId, bytes: &[u8], dirty: &[std::ops::Range<usize>]) {
        let (old_bytes, pages) = self.buffers.entry(id).or_default();
        let new_pages = bytes.len().div_ceil(PAGE_BYTES);
        for h in pages.drain(new_pages.min(pages.len())..) {
            self.total ^= h;
        }
        let kept = pages.len();
        pages.resize(new_pages, 0);
        // Dirty pages, plus everything from the old end on if the length changed.
        let mut todo: Vec<usize> = dirty
            .iter()
            .flat_map(|r| r.start / PAGE_BYTES..r.end.div_ceil(PAGE_BYTES).min(new_pages))
            .collect();
        if *old_bytes != bytes.len() {
            todo.extend((*old_bytes).min(bytes.len()) / PAGE_BYTES..new_pages);
        }
        todo.sort_unstable();
        todo.dedup();
        let hash = |&k: &usize| page_hash(id, k, &bytes[k * PAGE_BYTES..((k + 1) * PAGE_BYTES).min(bytes.len())]);
        // A typical edit dirties a few pages: hashing them here (tens of microseconds) beats
        // handing them to the thread pool, which from outside the pool means two thread
        // wake-ups, and under load a wait behind other work.
        let hashes: Vec<u64> = if todo.len() > PARALLEL_PAGES {
            todo.par_iter().map(hash).collect()
        } else {
            todo.iter().map(hash).collect()
        };
        for (&k, h) in todo.iter().zip(hashes) {
            if k < kept {
                self.total ^= pages[k];
            }
            pages[k] = h;
            self.total ^= h;
        }
        *old_bytes = bytes.len();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn hex_roundtrip() {
        let d = Digest(0x0123_4567_89ab_cdef);
        assert_eq!(d.to_string(), "0123456789abcdef");
        assert_eq!("0123456789abcdef".parse::<Digest>().unwrap(), d);
        assert!("0123456789ABCDEF".parse::<Digest>().is_err());
    }

    #[test]
    fn page_contribution_is_defined_by_the_contract() {
        // One short page: xxh3 of (id, page 0, bytes).
        let bytes = [1u8, 2, 3];
        let mut msg = 3u32.to_le_bytes().to_vec();
        msg.extend_from_slice(&0u32.to_le_bytes());
        msg.extend_from_slice(&bytes);
        assert_eq!(digest_of(BufferId::Voxels, &bytes).0, crate::hash::xxh3_64(&msg));
    }

    proptest! {
        #[test]
        fn incremental_equals_full(edits in prop::collection::vec((0usize..300_000, 0usize..70_000, any::<u8>(), 0usize..300_000), 1..8)) {
            let mut buf = vec![7u8; 150_000];
            let mut inc = PagedDigest::default();
            inc.update(BufferId::Blocks, &buf, 0..buf.len());
            for (at, len, val, resize) in edits {
                let dirty = if resize % 3 == 0 {
                    let old = buf.len();
                    buf.resize(resize, val);
                    old.min(resize)..resize.max(old)
                } else {
                    let at = at.min(buf.len());
                    let end = (at + len).min(buf.len());
                    buf[at..end].fill(val);
                    at..end
                };
                inc.update(BufferId::Blocks, &buf, dirty);
                prop_assert_eq!(inc.digest(), digest_of(BufferId::Blocks, &buf));
            }
        }
    }
}

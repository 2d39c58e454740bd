//! Deduplication of voxel groups: one authoritative open-addressing map from group content
//! to group slot, reference counts, and deterministic slot allocation.
//!
//! Unlike the reference engine (docs/NAADF.md §5 and §14, R1–R3):
//! - deleted entries become tombstones, so probe chains never break;
//! - a probe that fails after [`PROBE_LIMIT`] slots appends a new group instead of
//!   returning a bogus pointer;
//! - there is only one map, and it is rehashed from its own entries.
//!
//! A group's key is its content. Empty voxels carry AADF bits, but those are a pure
//! function of the content, so comparing the stored 32 words compares content.

use crate::cell::{self, GROUP_WORDS, PAYLOAD};
use crate::error::WorldError;
use crate::hash::block_hash;
use std::collections::BTreeSet;

/// Slots probed before giving up and appending an unshared group.
pub const PROBE_LIMIT: usize = 250;

const EMPTY: u32 = u32::MAX;
const TOMBSTONE: u32 = u32::MAX - 1;

#[derive(Clone, Copy)]
struct Slot {
    group: u32,
    hash: u32,
}

/// Open-addressing map from a group's hash and content to its group index
/// (`word pointer / 32`). Kept at most half full, tombstones included.
#[derive(Clone)]
struct GroupMap {
    slots: Vec<Slot>,
    bits: u32,
    live: usize,
    used: usize,
}

impl GroupMap {
    fn with_bits(bits: u32) -> Self {
        Self {
            slots: vec![Slot { group: EMPTY, hash: 0 }; 1 << bits],
            bits,
            live: 0,
            used: 0,
        }
    }

    #[inline]
    fn home(&self, hash: u32) -> usize {
        // Fibonacci hashing spreads the polynomial hash's weak low bits.
        (hash.wrapping_mul(0x9E37_79B9) >> (32 - self.bits)) as usize
    }

    /// The group holding exactly `words`, or where to insert it (`None` if the probe
    /// limit was hit without a free slot).
    fn find(&self, hash: u32, words: &[u32; GROUP_WORDS], voxels: &[u32]) -> Result<u32, Option<usize>> {
        let mask = self.slots.len() - 1;
        let mut at = self.home(hash);
        let mut vacant = None;
        for _ in 0..PROBE_LIMIT.min(self.slots.len()) {
            let s = self.slots[at];
            if s.group == EMPTY {
                return Err(vacant.or(Some(at)));
            }
            if s.group == TOMBSTONE {
                vacant = vacant.or(Some(at));
            } else if s.hash == hash {
                let p = s.group as usize * GROUP_WORDS;
                if voxels[p..p + GROUP_WORDS] == words[..] {
                    return Ok(s.group);
                }
            }
            at = (at + 1) & mask;
        }
        Err(vacant)
    }

    fn insert_at(&mut self, at: usize, hash: u32, group: u32) {
        if self.slots[at].group == EMPTY {
            self.used += 1;
        }
        self.slots[at] = Slot { group, hash };
        self.live += 1;
    }

    fn remove(&mut self, hash: u32, group: u32) {
        let mask = self.slots.len() - 1;
        let mut at = self.home(hash);
        for _ in 0..self.slots.len() {
            let s = self.slots[at];
            if s.group == EMPTY {
                return;
            }
            if s.group == group {
                self.slots[at].group = TOMBSTONE;
                self.live -= 1;
                return;
            }
            at = (at + 1) & mask;
        }
    }

    /// Keeps room for `n` more entries with the map at most half full (tombstones count);
    /// when it must, rehashes in slot order into a map at most a quarter full.
    fn reserve(&mut self, n: usize) {
        if (self.used + n) * 2 <= self.slots.len() {
            return;
        }
        let mut bits = self.bits;
        while (self.live + n) * 4 > 1 << bits {
            bits += 1;
        }
        let old = std::mem::replace(self, Self::with_bits(bits));
        for s in old.slots.into_iter().filter(|s| s.group < TOMBSTONE) {
            let mask = self.slots.len() - 1;
            let mut at = self.home(s.hash);
            while self.slots[at].group != EMPTY {
                at = (at + 1) & mask;
            }
            self.insert_at(at, s.hash, s.group);
        }
    }
}

/// The voxel-group store: the dedup map, per-group reference counts and the free slots.
#[derive(Clone)]
pub struct GroupStore {
    map: GroupMap,
    refs: Vec<u32>,
    free: BTreeSet<u32>,
}

impl Default for GroupStore {
    fn default() -> Self {
        Self {
            map: GroupMap::with_bits(12),
            refs: Vec::new(),
            free: BTreeSet::new(),
        }
    }
}

/// Hash of a stored group: the reference hash of its material ids.
pub fn stored_group_hash(voxels: &[u32], ptr: usize) -> u32 {
    let raw: [u16; 64] = std::array::from_fn(|i| cell::voxel_material(cell::group_voxel(voxels, ptr, i)));
    block_hash(&raw)
}

impl GroupStore {
    /// Takes a reference to the group with content `words` (final cells, AADF bits set),
    /// storing it in the lowest free slot (else appending) if it is new. Returns the group's
    /// word pointer.
    pub fn acquire(&mut self, voxels: &mut Vec<u32>, hash: u32, words: &[u32; GROUP_WORDS]) -> Result<u32, WorldError> {
        self.map.reserve(1);
        let vacant = match self.map.find(hash, words, voxels) {
            Ok(g) => {
                self.refs[g as usize] += 1;
                return Ok(g * GROUP_WORDS as u32);
            }
            Err(vacant) => vacant,
        };
        let g = match self.free.pop_first() {
            Some(g) => g,
            None => {
                let g = self.refs.len() as u32;
                if (g as usize + 1) * GROUP_WORDS > PAYLOAD as usize {
                    return Err(WorldError::Capacity(
                        "more voxel groups than 30-bit pointers can address".into(),
                    ));
                }
                self.refs.push(0);
                voxels.resize(voxels.len() + GROUP_WORDS, 0);
                g
            }
        };
        let p = g as usize * GROUP_WORDS;
        voxels[p..p + GROUP_WORDS].copy_from_slice(words);
        self.refs[g as usize] = 1;
        if let Some(at) = vacant {
            self.map.insert_at(at, hash, g);
        }
        Ok(p as u32)
    }

    /// Drops one reference to the group at word pointer `ptr`; the last one frees and zeroes
    /// its slot.
    pub fn release(&mut self, voxels: &mut [u32], ptr: u32) {
        let g = ptr as usize / GROUP_WORDS;
        self.refs[g] -= 1;
        if self.refs[g] == 0 {
            let hash = stored_group_hash(voxels, ptr as usize);
            self.map.remove(hash, g as u32);
            voxels[ptr as usize..ptr as usize + GROUP_WORDS].fill(0);
            self.free.insert(g as u32);
        }
    }

    /// Rebuilds the store from the buffers of a loaded world: reference counts from the
    /// blocks that point at each group, free slots where none do. `block_ptrs` yields the
    /// voxel pointer of every live mixed block (each already checked to be in range).
    pub fn rebuild(voxels: &[u32], block_ptrs: impl Iterator<Item = u32>) -> Self {
        let groups = voxels.len() / GROUP_WORDS;
        let mut s = Self {
            refs: vec![0; groups],
            ..Self::default()
        };
        // Sized once, with room for as many new groups again: a rehash right after a load
        // would stall the first edit (and every mirror of the same world at once).
        s.map.reserve(groups);
        for p in block_ptrs {
            s.refs[p as usize / GROUP_WORDS] += 1;
        }
        for g in 0..groups {
            if s.refs[g] == 0 {
                s.free.insert(g as u32);
                continue;
            }
            let hash = stored_group_hash(voxels, g * GROUP_WORDS);
            let words: &[u32; GROUP_WORDS] = voxels[g * GROUP_WORDS..][..GROUP_WORDS].try_into().expect("32 words");
            s.map.reserve(1);
            // An identical earlier group keeps the map entry; this one stays unshared.
            if let Err(Some(at)) = s.map.find(hash, words, voxels) {
                s.map.insert_at(at, hash, g as u32);
            }
        }
        s
    }

    /// Makes room in the dedup map for as many new groups as there are live ones, so that
    /// the edits after a build do not pay for a rehash.
    pub fn reserve_headroom(&mut self) {
        self.map.reserve(self.map.live);
    }

    /// Live references to the group at word pointer `ptr`.
    pub fn refs(&self, ptr: u32) -> u32 {
        self.refs.get(ptr as usize / GROUP_WORDS).copied().unwrap_or(0)
    }

    /// Number of live (referenced) groups.
    pub fn live_groups(&self) -> usize {
        self.refs.len() - self.free.len()
    }

    /// Word pointers of the free group slots, lowest first.
    pub fn free_slots(&self) -> impl Iterator<Item = u32> + '_ {
        self.free.iter().map(|g| g * GROUP_WORDS as u32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn group(seed: u32) -> ([u32; 32], u32) {
        let raw: [u16; 64] = std::array::from_fn(|i| ((seed as usize * 7 + i * 13) % 5) as u16);
        let words = std::array::from_fn(|w| {
            let v = |i: usize| u32::from(cell::voxel(raw[i]));
            v(2 * w) | v(2 * w + 1) << 16
        });
        (words, block_hash(&raw))
    }

    #[test]
    fn dedups_counts_and_reuses_lowest_slot() {
        let mut s = GroupStore::default();
        let mut voxels = Vec::new();
        let (a, ha) = group(1);
        let (b, hb) = group(2);
        let pa = s.acquire(&mut voxels, ha, &a).unwrap();
        let pb = s.acquire(&mut voxels, hb, &b).unwrap();
        assert_eq!(s.acquire(&mut voxels, ha, &a).unwrap(), pa);
        assert_eq!((pa, pb, s.refs(pa), s.live_groups()), (0, 32, 2, 2));
        s.release(&mut voxels, pa);
        s.release(&mut voxels, pa);
        assert!(voxels[..32].iter().all(|&w| w == 0));
        // b is still found through the tombstone left by a.
        assert_eq!(s.acquire(&mut voxels, hb, &b).unwrap(), pb);
        let (c, hc) = group(3);
        assert_eq!(s.acquire(&mut voxels, hc, &c).unwrap(), 0, "lowest free slot first");
    }

    /// A store rebuilt from a loaded world (or given headroom after a build) takes as many
    /// new groups again without rehashing: a rehash right after a load would stall the
    /// first edits of every mirror of that world at once.
    #[test]
    fn loaded_and_built_stores_have_room_to_grow() {
        let mut voxels = Vec::new();
        let mut ptrs = Vec::new();
        for k in 0..5000u32 {
            let (mut w, _) = group(k);
            w[0] = cell::voxel(1 + (k % 7) as u16).into();
            w[1] = k | 0x8000;
            ptrs.push(voxels.len() as u32);
            voxels.extend_from_slice(&w);
        }
        let room = |s: &GroupStore| (s.map.slots.len() / 2).saturating_sub(s.map.used);
        let loaded = GroupStore::rebuild(&voxels, ptrs.iter().copied());
        assert!(
            room(&loaded) >= loaded.live_groups(),
            "{} free for {}",
            room(&loaded),
            loaded.live_groups()
        );
        let mut built = GroupStore::default();
        let mut out = Vec::new();
        for g in voxels.chunks(GROUP_WORDS) {
            let w: &[u32; GROUP_WORDS] = g.try_into().unwrap();
            built.acquire(&mut out, stored_group_hash(g, 0), w).unwrap();
        }
        built.reserve_headroom();
        assert!(
            room(&built) >= built.live_groups(),
            "{} free for {}",
            room(&built),
            built.live_groups()
        );
    }

    #[test]
    fn survives_many_colliding_hashes() {
        let mut s = GroupStore::default();
        let mut voxels = Vec::new();
        let mut ptrs = Vec::new();
        for k in 0..600u32 {
            let (mut w, _) = group(k);
            w[0] = k;
            // The same hash for every group forces long probe chains and the append fallback.
            ptrs.push(s.acquire(&mut voxels, 42, &w).unwrap());
        }
        let mut sorted = ptrs.clone();
        sorted.dedup();
        assert_eq!(sorted.len(), 600);
        assert_eq!(s.live_groups(), 600);
    }
}

//! Snapshot pages on the server: the current 64 KiB pages of every digested buffer, kept
//! incrementally, and a cache of their zstd frames shared by all joining clients.
//!
//! Record-form clients are sent the [`TRANSFERRED`] buffers (ids 0–5) and derive the
//! entity buffers from the entity table; patch-form clients, which have no edit engine to
//! derive them with, are sent all eight ([`paged_buffers`]).
//!
//! The actor updates the [`PageStore`] after every change by comparing the world's page
//! hashes (kept by its incremental digest) with the stored ones, so only changed pages are
//! copied. A join takes a [`SnapshotView`]: the pages as `Arc`s, so views are cheap and stay
//! valid while the world moves on.

use naadf_proto::snapshot::{GROUP_PAGES, compress_pages};
use naadf_world::World;
use naadf_world::digest::{BufferId, Digest, PAGE_BYTES};
use naadf_world::file::TRANSFERRED;
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// One page: its hash (the digest contribution) and its bytes.
#[derive(Clone, Debug)]
pub struct StoredPage {
    /// xxh3 digest contribution of the page (unique per buffer, index and content).
    pub hash: u64,
    /// The raw page bytes.
    pub bytes: Arc<[u8]>,
}

/// A page that changed: `(buffer id, page index, new hash)`.
pub type PageChange = (u8, u32, u64);

/// Buffers a page store keeps: every digested one, by id.
pub const PAGED: usize = BufferId::WORLD.len();

/// The buffers a snapshot sends a client whose deltas come in `form` (ids, ascending).
pub fn paged_buffers(form: naadf_proto::v1::DeltaForm) -> &'static [BufferId] {
    match form {
        naadf_proto::v1::DeltaForm::Record => &TRANSFERRED,
        naadf_proto::v1::DeltaForm::Patch => &BufferId::WORLD,
    }
}

/// The current pages of the digested buffers, by buffer id.
#[derive(Debug)]
pub struct PageStore {
    pages: [Vec<StoredPage>; PAGED],
    lens: [usize; PAGED],
}

impl PageStore {
    /// All pages of `world`.
    pub fn new(world: &World) -> Self {
        let mut s = Self {
            pages: Default::default(),
            lens: [0; PAGED],
        };
        s.update(world);
        s
    }

    /// Brings the store up to date with `world`; returns the pages that changed (pages
    /// that vanished because a buffer shrank are implied by the new lengths).
    pub fn update(&mut self, world: &World) -> Vec<PageChange> {
        let mut changes = Vec::new();
        for (slot, &id) in BufferId::WORLD.iter().enumerate() {
            let hashes = world.page_hashes(id);
            self.lens[slot] = world.buffer_len(id);
            let pages = &mut self.pages[slot];
            pages.truncate(hashes.len());
            let first_diff = (0..hashes.len()).find(|&k| pages.get(k).is_none_or(|p| p.hash != hashes[k]));
            let Some(first) = first_diff else {
                continue;
            };
            let bytes = world.buffer_bytes(id);
            for (k, &h) in hashes.iter().enumerate().skip(first) {
                if pages.get(k).is_some_and(|p| p.hash == h) {
                    continue;
                }
                let page = StoredPage {
                    hash: h,
                    bytes: bytes[k * PAGE_BYTES..((k + 1) * PAGE_BYTES).min(bytes.len())].into(),
                };
                if k < pages.len() {
                    pages[k] = page;
                } else {
                    pages.push(page);
                }
                changes.push((slot as u8, k as u32, h));
            }
        }
        changes
    }

    /// The byte lengths of the buffers.
    pub fn lens(&self) -> [usize; PAGED] {
        self.lens
    }

    /// A view of the current pages.
    pub fn pages(&self) -> [Vec<StoredPage>; PAGED] {
        self.pages.clone()
    }
}

/// A consistent snapshot of the world at one point of the change sequence.
#[derive(Debug)]
pub struct SnapshotView {
    /// World size in voxels.
    pub size: [u32; 3],
    /// Edit version.
    pub version: u64,
    /// Growth sub-step.
    pub growth_seq: u32,
    /// Whether the world was quiescent.
    pub quiescent: bool,
    /// The digest.
    pub digest: Digest,
    /// The buffers' byte lengths, by id.
    pub lens: [usize; PAGED],
    /// The pages, by buffer id.
    pub pages: [Vec<StoredPage>; PAGED],
    /// The entity table's encoding.
    pub entity_table: Vec<u8>,
}

/// zstd frames of page groups, compressed once and shared by every join. A group is keyed
/// by its pages' hashes, so a frame stays valid exactly as long as its pages do.
#[derive(Debug, Default)]
pub struct PageCache {
    frames: Mutex<HashMap<u64, Arc<Vec<u8>>>>,
}

/// The cache key of a group of pages.
fn group_key(pages: &[&StoredPage]) -> u64 {
    let hashes: Vec<u8> = pages.iter().flat_map(|p| p.hash.to_le_bytes()).collect();
    naadf_world::hash::xxh3_64(&hashes)
}

impl PageCache {
    /// The zstd frames of `groups` (each compressed as one frame), compressing in parallel
    /// those not cached yet. When the cache outgrows twice the groups of a full snapshot of
    /// `view`, it starts over.
    pub fn frames(&self, groups: &[Vec<&StoredPage>], view: &SnapshotView) -> Vec<Arc<Vec<u8>>> {
        let keys: Vec<u64> = groups.iter().map(|g| group_key(g)).collect();
        let missing: Vec<(u64, &Vec<&StoredPage>)> = {
            let map = self.frames.lock().expect("page cache lock");
            keys.iter()
                .zip(groups)
                .filter(|(k, _)| !map.contains_key(k))
                .map(|(&k, g)| (k, g))
                .collect()
        };
        let made: Vec<(u64, Arc<Vec<u8>>)> = missing
            .par_iter()
            .map(|(k, g)| {
                let bytes: Vec<&[u8]> = g.iter().map(|p| &p.bytes[..]).collect();
                (*k, Arc::new(compress_pages(&bytes)))
            })
            .collect();
        let mut map = self.frames.lock().expect("page cache lock");
        let full: usize = view.pages.iter().map(|p| p.len().div_ceil(GROUP_PAGES)).sum();
        if map.len() + made.len() > 2 * full + 64 {
            map.clear();
        }
        map.extend(made.iter().cloned());
        let made: HashMap<u64, Arc<Vec<u8>>> = made.into_iter().collect();
        keys.iter()
            .map(|k| map.get(k).or_else(|| made.get(k)).expect("frame made").clone())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use naadf_world::WorldSize;
    use naadf_world::ops::{Batch, Limits};
    use naadf_world::preset::Preset;

    #[test]
    fn the_store_follows_the_world_page_for_page() {
        let source = Preset::Terrain
            .source(Some(WorldSize::new(128, 64, 128).unwrap()), 2)
            .unwrap();
        let mut w = World::build(&*source, &|_| {}).unwrap();
        let mut store = PageStore::new(&w);
        let b = Batch::parse_line(r#"{"batch":[{"op":"sphere","center":[30,30,30],"radius":9,"material":3},{"op":"define_material","id":300,"kind":"metal","albedo":[1,0.5,0.25],"roughness":0.2}]}"#).unwrap();
        w.apply(&b, &Limits::default()).unwrap();
        w.grow_until_quiescent();
        let changes = store.update(&w);
        assert!(!changes.is_empty());
        let fresh = PageStore::new(&w);
        assert_eq!(store.lens(), fresh.lens());
        for (a, b) in store.pages().iter().zip(fresh.pages().iter()) {
            assert_eq!(a.len(), b.len());
            for (p, q) in a.iter().zip(b) {
                assert_eq!((p.hash, &p.bytes[..]), (q.hash, &q.bytes[..]));
            }
        }
        assert!(store.update(&w).is_empty());
    }
}

//! Snapshots on the wire: the [`TRANSFERRED`] buffers cut into 64 KiB pages (the digest's
//! pages, docs/FORMAT.md §8), each sent as one zstd frame, and the assembly of a world from a
//! [`Header`], the buffers a client already holds, and the pages it receives.
//!
//! A client announces its cache as the page hashes of its buffers ([`cache_of`]); the
//! server sends only pages whose hash differs. The page hash is the digest contribution,
//! so after assembly the world's digest must equal the header's, which
//! [`Assembly::finish`] checks.

use crate::v1::{BufferLength, CachedBuffer, Header, Page};
use crate::{WireError, bad};
use naadf_world::digest::{BufferId, Digest, PAGE_BYTES};
use naadf_world::file::{TRANSFERRED, parts_from_buffers, section_limits};
use naadf_world::{World, WorldSize};

/// The zstd level of snapshot pages. Page groups are compressed once per content and
/// cached by the server, so a higher level than the world file's costs little.
pub const PAGE_ZSTD_LEVEL: i32 = 9;

/// The most bytes of buffers a client allocates for a snapshot unless it is told
/// otherwise (2 GiB). A header announces the buffers' lengths and the client sizes its
/// buffers to them before any page arrives; the lengths are checked against the announced
/// world size, but a few bytes of header may still announce gigabytes, so a client bounds
/// what it accepts.
pub const DEFAULT_MAX_WORLD_BYTES: u64 = 2 << 30;

/// Most pages in one `Page` message: one aligned run of 16 pages (1 MiB).
pub const GROUP_PAGES: usize = 16;

/// Compresses a group of pages (concatenated in index order) for the wire.
pub fn compress_pages(pages: &[&[u8]]) -> Vec<u8> {
    zstd::bulk::compress(&pages.concat(), PAGE_ZSTD_LEVEL).expect("zstd compresses in memory")
}

/// Splits the wanted page indices of one buffer into wire groups: runs that stay within
/// one aligned window of [`GROUP_PAGES`] pages.
pub fn group_pages(indices: &[u32]) -> Vec<Vec<u32>> {
    let mut out: Vec<Vec<u32>> = Vec::new();
    for &k in indices {
        match out.last_mut() {
            Some(g) if g[0] as usize / GROUP_PAGES == k as usize / GROUP_PAGES => g.push(k),
            _ => out.push(vec![k]),
        }
    }
    out
}

/// The position of a transferred buffer in [`TRANSFERRED`], from its wire id.
pub fn slot_of(buffer: u32) -> Result<usize, WireError> {
    TRANSFERRED
        .iter()
        .position(|&id| id as u32 == buffer)
        .ok_or_else(|| bad(format!("buffer id {buffer} is not a transferred buffer")))
}

/// The cache a client announces when it holds `world`: the page hashes of its transferred
/// buffers.
pub fn cache_of(world: &World) -> Vec<CachedBuffer> {
    TRANSFERRED
        .iter()
        .map(|&id| CachedBuffer {
            buffer: id as u32,
            page_hashes: world.page_hashes(id).to_vec(),
        })
        .collect()
}

/// The byte lengths a header announces, in [`TRANSFERRED`] order, checked against what a
/// world of the header's size can hold (so a hostile header cannot make a client allocate
/// without bound).
fn lengths(h: &Header, size: WorldSize) -> Result<[u64; 6], WireError> {
    // section_limits order: materials, models, chunks, chunk_entities, blocks, voxels, entities.
    let limits = section_limits(size.chunk_count() as u64);
    let limit_of = [limits[2], limits[3], limits[4], limits[5], limits[0], limits[1]];
    let mut out = [None; 6];
    for b in &h.buffers {
        let slot = slot_of(b.buffer)?;
        if out[slot].replace(b.bytes).is_some() {
            return Err(bad(format!("buffer {} has two lengths", b.buffer)));
        }
        if b.bytes > limit_of[slot] {
            return Err(bad(format!(
                "buffer {} of {} bytes is larger than a {size} world allows",
                b.buffer, b.bytes
            )));
        }
    }
    let mut lens = [0; 6];
    for (slot, l) in out.iter().enumerate() {
        lens[slot] = l.ok_or_else(|| {
            bad(format!(
                "header lacks the length of buffer {}",
                TRANSFERRED[slot] as u32
            ))
        })?;
    }
    Ok(lens)
}

/// The header's buffer lengths for a world whose transferred buffers have these lengths.
pub fn buffer_lengths(lens: [usize; 6]) -> Vec<BufferLength> {
    TRANSFERRED
        .iter()
        .zip(lens)
        .map(|(&id, bytes)| BufferLength {
            buffer: id as u32,
            bytes: bytes as u64,
        })
        .collect()
}

/// The world size a header announces.
pub fn header_size(h: &Header) -> Result<WorldSize, WireError> {
    match h.size.as_slice() {
        &[x, y, z] => Ok(WorldSize::new(x, y, z)?),
        s => Err(bad(format!("size needs 3 numbers, got {}", s.len()))),
    }
}

/// A snapshot being received: the client's cached buffers, resized to the header's
/// lengths, with the received pages written over them.
#[derive(Debug)]
pub struct Assembly {
    header: Header,
    size: WorldSize,
    buffers: [Vec<u8>; 6],
    received: u32,
}

impl Assembly {
    /// Starts assembling the snapshot `header` describes over `cache` (the client's copy of
    /// the transferred buffers, in [`TRANSFERRED`] order; empty vectors when it has none).
    /// A header whose buffers hold more than `max_bytes` in all is refused before anything
    /// is allocated.
    pub fn start(header: Header, cache: [Vec<u8>; 6], max_bytes: u64) -> Result<Self, WireError> {
        let size = header_size(&header)?;
        let lens = lengths(&header, size)?;
        let total = lens.iter().fold(0u64, |t, &l| t.saturating_add(l));
        if total > max_bytes {
            return Err(bad(format!(
                "the snapshot of a {size} world needs {total} bytes of buffers, more than the \
                 {max_bytes} this client accepts"
            )));
        }
        let mut buffers = cache;
        for (b, &len) in buffers.iter_mut().zip(&lens) {
            b.resize(len as usize, 0);
        }
        Ok(Self {
            header,
            size,
            buffers,
            received: 0,
        })
    }

    /// Writes one received group of pages.
    pub fn page(&mut self, p: &Page) -> Result<(), WireError> {
        if self.received >= self.header.pages {
            return Err(bad(format!(
                "more page groups than the {} announced",
                self.header.pages
            )));
        }
        let slot = slot_of(p.buffer)?;
        let buf = &mut self.buffers[slot];
        if p.indices.is_empty() || p.indices.len() > GROUP_PAGES || !p.indices.is_sorted_by(|a, b| a < b) {
            return Err(bad(format!(
                "a page group of buffer {} needs 1..={GROUP_PAGES} ascending indices",
                p.buffer
            )));
        }
        let mut ranges = Vec::with_capacity(p.indices.len());
        for &k in &p.indices {
            let start = k as usize * PAGE_BYTES;
            if start >= buf.len() {
                return Err(bad(format!(
                    "page {k} of buffer {} lies past its {} bytes",
                    p.buffer,
                    buf.len()
                )));
            }
            ranges.push(start..(start + PAGE_BYTES).min(buf.len()));
        }
        let want: usize = ranges.iter().map(|r| r.len()).sum();
        let bytes = zstd::bulk::decompress(&p.zstd, want)
            .map_err(|e| bad(format!("pages {:?} of buffer {}: {e}", p.indices, p.buffer)))?;
        if bytes.len() != want {
            return Err(bad(format!(
                "pages {:?} of buffer {} hold {} bytes, expected {want}",
                p.indices,
                p.buffer,
                bytes.len()
            )));
        }
        let mut at = 0;
        for r in ranges {
            let n = r.len();
            buf[r].copy_from_slice(&bytes[at..at + n]);
            at += n;
        }
        self.received += 1;
        Ok(())
    }

    /// Whether every announced page has arrived.
    pub fn is_complete(&self) -> bool {
        self.received == self.header.pages
    }

    /// The header being assembled.
    pub fn header(&self) -> &Header {
        &self.header
    }

    /// Builds and validates the world, and checks its digest against the header's.
    pub fn finish(self) -> Result<World, WireError> {
        if !self.is_complete() {
            return Err(bad(format!(
                "snapshot ended after {} of {} pages",
                self.received, self.header.pages
            )));
        }
        let [a, b, c, d, e, f] = &self.buffers;
        let parts = parts_from_buffers(
            self.size,
            self.header.version,
            [a, b, c, d, e, f],
            &self.header.entity_table,
        )?;
        let world = World::from_parts(parts)?;
        let want = Digest(self.header.digest);
        if world.digest() != want {
            return Err(bad(format!(
                "snapshot digest {} does not match the header's {want}",
                world.digest()
            )));
        }
        Ok(world)
    }
}

/// The transferred buffers of `world`, copied (a client's cache for [`Assembly::start`]).
pub fn buffers_of(world: &World) -> [Vec<u8>; 6] {
    TRANSFERRED.map(|id: BufferId| world.buffer_bytes(id).into_owned())
}

/// The header of a quiescent snapshot of all of `world` sent as `pages` page groups: what
/// a server sends first to a client without a cache (tests and fuzz seeds build streams
/// with it).
pub fn header_for(world: &World, pages: u32) -> Header {
    Header {
        protocol_version: crate::PROTOCOL_VERSION,
        size: world.size().voxels().to_vec(),
        version: world.version(),
        growth_seq: 0,
        quiescent: true,
        digest: world.digest().0,
        buffers: buffer_lengths(TRANSFERRED.map(|id| world.buffer_bytes(id).len())),
        entity_table: world.entity_table().encode(),
        pages,
        resync: false,
        resume: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use naadf_world::preset::Preset;

    fn world() -> World {
        let size = WorldSize::new(128, 64, 128).unwrap();
        let source = Preset::Terrain.source(Some(size), 3).unwrap();
        World::build(&*source, &|_| {}).unwrap()
    }

    /// Every page of `world` that differs from `cache` (hash by hash), grouped as the
    /// server sends them.
    fn pages_for(world: &World, cache: &[CachedBuffer]) -> Vec<Page> {
        let mut out = Vec::new();
        for &id in &TRANSFERRED {
            let bytes = world.buffer_bytes(id);
            let have = cache
                .iter()
                .find(|c| c.buffer == id as u32)
                .map_or(&[][..], |c| &c.page_hashes[..]);
            let wanted: Vec<u32> = (0..world.page_hashes(id).len())
                .filter(|&k| have.get(k) != Some(&world.page_hashes(id)[k]))
                .map(|k| k as u32)
                .collect();
            for g in group_pages(&wanted) {
                let pages: Vec<&[u8]> = g
                    .iter()
                    .map(|&k| {
                        let k = k as usize;
                        &bytes[k * PAGE_BYTES..((k + 1) * PAGE_BYTES).min(bytes.len())]
                    })
                    .collect();
                out.push(Page {
                    buffer: id as u32,
                    indices: g,
                    zstd: compress_pages(&pages),
                });
            }
        }
        out
    }

    #[test]
    fn a_snapshot_rebuilds_the_world_and_a_cache_skips_equal_pages() {
        let w = world();
        let pages = pages_for(&w, &[]);
        let mut a = Assembly::start(
            header_for(&w, pages.len() as u32),
            Default::default(),
            DEFAULT_MAX_WORLD_BYTES,
        )
        .unwrap();
        for p in &pages {
            a.page(p).unwrap();
        }
        let got = a.finish().unwrap();
        assert_eq!(got.digest(), w.digest());
        assert_eq!(got.blocks(), w.blocks());

        // Edit, then resend against the old world's cache: only changed pages travel.
        let mut w2 = w.clone();
        let b = naadf_world::ops::Batch::parse_line(r#"{"op":"sphere","center":[60,40,60],"radius":6,"material":2}"#)
            .unwrap();
        w2.apply(&b, &Default::default()).unwrap();
        w2.grow_until_quiescent();
        let delta = pages_for(&w2, &cache_of(&got));
        assert!(
            !delta.is_empty() && delta.len() < pages.len(),
            "{} of {}",
            delta.len(),
            pages.len()
        );
        let mut a = Assembly::start(
            header_for(&w2, delta.len() as u32),
            buffers_of(&got),
            DEFAULT_MAX_WORLD_BYTES,
        )
        .unwrap();
        for p in &delta {
            a.page(p).unwrap();
        }
        assert_eq!(a.finish().unwrap().digest(), w2.digest());
    }

    #[test]
    fn a_header_over_the_budget_is_refused_before_allocating() {
        // The world's own buffers: accepted at exactly their size, refused one byte below.
        let w = world();
        let need: u64 = TRANSFERRED.iter().map(|&id| w.buffer_bytes(id).len() as u64).sum();
        assert!(Assembly::start(header_for(&w, 1), Default::default(), need).is_ok());
        let e = Assembly::start(header_for(&w, 1), Default::default(), need - 1).unwrap_err();
        assert!(e.to_string().contains("bytes of buffers"), "{e}");
        // A 70-byte header announcing the largest world with 1 GiB in each of its four
        // cell buffers and 1 KiB of blocks: within what such a world may hold, but past the
        // default budget, so nothing is allocated.
        let mut h = header_for(&w, 1);
        h.size = vec![16384, 4096, 16384];
        h.buffers = buffer_lengths([1 << 30, 1 << 30, 1 << 30, 1 << 30, 1024, 0]);
        assert!(prost::Message::encoded_len(&h) < 100);
        let e = Assembly::start(h, Default::default(), DEFAULT_MAX_WORLD_BYTES).unwrap_err();
        assert!(
            e.to_string().contains("more than the 2147483648 this client accepts"),
            "{e}"
        );
    }

    #[test]
    fn groups_stay_in_aligned_windows() {
        assert_eq!(
            group_pages(&[0, 1, 15, 16, 40, 47, 48]),
            vec![vec![0, 1, 15], vec![16], vec![40, 47], vec![48]]
        );
        assert!(group_pages(&[]).is_empty());
    }

    #[test]
    fn bad_snapshots_are_errors() {
        let w = world();
        let pages = pages_for(&w, &[]);
        // Missing a page.
        let mut a = Assembly::start(
            header_for(&w, pages.len() as u32),
            Default::default(),
            DEFAULT_MAX_WORLD_BYTES,
        )
        .unwrap();
        for p in &pages[1..] {
            a.page(p).unwrap();
        }
        assert!(a.finish().unwrap_err().to_string().contains("pages"));
        // A page with the wrong content: the digest check catches it.
        let mut a = Assembly::start(
            header_for(&w, pages.len() as u32),
            Default::default(),
            DEFAULT_MAX_WORLD_BYTES,
        )
        .unwrap();
        for (i, p) in pages.iter().enumerate() {
            let mut p = p.clone();
            if i == 0 {
                let mut raw = zstd::bulk::decompress(&p.zstd, 1 << 24).unwrap();
                raw[5] ^= 1;
                p.zstd = compress_pages(&[&raw]);
            }
            a.page(&p).unwrap();
        }
        assert!(a.finish().is_err());
        // Hostile headers and pages.
        let mut h = header_for(&w, 1);
        h.buffers[3].bytes = u64::MAX;
        assert!(Assembly::start(h, Default::default(), DEFAULT_MAX_WORLD_BYTES).is_err());
        let mut h = header_for(&w, 1);
        h.size = vec![64, 64];
        assert!(Assembly::start(h, Default::default(), DEFAULT_MAX_WORLD_BYTES).is_err());
        let mut a = Assembly::start(header_for(&w, 1), Default::default(), DEFAULT_MAX_WORLD_BYTES).unwrap();
        let junk = Page {
            buffer: 2,
            indices: vec![0],
            zstd: vec![1, 2, 3],
        };
        assert!(a.page(&junk).is_err());
        let past = Page {
            buffer: 0,
            indices: vec![1 << 20],
            zstd: compress_pages(&[&[0; 4]]),
        };
        assert!(a.page(&past).is_err());
        let unsorted = Page {
            buffer: 2,
            indices: vec![1, 0],
            zstd: compress_pages(&[&[0; 4]]),
        };
        assert!(a.page(&unsorted).is_err());
    }
}

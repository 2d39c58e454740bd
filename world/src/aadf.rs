//! Axis-aligned distance fields (docs/NAADF.md §6–§7, docs/FORMAT.md §5.6).
//!
//! Every empty cell stores, per direction (−x, +x, −y, +y, −z, +z), how many further cells
//! of its level are empty in a box around it. All levels grow their fields in **lock
//! step**: level `k` (0-based), then axis x, y, z; a field grows by one only while it equals
//! `k`, and only if the neighbour on that side is empty and its box is at least as large on
//! the five other fields (the *merge test*). The neighbour's box then covers the new slab,
//! so every box stays empty. Each (level, axis) phase reads the state from before the phase
//! (double buffering), which makes the result deterministic.
//!
//! - voxel and block AADFs: 4³ cells, fields 0..=3, the box never leaves the parent
//!   ([`cell_aadf4`], a bit-sliced implementation of [`grid_aadf`]);
//! - chunk AADFs: the whole chunk grid, fields 0..=31, outside the world counts as empty,
//!   ([`build_chunk_aadf`]).
//! - regrowth after edits: the region a change may affect ([`REGROW_RADIUS`]), the resumable
//!   job that recomputes it ([`GrowthJob`]), and the world's background-growth bookkeeping
//!   and detached task ([`GrowthTask`]), which `World::start_growth` and
//!   `World::finish_growth` (in `edit/`) drive.

use crate::cell::{self, Aadf, CHUNK_FIELD_BITS, MAX_CHUNK_FIELD, State};
use crate::size::WorldSize;
use rayon::prelude::*;

/// What lies next to a cell in the direction it wants to grow.
#[derive(Clone, Copy, Debug)]
pub enum Neighbour {
    /// Outside the grid. Chunk grids treat this as empty; 4³ cells and entity grids as a wall.
    Outside,
    /// A cell that is not empty.
    Blocked,
    /// An empty cell with its current fields.
    Free(Aadf),
}

/// Whether an empty cell with fields `cur` may grow field `dir` (0..6) at `level`.
///
/// ```
/// use naadf_world::aadf::{may_grow, Neighbour};
/// use naadf_world::cell::Aadf;
/// let cur = Aadf([0, 0, 1, 1, 0, 0]);
/// assert!(may_grow(&cur, Neighbour::Free(Aadf([0, 0, 1, 1, 0, 0])), 1, 0, false));
/// assert!(!may_grow(&cur, Neighbour::Free(Aadf([0, 0, 0, 1, 0, 0])), 1, 0, false));
/// ```
#[inline]
pub fn may_grow(cur: &Aadf, neighbour: Neighbour, dir: usize, level: u8, outside_empty: bool) -> bool {
    if cur.0[dir] != level {
        return false;
    }
    match neighbour {
        Neighbour::Outside => outside_empty,
        Neighbour::Blocked => false,
        Neighbour::Free(n) => (0..6).all(|k| k == (dir ^ 1) || n.0[k] >= cur.0[k]),
    }
}

/// Lock-step AADF of a dense grid (x fastest), `levels` levels, walls outside unless
/// `outside_empty`. Non-empty cells get all-zero fields. This is the plain reference
/// implementation; the fast paths below must equal it.
pub fn grid_aadf(dims: [usize; 3], empty: &[bool], levels: u8, outside_empty: bool) -> Vec<Aadf> {
    let n = dims[0] * dims[1] * dims[2];
    assert_eq!(empty.len(), n, "grid_aadf: {} flags for {dims:?}", empty.len());
    let stride = [1, dims[0], dims[0] * dims[1]];
    let mut fields = vec![Aadf::default(); n];
    for level in 0..levels {
        let mut grew = false;
        for axis in 0..3 {
            let old = fields.clone();
            for i in (0..n).filter(|&i| empty[i]) {
                let p = (i / stride[axis]) % dims[axis];
                for side in 0..2 {
                    let dir = 2 * axis + side;
                    let neighbour = match (side, p) {
                        (0, 0) => Neighbour::Outside,
                        (1, p) if p + 1 == dims[axis] => Neighbour::Outside,
                        _ => {
                            let j = if side == 0 { i - stride[axis] } else { i + stride[axis] };
                            if empty[j] {
                                Neighbour::Free(old[j])
                            } else {
                                Neighbour::Blocked
                            }
                        }
                    };
                    if may_grow(&old[i], neighbour, dir, level, outside_empty) {
                        fields[i].0[dir] += 1;
                        grew = true;
                    }
                }
            }
        }
        if !grew {
            break;
        }
    }
    fields
}

/// Cells whose neighbour on side `dir` lies inside the 4³ array.
const fn inner_mask(dir: usize) -> u64 {
    let mut m = 0u64;
    let mut i = 0;
    while i < 64 {
        let p = [i % 4, (i / 4) % 4, i / 16];
        let c = p[dir / 2];
        let ok = if dir.is_multiple_of(2) { c > 0 } else { c < 3 };
        if ok {
            m |= 1 << i;
        }
        i += 1;
    }
    m
}

const INNER: [u64; 6] = [
    inner_mask(0),
    inner_mask(1),
    inner_mask(2),
    inner_mask(3),
    inner_mask(4),
    inner_mask(5),
];
const STRIDE4: [u32; 3] = [1, 4, 16];

/// Moves each cell's bit to the cell that has it as its `dir` neighbour: bit `i` of the
/// result is bit `i ± stride` of `v` (zero where that neighbour is outside).
#[inline]
fn neighbour_bits(v: u64, dir: usize) -> u64 {
    let s = STRIDE4[dir / 2];
    let moved = if dir.is_multiple_of(2) { v << s } else { v >> s };
    moved & INNER[dir]
}

/// Voxel- or block-level AADFs of a 4³ cell array, given the bitmask of its empty cells
/// (bit `x + 4y + 16z`). Returns each cell's six 2-bit fields packed into 12 bits (0 for
/// non-empty cells). Equal to `grid_aadf([4; 3], .., 3, false)`, computed bit-sliced: two
/// bit planes per field, 64 cells per machine word.
pub fn cell_aadf4(empty: u64) -> [u16; 64] {
    // lo[f] / hi[f]: bit planes of field f's 2-bit value.
    let mut lo = [0u64; 6];
    let mut hi = [0u64; 6];
    for level in 0..3u8 {
        let mut grew = 0u64;
        for axis in 0..3 {
            let (olo, ohi) = (lo, hi);
            for side in 0..2 {
                let dir = 2 * axis + side;
                let l0 = if level & 1 != 0 { !0 } else { 0 };
                let l1 = if level & 2 != 0 { !0 } else { 0 };
                let at_level = !(olo[dir] ^ l0) & !(ohi[dir] ^ l1);
                let mut grow = empty & at_level & neighbour_bits(empty, dir);
                for k in (0..6).filter(|&k| k != dir ^ 1) {
                    let (a0, a1) = (neighbour_bits(olo[k], dir), neighbour_bits(ohi[k], dir));
                    let (b0, b1) = (olo[k], ohi[k]);
                    grow &= (a1 & !b1) | (!(a1 ^ b1) & (a0 | !b0));
                }
                let next = level + 1;
                let n0 = if next & 1 != 0 { grow } else { 0 };
                let n1 = if next & 2 != 0 { grow } else { 0 };
                lo[dir] = (lo[dir] & !grow) | n0;
                hi[dir] = (hi[dir] & !grow) | n1;
                grew |= grow;
            }
        }
        if grew == 0 {
            break;
        }
    }
    let mut out = [0u16; 64];
    if empty == 0 {
        return out;
    }
    for (i, o) in out.iter_mut().enumerate() {
        let mut w = 0u16;
        for f in 0..6 {
            let v = ((lo[f] >> i) & 1) | (((hi[f] >> i) & 1) << 1);
            w |= (v as u16) << (2 * f);
        }
        *o = w;
    }
    out
}

/// Whether a chunk may carry (and grow into) a chunk AADF: empty. (Entities do not count:
/// they live outside the static world.)
#[inline]
pub fn chunk_is_free(cell: u32) -> bool {
    cell::state(cell) == State::Empty
}

/// Builds all chunk AADFs from scratch, level-major (31 levels × 3 axes), treating the
/// outside of the world as empty. Deterministic: each phase reads the state before the
/// phase, whatever the thread count.
pub fn build_chunk_aadf(size: WorldSize, chunks: &mut Vec<u32>) {
    let n = size.chunk_count();
    assert!(chunks.len() == n, "chunk buffers do not match {size}");
    let region: Vec<u32> = (0..n as u32).filter(|&i| chunk_is_free(chunks[i as usize])).collect();
    let mut job = GrowthJob::new(std::mem::take(chunks), region);
    while !job.step(size) {}
    *chunks = job.into_shadow();
}

/// Chunks around a change whose converged AADF may differ: a lock-step field depends on
/// chunks at most 31 levels plus one neighbour away; two more for margin.
pub const REGROW_RADIUS: u32 = MAX_CHUNK_FIELD as u32 + 3;

/// Chebyshev distance (in chunks) from each chunk to the nearest seed, for the chunks
/// within `reach` of one; `u8::MAX` for the others.
///
/// A breadth-first search over the 26 neighbours: a king's-move step changes each
/// coordinate by at most one, so the search's depth is exactly the Chebyshev distance. It
/// visits only the chunks within `reach`, each once, whatever the number of seeds.
fn seed_distance(size: WorldSize, seeds: &[u32], reach: u8) -> Vec<u8> {
    let d = size.chunks().map(i64::from);
    let mut dist = vec![u8::MAX; size.chunk_count()];
    let mut frontier: Vec<u32> = Vec::new();
    for &s in seeds {
        if std::mem::replace(&mut dist[s as usize], 0) != 0 {
            frontier.push(s);
        }
    }
    for depth in 1..=reach {
        let mut next = Vec::new();
        for &i in &frontier {
            let p = size.chunk_coords(i as usize).map(i64::from);
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let q = [p[0] + dx, p[1] + dy, p[2] + dz];
                        if (0..3).any(|a| q[a] < 0 || q[a] >= d[a]) {
                            continue;
                        }
                        let j = size.chunk_index(q.map(|v| v as u32));
                        if dist[j] == u8::MAX {
                            dist[j] = depth;
                            next.push(j as u32);
                        }
                    }
                }
            }
        }
        frontier = next;
    }
    dist
}

/// A resumable from-scratch recomputation of the chunk AADFs of a region.
///
/// The job works on a shadow copy of the chunk cells: the free chunks of the region start
/// at zero and grow in lock step, while every chunk outside the region keeps its current
/// value. For a chunk outside the region whose value is final, comparing against that final
/// value at level `k` is the same as comparing against its level-`k` value (a lock-step
/// field is `min(final, k)` after `k` levels, and the merge test only asks `≥ cur ≤ k`), so
/// the region converges to exactly what a build of the whole world would give — provided
/// the region holds every chunk whose final field may have changed.
#[derive(Clone, Debug)]
pub struct GrowthJob {
    shadow: Vec<u32>,
    region: Vec<u32>,
    active: Vec<u32>,
    grown: Vec<u32>,
    level: u8,
    axis: usize,
    /// Chunks that join the lock step only at a later level (a warm start), by level.
    entering: Vec<Vec<u32>>,
}

impl GrowthJob {
    /// Starts a job recomputing the free chunks within [`REGROW_RADIUS`] of
    /// `seeds`, on `chunks` (a copy of the cells).
    ///
    /// Warm start: a change influences the lock step one chunk per level, so a chunk at
    /// Chebyshev distance `d` from every seed has, up to level `d − 2`, the same history as
    /// before the change. Its field starts at `min(current, d − 2)` per direction and it
    /// joins the lock step at level `d − 2`; directions below that are already final. Only
    /// the work near the seeds remains, and the result is still a from-scratch build. A
    /// chunk whose cell is zero (reset by a clamp, or genuinely boxed in) starts cold.
    pub fn around(size: WorldSize, seeds: &[u32], chunks: Vec<u32>) -> Self {
        // The region: the free chunks within REGROW_RADIUS of a seed, ascending.
        let distance = seed_distance(size, seeds, REGROW_RADIUS as u8);
        let region: Vec<u32> = (0..size.chunk_count() as u32)
            .filter(|&i| distance[i as usize] <= REGROW_RADIUS as u8 && chunk_is_free(chunks[i as usize]))
            .collect();
        let mut shadow = chunks;
        let mut entering: Vec<Vec<u32>> = vec![Vec::new(); usize::from(MAX_CHUNK_FIELD) + 1];
        let mut active = Vec::new();
        for &i in &region {
            let c = shadow[i as usize];
            let start = if c == 0 {
                0
            } else {
                distance[i as usize].saturating_sub(2)
            };
            let start = start.min(MAX_CHUNK_FIELD);
            let mut f = Aadf::unpack(c, CHUNK_FIELD_BITS);
            for v in &mut f.0 {
                *v = (*v).min(start);
            }
            shadow[i as usize] = f.pack(CHUNK_FIELD_BITS);
            if start == 0 {
                active.push(i);
            } else {
                entering[usize::from(start)].push(i);
            }
        }
        GrowthJob {
            shadow,
            active,
            region,
            grown: Vec::new(),
            level: 0,
            axis: 0,
            entering,
        }
    }

    /// Starts a job on a copy of the chunk cells; `region` lists the chunks to recompute
    /// (free chunks, ascending).
    pub fn new(mut shadow: Vec<u32>, region: Vec<u32>) -> Self {
        for &i in &region {
            shadow[i as usize] = 0;
        }
        GrowthJob {
            shadow,
            active: region.clone(),
            region,
            grown: Vec::new(),
            entering: Vec::new(),
            level: 0,
            axis: 0,
        }
    }

    /// Runs one (level, axis) phase; returns whether the job has converged.
    pub fn step(&mut self, size: WorldSize) -> bool {
        if self.is_done() {
            return true;
        }
        let grown = grow_chunks(size, &self.shadow, &self.active, self.level, self.axis);
        self.grown.extend(grown.iter().map(|&(i, _)| i));
        for (i, w) in grown {
            self.shadow[i as usize] = w;
        }
        self.axis += 1;
        if self.axis == 3 {
            self.axis = 0;
            self.level += 1;
            // Only fields that grew at this level can equal the next one, and the chunks
            // of a warm start that join at the next level.
            self.active = std::mem::take(&mut self.grown);
            if let Some(joining) = self.entering.get_mut(usize::from(self.level)) {
                self.active.append(joining);
            }
            // Four ascending runs (one per axis, and the joining chunks): the stable sort
            // finds and merges runs, where an unstable sort would start from scratch.
            self.active.sort();
            self.active.dedup();
        }
        self.is_done()
    }

    /// Whether no field can grow any more.
    pub fn is_done(&self) -> bool {
        let waiting = self
            .entering
            .iter()
            .skip(usize::from(self.level) + 1)
            .any(|e| !e.is_empty());
        (self.active.is_empty() && !waiting) || self.level >= MAX_CHUNK_FIELD
    }

    /// The recomputed chunks, ascending.
    pub fn region(&self) -> &[u32] {
        &self.region
    }

    /// The shadow value of chunk `i`.
    pub fn value(&self, i: u32) -> u32 {
        self.shadow[i as usize]
    }

    /// The shadow copy of the chunk cells.
    pub fn into_shadow(self) -> Vec<u32> {
        self.shadow
    }
}

/// One (level, axis) phase over the `active` chunks: the new words of the chunks that grow.
fn grow_chunks(size: WorldSize, chunks: &[u32], active: &[u32], level: u8, axis: usize) -> Vec<(u32, u32)> {
    let dims = size.chunks();
    active
        .par_iter()
        .with_min_len(1024)
        .filter_map(|&i| {
            let w = chunks[i as usize];
            let cur = Aadf::unpack(w, CHUNK_FIELD_BITS);
            let mut next = cur;
            let p = size.chunk_coords(i as usize);
            for side in 0..2 {
                let dir = 2 * axis + side;
                if cur.0[dir] != level {
                    continue;
                }
                let mut q = p;
                let inside = if side == 0 {
                    q[axis] = q[axis].wrapping_sub(1);
                    p[axis] > 0
                } else {
                    q[axis] += 1;
                    q[axis] < dims[axis]
                };
                let neighbour = if !inside {
                    Neighbour::Outside
                } else {
                    let j = size.chunk_index(q);
                    if chunk_is_free(chunks[j]) {
                        Neighbour::Free(Aadf::unpack(chunks[j], CHUNK_FIELD_BITS))
                    } else {
                        Neighbour::Blocked
                    }
                };
                if may_grow(&cur, neighbour, dir, level, true) {
                    next.0[dir] += 1;
                }
            }
            (next != cur).then(|| (i, next.pack(CHUNK_FIELD_BITS)))
        })
        .collect()
}

/// Background chunk-AADF growth: the chunks whose freedom changed since the world last
/// converged, and the job recomputing the region around them.
///
/// Edits never restart a running job (under a steady stream of edits a restarted job would
/// never finish). A job works on the chunk cells as they were when it started; chunks
/// whose freedom flips meanwhile become the seeds of the next job, and those that stopped
/// being free are clamped out of the job's fields when it publishes, so every published
/// state is safe and the fields still converge to a from-scratch build.
#[derive(Clone, Debug, Default)]
pub(crate) struct Growth {
    /// Seeds of the running job (or of the next one, when none runs).
    pub(crate) seeds: Vec<u32>,
    /// The running (or attached, paused) job.
    pub(crate) job: Option<GrowthJob>,
    /// The growth sub-step of the world's version: how many growth results were published.
    pub(crate) seq: u32,
    /// Chunks whose freedom flipped while the job ran: the next job's seeds.
    pub(crate) pending: Vec<u32>,
    /// Chunks that stopped being free while the job ran.
    pub(crate) blocked: Vec<usize>,
    /// Whether the job runs outside the world, as a [`GrowthTask`].
    pub(crate) detached: bool,
}

/// Growth work taken out of a world by [`crate::World::start_growth`]: it owns a copy of what it
/// reads, so it can run on another thread while the world keeps applying edits.
#[derive(Debug)]
pub struct GrowthTask {
    /// The world's size.
    pub(crate) size: WorldSize,
    /// The chunks whose freedom changed: the job's region is around them.
    pub(crate) seeds: Vec<u32>,
    /// A copy of the chunk cells as the job started.
    pub(crate) chunks: Vec<u32>,
    /// The job, once its region is known.
    pub(crate) job: Option<GrowthJob>,
}

impl GrowthTask {
    /// Runs the job to convergence (finding its region first: that, too, is work the
    /// world's owner should not wait for).
    pub fn run(&mut self) {
        self.run_until(|| false);
    }

    /// Runs the job until it converges or `stop()` says so, asked between (level, axis)
    /// phases, each a few milliseconds at most; returns whether it converged. A stopped
    /// task resumes where it stopped, on any thread ([`GrowthTask::run`],
    /// [`crate::World::finish_growth`]).
    pub fn run_until(&mut self, stop: impl Fn() -> bool) -> bool {
        let job = self
            .job
            .get_or_insert_with(|| GrowthJob::around(self.size, &self.seeds, std::mem::take(&mut self.chunks)));
        while !job.is_done() {
            if stop() {
                return false;
            }
            job.step(self.size);
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn mask_to_flags(m: u64) -> Vec<bool> {
        (0..64).map(|i| m >> i & 1 == 1).collect()
    }

    #[test]
    fn all_empty_4cube_reaches_walls() {
        let f = cell_aadf4(!0);
        // Cell (0,0,0): nothing on the − sides, 3 on the + sides.
        assert_eq!(Aadf::unpack(u32::from(f[0]), 2), Aadf([0, 3, 0, 3, 0, 3]));
        let c = cell::index4(1, 2, 3);
        assert_eq!(Aadf::unpack(u32::from(f[c]), 2), Aadf([1, 2, 2, 1, 3, 0]));
    }

    proptest! {
        #[test]
        fn bitsliced_equals_reference(mask in any::<u64>(), sparse in any::<u64>()) {
            for m in [mask, mask | sparse, mask & sparse] {
                let fast = cell_aadf4(m);
                let slow = grid_aadf([4, 4, 4], &mask_to_flags(m), 3, false);
                for i in 0..64 {
                    prop_assert_eq!(u32::from(fast[i]), slow[i].pack(2), "cell {} of mask {:#x}", i, m);
                }
            }
        }

        #[test]
        fn grid_boxes_are_empty(dims in prop::array::uniform3(1usize..7), seed in any::<u64>(), outside in any::<bool>()) {
            let n = dims[0] * dims[1] * dims[2];
            let empty: Vec<bool> = (0..n).map(|i| !(seed.rotate_left(i as u32 * 7) ^ (i as u64 * 0x9E37)).is_multiple_of(5)).collect();
            let f = grid_aadf(dims, &empty, 31, outside);
            for i in 0..n {
                let p = [i % dims[0], (i / dims[0]) % dims[1], i / (dims[0] * dims[1])];
                if !empty[i] {
                    prop_assert_eq!(f[i], Aadf::default());
                    continue;
                }
                let lo: Vec<i64> = (0..3).map(|a| p[a] as i64 - i64::from(f[i].0[2 * a])).collect();
                let hi: Vec<i64> = (0..3).map(|a| p[a] as i64 + i64::from(f[i].0[2 * a + 1])).collect();
                for (j, &free) in empty.iter().enumerate() {
                    let q = [j % dims[0], (j / dims[0]) % dims[1], j / (dims[0] * dims[1])];
                    let inside = (0..3).all(|a| (lo[a]..=hi[a]).contains(&(q[a] as i64)));
                    prop_assert!(!inside || free, "cell {:?} box contains solid {:?}", p, q);
                }
                if !outside {
                    prop_assert!((0..3).all(|a| lo[a] >= 0 && hi[a] < dims[a] as i64));
                }
            }
        }
    }

    proptest! {
        #[test]
        fn seed_distance_is_chebyshev(dims in prop::array::uniform3(1u32..4), picks in prop::collection::vec(any::<u32>(), 0..5), reach in 0u8..8) {
            let size = WorldSize::new(64 * dims[0], 64 * dims[1], 64 * dims[2]).unwrap();
            let n = size.chunk_count() as u32;
            let seeds: Vec<u32> = picks.iter().map(|p| p % n).collect();
            let dist = seed_distance(size, &seeds, reach);
            for i in 0..n {
                let p = size.chunk_coords(i as usize);
                // The oracle: the nearest seed by brute force.
                let nearest = seeds
                    .iter()
                    .map(|&s| {
                        let q = size.chunk_coords(s as usize);
                        (0..3).map(|a| p[a].abs_diff(q[a])).max().unwrap()
                    })
                    .min();
                let want = match nearest {
                    Some(d) if d <= u32::from(reach) => d as u8,
                    _ => u8::MAX,
                };
                prop_assert_eq!(dist[i as usize], want, "chunk {:?}", p);
            }
        }
    }

    #[test]
    fn chunk_build_equals_grid_reference() {
        let size = WorldSize::new(128, 64, 192).unwrap();
        let n = size.chunk_count();
        let mut chunks: Vec<u32> = (0..n)
            .map(|i| if (i * 2654435761) % 11 == 0 { cell::full(1) } else { 0 })
            .collect();
        build_chunk_aadf(size, &mut chunks);
        let free: Vec<bool> = (0..n).map(|i| chunk_is_free(chunks[i])).collect();
        let d = size.chunks().map(|v| v as usize);
        let expect = grid_aadf(d, &free, 31, true);
        for i in 0..n {
            if free[i] {
                assert_eq!(chunks[i], expect[i].pack(CHUNK_FIELD_BITS), "chunk {i}");
            }
        }
    }
}

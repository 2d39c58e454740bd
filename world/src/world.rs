//! The [`World`]: the mirrored buffers plus the bookkeeping that keeps them canonical.

use crate::aadf::Growth;
use crate::aadf::{self, build_chunk_aadf, cell_aadf4, chunk_is_free};
use crate::build::{self, ChunkPlan, ChunkSource, group_words};
use crate::cell::{self, Aadf, CHUNK_FIELD_BITS, CHUNK_VOXELS, GROUP_WORDS, State};
use crate::dedup::GroupStore;
use crate::digest::{BufferId, Digest, PagedDigest};
use crate::entity::{Entities, EntityTable, Pose};
use crate::error::WorldError;
use crate::material::MaterialTable;
use crate::model::ModelTable;
use crate::prefix::PrefixSum3;
use crate::size::WorldSize;
use rayon::prelude::*;
use std::collections::BTreeSet;
use std::io::Write;

/// Block cells per chunk (one block array).
const BLOCK_ARRAY: usize = 64;

/// A NAADF world: the GPU-mirrored buffers (docs/FORMAT.md §5) and the tables that travel with them.
///
/// Invariants, checked on load and kept by every mutation:
/// - canonical form: no mixed cell whose children are all one uniform value, no full cell
///   of material 0, every material defined;
/// - every live voxel group is referenced by the blocks that the dedup map counts, and
///   free slots (block arrays and voxel groups) are all zero;
/// - voxel and block AADFs are exactly the lock-step fields of their content;
/// - every empty chunk's AADF box contains only empty chunks without entities.
#[derive(Clone)]
pub struct World {
    pub(crate) size: WorldSize,
    pub(crate) version: u64,
    pub(crate) materials: MaterialTable,
    pub(crate) models: ModelTable,
    pub(crate) chunks: Vec<u32>,
    pub(crate) chunk_entities: Vec<u32>,
    pub(crate) blocks: Vec<u32>,
    pub(crate) voxels: Vec<u32>,
    pub(crate) groups: GroupStore,
    pub(crate) free_block_arrays: BTreeSet<u32>,
    /// Entity table, types and instance buffer ([`crate::entity`]).
    pub(crate) entities: Entities,
    /// Page hashes of every buffer, updated with each change.
    pub(crate) digest: PagedDigest,
    /// Background chunk-AADF growth: queued work and the job in progress.
    pub(crate) growth: Growth,
}

impl std::fmt::Debug for World {
    /// A summary (size, version, digest): the buffers are too large to print.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("World")
            .field("size", &self.size)
            .field("version", &self.version)
            .field("digest", &self.digest())
            .finish_non_exhaustive()
    }
}

/// The raw contents of a world, as stored in a world file.
#[derive(Clone, Debug, PartialEq)]
pub struct WorldParts {
    /// World size.
    pub size: WorldSize,
    /// Number of edit batches applied.
    pub version: u64,
    /// Material table.
    pub materials: MaterialTable,
    /// Model table.
    pub models: ModelTable,
    /// Chunk cells.
    pub chunks: Vec<u32>,
    /// Per-chunk entity fields `(pointer << 8) | count`.
    pub chunk_entities: Vec<u32>,
    /// Block cells.
    pub blocks: Vec<u32>,
    /// Voxel words.
    pub voxels: Vec<u32>,
    /// Entity types and instances (the entity buffers are derived from them).
    pub entities: EntityTable,
}

impl World {
    /// Builds a world from a chunk source: construction, voxel/block AADFs, then the full
    /// chunk-AADF build. `progress` receives the number of chunks done so far.
    pub fn build(source: &dyn ChunkSource, progress: &(dyn Fn(u64) + Sync)) -> Result<Self, WorldError> {
        let size = source.size();
        let n = size.chunk_count();
        let mut w = World {
            size,
            version: 0,
            materials: source.materials(),
            models: source.models(),
            chunks: vec![0; n],
            chunk_entities: vec![0; n],
            blocks: Vec::new(),
            voxels: Vec::new(),
            groups: GroupStore::default(),
            free_block_arrays: BTreeSet::new(),
            entities: Entities::default(),
            digest: PagedDigest::default(),
            growth: Growth::default(),
        };
        build::plan_all(source, progress, |i, plan| w.place_chunk(i, plan))?;
        w.reserve_headroom();
        w.rebuild_chunk_aadf();
        Ok(w)
    }

    /// Writes a planned chunk into the buffers, allocating its block array and groups.
    fn place_chunk(&mut self, i: usize, plan: ChunkPlan) -> Result<(), WorldError> {
        match plan {
            ChunkPlan::Uniform(m) => self.chunks[i] = cell::uniform(m),
            ChunkPlan::Mixed { mut blocks, groups, .. } => {
                for g in &groups {
                    let ptr = self.groups.acquire(&mut self.voxels, g.hash, &g.words)?;
                    blocks[usize::from(g.block)] = cell::mixed(ptr);
                }
                let ptr = self.alloc_block_array()?;
                self.blocks[ptr as usize..][..BLOCK_ARRAY].copy_from_slice(&blocks[..]);
                self.chunks[i] = cell::mixed(ptr);
            }
        }
        Ok(())
    }

    /// The lowest free block array, else a new one at the end.
    pub(crate) fn alloc_block_array(&mut self) -> Result<u32, WorldError> {
        if let Some(p) = self.free_block_arrays.pop_first() {
            return Ok(p);
        }
        let p = self.blocks.len();
        if p + BLOCK_ARRAY > cell::PAYLOAD as usize {
            return Err(WorldError::Capacity(
                "more block arrays than 30-bit pointers can address".into(),
            ));
        }
        self.blocks.resize(p + BLOCK_ARRAY, 0);
        Ok(p as u32)
    }

    /// Recomputes every chunk AADF from scratch (level-major, deterministic), dropping any
    /// queued background growth, and refreshes the digest.
    pub fn rebuild_chunk_aadf(&mut self) {
        build_chunk_aadf(self.size, &mut self.chunks);
        self.growth = Growth::default();
        self.refresh_digest();
    }

    /// Recomputes every page hash from scratch.
    pub(crate) fn refresh_digest(&mut self) {
        let mut digest = PagedDigest::default();
        for id in BufferId::WORLD {
            let bytes = self.buffer_bytes(id);
            digest.update(id, &bytes, 0..bytes.len());
        }
        self.digest = digest;
    }

    /// Records that the byte `ranges` of buffer `id` changed, or that its length did.
    pub(crate) fn touch_digest(&mut self, id: BufferId, ranges: &[std::ops::Range<usize>]) {
        let mut digest = std::mem::take(&mut self.digest);
        digest.update_ranges(id, &self.buffer_bytes(id), ranges);
        self.digest = digest;
    }

    /// The bytes of a digested buffer or table, at its logical length (what the digest and
    /// the wire's snapshot pages cover).
    pub fn buffer_bytes(&self, id: BufferId) -> std::borrow::Cow<'_, [u8]> {
        use std::borrow::Cow;
        match id {
            BufferId::Chunks => Cow::Borrowed(bytemuck_u32(&self.chunks)),
            BufferId::ChunkEntities => Cow::Borrowed(bytemuck_u32(&self.chunk_entities)),
            BufferId::Blocks => Cow::Borrowed(bytemuck_u32(&self.blocks)),
            BufferId::Voxels => Cow::Borrowed(bytemuck_u32(&self.voxels)),
            BufferId::Materials => Cow::Borrowed(bytemuck_u32(self.materials.words())),
            BufferId::Models => Cow::Owned(self.models.encode()),
            BufferId::EntityTypes => Cow::Borrowed(bytemuck_u32(&self.entities.type_voxels)),
            BufferId::EntityInstances => Cow::Borrowed(bytemuck_u32(&self.entities.instances)),
        }
    }

    /// Rebuilds a world from stored parts, validating everything a traversal or an edit
    /// relies on. Corrupt or hostile parts give an error, never a panic.
    pub fn from_parts(p: WorldParts) -> Result<Self, WorldError> {
        let bad = |m: String| Err(WorldError::BadFile(m));
        let n = p.size.chunk_count();
        if p.chunks.len() != n || p.chunk_entities.len() != n {
            return bad(format!(
                "{} chunk cells and {} entity fields for a {} world ({n} chunks)",
                p.chunks.len(),
                p.chunk_entities.len(),
                p.size
            ));
        }
        let entities = Self::entities_from_parts(&p)?;
        if !p.blocks.len().is_multiple_of(BLOCK_ARRAY) || !p.voxels.len().is_multiple_of(GROUP_WORDS) {
            return bad(format!(
                "buffer lengths {} blocks / {} voxel words are not whole arrays",
                p.blocks.len(),
                p.voxels.len()
            ));
        }
        let max_id = (p.materials.len() - 1) as u32;
        let material_ok = |m: u32| (1..=max_id).contains(&m);
        let full_ok = |c: u32| (c & cell::PAYLOAD) <= u32::from(cell::MAX_MATERIAL) && material_ok(c & 0x7FFF);

        // Chunks: states, materials, block-array pointers (each array owned by one chunk).
        let mut arrays = vec![false; p.blocks.len() / BLOCK_ARRAY];
        for (i, &c) in p.chunks.iter().enumerate() {
            match c >> 30 {
                0 => {}
                1 if full_ok(c) => {}
                2 => {
                    let ptr = cell::pointer(c) as usize;
                    if !ptr.is_multiple_of(BLOCK_ARRAY)
                        || ptr + BLOCK_ARRAY > p.blocks.len()
                        || std::mem::replace(&mut arrays[ptr / BLOCK_ARRAY], true)
                    {
                        return bad(format!("chunk {i}: bad or shared block pointer {ptr}"));
                    }
                }
                _ => return bad(format!("chunk {i}: invalid cell {c:#010x}")),
            }
        }
        // Block arrays: free ones zero; live ones canonical with exact block AADFs.
        let mut group_used = vec![false; p.voxels.len() / GROUP_WORDS];
        let mut block_ptrs = Vec::new();
        for (a, &live) in arrays.iter().enumerate() {
            let cells = &p.blocks[a * BLOCK_ARRAY..][..BLOCK_ARRAY];
            if !live {
                if cells.iter().any(|&c| c != 0) {
                    return bad(format!("free block array {a} is not zeroed"));
                }
                continue;
            }
            let mut empty = 0u64;
            for (b, &c) in cells.iter().enumerate() {
                match c >> 30 {
                    0 => empty |= 1 << b,
                    1 if full_ok(c) => {}
                    2 => {
                        let ptr = cell::pointer(c) as usize;
                        if !ptr.is_multiple_of(GROUP_WORDS) || ptr + GROUP_WORDS > p.voxels.len() {
                            return bad(format!("block {b} of array {a}: bad voxel pointer {ptr}"));
                        }
                        group_used[ptr / GROUP_WORDS] = true;
                        block_ptrs.push(ptr as u32);
                    }
                    _ => return bad(format!("block {b} of array {a}: invalid cell {c:#010x}")),
                }
            }
            if cells
                .iter()
                .all(|&c| cell::state(c) != State::Mixed && uniform_material(c) == uniform_material(cells[0]))
            {
                return bad(format!("block array {a} is uniform and should have collapsed"));
            }
            let fields = cell_aadf4(empty);
            if let Some(b) = (0..64).find(|&b| empty >> b & 1 == 1 && cells[b] != u32::from(fields[b])) {
                return bad(format!("block {b} of array {a}: wrong block AADF"));
            }
        }
        // Voxel groups: free ones zero; live ones canonical, known materials, exact AADFs.
        let group_error = group_used.par_iter().enumerate().find_map_any(|(g, &used)| {
            let words = &p.voxels[g * GROUP_WORDS..][..GROUP_WORDS];
            if !used {
                return words
                    .iter()
                    .any(|&w| w != 0)
                    .then(|| format!("free voxel group {g} is not zeroed"));
            }
            let v: [u16; 64] = std::array::from_fn(|i| cell::group_voxel(words, 0, i));
            let m = v.map(cell::voxel_material);
            if v.iter()
                .any(|&x| cell::voxel_is_solid(x) && !material_ok(u32::from(cell::voxel_material(x))))
            {
                return Some(format!("voxel group {g}: undefined material"));
            }
            if m.iter().all(|&x| x == m[0]) {
                return Some(format!("voxel group {g} is uniform and should have collapsed"));
            }
            (group_words(&m)[..] != words[..]).then(|| format!("voxel group {g}: wrong voxel AADF"))
        });
        if let Some(e) = group_error {
            return bad(e);
        }
        let groups = GroupStore::rebuild(&p.voxels, block_ptrs.into_iter());
        let free_block_arrays = arrays
            .iter()
            .enumerate()
            .filter(|(_, live)| !**live)
            .map(|(a, _)| (a * BLOCK_ARRAY) as u32)
            .collect();
        let mut w = World {
            size: p.size,
            version: p.version,
            materials: p.materials,
            models: p.models,
            chunks: p.chunks,
            chunk_entities: p.chunk_entities,
            blocks: p.blocks,
            voxels: p.voxels,
            groups,
            free_block_arrays,
            entities,
            digest: PagedDigest::default(),
            growth: Growth::default(),
        };
        if let Some(i) = w.unsafe_chunk_aadf() {
            return bad(format!(
                "chunk {:?}: its AADF box contains a non-empty chunk",
                w.size.chunk_coords(i)
            ));
        }
        w.reserve_headroom();
        w.refresh_digest();
        Ok(w)
    }

    /// Makes room for the block and voxel buffers to grow by a quarter, and for the dedup
    /// map to take as many new groups as are live, without reallocating.
    ///
    /// A world fresh from a file, a snapshot or a `clone` holds exactly what it needs, so
    /// its first growing edit would copy whole buffers (and rehash the map); every mirror
    /// of the same world would pay that at the same version, together. Loading, joining
    /// and [`World::build`] call this; so should whoever keeps a cloned world to edit.
    pub fn reserve_headroom(&mut self) {
        self.blocks.reserve(self.blocks.len() / 4);
        self.voxels.reserve(self.voxels.len() / 4);
        self.groups.reserve_headroom();
    }

    /// The stored parts (a copy of every buffer and table).
    pub fn to_parts(&self) -> WorldParts {
        WorldParts {
            size: self.size,
            version: self.version,
            materials: self.materials.clone(),
            models: self.models.clone(),
            chunks: self.chunks.clone(),
            chunk_entities: self.chunk_entities.clone(),
            blocks: self.blocks.clone(),
            voxels: self.voxels.clone(),
            entities: self.entities.table.clone(),
        }
    }

    /// Validates the entity table of stored parts and derives its buffers; the stored
    /// chunk entity fields must be zero.
    fn entities_from_parts(p: &WorldParts) -> Result<Entities, WorldError> {
        let bad = |m: String| Err(WorldError::BadFile(m));
        let t = &p.entities;
        for (k, name) in t.types.iter().enumerate() {
            let Some(model) = p.models.get(name) else {
                return bad(format!("entity type {k}: model '{name}' is not defined"));
            };
            if let Err(e) = crate::entity::check_model(name, model, &p.materials) {
                return bad(format!("entity type {k}: {e}"));
            }
        }
        for (&id, pose) in &t.instances {
            if id > crate::entity::MAX_ENTITY_ID {
                return bad(format!("entity id {id} outside 0..={}", crate::entity::MAX_ENTITY_ID));
            }
            if !t.types.contains(&pose.model) {
                return bad(format!("entity {id}: model '{}' has no entity type", pose.model));
            }
            match crate::entity::checked_pose(pose.pos, pose.rot) {
                Ok(q) if q.pos == pose.pos && q.rot == pose.rot => {}
                Ok(_) => return bad(format!("entity {id}: pose {pose:?} is not a quantised pose")),
                Err(e) => return bad(format!("entity {id}: {e}")),
            }
        }
        let e = Entities::build(t.clone(), &p.models).or_else(|e| bad(format!("entities: {}", e.0)))?;
        if let Some(i) = p.chunk_entities.iter().position(|&f| f != 0) {
            return bad(format!(
                "chunk {:?}: entity field {:#x}; the chunk entity buffer must be zero (entities live \
                 outside the static world)",
                p.size.chunk_coords(i),
                p.chunk_entities[i]
            ));
        }
        Ok(e)
    }

    /// The first empty chunk whose AADF box holds a non-free chunk (checks the safety
    /// invariant in O(chunks) with a 3D prefix sum).
    pub fn unsafe_chunk_aadf(&self) -> Option<usize> {
        let size = self.size;
        let blocked = PrefixSum3::new(size.chunks().map(|v| v as usize), |x, y, z| {
            let i = size.chunk_index([x as u32, y as u32, z as u32]);
            u32::from(!chunk_is_free(self.chunks[i]))
        });
        (0..self.chunks.len()).into_par_iter().find_first(|&i| {
            if !chunk_is_free(self.chunks[i]) {
                return false;
            }
            let f = Aadf::unpack(self.chunks[i], CHUNK_FIELD_BITS);
            let p = size.chunk_coords(i).map(i64::from);
            let lo: [i64; 3] = std::array::from_fn(|a| p[a] - i64::from(f.0[2 * a]));
            let hi: [i64; 3] = std::array::from_fn(|a| p[a] + i64::from(f.0[2 * a + 1]) + 1);
            blocked.count(lo, hi) != 0
        })
    }

    /// World size.
    pub fn size(&self) -> WorldSize {
        self.size
    }
    /// Number of edit batches applied.
    pub fn version(&self) -> u64 {
        self.version
    }
    /// The material table.
    pub fn materials(&self) -> &MaterialTable {
        &self.materials
    }
    /// The model table.
    pub fn models(&self) -> &ModelTable {
        &self.models
    }
    /// Chunk cells, `x + y·Cx + z·Cx·Cy`.
    pub fn chunks(&self) -> &[u32] {
        &self.chunks
    }
    /// Per-chunk entity fields.
    pub fn chunk_entities(&self) -> &[u32] {
        &self.chunk_entities
    }
    /// Block cells.
    pub fn blocks(&self) -> &[u32] {
        &self.blocks
    }
    /// Voxel words.
    pub fn voxels(&self) -> &[u32] {
        &self.voxels
    }
    /// The voxel-group store (reference counts, free slots).
    pub fn groups(&self) -> &GroupStore {
        &self.groups
    }
    /// Start indices of the free block arrays, lowest first.
    pub fn free_block_arrays(&self) -> impl Iterator<Item = u32> + '_ {
        self.free_block_arrays.iter().copied()
    }

    /// The material at voxel `p` (0 = empty). `p` must lie inside the world.
    pub fn material_at(&self, p: [u32; 3]) -> u16 {
        let c = self.chunks[self.size.chunk_index(p.map(|v| v / 16))];
        match cell::state(c) {
            State::Empty => 0,
            State::Full => cell::material(c),
            State::Mixed => {
                let b = self.blocks[cell::pointer(c) as usize + cell::index4(p[0] / 4 % 4, p[1] / 4 % 4, p[2] / 4 % 4)];
                match cell::state(b) {
                    State::Empty => 0,
                    State::Full => cell::material(b),
                    State::Mixed => cell::voxel_material(cell::group_voxel(
                        &self.voxels,
                        cell::pointer(b) as usize,
                        cell::index4(p[0] % 4, p[1] % 4, p[2] % 4),
                    )),
                }
            }
        }
    }

    /// Decodes chunk `c` into material ids (`x + 16y + 256z`).
    pub fn decode_chunk(&self, c: [u32; 3], out: &mut [u16; CHUNK_VOXELS]) {
        let cellv = self.chunks[self.size.chunk_index(c)];
        match cell::state(cellv) {
            State::Empty => out.fill(0),
            State::Full => out.fill(cell::material(cellv)),
            State::Mixed => {
                for b in 0..64 {
                    self.decode_block_cell(self.block_cell(cellv, b), b, out);
                }
            }
        }
    }

    /// The cell of block `b` (`bx + 4by + 16bz`) of the chunk whose cell is `chunk`. The
    /// blocks of a uniform chunk have its state and material (an empty one's field is
    /// meaningless here).
    pub(crate) fn block_cell(&self, chunk: u32, b: u32) -> u32 {
        match cell::state(chunk) {
            State::Mixed => self.blocks[cell::pointer(chunk) as usize + b as usize],
            _ => chunk,
        }
    }

    /// Decodes block `b` of chunk `ci` into its 64 places of `out` (the chunk's material
    /// ids, `x + 16y + 256z`); the rest of `out` is left as it is.
    pub(crate) fn decode_block(&self, ci: usize, b: u32, out: &mut [u16; CHUNK_VOXELS]) {
        self.decode_block_cell(self.block_cell(self.chunks[ci], b), b, out);
    }

    /// [`World::decode_block`] for the block whose cell is `bc`.
    fn decode_block_cell(&self, bc: u32, b: u32, out: &mut [u16; CHUNK_VOXELS]) {
        let base = cell::index16(b % 4 * 4, b / 4 % 4 * 4, b / 16 * 4);
        // 16 rows of 4 voxels: x is contiguous in the chunk layout, and a row is two words
        // of the block's voxel group.
        let row_at = |row: usize| base + 16 * (row % 4) + 256 * (row / 4);
        match cell::state(bc) {
            State::Mixed => {
                let words = &self.voxels[cell::pointer(bc) as usize..][..cell::GROUP_WORDS];
                for (row, pair) in words.chunks_exact(2).enumerate() {
                    let at = row_at(row);
                    let dst: &mut [u16; 4] = (&mut out[at..at + 4]).try_into().expect("4 voxels");
                    let v = |w: u32, half: u32| cell::voxel_material((w >> (16 * half)) as u16);
                    *dst = [v(pair[0], 0), v(pair[0], 1), v(pair[1], 0), v(pair[1], 1)];
                }
            }
            state => {
                let m = if state == State::Full { cell::material(bc) } else { 0 };
                for row in 0..16 {
                    let at = row_at(row);
                    out[at..at + 4].fill(m);
                }
            }
        }
    }

    /// Writes the dense raw export: little-endian `u16` material ids, x fastest, then y,
    /// then z. Streams one 16-voxel z-slab at a time.
    pub fn export_raw(&self, out: &mut dyn Write) -> std::io::Result<()> {
        let [sx, sy, _] = self.size.voxels().map(|v| v as usize);
        let cz = self.size.chunks()[2] as usize;
        // A few slabs at a time, decoded in parallel and written in order.
        let batch = rayon::current_num_threads().max(1);
        for first in (0..cz).step_by(batch) {
            let slabs: Vec<Vec<u16>> = (first..(first + batch).min(cz))
                .into_par_iter()
                .map(|z| {
                    let mut slab = vec![0u16; sx * sy * 16];
                    self.decode_slab(z as u32, &mut slab);
                    slab
                })
                .collect();
            for slab in slabs {
                let bytes: Vec<u8> = slab.iter().flat_map(|v| v.to_le_bytes()).collect();
                out.write_all(&bytes)?;
            }
        }
        Ok(())
    }

    /// Decodes the 16 voxel planes of chunk layer `cz` into `slab` (material ids, x fastest,
    /// then y, then the 16 planes; `size.x · size.y · 16` entries).
    pub fn decode_slab(&self, cz: u32, slab: &mut [u16]) {
        let [sx, sy, _] = self.size.voxels().map(|v| v as usize);
        let [cx, cy, _] = self.size.chunks();
        let mut raw = [0u16; CHUNK_VOXELS];
        for y in 0..cy {
            for x in 0..cx {
                self.decode_chunk([x, y, cz], &mut raw);
                for lz in 0..16usize {
                    for ly in 0..16usize {
                        let dst = x as usize * 16 + sx * (y as usize * 16 + ly + sy * lz);
                        slab[dst..dst + 16].copy_from_slice(&raw[256 * lz + 16 * ly..][..16]);
                    }
                }
            }
        }
    }

    /// The world digest (docs/FORMAT.md §8) over every mirrored buffer and table, kept
    /// incrementally: O(1) to read, O(changed pages) to maintain.
    pub fn digest(&self) -> Digest {
        self.digest.digest()
    }

    /// The digest contribution of every 64 KiB page of buffer `id`, in page order (kept
    /// incrementally with the digest; a server compares them to find changed pages).
    pub fn page_hashes(&self, id: BufferId) -> &[u64] {
        self.digest.page_hashes(id)
    }

    /// The byte length of buffer `id` (without encoding it, unlike [`World::buffer_bytes`]).
    pub fn buffer_len(&self, id: BufferId) -> usize {
        self.digest.len(id)
    }

    /// The entity types and instances.
    pub fn entity_table(&self) -> &EntityTable {
        &self.entities.table
    }

    /// The entity with id `id`.
    pub fn entity(&self, id: u32) -> Option<&Pose> {
        self.entities.table.instances.get(&id)
    }

    /// The entity-type buffer: every type's dense voxel grid, each at a multiple of 64.
    pub fn entity_type_voxels(&self) -> &[u32] {
        &self.entities.type_voxels
    }

    /// Per entity type (in type order): its `voxelStart`, in units of 64 voxels.
    pub fn entity_type_starts(&self) -> &[u32] {
        &self.entities.type_starts
    }

    /// The entity instance buffer: each instance's 5-word record in the slot of its id.
    pub fn entity_instances(&self) -> &[u32] {
        &self.entities.instances
    }

    /// The hierarchy over the instances' world boxes, packed as the GPU walks it
    /// ([`crate::entity::bvh`]): derived from the instance buffer, neither mirrored nor
    /// digested. Empty when there is no instance.
    pub fn entity_hierarchy_words(&self) -> Vec<u32> {
        self.entities.set().hierarchy_words()
    }

    /// Whether a chunk is empty (it may carry a chunk AADF).
    pub fn chunk_is_free(&self, i: usize) -> bool {
        aadf::chunk_is_free(self.chunks[i])
    }
}

/// The material of a non-mixed cell (empty cells carry AADF bits but hold material 0).
fn uniform_material(c: u32) -> u16 {
    if cell::state(c) == State::Full {
        cell::material(c)
    } else {
        0
    }
}

/// The little-endian bytes of a `u32` buffer, without copying.
/// A world is a source of its own static voxels (entities left out): building from it
/// gives an equal world without entities, and times the build on real content.
impl ChunkSource for World {
    fn size(&self) -> WorldSize {
        self.size
    }

    fn materials(&self) -> MaterialTable {
        World::materials(self).clone()
    }

    fn models(&self) -> ModelTable {
        World::models(self).clone()
    }

    fn uniform_hint(&self, c: [u32; 3]) -> Option<u16> {
        let cell = self.chunks[self.size.chunk_index(c)];
        match cell::state(cell) {
            State::Empty => Some(0),
            State::Full => Some(cell::material(cell)),
            State::Mixed => None,
        }
    }

    fn fill_chunk(&self, c: [u32; 3], out: &mut [u16; CHUNK_VOXELS]) {
        self.decode_chunk(c, out);
    }
}

pub(crate) fn bytemuck_u32(v: &[u32]) -> &[u8] {
    #[cfg(not(target_endian = "little"))]
    compile_error!("naadf buffers are little-endian; big-endian hosts are not supported");
    bytemuck::cast_slice(v)
}

//! [`GpuWorld`]: the world buffers on the device, kept byte for byte equal to a
//! [`World`]'s.
//!
//! Syncing compares the world's 64 KiB page hashes (the ones its digest is made of, kept
//! incrementally) with those of the pages last uploaded, and writes only the pages that
//! differ with `write_buffer`: after a delta that is a handful of pages. Buffers grow by
//! doubling (old contents are copied on the device). A buffer larger than the adapter's
//! storage-binding limit is split into parts of `2^k` words, each its own binding; the
//! shaders read it through a generated accessor ([`super::shaders::prelude`]).
//!
//! The device may also hold **local instances** ([`LocalInstances`]: previews, markers)
//! that are not in the world: their type grids and records follow the world's, beyond the
//! logical lengths that are mirrored, read back and digested, and the instance hierarchy
//! covers both.
//!
//! Each sync also works out which chunks now show something else ([`ChunkPrints`], from
//! the pages that changed) and logs them by generation, so that renderers with a history
//! of earlier frames can drop or revalidate just the light those chunks touch
//! ([`GpuWorld::changes_since`]).

use super::bindings::{BUFFERS, Split, storage_entry};
use super::context::{Gpu, GpuError, checked_on};
use super::params::WorldInfo;
use super::traversal::Traversal;
use naadf_world::baselines::{Hybrid, Svdag, Svo};
use naadf_world::digest::{BufferId, Digest, PAGE_BYTES, digest_of};
use naadf_world::entity::bvh::joined_words;
use naadf_world::entity::local::{LocalInstances, LocalLayout};
use naadf_world::entity::pack::RECORD_WORDS;
use naadf_world::entity::{TYPE_ALIGN, hierarchy_words};
use naadf_world::fingerprint::{ChunkChanges, ChunkPrints, chunks_under, stale_words};
use naadf_world::traverse::{DEFAULT_MAX_STEPS, Method};
use naadf_world::{World, WorldError};
use std::collections::VecDeque;
use std::sync::atomic::{AtomicU64, Ordering};

/// The digested buffers that live on the GPU, in the binding order of the world's buffers
/// (`BUFFERS`). The model table and the chunk entity buffer (all zero: entities live
/// outside the static world) are not GPU buffers; the last two bindings, the instance
/// hierarchy and the comparison structure, are derived and not digested.
pub const GPU_BUFFERS: [BufferId; 6] = [
    BufferId::Chunks,
    BufferId::Blocks,
    BufferId::Voxels,
    BufferId::Materials,
    BufferId::EntityTypes,
    BufferId::EntityInstances,
];
/// The logical buffers of the entity types and instances (indices into `GPU_BUFFERS`).
const TYPES: usize = 4;
const INSTANCES: usize = 5;
const _: () = assert!(
    GPU_BUFFERS[TYPES] as u32 == BufferId::EntityTypes as u32
        && GPU_BUFFERS[INSTANCES] as u32 == BufferId::EntityInstances as u32
);
/// The logical buffer of the instance hierarchy ([`World::entity_hierarchy_words`]).
const HIERARCHY: usize = 6;
/// The logical buffer of the comparison structure (dense grid, SVO, SVDAG or hybrid
/// format).
const STRUCTURE: usize = 7;
/// The digested buffers that are not on the GPU: its digest takes them from the world.
const HOST_BUFFERS: [BufferId; 2] = [BufferId::Models, BufferId::ChunkEntities];
/// Smallest part (and page) size in words: parts never split a 64 KiB page.
const MIN_PART_WORDS: u64 = (PAGE_BYTES / 4) as u64;
/// The most storage buffers a pass other than the GI's binds besides the world's: the TAA
/// pass's parameters of this frame and the last, its two inputs and its output. (The GI
/// passes check their own, larger count for each frame size.)
const PASS_STORAGE_BUFFERS: u32 = 5;
/// Smallest buffer allocated (bindings must not be empty).
const MIN_BYTES: u64 = 16;

/// Generations a copy may count through before its range would meet the next copy's.
const GENERATIONS_PER_COPY: u64 = 1 << 40;

/// The first generation of a new copy: each copy in this process counts from a base of its
/// own, so that a renderer that kept state from one copy (a GI history, an irradiance cache,
/// ROMA's maps) never takes another copy's generation for one it has seen.
fn first_generation() -> u64 {
    static COPIES: AtomicU64 = AtomicU64::new(0);
    COPIES.fetch_add(1, Ordering::Relaxed) * GENERATIONS_PER_COPY
}

/// Syncs whose changed chunks are kept in the log; a renderer further behind than that is
/// told that everything changed.
const CHANGE_LOG_SYNCS: usize = 256;
/// Changed chunks the log keeps over all its syncs, at most.
const CHANGE_LOG_CHUNKS: usize = 1 << 20;

/// What one sync uploaded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Upload {
    /// Bytes written with `write_buffer`.
    pub bytes: u64,
    /// Pages written.
    pub pages: usize,
    /// Whether a buffer was reallocated (bind groups are rebuilt).
    pub reallocated: bool,
}

/// One logical buffer: its parts on the device, logical length, and the page hashes of
/// what was uploaded.
struct Logical {
    parts: Vec<wgpu::Buffer>,
    len: u64,
    hashes: Vec<u64>,
}

/// The world's buffers on a wgpu device.
pub struct GpuWorld {
    device: wgpu::Device,
    queue: wgpu::Queue,
    part_words: u64,
    buffers: Vec<Logical>,
    info: wgpu::Buffer,
    /// What `info` holds.
    world_info: WorldInfo,
    layout: wgpu::BindGroupLayout,
    bind_group: wgpu::BindGroup,
    split: Split,
    max_storage_buffers: u32,
    /// Counts the syncs that changed anything on the device, from a base of this copy's own
    /// ([`first_generation`]), so that no two copies share a generation.
    generation: u64,
    /// The fingerprints of the synced world's chunks (none until the first upload).
    prints: Option<ChunkPrints>,
    /// The chunks each generation changed, oldest first, back to just after
    /// `changes_from`.
    changes: VecDeque<(u64, ChunkChanges)>,
    /// The generation the log starts after: changes since an older one are unknown.
    changes_from: u64,
    /// The traversal the comparison-structure binding holds data for, if any.
    structure: Option<Traversal>,
    /// The local instances wanted on the device ([`GpuWorld::set_locals`]).
    locals: LocalInstances,
    /// The local instances on the device.
    shown: ShownLocals,
}

/// The local instances a device holds, and where.
#[derive(Default)]
struct ShownLocals {
    locals: LocalInstances,
    /// The world's type voxels and instance slots they follow.
    after: (usize, usize),
    /// Their records, as on the device.
    records: Vec<u32>,
    /// The packed hierarchy over `records` alone (slots from 0).
    hierarchy: Vec<u32>,
}

impl std::fmt::Debug for GpuWorld {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "GpuWorld({:?})", self.split)
    }
}

impl GpuWorld {
    /// Uploads `world` to `gpu`, splitting buffers at the adapter's storage-binding limit.
    pub fn new(gpu: &Gpu, world: &World) -> Result<Self, GpuError> {
        let limit = gpu
            .limits
            .max_storage_buffer_binding_size
            .min(gpu.limits.max_buffer_size);
        Self::with_part_words(gpu, world, limit / 4)
    }

    /// As [`GpuWorld::new`], with parts of at most `max_part_words` words (rounded down to a
    /// power of two, at least one 64 KiB page): tests use it to exercise splitting.
    pub fn with_part_words(gpu: &Gpu, world: &World, max_part_words: u64) -> Result<Self, GpuError> {
        let part_words = if max_part_words < MIN_PART_WORDS {
            return Err(GpuError::Unsupported(format!(
                "the adapter's storage-binding limit ({} bytes) is below one 64 KiB page",
                max_part_words * 4
            )));
        } else {
            1u64 << (63 - max_part_words.leading_zeros())
        };
        let device = gpu.device.clone();
        let buffers: Vec<Logical> = (0..BUFFERS.len())
            .map(|k| Logical {
                parts: vec![new_part(&device, BUFFERS[k].0, MIN_BYTES)],
                len: 0,
                hashes: Vec::new(),
            })
            .collect();
        let info = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("world info"),
            size: size_of::<WorldInfo>() as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let split = Split {
            part_shift: part_words.trailing_zeros(),
            parts: [1; 8],
        };
        let layout = bind_group_layout(&device, &split);
        let bind_group = make_bind_group(&device, &layout, &info, &buffers);
        let mut w = GpuWorld {
            bind_group,
            device,
            queue: gpu.queue.clone(),
            part_words,
            buffers,
            info,
            world_info: WorldInfo {
                max_steps: DEFAULT_MAX_STEPS,
                ..bytemuck::Zeroable::zeroed()
            },
            layout,
            split,
            max_storage_buffers: gpu.limits.max_storage_buffers_per_shader_stage,
            generation: first_generation(),
            prints: None,
            changes: VecDeque::new(),
            changes_from: 0,
            structure: None,
            locals: LocalInstances::default(),
            shown: ShownLocals::default(),
        };
        w.check_bindings(&split)?;
        w.sync(world)?;
        w.prints = Some(ChunkPrints::new(world));
        w.changes_from = w.generation;
        Ok(w)
    }

    /// Uploads every page of `world` that differs from what the device holds. After it
    /// the device buffers equal the world's, byte for byte, at their logical lengths.
    pub fn sync(&mut self, world: &World) -> Result<Upload, GpuError> {
        let device = self.device.clone();
        checked_on(&device, || self.sync_pages(world))?
    }

    /// Keeps `slot` holding `world`: uploads it the first time, syncs it afterwards.
    pub fn follow<'a>(slot: &'a mut Option<GpuWorld>, gpu: &Gpu, world: &World) -> Result<&'a GpuWorld, GpuError> {
        match slot {
            Some(g) => {
                g.sync(world)?;
                Ok(g)
            }
            None => Ok(slot.insert(GpuWorld::new(gpu, world)?)),
        }
    }

    /// [`GpuWorld::sync`] without the error scope.
    fn sync_pages(&mut self, world: &World) -> Result<Upload, GpuError> {
        let mut up = Upload::default();
        let mut stale = Vec::with_capacity(GPU_BUFFERS.len());
        for (k, &id) in GPU_BUFFERS.iter().enumerate() {
            let len = world.buffer_len(id) as u64;
            up.reallocated |= self.reserve(k, len)?;
            let hashes = world.page_hashes(id);
            // Whole pages, in words; the last page of a buffer may be shorter.
            let words = stale_words(&self.buffers[k].hashes, hashes);
            if !words.is_empty() {
                let bytes = world.buffer_bytes(id);
                for r in &words {
                    let lo = (4 * r.start).min(bytes.len());
                    let hi = (4 * r.end).min(bytes.len());
                    if lo < hi {
                        self.write(k, lo as u64, &bytes[lo..hi]);
                        up.bytes += (hi - lo) as u64;
                        up.pages += 1;
                    }
                }
            }
            stale.push((id, words));
            let b = &mut self.buffers[k];
            b.hashes = hashes.to_vec();
            b.len = len;
        }
        let instances_stale = stale
            .iter()
            .any(|(id, words)| *id == BufferId::EntityInstances && !words.is_empty());
        let local_changes = self.sync_locals(world, &mut up)?;
        // The hierarchy follows the instance records, the world's and the local ones: one
        // root over the world's hierarchy and the local instances' (each derived only when
        // its own records change), uploaded whole when either changed.
        if instances_stale || local_changes.is_some() {
            let world_slots = (world.entity_instances().len() / RECORD_WORDS) as u32;
            let words = joined_words(&world.entity_hierarchy_words(), &self.shown.hierarchy, world_slots);
            up.reallocated |= self.replace(HIERARCHY, bytemuck::cast_slice(&words))?;
            up.bytes += 4 * words.len() as u64;
        }
        let size = world.size();
        let info = WorldInfo {
            size: size.voxels(),
            instance_slots: ((world.entity_instances().len() + self.shown.records.len()) / RECORD_WORDS) as u32,
            chunks: size.chunks(),
            max_steps: self.world_info.max_steps,
        };
        if up.pages > 0 || up.reallocated || info != self.world_info || local_changes.is_some() {
            self.generation += 1;
            if let Some(prints) = &mut self.prints {
                let mut changed = prints.update(world, &stale);
                if let (ChunkChanges::Chunks(list), Some(local)) = (&mut changed, local_changes) {
                    list.extend(local);
                    list.sort_unstable();
                    list.dedup();
                }
                self.log_changes(changed);
            }
        }
        if info != self.world_info || up.reallocated {
            self.world_info = info;
            self.queue.write_buffer(&self.info, 0, bytemuck::bytes_of(&info));
        }
        if up.reallocated {
            self.rebind();
        }
        Ok(up)
    }

    /// Asks for `locals` on the device from the next sync on: drawn and hit by rays after
    /// the world's own instances, but never mirrored, read back or digested.
    pub fn set_locals(&mut self, locals: &LocalInstances) {
        if *locals != self.locals {
            self.locals = locals.clone();
        }
    }

    /// The local instances asked for.
    pub fn locals(&self) -> &LocalInstances {
        &self.locals
    }

    /// Writes the local instances' type grids and records after the world's when they
    /// changed or the world's grew or shrank under them; returns the chunks whose look
    /// changed, or `None` when nothing was written.
    fn sync_locals(&mut self, world: &World, up: &mut Upload) -> Result<Option<Vec<u32>>, GpuError> {
        let after = (
            world
                .buffer_len(BufferId::EntityTypes)
                .div_ceil(4)
                .next_multiple_of(TYPE_ALIGN),
            world.entity_instances().len() / RECORD_WORDS,
        );
        let unchanged = self.locals == self.shown.locals;
        if unchanged && (self.shown.records.is_empty() || after == self.shown.after) {
            return Ok(None);
        }
        // A world may redefine a material a local model uses: such locals are not drawn.
        let layout = self
            .locals
            .fits(world.materials())
            .and_then(|()| self.locals.layout(after.0))
            .unwrap_or_else(|e| {
                tracing::warn!("local instances not drawn: {e}");
                LocalLayout::default()
            });
        for (k, base, words) in [
            (TYPES, after.0, &layout.type_voxels),
            (INSTANCES, after.1 * RECORD_WORDS, &layout.records),
        ] {
            let bytes: &[u8] = bytemuck::cast_slice(words);
            let offset = 4 * base as u64;
            up.reallocated |= self.reserve(k, offset + bytes.len() as u64)?;
            self.write_span(k, offset, bytes);
            up.bytes += bytes.len() as u64;
        }
        let size = world.size();
        let mut chunks: Vec<u32> = self
            .locals
            .changed_since(&self.shown.locals)
            .iter()
            .flat_map(|r| chunks_under(size, r))
            .collect();
        chunks.sort_unstable();
        chunks.dedup();
        self.shown = ShownLocals {
            locals: self.locals.clone(),
            after,
            hierarchy: hierarchy_words(&layout.records),
            records: layout.records,
        };
        Ok(Some(chunks))
    }

    /// How many syncs changed the device's copy: renderers that accumulate over frames
    /// restart when it moves.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// The world's size in chunks along x, y and z.
    pub fn chunk_dims(&self) -> [u32; 3] {
        self.world_info.chunks
    }

    /// The chunks that show something else now than at `generation` (an earlier
    /// [`GpuWorld::generation`]): distance fields aside, their voxels, their entity records
    /// or those entities' types changed. [`ChunkChanges::Everything`] when the materials or
    /// the world's size changed, or when `generation` is older than the log reaches or is
    /// not one of this copy's (a renderer that last drew another copy).
    pub fn changes_since(&self, generation: u64) -> ChunkChanges {
        if generation < self.changes_from || generation > self.generation {
            return ChunkChanges::Everything;
        }
        let mut chunks = Vec::new();
        for (_, c) in self.changes.iter().filter(|(g, _)| *g > generation) {
            match c {
                ChunkChanges::Everything => return ChunkChanges::Everything,
                ChunkChanges::Chunks(list) => chunks.extend_from_slice(list),
            }
        }
        chunks.sort_unstable();
        chunks.dedup();
        ChunkChanges::Chunks(chunks)
    }

    /// Logs what this generation changed, forgetting the oldest entries beyond the log's
    /// bounds.
    fn log_changes(&mut self, changed: ChunkChanges) {
        self.changes.push_back((self.generation, changed));
        let size = |c: &ChunkChanges| match c {
            ChunkChanges::Chunks(list) => list.len(),
            ChunkChanges::Everything => 1,
        };
        let mut total: usize = self.changes.iter().map(|(_, c)| size(c)).sum();
        while self.changes.len() > CHANGE_LOG_SYNCS || total > CHANGE_LOG_CHUNKS {
            let Some((g, c)) = self.changes.pop_front() else { break };
            total -= size(&c);
            self.changes_from = g;
        }
    }

    /// Uploads a dense decode of `world` (16-bit material ids, x fastest) for the `grid`
    /// traversal variant. It is a snapshot: later syncs do not update it. It replaces any
    /// other comparison structure.
    pub fn upload_grid(&mut self, world: &World) -> Result<(), GpuError> {
        let n = world.size().voxel_count();
        self.check_structure_bytes(n * 2, &format!("a dense grid of {n} voxels"))?;
        let mut raw = Vec::with_capacity(n as usize * 2);
        world
            .export_raw(&mut raw)
            .map_err(|e| GpuError::Unsupported(format!("dense decode failed: {e}")))?;
        self.upload_structure(Traversal::Method(Method::Grid), &raw)
    }

    /// Uploads `svo` in its GPU layout ([`Svo::gpu_words`]) for [`Traversal::Svo`], replacing
    /// any other comparison structure.
    pub fn upload_svo(&mut self, svo: &Svo) -> Result<(), GpuError> {
        let words = svo.gpu_words().map_err(|e| GpuError::Unsupported(e.to_string()))?;
        self.check_structure_bytes(4 * words.len() as u64, "the SVO")?;
        self.upload_structure(Traversal::Svo, bytemuck::cast_slice(&words))
    }

    /// Uploads `dag` in its GPU layout ([`Svdag::gpu_words`]) for [`Traversal::Svdag`],
    /// replacing any other comparison structure.
    pub fn upload_svdag(&mut self, dag: &Svdag) -> Result<(), GpuError> {
        let words = dag.gpu_words().map_err(|e| GpuError::Unsupported(e.to_string()))?;
        self.check_structure_bytes(4 * words.len() as u64, "the SVDAG")?;
        self.upload_structure(Traversal::Svdag, bytemuck::cast_slice(&words))
    }

    /// Uploads `hybrid` in its GPU layout ([`Hybrid::gpu_words`]) for
    /// [`Traversal::Hybrid`] of its format, replacing any other comparison structure. Only
    /// the paper's two formats ([`HybridFormat`](naadf_world::baselines::HybridFormat))
    /// have a traversal to name them.
    pub fn upload_hybrid(&mut self, hybrid: &Hybrid) -> Result<(), GpuError> {
        let format = hybrid.format().ok_or_else(|| {
            GpuError::Unsupported(format!(
                "{} is not one of the paper's two hybrid formats",
                hybrid.name()
            ))
        })?;
        let words = hybrid.gpu_words();
        self.check_structure_bytes(4 * words.len() as u64, format.name())?;
        self.upload_structure(Traversal::Hybrid(format), bytemuck::cast_slice(words))
    }

    /// The traversal whose comparison structure is on the device (the last uploaded).
    pub fn structure(&self) -> Option<Traversal> {
        self.structure
    }

    /// Fails when `bytes` of a comparison structure exceed the 64 bindings it may take.
    fn check_structure_bytes(&self, bytes: u64, what: &str) -> Result<(), GpuError> {
        let max_bytes = self.part_words * 4 * 64;
        if bytes > max_bytes {
            return Err(GpuError::Unsupported(format!(
                "{what} ({} MiB) exceeds what the comparison binding holds ({} MiB)",
                bytes >> 20,
                max_bytes >> 20
            )));
        }
        Ok(())
    }

    /// Writes `bytes` to the comparison-structure buffer, page by page, as the data of
    /// `traversal`.
    fn upload_structure(&mut self, traversal: Traversal, bytes: &[u8]) -> Result<(), GpuError> {
        self.structure = None;
        if self.replace(STRUCTURE, bytes)? {
            self.rebind();
        }
        self.structure = Some(traversal);
        Ok(())
    }

    /// Replaces the whole of derived logical buffer `k` with `bytes`, page by page (an odd
    /// tail padded to a whole word); returns whether a buffer was reallocated (the caller
    /// rebinds).
    fn replace(&mut self, k: usize, bytes: &[u8]) -> Result<bool, GpuError> {
        let reallocated = self.reserve(k, bytes.len() as u64)?;
        let whole = bytes.len() & !3;
        self.write_span(k, 0, &bytes[..whole]);
        if whole < bytes.len() {
            // A dense grid is u16 pairs: its odd tail is padded to a word.
            let mut tail = bytes[whole..].to_vec();
            tail.resize(4, 0);
            self.write(k, whole as u64, &tail);
        }
        self.buffers[k].len = bytes.len() as u64;
        Ok(reallocated)
    }

    /// Reads buffer `id` back from the device, at its logical length.
    pub fn read_back(&self, gpu: &Gpu, id: BufferId) -> Result<Vec<u8>, GpuError> {
        let k = GPU_BUFFERS
            .iter()
            .position(|&b| b == id)
            .ok_or_else(|| GpuError::Unsupported(format!("{id:?} is not a GPU buffer")))?;
        let b = &self.buffers[k];
        gpu.read_parts(&b.parts, self.part_words * 4, 0, b.len)
    }

    /// The digest of the device copy: every GPU buffer read back, combined (as
    /// [`World::digest`] combines them) with `world`'s model table and chunk entity buffer,
    /// which are not GPU buffers. Equal to `world.digest()` exactly when the device holds
    /// `world`'s buffers.
    pub fn digest(&self, gpu: &Gpu, world: &World) -> Result<Digest, GpuError> {
        let mut d = HOST_BUFFERS
            .iter()
            .fold(Digest::default(), |d, &id| d ^ digest_of(id, &world.buffer_bytes(id)));
        for id in GPU_BUFFERS {
            d = d ^ digest_of(id, &self.read_back(gpu, id)?);
        }
        Ok(d)
    }

    /// The first GPU buffer whose device copy differs from `world`'s, if any: a check
    /// that syncing kept the mirror byte for byte.
    pub fn first_difference(&self, gpu: &Gpu, world: &World) -> Result<Option<BufferId>, GpuError> {
        for id in GPU_BUFFERS {
            if self.read_back(gpu, id)? != world.buffer_bytes(id).as_ref() {
                return Ok(Some(id));
            }
        }
        Ok(None)
    }

    /// The group-0 layout the passes' pipelines are built against.
    pub fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// The group-0 bind group (world parameters and buffers).
    pub fn bind_group(&self) -> &wgpu::BindGroup {
        &self.bind_group
    }

    /// How the buffers are currently split across bindings.
    pub fn split(&self) -> Split {
        self.split
    }

    /// Whether the instance buffer has any slot (the world's or a local one), so that the
    /// shaders walk the instance hierarchy at all (their `HAS_INSTANCES` override).
    pub fn has_instances(&self) -> bool {
        self.world_info.instance_slots > 0
    }

    /// Writes `bytes` (whole words) at byte `offset` of logical buffer `k`, page by page
    /// (a write never crosses a part).
    fn write_span(&self, k: usize, offset: u64, bytes: &[u8]) {
        let mut at = 0;
        while at < bytes.len() {
            let o = offset + at as u64;
            let n = (PAGE_BYTES - (o % PAGE_BYTES as u64) as usize).min(bytes.len() - at);
            self.write(k, o, &bytes[at..at + n]);
            at += n;
        }
    }

    /// Writes `bytes` at byte `offset` of logical buffer `k` (within one page).
    fn write(&self, k: usize, offset: u64, bytes: &[u8]) {
        let part_bytes = self.part_words * 4;
        let part = (offset / part_bytes) as usize;
        self.queue
            .write_buffer(&self.buffers[k].parts[part], offset % part_bytes, bytes);
    }

    /// Makes logical buffer `k` hold `len` bytes: grows its last part by doubling (copying
    /// its contents on the device) and adds parts. Returns whether anything was reallocated.
    fn reserve(&mut self, k: usize, len: u64) -> Result<bool, GpuError> {
        let part_bytes = self.part_words * 4;
        let parts_needed = len.div_ceil(part_bytes).max(1) as usize;
        let b = &self.buffers[k];
        let last_cap = b.parts.last().map_or(0, |p| p.size());
        let covered = (b.parts.len() as u64 - 1) * part_bytes + last_cap;
        if covered >= len {
            return Ok(false);
        }
        if parts_needed > 64 {
            return Err(GpuError::Unsupported(format!(
                "buffer {} needs {parts_needed} bindings of {} MiB; at most 64 are supported",
                BUFFERS[k].0,
                part_bytes >> 20
            )));
        }
        let mut split = self.split;
        split.parts[k] = parts_needed as u32;
        self.check_bindings(&split)?;
        let name = BUFFERS[k].0;
        let mut enc = self.device.create_command_encoder(&Default::default());
        let b = &mut self.buffers[k];
        let old_last = b.parts.len() - 1;
        for p in old_last..parts_needed {
            let want = if p + 1 < parts_needed {
                part_bytes
            } else {
                (len - p as u64 * part_bytes)
                    .next_power_of_two()
                    .clamp(MIN_BYTES, part_bytes)
            };
            if p == old_last && b.parts[p].size() >= want {
                // A full last part stays as it is; only new parts follow it.
                continue;
            }
            let fresh = new_part(&self.device, name, want);
            if p == old_last {
                let old = &b.parts[p];
                enc.copy_buffer_to_buffer(old, 0, &fresh, 0, old.size().min(want));
                b.parts[p] = fresh;
            } else {
                b.parts.push(fresh);
            }
        }
        self.queue.submit([enc.finish()]);
        self.split.parts[k] = parts_needed as u32;
        Ok(true)
    }

    /// Fails when `split` needs more storage bindings than a pass may bind next to its own.
    fn check_bindings(&self, split: &Split) -> Result<(), GpuError> {
        if split.storage_bindings() + PASS_STORAGE_BUFFERS > self.max_storage_buffers {
            return Err(GpuError::Unsupported(format!(
                "the world needs {} storage bindings plus {PASS_STORAGE_BUFFERS} per pass; the adapter allows {} per shader stage",
                split.storage_bindings(),
                self.max_storage_buffers
            )));
        }
        Ok(())
    }

    /// Rebuilds the layout and bind group after a reallocation.
    fn rebind(&mut self) {
        self.layout = bind_group_layout(&self.device, &self.split);
        self.bind_group = make_bind_group(&self.device, &self.layout, &self.info, &self.buffers);
    }
}

fn make_bind_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    info: &wgpu::Buffer,
    buffers: &[Logical],
) -> wgpu::BindGroup {
    let mut entries = vec![wgpu::BindGroupEntry {
        binding: 0,
        resource: info.as_entire_binding(),
    }];
    for p in buffers.iter().flat_map(|b| &b.parts) {
        entries.push(wgpu::BindGroupEntry {
            binding: entries.len() as u32,
            resource: p.as_entire_binding(),
        });
    }
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("world"),
        layout,
        entries: &entries,
    })
}

/// A storage buffer that can be written and read back: one part of a logical buffer (the
/// world's, or a GI history's).
pub(crate) fn new_part(device: &wgpu::Device, name: &str, size: u64) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(name),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

fn bind_group_layout(device: &wgpu::Device, split: &Split) -> wgpu::BindGroupLayout {
    // `world_info` at binding 0, then the buffer parts: all read-only.
    let entries: Vec<_> = (0..split.storage_bindings()).map(|b| storage_entry(b, true)).collect();
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("world"),
        entries: &entries,
    })
}

impl From<WorldError> for GpuError {
    fn from(e: WorldError) -> Self {
        GpuError::Unsupported(e.to_string())
    }
}

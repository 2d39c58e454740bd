//! [`Irradiance`]: `--mode irradiance` on the GPU (docs/RENDERING.md §3e). Diffuse surfaces
//! of the world are lit from a world-space cache of irradiance per voxel face
//! ([`crate::light::irradiance`] states the rules; `shaders/irradiance.wgsl` reads and keys
//! it, `shaders/irradiance_update.wgsl` refreshes it); mirrors and metals are traced as the
//! baseline traces them, and the frames are accumulated by the baseline's TAA.
//!
//! A frame runs, in order: the invalidation of the entries near the chunks changed since
//! the last frame (edits and entity moves alike); the sample pass, which requests every
//! entry it reads; and the update, which takes one sample of each requested entry the
//! ray budget pays for. A cache depends on the world, the sky, the sun and the seed only:
//! every camera stream with the same light and seed shares one, and the caches of the last
//! few (up to four) are kept, so that streams taking turns with different ones do not
//! empty each other's.

use super::baseline::{Baseline, History};
use super::context::{Gpu, GpuError};
use super::params::{IrradianceInfo, LightInfo, WgslStruct};
use super::pathtrace::PATHTRACE;
use super::pipeline::PassPipelines;
use super::shaders::{LIGHT, Loop, NO_TIER, PassSource, SAMPLE, WgslValue, constants};
use super::shot::Shot;
use super::temporal::Temporal;
use super::world::GpuWorld;
use crate::light::hdr::Radiance;
use crate::light::irradiance::{BOUNCE_DISTANCE, FaceKey, HISTORY, IrradianceOptions, R2};
use crate::light::{Sky, Sun};
use naadf_world::fingerprint::ChunkChanges;
use std::collections::BTreeSet;
use wgpu::util::DeviceExt;

/// `shaders/irradiance_table.wgsl`: the table's layout and what both passes share.
const TABLE: &str = include_str!("../../../shaders/irradiance_table.wgsl");
/// `shaders/irradiance.wgsl`: the diffuse tier of the sample pass.
const TIER: &str = include_str!("../../../shaders/irradiance.wgsl");
/// `shaders/irradiance_update.wgsl`: invalidation and refresh.
const UPDATE: &str = include_str!("../../../shaders/irradiance_update.wgsl");

/// Words of a slot: the key (2), the stamp, the count, the sums (3) and the samples drawn.
pub(crate) const WORDS: u32 = 8;
/// Caches kept at most: streams that take turns with different lights or seeds each keep
/// theirs, rather than emptying a shared one at every turn.
const MAX_CACHES: usize = 4;
/// Bytes the caches other than the current one may take together (a cache takes 36 to 144
/// MiB, by the frame size).
const KEPT_BYTES: u64 = 512 << 20;
/// Slots a key may be placed past its home slot.
const PROBES: u32 = 64;
/// Words of the request list before the slots: the counters.
pub(crate) const LIST: u32 = 4;
/// The request list's counters: entries requested, those with no samples, samples taken,
/// slots keyed.
pub(crate) const COUNT: u32 = 0;
/// See [`COUNT`].
pub(crate) const FRESH: u32 = 1;
/// See [`COUNT`].
pub(crate) const TAKEN: u32 = 2;
/// See [`COUNT`].
pub(crate) const OCCUPIED: u32 = 3;
/// The fewest slots of a table.
pub(crate) const MIN_SLOTS: u64 = 1 << 20;
/// The most changed boxes invalidated one by one; more are merged.
pub(crate) const MAX_BOXES: usize = 256;
/// Most requests one update dispatch serves (65,535 workgroups of 64).
pub(crate) const MAX_REQUESTS: u32 = 65_535 * 64;

/// The constants and struct both irradiance passes share with the Rust code.
fn generated() -> String {
    let list = [
        ("IRR_WORDS", WgslValue::U32(WORDS)),
        ("IRR_PROBES", WgslValue::U32(PROBES)),
        ("IRR_NONE", WgslValue::U32(u32::MAX)),
        ("IRR_HISTORY", WgslValue::U32(HISTORY)),
        ("IRR_COUNT", WgslValue::U32(COUNT)),
        ("IRR_FRESH", WgslValue::U32(FRESH)),
        ("IRR_TAKEN", WgslValue::U32(TAKEN)),
        ("IRR_OCCUPIED", WgslValue::U32(OCCUPIED)),
        ("IRR_LIST", WgslValue::U32(LIST)),
    ];
    constants(&list) + &format!("const IRR_R2 = vec2<u32>({}u, {}u);\n", R2[0], R2[1]) + &IrradianceInfo::wgsl()
}

/// The irradiance sample pass: the path tracer's `path_sample` with [`TIER`] as its
/// diffuse tier.
pub(crate) fn irradiance_sample_pass() -> PassSource {
    PassSource {
        entry: "path_sample",
        files: &[SAMPLE, LIGHT, TABLE, TIER, PATHTRACE],
        generated: generated(),
    }
}

/// One of the update module's passes (`irradiance_invalidate`, `irradiance_args`,
/// `irradiance_update`).
pub(crate) fn irradiance_update_pass(entry: &'static str) -> PassSource {
    PassSource {
        entry,
        files: &[SAMPLE, LIGHT, NO_TIER, TABLE, UPDATE],
        generated: generated(),
    }
}

/// What the cache's entries depend on besides the world: each basis has a cache of its own.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Basis {
    sky: Sky,
    sun: Option<Sun>,
    seed: u32,
}

/// The cache on the device.
struct Cache {
    basis: Basis,
    slots: u64,
    table: wgpu::Buffer,
    requests: wgpu::Buffer,
    /// The update's indirect dispatch, written by `irradiance_args`.
    args: wgpu::Buffer,
    /// The world's generation the entries show.
    generation: u64,
    /// Frames since the table was made: the stamp of the next is one more.
    stamp: u32,
    /// At most this many slots are keyed (the exact count is read back only near half).
    keyed_bound: u64,
}

impl Cache {
    /// Its bytes on the device.
    fn bytes(&self) -> u64 {
        self.table.size() + self.requests.size()
    }
}

/// What the last frame did to the cache, read back on demand ([`Irradiance::stats`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct IrradianceStats {
    /// Entries the frame requested.
    pub requested: u32,
    /// Those that had no samples.
    pub fresh: u32,
    /// Samples the update took.
    pub samples: u32,
    /// Slots keyed in the table.
    pub keyed: u32,
    /// Slots of the table.
    pub slots: u64,
}

/// The irradiance-cache renderer.
pub struct Irradiance {
    invalidate: PassPipelines,
    args: PassPipelines,
    update: PassPipelines,
    frames: Baseline,
    options: IrradianceOptions,
    /// A cache per basis lately rendered, the current one last and the others in the order
    /// they were last used (at most [`MAX_CACHES`], [`KEPT_BYTES`] besides the current).
    caches: Vec<Cache>,
    /// The boxes the update passes bind (they read none).
    no_boxes: wgpu::Buffer,
}

/// The read-only flags of the update module's group 1 after its two parameter buffers:
/// the table, the request list, the boxes, and for `irradiance_args` the dispatch.
const UPDATE_STORAGE: [bool; 4] = [false, false, true, false];

impl Irradiance {
    /// Prepares the passes (pipelines are built on first use).
    pub fn new(gpu: &Gpu) -> Self {
        let pass = |entry, storage| PassPipelines::new(gpu, irradiance_update_pass(entry), 2, storage);
        Irradiance {
            invalidate: pass("irradiance_invalidate", &UPDATE_STORAGE[..3]),
            args: pass("irradiance_args", &UPDATE_STORAGE),
            update: pass("irradiance_update", &UPDATE_STORAGE[..3]),
            frames: Baseline::with_sample_pass(gpu, irradiance_sample_pass(), &[true, false, false]),
            options: IrradianceOptions::default(),
            caches: Vec::new(),
            no_boxes: gpu.params("irradiance boxes", &[0u8; 32]),
        }
    }

    /// Sets the ray budget of the next frames (checked then).
    pub fn set_options(&mut self, options: IrradianceOptions) {
        self.options = options;
    }

    /// Bytes of the caches on the device (0 before the first frame).
    pub fn cache_bytes(&self) -> u64 {
        self.caches.iter().map(Cache::bytes).sum()
    }

    /// Forgets the caches: the next frame starts from an empty one.
    pub fn forget_cache(&mut self) {
        self.caches.clear();
    }

    /// Swaps the TAA history with `other` (one per camera stream, as the baseline's); the
    /// cache of a basis is shared by every stream that renders with it.
    pub fn swap_history(&mut self, other: &mut Option<History>) {
        self.frames.swap_history(other);
    }

    /// What the last frame did (read back from the device; zeros before the first frame).
    pub fn stats(&self, gpu: &Gpu) -> Result<IrradianceStats, GpuError> {
        let Some(c) = self.caches.last() else {
            return Ok(IrradianceStats::default());
        };
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&gpu.read_buffer(&c.requests, 16)?);
        Ok(IrradianceStats {
            requested: words[COUNT as usize],
            fresh: words[FRESH as usize],
            samples: words[TAKEN as usize],
            keyed: words[OCCUPIED as usize],
            slots: c.slots,
        })
    }

    /// Every keyed entry: its face, its mean irradiance and its sample count (for tests
    /// and tools; it reads the whole table back).
    pub fn entries(&self, gpu: &Gpu) -> Result<Vec<(FaceKey, [f32; 3], u32)>, GpuError> {
        let Some(c) = self.caches.last() else {
            return Ok(Vec::new());
        };
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&gpu.read_buffer(&c.table, c.table.size())?);
        Ok(words
            .chunks_exact(WORDS as usize)
            .filter(|s| s[1] != 0)
            .map(|s| {
                let n = s[3].max(1) as f32;
                let mean = [4, 5, 6].map(|i| f32::from_bits(s[i]) / n);
                (FaceKey::from_words([s[0], s[1]]), mean, s[3])
            })
            .collect())
    }

    /// Drops the least recently used caches beyond [`MAX_CACHES`] or [`KEPT_BYTES`]; the
    /// current one stays.
    fn trim(&mut self) {
        let older = |caches: &[Cache]| caches[..caches.len() - 1].iter().map(Cache::bytes).sum::<u64>();
        while self.caches.len() > MAX_CACHES || (self.caches.len() > 1 && older(&self.caches) > KEPT_BYTES) {
            self.caches.remove(0);
        }
    }

    /// Brings the cache of `shot`'s basis up to date for `shot` of `world` and makes it the
    /// current one: a new one when there is none for the basis or it is too small (or it
    /// fills past half), and the entries near changed chunks cleared.
    fn prepare(&mut self, gpu: &Gpu, world: &GpuWorld, shot: &Shot, light: &wgpu::Buffer) -> Result<(), GpuError> {
        self.options.check().map_err(GpuError::Unsupported)?;
        let basis = Basis {
            sky: shot.light.sky,
            sun: shot.light.sun,
            seed: shot.seed,
        };
        let pixels = u64::from(shot.size.0) * u64::from(shot.size.1);
        let slots = slots_for(gpu, pixels)?;
        let kept = self
            .caches
            .iter()
            .position(|c| c.basis == basis)
            .map(|at| self.caches.remove(at));
        match kept {
            Some(c) if c.slots >= slots && c.generation <= world.generation() => self.caches.push(c),
            _ => {
                // An empty cache shows no change: nothing to invalidate.
                self.caches.push(Cache {
                    generation: world.generation(),
                    ..allocate(gpu, basis, slots)?
                });
                self.trim();
            }
        }
        let cache = self.caches.last_mut().expect("pushed above");
        // A frame keys at most two entries per pixel (its surface and its gather's): while
        // that bound stays under half the slots nothing is read back; past it, the exact
        // count is, and a table more than half full is renewed (a key that finds no slot
        // within IRR_PROBES is gathered meanwhile).
        cache.keyed_bound += 2 * pixels;
        if cache.keyed_bound > cache.slots / 2 {
            let keyed = u64::from(bytemuck::pod_read_unaligned::<u32>(&gpu.read_buffer_at(
                &cache.requests,
                u64::from(OCCUPIED) * 4,
                4,
            )?));
            if keyed > cache.slots / 2 {
                *cache = Cache {
                    generation: cache.generation,
                    stamp: cache.stamp,
                    ..allocate(gpu, basis, cache.slots)?
                };
            } else {
                cache.keyed_bound = keyed;
            }
        }
        let changes = world.changes_since(cache.generation);
        cache.generation = world.generation();
        cache.stamp += 1;
        gpu.queue
            .write_buffer(&cache.requests, 0, bytemuck::cast_slice(&[0u32; 3]));
        let boxes = match changes {
            ChunkChanges::Everything => {
                *cache = Cache {
                    generation: world.generation(),
                    stamp: cache.stamp,
                    ..allocate(gpu, basis, cache.slots)?
                };
                return Ok(());
            }
            ChunkChanges::Chunks(chunks) if !chunks.is_empty() => changed_boxes(world.chunk_dims(), &chunks),
            ChunkChanges::Chunks(_) => return Ok(()),
        };
        let info = info(gpu, &self.options, cache, boxes.len() as u32 / 2);
        let boxes = gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("irradiance boxes"),
            contents: bytemuck::cast_slice(&boxes),
            usage: wgpu::BufferUsages::STORAGE,
        });
        self.invalidate.submit(
            gpu,
            world,
            &[light, &info, &cache.table, &cache.requests, &boxes],
            cache.slots.div_ceil(64) as u32,
        )
    }
}

impl Temporal for Irradiance {
    /// Brings the cache up to date, renders the next frame as the baseline does with the
    /// cache lighting diffuse surfaces, then refreshes the entries the frame requested.
    fn frame(&mut self, gpu: &Gpu, world: &GpuWorld, shot: &Shot) -> Result<(), GpuError> {
        let light = gpu.params("light", bytemuck::bytes_of(&LightInfo::new(&shot.light)));
        self.prepare(gpu, world, shot, &light)?;
        let cache = self.caches.last().expect("prepared above");
        let info = info(gpu, &self.options, cache, 0);
        self.frames
            .frame_with(gpu, world, shot, &[&info, &cache.table, &cache.requests])?;
        let args = self.args.get(gpu, world, Loop::Hierarchy, true)?;
        let update = self.update.get(gpu, world, Loop::Hierarchy, true)?;
        gpu.checked(|| {
            let buffers = [
                &light,
                &info,
                &cache.table,
                &cache.requests,
                &self.no_boxes,
                &cache.args,
            ];
            let args_group = self.args.group1(gpu, &buffers);
            let update_group = self.update.group1(gpu, &buffers[..5]);
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_compute_pass(&Default::default());
                pass.set_bind_group(0, world.bind_group(), &[]);
                pass.set_pipeline(&args);
                pass.set_bind_group(1, &args_group, &[]);
                pass.dispatch_workgroups(1, 1, 1);
            }
            {
                // A pass of its own: the dispatch reads what the one before wrote.
                let mut pass = enc.begin_compute_pass(&Default::default());
                pass.set_bind_group(0, world.bind_group(), &[]);
                pass.set_pipeline(&update);
                pass.set_bind_group(1, &update_group, &[]);
                pass.dispatch_workgroups_indirect(&cache.args, 0);
            }
            gpu.queue.submit([enc.finish()]);
        })
    }

    fn radiance(&self, gpu: &Gpu) -> Result<Radiance, GpuError> {
        self.frames.radiance(gpu)
    }
}

/// The parameters of a frame of `cache` with `boxes` boxes to invalidate.
fn info(gpu: &Gpu, options: &IrradianceOptions, cache: &Cache, boxes: u32) -> wgpu::Buffer {
    let info = IrradianceInfo {
        stamp: cache.stamp,
        mask: (cache.slots - 1) as u32,
        max_requests: (cache.slots as u32).min(MAX_REQUESTS),
        budget: options.samples_per_frame(cache.basis.sun.is_some()),
        seed: cache.basis.seed,
        boxes,
        _pad0: 0,
        _pad1: 0,
    };
    gpu.params("irradiance", bytemuck::bytes_of(&info))
}

/// Slots for frames of `pixels`: a power of two, at least [`MIN_SLOTS`] and two per pixel
/// (a frame keys at most two per pixel, though far fewer faces than pixels are seen in
/// practice), and at most what one binding holds: 4 Mi slots, 128 MiB, for 1920×1080.
fn slots_for(gpu: &Gpu, pixels: u64) -> Result<u64, GpuError> {
    let slots = (2 * pixels).next_power_of_two().max(MIN_SLOTS);
    let bytes = slots * u64::from(WORDS) * 4;
    let limits = gpu.device.limits();
    let limit = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
    if bytes > limit {
        return Err(GpuError::Unsupported(format!(
            "an irradiance cache for {pixels} pixels needs {bytes} bytes, over this device's {limit}-byte storage binding"
        )));
    }
    Ok(slots)
}

/// An empty cache of `slots` slots for `basis`.
fn allocate(gpu: &Gpu, basis: Basis, slots: u64) -> Result<Cache, GpuError> {
    let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
    let table = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("irradiance table"),
        size: slots * u64::from(WORDS) * 4,
        usage: storage,
        mapped_at_creation: false,
    });
    let requests = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("irradiance requests"),
        size: (u64::from(LIST) + slots.min(u64::from(MAX_REQUESTS))) * 4,
        usage: storage,
        mapped_at_creation: false,
    });
    let args = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("irradiance dispatch"),
        size: 16,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
        mapped_at_creation: false,
    });
    // New buffers are zeroed: every slot empty, every counter zero.
    Ok(Cache {
        basis,
        slots,
        table,
        requests,
        args,
        generation: 0,
        stamp: 0,
        keyed_bound: 0,
    })
}

/// The boxes (pairs of `[lo, hi]` voxel corners, inclusive, as `vec4<i32>`) within
/// [`BOUNCE_DISTANCE`] of the changed chunks `chunks` of a world of `dims` chunks: one per
/// chunk, or per 4³ chunks when there are too many, or a single bounding box.
fn changed_boxes(dims: [u32; 3], chunks: &[u32]) -> Vec<[i32; 4]> {
    let reach = BOUNCE_DISTANCE as i32;
    let coords = |c: u32| [c % dims[0], c / dims[0] % dims[1], c / (dims[0] * dims[1])].map(|v| v as i32);
    let boxes_of = |edge: i32| -> BTreeSet<[i32; 3]> { chunks.iter().map(|&c| coords(c).map(|v| v / edge)).collect() };
    let as_boxes = |set: BTreeSet<[i32; 3]>, edge: i32| -> Vec<[i32; 4]> {
        let size = 16 * edge;
        set.into_iter()
            .flat_map(|g| {
                let lo = g.map(|v| v * size - reach);
                let hi = g.map(|v| v * size + size - 1 + reach);
                [[lo[0], lo[1], lo[2], 0], [hi[0], hi[1], hi[2], 0]]
            })
            .collect()
    };
    let single = boxes_of(1);
    if single.len() <= MAX_BOXES {
        return as_boxes(single, 1);
    }
    let grouped = boxes_of(4);
    if grouped.len() <= MAX_BOXES {
        return as_boxes(grouped, 4);
    }
    let (mut lo, mut hi) = ([i32::MAX; 3], [i32::MIN; 3]);
    for c in chunks {
        let c = coords(*c);
        for a in 0..3 {
            lo[a] = lo[a].min(c[a] * 16 - reach);
            hi[a] = hi[a].max(c[a] * 16 + 15 + reach);
        }
    }
    vec![[lo[0], lo[1], lo[2], 0], [hi[0], hi[1], hi[2], 0]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn changed_boxes_cover_the_chunks_and_the_bounce_distance() {
        let dims = [8, 4, 8];
        let b = changed_boxes(dims, &[1 + 8 * 2]);
        assert_eq!(b, vec![[16 - 32, 32 - 32, -32, 0], [31 + 32, 47 + 32, 15 + 32, 0]]);
        // Many chunks merge into groups of 4³, then into one box.
        let dims = [16, 4, 8];
        let many: Vec<u32> = (0..16 * 4 * 8).collect();
        let b = changed_boxes(dims, &many);
        assert_eq!(b.len(), 2 * 4 * 2);
        let dims = [64, 16, 64];
        let spread: Vec<u32> = (0..64 * 16 * 64).step_by(3).collect();
        let b = changed_boxes(dims, &spread);
        assert_eq!(
            b,
            vec![
                [-32, -32, -32, 0],
                [64 * 16 - 1 + 32, 16 * 16 - 1 + 32, 64 * 16 - 1 + 32, 0]
            ]
        );
    }
}

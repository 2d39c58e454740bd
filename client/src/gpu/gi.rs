//! [`Gi`]: the paper's global illumination pipeline (`gi`; docs/RENDERING.md §3c), on the
//! mirrored world buffers.
//!
//! Each frame runs the passes of [`GiPass::ALL`] in order: the atmosphere table (when a
//! history starts), the jittered first hit, the long-term TAA's gather, the ray queue,
//! one secondary path per queued pixel into the sample ring, the projection of the ring's
//! samples into this frame's 8×8 regions and their refinement, spatial resampling with a
//! visibility ray and the sun, the bilateral denoiser, and the TAA merge. A history (the
//! TAA, the ring, the cameras of earlier frames) is kept per (size, light, seed, world
//! size); the camera may move and the world may change within it: the chunks a change
//! touched ([`GpuWorld::changes_since`]) drop or shorten the history of the light on and
//! near them. The two large arrays are split across bindings where one is too small.

use super::context::{Gpu, GpuError};
use super::params::{FrameInfo, GiInfo, LightInfo};
use super::pipeline::{PassPipelines, dispatch_2d};
use super::render::{CameraRays, check_frame_size};
use super::shaders::{GiSplit, Loop, NO_ENTITY, Pass};
use super::temporal::Temporal;
use super::world::{GpuWorld, new_part};
use crate::light::Light;
use crate::light::hdr::Radiance;
use naadf_world::camera::Camera;
use naadf_world::fingerprint::ChunkChanges;
use std::collections::{HashMap, VecDeque};

/// Frames the long-term TAA keeps a sample of, per pixel.
pub const TAA_SLOTS: u32 = 32;
/// Frames whose cameras are kept: how far back the sample ring's samples may come from.
pub const CAMERA_HISTORY: u32 = 128;
/// Edge of the atmosphere table in texels.
pub const LUT_SIZE: u32 = 256;
/// Sample slots per region in the projection.
pub const BUCKET_SLOTS: u32 = 32;
/// Samples a region keeps after refinement.
pub const MAX_KEPT: u32 = 7;
/// The ray queue traces a pixel whose TAA holds enough samples one frame in this many, and
/// every frame a pixel with none (docs/RENDERING.md §3c: the paper's 4 lets resampled
/// light, darker than the truth where nearby walls occlude, make up three frames in four).
pub const QUEUE_PERIOD: u32 = 2;
/// `vec4<u32>` per sample in the ring.
pub const RING_VEC4: u32 = 3;
/// After a world change, the TAA and the ring use samples from before it for at most this
/// many more frames near it (or everywhere, after a change of the materials), so that light
/// that changed (an emitter removed or added) updates within them.
pub const EDIT_HISTORY_FRAMES: u32 = 8;
/// How near a changed chunk (in chunks, along each axis) the light counts as changed: the
/// TAA and ring samples of surfaces there follow [`EDIT_HISTORY_FRAMES`]. Samples of the
/// changed chunks themselves, and ring samples whose light came from them, are dropped at
/// once; history elsewhere is kept.
pub const CHANGE_REACH: u32 = 2;
/// Above this many changed chunks in one frame, the change counts as global.
pub const MAX_LOCAL_CHANGES: usize = 4096;
/// Word offset of the secondary rays' indirect arguments in the control buffer.
pub const CONTROL_TRACE_ARGS: u32 = 0;
/// Word offset of the projection's indirect arguments in the control buffer.
pub const CONTROL_PROJECT_ARGS: u32 = 4;

/// Control words at the start of `words`: indirect arguments and ring bookkeeping, then the
/// sample count of each of the last [`CAMERA_HISTORY`] frames.
pub const CONTROL_WORDS: u32 = 16 + CAMERA_HISTORY;
/// vec4 words per camera in `mem`.
const CAM_VEC4: usize = 5;
/// Bytes per pixel of the TAA.
const TAA_PIXEL_BYTES: u64 = TAA_SLOTS as u64 * 8;
/// Ring samples per pixel.
const RING_PER_PIXEL: u64 = 2;
/// Words of the entity pose table at the end of `words`: per TAA slot, four record words
/// per entity id (shaders/gi_entities.wgsl).
const POSE_TABLE_WORDS: u64 = TAA_SLOTS as u64 * NO_ENTITY as u64 * 4;
/// The smallest part of a split array: the cameras (written from the CPU) fit in the first.
const MIN_PART_BYTES: u64 = 1 << 16;
/// Parameter buffers at the start of the GI passes' group 1: frame, light, GI state.
const GI_PARAMS: u32 = 3;

/// One pass of the pipeline, in frame order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GiPass {
    /// Fills the atmosphere table (first frame of a history only).
    Atmosphere,
    /// The jittered first hit and its mirror chain.
    FirstHit,
    /// This frame's slot of the entity pose table starts empty.
    PosesClear,
    /// The entities' poses into this frame's slot, from the chunks' instance records.
    Poses,
    /// The long-term TAA's gather of earlier frames' samples.
    Taa,
    /// Which pixels trace a secondary ray, compacted per region.
    Queue,
    /// The queue's layout, the ring's bookkeeping and the indirect arguments.
    QueueScan,
    /// One secondary path per queued pixel, into the sample ring.
    Trace,
    /// The ring's samples counted into this frame's regions.
    Project,
    /// The winning samples stored in their regions' slots.
    ProjectStore,
    /// At most [`MAX_KEPT`] levelled samples per region.
    Refine,
    /// Spatial resampling, the visibility ray and the sun.
    Resample,
    /// The denoiser along x.
    DenoiseX,
    /// The denoiser along y.
    DenoiseY,
    /// This frame's colour into the TAA, and the result.
    Merge,
}

impl GiPass {
    /// Every pass, in frame order.
    pub const ALL: [GiPass; 15] = [
        GiPass::Atmosphere,
        GiPass::FirstHit,
        GiPass::PosesClear,
        GiPass::Poses,
        GiPass::Taa,
        GiPass::Queue,
        GiPass::QueueScan,
        GiPass::Trace,
        GiPass::Project,
        GiPass::ProjectStore,
        GiPass::Refine,
        GiPass::Resample,
        GiPass::DenoiseX,
        GiPass::DenoiseY,
        GiPass::Merge,
    ];

    /// The WGSL entry point.
    pub fn entry(self) -> &'static str {
        match self {
            GiPass::Atmosphere => "gi_atmosphere",
            GiPass::FirstHit => "gi_first_hit",
            GiPass::PosesClear => "gi_poses_clear",
            GiPass::Poses => "gi_poses",
            GiPass::Taa => "gi_taa",
            GiPass::Queue => "gi_queue",
            GiPass::QueueScan => "gi_queue_scan",
            GiPass::Trace => "gi_trace",
            GiPass::Project => "gi_project",
            GiPass::ProjectStore => "gi_project_store",
            GiPass::Refine => "gi_refine",
            GiPass::Resample => "gi_resample",
            GiPass::DenoiseX => "gi_denoise_x",
            GiPass::DenoiseY => "gi_denoise_y",
            GiPass::Merge => "gi_merge",
        }
    }
}

/// Where each array of `mem` starts (vec4 words) for `p` pixels and `r` regions, with the
/// ring last; and the start of the queued pixels in `words`.
#[derive(Clone, Copy, Debug)]
struct Layout {
    offsets: [u32; 13],
    /// vec4 words of `mem` before the ring.
    ring_start: u64,
    /// Words of `words`.
    words: u64,
}

impl Layout {
    fn new(p: u64, r: u64) -> Self {
        let sizes = [
            u64::from(LUT_SIZE * LUT_SIZE), // lut
            p,                              // gbuf
            p,                              // gmat
            p,                              // emitted
            2 * p,                          // taa_info
            p,                              // illum
            p,                              // illum2
            p,                              // result
            r * u64::from(MAX_KEPT) * 2,    // refined
            3 * r,                          // region_info
            p,                              // own
        ];
        let mut offsets = [0u32; 13];
        let mut at = CAMERA_HISTORY as u64 * CAM_VEC4 as u64;
        for (k, size) in sizes.iter().enumerate() {
            offsets[k] = at as u32;
            at += size;
        }
        offsets[11] = at as u32; // ring
        let queue = u64::from(CONTROL_WORDS) + 2 * r;
        offsets[12] = queue as u32;
        Layout {
            offsets,
            ring_start: at,
            words: queue + 64 * r + POSE_TABLE_WORDS,
        }
    }
}

/// Index of the TAA's sums and ranges in [`Layout::offsets`].
const TAA_INFO: usize = 4;
/// Index of the result array in [`Layout::offsets`].
const RESULT: usize = 7;
/// Bytes of indirect arguments at the start of `words`, copied each frame into a buffer of
/// their own (a dispatch cannot read its arguments from a buffer it binds).
const ARGS_BYTES: u64 = 32;

/// What a history is of: when any of it changes, the history restarts.
#[derive(Clone, Debug, PartialEq)]
struct Subject {
    size: (u32, u32),
    light: Light,
    seed: u32,
    /// The world's size in chunks (the change marks are per chunk).
    chunks: [u32; 3],
}

/// A camera of an earlier frame and the jitter it was rendered with.
#[derive(Clone, Copy, Debug)]
struct Past {
    camera: Camera,
    jitter: [f32; 2],
}

/// The buffers and state of a running GI history.
pub struct GiHistory {
    subject: Subject,
    layout: Layout,
    /// How `mem` and `taa` are split across bindings.
    split: GiSplit,
    /// `words` and `buckets` (docs in gi_common.wgsl).
    words: wgpu::Buffer,
    buckets: wgpu::Buffer,
    /// The parts of `mem` and of `taa`.
    mem: Vec<wgpu::Buffer>,
    taa: Vec<wgpu::Buffer>,
    /// Per chunk, the first frame after its newest change and after the newest change
    /// within [`CHANGE_REACH`] of it (0: none); `marks` on the device.
    marks: Vec<[u32; 2]>,
    changes: wgpu::Buffer,
    /// The indirect arguments, copied from `words`.
    args: wgpu::Buffer,
    ring_capacity: u32,
    /// Frames rendered so far.
    frames: u32,
    /// The cameras of this frame and earlier ones, newest first.
    cameras: VecDeque<Past>,
    /// The world generation of the last frame.
    generation: u64,
    /// The first frame after the newest change of the materials or of more chunks than
    /// are marked one by one (0: none).
    edit_frame: u32,
    /// The first frame after the newest change of any chunk, entity moves included (0:
    /// none).
    change_frame: u32,
}

impl GiHistory {
    /// Marks `changed` chunks, and those within [`CHANGE_REACH`] of them, as changed
    /// before this frame, and uploads the marks that moved.
    fn mark(&mut self, gpu: &Gpu, changed: &[u32]) {
        let [cx, cy, cz] = self.subject.chunks;
        let reach = CHANGE_REACH as i64;
        // The lowest and one past the highest mark set.
        let (mut lo, mut hi) = (usize::MAX, 0);
        let mut set = |i: usize, k: usize, marks: &mut Vec<[u32; 2]>| {
            marks[i][k] = self.frames;
            (lo, hi) = (lo.min(i), hi.max(i + 1));
        };
        for &c in changed {
            let c = c as i64;
            let at = [
                c % i64::from(cx),
                c / i64::from(cx) % i64::from(cy),
                c / (i64::from(cx) * i64::from(cy)),
            ];
            set(c as usize, 0, &mut self.marks);
            for z in (at[2] - reach).max(0)..=(at[2] + reach).min(i64::from(cz) - 1) {
                for y in (at[1] - reach).max(0)..=(at[1] + reach).min(i64::from(cy) - 1) {
                    for x in (at[0] - reach).max(0)..=(at[0] + reach).min(i64::from(cx) - 1) {
                        let i = x + i64::from(cx) * (y + i64::from(cy) * z);
                        set(i as usize, 1, &mut self.marks);
                    }
                }
            }
        }
        if lo < hi {
            gpu.queue
                .write_buffer(&self.changes, lo as u64 * 8, bytemuck::cast_slice(&self.marks[lo..hi]));
        }
    }
}

/// The GI renderer: a history per (size, light, seed, world size).
pub struct Gi {
    /// The passes' pipelines, per split of the history's arrays.
    pipes: HashMap<GiSplit, Vec<PassPipelines>>,
    /// The largest part of a split array, in bytes.
    max_part_bytes: u64,
    history: Option<GiHistory>,
    /// Whether the bilateral denoiser runs (default on).
    pub denoise: bool,
    /// Whether each pass's GPU time is measured ([`Gi::pass_times`]; needs the adapter's
    /// timestamp queries).
    pub profile: bool,
    timer: Option<Timer>,
}

/// Timestamps at the start and end of every pass of a frame.
struct Timer {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    /// Which passes the last frame ran.
    ran: [bool; GiPass::ALL.len()],
}

/// Timestamps per frame: two per pass.
const TIMESTAMPS: u32 = 2 * GiPass::ALL.len() as u32;

/// The jitter of frame `frame` in the pixel: point `frame mod 32` of a 32-point (0, 5, 2)-net
/// (the van der Corput sequence in x, the second Sobol dimension in y: Halton's base 2 and
/// its base-2 partner, digitally shifted by ½), each point moved to the centre of its 1/32
/// stratum. Every axis is
/// then stratified exactly and the mean jitter is the pixel's centre. The reference's
/// Halton (3, 7) over 32 frames is not: its mean y is 0.459, which shifted every edge by
/// 0.04 pixel and brightened the row below a bright horizon (docs/RENDERING.md §3c).
fn jitter(frame: u32) -> [f32; 2] {
    let i = frame % TAA_SLOTS;
    // Both dimensions as 32-bit fractions: x reverses the bits of i; y XORs the Sobol
    // direction numbers of the set bits of i (v₁ = 2⁻¹, v_{k+1} = v_k ⊕ v_k / 2).
    let x = i.reverse_bits();
    let (mut y, mut v, mut rest) = (0u32, 1u32 << 31, i);
    while rest > 0 {
        if rest & 1 == 1 {
            y ^= v;
        }
        rest >>= 1;
        v ^= v >> 1;
    }
    // A digital shift by ½ (XOR of the top bit) keeps the net and puts the first point,
    // the only one of a single frame, at the pixel's centre.
    let half_stratum = 0.5 / TAA_SLOTS as f32;
    [x, y].map(|b| ((b ^ 1 << 31) as f64 / 4_294_967_296.0) as f32 + half_stratum)
}

impl Gi {
    /// Prepares the passes (pipelines are built on first use). The history's large arrays
    /// are split across bindings at the adapter's storage-binding limit.
    pub fn new(gpu: &Gpu) -> Self {
        Self::with_max_part_bytes(gpu, gpu.limits.max_storage_buffer_binding_size)
    }

    /// As [`Gi::new`], with parts of at most `max_part_bytes` (rounded down to a power of
    /// two, at least 64 KiB, at most the adapter's limit): tests use it to exercise splitting.
    pub fn with_max_part_bytes(gpu: &Gpu, max_part_bytes: u64) -> Self {
        let limit = gpu
            .limits
            .max_storage_buffer_binding_size
            .min(gpu.limits.max_buffer_size)
            .min(max_part_bytes)
            .max(MIN_PART_BYTES);
        Gi {
            pipes: HashMap::new(),
            max_part_bytes: 1 << (63 - limit.leading_zeros()),
            history: None,
            denoise: true,
            profile: false,
            timer: None,
        }
    }

    /// Frames in the current history.
    pub fn frames(&self) -> u32 {
        self.history.as_ref().map_or(0, |h| h.frames)
    }

    /// The storage bindings of the current history's own group: more than the fewest (8)
    /// when its arrays are split across bindings.
    pub fn bindings(&self) -> Option<u32> {
        self.history.as_ref().map(|h| h.split.bindings())
    }

    /// Swaps the history with `other` (one history per camera stream).
    pub fn swap_history(&mut self, other: &mut Option<GiHistory>) {
        std::mem::swap(&mut self.history, other);
    }

    /// The GPU milliseconds of each pass of the last frame, in frame order, when
    /// [`Gi::profile`] is on and the adapter has timestamp queries.
    pub fn pass_times(&self, gpu: &Gpu) -> Option<Vec<(GiPass, f64)>> {
        let t = self.timer.as_ref().filter(|_| self.profile && self.history.is_some())?;
        let bytes = gpu.read_buffer(&t.resolved, u64::from(TIMESTAMPS) * 8).ok()?;
        let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(&bytes);
        let ns_per_tick = f64::from(gpu.queue.get_timestamp_period());
        Some(
            GiPass::ALL
                .iter()
                .enumerate()
                .filter(|&(k, _)| t.ran[k])
                .map(|(k, &p)| {
                    (
                        p,
                        ticks[2 * k + 1].saturating_sub(ticks[2 * k]) as f64 * ns_per_tick * 1e-6,
                    )
                })
                .collect(),
        )
    }

    /// How many earlier frames' samples the TAA merged into each pixel of the last frame
    /// (row by row): how converged the pixel is.
    pub fn history_lengths(&self, gpu: &Gpu) -> Result<Vec<u32>, GpuError> {
        let info = self.read_pixels(gpu, TAA_INFO, 2)?;
        Ok(info.iter().step_by(2).map(|v| v[3] as u32).collect())
    }

    /// The per-pixel array `array` of [`Layout::offsets`] (`vec4s` vec4 words per pixel)
    /// of the current history; an error before the first frame.
    fn read_pixels(&self, gpu: &Gpu, array: usize, vec4s: u64) -> Result<Vec<[f32; 4]>, GpuError> {
        let h = self
            .history
            .as_ref()
            .ok_or_else(|| GpuError::Readback("no gi frame was rendered".into()))?;
        let (w, ht) = h.subject.size;
        let bytes = gpu.read_parts(
            &h.mem,
            1 << h.split.part_bytes_shift,
            u64::from(h.layout.offsets[array]) * 16,
            u64::from(w) * u64::from(ht) * vec4s * 16,
        )?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// The bytes of each array of the current history (docs/RENDERING.md §3c), largest
    /// first; `None` before the first frame.
    pub fn memory(&self) -> Option<Vec<(&'static str, u64)>> {
        let h = self.history.as_ref()?;
        let o = &h.layout.offsets;
        let vec4s = |k: usize| u64::from(o[k + 1] - o[k]) * 16;
        let mut out = vec![
            ("cameras", u64::from(o[0]) * 16),
            ("atmosphere table", vec4s(0)),
            ("first-hit surfaces", vec4s(1)),
            ("first-hit materials", vec4s(2)),
            ("first-hit light", vec4s(3)),
            ("TAA sums and ranges", vec4s(4)),
            ("incoming light", vec4s(5)),
            ("denoiser intermediate", vec4s(6)),
            ("result", vec4s(7)),
            ("refined samples", vec4s(8)),
            ("region statistics", vec4s(9)),
            ("own samples", vec4s(10)),
            ("sample ring", u64::from(h.ring_capacity) * u64::from(RING_VEC4) * 16),
            ("queue and control", (h.layout.words - POSE_TABLE_WORDS) * 4),
            ("entity poses", POSE_TABLE_WORDS * 4),
            ("region buckets", h.buckets.size()),
            ("TAA samples", h.taa.iter().map(wgpu::Buffer::size).sum()),
        ];
        out.sort_by_key(|&(_, bytes)| std::cmp::Reverse(bytes));
        Some(out)
    }
}

impl Temporal for Gi {
    /// Renders the next frame of `camera`'s view of `world`. A new size, light, seed or
    /// world size starts a new history; a camera move or a world change does not: the
    /// history is reprojected, light on a changed chunk restarts, and light from before a
    /// change near it fades out within [`EDIT_HISTORY_FRAMES`].
    fn frame(
        &mut self,
        gpu: &Gpu,
        world: &GpuWorld,
        camera: &Camera,
        size: (u32, u32),
        light: &Light,
        seed: u32,
    ) -> Result<(), GpuError> {
        let pixels = check_frame_size(gpu, size, 0)?;
        let now_rays = CameraRays::new(camera, size)?;
        let (rx, ry) = (size.0.div_ceil(8), size.1.div_ceil(8));
        let regions = u64::from(rx) * u64::from(ry);
        let layout = Layout::new(pixels, regions);
        let ring = pixels * RING_PER_PIXEL;
        let mem_bytes = (layout.ring_start + ring * u64::from(RING_VEC4)) * 16;
        let taa_bytes = pixels * TAA_PIXEL_BYTES;
        let part = self.max_part_bytes;
        let split = GiSplit {
            part_bytes_shift: part.trailing_zeros(),
            mem_parts: mem_bytes.div_ceil(part) as u32,
            taa_parts: taa_bytes.div_ceil(part) as u32,
        };
        let bindings = world.split().storage_bindings() + split.bindings();
        let allowed = gpu.limits.max_storage_buffers_per_shader_stage;
        if bindings > allowed || mem_bytes / 16 > u64::from(u32::MAX) {
            return Err(GpuError::Unsupported(format!(
                "frame size {}x{}: the GI history ({} MiB) needs {bindings} storage bindings of at most {} MiB with the world's; the adapter allows {allowed} per shader stage",
                size.0,
                size.1,
                (mem_bytes + taa_bytes) >> 20,
                part >> 20
            )));
        }
        let pipes = self.pipes.entry(split).or_insert_with(|| {
            // Three parameter buffers (frame, light, GI state), then the storage buffers,
            // of which only the change marks are read-only.
            let storage: Vec<bool> = (GI_PARAMS..split.bindings())
                .map(|b| b == GiSplit::CHANGES_BINDING)
                .collect();
            GiPass::ALL
                .iter()
                .map(|&p| PassPipelines::new(gpu, Pass::Gi(p, split), GI_PARAMS, &storage))
                .collect()
        });
        let mut pipelines = Vec::with_capacity(pipes.len());
        for p in pipes.iter_mut() {
            pipelines.push(p.get(gpu, world, Loop::Hierarchy, true)?);
        }
        let chunks = world.chunk_dims();
        let subject = Subject {
            size,
            light: *light,
            seed,
            chunks,
        };
        let chunk_count = chunks.iter().map(|&c| c as usize).product::<usize>();
        let storage_buffer = |label: &str, bytes: u64| new_part(&gpu.device, label, bytes);
        let parts = |label: &str, bytes: u64| -> Vec<wgpu::Buffer> {
            (0..bytes.div_ceil(part))
                .map(|p| storage_buffer(label, (bytes - p * part).min(part)))
                .collect()
        };
        let h = match self.history.take() {
            Some(h) if h.subject == subject => h,
            _ => GiHistory {
                subject,
                split,
                words: storage_buffer("gi words", layout.words * 4),
                buckets: storage_buffer("gi buckets", regions * (2 * u64::from(BUCKET_SLOTS) + 12) * 4),
                mem: parts("gi mem", mem_bytes),
                taa: parts("gi taa", taa_bytes),
                marks: vec![[0; 2]; chunk_count],
                changes: storage_buffer("gi chunk changes", (chunk_count as u64 * 8).max(16)),
                layout,
                args: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("gi indirect args"),
                    size: ARGS_BYTES,
                    usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
                ring_capacity: ring as u32,
                frames: 0,
                cameras: VecDeque::new(),
                generation: world.generation(),
                edit_frame: 0,
                change_frame: 0,
            },
        };
        let h = self.history.insert(h);
        if h.generation != world.generation() {
            match world.changes_since(h.generation) {
                ChunkChanges::Chunks(list) if list.is_empty() => {}
                ChunkChanges::Chunks(list) if list.len() <= MAX_LOCAL_CHANGES => {
                    h.mark(gpu, &list);
                    h.change_frame = h.frames;
                }
                _ => (h.edit_frame, h.change_frame) = (h.frames, h.frames),
            }
            h.generation = world.generation();
        }
        let jit = jitter(h.frames);
        h.cameras.push_front(Past {
            camera: *camera,
            jitter: jit,
        });
        h.cameras.truncate(CAMERA_HISTORY as usize);
        // Every camera relative to this frame's integer position, so that nothing on the
        // device subtracts two large coordinates.
        let floor_now = now_rays.int.map(f64::from);
        let mut cams = vec![[0f32; 4]; CAMERA_HISTORY as usize * CAM_VEC4];
        for (age, past) in h.cameras.iter().enumerate() {
            let relative = Camera {
                pos: std::array::from_fn(|a| past.camera.pos[a] - floor_now[a]),
                ..past.camera
            };
            let r = CameraRays::new(&relative, size)?;
            let pos: [f32; 3] = std::array::from_fn(|a| r.int[a] as f32 + r.frac[a]);
            let origin: [f32; 3] = std::array::from_fn(|a| r.int[a] as f32);
            let c = &mut cams[age * CAM_VEC4..(age + 1) * CAM_VEC4];
            c[0] = [pos[0], pos[1], pos[2], past.jitter[0]];
            c[1] = [r.forward[0], r.forward[1], r.forward[2], past.jitter[1]];
            c[2] = [r.right[0], r.right[1], r.right[2], 0.0];
            c[3] = [r.up[0], r.up[1], r.up[2], 0.0];
            c[4] = [origin[0], origin[1], origin[2], 0.0];
        }
        gpu.queue.write_buffer(&h.mem[0], 0, bytemuck::cast_slice(&cams));
        let info = GiInfo {
            frame: h.frames,
            taa_slot: h.frames % TAA_SLOTS,
            taa_valid: h.frames.min(TAA_SLOTS - 1),
            edit_frame: h.edit_frame,
            change_frame: h.change_frame,
            jitter_x: jit[0],
            jitter_y: jit[1],
            regions_x: rx,
            regions_y: ry,
            ring_capacity: h.ring_capacity,
            denoise: u32::from(self.denoise),
            off_own: h.layout.offsets[10],
            off_lut: h.layout.offsets[0],
            off_gbuf: h.layout.offsets[1],
            off_gmat: h.layout.offsets[2],
            off_emitted: h.layout.offsets[3],
            off_taa_info: h.layout.offsets[4],
            off_illum: h.layout.offsets[5],
            off_illum2: h.layout.offsets[6],
            off_result: h.layout.offsets[7],
            off_refined: h.layout.offsets[8],
            off_region_info: h.layout.offsets[9],
            off_ring: h.layout.offsets[11],
            off_queue_list: h.layout.offsets[12],
        };
        let frame = FrameInfo::new(&now_rays, size, seed, h.frames, h.frames > 0);
        let params = [
            gpu.params("frame", bytemuck::bytes_of(&frame)),
            gpu.params("light", bytemuck::bytes_of(&LightInfo::new(light))),
            gpu.params("gi", bytemuck::bytes_of(&info)),
        ];
        let buffers: Vec<&wgpu::Buffer> = params
            .iter()
            .chain([&h.words, &h.buckets, &h.changes])
            .chain(&h.mem)
            .chain(&h.taa)
            .collect();
        let pixel_groups = (size.0.div_ceil(8), size.1.div_ceil(8));
        let (control, args) = (&h.words, &h.args);
        let first = h.frames == 0;
        let denoise = self.denoise;
        if self.profile && self.timer.is_none() && gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY) {
            self.timer = Some(Timer {
                queries: gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("gi pass times"),
                    ty: wgpu::QueryType::Timestamp,
                    count: TIMESTAMPS,
                }),
                resolved: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("gi pass times"),
                    size: u64::from(TIMESTAMPS) * 8,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                }),
                ran: [false; GiPass::ALL.len()],
            });
        }
        let timer = self.timer.as_mut().filter(|_| self.profile);
        // The table is filled when a history starts; the denoiser runs when asked for.
        let runs = GiPass::ALL.map(|pass| match pass {
            GiPass::Atmosphere => first,
            GiPass::DenoiseX | GiPass::DenoiseY => denoise,
            _ => true,
        });
        gpu.checked(|| {
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            for (k, &pass) in GiPass::ALL.iter().enumerate() {
                if !runs[k] {
                    continue;
                }
                if pass == GiPass::Trace {
                    enc.copy_buffer_to_buffer(control, 0, args, 0, ARGS_BYTES);
                }
                let group = pipes[k].group1(gpu, &buffers);
                // One compute pass per dispatch, so that the copy of the indirect arguments
                // can sit between two of them.
                let mut cp = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some(pass.entry()),
                    timestamp_writes: timer.as_ref().map(|t| wgpu::ComputePassTimestampWrites {
                        query_set: &t.queries,
                        beginning_of_pass_write_index: Some(2 * k as u32),
                        end_of_pass_write_index: Some(2 * k as u32 + 1),
                    }),
                });
                cp.set_pipeline(&pipelines[k]);
                cp.set_bind_group(0, world.bind_group(), &[]);
                cp.set_bind_group(1, &group, &[]);
                match pass {
                    GiPass::Atmosphere => cp.dispatch_workgroups(LUT_SIZE / 8, LUT_SIZE / 8, 1),
                    GiPass::QueueScan => cp.dispatch_workgroups(1, 1, 1),
                    GiPass::Trace => cp.dispatch_workgroups_indirect(args, u64::from(CONTROL_TRACE_ARGS) * 4),
                    GiPass::Project | GiPass::ProjectStore => {
                        cp.dispatch_workgroups_indirect(args, u64::from(CONTROL_PROJECT_ARGS) * 4)
                    }
                    GiPass::Refine => cp.dispatch_workgroups(regions.div_ceil(64) as u32, 1, 1),
                    GiPass::PosesClear => cp.dispatch_workgroups(NO_ENTITY.div_ceil(64), 1, 1),
                    GiPass::Poses => {
                        let (x, y) = dispatch_2d(chunk_count.div_ceil(64) as u32);
                        cp.dispatch_workgroups(x, y, 1)
                    }
                    _ => cp.dispatch_workgroups(pixel_groups.0, pixel_groups.1, 1),
                }
            }
            if let Some(t) = timer {
                enc.resolve_query_set(&t.queries, 0..TIMESTAMPS, &t.resolved, 0);
                t.ran = runs;
            }
            gpu.queue.submit([enc.finish()]);
        })?;
        h.frames += 1;
        Ok(())
    }

    /// The newest result as linear radiance; an error before the first frame.
    fn radiance(&self, gpu: &Gpu) -> Result<Radiance, GpuError> {
        let px = self.read_pixels(gpu, RESULT, 1)?;
        let (w, ht) = self.history.as_ref().map_or((0, 0), |h| h.subject.size);
        Ok(Radiance {
            width: w,
            height: ht,
            rgb: px.iter().map(|p| [p[0], p[1], p[2]]).collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 32 jitters are a (0, 5, 2)-net centred in its strata: every elementary box of
    /// area 1/32 (1/32 × 1, 1/16 × 1/2, …, 1 × 1/32) holds exactly one, and the mean is the
    /// pixel's centre; the sequence restarts with the TAA's slots.
    #[test]
    fn the_jitters_stratify_the_pixel() {
        let points: Vec<[f32; 2]> = (0..TAA_SLOTS).map(jitter).collect();
        for a in 0..=5u32 {
            let (nx, ny) = (1u32 << a, 1u32 << (5 - a));
            let mut boxes = vec![0u32; 32];
            for p in &points {
                assert!(p.iter().all(|j| (0.0..1.0).contains(j)), "{p:?}");
                boxes[(p[0] * nx as f32) as usize + nx as usize * (p[1] * ny as f32) as usize] += 1;
            }
            assert!(boxes.iter().all(|&n| n == 1), "{nx} × {ny} boxes: {boxes:?}");
        }
        for axis in 0..2 {
            let mean = points.iter().map(|p| f64::from(p[axis])).sum::<f64>() / 32.0;
            assert!((mean - 0.5).abs() < 1e-6, "axis {axis}: mean {mean}");
        }
        assert_eq!(jitter(TAA_SLOTS), jitter(0));
        assert_eq!(jitter(0), [0.5 + 1.0 / 64.0, 0.5 + 1.0 / 64.0]);
    }
}

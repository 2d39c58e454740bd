//! [`Gi`]: the paper's global illumination pipeline (`gi`; docs/RENDERING.md §3c), on the
//! mirrored world buffers.
//!
//! Each frame runs the passes of [`GiPass::ALL`] in order: the atmosphere table (when a
//! history starts), the jittered first hit, the long-term TAA's gather, the ray queue,
//! one secondary path per queued pixel into the sample ring, the projection of the ring's
//! samples into this frame's 8×8 regions and their refinement, spatial resampling with a
//! visibility ray and the sun, the bilateral denoiser, and the TAA merge. A history (the
//! TAA, the ring, the cameras of earlier frames; [`GiHistory`]) is kept per (size, light,
//! seed, world size); the camera may move and the world may change within it: the chunks
//! a change touched ([`GpuWorld::changes_since`]) drop or shorten the history of the light
//! on and near them. The two large arrays are split across bindings where one is too small.
//!
//! The modules: `passes` (the passes and their WGSL), `memory` (the arrays' layout and
//! split, and the constants the WGSL shares), `history` (what a history keeps and how a
//! frame starts it); this one runs a frame.

mod history;
mod memory;
mod passes;

pub use history::{CHANGE_REACH, GiHistory};
pub use memory::GiSplit;
pub use passes::GiPass;
pub(crate) use passes::gi_pass;

use super::context::{Gpu, GpuError};
use super::pipeline::PassPipelines;
use super::shaders::WgslValue;
use super::shaders::{Loop, NO_ENTITY};
use super::shot::{CameraRays, Shot, check_frame_size};
use super::temporal::Temporal;
use super::world::GpuWorld;
use crate::light::hdr::Radiance;
use history::{ARGS_BYTES, MAX_LOCAL_CHANGES};
use memory::{
    CONTROL_PROJECT_ARGS, CONTROL_TRACE_ARGS, GI_CONSTANTS, LUT_SIZE, Layout, POSE_TABLE_WORDS, Plan, RING_PER_PIXEL,
    RING_VEC4, TAA_PIXEL_BYTES,
};
use std::collections::HashMap;

/// The constants a host of the GI passes needs, by name: those the WGSL shares
/// ([`GI_CONSTANTS`]) and the host side's own (the arrays' sizes, the change rule, the
/// indirect arguments). The browser page takes them from here (`gpu/browser.rs`).
pub(crate) fn host_constants() -> Vec<(&'static str, u64)> {
    let mut out: Vec<(&'static str, u64)> = GI_CONSTANTS
        .iter()
        .filter_map(|&(name, v)| match v {
            WgslValue::U32(v) => Some((name, u64::from(v))),
            _ => None,
        })
        .collect();
    out.extend([
        ("TAA_PIXEL_BYTES", TAA_PIXEL_BYTES),
        ("RING_PER_PIXEL", RING_PER_PIXEL),
        ("POSE_TABLE_WORDS", POSE_TABLE_WORDS),
        ("CHANGE_REACH", u64::from(CHANGE_REACH)),
        ("MAX_LOCAL_CHANGES", MAX_LOCAL_CHANGES as u64),
        ("ARGS_BYTES", ARGS_BYTES),
        ("NO_ENTITY", u64::from(NO_ENTITY)),
    ]);
    out
}

/// The smallest part of a split array: the cameras (written from the CPU) fit in the first.
const MIN_PART_BYTES: u64 = 1 << 16;
/// Parameter buffers at the start of the GI passes' group 1: frame, light, GI state.
const GI_PARAMS: u32 = 3;

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

impl Timer {
    /// The timestamp queries in `slot` when `profile` is on, made on first use where the
    /// adapter has them.
    fn get<'a>(slot: &'a mut Option<Timer>, gpu: &Gpu, profile: bool) -> Option<&'a mut Timer> {
        if profile && slot.is_none() && gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY) {
            *slot = Some(Timer {
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
        slot.as_mut().filter(|_| profile)
    }
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
        let info = self.read_pixels(gpu, |l| l.taa_info, 2)?;
        Ok(info.iter().step_by(2).map(|v| v[3] as u32).collect())
    }

    /// The per-pixel array of `mem` that `array` picks from the [`Layout`] (`vec4s` vec4
    /// words per pixel) of the current history; an error before the first frame.
    fn read_pixels(&self, gpu: &Gpu, array: fn(&Layout) -> u32, vec4s: u64) -> Result<Vec<[f32; 4]>, GpuError> {
        let h = self
            .history
            .as_ref()
            .ok_or_else(|| GpuError::Readback("no gi frame was rendered".into()))?;
        let (w, ht) = h.shot.size;
        let bytes = gpu.read_parts(
            &h.mem,
            1 << h.split.part_bytes_shift,
            u64::from(array(&h.layout)) * 16,
            u64::from(w) * u64::from(ht) * vec4s * 16,
        )?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// The bytes of each array of the current history (docs/RENDERING.md §3c), largest
    /// first; `None` before the first frame.
    pub fn memory(&self) -> Option<Vec<(&'static str, u64)>> {
        let h = self.history.as_ref()?;
        let mut out = h.layout.arrays().to_vec();
        out.extend([
            ("sample ring", u64::from(h.ring_capacity) * u64::from(RING_VEC4) * 16),
            ("queue and control", (h.layout.words - POSE_TABLE_WORDS) * 4),
            ("entity poses", POSE_TABLE_WORDS * 4),
            ("region buckets", h.buckets.size()),
            ("TAA samples", h.taa.iter().map(wgpu::Buffer::size).sum()),
        ]);
        out.sort_by_key(|&(_, bytes)| std::cmp::Reverse(bytes));
        Some(out)
    }

    /// The memory of a `size` frame, checked against the adapter's bindings together with
    /// `world`'s.
    fn plan(&self, gpu: &Gpu, world: &GpuWorld, size: (u32, u32)) -> Result<Plan, GpuError> {
        let plan = Plan::new(size, self.max_part_bytes);
        let bindings = world.split().storage_bindings() + plan.split.bindings();
        let allowed = gpu.limits.max_storage_buffers_per_shader_stage;
        if bindings > allowed || plan.mem_bytes / 16 > u64::from(u32::MAX) {
            return Err(GpuError::Unsupported(format!(
                "frame size {}x{}: the GI history ({} MiB) needs {bindings} storage bindings of at most {} MiB with the world's; the adapter allows {allowed} per shader stage",
                size.0,
                size.1,
                (plan.mem_bytes + plan.taa_bytes) >> 20,
                self.max_part_bytes >> 20
            )));
        }
        Ok(plan)
    }

    /// The pipeline of every pass, in frame order, for the history's arrays split as
    /// `split` and `world`'s buffers.
    fn pipelines(
        &mut self,
        gpu: &Gpu,
        world: &GpuWorld,
        split: GiSplit,
    ) -> Result<Vec<wgpu::ComputePipeline>, GpuError> {
        let pipes = self.pipes.entry(split).or_insert_with(|| {
            // Three parameter buffers (frame, light, GI state), then the storage buffers,
            // of which only the change marks are read-only.
            let storage: Vec<bool> = (GI_PARAMS..split.bindings())
                .map(|b| b == GiSplit::CHANGES_BINDING)
                .collect();
            GiPass::ALL
                .iter()
                .map(|&p| PassPipelines::new(gpu, passes::gi_pass(p, split), GI_PARAMS, &storage))
                .collect()
        });
        pipes
            .iter_mut()
            .map(|p| p.get(gpu, world, Loop::Hierarchy, true))
            .collect()
    }
}

impl Temporal for Gi {
    /// Renders the next frame of `shot` of `world`. A new size, light, seed or world size
    /// starts a new history; a camera move or a world change does not: the history is
    /// reprojected, light on a changed chunk restarts, and light from before a change near
    /// it fades out within `EDIT_HISTORY_FRAMES`.
    fn frame(&mut self, gpu: &Gpu, world: &GpuWorld, shot: &Shot) -> Result<(), GpuError> {
        check_frame_size(gpu, shot.size, 0)?;
        let now = CameraRays::new(&shot.camera, shot.size)?;
        let plan = self.plan(gpu, world, shot.size)?;
        let pipelines = self.pipelines(gpu, world, plan.split)?;
        let denoise = self.denoise;
        let h = GiHistory::follow(&mut self.history, gpu, world, shot, &plan);
        let jitter = h.upload_cameras(gpu, shot, &now)?;
        let params = h.params(gpu, &now, jitter, denoise);
        // The table is filled when a history starts; the denoiser runs when asked for.
        let first = h.frames == 0;
        let runs = GiPass::ALL.map(|pass| match pass {
            GiPass::Atmosphere => first,
            GiPass::DenoiseX | GiPass::DenoiseY => denoise,
            _ => true,
        });
        let timer = Timer::get(&mut self.timer, gpu, self.profile);
        let pipes = &self.pipes[&plan.split];
        encode(
            gpu,
            world,
            &plan,
            h,
            &Passes {
                pipes,
                pipelines: &pipelines,
                runs,
            },
            &params,
            timer,
        )?;
        h.frames += 1;
        Ok(())
    }

    /// The newest result as linear radiance; an error before the first frame.
    fn radiance(&self, gpu: &Gpu) -> Result<Radiance, GpuError> {
        let px = self.read_pixels(gpu, |l| l.result, 1)?;
        let (w, ht) = self.history.as_ref().map_or((0, 0), |h| h.shot.size);
        Ok(Radiance {
            width: w,
            height: ht,
            rgb: px.iter().map(|p| [p[0], p[1], p[2]]).collect(),
        })
    }
}

/// The passes of one frame: their pipelines (layouts and bind groups, and the built
/// pipeline for the world's split), and which of them run.
struct Passes<'a> {
    pipes: &'a [PassPipelines],
    pipelines: &'a [wgpu::ComputePipeline],
    runs: [bool; GiPass::ALL.len()],
}

/// Encodes and submits one frame of history `h`: every pass that runs, in order, each in
/// its compute pass (timed when `timer` is given), with the copy of the indirect arguments
/// before the secondary rays.
fn encode(
    gpu: &Gpu,
    world: &GpuWorld,
    plan: &Plan,
    h: &GiHistory,
    passes: &Passes,
    params: &[wgpu::Buffer; 3],
    timer: Option<&mut Timer>,
) -> Result<(), GpuError> {
    let buffers = h.bindings(params);
    let (width, height) = h.shot.size;
    let pixel_groups = (width.div_ceil(8), height.div_ceil(8));
    gpu.checked(|| {
        let mut enc = gpu.device.create_command_encoder(&Default::default());
        for (k, &pass) in GiPass::ALL.iter().enumerate() {
            if !passes.runs[k] {
                continue;
            }
            if pass == GiPass::Trace {
                enc.copy_buffer_to_buffer(&h.words, 0, &h.args, 0, ARGS_BYTES);
            }
            let group = passes.pipes[k].group1(gpu, &buffers);
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
            cp.set_pipeline(&passes.pipelines[k]);
            cp.set_bind_group(0, world.bind_group(), &[]);
            cp.set_bind_group(1, &group, &[]);
            match pass {
                GiPass::Atmosphere => cp.dispatch_workgroups(LUT_SIZE / 8, LUT_SIZE / 8, 1),
                GiPass::QueueScan => cp.dispatch_workgroups(1, 1, 1),
                GiPass::Trace => cp.dispatch_workgroups_indirect(&h.args, u64::from(CONTROL_TRACE_ARGS) * 4),
                GiPass::Project | GiPass::ProjectStore => {
                    cp.dispatch_workgroups_indirect(&h.args, u64::from(CONTROL_PROJECT_ARGS) * 4)
                }
                GiPass::Refine => cp.dispatch_workgroups(plan.regions.div_ceil(64) as u32, 1, 1),
                GiPass::Poses => cp.dispatch_workgroups(NO_ENTITY.div_ceil(64), 1, 1),
                _ => cp.dispatch_workgroups(pixel_groups.0, pixel_groups.1, 1),
            }
        }
        if let Some(t) = timer {
            enc.resolve_query_set(&t.queries, 0..TIMESTAMPS, &t.resolved, 0);
            t.ran = passes.runs;
        }
        gpu.queue.submit([enc.finish()]);
    })
}

//! [`Baseline`]: the paper's comparison for the GI pipeline (`baseline`; docs/RENDERING.md
//! §3b): each frame one path-traced sample per pixel, blended into the reprojected
//! history with an exponential moving average (α = 0.1) after clamping the history to the
//! 3×3 neighbourhood of the new samples in YCoCg.

use super::context::{Gpu, GpuError};
use super::params::{FrameInfo, LightInfo};
use super::pathtrace::path_pass;
use super::pipeline::PassPipelines;
use super::shaders::{Loop, PassSource, SAMPLE};
use super::shot::{CameraRays, Shot, check_frame_size};
use super::temporal::Temporal;
use super::world::GpuWorld;
use crate::light::hdr::Radiance;
use naadf_world::camera::Camera;

/// `shaders/taa.wgsl`: the baseline's temporal accumulation.
const TAA: &str = include_str!("../../../shaders/taa.wgsl");

/// Bytes per pixel of each frame buffer (RGB and the first-hit distance, `f32` each).
const PIXEL_BYTES: u64 = 16;

/// The buffers of a running history.
pub struct History {
    /// The shot of the newest result: a shot that does not continue it starts a new
    /// history.
    shot: Shot,
    /// This frame's samples.
    samples: wgpu::Buffer,
    /// The results of the last two frames; `latest` indexes the newest.
    results: [wgpu::Buffer; 2],
    latest: usize,
    /// Frames rendered so far.
    frames: u32,
}

/// The baseline renderer: a history per (size, light, seed).
pub struct Baseline {
    sample: PassPipelines,
    taa: PassPipelines,
    history: Option<History>,
}

/// The frame parameters of `camera` for a `size` frame, with its position taken relative to
/// `origin` and the given sample number and history flag.
fn frame_info(
    camera: &Camera,
    origin: [f64; 3],
    size: (u32, u32),
    seed: u32,
    sample: u32,
    history: bool,
) -> Result<FrameInfo, GpuError> {
    let relative = Camera {
        pos: std::array::from_fn(|a| camera.pos[a] - origin[a]),
        ..*camera
    };
    Ok(FrameInfo::new(
        &CameraRays::new(&relative, size)?,
        size,
        seed,
        sample,
        history,
    ))
}

/// The resolve pass's WGSL: the sample streams and [`TAA`].
pub(crate) fn taa_pass() -> PassSource {
    PassSource {
        entry: "taa_resolve",
        files: &[SAMPLE, TAA],
        generated: String::new(),
    }
}

impl Baseline {
    /// Prepares the passes (pipelines are built on first use).
    pub fn new(gpu: &Gpu) -> Self {
        Self::with_sample_pass(gpu, path_pass("path_sample"), &[])
    }

    /// The same renderer with another sample pass (`path_sample` with a lighting tier)
    /// whose group 1 has storage buffers of `extra` read-only flags after the baseline's
    /// own (the frame, the light, the samples).
    pub(crate) fn with_sample_pass(gpu: &Gpu, sample: PassSource, extra: &[bool]) -> Self {
        let storage: Vec<bool> = [false].into_iter().chain(extra.iter().copied()).collect();
        Baseline {
            sample: PassPipelines::new(gpu, sample, 2, &storage),
            taa: PassPipelines::new(gpu, taa_pass(), 2, &[true, true, false]),
            history: None,
        }
    }

    /// Frames in the current history.
    pub fn frames(&self) -> u32 {
        self.history.as_ref().map_or(0, |h| h.frames)
    }

    /// Swaps the history with `other`: a caller that renders several camera streams in
    /// turn keeps each stream's history and swaps it in before rendering it.
    pub fn swap_history(&mut self, other: &mut Option<History>) {
        std::mem::swap(&mut self.history, other);
    }
}

impl Temporal for Baseline {
    /// Renders the next frame of `shot` of `world` (sample number = frames so far). A new
    /// size, light or seed starts a new history; a new camera or world does not: the
    /// history is reprojected and clamped, as the baseline does.
    fn frame(&mut self, gpu: &Gpu, world: &GpuWorld, shot: &Shot) -> Result<(), GpuError> {
        self.frame_with(gpu, world, shot, &[])
    }

    /// The newest result as linear radiance; an error before the first frame.
    fn radiance(&self, gpu: &Gpu) -> Result<Radiance, GpuError> {
        let h = self
            .history
            .as_ref()
            .ok_or_else(|| GpuError::Readback("no baseline frame was rendered".into()))?;
        let (w, ht) = h.shot.size;
        let bytes = gpu.read_buffer(&h.results[h.latest], u64::from(w) * u64::from(ht) * PIXEL_BYTES)?;
        let px: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&bytes);
        Ok(Radiance {
            width: w,
            height: ht,
            rgb: px.iter().map(|p| [p[0], p[1], p[2]]).collect(),
        })
    }
}

impl Baseline {
    /// [`Temporal::frame`] with the sample pass's `extra` storage buffers bound after its
    /// own.
    pub(crate) fn frame_with(
        &mut self,
        gpu: &Gpu,
        world: &GpuWorld,
        shot: &Shot,
        extra: &[&wgpu::Buffer],
    ) -> Result<(), GpuError> {
        let (camera, size, seed) = (&shot.camera, shot.size, shot.seed);
        let pixels = check_frame_size(gpu, size, PIXEL_BYTES)?;
        // Validates the camera before any state changes.
        CameraRays::new(camera, size)?;
        let sample_pipe = self.sample.get(gpu, world, Loop::Hierarchy, true)?;
        let taa_pipe = self.taa.get(gpu, world, Loop::Hierarchy, true)?;
        let buffer = |label| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: pixels * PIXEL_BYTES,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let h = match self.history.take() {
            Some(h) if shot.continues(&h.shot) => h,
            _ => History {
                shot: *shot,
                samples: buffer("baseline samples"),
                results: [buffer("baseline result 0"), buffer("baseline result 1")],
                latest: 0,
                frames: 0,
            },
        };
        let h = self.history.insert(h);
        // The sample pass needs the camera where it is; the resolve pass reads only the
        // current camera's directions, and the previous camera relative to it.
        let now = frame_info(camera, [0.0; 3], size, seed, h.frames, false)?;
        let before = frame_info(&h.shot.camera, camera.pos, size, seed, h.frames, h.frames > 0)?;
        let now = gpu.params("frame", bytemuck::bytes_of(&now));
        let before = gpu.params("previous frame", bytemuck::bytes_of(&before));
        let light = gpu.params("light", bytemuck::bytes_of(&LightInfo::new(&shot.light)));
        let (old, new) = (&h.results[h.latest], &h.results[1 - h.latest]);
        let groups = (size.0.div_ceil(8), size.1.div_ceil(8));
        gpu.checked(|| {
            let own = [&now, &light, &h.samples];
            let sample_buffers: Vec<&wgpu::Buffer> = own.into_iter().chain(extra.iter().copied()).collect();
            let sample_group = self.sample.group1(gpu, &sample_buffers);
            let taa_group = self.taa.group1(gpu, &[&now, &before, &h.samples, old, new]);
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_compute_pass(&Default::default());
                pass.set_bind_group(0, world.bind_group(), &[]);
                pass.set_pipeline(&sample_pipe);
                pass.set_bind_group(1, &sample_group, &[]);
                pass.dispatch_workgroups(groups.0, groups.1, 1);
                pass.set_pipeline(&taa_pipe);
                pass.set_bind_group(1, &taa_group, &[]);
                pass.dispatch_workgroups(groups.0, groups.1, 1);
            }
            gpu.queue.submit([enc.finish()]);
        })?;
        h.latest = 1 - h.latest;
        h.frames += 1;
        h.shot = *shot;
        Ok(())
    }
}

//! [`PathTracer`]: the light model of [`crate::light`] traced progressively on the GPU
//! (`pathtrace`; docs/RENDERING.md).
//!
//! It keeps a running sum of radiance per pixel and the number of samples in it. Asking
//! for more samples of the same view adds to the sums; any other change (camera, size,
//! light, seed, or the world on the device) restarts them, so an edit never mixes two
//! worlds into one image.

use super::context::{Gpu, GpuError};
use super::params::{FrameInfo, LightInfo};
use super::pipeline::PassPipelines;
use super::shaders::{LIGHT, Loop, NO_TIER, PassSource, SAMPLE};
use super::shot::{CameraRays, Shot, check_frame_size};
use super::world::GpuWorld;
use crate::light::hdr::Radiance;
use wgpu::util::DeviceExt;

/// `shaders/pathtrace.wgsl`: path-traced samples (progressive sums, or one per frame).
pub(crate) const PATHTRACE: &str = include_str!("../../../shaders/pathtrace.wgsl");

/// Pixel-samples one submission traces at most (one dispatch per sample): keeps each
/// submission short (a real GPU's watchdog) and the progress reports frequent.
const SUBMIT_PIXEL_SAMPLES: u64 = 1 << 19;
/// Bytes of running sum per pixel (RGB and the sample count, `f32` each).
const SUM_BYTES: u64 = 16;

/// A path-tracing pass's WGSL: the sample streams, the light model and [`PATHTRACE`],
/// with entry point `path_trace` (progressive sums) or `path_sample` (one sample per pixel
/// and its first-hit distance, for the baseline's TAA).
pub(crate) fn path_pass(entry: &'static str) -> PassSource {
    PassSource {
        entry,
        files: &[SAMPLE, LIGHT, NO_TIER, PATHTRACE],
        generated: String::new(),
    }
}

/// The running sums on the device.
pub struct Accumulation {
    /// What the sums are of: when the shot or the world on the device changes, they restart.
    shot: Shot,
    generation: u64,
    sums: wgpu::Buffer,
    samples: u32,
}

impl Accumulation {
    /// Whether these are sums of `shot` of `world` as the device holds it now.
    fn sums_of(&self, world: &GpuWorld, shot: &Shot) -> bool {
        self.shot == *shot && self.generation == world.generation()
    }
}

/// The progressive path tracer.
pub struct PathTracer {
    pipes: PassPipelines,
    acc: Option<Accumulation>,
}

impl PathTracer {
    /// Prepares the pass (its pipeline is built on first use).
    pub fn new(gpu: &Gpu) -> Self {
        PathTracer {
            pipes: PassPipelines::new(gpu, path_pass("path_trace"), 2, &[false]),
            acc: None,
        }
    }

    /// Samples per pixel in the running sums.
    pub fn samples(&self) -> u32 {
        self.acc.as_ref().map_or(0, |a| a.samples)
    }

    /// Adds one sample per pixel to the sums of this view (the first, if the view, the light,
    /// the seed or the world changed) and returns their mean: progressive rendering, one
    /// sample per frame, in a viewer.
    pub fn add_sample(&mut self, gpu: &Gpu, world: &GpuWorld, shot: &Shot) -> Result<Radiance, GpuError> {
        let next = match &self.acc {
            Some(a) if a.sums_of(world, shot) => a.samples + 1,
            _ => 1,
        };
        self.render(gpu, world, shot, next, &mut |_| {})
    }

    /// Swaps the running sums with `other`: a caller that renders several views in turn
    /// keeps each view's sums and swaps them in before rendering it.
    pub fn swap_sums(&mut self, other: &mut Option<Accumulation>) {
        std::mem::swap(&mut self.acc, other);
    }

    /// Brings the sums of `shot` of `world` to `spp` samples per pixel and returns their
    /// mean. Sums of the same shot and world are kept and added to; anything else restarts
    /// them, as does asking for fewer samples than they hold. `progress` hears the samples
    /// per pixel done after each dispatch.
    pub fn render(
        &mut self,
        gpu: &Gpu,
        world: &GpuWorld,
        shot: &Shot,
        spp: u32,
        progress: &mut dyn FnMut(u32),
    ) -> Result<Radiance, GpuError> {
        let size = shot.size;
        if spp == 0 {
            return Err(GpuError::Unsupported(
                "a path-traced frame needs at least one sample per pixel".into(),
            ));
        }
        let pixels = check_frame_size(gpu, size, SUM_BYTES)?;
        let rays = CameraRays::new(&shot.camera, size)?;
        let pipeline = self.pipes.get(gpu, world, Loop::Hierarchy, true)?;
        let acc = match self.acc.take() {
            Some(a) if a.sums_of(world, shot) && a.samples <= spp => a,
            _ => Accumulation {
                shot: *shot,
                generation: world.generation(),
                sums: gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("path sums"),
                    contents: &vec![0u8; (pixels * SUM_BYTES) as usize],
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                }),
                samples: 0,
            },
        };
        let acc = self.acc.insert(acc);
        let light_params = gpu.params("light", bytemuck::bytes_of(&LightInfo::new(&shot.light)));
        let per_submit = (SUBMIT_PIXEL_SAMPLES / pixels).clamp(1, 256) as u32;
        while acc.samples < spp {
            let batch = per_submit.min(spp - acc.samples);
            let frames: Vec<wgpu::Buffer> = (acc.samples..acc.samples + batch)
                .map(|sample| {
                    let frame = FrameInfo::new(&rays, size, shot.seed, sample, false);
                    gpu.params("frame", bytemuck::bytes_of(&frame))
                })
                .collect();
            gpu.checked(|| {
                let groups: Vec<wgpu::BindGroup> = frames
                    .iter()
                    .map(|f| self.pipes.group1(gpu, &[f, &light_params, &acc.sums]))
                    .collect();
                let mut enc = gpu.device.create_command_encoder(&Default::default());
                {
                    let mut pass = enc.begin_compute_pass(&Default::default());
                    pass.set_pipeline(&pipeline);
                    pass.set_bind_group(0, world.bind_group(), &[]);
                    for group in &groups {
                        pass.set_bind_group(1, group, &[]);
                        pass.dispatch_workgroups(size.0.div_ceil(8), size.1.div_ceil(8), 1);
                    }
                }
                gpu.queue.submit([enc.finish()]);
            })?;
            gpu.device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|e| GpuError::Readback(e.to_string()))?;
            acc.samples += batch;
            progress(acc.samples);
        }
        let bytes = gpu.read_buffer(&acc.sums, pixels * SUM_BYTES)?;
        let sums: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&bytes);
        let n = acc.samples as f32;
        Ok(Radiance {
            width: size.0,
            height: size.1,
            rgb: sums.iter().map(|s| [s[0] / n, s[1] / n, s[2] / n]).collect(),
        })
    }
}

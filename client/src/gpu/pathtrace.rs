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
use super::render::{CameraRays, check_frame_size};
use super::shaders::{Loop, Pass};
use super::world::GpuWorld;
use crate::light::hdr::Radiance;
use crate::light::{Light, Sky, Sun};
use naadf_world::camera::Camera;
use wgpu::util::DeviceExt;

/// Pixel-samples one submission traces at most (one dispatch per sample): keeps each
/// submission short (a real GPU's watchdog) and the progress reports frequent.
const SUBMIT_PIXEL_SAMPLES: u64 = 1 << 19;
/// Bytes of running sum per pixel (RGB and the sample count, `f32` each).
const SUM_BYTES: u64 = 16;

impl LightInfo {
    /// The parameters of `light`.
    pub fn new(light: &Light) -> Self {
        let sky_sun = light.sky_sun();
        let (sky, sky_physical) = match light.sky {
            Sky::Uniform(rgb) => (rgb, 0),
            Sky::Physical => ([sky_sun.irradiance as f32; 3], 1),
        };
        let sun = light.sun;
        LightInfo {
            sky,
            sky_physical,
            sun_dir: sky_sun.direction().map(|c| c as f32),
            sun_on: u32::from(sun.is_some()),
            sun_disc: sun.map_or(0.0, |s| s.disc_radiance() as f32),
            sun_weight: sun.map_or(0.0, |s| s.sample_weight() as f32),
            sun_omc: Sun::one_minus_cos() as f32,
            bounces: light.bounces,
        }
    }
}

impl FrameInfo {
    /// The frame parameters of a lit pass: `rays` at `size`, sample number `sample` of `seed`, and
    /// whether a temporal pass has a history.
    pub(crate) fn new(rays: &CameraRays, size: (u32, u32), seed: u32, sample: u32, history: bool) -> Self {
        FrameInfo {
            cam_int: rays.int,
            width: size.0,
            cam_frac: rays.frac,
            height: size.1,
            forward: rays.forward,
            seed,
            right: rays.right,
            sample,
            up: rays.up,
            history: u32::from(history),
        }
    }
}

/// What the running sums are of: when any of it changes, they restart.
#[derive(Clone, Debug, PartialEq)]
struct Subject {
    camera: Camera,
    size: (u32, u32),
    light: Light,
    seed: u32,
    generation: u64,
}

impl Subject {
    fn new(world: &GpuWorld, camera: &Camera, size: (u32, u32), light: &Light, seed: u32) -> Self {
        Subject {
            camera: *camera,
            size,
            light: *light,
            seed,
            generation: world.generation(),
        }
    }
}

/// The running sums on the device.
pub struct Accumulation {
    subject: Subject,
    sums: wgpu::Buffer,
    samples: u32,
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
            pipes: PassPipelines::new(gpu, Pass::PathTrace, 2, &[false]),
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
    pub fn add_sample(
        &mut self,
        gpu: &Gpu,
        world: &GpuWorld,
        camera: &Camera,
        size: (u32, u32),
        light: &Light,
        seed: u32,
    ) -> Result<Radiance, GpuError> {
        let subject = Subject::new(world, camera, size, light, seed);
        let next = match &self.acc {
            Some(a) if a.subject == subject => a.samples + 1,
            _ => 1,
        };
        self.render(gpu, world, camera, size, light, seed, next, &mut |_| {})
    }

    /// Swaps the running sums with `other`: a caller that renders several views in turn
    /// keeps each view's sums and swaps them in before rendering it.
    pub fn swap_sums(&mut self, other: &mut Option<Accumulation>) {
        std::mem::swap(&mut self.acc, other);
    }

    /// Brings the sums of `camera`'s view of `world` under `light` with `seed` to `spp`
    /// samples per pixel and returns their mean. Sums of the same view are kept and added
    /// to; anything else restarts them, as does asking for fewer samples than they hold.
    /// `progress` hears the samples per pixel done after each dispatch.
    #[allow(clippy::too_many_arguments)]
    pub fn render(
        &mut self,
        gpu: &Gpu,
        world: &GpuWorld,
        camera: &Camera,
        size: (u32, u32),
        light: &Light,
        seed: u32,
        spp: u32,
        progress: &mut dyn FnMut(u32),
    ) -> Result<Radiance, GpuError> {
        if spp == 0 {
            return Err(GpuError::Unsupported(
                "a path-traced frame needs at least one sample per pixel".into(),
            ));
        }
        let pixels = check_frame_size(gpu, size, SUM_BYTES)?;
        let rays = CameraRays::new(camera, size)?;
        let pipeline = self.pipes.get(gpu, world, Loop::Hierarchy, true)?;
        let subject = Subject::new(world, camera, size, light, seed);
        let acc = match self.acc.take() {
            Some(a) if a.subject == subject && a.samples <= spp => a,
            _ => Accumulation {
                subject,
                sums: gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("path sums"),
                    contents: &vec![0u8; (pixels * SUM_BYTES) as usize],
                    usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                }),
                samples: 0,
            },
        };
        let acc = self.acc.insert(acc);
        let light_params = gpu.params("light", bytemuck::bytes_of(&LightInfo::new(light)));
        let per_submit = (SUBMIT_PIXEL_SAMPLES / pixels).clamp(1, 256) as u32;
        while acc.samples < spp {
            let batch = per_submit.min(spp - acc.samples);
            let frames: Vec<wgpu::Buffer> = (acc.samples..acc.samples + batch)
                .map(|sample| {
                    let frame = FrameInfo::new(&rays, size, seed, sample, false);
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

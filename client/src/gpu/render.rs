//! [`Renderer`]: camera frames in the modes of [`Mode`] (docs/RENDERING.md).

use super::context::{Gpu, GpuError};
use super::params::{View, WgslStruct};
use super::pipeline::PassPipelines;
use super::shaders::{FIRST_HIT, Loop, PassSource, WgslValue};
use super::shot::{CameraRays, check_frame_size};
use super::world::GpuWorld;
use crate::frame::{Frame, Mode};
use naadf_world::camera::Camera;

/// `shaders/render.wgsl`: the frame pass.
const RENDER: &str = include_str!("../../../shaders/render.wgsl");

/// The default sun direction: the reference's RotY(30°)·RotZ(60°)·(0, 1, 0).
pub const DEFAULT_SUN: [f32; 3] = [-0.75, 0.5, 0.433_012_7];
/// Step counts map onto the heat map's full range at this many cells (on a log scale:
/// `log2(1 + steps) / log2(1 + STEPS_FULL_SCALE)`).
pub const STEPS_FULL_SCALE: f32 = 512.0;

/// The frame pass's WGSL: the first-hit chain, [`RENDER`], its [`View`] and the codes of
/// the modes it renders.
pub(crate) fn render_pass() -> PassSource {
    let modes: String = Mode::ALL
        .iter()
        .filter(|m| !m.is_lit())
        .map(|m| WgslValue::U32(m.code()).declare(&format!("MODE_{}", m.name().to_uppercase())))
        .collect();
    PassSource {
        entry: "render",
        files: &[FIRST_HIT, RENDER],
        generated: View::wgsl() + &modes,
    }
}

/// The frame pass.
pub struct Renderer {
    pipes: PassPipelines,
    /// Unit direction toward the sun.
    pub sun: [f32; 3],
}

impl Renderer {
    /// Prepares the pass (pipelines are built on first use).
    pub fn new(gpu: &Gpu) -> Self {
        Renderer {
            pipes: PassPipelines::new(gpu, render_pass(), 1, &[false, false]),
            sun: DEFAULT_SUN,
        }
    }

    /// Renders `camera`'s view of `world` at `width × height` in `mode`; with `gbuffer`,
    /// also returns the first-hit records.
    pub fn render(
        &mut self,
        gpu: &Gpu,
        world: &GpuWorld,
        camera: &Camera,
        (width, height): (u32, u32),
        mode: Mode,
        gbuffer: bool,
    ) -> Result<Frame, GpuError> {
        if mode.is_lit() {
            return Err(GpuError::Unsupported(format!(
                "the render pass does not render {}: the path tracer, the baseline and the GI pipeline do",
                mode.name()
            )));
        }
        let pixels = check_frame_size(gpu, (width, height), 16)?;
        let rays = CameraRays::new(camera, (width, height))?;
        let pipeline = self.pipes.get(gpu, world, Loop::Hierarchy, true)?;
        let view = View {
            cam_oi: rays.int,
            mode: mode.code(),
            cam_of: rays.frac,
            width,
            forward: rays.forward,
            height,
            right: rays.right,
            flags: u32::from(gbuffer),
            up: rays.up,
            steps_scale: 1.0 / (1.0 + STEPS_FULL_SCALE).log2(),
            sun: self.sun,
            _pad: 0,
        };
        let params = gpu.params("view", bytemuck::bytes_of(&view));
        let storage = |label, size: u64| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(16),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        };
        let colour = storage("pixels", pixels * 4);
        let gbuf = storage("gbuffer", if gbuffer { pixels * 16 } else { 16 });
        gpu.checked(|| {
            let bind_group = self.pipes.group1(gpu, &[&params, &colour, &gbuf]);
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_compute_pass(&Default::default());
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, world.bind_group(), &[]);
                pass.set_bind_group(1, &bind_group, &[]);
                pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
            }
            gpu.queue.submit([enc.finish()]);
        })?;
        let rgba = gpu.read_buffer(&colour, pixels * 4)?;
        let gbuffer = if gbuffer {
            let bytes = gpu.read_buffer(&gbuf, pixels * 16)?;
            // A byte vector need not be 4-aligned: copy, do not cast in place.
            Some(bytemuck::pod_collect_to_vec::<u8, [u32; 4]>(&bytes))
        } else {
            None
        };
        Ok(Frame {
            width,
            height,
            rgba,
            gbuffer,
        })
    }
}

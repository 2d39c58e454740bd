//! [`Headless`]: frames of a changing world without a window — a device, a renderer, a
//! path tracer and a GPU copy of the world that follows it (`naadf render`, `naadf replay`).

use super::baseline::Baseline;
use super::context::{Gpu, GpuError};
use super::pathtrace::PathTracer;
use super::render::{Frame, Mode, Renderer};
use super::world::GpuWorld;
use crate::light::Light;
use crate::light::hdr::Radiance;
use naadf_world::World;
use naadf_world::camera::Camera;

/// A headless renderer.
pub struct Headless {
    /// The device.
    pub gpu: Gpu,
    renderer: Renderer,
    path_tracer: PathTracer,
    baseline: Baseline,
    world: Option<GpuWorld>,
}

impl Headless {
    /// Opens the default adapter ([`Gpu::new`]).
    pub fn new() -> Result<Self, GpuError> {
        let gpu = Gpu::new()?;
        let renderer = Renderer::new(&gpu);
        let path_tracer = PathTracer::new(&gpu);
        let baseline = Baseline::new(&gpu);
        Ok(Headless {
            gpu,
            renderer,
            path_tracer,
            baseline,
            world: None,
        })
    }

    /// Renders `world` (uploaded the first time, synced by changed pages afterwards).
    pub fn frame(
        &mut self,
        world: &World,
        camera: &Camera,
        size: (u32, u32),
        mode: Mode,
        gbuffer: bool,
    ) -> Result<Frame, GpuError> {
        let gw = GpuWorld::follow(&mut self.world, &self.gpu, world)?;
        self.renderer.render(&self.gpu, gw, camera, size, mode, gbuffer)
    }

    /// Path-traces `world` to `spp` samples per pixel ([`PathTracer::render`]: samples of
    /// the same view and world add up; a change restarts them).
    #[allow(clippy::too_many_arguments)]
    pub fn path_trace(
        &mut self,
        world: &World,
        camera: &Camera,
        size: (u32, u32),
        light: &Light,
        seed: u32,
        spp: u32,
        progress: &mut dyn FnMut(u32),
    ) -> Result<Radiance, GpuError> {
        let gw = GpuWorld::follow(&mut self.world, &self.gpu, world)?;
        self.path_tracer
            .render(&self.gpu, gw, camera, size, light, seed, spp, progress)
    }

    /// Renders the next `baseline` frame of `world` ([`Baseline::frame`]).
    pub fn baseline_frame(
        &mut self,
        world: &World,
        camera: &Camera,
        size: (u32, u32),
        light: &Light,
        seed: u32,
    ) -> Result<(), GpuError> {
        let gw = GpuWorld::follow(&mut self.world, &self.gpu, world)?;
        self.baseline.frame(&self.gpu, gw, camera, size, light, seed)
    }

    /// The newest `baseline` frame as linear radiance.
    pub fn baseline_radiance(&self) -> Result<Radiance, GpuError> {
        self.baseline
            .radiance(&self.gpu)?
            .ok_or_else(|| GpuError::Readback("no baseline frame was rendered".into()))
    }
}

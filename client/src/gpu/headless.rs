//! [`Headless`]: frames of a changing world without a window — a device, a renderer and
//! a GPU copy of the world that follows it (`naadf render`, `naadf replay`).

use super::context::{Gpu, GpuError};
use super::render::{Frame, Mode, Renderer};
use super::world::GpuWorld;
use naadf_world::World;
use naadf_world::camera::Camera;

/// A headless renderer.
pub struct Headless {
    /// The device.
    pub gpu: Gpu,
    renderer: Renderer,
    world: Option<GpuWorld>,
}

impl Headless {
    /// Opens the default adapter ([`Gpu::new`]).
    pub fn new() -> Result<Self, GpuError> {
        let gpu = Gpu::new()?;
        let renderer = Renderer::new(&gpu);
        Ok(Headless {
            gpu,
            renderer,
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
}

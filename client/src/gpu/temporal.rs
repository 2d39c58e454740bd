//! [`Temporal`]: a renderer whose frames build on a history ([`super::Baseline`],
//! [`super::Gi`]), so that callers drive either one the same way.

use super::context::{Gpu, GpuError};
use super::world::GpuWorld;
use crate::light::Light;
use crate::light::hdr::Radiance;
use naadf_world::camera::Camera;

/// A renderer of a temporal mode ([`super::Mode::is_temporal`]).
pub trait Temporal {
    /// Renders the next frame of `camera`'s view of `world`; a new size, light or seed
    /// starts a new history.
    fn frame(
        &mut self,
        gpu: &Gpu,
        world: &GpuWorld,
        camera: &Camera,
        size: (u32, u32),
        light: &Light,
        seed: u32,
    ) -> Result<(), GpuError>;

    /// The newest frame as linear radiance; an error before the first frame.
    fn radiance(&self, gpu: &Gpu) -> Result<Radiance, GpuError>;
}

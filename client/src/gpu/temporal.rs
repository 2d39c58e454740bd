//! [`Temporal`]: a renderer whose frames build on a history ([`super::Baseline`],
//! [`super::Gi`]), so that callers drive either one the same way.

use super::context::{Gpu, GpuError};
use super::shot::Shot;
use super::world::GpuWorld;
use crate::light::hdr::Radiance;

/// A renderer of a temporal mode ([`crate::Mode::is_temporal`]).
pub trait Temporal {
    /// Renders the next frame of `shot` of `world`; a shot that does not continue the
    /// history's ([`Shot::continues`]) starts a new one.
    fn frame(&mut self, gpu: &Gpu, world: &GpuWorld, shot: &Shot) -> Result<(), GpuError>;

    /// The newest frame as linear radiance; an error before the first frame.
    fn radiance(&self, gpu: &Gpu) -> Result<Radiance, GpuError>;
}

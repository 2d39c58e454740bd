//! [`Renderers`]: a renderer for every frame mode on one device, the set that a headless
//! renderer and the viewer's window both hold, and which of them renders a temporal mode.

use super::baseline::Baseline;
use super::context::Gpu;
use super::gi::Gi;
use super::irradiance::Irradiance;
use super::pathtrace::PathTracer;
use super::render::Renderer;
use super::roma::Roma;
use super::temporal::Temporal;
use crate::frame::Mode;

/// A renderer for every frame mode (docs/RENDERING.md §3–3e).
pub(crate) struct Renderers {
    /// The render-pass modes (`albedo`, `material`, `normal`, `steps`).
    pub renderer: Renderer,
    /// `pathtrace`.
    pub path_tracer: PathTracer,
    /// `baseline`.
    pub baseline: Baseline,
    /// `gi`.
    pub gi: Gi,
    /// `roma`.
    pub roma: Roma,
    /// `irradiance`.
    pub irradiance: Irradiance,
}

impl Renderers {
    /// Prepares every renderer on `gpu` (pipelines are built on first use).
    pub fn new(gpu: &Gpu) -> Self {
        Renderers {
            renderer: Renderer::new(gpu),
            path_tracer: PathTracer::new(gpu),
            baseline: Baseline::new(gpu),
            gi: Gi::new(gpu),
            roma: Roma::new(gpu),
            irradiance: Irradiance::new(gpu),
        }
    }

    /// The renderer of `mode` if it is temporal ([`Mode::is_temporal`]).
    pub fn temporal_mut(&mut self, mode: Mode) -> Option<&mut dyn Temporal> {
        Some(match mode {
            Mode::Baseline => &mut self.baseline,
            Mode::Gi => &mut self.gi,
            Mode::Roma => &mut self.roma,
            Mode::Irradiance => &mut self.irradiance,
            _ => return None,
        })
    }

    /// The renderer of `mode` if it is temporal, to read.
    pub fn temporal(&self, mode: Mode) -> Option<&dyn Temporal> {
        Some(match mode {
            Mode::Baseline => &self.baseline,
            Mode::Gi => &self.gi,
            Mode::Roma => &self.roma,
            Mode::Irradiance => &self.irradiance,
            _ => return None,
        })
    }
}

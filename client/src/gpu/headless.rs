//! [`Headless`]: frames of a changing world without a window — a device, a renderer, the
//! lit renderers (path tracer, baseline, GI, ROMA, irradiance cache) and a GPU copy of the
//! world that follows it (`naadf render`, `naadf replay`, render nodes).

use super::baseline::History;
use super::context::{Gpu, GpuError};
use super::gi::{Gi, GiHistory};
use super::pathtrace::Accumulation;
use super::renderers::Renderers;
use super::shot::Shot;
use super::world::GpuWorld;
use crate::frame::{Frame, FrameSpec, Mode};
use crate::light::hdr::Radiance;
use crate::light::{DEFAULT_LIT_BOUNCES, DEFAULT_PATHTRACE_BOUNCES, Light};
use naadf_world::World;
use naadf_world::camera::Camera;

/// A headless renderer.
pub struct Headless {
    /// The device.
    pub gpu: Gpu,
    renderers: Renderers,
    world: Option<GpuWorld>,
    /// The camera streams of [`Headless::render_spec`], least recently used first.
    streams: Vec<Stream>,
}

/// Most camera streams a headless renderer keeps the state of; the least recently used
/// one is dropped for a new one.
pub const MAX_STREAMS: usize = 8;

/// What a camera stream keeps between its frames.
struct Stream {
    name: String,
    sums: Option<Accumulation>,
    history: Option<History>,
    gi: Option<GiHistory>,
    roma: Option<History>,
    irradiance: Option<History>,
}

impl Headless {
    /// Opens the default adapter ([`Gpu::new`]).
    pub fn new() -> Result<Self, GpuError> {
        let gpu = Gpu::new()?;
        Ok(Headless {
            renderers: Renderers::new(&gpu),
            gpu,
            world: None,
            streams: Vec::new(),
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
        self.renderers
            .renderer
            .render(&self.gpu, gw, camera, size, mode, gbuffer)
    }

    /// Path-traces `shot` of `world` to `spp` samples per pixel ([`PathTracer::render`]:
    /// samples of the same shot and world add up; a change restarts them).
    pub fn path_trace(
        &mut self,
        world: &World,
        shot: &Shot,
        spp: u32,
        progress: &mut dyn FnMut(u32),
    ) -> Result<Radiance, GpuError> {
        let gw = GpuWorld::follow(&mut self.world, &self.gpu, world)?;
        self.renderers.path_tracer.render(&self.gpu, gw, shot, spp, progress)
    }

    /// Renders the next frame of `shot` of `world` in a temporal mode
    /// ([`Mode::is_temporal`]: `baseline` with [`Baseline`], `gi` with [`Gi`], `roma` with
    /// [`Roma`], `irradiance` with [`Irradiance`]).
    pub fn temporal_frame(&mut self, mode: Mode, world: &World, shot: &Shot) -> Result<(), GpuError> {
        let gw = GpuWorld::follow(&mut self.world, &self.gpu, world)?;
        let renderer = self.renderers.temporal_mut(mode).ok_or_else(|| not_temporal(mode))?;
        renderer.frame(&self.gpu, gw, shot)
    }

    /// The newest frame of a temporal mode as linear radiance.
    pub fn temporal_radiance(&self, mode: Mode) -> Result<Radiance, GpuError> {
        let renderer = self.renderers.temporal(mode).ok_or_else(|| not_temporal(mode))?;
        renderer.radiance(&self.gpu)
    }

    /// The GI renderer (its options, such as the denoiser).
    pub fn gi_mut(&mut self) -> &mut Gi {
        &mut self.renderers.gi
    }

    /// Renders the frame `spec` asks for, in any mode: the lit modes continue the state of
    /// `spec.lit.stream` (its path-tracer sums and its baseline, GI, ROMA and irradiance
    /// histories; a request without a stream starts afresh) and are tone-mapped with its
    /// exposure.
    pub fn render_spec(&mut self, world: &World, spec: &FrameSpec) -> Result<Frame, GpuError> {
        if !spec.mode.is_lit() {
            return self.frame(world, &spec.camera, spec.size, spec.mode, false);
        }
        let lit = &spec.lit;
        lit.check().map_err(GpuError::Unsupported)?;
        let bounces = match spec.mode {
            Mode::PathTrace => DEFAULT_PATHTRACE_BOUNCES,
            _ => DEFAULT_LIT_BOUNCES,
        };
        let light = lit.light(bounces).map_err(GpuError::Unsupported)?;
        // A request without a stream starts from nothing and leaves nothing behind, so that
        // it does not depend on whoever came before it.
        let fresh = Stream {
            name: lit.stream.clone(),
            sums: None,
            history: None,
            gi: None,
            roma: None,
            irradiance: None,
        };
        let mut stream = match self.streams.iter().position(|s| s.name == lit.stream) {
            Some(at) if !lit.stream.is_empty() => self.streams.remove(at),
            _ => fresh,
        };
        let swap = |h: &mut Self, s: &mut Stream| {
            let r = &mut h.renderers;
            r.path_tracer.swap_sums(&mut s.sums);
            r.baseline.swap_history(&mut s.history);
            r.gi.swap_history(&mut s.gi);
            r.roma.swap_history(&mut s.roma);
            r.irradiance.swap_history(&mut s.irradiance);
        };
        swap(self, &mut stream);
        let radiance = self.render_lit(world, spec, &light);
        swap(self, &mut stream);
        if !lit.stream.is_empty() {
            if self.streams.len() == MAX_STREAMS {
                self.streams.remove(0);
            }
            self.streams.push(stream);
        }
        Ok(radiance?.tone_mapped(lit.exposure))
    }

    /// The radiance of a lit `spec` with the stream's state swapped in.
    fn render_lit(&mut self, world: &World, spec: &FrameSpec, light: &Light) -> Result<Radiance, GpuError> {
        let lit = &spec.lit;
        let shot = Shot::new(spec.camera, spec.size, *light, lit.seed);
        if spec.mode == Mode::PathTrace {
            return self.path_trace(world, &shot, lit.spp, &mut |_| {});
        }
        self.renderers.roma.set_options(lit.roma);
        self.renderers.irradiance.set_options(lit.irradiance);
        for _ in 0..lit.frames {
            self.temporal_frame(spec.mode, world, &shot)?;
        }
        self.temporal_radiance(spec.mode)
    }
}

fn not_temporal(mode: Mode) -> GpuError {
    GpuError::Unsupported(format!(
        "{} is not a temporal mode (baseline, gi, roma, irradiance)",
        mode.name()
    ))
}

//! [`Renderer`]: camera frames in the modes of [`Mode`] (docs/RENDERING.md).

use super::context::{Gpu, GpuError};
use super::pipeline::PassPipelines;
use super::rays::split_origin;
use super::shaders::{Loop, Pass};
use super::world::GpuWorld;
use naadf_world::camera::Camera;
use naadf_world::traverse::MAX_COORD;
use std::io::Write;

/// What a frame shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// The first-hit chain (primary hit plus up to 3 mirror bounces) shaded with albedo ×
    /// (hard sun shadow + ambient) + emission, sky on a miss; deterministic.
    Albedo,
    /// Flat material colour of the primary hit (sRGB, no lighting; black on a miss).
    Material,
    /// The primary hit's world-space normal as `n · 0.5 + 0.5` (black on a miss).
    Normal,
    /// Heat map of the cells the primary ray visited.
    Steps,
    /// The light model, path-traced progressively ([`super::PathTracer`]).
    PathTrace,
    /// One path-traced sample per pixel per frame with an exponential TAA
    /// ([`super::Baseline`]).
    Baseline,
    /// The paper's GI pipeline ([`super::Gi`]).
    Gi,
}

impl Mode {
    /// Every mode, in CLI order.
    pub const ALL: [Mode; 7] = [
        Mode::Albedo,
        Mode::Material,
        Mode::Normal,
        Mode::Steps,
        Mode::PathTrace,
        Mode::Baseline,
        Mode::Gi,
    ];

    /// The CLI name.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Albedo => "albedo",
            Mode::Material => "material",
            Mode::Normal => "normal",
            Mode::Steps => "steps",
            Mode::PathTrace => "pathtrace",
            Mode::Baseline => "baseline",
            Mode::Gi => "gi",
        }
    }

    /// Parses a CLI name.
    pub fn parse(s: &str) -> Option<Mode> {
        Mode::ALL.into_iter().find(|m| m.name() == s)
    }

    /// Whether the mode renders the light model (docs/RENDERING.md §3a–c) rather than a
    /// pass of [`Renderer`].
    pub fn is_lit(self) -> bool {
        matches!(self, Mode::PathTrace | Mode::Baseline | Mode::Gi)
    }

    /// Whether each frame builds on the frames before it (`baseline`, `gi`): these take
    /// `--frames` and a camera path, and keep a history per camera stream.
    pub fn is_temporal(self) -> bool {
        matches!(self, Mode::Baseline | Mode::Gi)
    }

    /// The mode's code in the render pass (its `MODE_*` constants); the lit modes have
    /// none, as that pass does not render them.
    pub(super) const fn code(self) -> u32 {
        match self {
            Mode::Albedo => 0,
            Mode::Material => 1,
            Mode::Normal => 2,
            Mode::Steps => 3,
            Mode::PathTrace | Mode::Baseline | Mode::Gi => u32::MAX,
        }
    }
}

/// The default sun direction: the reference's RotY(30°)·RotZ(60°)·(0, 1, 0).
pub const DEFAULT_SUN: [f32; 3] = [-0.75, 0.5, 0.433_012_7];
/// Step counts map onto the heat map's full range at this many cells (on a log scale:
/// `log2(1 + steps) / log2(1 + STEPS_FULL_SCALE)`).
pub const STEPS_FULL_SCALE: f32 = 512.0;
/// Largest frame edge.
pub const MAX_EDGE: u32 = 16384;
/// Magic bytes that open a first-hit buffer file ([`write_gbuffer`]).
pub const GBUFFER_MAGIC: &[u8; 8] = b"NAADFGB1";

/// A rendered frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// RGBA8 pixels, rows from the top.
    pub rgba: Vec<u8>,
    /// Per pixel, the reference's `firstHitData` words (when asked for).
    pub gbuffer: Option<Vec<[u32; 4]>>,
}

impl Frame {
    /// Decodes a PNG (any colour type) into an RGBA8 frame without a first-hit buffer.
    pub fn from_png(bytes: &[u8]) -> Result<Frame, GpuError> {
        let img = image::load_from_memory_with_format(bytes, image::ImageFormat::Png)
            .map_err(|e| GpuError::Unsupported(format!("not a readable PNG: {e}")))?
            .to_rgba8();
        Ok(Frame {
            width: img.width(),
            height: img.height(),
            rgba: img.into_raw(),
            gbuffer: None,
        })
    }

    /// Mean absolute difference of the R, G and B bytes (0–255) between two frames of the
    /// same size; `None` when the sizes differ.
    ///
    /// ```
    /// use naadf_client::gpu::Frame;
    /// let f = |v: u8| Frame { width: 1, height: 2, rgba: vec![v, v, v, 255, 0, 0, 0, 255], gbuffer: None };
    /// assert_eq!(f(10).mean_abs_diff(&f(16)), Some(3.0));
    /// ```
    pub fn mean_abs_diff(&self, other: &Frame) -> Option<f64> {
        if (self.width, self.height) != (other.width, other.height) || self.rgba.len() != other.rgba.len() {
            return None;
        }
        let sum: u64 = self
            .rgba
            .chunks_exact(4)
            .zip(other.rgba.chunks_exact(4))
            .map(|(a, b)| (0..3).map(|c| u64::from(a[c].abs_diff(b[c]))).sum::<u64>())
            .sum();
        Some(sum as f64 / (3 * (self.rgba.len() / 4)).max(1) as f64)
    }

    /// The frame as PNG bytes.
    pub fn png(&self) -> Result<Vec<u8>, GpuError> {
        use image::ImageEncoder;
        let mut out = Vec::new();
        image::codecs::png::PngEncoder::new(&mut out)
            .write_image(&self.rgba, self.width, self.height, image::ExtendedColorType::Rgba8)
            .map_err(|e| GpuError::Readback(format!("PNG encoding: {e}")))?;
        Ok(out)
    }
}

/// Writes a first-hit buffer: [`GBUFFER_MAGIC`], width and height (u32 LE), then per pixel
/// (rows from the top) the four u32 LE words of the reference's `firstHitData`.
pub fn write_gbuffer(out: &mut dyn Write, width: u32, height: u32, words: &[[u32; 4]]) -> std::io::Result<()> {
    out.write_all(GBUFFER_MAGIC)?;
    out.write_all(&width.to_le_bytes())?;
    out.write_all(&height.to_le_bytes())?;
    let bytes: Vec<u8> = words.iter().flatten().flat_map(|w| w.to_le_bytes()).collect();
    out.write_all(&bytes)
}

/// Checks a frame size against [`MAX_EDGE`] and against one storage binding of
/// `bytes_per_pixel` per pixel (0 for a caller that splits its arrays across bindings and
/// checks them itself); returns the pixel count.
pub(crate) fn check_frame_size(gpu: &Gpu, (width, height): (u32, u32), bytes_per_pixel: u64) -> Result<u64, GpuError> {
    let pixels = u64::from(width) * u64::from(height);
    if width == 0
        || height == 0
        || width > MAX_EDGE
        || height > MAX_EDGE
        || pixels * bytes_per_pixel > gpu.limits.max_storage_buffer_binding_size
    {
        return Err(GpuError::Unsupported(format!(
            "frame size {width}x{height}: each edge must be 1..={MAX_EDGE} and the frame small enough for one binding of the adapter ({} bytes)",
            gpu.limits.max_storage_buffer_binding_size
        )));
    }
    Ok(pixels)
}

/// A camera as the frame passes take it (docs/CAMERA.md): the position split into integer
/// and fraction, `forward`, and `right` and `up` scaled by `a·W/H` and `a`
/// (`a = tan(fov_y/2)`), so that a pass forms `dir = forward + sx·right + sy·up`.
pub(crate) struct CameraRays {
    pub int: [i32; 3],
    pub frac: [f32; 3],
    pub forward: [f32; 3],
    pub right: [f32; 3],
    pub up: [f32; 3],
}

impl CameraRays {
    /// The rays of `camera` for a `width × height` frame; fails for a position the shaders
    /// cannot hold.
    pub fn new(camera: &Camera, (width, height): (u32, u32)) -> Result<Self, GpuError> {
        // The shaders take the origin's floor as an i32: the CPU's ray range applies.
        if camera.pos.iter().any(|c| c.abs() > MAX_COORD) {
            return Err(GpuError::Unsupported(format!(
                "camera position {:?} is out of range (within ±2^30)",
                camera.pos
            )));
        }
        let basis = camera.basis();
        let a = (camera.fov_y.to_radians() / 2.0).tan();
        let aspect = f64::from(width) / f64::from(height);
        let (int, frac) = split_origin(camera.pos);
        let v3 = |v: [f64; 3], s: f64| v.map(|c| (c * s) as f32);
        Ok(CameraRays {
            int,
            frac,
            forward: v3(basis.forward, 1.0),
            right: v3(basis.right, a * aspect),
            up: v3(basis.up, a),
        })
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
            pipes: PassPipelines::new(gpu, Pass::Render, 1, &[false, false]),
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
        let (int, frac) = (rays.int, rays.frac.map(f32::to_bits));
        let [fx, fy, fz] = rays.forward.map(f32::to_bits);
        let [rx, ry, rz] = rays.right.map(f32::to_bits);
        let [ux, uy, uz] = rays.up.map(f32::to_bits);
        let sun = self.sun.map(f32::to_bits);
        let view: [u32; 24] = [
            int[0] as u32,
            int[1] as u32,
            int[2] as u32,
            mode.code(),
            frac[0],
            frac[1],
            frac[2],
            width,
            fx,
            fy,
            fz,
            height,
            rx,
            ry,
            rz,
            u32::from(gbuffer),
            ux,
            uy,
            uz,
            (1.0 / (1.0 + STEPS_FULL_SCALE).log2()).to_bits(),
            sun[0],
            sun[1],
            sun[2],
            0,
        ];
        let params = gpu.params("view", bytemuck::cast_slice(&view));
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

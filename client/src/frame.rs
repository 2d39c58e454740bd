//! What a frame is, apart from any renderer: its [`Mode`], the request for one
//! ([`FrameSpec`], what [`Client::frame`](crate::Client::frame) asks for and what a render
//! node's job says) and the rendered pixels ([`Frame`]).
//!
//! Nothing here needs a GPU, so the wire client, the render nodes' connection loop and the
//! radiance images use these types in a build without the renderer.

use crate::light::irradiance::{DEFAULT_RAYS, IrradianceOptions};
use crate::light::roma::{DEFAULT_AO_RANGE, DEFAULT_DIRECTIONS, RomaOptions};
use crate::light::{DEFAULT_SPP, LitOptions, Sky, Sun};
use naadf_proto::v1::FrameRequest;
use naadf_world::camera::Camera;
use std::io::Write;
use std::time::Duration;
use thiserror::Error;

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
    /// The light model, path-traced progressively (the GPU client's `PathTracer`).
    PathTrace,
    /// One path-traced sample per pixel per frame with an exponential TAA
    /// (the GPU client's `Baseline`).
    Baseline,
    /// The paper's GI pipeline (the GPU client's `Gi`).
    Gi,
    /// ROMA visibility (occupancy maps along fixed directions) for ambient occlusion and
    /// sun shadows of diffuse surfaces; mirrors and metals as `baseline` traces them.
    Roma,
    /// A world-space irradiance cache lighting diffuse surfaces, refreshed by a ray budget
    /// per frame (the GPU client's `Irradiance`).
    Irradiance,
}

impl Mode {
    /// Every mode, in CLI order.
    pub const ALL: [Mode; 9] = [
        Mode::Albedo,
        Mode::Material,
        Mode::Normal,
        Mode::Steps,
        Mode::PathTrace,
        Mode::Baseline,
        Mode::Gi,
        Mode::Roma,
        Mode::Irradiance,
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
            Mode::Roma => "roma",
            Mode::Irradiance => "irradiance",
        }
    }

    /// Parses a CLI name.
    pub fn parse(s: &str) -> Option<Mode> {
        Mode::ALL.into_iter().find(|m| m.name() == s)
    }

    /// Whether the mode renders the light model (docs/RENDERING.md §3a–e) rather than a
    /// pass of the GPU client's `Renderer`.
    pub fn is_lit(self) -> bool {
        matches!(
            self,
            Mode::PathTrace | Mode::Baseline | Mode::Gi | Mode::Roma | Mode::Irradiance
        )
    }

    /// Whether each frame builds on the frames before it (`baseline`, `gi`, `roma`,
    /// `irradiance`): these take `--frames` and a camera path, and keep a history per camera
    /// stream.
    pub fn is_temporal(self) -> bool {
        matches!(self, Mode::Baseline | Mode::Gi | Mode::Roma | Mode::Irradiance)
    }

    /// The mode's code in the render pass (its `MODE_*` constants); the lit modes have
    /// none, as that pass does not render them.
    pub const fn code(self) -> u32 {
        match self {
            Mode::Albedo => 0,
            Mode::Material => 1,
            Mode::Normal => 2,
            Mode::Steps => 3,
            Mode::PathTrace | Mode::Baseline | Mode::Gi | Mode::Roma | Mode::Irradiance => u32::MAX,
        }
    }
}

/// A frame to render: what [`Client::frame`](crate::Client::frame) asks for and what a render node's job says.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameSpec {
    /// The camera.
    pub camera: Camera,
    /// Image size in pixels (width, height).
    pub size: (u32, u32),
    /// Render mode.
    pub mode: Mode,
    /// The oldest world version the frame may show.
    pub min_version: u64,
    /// Raw RGBA8 (rows from the top) instead of PNG.
    pub raw: bool,
    /// The deadline, or the server's default ([`naadf_proto::DEFAULT_FRAME_DEADLINE`]).
    /// Sent in whole milliseconds; one under a millisecond means the default.
    pub timeout: Option<Duration>,
    /// The options of the lit modes (ignored by the others).
    pub lit: LitOptions,
}

impl FrameSpec {
    /// A PNG frame of any version, with the server's default deadline.
    pub fn new(camera: Camera, size: (u32, u32), mode: Mode) -> Self {
        Self {
            camera,
            size,
            mode,
            min_version: 0,
            raw: false,
            timeout: None,
            lit: LitOptions::default(),
        }
    }

    /// The request on the wire.
    pub(crate) fn to_wire(&self) -> FrameRequest {
        FrameRequest {
            // A camera is numbers only: it always serializes.
            camera: serde_json::to_string(&self.camera).expect("camera JSON"),
            width: self.size.0,
            height: self.size.1,
            mode: self.mode.name().into(),
            min_version: self.min_version,
            raw: self.raw,
            timeout_ms: self
                .timeout
                .map_or(0, |t| t.as_millis().min(u128::from(u32::MAX)) as u32),
            spp: self.lit.spp,
            frames: self.lit.frames,
            seed: self.lit.seed,
            bounces: self.lit.bounces,
            sky: self.lit.sky.map(|s| s.to_string()).unwrap_or_default(),
            sun: match self.lit.sun {
                None => String::new(),
                Some(None) => "off".into(),
                Some(Some(sun)) => sun.to_string(),
            },
            exposure: self.lit.exposure,
            stream: self.lit.stream.clone(),
            // The defaults travel as absent fields. The AO range crosses as an f32.
            roma_directions: (self.lit.roma.directions != DEFAULT_DIRECTIONS).then_some(self.lit.roma.directions),
            ao_range: (self.lit.roma.ao_range != DEFAULT_AO_RANGE).then_some(self.lit.roma.ao_range as f32),
            irradiance_rays: (self.lit.irradiance.rays != DEFAULT_RAYS).then_some(self.lit.irradiance.rays),
        }
    }

    /// A request from the wire; an error names what this client cannot render, or a ROMA
    /// or irradiance setting out of its range ([`RomaOptions::check`],
    /// [`IrradianceOptions::check`]).
    pub(crate) fn from_wire(r: &FrameRequest) -> Result<Self, String> {
        let roma = RomaOptions {
            directions: r.roma_directions.unwrap_or(DEFAULT_DIRECTIONS),
            ao_range: r.ao_range.map_or(DEFAULT_AO_RANGE, f64::from),
        };
        roma.check()?;
        let irradiance = IrradianceOptions {
            rays: r.irradiance_rays.unwrap_or(DEFAULT_RAYS),
        };
        irradiance.check()?;
        Ok(Self {
            camera: Camera::from_json(&r.camera).map_err(|e| e.to_string())?,
            size: (r.width, r.height),
            mode: Mode::parse(&r.mode).ok_or_else(|| format!("unknown mode '{}'", r.mode))?,
            min_version: r.min_version,
            raw: r.raw,
            timeout: (r.timeout_ms != 0).then(|| Duration::from_millis(u64::from(r.timeout_ms))),
            lit: LitOptions {
                spp: if r.spp == 0 { DEFAULT_SPP } else { r.spp },
                frames: r.frames.max(1),
                seed: r.seed,
                bounces: r.bounces,
                sky: (!r.sky.is_empty()).then(|| Sky::parse(&r.sky)).transpose()?,
                sun: (!r.sun.is_empty()).then(|| Sun::parse(&r.sun)).transpose()?,
                exposure: if r.exposure == 0.0 { 1.0 } else { r.exposure },
                stream: r.stream.clone(),
                roma,
                irradiance,
            },
        })
    }
}

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
    pub fn from_png(bytes: &[u8]) -> Result<Frame, FrameError> {
        let img = image::load_from_memory_with_format(bytes, image::ImageFormat::Png)
            .map_err(|e| FrameError::Decode(e.to_string()))?
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
    /// use naadf_client::Frame;
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
    pub fn png(&self) -> Result<Vec<u8>, FrameError> {
        use image::ImageEncoder;
        let mut out = Vec::new();
        image::codecs::png::PngEncoder::new(&mut out)
            .write_image(&self.rgba, self.width, self.height, image::ExtendedColorType::Rgba8)
            .map_err(|e| FrameError::Encode(e.to_string()))?;
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

/// Why a frame could not be encoded or decoded.
#[derive(Debug, Error)]
pub enum FrameError {
    /// The bytes are not a PNG this client can read.
    #[error("not a readable PNG: {0}")]
    Decode(String),
    /// Encoding the PNG failed.
    #[error("PNG encoding: {0}")]
    Encode(String),
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::irradiance::{MAX_RAYS, MIN_RAYS};

    /// The server refuses modes outside the protocol's list: every mode a node can render
    /// must be on it.
    #[test]
    fn render_modes_are_the_protocols() {
        assert_eq!(Mode::ALL.map(Mode::name), naadf_proto::FRAME_MODES);
    }

    #[test]
    fn frame_specs_cross_the_wire_unchanged() {
        let camera = Camera::from_json(r#"{"pos":[1.5,2,-3],"yaw":45,"pitch":-30,"fov_y":70}"#).unwrap();
        let mut spec = FrameSpec::new(camera, (96, 64), Mode::Material);
        assert_eq!(FrameSpec::from_wire(&spec.to_wire()), Ok(spec.clone()));
        assert_eq!(spec.to_wire().timeout_ms, 0, "the server's default deadline");
        spec.min_version = 7;
        spec.raw = true;
        spec.timeout = Some(Duration::from_millis(1500));
        assert_eq!(FrameSpec::from_wire(&spec.to_wire()), Ok(spec.clone()));
        let mut wire = spec.to_wire();
        wire.mode = "x-ray".into();
        assert_eq!(FrameSpec::from_wire(&wire), Err("unknown mode 'x-ray'".into()));
        spec.mode = Mode::Baseline;
        spec.lit = LitOptions {
            spp: 9,
            frames: 3,
            seed: 4,
            bounces: Some(0),
            sky: Some(Sky::Uniform([0.5, 1.0, 2.0])),
            sun: Some(Sun::parse("10,20,30").unwrap()),
            exposure: 0.5,
            stream: "me".into(),
            ..LitOptions::default()
        };
        assert_eq!(FrameSpec::from_wire(&spec.to_wire()), Ok(spec.clone()));
        spec.lit.sun = Some(None);
        assert_eq!(FrameSpec::from_wire(&spec.to_wire()), Ok(spec.clone()));
        let mut wire = spec.to_wire();
        wire.sky = "cloudy".into();
        assert!(FrameSpec::from_wire(&wire).unwrap_err().contains("sky 'cloudy'"));
    }

    #[test]
    fn roma_settings_cross_the_wire() {
        let camera = Camera::from_json(r#"{"pos":[0,40,0],"yaw":0,"pitch":-20,"fov_y":60}"#).unwrap();
        let mut spec = FrameSpec::new(camera, (64, 48), Mode::Roma);
        // The defaults travel as absent fields and come back as the defaults.
        let wire = spec.to_wire();
        assert_eq!((wire.roma_directions, wire.ao_range), (None, None));
        assert_eq!(FrameSpec::from_wire(&wire), Ok(spec.clone()));
        // Others travel as given (an AO range that an f32 holds exactly comes back unchanged).
        spec.lit.roma = RomaOptions {
            directions: 9,
            ao_range: 48.5,
        };
        let wire = spec.to_wire();
        assert_eq!((wire.roma_directions, wire.ao_range), (Some(9), Some(48.5)));
        assert_eq!(FrameSpec::from_wire(&wire), Ok(spec.clone()));
        spec.lit.roma.directions = 1;
        spec.lit.roma.ao_range = 256.0;
        assert_eq!(FrameSpec::from_wire(&spec.to_wire()), Ok(spec.clone()));
    }

    #[test]
    fn bad_roma_settings_are_refused() {
        let camera = Camera::from_json(r#"{"pos":[0,40,0],"yaw":0,"pitch":-20,"fov_y":60}"#).unwrap();
        let wire = FrameSpec::new(camera, (64, 48), Mode::Roma).to_wire();
        let refused = |directions: Option<u32>, ao_range: Option<f32>| {
            FrameSpec::from_wire(&FrameRequest {
                roma_directions: directions,
                ao_range,
                ..wire.clone()
            })
            .unwrap_err()
        };
        for k in [0, 2, 12, 25, u32::MAX] {
            let e = refused(Some(k), None);
            assert!(e.contains(&format!("{k} ROMA directions")), "{k}: {e}");
        }
        for range in [0.0, -1.0, 256.5, f32::INFINITY, f32::NAN] {
            let e = refused(None, Some(range));
            assert!(e.contains("AO range"), "{range}: {e}");
        }
    }

    #[test]
    fn irradiance_settings_cross_the_wire() {
        let camera = Camera::from_json(r#"{"pos":[0,40,0],"yaw":0,"pitch":-20,"fov_y":60}"#).unwrap();
        let mut spec = FrameSpec::new(camera, (64, 48), Mode::Irradiance);
        // The default travels as an absent field and comes back as the default.
        let wire = spec.to_wire();
        assert_eq!(wire.irradiance_rays, None);
        assert_eq!(FrameSpec::from_wire(&wire), Ok(spec.clone()));
        // Others travel as given, the ends of the range included.
        for rays in [MIN_RAYS, 1000, MAX_RAYS] {
            spec.lit.irradiance = IrradianceOptions { rays };
            let wire = spec.to_wire();
            assert_eq!(wire.irradiance_rays, Some(rays));
            assert_eq!(FrameSpec::from_wire(&wire), Ok(spec.clone()));
        }
    }

    #[test]
    fn bad_irradiance_settings_are_refused() {
        let camera = Camera::from_json(r#"{"pos":[0,40,0],"yaw":0,"pitch":-20,"fov_y":60}"#).unwrap();
        let wire = FrameSpec::new(camera, (64, 48), Mode::Irradiance).to_wire();
        for rays in [0, MIN_RAYS - 1, MAX_RAYS + 1, u32::MAX] {
            let e = FrameSpec::from_wire(&FrameRequest {
                irradiance_rays: Some(rays),
                ..wire.clone()
            })
            .unwrap_err();
            assert!(e.contains(&format!("{rays} irradiance rays")), "{rays}: {e}");
        }
    }
}

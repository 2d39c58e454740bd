//! The light model of the lit modes (`pathtrace`, `baseline`; docs/RENDERING.md §3a).
//!
//! One model, two implementations that must agree: the GPU path tracer
//! (`shaders/light.wgsl`, driven by the GPU client's `PathTracer`) and the CPU path tracer
//! ([`cpu::CpuPathTracer`]), which walks the CPU traversal and serves as a second method in
//! the tests. This module holds what both share: the sky and sun settings and their CLI
//! syntax ([`Sky`], [`Sun`], [`Light`]), the random-number stream ([`rng`]) and the
//! physical sky ([`sky`]); [`hdr`] writes radiance images and tone-maps them, and
//! `quality` (with the `gpu` feature) measures an image against a reference.
//!
//! - Materials: `diffuse` is Lambertian; `emissive` adds `albedo · emission` and reflects
//!   as diffuse; `metal` is GGX with α = roughness and Schlick's Fresnel with F0 = albedo;
//!   `mirror` reflects perfectly, tinted by albedo.
//! - The sun is a disc of angular radius [`SUN_ANGULAR_RADIUS_DEG`] whose radiance makes its
//!   irradiance on a surface facing it exactly `E`. Camera rays and rays leaving a mirror
//!   see the disc; diffuse and metal surfaces receive the sun only through an explicit
//!   sample of the disc (next-event estimation), so it is never counted twice.
//! - `bounces` counts the scattered rays after the camera ray; the sun is sampled at a hit
//!   only when one more scattered ray is still allowed.

pub mod cpu;
pub mod hdr;
pub mod irradiance;
#[cfg(feature = "gpu")]
pub mod quality;
pub mod rng;
pub mod roma;
pub mod scatter;
pub mod sky;

use irradiance::options::IrradianceOptions;
use roma::options::RomaOptions;
use std::f64::consts::PI;

/// Angular radius of the sun disc, in degrees.
pub const SUN_ANGULAR_RADIUS_DEG: f64 = 0.27;
/// Most scattered rays a path may have (`--bounces`).
pub const MAX_BOUNCES: u32 = 64;
/// Bounces of `pathtrace` when none are given.
pub const DEFAULT_PATHTRACE_BOUNCES: u32 = 8;
/// Bounces of `baseline` (and the GI pipeline) when none are given.
pub const DEFAULT_LIT_BOUNCES: u32 = 3;
/// How far a scattered or shadow ray starts off the surface, along its normal, in voxels.
pub const SURFACE_OFFSET: f64 = 0.01;

/// The sky: the radiance of every ray that leaves the world's box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sky {
    /// The single-scattering atmosphere of [`sky`], lit by the sun (or by the default sun's
    /// direction and strength when the sun is off).
    Physical,
    /// The same linear RGB radiance from every direction, below the horizon included.
    Uniform([f32; 3]),
}

impl Sky {
    /// Parses `physical`, `uniform:L` or `uniform:R,G,B` (finite, non-negative radiance).
    ///
    /// ```
    /// use naadf_client::light::Sky;
    /// assert_eq!(Sky::parse("uniform:2").unwrap(), Sky::Uniform([2.0; 3]));
    /// assert_eq!(Sky::parse("uniform:1,0.5,0").unwrap(), Sky::Uniform([1.0, 0.5, 0.0]));
    /// assert!(Sky::parse("uniform:-1").is_err());
    /// assert!(Sky::parse("cloudy").is_err());
    /// ```
    pub fn parse(s: &str) -> Result<Sky, String> {
        if s == "physical" {
            return Ok(Sky::Physical);
        }
        let Some(values) = s.strip_prefix("uniform:") else {
            return Err(format!(
                "sky '{s}': expected 'physical', 'uniform:L' or 'uniform:R,G,B'"
            ));
        };
        let v = parse_numbers(values).map_err(|e| format!("sky '{s}': {e}"))?;
        let rgb = match v[..] {
            [l] => [l; 3],
            [r, g, b] => [r, g, b],
            _ => return Err(format!("sky '{s}': give one radiance or three (R,G,B)")),
        };
        if rgb.iter().any(|c| !(0.0..=65504.0).contains(c)) {
            return Err(format!("sky '{s}': radiance must lie in 0..=65504"));
        }
        Ok(Sky::Uniform(rgb.map(|c| c as f32)))
    }
}

/// A directional light with a small disc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sun {
    /// Azimuth in degrees: 0 = from +Z, 90 = from +X.
    pub azimuth: f64,
    /// Elevation above the horizon in degrees.
    pub elevation: f64,
    /// Irradiance on a surface facing the sun.
    pub irradiance: f64,
}

/// The sun of `--sky physical` when none is given: azimuth 300°, elevation 30°, E = 3.
pub const DEFAULT_SUN: Sun = Sun {
    azimuth: 300.0,
    elevation: 30.0,
    irradiance: 3.0,
};

impl Sun {
    /// Parses `off` (`None`) or `AZ,EL,E` (degrees, degrees, irradiance).
    ///
    /// ```
    /// use naadf_client::light::Sun;
    /// assert_eq!(Sun::parse("off").unwrap(), None);
    /// let sun = Sun::parse("90,30,2").unwrap().unwrap();
    /// assert!((sun.direction()[0] - 30f64.to_radians().cos()).abs() < 1e-12);
    /// assert!(Sun::parse("0,95,1").is_err());
    /// assert!(Sun::parse("0,30").is_err());
    /// ```
    pub fn parse(s: &str) -> Result<Option<Sun>, String> {
        if s == "off" {
            return Ok(None);
        }
        let v = parse_numbers(s).map_err(|e| format!("sun '{s}': {e}"))?;
        let [azimuth, elevation, irradiance] = v[..] else {
            return Err(format!(
                "sun '{s}': expected 'off' or 'AZ,EL,E' (degrees, degrees, irradiance)"
            ));
        };
        if !(-90.0..=90.0).contains(&elevation) {
            return Err(format!("sun '{s}': elevation must lie in -90..=90 degrees"));
        }
        if !(0.0..=1e6).contains(&irradiance) {
            return Err(format!("sun '{s}': irradiance must lie in 0..=1e6"));
        }
        Ok(Some(Sun {
            azimuth,
            elevation,
            irradiance,
        }))
    }

    /// Unit vector toward the sun.
    pub fn direction(&self) -> [f64; 3] {
        let (az, el) = (self.azimuth.to_radians(), self.elevation.to_radians());
        [az.sin() * el.cos(), el.sin(), az.cos() * el.cos()]
    }

    /// `1 − cos r` of the disc's angular radius r, computed without cancellation.
    pub fn one_minus_cos() -> f64 {
        2.0 * (SUN_ANGULAR_RADIUS_DEG.to_radians() / 2.0).sin().powi(2)
    }

    /// The disc's radiance, `E / (π sin² r)`: a surface facing the sun receives exactly E.
    pub fn disc_radiance(&self) -> f64 {
        self.irradiance / (PI * SUN_ANGULAR_RADIUS_DEG.to_radians().sin().powi(2))
    }

    /// The disc's radiance times its solid angle `2π(1 − cos r)`: the weight of one sample
    /// drawn uniformly from the disc.
    pub fn sample_weight(&self) -> f64 {
        self.disc_radiance() * 2.0 * PI * Self::one_minus_cos()
    }
}

/// Everything that lights a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// The sky.
    pub sky: Sky,
    /// The sun, if any.
    pub sun: Option<Sun>,
    /// Scattered rays after the camera ray (0..=[`MAX_BOUNCES`]).
    pub bounces: u32,
}

impl Light {
    /// The light of `--sky`, `--sun` and `--bounces`. Without `--sun`, a uniform sky has no
    /// sun and the physical sky has [`DEFAULT_SUN`].
    pub fn new(sky: Sky, sun: Option<Option<Sun>>, bounces: u32) -> Result<Light, String> {
        if bounces > MAX_BOUNCES {
            return Err(format!("{bounces} bounces: at most {MAX_BOUNCES}"));
        }
        let sun = sun.unwrap_or(match sky {
            Sky::Physical => Some(DEFAULT_SUN),
            Sky::Uniform(_) => None,
        });
        Ok(Light { sky, sun, bounces })
    }

    /// The sun that lights the physical sky: the sun, or [`DEFAULT_SUN`] when it is off.
    pub fn sky_sun(&self) -> Sun {
        self.sun.unwrap_or(DEFAULT_SUN)
    }
}

impl std::fmt::Display for Sky {
    /// The CLI syntax ([`Sky::parse`] reads it back).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Sky::Physical => write!(f, "physical"),
            Sky::Uniform([r, g, b]) => write!(f, "uniform:{r},{g},{b}"),
        }
    }
}

impl std::fmt::Display for Sun {
    /// The CLI syntax `AZ,EL,E` ([`Sun::parse`] reads it back).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{},{}", self.azimuth, self.elevation, self.irradiance)
    }
}

/// Samples per pixel of `pathtrace` when none are given.
pub const DEFAULT_SPP: u32 = 64;

/// The options of a lit frame, as the CLI and a frame request give them (docs/RENDERING.md
/// §3a–b); `None` takes the mode's default.
#[derive(Clone, Debug, PartialEq)]
pub struct LitOptions {
    /// Samples per pixel (`pathtrace`).
    pub spp: u32,
    /// Frames to render (`baseline`).
    pub frames: u32,
    /// Seed of the random samples.
    pub seed: u32,
    /// Scattered rays after the camera ray.
    pub bounces: Option<u32>,
    /// The sky (default physical).
    pub sky: Option<Sky>,
    /// The sun: `Some(None)` is `off` (default: by the sky, see [`Light::new`]).
    pub sun: Option<Option<Sun>>,
    /// Exposure of the tone-mapped image.
    pub exposure: f32,
    /// The requester's camera stream: frames of one stream continue one history ("" for
    /// none).
    pub stream: String,
    /// The settings of `roma`: its candidate directions and AO range.
    pub roma: RomaOptions,
    /// The settings of `irradiance`: its ray budget per frame.
    pub irradiance: IrradianceOptions,
}

impl Default for LitOptions {
    fn default() -> Self {
        LitOptions {
            spp: DEFAULT_SPP,
            frames: 1,
            seed: 0,
            bounces: None,
            sky: None,
            sun: None,
            exposure: 1.0,
            stream: String::new(),
            roma: RomaOptions::default(),
            irradiance: IrradianceOptions::default(),
        }
    }
}

impl LitOptions {
    /// The light for a frame of a mode whose default bounce count is `bounces`.
    pub fn light(&self, bounces: u32) -> Result<Light, String> {
        Light::new(
            self.sky.unwrap_or(Sky::Physical),
            self.sun,
            self.bounces.unwrap_or(bounces),
        )
    }

    /// Checks the numbers: at least one sample and frame, a positive finite exposure, and
    /// the ROMA and irradiance settings ([`RomaOptions::check`],
    /// [`IrradianceOptions::check`]).
    pub fn check(&self) -> Result<(), String> {
        if self.spp == 0 || self.frames == 0 {
            return Err("a lit frame needs at least one sample per pixel and one frame".into());
        }
        if !(self.exposure.is_finite() && self.exposure > 0.0) {
            return Err(format!("exposure {}: must be a positive finite number", self.exposure));
        }
        self.roma.check()?;
        self.irradiance.check()
    }
}

fn parse_numbers(s: &str) -> Result<Vec<f64>, String> {
    s.split(',')
        .map(|v| {
            let x: f64 = v.trim().parse().map_err(|e| format!("'{v}': {e}"))?;
            if x.is_finite() {
                Ok(x)
            } else {
                Err(format!("'{v}' is not finite"))
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_disc_gives_its_irradiance_on_a_facing_surface() {
        let sun = Sun {
            azimuth: 0.0,
            elevation: 90.0,
            irradiance: 3.0,
        };
        // ∫ cosθ dω over the cone is π sin² r.
        let r = SUN_ANGULAR_RADIUS_DEG.to_radians();
        assert!((sun.disc_radiance() * PI * r.sin().powi(2) - 3.0).abs() < 1e-12);
        // The mean cosine of a uniform cone sample is 1 − (1 − cos r)/2.
        let mean_cos = 1.0 - Sun::one_minus_cos() / 2.0;
        assert!((sun.sample_weight() * mean_cos - 3.0).abs() < 1e-12);
    }

    #[test]
    fn sky_and_sun_print_what_they_parse() {
        for sky in ["physical", "uniform:0.25,1,3"] {
            assert_eq!(Sky::parse(sky).unwrap().to_string(), sky);
        }
        let sun = Sun::parse("300.5,-2,3").unwrap().unwrap();
        assert_eq!(Sun::parse(&sun.to_string()).unwrap(), Some(sun));
    }

    #[test]
    fn light_defaults_follow_the_sky() {
        assert_eq!(Light::new(Sky::Physical, None, 8).unwrap().sun, Some(DEFAULT_SUN));
        assert_eq!(Light::new(Sky::Uniform([1.0; 3]), None, 8).unwrap().sun, None);
        assert!(Light::new(Sky::Physical, None, MAX_BOUNCES + 1).is_err());
        let d = DEFAULT_SUN.direction();
        assert!(
            (d[1] - 0.5).abs() < 1e-12 && d[0] < 0.0,
            "300° is from −X, 30° up: {d:?}"
        );
    }
}

//! [`CpuPathTracer`]: the light model traced on the CPU over the CPU traversal, with the
//! same random streams as the GPU path tracer: a second method for the tests (a GPU mean
//! must fall within the CPU estimate's confidence interval) and a reference that needs no
//! device.

use super::rng::Rng;
use super::scatter::{self, MIN_ALPHA};
use super::{Light, SURFACE_OFFSET, Sky, Sun, sky};
use glam::DVec3;
use naadf_world::World;
use naadf_world::camera::Camera;
use naadf_world::entity::pack::rotate;
use naadf_world::material::MaterialKind;
use naadf_world::traverse::{DEFAULT_MAX_STEPS, Hit, Ray, occluded_naadf, trace_naadf};

/// A Monte Carlo estimate: the mean and the standard error of the mean, per channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Mean radiance.
    pub mean: [f64; 3],
    /// Standard error of the mean.
    pub standard_error: [f64; 3],
}

/// A lighting tier: what lights diffuse (and emissive) surfaces instead of the rest of
/// the path (`roma`'s [`super::roma::CpuRoma`], `irradiance`'s
/// [`super::irradiance::CpuIrradiance`]). `Sync`: one tier serves every thread that
/// traces pixels.
pub trait DiffuseTier: Sync {
    /// The light leaving the diffuse surface of `hit` at `surface` with world normal `n`
    /// and `albedo` toward the path (its emission excluded: the path adds it), for a path
    /// of `tracer`.
    fn diffuse(
        &self,
        tracer: &CpuPathTracer,
        hit: &Hit,
        surface: DVec3,
        n: DVec3,
        albedo: DVec3,
        rng: &mut Rng,
    ) -> DVec3;
}

/// A path tracer of one world under one light.
pub struct CpuPathTracer<'w> {
    world: &'w World,
    light: Light,
    seed: u32,
    /// The lighting tier of diffuse surfaces, if not the path tracer's own.
    tier: Option<&'w dyn DiffuseTier>,
}

impl<'w> CpuPathTracer<'w> {
    /// A tracer of `world` under `light` whose sample streams come from `seed`.
    pub fn new(world: &'w World, light: Light, seed: u32) -> Self {
        CpuPathTracer {
            world,
            light,
            seed,
            tier: None,
        }
    }

    /// The same tracer with diffuse (and emissive) surfaces lit by `tier` instead
    /// (`--mode roma`, `--mode irradiance`): a path ends at the first of them with the
    /// tier's light, while mirrors and metals scatter as the path tracer scatters them.
    pub fn with_tier(self, tier: &'w dyn DiffuseTier) -> Self {
        CpuPathTracer {
            tier: Some(tier),
            ..self
        }
    }

    /// The world traced.
    pub(crate) fn world(&self) -> &'w World {
        self.world
    }

    /// Samples `samples` of pixel `(px, py)` of a `size` image seen by `camera`.
    ///
    /// ```
    /// use naadf_client::light::{cpu::CpuPathTracer, Light, Sky};
    /// use naadf_world::{World, camera::Camera, preset::Preset};
    /// let world = World::build(&*Preset::Test.source(None, 1).unwrap(), &|_| {}).unwrap();
    /// let light = Light::new(Sky::Uniform([1.0; 3]), None, 0).unwrap();
    /// let camera = Camera::from_json(r#"{"pos":[-50,-50,-50],"yaw":180,"pitch":0}"#).unwrap();
    /// // Looking away from the world, every sample sees the sky.
    /// let e = CpuPathTracer::new(&world, light, 0).estimate(&camera, (0, 0), (4, 4), 0..16);
    /// assert_eq!(e.mean, [1.0; 3]);
    /// ```
    pub fn estimate(
        &self,
        camera: &Camera,
        (px, py): (u32, u32),
        size: (u32, u32),
        samples: std::ops::Range<u32>,
    ) -> Estimate {
        let n = samples.len().max(1) as f64;
        let (mut sum, mut sq) = (DVec3::ZERO, DVec3::ZERO);
        for s in samples {
            let l = self.sample(camera, (px, py), size, s);
            sum += l;
            sq += l * l;
        }
        let mean = sum / n;
        let var = ((sq / n - mean * mean) * (n / (n - 1.0).max(1.0))).max(DVec3::ZERO);
        Estimate {
            mean: mean.to_array(),
            standard_error: (var / n).to_array().map(f64::sqrt),
        }
    }

    /// Sample `s` of pixel `(px, py)`: the radiance along one jittered camera ray.
    pub fn sample(&self, camera: &Camera, (px, py): (u32, u32), (w, h): (u32, u32), s: u32) -> DVec3 {
        let mut rng = Rng::new(self.seed, px + py * w, s);
        let jx = f64::from(rng.next_f32());
        let jy = f64::from(rng.next_f32());
        match camera.ray_through(&camera.basis(), f64::from(px) + jx, f64::from(py) + jy, w, h) {
            Ok(ray) => self.radiance(ray, true, &mut rng),
            Err(_) => DVec3::ZERO,
        }
    }

    /// The radiance arriving along `ray` (docs/RENDERING.md §3a); `sees_disc`: whether the
    /// ray sees the sun's disc (camera rays and rays leaving a mirror do).
    pub(crate) fn radiance(&self, mut ray: Ray, mut sees_disc: bool, rng: &mut Rng) -> DVec3 {
        let sun = self.light.sun;
        let sun_dir = DVec3::from(self.light.sky_sun().direction());
        let mut light = DVec3::ZERO;
        let mut throughput = DVec3::ONE;
        for bounce in 0..=self.light.bounces {
            let d = DVec3::from(ray.dir());
            let Some(hit) = trace_naadf(self.world, &ray) else {
                light += throughput * self.sky(d, sun_dir, if sees_disc { sun } else { None });
                break;
            };
            // Out of cells (no light), or a ray that starts inside a solid voxel.
            if hit.steps > DEFAULT_MAX_STEPS || hit.normal == [0; 3] {
                break;
            }
            let Some(m) = self.world.materials().get(hit.material) else {
                break;
            };
            let mut n = DVec3::from(hit.normal.map(f64::from));
            if let Some(pose) = hit.entity.and_then(|id| self.world.entity(id)) {
                n = DVec3::from(rotate(pose.rot, n.to_array())).normalize();
            }
            let albedo = DVec3::from(m.albedo.map(f64::from));
            if m.kind == MaterialKind::Emissive {
                light += throughput * albedo * f64::from(m.emission);
            }
            let diffuse = !matches!(m.kind, MaterialKind::Mirror | MaterialKind::Metal);
            if let Some(tier) = self.tier.filter(|_| diffuse) {
                let surface = DVec3::from(ray.origin()) + d * hit.t;
                light += throughput * tier.diffuse(self, &hit, surface, n, albedo, rng);
                break;
            }
            if bounce == self.light.bounces {
                break;
            }
            let p = DVec3::from(ray.origin()) + d * hit.t + n * SURFACE_OFFSET;
            let (dir, weight) = match m.kind {
                MaterialKind::Mirror => {
                    sees_disc = true;
                    (d - n * (2.0 * d.dot(n)), albedo)
                }
                kind => {
                    let wo = -d;
                    let alpha = f64::from(m.roughness).max(MIN_ALPHA);
                    let brdf = |wi: DVec3| match kind {
                        MaterialKind::Metal => scatter::ggx(n, wo, wi, alpha, albedo),
                        _ => albedo / std::f64::consts::PI,
                    };
                    if let Some((wi, e)) = self.sun_sample(p, n, rng) {
                        light += throughput * brdf(wi) * e;
                    }
                    let u = [f64::from(rng.next_f32()), f64::from(rng.next_f32())];
                    sees_disc = false;
                    match kind {
                        MaterialKind::Metal => scatter::ggx_sample(n, wo, alpha, albedo, u),
                        _ => (scatter::cosine(n, u), albedo),
                    }
                }
            };
            if dir.dot(n) <= 0.0 {
                break;
            }
            throughput *= weight;
            let Ok(next) = Ray::new(p.to_array(), dir.to_array()) else {
                break;
            };
            ray = next;
        }
        light
    }

    /// One sample of the sun's disc seen from `p` (just off a surface of normal `n`): its
    /// direction and the irradiance it brings, `E·cosθ`-weighted, when it is above the
    /// surface and unblocked (two random numbers drawn whenever the sun is on).
    pub(crate) fn sun_sample(&self, p: DVec3, n: DVec3, rng: &mut Rng) -> Option<(DVec3, f64)> {
        let sun = self.light.sun?;
        let u = [f64::from(rng.next_f32()), f64::from(rng.next_f32())];
        let wi = scatter::cone(DVec3::from(sun.direction()), Sun::one_minus_cos(), u);
        let cos = n.dot(wi);
        (cos > 0.0 && !self.blocked(p, wi)).then(|| (wi, cos * sun.sample_weight()))
    }

    /// The sky along `d` as a ray leaving a diffuse surface sees it (no disc).
    pub(crate) fn sky_seen(&self, d: DVec3) -> DVec3 {
        self.sky(d, DVec3::from(self.light.sky_sun().direction()), None)
    }

    /// Whether a shadow ray from `p` along `dir` meets anything (or runs out of cells).
    fn blocked(&self, p: DVec3, dir: DVec3) -> bool {
        match Ray::new(p.to_array(), dir.to_array()) {
            Ok(r) => occluded_naadf(self.world, &r),
            Err(_) => true,
        }
    }

    /// The sky along `d`, with the disc of `disc` when the ray may see it.
    fn sky(&self, d: DVec3, sun_dir: DVec3, disc: Option<Sun>) -> DVec3 {
        let mut l = match self.light.sky {
            Sky::Uniform(rgb) => DVec3::from(rgb.map(f64::from)),
            Sky::Physical => {
                let scale = self.light.sky_sun().irradiance;
                let f = |v: DVec3| v.as_vec3().to_array();
                DVec3::from(sky::physical(f(d), f(sun_dir)).map(f64::from)) * scale
            }
        };
        if let Some(sun) = disc
            && 1.0 - d.dot(sun_dir) <= Sun::one_minus_cos()
        {
            l += DVec3::splat(sun.disc_radiance());
        }
        l
    }
}

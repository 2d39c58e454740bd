//! The physical sky: single scattering in a spherical atmosphere of Rayleigh and Mie
//! scatterers with an ozone layer, lit by the sun (`--sky physical`).
//!
//! The same model as the reference engine's atmosphere pass (Rayleigh, Mie and ozone
//! coefficients of Hillaire's 2020 model), evaluated directly per direction: 24 steps along
//! the view ray, 6 toward the sun from each. The eye sits [`EYE_HEIGHT`] above the ground
//! wherever the ray left the world, so the sky is a function of direction alone and a
//! ray's sky does not depend on where in the world it escaped. Directions below the horizon
//! see the air in front of the ground (the ground itself is black). The result scales
//! linearly with the sun's irradiance. The sun disc is not part of it (see [`super::Sun`]).
//!
//! Written in `f32` operation by operation as its WGSL twin (`sky_physical` in
//! `shaders/light.wgsl`), so that the CPU and GPU path tracers see the same sky up to
//! rounding. Heights are kept relative to the ground to avoid cancelling planet radii.

/// Planet radius in metres (one voxel is one metre here).
pub const PLANET_RADIUS: f32 = 6_360_000.0;
/// Thickness of the atmosphere in metres.
pub const ATMOSPHERE_HEIGHT: f32 = 60_000.0;
/// Height of the eye above the ground, in metres.
pub const EYE_HEIGHT: f32 = 100.0;
/// Steps along the view ray.
pub const VIEW_STEPS: u32 = 24;
/// Steps from each view sample toward the sun.
pub const LIGHT_STEPS: u32 = 6;

/// Rayleigh scattering coefficients at the ground, per metre (red, green, blue).
pub const RAYLEIGH: [f32; 3] = [5.802e-6, 13.558e-6, 33.1e-6];
/// Scale height of the Rayleigh scatterers, in metres.
pub const RAYLEIGH_SCALE: f32 = 8_000.0;
/// Mie scattering coefficient at the ground, per metre.
pub const MIE_SCATTER: f32 = 3.996e-6;
/// Mie extinction coefficient at the ground, per metre.
pub const MIE_EXTINCTION: f32 = 4.44e-6;
/// Scale height of the Mie scatterers, in metres.
pub const MIE_SCALE: f32 = 1_200.0;
/// Asymmetry of the Mie phase function (Cornette–Shanks `g`).
pub const MIE_G: f32 = 0.8;
/// Ozone absorption coefficients at the layer's peak, per metre (red, green, blue).
pub const OZONE: [f32; 3] = [0.650e-6, 1.881e-6, 0.085e-6];
/// Height of the ozone layer's peak, in metres.
pub const OZONE_CENTRE: f32 = 25_000.0;
/// Half the width of the ozone layer's tent profile, in metres.
pub const OZONE_HALF_WIDTH: f32 = 15_000.0;
const PI: f32 = std::f32::consts::PI;

/// Distance from a point at height `h` (above the ground) along a direction whose cosine
/// with the local zenith is `mu`, to the sphere at height `top`; `None` when the ray does
/// not reach it going forward.
fn sphere_distance(h: f32, mu: f32, top: f32) -> Option<f32> {
    let r = PLANET_RADIUS + h;
    // (R + top)² − r² without cancelling the radii.
    let disc = (top - h) * (2.0 * PLANET_RADIUS + top + h) + r * r * mu * mu;
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    let far = -r * mu + s;
    if far < 0.0 {
        return None;
    }
    let near = -r * mu - s;
    Some(if near > 0.0 { near } else { far })
}

/// Extinction coefficients (per metre) at height `h`, and the Rayleigh and Mie densities.
fn medium(h: f32) -> ([f32; 3], f32, f32) {
    let rayleigh = (-h / RAYLEIGH_SCALE).exp();
    let mie = (-h / MIE_SCALE).exp();
    let ozone = (1.0 - (h - OZONE_CENTRE).abs() / OZONE_HALF_WIDTH).max(0.0);
    let sigma = std::array::from_fn(|c| RAYLEIGH[c] * rayleigh + MIE_EXTINCTION * mie + OZONE[c] * ozone);
    (sigma, rayleigh, mie)
}

/// Transmittance from height `h` toward a direction of zenith cosine `mu`, out of the
/// atmosphere; zero when the ground is in the way.
fn sun_transmittance(h: f32, mu: f32) -> [f32; 3] {
    if sphere_distance(h, mu, 0.0).is_some_and(|_| mu < 0.0) {
        return [0.0; 3];
    }
    let length = sphere_distance(h, mu, ATMOSPHERE_HEIGHT).unwrap_or(0.0);
    let dt = length / LIGHT_STEPS as f32;
    let r = PLANET_RADIUS + h;
    let mut depth = [0.0f32; 3];
    for i in 0..LIGHT_STEPS {
        let t = (i as f32 + 0.5) * dt;
        let hi = (t * t + 2.0 * r * mu * t + r * r).sqrt() - PLANET_RADIUS;
        let (sigma, _, _) = medium(hi);
        for c in 0..3 {
            depth[c] += sigma[c] * dt;
        }
    }
    depth.map(|d| (-d).exp())
}

/// Sky radiance along the unit direction `dir` for the unit sun direction `sun`, per unit
/// of the sun's irradiance.
///
/// ```
/// use naadf_client::light::sky::physical;
/// let sun = [0.0, 0.5, 0.866_025_4];
/// let zenith = physical([0.0, 1.0, 0.0], sun);
/// assert!(zenith[2] > zenith[0], "the zenith is blue: {zenith:?}");
/// let near_sun = physical([0.0, 0.52, 0.854], sun);
/// assert!(near_sun[0] > zenith[0], "forward scattering brightens the sky near the sun");
/// ```
pub fn physical(dir: [f32; 3], sun: [f32; 3]) -> [f32; 3] {
    let mu = dir[1];
    let nu = dir[0] * sun[0] + dir[1] * sun[1] + dir[2] * sun[2];
    let h0 = EYE_HEIGHT;
    let r0 = PLANET_RADIUS + h0;
    let length = match sphere_distance(h0, mu, 0.0) {
        Some(ground) if mu < 0.0 => ground,
        _ => sphere_distance(h0, mu, ATMOSPHERE_HEIGHT).unwrap_or(0.0),
    };
    let dt = length / VIEW_STEPS as f32;
    let phase_r = 3.0 / (16.0 * PI) * (1.0 + nu * nu);
    let g2 = MIE_G * MIE_G;
    let phase_m = (1.0 - g2) / (4.0 * PI * (1.0 + g2 - 2.0 * MIE_G * nu).powf(1.5));
    let mut depth = [0.0f32; 3];
    let mut light = [0.0f32; 3];
    for i in 0..VIEW_STEPS {
        let t = (i as f32 + 0.5) * dt;
        let r = (t * t + 2.0 * r0 * mu * t + r0 * r0).sqrt();
        let h = r - PLANET_RADIUS;
        let mu_sun = (r0 * sun[1] + t * nu) / r;
        let (sigma, rayleigh, mie) = medium(h);
        let to_sun = sun_transmittance(h, mu_sun);
        for c in 0..3 {
            let view = (-(depth[c] + 0.5 * sigma[c] * dt)).exp();
            let scatter = RAYLEIGH[c] * rayleigh * phase_r + MIE_SCATTER * mie * phase_m;
            light[c] += view * to_sun[c] * scatter * dt;
            depth[c] += sigma[c] * dt;
        }
    }
    light
}

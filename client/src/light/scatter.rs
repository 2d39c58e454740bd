//! How a surface scatters light: sampling directions and evaluating the BRDF of each
//! material kind (the CPU twin of the sampling functions in `shaders/light.wgsl`).
//!
//! Directions are unit [`DVec3`]s; `n` is the surface normal, `wo` points away from the
//! surface toward where the light goes (the reversed incoming ray), `wi` toward where it
//! comes from.

use glam::DVec3;
use std::f64::consts::PI;

/// The smallest GGX α a metal is traced with: a smoother lobe is a mirror that the sun's
/// disc sample could no longer find.
pub const MIN_ALPHA: f64 = 1e-3;

/// An orthonormal basis `(t, b)` completing the unit vector `n` (Duff et al. 2017).
pub fn basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// A cosine-distributed direction about `n` (pdf cosθ/π), from two uniform numbers.
pub fn cosine(n: DVec3, u: [f64; 2]) -> DVec3 {
    let (t, b) = basis(n);
    let r = u[0].sqrt();
    let phi = 2.0 * PI * u[1];
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u[0]).max(0.0).sqrt()).normalize()
}

/// A direction uniform over the cone about `axis` whose half-angle has `1 − cos = omc`.
pub fn cone(axis: DVec3, omc: f64, u: [f64; 2]) -> DVec3 {
    let (t, b) = basis(axis);
    let x = u[0] * omc;
    let cos = 1.0 - x;
    let sin = (x * (2.0 - x)).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    (t * (sin * phi.cos()) + b * (sin * phi.sin()) + axis * cos).normalize()
}

/// Schlick's Fresnel with reflectance `f0` at normal incidence.
pub fn schlick(f0: DVec3, cos: f64) -> DVec3 {
    f0 + (DVec3::ONE - f0) * (1.0 - cos.clamp(0.0, 1.0)).powi(5)
}

/// Smith's Λ for GGX at a direction of cosine `cos` to the normal.
fn lambda(alpha: f64, cos: f64) -> f64 {
    let c2 = (cos * cos).max(1e-12);
    let tan2 = (1.0 - c2).max(0.0) / c2;
    0.5 * (-1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// The GGX normal distribution at a half vector of cosine `cos`.
fn ggx_d(alpha: f64, cos: f64) -> f64 {
    let a2 = alpha * alpha;
    let k = cos * cos * (a2 - 1.0) + 1.0;
    a2 / (PI * k * k)
}

/// The GGX BRDF (height-correlated Smith masking, Schlick's Fresnel), zero below the surface.
pub fn ggx(n: DVec3, wo: DVec3, wi: DVec3, alpha: f64, f0: DVec3) -> DVec3 {
    let (co, ci) = (n.dot(wo), n.dot(wi));
    if co <= 0.0 || ci <= 0.0 {
        return DVec3::ZERO;
    }
    let h = (wo + wi).normalize();
    let g2 = 1.0 / (1.0 + lambda(alpha, co) + lambda(alpha, ci));
    schlick(f0, wo.dot(h)) * (ggx_d(alpha, n.dot(h)) * g2 / (4.0 * co * ci))
}

/// Samples the GGX lobe through its distribution of visible normals (Heitz 2018): the
/// reflected direction and its weight `BRDF · cos / pdf = F · G2 / G1`.
pub fn ggx_sample(n: DVec3, wo: DVec3, alpha: f64, f0: DVec3, u: [f64; 2]) -> (DVec3, DVec3) {
    let (t, b) = basis(n);
    let v = DVec3::new(wo.dot(t), wo.dot(b), wo.dot(n));
    let vh = DVec3::new(alpha * v.x, alpha * v.y, v.z).normalize();
    let lensq = vh.x * vh.x + vh.y * vh.y;
    let t1 = if lensq > 0.0 {
        DVec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt()
    } else {
        DVec3::X
    };
    let t2 = vh.cross(t1);
    let r = u[0].sqrt();
    let phi = 2.0 * PI * u[1];
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    let m = DVec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0)).normalize();
    let local_wi = m * (2.0 * v.dot(m)) - v;
    let wi = (t * local_wi.x + b * local_wi.y + n * local_wi.z).normalize();
    let (lo, li) = (lambda(alpha, v.z), lambda(alpha, local_wi.z));
    let weight = schlick(f0, v.dot(m)) * ((1.0 + lo) / (1.0 + lo + li));
    (wi, weight)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The VNDF sample's weight is the BRDF over the sampling density: its mean over many
    /// samples equals a brute-force integral of BRDF · cos over the hemisphere (the
    /// directional albedo), which also checks `ggx` against `ggx_sample`.
    #[test]
    fn ggx_sampling_weights_integrate_the_brdf() {
        let n = DVec3::new(0.0, 1.0, 0.0);
        let f0 = DVec3::splat(0.9);
        for (alpha, theta) in [(0.3, 0.4), (0.6, 1.1), (0.15, 0.0)] {
            let wo = DVec3::new(f64::sin(theta), f64::cos(theta), 0.0);
            let k = 512;
            let mut sampled = 0.0;
            for i in 0..k {
                for j in 0..k {
                    let u = [(i as f64 + 0.5) / k as f64, (j as f64 + 0.5) / k as f64];
                    let (wi, w) = ggx_sample(n, wo, alpha, f0, u);
                    if wi.dot(n) > 0.0 {
                        sampled += w.x;
                    }
                }
            }
            sampled /= (k * k) as f64;
            // Brute force: cosine-weighted stratified hemisphere, BRDF · π.
            let mut brute = 0.0;
            let m = 1024;
            for i in 0..m {
                for j in 0..m {
                    let wi = cosine(n, [(i as f64 + 0.5) / m as f64, (j as f64 + 0.5) / m as f64]);
                    brute += ggx(n, wo, wi, alpha, f0).x * PI;
                }
            }
            brute /= (m * m) as f64;
            assert!(
                (sampled - brute).abs() < 0.01 * brute,
                "α {alpha}, θ {theta}: VNDF {sampled} vs brute force {brute}"
            );
        }
    }

    #[test]
    fn cone_samples_stay_inside_the_cone() {
        let axis = DVec3::new(0.3, 0.5, -0.8).normalize();
        let omc = 1.11e-5;
        for i in 0..100 {
            let d = cone(axis, omc, [i as f64 / 100.0, (i * 37 % 100) as f64 / 100.0]);
            assert!(1.0 - d.dot(axis) <= omc * (1.0 + 1e-6) + 1e-15);
            assert!((d.length() - 1.0).abs() < 1e-12);
        }
    }
}

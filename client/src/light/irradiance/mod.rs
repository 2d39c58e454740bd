//! The world-space irradiance cache (`--mode irradiance`; docs/RENDERING.md §3e), after
//! DVBGI (Cosin Ayerbe et al., "Dynamic Voxel-Based Global Illumination"): irradiance
//! kept per visible voxel face in world space, refreshed lazily for the faces the view
//! needs, and reused by every frame.
//!
//! This is the CPU implementation, the second method the GPU's (`shaders/irradiance.wgsl`,
//! `shaders/irradiance_update.wgsl`) is tested against; both follow these rules:
//!
//! - **Entries.** One per face of a world voxel ([`FaceKey`]): the voxel and the face's
//!   outward axis. Entity surfaces have none: they are the dynamic part, lit every frame
//!   (below), so a moving entity never writes its light into an entry.
//! - **A sample of an entry** ([`CpuIrradiance::sample`]): a point uniform on the face,
//!   lifted [`SURFACE_OFFSET`] off it; one sample of the sun's disc (its irradiance when
//!   clear); and one cosine-distributed ray whose radiance is the path tracer's with one
//!   more bounce (`pathtrace --bounces 1` from that point, without the disc), times π.
//!   The ray's direction is sample `n` of Roberts' R2 sequence ([`qmc`]), shifted by two
//!   offsets drawn once per entry (from the stream `(seed, key's stream, u32::MAX)`), so
//!   that consecutive samples of an entry spread evenly over the hemisphere; the point, the
//!   sun's sample and the rest of the path draw from the stream `(seed, key's stream, n)`.
//!   So an
//!   entry's mean is the face's irradiance from the sun, the sky and the light that
//!   bounced once, and a diffuse surface shaded with it matches `pathtrace --bounces 2`.
//! - **Shading** of a diffuse surface of the world: `albedo / π · E` with `E` the mean of
//!   its face's entry. An entity surface, and a face whose entry has no samples yet, are
//!   lit by *gathering* ([`CpuIrradiance::gather`]): one sun sample and one cosine ray,
//!   whose radiance is the sky, or the light of the surface it meets: its emission and,
//!   for a world face, `albedo / π` times that face's entry.
//! - **Freshness** (the GPU's): an entry keeps the mean of at most [`HISTORY`] samples,
//!   halving its sums when full; an edit or an entity move clears every entry within
//!   [`BOUNCE_DISTANCE`] of the changed chunks, so no change near a face stays visible;
//!   a change farther away fades within [`HISTORY`] refreshes.

pub(crate) mod options;

pub use options::{DEFAULT_RAYS, IrradianceOptions, MAX_RAYS, MIN_RAYS};

use super::cpu::{CpuPathTracer, DiffuseTier};
use super::rng::{Rng, pcg_hash};
use super::scatter::cosine;
use super::{Light, SURFACE_OFFSET};
use glam::DVec3;
use naadf_world::World;
use naadf_world::material::MaterialKind;
use naadf_world::traverse::{DEFAULT_MAX_STEPS, Hit, Ray, trace_naadf};
use std::collections::HashMap;
use std::f64::consts::PI;
use std::sync::Mutex;

/// How far from a changed chunk, in voxels, entries are cleared: two chunks. Light that
/// bounced once reaches a face from farther only through faces that see both.
pub const BOUNCE_DISTANCE: f64 = 32.0;
/// The most samples an entry's mean keeps: when full, its sums are halved, so a change
/// that clears nothing still fades.
pub const HISTORY: u32 = 64;

/// The additive recurrence of Roberts' R2 sequence in 32-bit fixed point: `2³² / g` and
/// `2³² / g²`, g the plastic number (the real root of x³ = x + 1).
pub const R2: [u32; 2] = [3_242_174_889, 2_447_445_414];

/// Coordinate `d` of sample `n` of the R2 sequence shifted by `offset` (a Cranley–Patterson
/// rotation), in [0, 1) with 24 bits, as [`Rng::next_f32`] gives them. Integer arithmetic,
/// so the GPU's is the same bit for bit.
pub fn qmc(n: u32, d: usize, offset: u32) -> f32 {
    (n.wrapping_mul(R2[d]).wrapping_add(offset) >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// A face of a world voxel: the key of one entry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct FaceKey {
    /// The voxel, in world coordinates.
    pub voxel: [u32; 3],
    /// `2 · axis + 1` for the face whose outward normal points down the axis, `2 · axis`
    /// up it.
    pub face: u32,
}

impl FaceKey {
    /// The face of `voxel` with outward normal `normal` (a unit axis vector; `None`
    /// otherwise).
    ///
    /// ```
    /// use naadf_client::light::irradiance::FaceKey;
    /// let k = FaceKey::of([3, 4, 5], [0, -1, 0]).unwrap();
    /// assert_eq!(k.face, 3);
    /// assert_eq!(k.normal().to_array(), [0.0, -1.0, 0.0]);
    /// assert!(FaceKey::of([0; 3], [0; 3]).is_none());
    /// ```
    pub fn of(voxel: [u32; 3], normal: [i32; 3]) -> Option<FaceKey> {
        let axis = normal.iter().position(|&c| c != 0)?;
        let face = 2 * axis as u32 + u32::from(normal[axis] < 0);
        Some(FaceKey { voxel, face })
    }

    /// The outward normal.
    pub fn normal(&self) -> DVec3 {
        let mut n = DVec3::ZERO;
        n[(self.face / 2) as usize] = if self.face.is_multiple_of(2) { 1.0 } else { -1.0 };
        n
    }

    /// The point of the face at `u` (each in [0, 1)), lifted [`SURFACE_OFFSET`] off it.
    pub fn point(&self, u: [f64; 2]) -> DVec3 {
        let axis = (self.face / 2) as usize;
        let up = self.face.is_multiple_of(2);
        let mut p = DVec3::from(self.voxel.map(f64::from));
        p[axis] += if up { 1.0 + SURFACE_OFFSET } else { -SURFACE_OFFSET };
        p[(axis + 1) % 3] += u[0];
        p[(axis + 2) % 3] += u[1];
        p
    }

    /// The two words the GPU's table keys the entry by: `x | z << 16` and `y | face << 16`,
    /// each with its top half's or bottom half's spare top bit set, so that neither word of
    /// a key is zero, the empty slot's.
    pub fn words(&self) -> [u32; 2] {
        let [x, y, z] = self.voxel;
        [x | 0x8000 | z << 16, 0x8000_0000 | self.face << 16 | y]
    }

    /// The key of the GPU's words ([`FaceKey::words`]).
    pub fn from_words(w: [u32; 2]) -> FaceKey {
        FaceKey {
            voxel: [w[0] & 0x7FFF, w[1] & 0xFFFF, w[0] >> 16],
            face: (w[1] >> 16) & 0x7,
        }
    }

    /// The entry's random stream: its samples draw from `Rng::new(seed, stream, n)`.
    pub fn stream(&self) -> u32 {
        let [a, b] = self.words();
        pcg_hash(a ^ pcg_hash(b))
    }
}

/// The irradiance cache of one world under one light, converged: each entry the mean of
/// a fixed number of samples, taken when a surface first needs it.
pub struct CpuIrradiance<'w> {
    /// The path tracer that takes the samples (one bounce, no tier).
    tracer: CpuPathTracer<'w>,
    seed: u32,
    samples: u32,
    entries: Mutex<HashMap<FaceKey, DVec3>>,
}

impl<'w> CpuIrradiance<'w> {
    /// The cache of `world` under `light` (its bounce count is ignored): entries are the
    /// means of samples `0..samples` drawn under `seed`.
    pub fn new(world: &'w World, light: Light, seed: u32, samples: u32) -> Self {
        let one_bounce = Light { bounces: 1, ..light };
        CpuIrradiance {
            tracer: CpuPathTracer::new(world, one_bounce, seed),
            seed,
            samples: samples.max(1),
            entries: Mutex::new(HashMap::new()),
        }
    }

    /// Sample `n` of the irradiance of face `key` (module docs).
    pub fn sample(&self, key: FaceKey, n: u32) -> DVec3 {
        let mut offsets = Rng::new(self.seed, key.stream(), u32::MAX);
        let offsets = [offsets.next_u32(), offsets.next_u32()];
        let mut rng = Rng::new(self.seed, key.stream(), n);
        let p = key.point([f64::from(rng.next_f32()), f64::from(rng.next_f32())]);
        let normal = key.normal();
        let mut e = DVec3::splat(self.tracer.sun_sample(p, normal, &mut rng).map_or(0.0, |s| s.1));
        let u = [0, 1].map(|d| f64::from(qmc(n, d, offsets[d])));
        if let Ok(ray) = Ray::new(p.to_array(), cosine(normal, u).to_array()) {
            e += PI * self.tracer.radiance(ray, false, &mut rng);
        }
        e
    }

    /// The irradiance of face `key`: the mean of its samples.
    pub fn irradiance(&self, key: FaceKey) -> DVec3 {
        if let Some(e) = self.entries.lock().expect("irradiance entries").get(&key) {
            return *e;
        }
        let sum: DVec3 = (0..self.samples).map(|n| self.sample(key, n)).sum();
        let e = sum / f64::from(self.samples);
        self.entries.lock().expect("irradiance entries").insert(key, e);
        e
    }

    /// The irradiance at `p` (normal `n`) by gathering: one sun sample, and π times the
    /// radiance of one cosine ray, which is the sky's or that of the surface it meets (its
    /// emission, and for a world face the entry's light).
    pub fn gather(&self, p: DVec3, n: DVec3, rng: &mut Rng) -> DVec3 {
        let mut e = DVec3::splat(self.tracer.sun_sample(p, n, rng).map_or(0.0, |s| s.1));
        let u = [f64::from(rng.next_f32()), f64::from(rng.next_f32())];
        let w = cosine(n, u);
        let Ok(ray) = Ray::new(p.to_array(), w.to_array()) else {
            return e;
        };
        let world = self.tracer.world();
        let Some(hit) = trace_naadf(world, &ray) else {
            return e + PI * self.tracer.sky_seen(w);
        };
        if hit.steps > DEFAULT_MAX_STEPS || hit.normal == [0; 3] {
            return e;
        }
        let Some(m) = world.materials().get(hit.material) else {
            return e;
        };
        let albedo = DVec3::from(m.albedo.map(f64::from));
        let mut l = DVec3::ZERO;
        if m.kind == MaterialKind::Emissive {
            l += albedo * f64::from(m.emission);
        }
        let diffuse = !matches!(m.kind, MaterialKind::Mirror | MaterialKind::Metal);
        if let Some(key) = FaceKey::of(hit.voxel, hit.normal).filter(|_| diffuse && hit.entity.is_none()) {
            l += albedo / PI * self.irradiance(key);
        }
        e += PI * l;
        e
    }
}

impl DiffuseTier for CpuIrradiance<'_> {
    /// `albedo / π` times the entry of the face of `hit`, or, on an entity, what gathering
    /// finds.
    fn diffuse(&self, _: &CpuPathTracer, hit: &Hit, surface: DVec3, n: DVec3, albedo: DVec3, rng: &mut Rng) -> DVec3 {
        match FaceKey::of(hit.voxel, hit.normal).filter(|_| hit.entity.is_none()) {
            Some(key) => albedo / PI * self.irradiance(key),
            None => albedo / PI * self.gather(surface + n * SURFACE_OFFSET, n, rng),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_r2_sequence_fills_the_unit_square_evenly() {
        // 64 consecutive points from any start put 2 to 6 points in each cell of a 4×4 grid
        // (64 random points leave a cell with fewer than 2 or more than 6 in most draws).
        for start in [0u32, 37, 1 << 20, 12_345_678] {
            let mut cells = [0u32; 16];
            for n in start..start + 64 {
                let (x, y) = (qmc(n, 0, 12345), qmc(n, 1, 999));
                cells[(x * 4.0) as usize + 4 * (y * 4.0) as usize] += 1;
            }
            assert!(cells.iter().all(|&c| (2..=6).contains(&c)), "{cells:?}");
        }
    }

    #[test]
    fn keys_round_trip_through_the_gpus_words() {
        for (voxel, face) in [([0, 0, 0], 0), ([16383, 4095, 16383], 5), ([7, 300, 9000], 3)] {
            let k = FaceKey { voxel, face };
            assert_eq!(FaceKey::from_words(k.words()), k);
            assert!(k.words().iter().all(|&w| w != 0));
        }
    }

    #[test]
    fn face_points_lie_just_outside_the_face() {
        for face in 0..6 {
            let k = FaceKey {
                voxel: [10, 20, 30],
                face,
            };
            let p = k.point([0.25, 0.75]);
            let inside = (0..3).all(|a| p[a] >= f64::from(k.voxel[a]) && p[a] < f64::from(k.voxel[a] + 1));
            assert!(!inside, "face {face}: {p}");
            // One offset away from the voxel along the normal only.
            let back = p - k.normal() * (2.0 * SURFACE_OFFSET);
            assert!(
                (0..3).all(|a| back[a] >= f64::from(k.voxel[a]) && back[a] < f64::from(k.voxel[a] + 1)),
                "face {face}: {back}"
            );
        }
    }
}

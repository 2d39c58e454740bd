//! Small deterministic hash and gradient-noise helpers for the presets.
//!
//! Everything here is a pure function of its integer or `f32` inputs (no tables, no
//! state), so generated worlds depend only on the seed and the voxel position, on every
//! platform: the arithmetic is plain IEEE `f32` without fused operations.
//!
//! Why not the `noise` crate: its generators carry a permutation table built per seed,
//! while the presets draw from dozens of derived seeds (`subseed`) inside per-voxel code;
//! a table-free hash-based gradient noise keeps every sample a pure function of
//! (seed, position) with no per-seed setup.

/// Mixes a seed and three integer coordinates into 64 well-distributed bits.
#[inline]
pub(crate) fn hash3(seed: u64, x: i32, y: i32, z: i32) -> u64 {
    let mut h = seed
        ^ (x as u32 as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (y as u32 as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ (z as u32 as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
    h ^= h >> 31;
    h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h ^= h >> 29;
    h = h.wrapping_mul(0x94D0_49BB_1331_11EB);
    h ^ (h >> 32)
}

/// A derived seed: independent streams for independent fields.
#[inline]
pub(crate) fn subseed(seed: u64, k: u64) -> u64 {
    hash3(seed ^ k.wrapping_mul(0xD6E8_FEB8_6659_FD93), k as i32, 0x5EED, 7)
}

/// Uniform in `[0, 1)` from the top 24 bits of a hash.
#[inline]
pub(crate) fn unit(h: u64) -> f32 {
    (h >> 40) as f32 * (1.0 / 16_777_216.0)
}

/// An integer in `lo..=hi` from a hash (and a salt, to draw several from one hash).
#[inline]
pub(crate) fn range(h: u64, salt: u32, lo: i32, hi: i32) -> i32 {
    let r = hash3(h, salt as i32, 0, 0);
    lo + (r % (hi - lo + 1) as u64) as i32
}

/// Quintic fade curve.
#[inline]
fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

#[inline]
fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

/// Hermite smoothstep of `x` between `e0` and `e1`, clamped to `[0, 1]`.
#[inline]
pub(crate) fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// `1/√2`.
const R: f32 = std::f32::consts::FRAC_1_SQRT_2;

const GRAD2: [[f32; 2]; 8] = [
    [1.0, 0.0],
    [-1.0, 0.0],
    [0.0, 1.0],
    [0.0, -1.0],
    [R, R],
    [-R, R],
    [R, -R],
    [-R, -R],
];

/// 2D gradient noise, roughly in `[-1, 1]`, zero at integer points.
#[inline]
pub(crate) fn noise2(seed: u64, x: f32, y: f32) -> f32 {
    let (ix, iy) = (ifloor(x), ifloor(y));
    let (dx, dy) = (x - ix as f32, y - iy as f32);
    let g = |i: i32, j: i32, ox: f32, oy: f32| {
        let v = GRAD2[(hash3(seed, ix + i, iy + j, 0) & 7) as usize];
        v[0] * ox + v[1] * oy
    };
    let (u, v) = (fade(dx), fade(dy));
    let a = lerp(g(0, 0, dx, dy), g(1, 0, dx - 1.0, dy), u);
    let b = lerp(g(0, 1, dx, dy - 1.0), g(1, 1, dx - 1.0, dy - 1.0), u);
    lerp(a, b, v) * 1.41
}

/// Perlin's 12 edge gradients, four of them twice (16 entries: a branch-free lookup).
const GRAD3: [[f32; 3]; 16] = [
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [1.0, -1.0, 0.0],
    [-1.0, -1.0, 0.0],
    [1.0, 0.0, 1.0],
    [-1.0, 0.0, 1.0],
    [1.0, 0.0, -1.0],
    [-1.0, 0.0, -1.0],
    [0.0, 1.0, 1.0],
    [0.0, -1.0, 1.0],
    [0.0, 1.0, -1.0],
    [0.0, -1.0, -1.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [0.0, -1.0, 1.0],
    [0.0, -1.0, -1.0],
];

/// `floor` as an integer, without a libm call (inputs well inside the `i32` range).
#[inline]
fn ifloor(x: f32) -> i32 {
    let i = x as i32;
    i - i32::from(x < i as f32)
}

/// 3D gradient noise (Perlin's edge gradients), roughly in `[-1, 1]`.
#[inline]
pub(crate) fn noise3(seed: u64, x: f32, y: f32, z: f32) -> f32 {
    let (ix, iy, iz) = (ifloor(x), ifloor(y), ifloor(z));
    let (dx, dy, dz) = (x - ix as f32, y - iy as f32, z - iz as f32);
    let g = |i: i32, j: i32, k: i32| {
        let v = GRAD3[(hash3(seed, ix + i, iy + j, iz + k) & 15) as usize];
        v[0] * (dx - i as f32) + v[1] * (dy - j as f32) + v[2] * (dz - k as f32)
    };
    let (u, v, w) = (fade(dx), fade(dy), fade(dz));
    let x00 = lerp(g(0, 0, 0), g(1, 0, 0), u);
    let x10 = lerp(g(0, 1, 0), g(1, 1, 0), u);
    let x01 = lerp(g(0, 0, 1), g(1, 0, 1), u);
    let x11 = lerp(g(0, 1, 1), g(1, 1, 1), u);
    lerp(lerp(x00, x10, v), lerp(x01, x11, v), w) * 0.9
}

/// Fractal sum of `octaves` octaves of [`noise2`], normalised to roughly `[-1, 1]`.
#[inline]
pub(crate) fn fbm2(seed: u64, x: f32, y: f32, octaves: u32) -> f32 {
    let (mut sum, mut amp, mut norm, mut f) = (0.0, 1.0, 0.0, 1.0);
    for o in 0..octaves {
        sum += amp * noise2(seed.wrapping_add(u64::from(o)), x * f, y * f);
        norm += amp;
        amp *= 0.5;
        f *= 2.03;
    }
    sum / norm
}

/// Fractal sum of `octaves` octaves of [`noise3`], normalised to roughly `[-1, 1]`.
#[inline]
pub(crate) fn fbm3(seed: u64, x: f32, y: f32, z: f32, octaves: u32) -> f32 {
    let (mut sum, mut amp, mut norm, mut f) = (0.0, 1.0, 0.0, 1.0);
    for o in 0..octaves {
        sum += amp * noise3(seed.wrapping_add(u64::from(o)), x * f, y * f, z * f);
        norm += amp;
        amp *= 0.5;
        f *= 2.03;
    }
    sum / norm
}

/// Ridged fractal noise in `[0, 1]`: sharp crests where the base noise crosses zero.
#[inline]
pub(crate) fn ridged2(seed: u64, x: f32, y: f32, octaves: u32) -> f32 {
    let (mut sum, mut amp, mut norm, mut f) = (0.0, 1.0, 0.0, 1.0);
    for o in 0..octaves {
        let n = 1.0 - noise2(seed.wrapping_add(u64::from(o)), x * f, y * f).abs();
        sum += amp * n * n;
        norm += amp;
        amp *= 0.5;
        f *= 2.03;
    }
    (sum / norm).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_is_bounded_and_deterministic() {
        let mut lo = f32::MAX;
        let mut hi = f32::MIN;
        for i in 0..20_000 {
            let x = i as f32 * 0.173 - 900.0;
            let y = i as f32 * 0.0711 + 13.0;
            let a = noise2(5, x, y);
            let b = noise3(5, x, y, x * 0.3);
            assert_eq!(a.to_bits(), noise2(5, x, y).to_bits());
            lo = lo.min(a).min(b);
            hi = hi.max(a).max(b);
        }
        assert!(lo > -1.2 && hi < 1.2 && lo < -0.5 && hi > 0.5, "{lo} {hi}");
        assert!((0.0..=1.0).contains(&ridged2(1, 3.3, 4.4, 3)));
        assert!(unit(u64::MAX) < 1.0);
    }
}

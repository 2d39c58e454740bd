//! Hashes: the reference engine's block hash (docs/NAADF.md §4), and XXH3-64, which every
//! checksum and digest page of this project uses (docs/FORMAT.md).
//!
//! XXH3 comes from `twox-hash`, which picks its SIMD code (AVX2 or SSE2 on x86-64) at run
//! time: a build for baseline x86-64 still hashes a 64 KiB page with AVX2 where the CPU has
//! it, about twice as fast as SSE2. Digest pages are rehashed on every edit, on the server
//! and on every mirror.
//!
//! The block hash:
//! `H = C[0] + Σ_{i=0..63} C[i+1]·(v_i & 0x7FFF)` in wrapping `u32` arithmetic, with
//! `C[k] = 31^(64−k)`. Only the material bits enter the hash; equality is always checked
//! on the full content.

use std::hash::Hasher;

/// XXH3-64 with seed 0 of `bytes`.
///
/// ```
/// assert_eq!(naadf_world::hash::xxh3_64(b""), 0x2D06800538D394C2);
/// ```
#[inline]
pub fn xxh3_64(bytes: &[u8]) -> u64 {
    twox_hash::XxHash3_64::oneshot(bytes)
}

/// Streaming XXH3-64 with seed 0: [`Xxh3::digest`] after any sequence of
/// [`Xxh3::update`]s equals [`xxh3_64`] of their concatenation.
///
/// ```
/// use naadf_world::hash::{Xxh3, xxh3_64};
/// let mut h = Xxh3::new();
/// h.update(b"nested ");
/// h.update(b"distance fields");
/// assert_eq!(h.digest(), xxh3_64(b"nested distance fields"));
/// ```
#[derive(Clone, Default)]
pub struct Xxh3(twox_hash::XxHash3_64);

impl Xxh3 {
    /// A hasher that has seen no bytes.
    pub fn new() -> Self {
        Self::default()
    }

    /// Feeds `bytes`.
    #[inline]
    pub fn update(&mut self, bytes: &[u8]) {
        self.0.write(bytes);
    }

    /// The hash of every byte fed so far.
    pub fn digest(&self) -> u64 {
        self.0.finish()
    }
}

const fn coefficients() -> [u32; 65] {
    let mut c = [0u32; 65];
    c[64] = 1;
    let mut k = 64;
    while k > 0 {
        c[k - 1] = c[k].wrapping_mul(31);
        k -= 1;
    }
    c
}

const C: [u32; 65] = coefficients();

/// Hash of a block's 64 voxels (material ids, or 16-bit voxel cells: bit 15 is ignored).
///
/// ```
/// assert_eq!(naadf_world::hash::block_hash(&[0; 64]), 0x4DBF7801);
/// ```
#[inline]
pub fn block_hash(voxels: &[u16; 64]) -> u32 {
    let mut h = C[0];
    for (i, &v) in voxels.iter().enumerate() {
        h = h.wrapping_add(C[i + 1].wrapping_mul(u32::from(v & 0x7FFF)));
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_test_vectors() {
        assert_eq!(block_hash(&[0; 64]), 0x4DBF7801);
        let mut v = [0u16; 64];
        v[0] = 1;
        assert_eq!(block_hash(&v), 0xCC207BE0);
        let mut v = [0u16; 64];
        v[63] = 1;
        assert_eq!(block_hash(&v), 0x4DBF7802);
        let v: [u16; 64] = std::array::from_fn(|i| i as u16);
        assert_eq!(block_hash(&v), 0xCE673821);
    }

    #[test]
    fn solid_flag_is_ignored() {
        let a: [u16; 64] = std::array::from_fn(|i| (i % 3) as u16);
        let b = a.map(|v| if v == 0 { 0 } else { v | 0x8000 });
        assert_eq!(block_hash(&a), block_hash(&b));
    }
}

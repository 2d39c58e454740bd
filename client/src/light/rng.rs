//! The random numbers of a path, the same on the CPU and the GPU (`shaders/light.wgsl`).
//!
//! Each sample of each pixel has its own stream, seeded from the run's seed, the pixel's
//! index and the sample's index (never from a queue slot or a thread), so a frame does not
//! depend on how the work was scheduled, and the sample `s` of a pixel is the same whether
//! it was drawn in one dispatch or in many.

/// The PCG hash (Jarzynski and Olano, "Hash Functions for GPU Rendering", 2020).
#[inline]
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// A PCG-RXS-M-XS 32 stream.
///
/// ```
/// use naadf_client::light::rng::Rng;
/// let mut a = Rng::new(0, 7, 3);
/// let mut b = Rng::new(0, 7, 3);
/// assert_eq!(a.next_u32(), b.next_u32());
/// assert_ne!(Rng::new(0, 7, 4).next_u32(), Rng::new(0, 7, 3).next_u32());
/// let u = a.next_f32();
/// assert!((0.0..1.0).contains(&u));
/// ```
#[derive(Clone, Copy, Debug)]
pub struct Rng {
    state: u32,
}

impl Rng {
    /// The stream of sample `sample` of pixel `pixel` (row-major index) under `seed`.
    pub fn new(seed: u32, pixel: u32, sample: u32) -> Rng {
        Rng {
            state: pcg_hash(seed ^ pcg_hash(pixel ^ pcg_hash(sample))),
        }
    }

    /// The next 32 random bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        self.state = pcg_hash(self.state);
        self.state
    }

    /// A uniform number in [0, 1) with 24 random bits (exact in `f32`).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }
}

//! The inner loop of the batch walk ([`super::batch`]): each ray of a node's list tested
//! against the node's four boxes, and appended to the list of each lane it enters.
//!
//! Every build here makes the same `f32` operations per ray and lane as
//! [`WalkRay::lanes`] (subtract, multiply, minimum, maximum, compare, in the same order),
//! so they sort every ray into the same lists, in the same order; only the work differs:
//! - **plain**, ray by ray, its four lanes as one vector, no branch per ray and lane;
//! - **the same, built for AVX2**;
//! - **AVX-512**: four rays per 512-bit vector (one ray per 128-bit quarter, so the node's
//!   boxes are loaded once per node), and each lane's list filled sixteen rays at a time by
//!   one compress of their ids, where the plain build makes four stores and counts per ray.
//!   Alone, on 1,000 random boxes and 1,024 rays: plain 7.2–7.4 ns per ray and node, AVX2
//!   3.6–3.7 ns, AVX-512 2.6–2.8 ns (BENCHMARKS.md).

use super::node::{Node, WIDTH, WalkRay};

/// Rays a batch holds at most: [`super::Bvh::crossing_many`] takes longer slices in runs of
/// this many, and a list of a node's rays holds at most this many ids. (Lists of a few
/// thousand entries per level stay in the processor's caches.)
pub const BATCH: usize = 1024;
// The plain loop writes one list per lane by name, and ids are `u16`s.
const _: () = assert!(WIDTH == 4 && BATCH.is_power_of_two() && BATCH < 1 << 16);

/// Entries past [`BATCH`] that a list must hold: the AVX-512 build writes sixteen ids at
/// its list's end, of which it keeps those that enter.
pub const LIST_SLACK: usize = 16;

/// Which build of the loop this processor runs (looked up once per walk, not per node).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// Portable code.
    Plain,
    /// The portable code compiled for AVX2.
    #[cfg(target_arch = "x86_64")]
    Avx2,
    /// Four rays per vector and compressed stores (AVX-512 F, DQ, VL, VBMI2, and BMI2).
    #[cfg(target_arch = "x86_64")]
    Avx512,
}

impl Kernel {
    /// The fastest build this processor can run.
    pub fn detect() -> Self {
        #[cfg(target_arch = "x86_64")]
        for k in [Kernel::Avx512, Kernel::Avx2] {
            if k.runs_here() {
                return k;
            }
        }
        Kernel::Plain
    }

    /// Whether this processor has every feature the build enables.
    fn runs_here(self) -> bool {
        match self {
            Kernel::Plain => true,
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => std::is_x86_feature_detected!("avx2"),
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 => avx512::supported(),
        }
    }
}

/// Tests each ray `ids` of `batch` against the four boxes of `n` and appends it to the
/// list of each lane it enters; returns the lists' lengths. Each list holds at least
/// [`BATCH`]` + `[`LIST_SLACK`] entries.
pub fn sort_into_lanes(
    kernel: Kernel,
    n: &Node,
    batch: &[WalkRay],
    ids: &[u16],
    lists: &mut [Vec<u16>; WIDTH],
) -> [usize; WIDTH] {
    match kernel {
        Kernel::Plain => sort_into_lanes_body(n, batch, ids, lists),
        // SAFETY: `detect` picks a build only where the processor has every feature its
        // attribute enables.
        #[cfg(target_arch = "x86_64")]
        Kernel::Avx2 => unsafe { sort_into_lanes_avx2(n, batch, ids, lists) },
        #[cfg(target_arch = "x86_64")]
        Kernel::Avx512 => unsafe { avx512::sort_into_lanes(n, batch, ids, lists) },
    }
}

/// [`sort_into_lanes_body`] compiled for processors with AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn sort_into_lanes_avx2(n: &Node, batch: &[WalkRay], ids: &[u16], lists: &mut [Vec<u16>; WIDTH]) -> [usize; WIDTH] {
    sort_into_lanes_body(n, batch, ids, lists)
}

#[inline(always)]
fn sort_into_lanes_body(n: &Node, batch: &[WalkRay], ids: &[u16], lists: &mut [Vec<u16>; WIDTH]) -> [usize; WIDTH] {
    // Each ray is written to every list and kept (the list's length moved past it) only by
    // the lists of lanes it enters: no branch per ray and lane. Indices stay below `BATCH`
    // (a power of two), which the mask tells the compiler.
    let [l0, l1, l2, l3] = lists;
    let (l0, l1, l2, l3) = (&mut l0[..BATCH], &mut l1[..BATCH], &mut l2[..BATCH], &mut l3[..BATCH]);
    let (mut n0, mut n1, mut n2, mut n3) = (0usize, 0usize, 0usize, 0usize);
    for &i in ids {
        let (near, far) = batch[i as usize].lanes(n);
        l0[n0 & (BATCH - 1)] = i;
        n0 += usize::from(near[0] <= far[0]);
        l1[n1 & (BATCH - 1)] = i;
        n1 += usize::from(near[1] <= far[1]);
        l2[n2 & (BATCH - 1)] = i;
        n2 += usize::from(near[2] <= far[2]);
        l3[n3 & (BATCH - 1)] = i;
        n3 += usize::from(near[3] <= far[3]);
    }
    [n0, n1, n2, n3]
}

/// The AVX-512 build.
#[cfg(target_arch = "x86_64")]
mod avx512 {
    use super::{BATCH, LIST_SLACK, Node, WIDTH, WalkRay};
    use std::arch::x86_64::*;

    // A ray is eight `f32`s: origin, inverse direction, window.
    const _: () = assert!(size_of::<WalkRay>() == 32 && WIDTH == 4 && LIST_SLACK >= 16);

    /// Whether the processor has every feature [`sort_into_lanes`] enables.
    pub(super) fn supported() -> bool {
        std::is_x86_feature_detected!("avx512f")
            && std::is_x86_feature_detected!("avx512dq")
            && std::is_x86_feature_detected!("avx512vl")
            && std::is_x86_feature_detected!("avx512vbmi2")
            && std::is_x86_feature_detected!("bmi2")
    }

    /// A node's six rows of planes (`lo` and `hi` of each axis), each row repeated in the
    /// four quarters of a vector.
    struct Planes {
        lo: [__m512; 3],
        hi: [__m512; 3],
    }

    /// [`super::sort_into_lanes`], sixteen rays at a time.
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512vbmi2,bmi2")]
    pub(super) fn sort_into_lanes(
        n: &Node,
        batch: &[WalkRay],
        ids: &[u16],
        lists: &mut [Vec<u16>; WIDTH],
    ) -> [usize; WIDTH] {
        let row = |r: &[f32; WIDTH]| {
            // SAFETY: `r` holds the four floats read.
            _mm512_broadcast_f32x4(unsafe { _mm_loadu_ps(r.as_ptr()) })
        };
        let planes = Planes {
            lo: n.lo.each_ref().map(row),
            hi: n.hi.each_ref().map(row),
        };
        let mut len = [0usize; WIDTH];
        let mut chunks = ids.chunks_exact(16);
        for chunk in &mut chunks {
            let chunk: &[u16; 16] = chunk.try_into().expect("chunks of 16");
            sixteen(&planes, batch, chunk, 16, lists, &mut len);
        }
        let rest = chunks.remainder();
        if let Some(&first) = rest.first() {
            // The missing rays repeat a real one; their bits are dropped.
            let mut chunk = [first; 16];
            chunk[..rest.len()].copy_from_slice(rest);
            sixteen(&planes, batch, &chunk, rest.len(), lists, &mut len);
        }
        len
    }

    /// Sorts the first `valid` rays of `ids` into the lists, whose lengths are `len` (the
    /// rest repeat a real ray and are dropped; only the quarters that hold real rays are
    /// tested, as short lists are common deep in the tree).
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512vbmi2,bmi2")]
    fn sixteen(
        planes: &Planes,
        batch: &[WalkRay],
        ids: &[u16; 16],
        valid: usize,
        lists: &mut [Vec<u16>; WIDTH],
        len: &mut [usize; WIDTH],
    ) {
        // Bit `4 j + l` of `met`: ray `j` enters lane `l`.
        let mut met = 0u64;
        for q in 0..valid.div_ceil(4) {
            let quad: [&WalkRay; 4] = std::array::from_fn(|k| &batch[ids[4 * q + k] as usize]);
            met |= u64::from(quad_mask(planes, quad)) << (16 * q);
        }
        let keep = (1u32 << valid) - 1;
        // SAFETY: `ids` holds the sixteen `u16`s read.
        let idv = unsafe { _mm256_loadu_si256(ids.as_ptr().cast()) };
        for (l, list) in lists.iter_mut().enumerate() {
            let bits = _pext_u64(met, 0x1111_1111_1111_1111 << l) as u32 & keep;
            let packed = _mm256_maskz_compress_epi16(bits as __mmask16, idv);
            // The list's capacity past `BATCH` takes the sixteen written; only the
            // `count_ones` kept count. (A list never holds more than `BATCH` rays.)
            let at = &mut list[len[l]..len[l] + 16];
            // SAFETY: `at` holds the sixteen `u16`s written.
            unsafe { _mm256_storeu_si256(at.as_mut_ptr().cast(), packed) };
            len[l] += bits.count_ones() as usize;
        }
        debug_assert!(len.iter().all(|&k| k <= BATCH));
    }

    /// Bit `4 k + l`: ray `k` of `quad` enters lane `l`, by the arithmetic of
    /// [`WalkRay::lanes`], with the four rays in the four quarters of each vector.
    #[inline]
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512vbmi2,bmi2")]
    fn quad_mask(planes: &Planes, quad: [&WalkRay; 4]) -> u16 {
        // SAFETY: a `WalkRay` is eight `f32`s (`repr(C)`, asserted above).
        let load = |r: &WalkRay| unsafe { _mm256_loadu_ps((r as *const WalkRay).cast()) };
        let a = _mm512_insertf32x8::<1>(_mm512_castps256_ps512(load(quad[0])), load(quad[1]));
        let b = _mm512_insertf32x8::<1>(_mm512_castps256_ps512(load(quad[2])), load(quad[3]));
        // Field `f` of each ray across its quarter: `a` holds rays 0 and 1, `b` rays 2 and 3.
        let field = |f: i32| {
            let idx = _mm512_setr_epi32(
                f,
                f,
                f,
                f,
                8 + f,
                8 + f,
                8 + f,
                8 + f,
                16 + f,
                16 + f,
                16 + f,
                16 + f,
                24 + f,
                24 + f,
                24 + f,
                24 + f,
            );
            _mm512_permutex2var_ps(a, idx, b)
        };
        let mut near = field(6);
        let mut far = field(7);
        for axis in 0..3 {
            let (o, inv) = (field(axis as i32), field(3 + axis as i32));
            let t0 = _mm512_mul_ps(_mm512_sub_ps(planes.lo[axis], o), inv);
            let t1 = _mm512_mul_ps(_mm512_sub_ps(planes.hi[axis], o), inv);
            near = _mm512_max_ps(near, _mm512_min_ps(t0, t1));
            far = _mm512_min_ps(far, _mm512_max_ps(t0, t1));
        }
        _mm512_cmp_ps_mask::<_CMP_LE_OQ>(near, far)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::entity::bvh::{Aabb, Bvh};

    /// Every build this processor runs sorts rays into the same lists as the plain one,
    /// for lists of every length (full runs of sixteen and the rest), rays that only touch
    /// a box included.
    #[test]
    fn every_build_of_the_loop_agrees_with_the_plain_one() {
        let mut rng = crate::raysets::SplitMix64(5);
        let boxes: Vec<Aabb> = (0..500)
            .map(|_| {
                let lo = [0; 3].map(|_| rng.unit() * 200.0);
                (lo, lo.map(|v| v + 10.0 * rng.unit()))
            })
            .collect();
        let bvh = Bvh::build(&boxes);
        let batch: Vec<WalkRay> = (0..BATCH)
            .map(|k| {
                let o = [0; 3].map(|_| rng.unit() * 240.0 - 20.0);
                // Every eighth ray moves along an axis alone.
                let d = if k % 8 == 0 {
                    let mut d = [0.0; 3];
                    d[k / 8 % 3] = if k % 16 == 0 { 1.0 } else { -1.0 };
                    d
                } else {
                    [0; 3].map(|_| rng.unit() - 0.5)
                };
                WalkRay::new(o, d, 0.0, 300.0 * rng.unit())
            })
            .collect();
        let all: Vec<u16> = (0..BATCH as u16).rev().collect();
        let fresh = || std::array::from_fn(|_| vec![0u16; BATCH + LIST_SLACK]);
        let mut kernels = vec![Kernel::Plain];
        #[cfg(target_arch = "x86_64")]
        kernels.extend([Kernel::Avx2, Kernel::Avx512].into_iter().filter(|k| k.runs_here()));
        assert!(kernels.contains(&Kernel::detect()));
        let mut entered = 0;
        for n in &bvh.nodes {
            // Every third ray's window ends just where it enters a box: it touches the box.
            let mut batch = batch.clone();
            for r in batch.iter_mut().step_by(3) {
                let (near, far) = r.lanes(n);
                if let Some(l) = (0..WIDTH).find(|&l| near[l] <= far[l]) {
                    r.t_hi = near[l];
                }
            }
            for take in [0, 1, 15, 16, 17, 100, BATCH] {
                let ids = &all[..take];
                let mut want = fresh();
                let want_len = sort_into_lanes(Kernel::Plain, n, &batch, ids, &mut want);
                entered += want_len.iter().sum::<usize>();
                for &k in &kernels[1..] {
                    let mut got = fresh();
                    let got_len = sort_into_lanes(k, n, &batch, ids, &mut got);
                    assert_eq!(got_len, want_len, "{k:?}");
                    for l in 0..WIDTH {
                        assert_eq!(got[l][..got_len[l]], want[l][..want_len[l]], "{k:?}");
                    }
                }
            }
        }
        assert!(entered > 0, "some rays enter some boxes");
    }
}

//! 3D prefix sums: count marked cells in any box in O(1).

/// Summed-volume table over a `d[0] × d[1] × d[2]` grid (x fastest).
pub(crate) struct PrefixSum3 {
    d: [usize; 3],
    sum: Vec<u32>,
}

impl PrefixSum3 {
    /// Builds the table from a per-cell count.
    pub(crate) fn new(d: [usize; 3], value: impl Fn(usize, usize, usize) -> u32) -> Self {
        let mut t = PrefixSum3 {
            d,
            sum: vec![0; (d[0] + 1) * (d[1] + 1) * (d[2] + 1)],
        };
        for z in 1..=d[2] {
            for y in 1..=d[1] {
                for x in 1..=d[0] {
                    let v = value(x - 1, y - 1, z - 1) + t.at(x - 1, y, z) + t.at(x, y - 1, z) + t.at(x, y, z - 1)
                        - t.at(x - 1, y - 1, z)
                        - t.at(x - 1, y, z - 1)
                        - t.at(x, y - 1, z - 1)
                        + t.at(x - 1, y - 1, z - 1);
                    let i = t.index(x, y, z);
                    t.sum[i] = v;
                }
            }
        }
        t
    }

    #[inline]
    fn index(&self, x: usize, y: usize, z: usize) -> usize {
        x + (self.d[0] + 1) * (y + (self.d[1] + 1) * z)
    }

    #[inline]
    fn at(&self, x: usize, y: usize, z: usize) -> u32 {
        self.sum[self.index(x, y, z)]
    }

    /// The total over the half-open box `lo..hi` (each corner clamped to the grid).
    pub(crate) fn count(&self, lo: [i64; 3], hi: [i64; 3]) -> i64 {
        let c = |v: i64, a: usize| v.clamp(0, self.d[a] as i64) as usize;
        let (a, b) = (
            [c(lo[0], 0), c(lo[1], 1), c(lo[2], 2)],
            [c(hi[0], 0), c(hi[1], 1), c(hi[2], 2)],
        );
        if (0..3).any(|k| a[k] >= b[k]) {
            return 0;
        }
        let s = |x, y, z| i64::from(self.at(x, y, z));
        s(b[0], b[1], b[2]) - s(a[0], b[1], b[2]) - s(b[0], a[1], b[2]) - s(b[0], b[1], a[2])
            + s(a[0], a[1], b[2])
            + s(a[0], b[1], a[2])
            + s(b[0], a[1], a[2])
            - s(a[0], a[1], a[2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_match_brute_force() {
        let d = [5, 4, 6];
        let v = |x: usize, y: usize, z: usize| u32::from((x * 7 + y * 3 + z * 11).is_multiple_of(4));
        let t = PrefixSum3::new(d, v);
        for lo in [[0i64, 0, 0], [1, 2, 3], [-3, 1, 0]] {
            for hi in [[5i64, 4, 6], [3, 3, 4], [9, 9, 9], [1, 2, 3]] {
                let mut n = 0;
                for z in 0..6 {
                    for y in 0..4 {
                        for x in 0..5 {
                            let p = [x as i64, y as i64, z as i64];
                            if (0..3).all(|k| p[k] >= lo[k] && p[k] < hi[k]) {
                                n += i64::from(v(x, y, z));
                            }
                        }
                    }
                }
                assert_eq!(t.count(lo, hi), n, "{lo:?}..{hi:?}");
            }
        }
    }
}

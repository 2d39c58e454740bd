//! Keeping chunk AADFs safe across edits.
//!
//! When chunks stop being free (they gain solid voxels, or entities), every free chunk
//! whose AADF box contains one of them is reset to a zero AADF in the same version; that
//! keeps the safety invariant. When chunks change freedom either way, the chunks around
//! them are recomputed from scratch in the background ([`crate::aadf::GrowthJob`]).

use super::writes::Writes;
use crate::aadf::chunk_is_free;
use crate::cell::{Aadf, CHUNK_FIELD_BITS, MAX_CHUNK_FIELD};
use crate::digest::BufferId;
use crate::prefix::PrefixSum3;
use crate::world::World;
use rayon::prelude::*;

/// Boxes of at least this many chunks are scanned on the thread pool.
const PARALLEL_CLAMP_CHUNKS: usize = 1 << 20;

impl World {
    /// Resets every free chunk whose AADF box contains one of `origins` (chunks that just
    /// stopped being free). Uses a prefix sum of the origins over their bounding box, grown
    /// by the largest possible box extent.
    pub(crate) fn clamp_around(&mut self, origins: &[usize], w: &mut Writes) {
        if origins.is_empty() {
            return;
        }
        let size = self.size;
        let dims = size.chunks();
        let reach = u32::from(MAX_CHUNK_FIELD);
        let coords: Vec<[u32; 3]> = origins.iter().map(|&i| size.chunk_coords(i)).collect();
        let lo: [u32; 3] =
            std::array::from_fn(|a| coords.iter().map(|c| c[a]).min().unwrap_or(0).saturating_sub(reach));
        let hi: [u32; 3] =
            std::array::from_fn(|a| (coords.iter().map(|c| c[a]).max().unwrap_or(0) + reach + 1).min(dims[a]));
        let d: [usize; 3] = std::array::from_fn(|a| (hi[a] - lo[a]) as usize);
        // Few origins (the usual edit): test each box against each origin directly. Many:
        // count origins in each box with a prefix sum over a dense mark grid.
        let local: Vec<[i64; 3]> = coords
            .iter()
            .map(|c| std::array::from_fn(|a| i64::from(c[a] - lo[a])))
            .collect();
        let prefix = (local.len() > 16).then(|| {
            let mut marks = vec![0u32; d[0] * d[1] * d[2]];
            for c in &local {
                marks[c[0] as usize + d[0] * (c[1] as usize + d[1] * c[2] as usize)] = 1;
            }
            PrefixSum3::new(d, |x, y, z| marks[x + d[0] * (y + d[1] * z)])
        });
        let contains = |a: [i64; 3], b: [i64; 3]| match &prefix {
            Some(p) => p.count(a, b) > 0,
            None => local.iter().any(|o| (0..3).all(|k| a[k] <= o[k] && o[k] < b[k])),
        };
        let chunks = &self.chunks;
        let layer = |z: u32| {
            let mut out = Vec::new();
            for y in lo[1]..hi[1] {
                for x in lo[0]..hi[0] {
                    let p = [x, y, z];
                    let i = size.chunk_index(p);
                    let c = chunks[i];
                    if c == 0 || !chunk_is_free(c) {
                        continue;
                    }
                    let f = Aadf::unpack(c, CHUNK_FIELD_BITS);
                    // The box in the bounding box's coordinates.
                    let a: [i64; 3] =
                        std::array::from_fn(|k| i64::from(p[k]) - i64::from(f.0[2 * k]) - i64::from(lo[k]));
                    let b: [i64; 3] =
                        std::array::from_fn(|k| i64::from(p[k]) + i64::from(f.0[2 * k + 1]) + 1 - i64::from(lo[k]));
                    if contains(a, b) {
                        out.push(i);
                    }
                }
            }
            out
        };
        // One edit's box (up to 63³ chunks) takes a fraction of a millisecond on one
        // thread; handing it to the pool costs thread wake-ups and, under load, CPU that
        // idle workers burn spinning. Only batches whose box is far larger go parallel.
        let reset: Vec<usize> = if d[0] * d[1] * d[2] >= PARALLEL_CLAMP_CHUNKS {
            (lo[2]..hi[2]).into_par_iter().flat_map_iter(layer).collect()
        } else {
            (lo[2]..hi[2]).flat_map(layer).collect()
        };
        for i in reset {
            self.chunks[i] = 0;
            w.push(BufferId::Chunks, i, 1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::preset::Preset;
    use crate::raysets::SplitMix64;
    use crate::size::WorldSize;

    /// The oracle: every free chunk with a nonzero field whose box holds an origin, found
    /// by testing every chunk of the world against every origin.
    fn brute_force(w: &World, origins: &[usize]) -> Vec<usize> {
        let size = w.size();
        (0..size.chunk_count())
            .filter(|&i| w.chunks()[i] != 0 && chunk_is_free(w.chunks()[i]))
            .filter(|&i| {
                let f = Aadf::unpack(w.chunks()[i], CHUNK_FIELD_BITS);
                let p = size.chunk_coords(i).map(i64::from);
                origins.iter().any(|&o| {
                    let o = size.chunk_coords(o).map(i64::from);
                    (0..3).all(|k| p[k] - i64::from(f.0[2 * k]) <= o[k] && o[k] <= p[k] + i64::from(f.0[2 * k + 1]))
                })
            })
            .collect()
    }

    #[test]
    fn clamping_resets_exactly_the_boxes_that_hold_an_origin() {
        let size = WorldSize::new(512, 128, 256).unwrap();
        let world = World::build(&*Preset::Terrain.source(Some(size), 5).unwrap(), &|_| {}).unwrap();
        let mut rng = SplitMix64(11);
        // 1–3 origins take the lane test, 40 the prefix sum.
        for count in [1, 1, 2, 3, 40] {
            let origins: Vec<usize> = (0..count)
                .map(|_| rng.below(size.chunk_count() as u32) as usize)
                .collect();
            let want = brute_force(&world, &origins);
            let mut w = world.clone();
            let mut writes = Writes::default();
            w.clamp_around(&origins, &mut writes);
            let got: Vec<usize> = (0..size.chunk_count())
                .filter(|&i| w.chunks()[i] != world.chunks()[i])
                .collect();
            assert!(!want.is_empty(), "origins {origins:?} reset nothing: a weak test");
            assert_eq!(got, want, "origins {origins:?}");
            assert!(got.iter().all(|&i| w.chunks()[i] == 0));
        }
    }
}

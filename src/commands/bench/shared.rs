//! What the benchmarks share: percentiles and medians, the ratio report, the surface of a
//! world column, and the entity model.

use naadf_world::World;
use naadf_world::ops::Op;
use naadf_world::traverse::{Ray, trace_naadf};
use std::collections::BTreeMap;

/// The first solid voxel below the top of the world at column (x, z), if any.
pub fn surface(world: &World, x: u32, z: u32) -> Option<[u32; 3]> {
    let top = f64::from(world.size().voxels()[1]) - 0.5;
    let ray = Ray::new([f64::from(x) + 0.5, top, f64::from(z) + 0.5], [0.0, -1.0, 0.0]).ok()?;
    trace_naadf(world, &ray).map(|h| h.voxel)
}

/// The `q` quantile (0–1) of `sorted`, by nearest rank; NaN when empty.
pub fn percentile(sorted: &[f64], q: f64) -> f64 {
    sorted
        .get(((sorted.len() as f64 - 1.0) * q).round() as usize)
        .copied()
        .unwrap_or(f64::NAN)
}

/// The median of `values` (nearest rank) and their lowest and highest; NaN when empty.
pub fn median_range(values: &[f64]) -> (f64, [f64; 2]) {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let (lo, hi) = (v.first().copied(), v.last().copied());
    (percentile(&v, 0.5), [lo.unwrap_or(f64::NAN), hi.unwrap_or(f64::NAN)])
}

/// Prints `naadf`'s speed-up over every other method measured, from Mrays/s per method.
pub fn print_ratios(prefix: &str, primary: &BTreeMap<&str, f64>, secondary: &BTreeMap<&str, f64>) {
    let ratio = |set: &BTreeMap<&str, f64>, other: &str| set.get(other).map_or(f64::NAN, |o| set["naadf"] / o);
    for &other in primary.keys().filter(|&&m| m != "naadf") {
        println!(
            "{prefix}naadf/{other}: primary {:.1}×, secondary {:.1}×",
            ratio(primary, other),
            ratio(secondary, other)
        );
    }
}

/// Defines the 8³ hollow-box model used by entity benchmarks.
pub fn entity_model_op() -> Op {
    let mut voxels = Vec::new();
    for z in 0..8i64 {
        for y in 0..8i64 {
            for x in 0..8i64 {
                if [x, y, z].iter().any(|&c| c == 0 || c == 7) {
                    voxels.push([x, y, z, 1]);
                }
            }
        }
    }
    Op::DefineModel {
        name: "bench_box".into(),
        size: [8, 8, 8],
        voxels,
    }
}

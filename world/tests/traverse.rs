//! The three traversal methods agree exactly on many rays, and the hits are right by brute
//! force against the raw volume.

mod common;

use common::{Raw, Rng, adversarial, random_world, rays};
use naadf_world::WorldSize;
use naadf_world::traverse::{DenseGrid, Hit, Method, Ray, Tracer, same_result, trace_naadf, trace_nodf};

/// Brute-force checks of a hit: the voxel is solid with that material, the entry point
/// lies on the reported face, and no solid voxel lies on the ray before it.
fn check_hit(raw: &Raw, ray: &Ray, hit: &Option<Hit>) {
    let (o, d) = (ray.origin(), ray.dir());
    let Some(h) = hit else {
        // A miss: sample the ray densely inside the world; nothing solid may be found.
        for k in 0..4000 {
            let t = k as f64 * 0.05 + 0.0137;
            let p = [0, 1, 2].map(|a| o[a] + d[a] * t);
            let c = p.map(|v| v.floor() as i64);
            if raw.size.contains(c) {
                let frac_ok = (0..3).all(|a| (p[a] - p[a].round()).abs() > 1e-6);
                assert!(
                    !frac_ok || raw.get(c.map(|v| v as u32)) == 0,
                    "miss, but {c:?} is solid on the ray at t={t}"
                );
            }
        }
        return;
    };
    assert_eq!(raw.get(h.voxel), h.material, "hit voxel {:?} material", h.voxel);
    assert_ne!(h.material, 0);
    let p = [0, 1, 2].map(|a| o[a] + d[a] * h.t);
    for a in 0..3 {
        let lo = f64::from(h.voxel[a]);
        assert!(
            p[a] >= lo - 1e-6 && p[a] <= lo + 1.0 + 1e-6,
            "entry point {p:?} not on voxel {:?}",
            h.voxel
        );
        if h.normal[a] != 0 {
            let face = if h.normal[a] < 0 { lo } else { lo + 1.0 };
            assert!(
                (p[a] - face).abs() < 1e-6,
                "entry point {p:?} not on face {:?} of {:?}",
                h.normal,
                h.voxel
            );
        }
    }
    // Nothing solid strictly before the hit (sampled between cell boundaries).
    for k in 0..2000 {
        let t = h.t * (k as f64 + 0.5) / 2000.0;
        let q = [0, 1, 2].map(|a| o[a] + d[a] * t);
        let c = q.map(|v| v.floor() as i64);
        let clear_of_planes = (0..3).all(|a| (q[a] - q[a].round()).abs() > 1e-6);
        if clear_of_planes && raw.size.contains(c) && c != h.voxel.map(i64::from) {
            assert_eq!(
                raw.get(c.map(|v| v as u32)),
                0,
                "solid voxel {c:?} before the hit at t={t} < {}",
                h.t
            );
        }
    }
}

fn agree_on(raw: &Raw, seed: u64, n: usize) {
    let w = raw.build();
    let grid = DenseGrid::from_world(&w).unwrap();
    let mut rng = Rng(seed);
    let mut hits = 0;
    for (i, ray) in rays(raw.size.voxels(), &mut rng, n).iter().enumerate() {
        let a = trace_naadf(&w, ray);
        let b = trace_nodf(&w, ray);
        let c = grid.trace(ray);
        assert!(
            same_result(&a, &b) && same_result(&a, &c),
            "ray {i} {ray:?}: naadf {a:?} / nodf {b:?} / grid {c:?}"
        );
        if i % 8 == 0 {
            check_hit(raw, ray, &a);
        }
        if let (Some(x), Some(y)) = (a, b) {
            assert!(
                x.steps <= y.steps,
                "AADF jumps never take more steps: {} > {}",
                x.steps,
                y.steps
            );
        }
        hits += usize::from(a.is_some());
    }
    assert!(hits > 0, "no ray hit anything");
}

#[test]
fn methods_agree_on_random_worlds() {
    for seed in 0..6u64 {
        let size = common::size_for(seed, &[[64, 64, 64], [128, 64, 64], [64, 128, 192]]);
        agree_on(&random_world(size, seed * 31 + 1), seed, 1500);
    }
}

#[test]
fn methods_agree_on_adversarial_worlds() {
    for (name, raw) in adversarial(WorldSize::new(64, 64, 128).unwrap()) {
        if name == "empty" {
            let w = raw.build();
            let mut rng = Rng(5);
            for ray in rays(raw.size.voxels(), &mut rng, 300) {
                assert_eq!(trace_naadf(&w, &ray), None);
                assert_eq!(trace_nodf(&w, &ray), None);
            }
            continue;
        }
        agree_on(&raw, 77, 1200);
    }
}

#[test]
fn contract_cases() {
    let size = WorldSize::new(64, 64, 64).unwrap();
    let mut raw = Raw::empty(size, 3);
    raw.set([10, 10, 10], 3);
    raw.set([0, 0, 0], 2);
    raw.set([63, 5, 5], 1);
    let w = raw.build();
    for m in Method::ALL {
        let t = Tracer::new(&w, m).unwrap();
        // Origin inside a solid voxel: t = 0, zero normal.
        let h = t
            .trace(&Ray::new([10.5, 10.2, 10.9], [0.3, 1.0, 0.0]).unwrap())
            .unwrap();
        assert_eq!(
            (h.voxel, h.normal, h.t, h.material),
            ([10, 10, 10], [0, 0, 0], 0.0, 3),
            "{m:?}"
        );
        // Straight at a face; t is along the normalised direction.
        let h = t.trace(&Ray::new([10.5, 10.5, 2.0], [0.0, 0.0, 5.0]).unwrap()).unwrap();
        assert_eq!((h.voxel, h.normal, h.t), ([10, 10, 10], [0, 0, -1], 8.0), "{m:?}");
        // From outside the world: enters through the box itself, no inset.
        let h = t.trace(&Ray::new([-3.0, 0.5, 0.5], [1.0, 0.0, 0.0]).unwrap()).unwrap();
        assert_eq!(
            (h.voxel, h.normal, h.t, h.material),
            ([0, 0, 0], [-1, 0, 0], 3.0, 2),
            "{m:?}"
        );
        let h = t
            .trace(&Ray::new([100.0, 5.5, 5.5], [-1.0, 0.0, 0.0]).unwrap())
            .unwrap();
        assert_eq!((h.voxel, h.normal, h.t), ([63, 5, 5], [1, 0, 0], 36.0), "{m:?}");
        // Missing the box entirely, and leaving it.
        assert_eq!(t.trace(&Ray::new([-1.0, 70.0, 5.0], [1.0, 0.0, 0.0]).unwrap()), None);
        assert_eq!(t.trace(&Ray::new([5.5, 5.5, 5.5], [0.0, 1.0, 0.0]).unwrap()), None);
        // A diagonal through the edge between (9,9,10)/(10,10,10): x steps before y, so the ray
        // passes (10,9,10), which is empty, then enters (10,10,10) through its −y face.
        let h = t.trace(&Ray::new([8.0, 8.0, 10.5], [1.0, 1.0, 0.0]).unwrap()).unwrap();
        assert_eq!((h.voxel, h.normal), ([10, 10, 10], [0, -1, 0]), "{m:?}");
    }
}

#[test]
fn methods_agree_on_preset_worlds_from_fixed_cameras() {
    use naadf_world::preset::Preset;
    use naadf_world::raysets::{fixed_cameras, primary_rays, secondary_rays};
    for (preset, size) in [("terrain", [256, 128, 256]), ("test", [64, 64, 128])] {
        let size = WorldSize::new(size[0], size[1], size[2]).unwrap();
        let source = Preset::parse(preset).unwrap().source(Some(size), 3).unwrap();
        let w = naadf_world::World::build(&*source, &|_| {}).unwrap();
        let grid = DenseGrid::from_world(&w).unwrap();
        let primary = primary_rays(&fixed_cameras(size), 48, 27);
        let hits: Vec<Option<Hit>> = primary.iter().map(|r| trace_naadf(&w, r)).collect();
        assert!(
            hits.iter().filter(|h| h.is_some()).count() > primary.len() / 4,
            "{preset}: cameras see little"
        );
        let secondary = secondary_rays(&primary, &hits, 9);
        for ray in primary.iter().chain(&secondary) {
            let a = trace_naadf(&w, ray);
            let (b, c) = (trace_nodf(&w, ray), grid.trace(ray));
            assert!(
                same_result(&a, &b) && same_result(&a, &c),
                "{preset} {ray:?}: {a:?} / {b:?} / {c:?}"
            );
        }
    }
}

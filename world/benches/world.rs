//! Micro-benchmarks of the world core (criterion). Whole-world figures come from
//! `naadf bench build` and `naadf bench traverse`; see BENCHMARKS.md.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use naadf_world::aadf::{cell_aadf4, grid_aadf};
use naadf_world::baselines::Svdag;
use naadf_world::build::group_words;
use naadf_world::hash::block_hash;
use naadf_world::preset::Preset;
use naadf_world::raysets::{fixed_cameras, primary_rays};
use naadf_world::traverse::{Method, Tracer};
use naadf_world::{World, WorldSize};
use std::hint::black_box;

fn cells(c: &mut Criterion) {
    let voxels: [u16; 64] = std::array::from_fn(|i| if (i * 7) % 5 == 0 { 3 } else { 0 });
    c.bench_function("block_hash", |b| b.iter(|| block_hash(black_box(&voxels))));
    c.bench_function("group_words (hash-free encode + voxel AADF)", |b| {
        b.iter(|| group_words(black_box(&voxels)))
    });
    let mask = 0x0F0F_00FF_F0F0_FF00u64;
    c.bench_function("cell_aadf4 bit-sliced", |b| b.iter(|| cell_aadf4(black_box(mask))));
    let flags: Vec<bool> = (0..64).map(|i| mask >> i & 1 == 1).collect();
    c.bench_function("cell_aadf4 scalar reference", |b| {
        b.iter(|| grid_aadf([4, 4, 4], black_box(&flags), 3, false))
    });
}

fn build_and_trace(c: &mut Criterion) {
    let size = WorldSize::new(256, 128, 256).unwrap();
    let source = Preset::Terrain.source(Some(size), 3).unwrap();
    let mut g = c.benchmark_group("terrain 256×128×256");
    g.sample_size(10);
    g.throughput(Throughput::Elements(size.voxel_count()));
    g.bench_function("build (generation included)", |b| {
        b.iter(|| World::build(&*source, &|_| {}).unwrap())
    });
    let world = World::build(&*source, &|_| {}).unwrap();
    let rays = primary_rays(&fixed_cameras(size), 64, 36);
    g.throughput(Throughput::Elements(rays.len() as u64));
    for m in Method::ALL {
        let t = Tracer::new(&world, m).unwrap();
        g.bench_function(format!("primary rays {}", m.name()), |b| {
            b.iter(|| rays.iter().filter(|r| t.trace(r).is_some()).count())
        });
    }
    // The paper's SVDAG baseline on the same rays (docs/BASELINES.md).
    let dag = Svdag::build(&world).unwrap();
    g.bench_function("primary rays svdag", |b| {
        b.iter(|| rays.iter().filter(|r| dag.trace(r).is_some()).count())
    });
    g.throughput(Throughput::Elements(size.voxel_count()));
    g.bench_function("svdag build", |b| b.iter(|| Svdag::build(&world).unwrap()));
    g.finish();
}

criterion_group!(benches, cells, build_and_trace);
criterion_main!(benches);

//! The `test` preset: a small world built to exercise every cell kind.
//!
//! It holds a stone ground (whole full chunks) under a bumpy grass layer, random solid
//! spheres and boxes of several materials, a hollow box, thin pillars, a box that fills
//! exactly one chunk, single voxels at chunk and block corners (the world's top corners
//! included), and empty sky: empty, full and mixed chunks and blocks all occur at any
//! valid size. Everything is a function of the seed and the world size.

use super::field::{hash3, range, subseed, unit};
use crate::build::ChunkSource;
use crate::cell::CHUNK_VOXELS;
use crate::material::{Material, MaterialKind, MaterialTable};
use crate::size::WorldSize;

/// Material ids of the test preset.
pub(crate) mod mat {
    pub const STONE: u16 = 1;
    pub const GRASS: u16 = 2;
    pub const BRICK: u16 = 3;
    pub const METAL: u16 = 4;
    pub const MIRROR: u16 = 5;
    pub const LAMP: u16 = 6;
    pub const GLASS: u16 = 7;
    pub const WOOD: u16 = 8;
}

/// The test material table (ids as in [`mat`]).
pub(crate) fn materials() -> MaterialTable {
    let k = |kind, albedo, emission, roughness| Material {
        kind,
        albedo,
        emission,
        roughness,
    };
    MaterialTable::from_materials(&[
        Material::diffuse([0.40, 0.40, 0.40]),
        Material::diffuse([0.20, 0.45, 0.10]),
        Material::diffuse([0.55, 0.20, 0.12]),
        k(MaterialKind::Metal, [0.80, 0.78, 0.75], 0.0, 0.25),
        k(MaterialKind::Mirror, [0.95, 0.95, 0.95], 0.0, 0.0),
        k(MaterialKind::Emissive, [1.0, 0.9, 0.7], 10.0, 0.0),
        k(MaterialKind::Mirror, [0.5, 0.7, 0.8], 0.0, 0.0),
        Material::diffuse([0.30, 0.18, 0.08]),
    ])
    .expect("valid test materials")
}

/// Ground: stone below this height, grass on it.
const GROUND: i32 = 16;
/// Cell edge of the primitive buckets (a multiple of the chunk edge).
const BUCKET: i32 = 64;

#[derive(Clone, Copy, Debug)]
enum Shape {
    /// The whole box.
    Solid,
    /// A sphere of centre `c` and squared radius `r2` (voxel centres inside).
    Sphere { c: [f32; 3], r2: f32 },
    /// The box's one-voxel shell; its inside is cleared.
    Hollow,
}

#[derive(Clone, Copy, Debug)]
struct Prim {
    shape: Shape,
    lo: [i32; 3],
    hi: [i32; 3],
    m: u16,
}

impl Prim {
    fn solid(lo: [i32; 3], hi: [i32; 3], m: u16) -> Self {
        Prim {
            shape: Shape::Solid,
            lo,
            hi,
            m,
        }
    }

    /// The voxel at `p` (inside the bounding box) given the current content.
    fn voxel(&self, p: [i32; 3], cur: u16) -> u16 {
        match self.shape {
            Shape::Solid => self.m,
            Shape::Sphere { c, r2 } => {
                let d2: f32 = (0..3).map(|a| (p[a] as f32 + 0.5 - c[a]).powi(2)).sum();
                if d2 < r2 { self.m } else { cur }
            }
            Shape::Hollow => {
                if (0..3).any(|a| p[a] == self.lo[a] || p[a] == self.hi[a] - 1) {
                    self.m
                } else {
                    0
                }
            }
        }
    }

    fn meets(&self, lo: [i32; 3], hi: [i32; 3]) -> bool {
        (0..3).all(|a| self.lo[a] < hi[a] && lo[a] < self.hi[a])
    }
}

/// The test chunk source.
pub(crate) struct TestWorld {
    size: WorldSize,
    seed: u64,
    prims: Vec<Prim>,
    /// Indices of the primitives meeting each 64×64 column cell, in drawing order.
    buckets: Vec<Vec<u32>>,
    cells_x: i32,
}

impl TestWorld {
    /// A test world of `size`, deterministic in `seed`.
    pub(crate) fn new(size: WorldSize, seed: u64) -> Self {
        let [sx, sy, sz] = size.voxels().map(|v| v as i32);
        let s = subseed(seed, 100);
        let mut prims = Vec::new();
        // Random spheres and boxes above (and dipping into) the ground.
        let n = 6 + 6 * (sx / 64) * (sz / 64);
        const MATS: [u16; 7] = [
            mat::STONE,
            mat::BRICK,
            mat::METAL,
            mat::MIRROR,
            mat::GLASS,
            mat::WOOD,
            mat::BRICK,
        ];
        for i in 0..n {
            let h = hash3(s, i, 1, 2);
            let c = [
                range(h, 1, 0, sx - 1),
                range(h, 2, GROUND + 4, GROUND + 24),
                range(h, 3, 0, sz - 1),
            ];
            let m = if range(h, 4, 0, 15) == 0 {
                mat::LAMP
            } else {
                MATS[range(h, 5, 0, 6) as usize]
            };
            if range(h, 6, 0, 1) == 0 {
                let r = 1.5 + 6.0 * unit(hash3(h, 7, 0, 0));
                let cf = c.map(|v| v as f32 + 0.5);
                prims.push(Prim {
                    shape: Shape::Sphere { c: cf, r2: r * r },
                    lo: cf.map(|v| (v - r).floor() as i32),
                    hi: cf.map(|v| (v + r).ceil() as i32 + 1),
                    m,
                });
            } else {
                let e: [i32; 3] = std::array::from_fn(|a| range(h, 8 + a as u32, 1, 6));
                prims.push(Prim::solid(
                    std::array::from_fn(|a| c[a] - e[a]),
                    std::array::from_fn(|a| c[a] + e[a]),
                    m,
                ));
            }
        }
        // Thin pillars (1×1 and one 2×2).
        for (x, z) in [(5, 5), (sx - 6, 9), (9, sz - 6), (sx / 2 + 3, sz / 2 - 7)] {
            prims.push(Prim::solid([x, GROUND + 1, z], [x + 1, GROUND + 29, z + 1], mat::WOOD));
        }
        prims.push(Prim::solid(
            [sx - 12, GROUND + 1, 12],
            [sx - 10, GROUND + 31, 14],
            mat::METAL,
        ));
        // A hollow box (empty inside).
        prims.push(Prim {
            shape: Shape::Hollow,
            lo: [34, GROUND + 2, 34],
            hi: [60, GROUND + 26, 60],
            m: mat::BRICK,
        });
        // Exactly one full chunk.
        prims.push(Prim::solid([16, 32, 16], [32, 48, 32], mat::METAL));
        // Single voxels at chunk and block corners.
        for p in [
            [15, 50, 15],
            [16, 50, 16],
            [3, 47, 4],
            [4, 46, 3],
            [47, 47, 47],
            [sx - 1, 48, 0],
            [0, sy - 1, 0],
            [sx - 1, sy - 1, sz - 1],
            [sx / 2, sy - 17, sz / 2],
        ] {
            prims.push(Prim::solid(p, p.map(|v| v + 1), mat::LAMP));
        }
        let cells_x = (sx + BUCKET - 1) / BUCKET;
        let cells_z = (sz + BUCKET - 1) / BUCKET;
        let mut buckets = vec![Vec::new(); (cells_x * cells_z) as usize];
        for (i, p) in prims.iter().enumerate() {
            let cx = p.lo[0].max(0) / BUCKET..=((p.hi[0] - 1).min(sx - 1) / BUCKET);
            for cz in p.lo[2].max(0) / BUCKET..=((p.hi[2] - 1).min(sz - 1) / BUCKET) {
                for cx in cx.clone() {
                    buckets[(cx + cells_x * cz) as usize].push(i as u32);
                }
            }
        }
        TestWorld {
            size,
            seed: s,
            prims,
            buckets,
            cells_x,
        }
    }

    /// The primitives meeting the chunk at voxel corner `o`, in drawing order.
    fn prims_in(&self, o: [i32; 3]) -> impl Iterator<Item = &Prim> {
        let hi = o.map(|v| v + 16);
        let cell = o[0] / BUCKET + self.cells_x * (o[2] / BUCKET);
        self.buckets[cell as usize]
            .iter()
            .map(|&i| &self.prims[i as usize])
            .filter(move |p| p.meets(o, hi))
    }
}

impl ChunkSource for TestWorld {
    fn size(&self) -> WorldSize {
        self.size
    }

    fn materials(&self) -> MaterialTable {
        materials()
    }

    fn uniform_hint(&self, chunk: [u32; 3]) -> Option<u16> {
        let o = chunk.map(|v| v as i32 * 16);
        if self.prims_in(o).next().is_some() {
            return None;
        }
        if o[1] > GROUND + 1 {
            Some(0)
        } else if o[1] + 16 <= GROUND {
            Some(mat::STONE)
        } else {
            None
        }
    }

    fn fill_chunk(&self, chunk: [u32; 3], out: &mut [u16; CHUNK_VOXELS]) {
        let o = chunk.map(|v| v as i32 * 16);
        for lz in 0..16 {
            for lx in 0..16 {
                let (x, z) = (o[0] + lx, o[2] + lz);
                let bump = hash3(self.seed, x, z, 3).is_multiple_of(5);
                for ly in 0..16 {
                    let y = o[1] + ly;
                    out[(lx + 16 * ly + 256 * lz) as usize] = if y < GROUND {
                        mat::STONE
                    } else if y == GROUND || (y == GROUND + 1 && bump) {
                        mat::GRASS
                    } else {
                        0
                    };
                }
            }
        }
        for p in self.prims_in(o) {
            let a: [i32; 3] = std::array::from_fn(|i| p.lo[i].max(o[i]));
            let b: [i32; 3] = std::array::from_fn(|i| p.hi[i].min(o[i] + 16));
            for z in a[2]..b[2] {
                for y in a[1]..b[1] {
                    for x in a[0]..b[0] {
                        let at = ((x - o[0]) + 16 * (y - o[1]) + 256 * (z - o[2])) as usize;
                        out[at] = p.voxel([x, y, z], out[at]);
                    }
                }
            }
        }
    }
}

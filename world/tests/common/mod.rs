//! Test worlds generated in code: dense raw volumes that serve as the oracle.

#![allow(dead_code)]

use naadf_world::cell::CHUNK_VOXELS;
use naadf_world::{ChunkSource, Material, MaterialTable, World, WorldSize};

/// A dense raw volume (material ids, x fastest): both the source and the oracle.
pub struct Raw {
    pub size: WorldSize,
    pub v: Vec<u16>,
    pub materials: u16,
}

impl Raw {
    pub fn empty(size: WorldSize, materials: u16) -> Self {
        Raw {
            size,
            v: vec![0; size.voxel_count() as usize],
            materials,
        }
    }

    pub fn idx(&self, p: [u32; 3]) -> usize {
        let s = self.size.voxels();
        (p[0] + s[0] * (p[1] + s[1] * p[2])) as usize
    }

    pub fn get(&self, p: [u32; 3]) -> u16 {
        self.v[self.idx(p)]
    }

    pub fn set(&mut self, p: [u32; 3], m: u16) {
        let i = self.idx(p);
        self.v[i] = m;
    }

    pub fn build(&self) -> World {
        World::build(self, &|_| {}).expect("build")
    }

    /// All coordinates, x fastest.
    pub fn coords(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        let s = self.size.voxels();
        (0..s[2]).flat_map(move |z| (0..s[1]).flat_map(move |y| (0..s[0]).map(move |x| [x, y, z])))
    }
}

impl ChunkSource for Raw {
    fn size(&self) -> WorldSize {
        self.size
    }
    fn materials(&self) -> MaterialTable {
        let ms: Vec<Material> = (1..=self.materials)
            .map(|i| Material::diffuse([f32::from(i % 7) / 7.0, 0.5, 0.25]))
            .collect();
        MaterialTable::from_materials(&ms).unwrap()
    }
    fn fill_chunk(&self, c: [u32; 3], out: &mut [u16; CHUNK_VOXELS]) {
        for z in 0..16 {
            for y in 0..16 {
                for x in 0..16 {
                    out[(x + 16 * y + 256 * z) as usize] = self.get([c[0] * 16 + x, c[1] * 16 + y, c[2] * 16 + z]);
                }
            }
        }
    }
}

/// SplitMix64: a tiny deterministic generator for test data.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    pub fn below(&mut self, n: u64) -> u64 {
        self.next() % n.max(1)
    }
    pub fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Random spheres, boxes, thin walls and single voxels: every chunk and block kind.
pub fn random_world(size: WorldSize, seed: u64) -> Raw {
    let mut rng = Rng(seed);
    let mut raw = Raw::empty(size, 9);
    let s = size.voxels();
    // A ground slab fills some chunks completely.
    let ground = rng.below(u64::from(s[1]) / 2) as u32;
    for p in raw.coords().collect::<Vec<_>>() {
        if p[1] < ground {
            raw.set(p, 1 + (p[1] / 16 % 2) as u16);
        }
    }
    for _ in 0..(4 + rng.below(10)) {
        let c = [0, 1, 2].map(|a| rng.below(u64::from(s[a])) as i64);
        let r = 1 + rng.below(14) as i64;
        let m = 1 + rng.below(9) as u16;
        let hollow = rng.below(3) == 0;
        let is_box = rng.below(2) == 0;
        for z in (c[2] - r).max(0)..(c[2] + r).min(i64::from(s[2])) {
            for y in (c[1] - r).max(0)..(c[1] + r).min(i64::from(s[1])) {
                for x in (c[0] - r).max(0)..(c[0] + r).min(i64::from(s[0])) {
                    let d2 = (x - c[0]).pow(2) + (y - c[1]).pow(2) + (z - c[2]).pow(2);
                    let inside = if is_box { true } else { d2 < r * r };
                    let shell = if is_box {
                        [x - c[0], y - c[1], z - c[2]].iter().any(|v| v.abs() >= r - 1)
                    } else {
                        d2 >= (r - 1) * (r - 1)
                    };
                    if inside && (!hollow || shell) {
                        raw.set([x as u32, y as u32, z as u32], m);
                    }
                }
            }
        }
    }
    for _ in 0..rng.below(40) {
        let p = [0, 1, 2].map(|a| rng.below(u64::from(s[a])) as u32);
        let m = rng.below(10) as u16;
        raw.set(p, m);
    }
    raw
}

/// Hand-picked adversarial volumes.
pub fn adversarial(size: WorldSize) -> Vec<(&'static str, Raw)> {
    let s = size.voxels();
    let mut out = vec![("empty", Raw::empty(size, 3))];
    let mut full = Raw::empty(size, 3);
    full.v.fill(2);
    out.push(("all one material", full));
    let mut checker = Raw::empty(size, 3);
    for p in checker.coords().collect::<Vec<_>>() {
        if (p[0] + p[1] + p[2]) % 2 == 0 {
            checker.set(p, 3);
        }
    }
    out.push(("checkerboard", checker));
    let mut corners = Raw::empty(size, 3);
    for p in corners.coords().collect::<Vec<_>>() {
        let at_corner = |n: u32, e: u32| n.is_multiple_of(e) || n % e == e - 1;
        if (0..3).all(|a| at_corner(p[a], 16)) && (p[0] / 16 + p[1] / 16 * 3 + p[2] / 16 * 5) % 3 == 0 {
            corners.set(p, 1);
        }
        if (0..3).all(|a| at_corner(p[a], 4)) && (p[0] * 7 + p[1] * 3 + p[2]) % 97 == 0 {
            corners.set(p, 2);
        }
    }
    out.push(("cell corners", corners));
    let mut borders = Raw::empty(size, 3);
    for p in borders.coords().collect::<Vec<_>>() {
        let on_border = (0..3).filter(|&a| p[a] == 0 || p[a] == s[a] - 1).count();
        if on_border >= 2 {
            borders.set(p, 1 + on_border as u16 - 2);
        }
    }
    out.push(("world borders", borders));
    out
}

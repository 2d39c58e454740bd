//! Test worlds generated in code: dense raw volumes that serve as the oracle.

#![allow(dead_code)]

use naadf_world::aadf::chunk_is_free;
use naadf_world::cell::{self, Aadf, CHUNK_VOXELS, State};
use naadf_world::traverse::Ray;
use naadf_world::{ChunkSource, Material, MaterialTable, World, WorldSize};
use std::collections::HashMap;

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

/// The `seed`-th of `sizes`, cycling: tests spread their seeds over a few world shapes.
pub fn size_for(seed: u64, sizes: &[[u32; 3]]) -> WorldSize {
    let s = sizes[seed as usize % sizes.len()];
    WorldSize::new(s[0], s[1], s[2]).unwrap()
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

pub fn assert_roundtrip(raw: &Raw, w: &World, what: &str) {
    for p in raw.coords() {
        assert_eq!(w.material_at(p), raw.get(p), "{what}: voxel {p:?}");
    }
    let mut bytes = Vec::new();
    w.export_raw(&mut bytes).unwrap();
    let exported: Vec<u16> = bytes
        .chunks_exact(2)
        .map(|b| u16::from_le_bytes([b[0], b[1]]))
        .collect();
    assert!(exported == raw.v, "{what}: export differs from the raw volume");
}

/// Canonical form, reference counts and pointer sanity.
pub fn assert_canonical(w: &World, what: &str) {
    let mut refs: HashMap<u32, u32> = HashMap::new();
    for &c in w.chunks() {
        assert_ne!(c >> 30, 3, "{what}: state 3");
        if cell::state(c) == State::Full {
            assert_ne!(cell::material(c), 0, "{what}: full chunk of material 0");
        }
        if cell::state(c) != State::Mixed {
            continue;
        }
        let blocks = &w.blocks()[cell::pointer(c) as usize..][..64];
        assert!(
            !blocks.iter().all(|&b| b == blocks[0] && cell::state(b) != State::Mixed),
            "{what}: uniform mixed chunk"
        );
        for &b in blocks {
            if cell::state(b) == State::Mixed {
                *refs.entry(cell::pointer(b)).or_default() += 1;
                let g: Vec<u16> = (0..64)
                    .map(|i| cell::voxel_material(cell::group_voxel(w.voxels(), cell::pointer(b) as usize, i)))
                    .collect();
                assert!(!g.iter().all(|&m| m == g[0]), "{what}: uniform voxel group");
            }
        }
    }
    assert_eq!(refs.len(), w.groups().live_groups(), "{what}: live group count");
    for (&ptr, &n) in &refs {
        assert_eq!(w.groups().refs(ptr), n, "{what}: refcount of group {ptr}");
    }
    // After a fresh build no two live groups are identical.
    let mut seen = HashMap::new();
    for &ptr in refs.keys() {
        let words = &w.voxels()[ptr as usize..][..32];
        assert!(seen.insert(words.to_vec(), ptr).is_none(), "{what}: duplicate groups");
    }
    for free in w.groups().free_slots() {
        assert!(!refs.contains_key(&free), "{what}: live pointer into a free slot");
        assert!(
            w.voxels()[free as usize..][..32].iter().all(|&v| v == 0),
            "{what}: free group not zeroed"
        );
    }
    let live_arrays: Vec<u32> = w
        .chunks()
        .iter()
        .filter(|&&c| cell::state(c) == State::Mixed)
        .map(|&c| cell::pointer(c))
        .collect();
    for arr in w.free_block_arrays() {
        assert!(
            !live_arrays.contains(&arr),
            "{what}: live chunk points into free block array {arr}"
        );
        assert!(
            w.blocks()[arr as usize..][..64].iter().all(|&b| b == 0),
            "{what}: free block array not zeroed"
        );
    }
}

/// No empty cell's box (at any level) contains a solid cell, and the chunk entity
/// buffer is zero (entities live outside the static world): brute force over voxels.
pub fn assert_aadf_valid(raw: &Raw, w: &World, what: &str) {
    assert!(
        w.chunk_entities().iter().all(|&f| f == 0),
        "{what}: a chunk entity field is not zero"
    );
    let s = raw.size.voxels().map(i64::from);
    let solid_in = |lo: [i64; 3], hi: [i64; 3]| -> bool {
        for z in lo[2].max(0)..hi[2].min(s[2]) {
            for y in lo[1].max(0)..hi[1].min(s[1]) {
                for x in lo[0].max(0)..hi[0].min(s[0]) {
                    if raw.get([x as u32, y as u32, z as u32]) != 0 {
                        return true;
                    }
                }
            }
        }
        false
    };
    let size = raw.size;
    for (i, &c) in w.chunks().iter().enumerate() {
        let cp = size.chunk_coords(i).map(i64::from);
        if chunk_is_free(c) {
            let f = Aadf::unpack(c, 5);
            let lo: [i64; 3] = std::array::from_fn(|a| (cp[a] - i64::from(f.0[2 * a])) * 16);
            let hi: [i64; 3] = std::array::from_fn(|a| (cp[a] + 1 + i64::from(f.0[2 * a + 1])) * 16);
            assert!(
                !solid_in(lo, hi),
                "{what}: chunk {cp:?} box {f:?} contains solid voxels"
            );
            continue;
        }
        if cell::state(c) != State::Mixed {
            continue;
        }
        for b in 0..64usize {
            let bc = w.blocks()[cell::pointer(c) as usize + b];
            let bp = [b as i64 % 4, b as i64 / 4 % 4, b as i64 / 16];
            let base: [i64; 3] = std::array::from_fn(|a| cp[a] * 16 + bp[a] * 4);
            if cell::state(bc) == State::Empty {
                let f = Aadf::unpack(bc, 2);
                assert_eq!(bc >> 12, 0, "{what}: stray bits in an empty block");
                let lo: [i64; 3] = std::array::from_fn(|a| base[a] - 4 * i64::from(f.0[2 * a]));
                let hi: [i64; 3] = std::array::from_fn(|a| base[a] + 4 + 4 * i64::from(f.0[2 * a + 1]));
                assert!(
                    (0..3).all(|a| bp[a] - i64::from(f.0[2 * a]) >= 0 && bp[a] + i64::from(f.0[2 * a + 1]) <= 3),
                    "{what}: block box leaves its chunk"
                );
                assert!(!solid_in(lo, hi), "{what}: block box contains solid voxels");
            } else if cell::state(bc) == State::Mixed {
                for v in 0..64usize {
                    let vv = cell::group_voxel(w.voxels(), cell::pointer(bc) as usize, v);
                    if cell::voxel_is_solid(vv) {
                        continue;
                    }
                    assert_eq!(vv >> 12, 0, "{what}: stray bits in an empty voxel");
                    let f = Aadf::unpack(u32::from(vv), 2);
                    let vp = [v as i64 % 4, v as i64 / 4 % 4, v as i64 / 16];
                    assert!(
                        (0..3).all(|a| vp[a] - i64::from(f.0[2 * a]) >= 0 && vp[a] + i64::from(f.0[2 * a + 1]) <= 3),
                        "{what}: voxel box leaves its block"
                    );
                    let lo: [i64; 3] = std::array::from_fn(|a| base[a] + vp[a] - i64::from(f.0[2 * a]));
                    let hi: [i64; 3] = std::array::from_fn(|a| base[a] + vp[a] + 1 + i64::from(f.0[2 * a + 1]));
                    assert!(!solid_in(lo, hi), "{what}: voxel box contains solid voxels");
                }
            }
        }
    }
    assert_eq!(w.unsafe_chunk_aadf(), None, "{what}: prefix-sum safety check disagrees");
}

/// Rays of every awkward kind for a world of size `s`.
pub fn rays(s: [u32; 3], rng: &mut Rng, n: usize) -> Vec<Ray> {
    let sf = s.map(f64::from);
    let mut out = Vec::new();
    let mut push = |o: [f64; 3], d: [f64; 3]| {
        if let Ok(r) = Ray::new(o, d) {
            out.push(r);
        }
    };
    let axis_dirs = [
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ];
    for _ in 0..n {
        let inside = |rng: &mut Rng| [0, 1, 2].map(|a| rng.unit() * sf[a]);
        let around = |rng: &mut Rng| [0, 1, 2].map(|a| (rng.unit() * 1.6 - 0.3) * sf[a]);
        let lattice =
            |rng: &mut Rng, step: u64| [0, 1, 2].map(|a| (rng.below(u64::from(s[a]) / step + 1) * step) as f64);
        let unit_dir = |rng: &mut Rng| [0, 1, 2].map(|_| rng.unit() * 2.0 - 1.0);
        let small_int_dir = |rng: &mut Rng| [0, 1, 2].map(|_| rng.below(5) as f64 - 2.0);
        match rng.below(9) {
            // Random origins inside and around the world.
            0 => push(inside(rng), unit_dir(rng)),
            1 => push(around(rng), unit_dir(rng)),
            // Axis-aligned rays, some along cell boundaries.
            2 => push(inside(rng), axis_dirs[rng.below(6) as usize]),
            3 => push(lattice(rng, 1), axis_dirs[rng.below(6) as usize]),
            // Diagonals from lattice points run exactly through edges and corners.
            4 => push(lattice(rng, 1), small_int_dir(rng)),
            5 => push(lattice(rng, 4), small_int_dir(rng)),
            6 => push(lattice(rng, 16), small_int_dir(rng)),
            // Origins on cell boundaries with random directions.
            7 => {
                let mut o = inside(rng);
                o[rng.below(3) as usize] = rng.below(u64::from(s[0].min(s[1]).min(s[2])) + 1) as f64;
                push(o, unit_dir(rng));
            }
            // From far outside, aimed at the world.
            _ => {
                let target = inside(rng);
                let from = [0, 1, 2].map(|a| target[a] + (rng.unit() * 2.0 - 1.0) * 3.0 * sf[a]);
                push(from, [0, 1, 2].map(|a| target[a] - from[a]));
            }
        }
    }
    out
}

/// Feeds the server's change sets to a mirror through their encoded records and checks
/// that the mirror reports the same digest and buffer writes, then the same buffers.
pub fn follow(server: &World, mirror: &mut World, changes: Vec<naadf_world::edit::ChangeSet>) {
    use naadf_world::edit::Record;
    use naadf_world::ops::Limits;
    for c in changes {
        let d = Record::decode(&c.encode()).unwrap();
        let got = mirror.apply_record(d.version, &d.record, &Limits::default()).unwrap();
        assert_eq!(
            got.digest, c.digest,
            "mirror digest at ({}, {})",
            c.version, c.growth_seq
        );
        assert_eq!(got.writes, c.writes, "mirror writes differ");
    }
    assert!(mirror.to_parts() == server.to_parts());
}

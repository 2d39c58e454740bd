//! The `terrain` preset: rolling hills, ridged mountains, a sea, caves, overhangs, trees
//! and a few buildings, generated chunk by chunk.
//!
//! Every voxel is a pure function of the seed and its position (plus the world height,
//! which scales the landscape). Nothing dense is ever stored:
//! - 2D fields (height, overhang amplitude) are evaluated on a lattice of every 4 voxels
//!   and interpolated bilinearly; 3D fields (overhangs, caves) on a 4³ lattice and
//!   interpolated trilinearly. Lattice points are global, so chunks agree at their seams,
//!   and interpolation never leaves the range of the lattice values, which gives exact
//!   bounds for [`ChunkSource::uniform_hint`] and for the fast paths of
//!   [`ChunkSource::fill_chunk`].
//! - Trees sit on a hashed grid of 9×9 column cells (at most one per cell) and buildings
//!   on a grid of 64×64 cells (at most one per cell, fully inside it). A chunk paints
//!   every candidate whose bounding box meets it, in a fixed global order, so the result
//!   does not depend on which chunk is generated first.
//!
//! Features never overwrite terrain below the ground except tree roots, and only paint
//! foundations into air; that keeps the "solid stone" hint sound.

use super::field::{fbm2, fbm3, hash3, noise3, range, ridged2, smoothstep, subseed, unit};
use crate::build::ChunkSource;
use crate::cell::CHUNK_VOXELS;
use crate::material::{Material, MaterialKind, MaterialTable};
use crate::size::WorldSize;
use rayon::prelude::*;
use std::cell::RefCell;
use std::rc::Rc;
use std::sync::atomic::{AtomicU64, Ordering};

/// Material ids of the terrain preset (1-based, as in [`materials`]).
pub(crate) mod mat {
    pub const GRASS: u16 = 1;
    pub const DIRT: u16 = 2;
    pub const STONE: u16 = 3;
    pub const SAND: u16 = 4;
    pub const WATER: u16 = 5;
    pub const SNOW: u16 = 6;
    pub const WOOD: u16 = 7;
    pub const LEAVES: u16 = 8;
    pub const PINE: u16 = 9;
    pub const BRICK: u16 = 10;
    pub const PLASTER: u16 = 11;
    pub const GLASS: u16 = 12;
    pub const METAL: u16 = 13;
    pub const LAMP: u16 = 14;
    pub const ROOF: u16 = 15;
    pub const COBBLE: u16 = 16;
    pub const MIRROR: u16 = 17;
    /// Number of materials.
    #[cfg(test)]
    pub const COUNT: u16 = 17;
}

/// The terrain material table (ids as in [`mat`]).
pub(crate) fn materials() -> MaterialTable {
    let d = Material::diffuse;
    let k = |kind, albedo, emission, roughness| Material {
        kind,
        albedo,
        emission,
        roughness,
    };
    MaterialTable::from_materials(&[
        d([0.16, 0.36, 0.08]),                                    // grass
        d([0.30, 0.20, 0.12]),                                    // dirt
        d([0.38, 0.37, 0.36]),                                    // stone
        d([0.76, 0.68, 0.48]),                                    // sand
        k(MaterialKind::Metal, [0.06, 0.20, 0.32], 0.0, 0.08),    // water
        d([0.92, 0.93, 0.95]),                                    // snow
        d([0.26, 0.16, 0.08]),                                    // wood
        d([0.12, 0.32, 0.06]),                                    // leaves
        d([0.06, 0.20, 0.08]),                                    // pine needles
        d([0.50, 0.18, 0.12]),                                    // brick
        d([0.80, 0.78, 0.72]),                                    // plaster
        k(MaterialKind::Mirror, [0.55, 0.68, 0.78], 0.0, 0.0),    // glass
        k(MaterialKind::Metal, [0.78, 0.78, 0.80], 0.0, 0.30),    // metal
        k(MaterialKind::Emissive, [1.00, 0.82, 0.55], 12.0, 0.0), // lamp
        d([0.40, 0.12, 0.08]),                                    // roof tiles
        d([0.30, 0.29, 0.27]),                                    // cobble
        k(MaterialKind::Mirror, [0.95, 0.95, 0.95], 0.0, 0.0),    // mirror
    ])
    .expect("valid terrain materials")
}

/// Lattice spacing of the interpolated fields (equal to the block edge).
const STEP: i32 = 4;
/// Tree cell edge (one candidate tree per cell).
const TREE_CELL: i32 = 9;
/// How far a tree's bounding box reaches from its trunk, horizontally.
const TREE_REACH: i32 = 6;
/// Building cell edge (one candidate building per cell, inside it).
const BUILDING_CELL: i32 = 64;
/// Storey height of buildings (slab included).
const FLOOR_H: i32 = 5;

/// Derived seeds, one per field.
#[derive(Clone, Copy, Debug)]
struct Seeds {
    continent: u64,
    hills: u64,
    mountain_mask: u64,
    ridges: u64,
    overhang_mask: u64,
    overhang: u64,
    tunnel_a: u64,
    tunnel_b: u64,
    cavern: u64,
    forest: u64,
    trees: u64,
    buildings: u64,
}

impl Seeds {
    fn new(seed: u64) -> Self {
        let s = |k| subseed(seed, k);
        Self {
            continent: s(1),
            hills: s(2),
            mountain_mask: s(3),
            ridges: s(4),
            overhang_mask: s(5),
            overhang: s(6),
            tunnel_a: s(7),
            tunnel_b: s(8),
            cavern: s(9),
            forest: s(10),
            trees: s(11),
            buildings: s(12),
        }
    }
}

/// Landscape parameters, all scaled from the world height.
#[derive(Clone, Copy, Debug)]
struct Params {
    sy: f32,
    /// Water fills empty voxels below this height.
    sea: i32,
    /// Highest value of the height field.
    h_cap: f32,
    /// Largest overhang amplitude (voxels).
    a_max: f32,
    /// Tallest tree or building above its ground.
    headroom: i32,
    /// No caves below this height.
    cave_min: i32,
    /// Snow above this height.
    snow: f32,
    /// Horizontal wavelength of the hills.
    lambda: f32,
    /// Wavelength of the overhang noise.
    over_len: f32,
    /// Nothing solid at or above this height.
    top: i32,
}

impl Params {
    fn new(size: WorldSize) -> Self {
        let sy = size.voxels()[1] as f32;
        let h_cap = 0.74 * sy;
        let a_max = (0.10 * sy).max(3.0);
        let headroom = ((0.22 * sy) as i32).clamp(10, 32);
        let s = (sy / 512.0).clamp(0.15, 2.0);
        let top = (h_cap.ceil() as i32 + headroom.max(a_max.ceil() as i32) + 3).min(sy as i32);
        Self {
            sy,
            sea: (0.30 * sy).round() as i32,
            h_cap,
            a_max,
            headroom,
            cave_min: ((0.04 * sy) as i32).max(3),
            snow: 0.60 * sy,
            lambda: 320.0 * s,
            over_len: 28.0 * s.clamp(0.5, 1.5),
            top,
        }
    }
}

/// The 5×5 lattice of height and overhang amplitude over one chunk column, `[x][z]`.
struct Lattice {
    h: [[f32; 5]; 5],
    a: [[f32; 5]; 5],
}

impl Lattice {
    /// Lowest possible top of guaranteed solid terrain and highest possible solid terrain.
    fn bounds(&self) -> (f32, f32) {
        let mut lo = f32::MAX;
        let mut hi = f32::MIN;
        for i in 0..5 {
            for k in 0..5 {
                lo = lo.min(self.h[i][k] - self.a[i][k]);
                hi = hi.max(self.h[i][k] + self.a[i][k]);
            }
        }
        (lo, hi)
    }
}

/// Bilinear interpolation between four lattice corners at fractions `fx`, `fz`.
#[inline]
fn bilerp(c00: f32, c10: f32, c01: f32, c11: f32, fx: f32, fz: f32) -> f32 {
    let a = c00 + (c10 - c00) * fx;
    let b = c01 + (c11 - c01) * fx;
    a + (b - a) * fz
}

/// A tree, resolved from its cell.
#[derive(Clone, Copy, Debug)]
struct Tree {
    x: i32,
    z: i32,
    /// First air voxel above the ground at the trunk.
    g: i32,
    conifer: bool,
    /// Trunk voxels are `g - 1 .. trunk_top`.
    trunk_top: i32,
    /// Leaf blobs (deciduous): centre x, y, z and radius.
    blobs: [[f32; 4]; 3],
    /// Cone (conifer): base y, top y, base radius.
    cone: [f32; 3],
    seed: u64,
    lo: [i32; 3],
    hi: [i32; 3],
}

/// A building, resolved from its cell.
#[derive(Clone, Copy, Debug)]
struct Building {
    x0: i32,
    z0: i32,
    w: i32,
    d: i32,
    /// Ground-floor slab height (above every terrain voxel of the footprint).
    base: i32,
    /// Foundations fill air from here up to `base`.
    ground_lo: i32,
    floors: i32,
    gable: bool,
    style: u8,
    door_far: bool,
    lamps: bool,
    beacon: bool,
    lo: [i32; 3],
    hi: [i32; 3],
}

/// What every chunk of one chunk column needs: the field lattice, its bounds, and the
/// trees that meet the column (at any height).
struct Column {
    lat: Lattice,
    lo: f32,
    hi: f32,
    trees: Vec<Tree>,
}

/// Slots of the per-thread column cache (direct-mapped).
const CACHE_SLOTS: usize = 512;

/// A cached column: terrain instance id, column corner, data.
type CacheSlot = Option<(u64, i32, i32, Rc<Column>)>;

thread_local! {
    /// Recently used columns. Chunks are generated in linear order, so the chunks of one
    /// column come close together; the cache saves recomputing its 2D fields and trees
    /// for each of them. It holds pure function values only, so it never changes results.
    static COLUMNS: RefCell<Vec<CacheSlot>> = RefCell::new(vec![None; CACHE_SLOTS]);
}

/// The terrain chunk source.
pub(crate) struct Terrain {
    /// Unique per instance: keys the per-thread column cache.
    id: u64,
    size: WorldSize,
    p: Params,
    s: Seeds,
    /// Building per 64×64 cell over the world (`x + cells_x · z`).
    buildings: Vec<Option<Building>>,
    cells_x: i32,
    cells_z: i32,
}

/// Whether boxes `[lo, hi)` and `[lo2, hi2)` overlap.
#[inline]
fn overlaps(lo: [i32; 3], hi: [i32; 3], lo2: [i32; 3], hi2: [i32; 3]) -> bool {
    (0..3).all(|a| lo[a] < hi2[a] && lo2[a] < hi[a])
}

impl Terrain {
    /// A terrain world of `size`, deterministic in `seed`.
    pub(crate) fn new(size: WorldSize, seed: u64) -> Self {
        let [sx, _, sz] = size.voxels();
        static NEXT_ID: AtomicU64 = AtomicU64::new(0);
        let mut t = Terrain {
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
            size,
            p: Params::new(size),
            s: Seeds::new(seed),
            buildings: Vec::new(),
            cells_x: sx.div_ceil(BUILDING_CELL as u32) as i32,
            cells_z: sz.div_ceil(BUILDING_CELL as u32) as i32,
        };
        let cells: Vec<(i32, i32)> = (0..t.cells_z)
            .flat_map(|z| (0..t.cells_x).map(move |x| (x, z)))
            .collect();
        t.buildings = cells.par_iter().map(|&(x, z)| t.building_in_cell(x, z)).collect();
        t
    }

    /// The height field at a lattice point (any integer position).
    fn height(&self, x: f32, z: f32) -> f32 {
        let (p, s) = (&self.p, &self.s);
        let l = p.lambda;
        let c = fbm2(s.continent, x / (4.0 * l), z / (4.0 * l), 2);
        let b = fbm2(s.hills, x / l, z / l, 5);
        let m = smoothstep(0.0, 0.45, fbm2(s.mountain_mask, x / (2.2 * l), z / (2.2 * l), 2));
        let r = if m > 0.0 {
            ridged2(s.ridges, x / (0.7 * l), z / (0.7 * l), 4)
        } else {
            0.0
        };
        let h = p.sea as f32 + p.sy * (0.02 + 0.13 * c + 0.10 * b + 0.34 * m * r);
        h.clamp(2.0, p.h_cap)
    }

    /// Height and overhang amplitude at lattice point `(x, z)`.
    fn lattice_point(&self, x: i32, z: i32) -> (f32, f32) {
        let (fx, fz) = (x as f32, z as f32);
        let h = self.height(fx, fz);
        let sea = self.p.sea as f32;
        let ramp = smoothstep(sea + 3.0, sea + 3.0 + 2.0 * self.p.a_max, h);
        let a = if ramp > 0.0 {
            let l = 1.3 * self.p.lambda;
            self.p.a_max * ramp * smoothstep(0.05, 0.35, fbm2(self.s.overhang_mask, fx / l, fz / l, 2))
        } else {
            0.0
        };
        (h, a)
    }

    /// The lattice over the chunk column whose corner is `(x0, z0)`.
    fn lattice(&self, x0: i32, z0: i32) -> Lattice {
        let mut l = Lattice {
            h: [[0.0; 5]; 5],
            a: [[0.0; 5]; 5],
        };
        for i in 0..5 {
            for k in 0..5 {
                let (h, a) = self.lattice_point(x0 + STEP * i as i32, z0 + STEP * k as i32);
                l.h[i][k] = h;
                l.a[i][k] = a;
            }
        }
        l
    }

    /// Interpolated height and overhang amplitude at any column (same arithmetic as the
    /// per-chunk interpolation).
    fn column(&self, x: i32, z: i32) -> (f32, f32) {
        let (gx, gz) = (x.div_euclid(STEP) * STEP, z.div_euclid(STEP) * STEP);
        let (fx, fz) = ((x - gx) as f32 * 0.25, (z - gz) as f32 * 0.25);
        let c00 = self.lattice_point(gx, gz);
        let c10 = self.lattice_point(gx + STEP, gz);
        let c01 = self.lattice_point(gx, gz + STEP);
        let c11 = self.lattice_point(gx + STEP, gz + STEP);
        (
            bilerp(c00.0, c10.0, c01.0, c11.0, fx, fz),
            bilerp(c00.1, c10.1, c01.1, c11.1, fx, fz),
        )
    }

    /// Overhang noise at a 3D lattice point, in `[-1, 1]`.
    fn overhang(&self, x: i32, y: i32, z: i32) -> f32 {
        let l = self.p.over_len;
        let n = fbm3(self.s.overhang, x as f32 / l, y as f32 / (0.5 * l), z as f32 / l, 2);
        (4.0 * n).clamp(-1.0, 1.0)
    }

    /// Cave fields at a 3D lattice point: two tunnel noises and the cavern noise.
    fn cave_fields(&self, x: i32, y: i32, z: i32) -> [f32; 3] {
        let (fx, fy, fz) = (x as f32, y as f32, z as f32);
        let t = 56.0;
        let c = 72.0;
        [
            noise3(self.s.tunnel_a, fx / t, fy / (0.7 * t), fz / t),
            noise3(self.s.tunnel_b, fx / t, fy / (0.7 * t), fz / t),
            noise3(self.s.cavern, fx / c, fy / (0.6 * c), fz / c),
        ]
    }

    /// Caves may be carved below this height in a column of height `h`.
    #[inline]
    fn cave_top(&self, h: f32) -> f32 {
        if h > self.p.sea as f32 + 6.0 { h - 3.0 } else { h - 10.0 }
    }

    /// The building of cell `(cx, cz)`, if it has one.
    fn building_in_cell(&self, cx: i32, cz: i32) -> Option<Building> {
        let p = &self.p;
        let h = hash3(self.s.buildings, cx, cz, 0);
        if unit(h) >= 0.4 {
            return None;
        }
        let w = range(h, 1, 9, 22);
        let d = range(h, 2, 9, 22);
        let x0 = cx * BUILDING_CELL + 3 + range(h, 3, 0, BUILDING_CELL - 6 - w);
        let z0 = cz * BUILDING_CELL + 3 + range(h, 4, 0, BUILDING_CELL - 6 - d);
        // Exact bounds of the interpolated fields over the footprint and its rim.
        let (mut hmin, mut hmax) = (f32::MAX, f32::MIN);
        let lx = (x0 - 1).div_euclid(STEP) * STEP;
        let lz = (z0 - 1).div_euclid(STEP) * STEP;
        let mut x = lx;
        while x < x0 + w + 1 + STEP {
            let mut z = lz;
            while z < z0 + d + 1 + STEP {
                let (hh, a) = self.lattice_point(x, z);
                if a > 0.0 {
                    return None;
                }
                hmin = hmin.min(hh);
                hmax = hmax.max(hh);
                z += STEP;
            }
            x += STEP;
        }
        if hmin < p.sea as f32 + 2.0 || hmax > p.snow - 2.0 || hmax - hmin > 8.0 {
            return None;
        }
        let base = (hmax - 0.5).ceil() as i32;
        let gable = w.min(d) <= 15 && range(h, 5, 0, 2) == 0;
        let roof_h = if gable { 1 + (w.min(d) - 1) / 2 } else { 2 };
        let mut floors = range(h, 6, 1, 5);
        while floors > 0 && floors * FLOOR_H + roof_h + 1 > p.headroom {
            floors -= 1;
        }
        if floors == 0 {
            return None;
        }
        let style = match range(h, 7, 0, 9) {
            0..=3 => 0,
            4..=6 => 1,
            7 => 2,
            _ => 3,
        };
        let ground_lo = (hmin - 0.5).floor() as i32 - 1;
        let top = base + floors * FLOOR_H + roof_h;
        Some(Building {
            x0,
            z0,
            w,
            d,
            base,
            ground_lo,
            floors,
            gable,
            style,
            door_far: range(h, 8, 0, 1) == 1,
            lamps: range(h, 9, 0, 2) > 0,
            beacon: !gable && range(h, 10, 0, 1) == 0,
            lo: [x0 - 1, ground_lo, z0 - 1],
            hi: [x0 + w + 1, top + 1, z0 + d + 1],
        })
    }

    /// The building of cell `(cx, cz)` (none outside the world).
    fn building(&self, cx: i32, cz: i32) -> Option<&Building> {
        if cx < 0 || cz < 0 || cx >= self.cells_x || cz >= self.cells_z {
            return None;
        }
        self.buildings[(cx + self.cells_x * cz) as usize].as_ref()
    }

    /// Whether a tree at `(x, z)` would touch a building.
    fn near_building(&self, x: i32, z: i32) -> bool {
        let r = TREE_REACH + 1;
        let cells = |v: i32| (v - r).div_euclid(BUILDING_CELL)..=(v + r).div_euclid(BUILDING_CELL);
        cells(x).any(|cx| {
            cells(z).any(|cz| {
                self.building(cx, cz)
                    .is_some_and(|b| x + r >= b.lo[0] && x - r < b.hi[0] && z + r >= b.lo[2] && z - r < b.hi[2])
            })
        })
    }

    /// The tree of tree cell `(cx, cz)`, if it has one.
    fn tree_in_cell(&self, cx: i32, cz: i32) -> Option<Tree> {
        let p = &self.p;
        let h = hash3(self.s.trees, cx, cz, 1);
        let x = cx * TREE_CELL + range(h, 1, 1, TREE_CELL - 2);
        let z = cz * TREE_CELL + range(h, 2, 1, TREE_CELL - 2);
        let u = unit(h);
        if u >= 0.8 {
            return None;
        }
        let l = 0.5 * p.lambda;
        let forest = fbm2(self.s.forest, x as f32 / l, z as f32 / l, 2);
        if u >= 0.06 + 0.74 * smoothstep(-0.05, 0.35, forest) {
            return None;
        }
        let (gh, ga) = self.column(x, z);
        let sea = p.sea as f32;
        if gh < sea + 3.0 || gh > p.snow - 2.0 || ga > 0.25 {
            return None;
        }
        if self.near_building(x, z) {
            return None;
        }
        let g = (gh - 0.5).ceil() as i32;
        let k = (p.headroom as f32 / 18.0).min(1.0);
        let conifer = gh > sea + 0.45 * (p.snow - sea) || range(h, 3, 0, 3) == 0;
        let (cx_, cz_) = (x as f32 + 0.5, z as f32 + 0.5);
        let mut t = Tree {
            x,
            z,
            g,
            conifer,
            trunk_top: 0,
            blobs: [[0.0; 4]; 3],
            cone: [0.0; 3],
            seed: h,
            lo: [0; 3],
            hi: [0; 3],
        };
        let top = if conifer {
            let th = ((range(h, 4, 9, 14) as f32) * k).round().max(5.0) as i32;
            let r0 = (2.4 + 1.2 * unit(hash3(h, 5, 0, 0))) * k.max(0.6);
            t.trunk_top = g + th - 1;
            t.cone = [g as f32 + 2.0, (g + th) as f32 + 1.5, r0];
            t.cone[1]
        } else {
            let th = ((range(h, 4, 4, 7) as f32) * k).round().max(2.0) as i32;
            let r = (2.6 + 1.4 * unit(hash3(h, 5, 0, 0))) * k.max(0.5);
            let cy = (g + th) as f32 + 0.6 * r;
            t.trunk_top = g + th + (0.5 * r) as i32;
            t.blobs[0] = [cx_, cy, cz_, r];
            for b in 1..3 {
                let hb = hash3(h, 6, b as i32, 0);
                let ox = (unit(hb) * 2.0 - 1.0) * 0.7 * r;
                let oz = (unit(hash3(hb, 1, 0, 0)) * 2.0 - 1.0) * 0.7 * r;
                let oy = (unit(hash3(hb, 2, 0, 0)) - 0.6) * r;
                t.blobs[b] = [cx_ + ox, cy + oy, cz_ + oz, 0.7 * r];
            }
            t.blobs.iter().map(|b| b[1] + b[3]).fold(0.0, f32::max)
        };
        let top = top.ceil() as i32 + 1;
        if top - g > p.headroom {
            return None;
        }
        t.lo = [x - TREE_REACH, g - 1, z - TREE_REACH];
        t.hi = [x + TREE_REACH + 1, top, z + TREE_REACH + 1];
        Some(t)
    }

    /// The column data of the chunk column at corner `(x0, z0)`, from the cache if there.
    fn column_data(&self, x0: i32, z0: i32) -> Rc<Column> {
        let slot = ((x0 / 16) as usize).wrapping_add((z0 / 16) as usize * 61) % CACHE_SLOTS;
        let hit = COLUMNS.with(|c| match &c.borrow()[slot] {
            Some((id, x, z, col)) if *id == self.id && *x == x0 && *z == z0 => Some(col.clone()),
            _ => None,
        });
        if let Some(col) = hit {
            return col;
        }
        let lat = self.lattice(x0, z0);
        let (lo, hi) = lat.bounds();
        let trees = self.trees_near([x0, i32::MIN / 2, z0], [x0 + 16, i32::MAX / 2, z0 + 16]);
        let col = Rc::new(Column { lat, lo, hi, trees });
        COLUMNS.with(|c| c.borrow_mut()[slot] = Some((self.id, x0, z0, col.clone())));
        col
    }

    /// Trees whose bounding boxes meet the box `[lo, hi)`, in global cell order.
    fn trees_near(&self, lo: [i32; 3], hi: [i32; 3]) -> Vec<Tree> {
        let cells =
            |a: i32, b: i32| (a - TREE_REACH).div_euclid(TREE_CELL)..=(b - 1 + TREE_REACH).div_euclid(TREE_CELL);
        let mut out = Vec::new();
        for cz in cells(lo[2], hi[2]) {
            for cx in cells(lo[0], hi[0]) {
                if let Some(t) = self.tree_in_cell(cx, cz)
                    && overlaps(t.lo, t.hi, lo, hi)
                {
                    out.push(t);
                }
            }
        }
        out
    }

    /// The terrain (no features) of the chunk at voxel corner `(x0, y0, z0)`.
    fn fill_ground(&self, o: [i32; 3], lat: &Lattice, out: &mut [u16; CHUNK_VOXELS]) {
        let p = &self.p;
        let [x0, y0, z0] = o;
        let (lo, hi) = lat.bounds();
        let (y0f, sea) = (y0 as f32, p.sea);
        if y0f >= hi && y0 >= sea {
            out.fill(0);
            return;
        }
        // Caves: which 4³ cells (= blocks) may hold cave voxels.
        let hmax = lat.h.iter().flatten().fold(f32::MIN, |m, &v| m.max(v));
        let mut caves = [[[[0.0f32; 3]; 5]; 5]; 5];
        let mut cave_cells = 0u64;
        if y0 + 16 > p.cave_min && y0f < self.cave_top(hmax) {
            for (i, plane) in caves.iter_mut().enumerate() {
                for (j, row) in plane.iter_mut().enumerate() {
                    for (k, v) in row.iter_mut().enumerate() {
                        *v = self.cave_fields(x0 + STEP * i as i32, y0 + STEP * j as i32, z0 + STEP * k as i32);
                    }
                }
            }
            for cell in 0..64 {
                let (i, j, k) = (cell % 4, cell / 4 % 4, cell / 16);
                let mut mn = [f32::MAX; 3];
                let mut mx = [f32::MIN; 3];
                for c in 0..8 {
                    let v = caves[i + (c & 1)][j + (c >> 1 & 1)][k + (c >> 2)];
                    for f in 0..3 {
                        mn[f] = mn[f].min(v[f]);
                        mx[f] = mx[f].max(v[f]);
                    }
                }
                let min_abs = |f: usize| {
                    if mn[f] > 0.0 {
                        mn[f]
                    } else if mx[f] < 0.0 {
                        -mx[f]
                    } else {
                        0.0
                    }
                };
                let tunnel = min_abs(0).powi(2) + min_abs(1).powi(2) < TUNNEL;
                if tunnel || mx[2] > CAVERN {
                    cave_cells |= 1 << cell;
                }
            }
        }
        if cave_cells == 0 && y0f + 20.0 < lo {
            out.fill(mat::STONE);
            return;
        }
        // Overhangs: a 5×6×5 lattice (one layer above the chunk for the surface depth).
        let amax = lat.a.iter().flatten().fold(0.0f32, |m, &v| m.max(v));
        let use_over = amax > 0.0 && y0f + 20.0 > lo - 1.0 && y0f < hi + 1.0;
        let mut over = [[[0.0f32; 5]; 6]; 5];
        if use_over {
            for (i, plane) in over.iter_mut().enumerate() {
                for (j, row) in plane.iter_mut().enumerate() {
                    for (k, v) in row.iter_mut().enumerate() {
                        *v = self.overhang(x0 + STEP * i as i32, y0 + STEP * j as i32, z0 + STEP * k as i32);
                    }
                }
            }
        }
        let snow = p.snow;
        for lz in 0..16usize {
            let (k, fz) = (lz >> 2, (lz & 3) as f32 * 0.25);
            for lx in 0..16usize {
                let (i, fx) = (lx >> 2, (lx & 3) as f32 * 0.25);
                let b = |g: &[[f32; 5]; 5]| bilerp(g[i][k], g[i + 1][k], g[i][k + 1], g[i + 1][k + 1], fx, fz);
                let h = b(&lat.h);
                let a = b(&lat.a);
                let column = lx + 256 * lz;
                if y0f >= h + a {
                    // Nothing solid from here up: sky, or sea below the sea level.
                    for ly in 0..16 {
                        out[column + 16 * ly] = if y0 + (ly as i32) < sea { mat::WATER } else { 0 };
                    }
                    continue;
                }
                let col_cells = cave_cells >> (i + 16 * k) & 0x1111;
                if col_cells == 0 && y0f + 20.0 < h - a {
                    for ly in 0..16 {
                        out[column + 16 * ly] = mat::STONE;
                    }
                    continue;
                }
                let h = &lat.h;
                let gx = (h[i + 1][k] - h[i][k]) + (h[i + 1][k + 1] - h[i][k + 1] - h[i + 1][k] + h[i][k]) * fz;
                let gz = (h[i][k + 1] - h[i][k]) + (h[i + 1][k + 1] - h[i + 1][k] - h[i][k + 1] + h[i][k]) * fx;
                let slope = (gx * gx + gz * gz).sqrt() / STEP as f32;
                let h = b(&lat.h);
                let (top, sub) = if h < sea as f32 + 2.5 {
                    (mat::SAND, mat::SAND)
                } else if h > snow {
                    (mat::SNOW, mat::STONE)
                } else if slope > 1.0 {
                    (mat::STONE, mat::STONE)
                } else {
                    (mat::GRASS, mat::DIRT)
                };
                let mut ov = [0.0f32; 6];
                if use_over && a > 0.0 {
                    for (j, v) in ov.iter_mut().enumerate() {
                        *v = bilerp(
                            over[i][j][k],
                            over[i + 1][j][k],
                            over[i][j][k + 1],
                            over[i + 1][j][k + 1],
                            fx,
                            fz,
                        );
                    }
                }
                let mut cv = [[0.0f32; 3]; 5];
                if col_cells != 0 {
                    for (j, v) in cv.iter_mut().enumerate() {
                        for (f, t) in v.iter_mut().enumerate() {
                            *t = bilerp(
                                caves[i][j][k][f],
                                caves[i + 1][j][k][f],
                                caves[i][j][k + 1][f],
                                caves[i + 1][j][k + 1][f],
                                fx,
                                fz,
                            );
                        }
                    }
                }
                let ctop = self.cave_top(h);
                let mut run = 0u8;
                for ly in (0..20usize).rev() {
                    let y = y0 + ly as i32;
                    let yf = y as f32 + 0.5;
                    let (j, fy) = (ly >> 2, (ly & 3) as f32 * 0.25);
                    let n = ov[j] + (ov[(j + 1).min(5)] - ov[j]) * fy;
                    let solid = yf < h + a * n;
                    if ly < 16 {
                        let m = if solid {
                            let cave = col_cells >> (4 * j) & 1 == 1 && y >= p.cave_min && yf < ctop && {
                                let f = |f: usize| cv[j][f] + (cv[j + 1][f] - cv[j][f]) * fy;
                                let (t0, t1) = (f(0), f(1));
                                t0 * t0 + t1 * t1 < TUNNEL || f(2) > CAVERN
                            };
                            if cave {
                                0
                            } else if yf >= h {
                                if run == 0 && top == mat::GRASS {
                                    mat::GRASS
                                } else {
                                    mat::STONE
                                }
                            } else {
                                match run {
                                    0 => top,
                                    1..=3 => sub,
                                    _ => mat::STONE,
                                }
                            }
                        } else if y < sea {
                            mat::WATER
                        } else {
                            0
                        };
                        out[lx + 16 * ly + 256 * lz] = m;
                    }
                    run = if solid { (run + 1).min(4) } else { 0 };
                }
            }
        }
    }

    /// Paints the trees and the building that meet the chunk at voxel corner `o`.
    fn paint_features(&self, o: [i32; 3], trees: &[Tree], out: &mut [u16; CHUNK_VOXELS]) {
        let hi = [o[0] + 16, o[1] + 16, o[2] + 16];
        for t in trees.iter().filter(|t| overlaps(t.lo, t.hi, o, hi)) {
            paint_box(o, t.lo, t.hi, out, |x, y, z, cur| t.voxel(x, y, z, cur));
        }
        if let Some(b) = self.building(o[0].div_euclid(BUILDING_CELL), o[2].div_euclid(BUILDING_CELL))
            && overlaps(b.lo, b.hi, o, hi)
        {
            paint_box(o, b.lo, b.hi, out, |x, y, z, cur| b.voxel(x, y, z, cur));
        }
    }
}

/// Tunnel threshold on `a² + b²` of the two tunnel noises.
const TUNNEL: f32 = 0.012;
/// Cavern threshold on the cavern noise.
const CAVERN: f32 = 0.42;

/// Applies `f` to every voxel of box `[lo, hi)` that lies in the chunk at corner `o`.
fn paint_box(
    o: [i32; 3],
    lo: [i32; 3],
    hi: [i32; 3],
    out: &mut [u16; CHUNK_VOXELS],
    f: impl Fn(i32, i32, i32, u16) -> u16,
) {
    let a: [i32; 3] = std::array::from_fn(|i| lo[i].max(o[i]));
    let b: [i32; 3] = std::array::from_fn(|i| hi[i].min(o[i] + 16));
    for z in a[2]..b[2] {
        for y in a[1]..b[1] {
            for x in a[0]..b[0] {
                let at = ((x - o[0]) + 16 * (y - o[1]) + 256 * (z - o[2])) as usize;
                out[at] = f(x, y, z, out[at]);
            }
        }
    }
}

impl Tree {
    /// The voxel at `(x, y, z)` given the current content `cur`.
    #[inline]
    fn voxel(&self, x: i32, y: i32, z: i32, cur: u16) -> u16 {
        if x == self.x && z == self.z && y >= self.g - 1 && y < self.trunk_top {
            return mat::WOOD;
        }
        if cur != 0 {
            return cur;
        }
        let jitter = 0.75 + 0.4 * unit(hash3(self.seed, x, y, z));
        let (px, py, pz) = (x as f32 + 0.5, y as f32 + 0.5, z as f32 + 0.5);
        if self.conifer {
            let [b, t, r0] = self.cone;
            if py < b || py > t {
                return cur;
            }
            let tier = if (y - self.g) % 3 == 0 { 0.7 } else { 1.0 };
            let r = r0 * (1.0 - (py - b) / (t - b)) * tier + 0.6;
            let (dx, dz) = (px - (self.x as f32 + 0.5), pz - (self.z as f32 + 0.5));
            if dx * dx + dz * dz < r * r * jitter {
                return mat::PINE;
            }
        } else {
            for [cx, cy, cz, r] in self.blobs {
                let (dx, dy, dz) = (px - cx, py - cy, pz - cz);
                if dx * dx + dy * dy + dz * dz < r * r * jitter {
                    return mat::LEAVES;
                }
            }
        }
        cur
    }
}

impl Building {
    /// The voxel at `(x, y, z)` given the current content `cur`.
    fn voxel(&self, x: i32, y: i32, z: i32, cur: u16) -> u16 {
        let (u, v, w, d) = (x - self.x0, z - self.z0, self.w, self.d);
        let door_v = if self.door_far { d - 1 } else { 0 };
        if !(0..w).contains(&u) || !(0..d).contains(&v) {
            let lamp_v = if self.door_far { d } else { -1 };
            let dc = w / 2;
            return if self.lamps && v == lamp_v && (u == dc - 2 || u == dc + 1) && y == self.base + 3 {
                mat::LAMP
            } else {
                cur
            };
        }
        if y < self.base {
            return if cur == 0 && y >= self.ground_lo {
                mat::COBBLE
            } else {
                cur
            };
        }
        let (wall, trim) = match self.style {
            0 => (mat::BRICK, mat::PLASTER),
            1 => (mat::PLASTER, mat::BRICK),
            2 => (mat::MIRROR, mat::METAL),
            _ => (mat::METAL, mat::PLASTER),
        };
        let rel = y - self.base;
        let top = self.floors * FLOOR_H;
        let perim = u == 0 || u == w - 1 || v == 0 || v == d - 1;
        if rel <= top {
            let r = rel % FLOOR_H;
            if r == 0 {
                return if perim { trim } else { mat::PLASTER };
            }
            if !perim {
                return if r == FLOOR_H - 1 && u == w / 2 && v == d / 2 {
                    mat::LAMP
                } else {
                    0
                };
            }
            if (u == 0 || u == w - 1) && (v == 0 || v == d - 1) {
                return trim;
            }
            if rel < FLOOR_H && v == door_v && (u == w / 2 - 1 || u == w / 2) && r <= 3 {
                return 0;
            }
            if self.style == 2 {
                return wall;
            }
            if self.style == 1 && r == FLOOR_H - 1 {
                return mat::METAL;
            }
            let (t, len) = if v == 0 || v == d - 1 { (u, w) } else { (v, d) };
            let window = (r == 2 || r == 3) && t >= 2 && t <= len - 3 && t % 3 != 1;
            return if window { mat::GLASS } else { wall };
        }
        let i = rel - top - 1;
        if self.gable {
            // The ridge runs along the longer side.
            let (m, end) = if d <= w {
                (v.min(d - 1 - v), u == 0 || u == w - 1)
            } else {
                (u.min(w - 1 - u), v == 0 || v == d - 1)
            };
            if m == i {
                mat::ROOF
            } else if m > i {
                if end { wall } else { 0 }
            } else {
                cur
            }
        } else if i == 0 && perim {
            trim
        } else if self.beacon && u == w / 2 && v == d / 2 && i <= 1 {
            if i == 1 { mat::LAMP } else { mat::METAL }
        } else {
            cur
        }
    }
}

impl ChunkSource for Terrain {
    fn size(&self) -> WorldSize {
        self.size
    }

    fn materials(&self) -> MaterialTable {
        materials()
    }

    fn uniform_hint(&self, chunk: [u32; 3]) -> Option<u16> {
        let o = chunk.map(|v| v as i32 * 16);
        if o[1] >= self.p.top {
            return Some(0);
        }
        let col = self.column_data(o[0], o[2]);
        let y0 = o[1] as f32;
        if o[1] + 16 <= self.p.cave_min && y0 + 20.0 < col.lo {
            // Features only write into air below their ground, and there is none here.
            return Some(mat::STONE);
        }
        if y0 < col.hi || o[1] < self.p.sea {
            return None;
        }
        let top = [o[0] + 16, o[1] + 16, o[2] + 16];
        let building = self
            .building(o[0].div_euclid(BUILDING_CELL), o[2].div_euclid(BUILDING_CELL))
            .is_some_and(|b| overlaps(b.lo, b.hi, o, top));
        if building || col.trees.iter().any(|t| overlaps(t.lo, t.hi, o, top)) {
            return None;
        }
        Some(0)
    }

    fn fill_chunk(&self, chunk: [u32; 3], out: &mut [u16; CHUNK_VOXELS]) {
        let o = chunk.map(|v| v as i32 * 16);
        if o[1] >= self.p.top {
            out.fill(0);
            return;
        }
        let col = self.column_data(o[0], o[2]);
        self.fill_ground(o, &col.lat, out);
        self.paint_features(o, &col.trees, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn params_keep_everything_below_the_top() {
        for sy in [64, 128, 256, 512, 1024, 4096] {
            let p = Params::new(WorldSize::new(64, sy, 64).unwrap());
            assert!(p.top <= sy as i32, "{sy}: top {}", p.top);
            assert!(p.h_cap + p.a_max < p.top as f32);
            assert!(p.h_cap as i32 + p.headroom + 2 <= p.top);
            assert!(p.sea > p.cave_min);
        }
        assert_eq!(mat::COUNT as usize + 1, materials().len());
    }
}

//! ROMA visibility (`--mode roma`; docs/RENDERING.md §3d): occupancy bitmaps of the world
//! aligned with a fixed set of directions, so that whether a short ray is blocked is a
//! few bit tests along one texel column of the map nearest its direction, with no
//! hierarchy to walk (Zeng et al., "Ray-aligned Occupancy Map Array").
//!
//! This is the CPU implementation, the second method the GPU's (`shaders/roma.wgsl`) is
//! tested against; both follow the same rules, written out here:
//!
//! - **Directions.** `side²` candidate directions stratify the upper hemisphere (+y)
//!   through the Shirley–Chiu concentric map, one per stratum, at the stratum's centre
//!   ([`candidate`]). A ray uses the map of its direction's stratum ([`stratum`]; a ray
//!   into the lower hemisphere uses the map of its reverse, walked backwards) and is traced
//!   *un-snapped*: its exact direction is walked across the map's texel columns. One more
//!   map is aligned with the sun ([`sun_map`], after the candidates).
//! - **Maps.** A map's frame is the orthonormal basis `(t, b, w)` of its direction `w`
//!   ([`super::scatter::basis`]); its cell `c` at level `l` is the cube of edge
//!   [`CELL`]`[l]` voxels whose map coordinates `(p·t, p·b, p·w) / CELL[l]` floor to `c`,
//!   and it is occupied when the world's cell of that level containing its centre is not
//!   empty (level 0 a voxel, level 1 a block, level 2 a chunk), or when its centre lies in
//!   an entity's instance box. A tile is [`TILE`]³ cells: one 32-bit word per texel column,
//!   bit `z` for the cell at depth `z` of the tile.
//! - **Windows.** Each level keeps, per map, the [`WINDOW_TILES`]³ tiles around the camera
//!   (their base is the camera's tile minus half the window). A point uses the finest
//!   level within [`REACH`] cells of the camera ([`level_of`]), beyond every level it is
//!   unoccluded. Rays start [`ORIGIN_OFFSET`]`[l]` cells off the surface along its normal;
//!   a ray that leaves a level's window goes on in the next level's, from at least two of
//!   its cells away, and is clear once it has left the last.
//! - **Lighting** of a diffuse surface: a cosine-distributed direction `ω` visible within
//!   the AO range adds `albedo · sky(ω)` (its mean is albedo × sky irradiance × AO / π
//!   under a uniform sky), and a sample of the sun's disc visible through the sun's map
//!   adds `albedo / π · E · cos θ` ([`CpuRoma::diffuse`]).

pub(crate) mod options;

pub use options::{DEFAULT_AO_RANGE, DEFAULT_DIRECTIONS, MAX_AO_RANGE, MAX_SIDE, RomaOptions};

use super::cpu::{CpuPathTracer, DiffuseTier};
use super::rng::Rng;
use super::scatter::{basis, cone, cosine};
use super::{Light, Sun};
use glam::{DVec3, IVec3};
use naadf_world::World;
use naadf_world::cell::{self, State};
use naadf_world::traverse::Hit;
use std::collections::HashMap;
use std::f64::consts::{FRAC_PI_4, PI};
use std::sync::{Arc, Mutex};

/// Levels of the maps, finest first.
pub const LEVELS: usize = 3;
/// The edge of a level's cell, in voxels: a voxel, a block, a chunk.
pub const CELL: [f64; LEVELS] = [1.0, 4.0, 16.0];
/// How far off the surface a ray starts, in cells of its level: at level 0 a cell is a
/// voxel, so one voxel clears every cell a surface's own voxel shares; a coarser cell is
/// occupied up to a cell above a surface inside it, so it needs two.
pub const ORIGIN_OFFSET: [f64; LEVELS] = [1.0, 2.0, 2.0];
/// Cells along a tile's edge: the bits of one column word.
pub const TILE: i32 = 32;
/// Words of a tile (one per texel column).
pub const TILE_WORDS: usize = (TILE * TILE) as usize;
/// Tiles along a window's edge: a window is 256³ cells.
pub const WINDOW_TILES: i32 = 8;
/// Tiles of a window.
pub const WINDOW_TILE_COUNT: usize = (WINDOW_TILES * WINDOW_TILES * WINDOW_TILES) as usize;
/// How far from the camera, in cells, a level serves points: the window is snapped to
/// tiles, so it holds every point within its half-edge less one tile of the camera, and
/// two cells less keep a ray's origin, off the surface, inside it too.
pub const REACH: f64 = ((WINDOW_TILES / 2 - 1) * TILE - 2) as f64;
/// The most texel columns a ray walks in one level: more than a window's diagonal.
pub const MAX_COLUMNS: u32 = 1024;

/// The index of the sun's map after `directions` candidates.
pub const fn sun_map(directions: u32) -> usize {
    directions as usize
}

/// The Shirley–Chiu concentric map of `(a, b)` in `[-1, 1]²` to the unit disc.
fn concentric(a: f64, b: f64) -> (f64, f64) {
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let (r, phi) = if a * a > b * b {
        (a, FRAC_PI_4 * (b / a))
    } else {
        (b, 2.0 * FRAC_PI_4 - FRAC_PI_4 * (a / b))
    };
    (r * phi.cos(), r * phi.sin())
}

/// The inverse of [`concentric`]: the square point of a disc point.
fn inverse_concentric(x: f64, y: f64) -> (f64, f64) {
    let r = (x * x + y * y).sqrt();
    let mut phi = y.atan2(x);
    if phi < -FRAC_PI_4 {
        phi += 2.0 * PI;
    }
    if phi < FRAC_PI_4 {
        (r, phi * r / FRAC_PI_4)
    } else if phi < 3.0 * FRAC_PI_4 {
        (-(phi - 2.0 * FRAC_PI_4) * r / FRAC_PI_4, r)
    } else if phi < 5.0 * FRAC_PI_4 {
        (-r, -(phi - 4.0 * FRAC_PI_4) * r / FRAC_PI_4)
    } else {
        ((phi - 6.0 * FRAC_PI_4) * r / FRAC_PI_4, -r)
    }
}

/// Candidate `k` of `side²`: the centre of stratum `(k % side, k / side)` of the
/// concentric square, lifted to the upper hemisphere (cosine-weighted, as Malley's method
/// lifts a uniform disc point).
///
/// ```
/// use naadf_client::light::roma::{candidate, stratum};
/// for k in 0..16 {
///     let d = candidate(4, k);
///     assert!((d.length() - 1.0).abs() < 1e-12 && d.y > 0.0);
///     assert_eq!(stratum(4, d), k);
/// }
/// ```
pub fn candidate(side: u32, k: u32) -> DVec3 {
    let s = f64::from(side);
    let a = (f64::from(k % side) + 0.5) / s * 2.0 - 1.0;
    let b = (f64::from(k / side) + 0.5) / s * 2.0 - 1.0;
    let (x, z) = concentric(a, b);
    DVec3::new(x, (1.0 - x * x - z * z).max(0.0).sqrt(), z)
}

/// The stratum of unit direction `d` among `side²` (of its reverse when it points down).
pub fn stratum(side: u32, d: DVec3) -> u32 {
    let d = if d.y < 0.0 { -d } else { d };
    let (a, b) = inverse_concentric(d.x, d.z);
    let s = f64::from(side);
    let cell = |v: f64| (((v + 1.0) * 0.5 * s).floor().max(0.0) as u32).min(side - 1);
    cell(a) + side * cell(b)
}

/// A map's frame: the rows that carry a world point into map coordinates (before the
/// division by the cell edge).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapFrame {
    /// The rows `t`, `b` and `w` (the map's direction).
    pub rows: [DVec3; 3],
}

impl MapFrame {
    /// The frame of unit direction `w`.
    pub fn of(w: DVec3) -> Self {
        let (t, b) = basis(w);
        MapFrame { rows: [t, b, w] }
    }

    /// `p` in the map's coordinates, in voxels.
    fn to_map(self, p: DVec3) -> DVec3 {
        DVec3::new(self.rows[0].dot(p), self.rows[1].dot(p), self.rows[2].dot(p))
    }

    /// The world point of map coordinates `m` (in voxels).
    fn to_world(self, m: DVec3) -> DVec3 {
        self.rows[0] * m.x + self.rows[1] * m.y + self.rows[2] * m.z
    }
}

/// The frames of every map: the candidates of `options`, then the sun's (straight up when
/// the sun is off).
pub fn map_frames(options: &RomaOptions, sun: Option<&Sun>) -> Vec<MapFrame> {
    let side = options.side();
    let sun_dir = sun.map_or(DVec3::Y, |s| DVec3::from(s.direction()));
    (0..options.directions)
        .map(|k| candidate(side, k))
        .chain([sun_dir])
        .map(MapFrame::of)
        .collect()
}

/// The base tile of the window of `frame` at `level` around `camera`: the camera's tile
/// less half the window, per map axis.
pub fn window_base(frame: &MapFrame, level: usize, camera: DVec3) -> IVec3 {
    let m = frame.to_map(camera) / CELL[level];
    let tile = (m / f64::from(TILE)).floor();
    IVec3::new(tile.x as i32, tile.y as i32, tile.z as i32) - IVec3::splat(WINDOW_TILES / 2)
}

/// The finest level that serves `p` for a camera at `camera` (`None` beyond them all).
pub fn level_of(p: DVec3, camera: DVec3) -> Option<usize> {
    let d = (p - camera).abs().max_element();
    (0..LEVELS).find(|&l| d < REACH * CELL[l])
}

/// Whether the world's cell of `level` holding world point `p` is not empty (outside the
/// world: empty).
pub fn occupied(world: &World, level: usize, p: DVec3) -> bool {
    let size = world.size();
    let dims = size.voxels();
    if (0..3).any(|a| !(p[a] >= 0.0 && p[a] < f64::from(dims[a]))) {
        return false;
    }
    let v = [p.x as u32, p.y as u32, p.z as u32];
    match level {
        0 => world.material_at(v) != 0,
        _ => {
            let c = world.chunks()[size.chunk_index(v.map(|x| x / 16))];
            match cell::state(c) {
                State::Empty => false,
                State::Full => true,
                State::Mixed if level >= 2 => true,
                State::Mixed => {
                    let i = cell::index4(v[0] / 4 % 4, v[1] / 4 % 4, v[2] / 4 % 4);
                    cell::state(world.blocks()[cell::pointer(c) as usize + i]) != State::Empty
                }
            }
        }
    }
}

/// The words of tile `tile` of map `frame` at `level`: bit `z` of word `x + 32y` is the
/// occupancy of cell `tile·32 + (x, y, z)`.
pub fn tile_words(
    world: &World,
    boxes: &[([f64; 3], [f64; 3])],
    frame: &MapFrame,
    level: usize,
    tile: IVec3,
) -> Vec<u32> {
    let cell = CELL[level];
    let corner = tile * TILE;
    let inside = |p: DVec3, b: &([f64; 3], [f64; 3])| (0..3).all(|a| p[a] >= b.0[a] && p[a] <= b.1[a]);
    let mut words = vec![0u32; TILE_WORDS];
    for y in 0..TILE {
        for x in 0..TILE {
            let mut word = 0u32;
            for z in 0..TILE {
                let c = corner + IVec3::new(x, y, z);
                let p = frame.to_world((c.as_dvec3() + 0.5) * cell);
                if occupied(world, level, p) || boxes.iter().any(|b| inside(p, b)) {
                    word |= 1 << z;
                }
            }
            words[(x + TILE * y) as usize] = word;
        }
    }
    words
}

/// The tiles a [`CpuRoma`] built so far, by level, map and tile coordinates.
type TileCache = Mutex<HashMap<(usize, usize, IVec3), Arc<Vec<u32>>>>;

/// How a ray through one level's window ended.
enum Walk {
    /// It met an occupied cell.
    Hit,
    /// It found none up to `t` (where it left the window, or its end).
    Clear(f64),
}

/// ROMA maps of one world for one camera and sun: the CPU's, with tiles built when a ray
/// first needs them.
pub struct CpuRoma<'w> {
    world: &'w World,
    options: RomaOptions,
    light: Light,
    camera: DVec3,
    frames: Vec<MapFrame>,
    /// The window base of each map at each level.
    bases: Vec<[IVec3; LEVELS]>,
    boxes: Vec<([f64; 3], [f64; 3])>,
    tiles: TileCache,
}

impl<'w> CpuRoma<'w> {
    /// The maps of `world` for a camera at `camera` under `light`.
    pub fn new(world: &'w World, options: RomaOptions, light: Light, camera: [f64; 3]) -> Result<Self, String> {
        options.check()?;
        let camera = DVec3::from(camera);
        let frames = map_frames(&options, light.sun.as_ref());
        let bases = frames
            .iter()
            .map(|f| std::array::from_fn(|l| window_base(f, l, camera)))
            .collect();
        Ok(CpuRoma {
            world,
            options,
            light,
            camera,
            frames,
            bases,
            boxes: naadf_world::entity::instance_boxes(world.entity_instances()),
            tiles: Mutex::new(HashMap::new()),
        })
    }

    /// The occupancy column `(x, y)` of map `map` at `level` in tile row `tz` (0 outside
    /// the window).
    fn column(&self, level: usize, map: usize, x: i32, y: i32, tz: i32) -> u32 {
        let tile = IVec3::new(x.div_euclid(TILE), y.div_euclid(TILE), tz);
        let rel = tile - self.bases[map][level];
        if rel.min_element() < 0 || rel.max_element() >= WINDOW_TILES {
            return 0;
        }
        let words = {
            let mut tiles = self.tiles.lock().expect("ROMA tiles");
            tiles
                .entry((level, map, tile))
                .or_insert_with(|| Arc::new(tile_words(self.world, &self.boxes, &self.frames[map], level, tile)))
                .clone()
        };
        words[(x.rem_euclid(TILE) + TILE * y.rem_euclid(TILE)) as usize]
    }

    /// Whether column `(x, y)` has an occupied cell from depth `lo` to `hi` (inclusive).
    fn column_any(&self, level: usize, map: usize, x: i32, y: i32, lo: i32, hi: i32) -> bool {
        (lo.div_euclid(TILE)..=hi.div_euclid(TILE)).any(|tz| {
            let first = (lo - tz * TILE).max(0);
            let last = (hi - tz * TILE).min(TILE - 1);
            let mask = (u32::MAX >> (31 - last + first)) << first;
            self.column(level, map, x, y, tz) & mask != 0
        })
    }

    /// Walks `o + t·d` for `t` in `[t0, t1]` across the texel columns of map `map` at
    /// `level`, within its window.
    fn walk(&self, level: usize, map: usize, o: DVec3, d: DVec3, t0: f64, t1: f64) -> Walk {
        let frame = &self.frames[map];
        let q = frame.to_map(o) / CELL[level];
        let e = frame.to_map(d) / CELL[level];
        let lo = (self.bases[map][level] * TILE).as_dvec3();
        let hi = lo + f64::from(WINDOW_TILES * TILE);
        // The window's slab test.
        let (mut ta, mut tb) = (t0, t1);
        for a in 0..3 {
            if e[a] == 0.0 {
                if q[a] < lo[a] || q[a] >= hi[a] {
                    return Walk::Clear(t0);
                }
                continue;
            }
            let (s0, s1) = ((lo[a] - q[a]) / e[a], (hi[a] - q[a]) / e[a]);
            ta = ta.max(s0.min(s1));
            tb = tb.min(s0.max(s1));
        }
        if ta >= tb {
            // Nothing of the ray lies in this window: the next level takes it from `t0`.
            return Walk::Clear(t0);
        }
        let start = q + e * ta;
        let (mut x, mut y) = (start.x.floor() as i32, start.y.floor() as i32);
        let axis = |p: f64, i: i32, v: f64| {
            if v > 0.0 {
                ((f64::from(i + 1) - p) / v, 1.0 / v, 1)
            } else if v < 0.0 {
                ((f64::from(i) - p) / v, -1.0 / v, -1)
            } else {
                (f64::INFINITY, f64::INFINITY, 0)
            }
        };
        let (mut next_x, dx, sx) = axis(q.x, x, e.x);
        let (mut next_y, dy, sy) = axis(q.y, y, e.y);
        let mut t_in = ta;
        for _ in 0..MAX_COLUMNS {
            let t_out = next_x.min(next_y).min(tb);
            let (wa, wb) = (q.z + e.z * t_in, q.z + e.z * t_out);
            if self.column_any(level, map, x, y, wa.min(wb).floor() as i32, wa.max(wb).floor() as i32) {
                return Walk::Hit;
            }
            if t_out >= tb {
                break;
            }
            if next_x <= next_y {
                x += sx;
                next_x += dx;
            } else {
                y += sy;
                next_y += dy;
            }
            t_in = t_out;
        }
        Walk::Clear(tb)
    }

    /// Whether the ray from surface point `p` (normal `n`) along unit `d` is clear for
    /// `range` voxels through map `map`, starting at the level that serves `p` (beyond
    /// them all: clear).
    fn clear(&self, map: usize, p: DVec3, n: DVec3, d: DVec3, range: f64) -> bool {
        let Some(level) = level_of(p, self.camera) else {
            return true;
        };
        let o = p + n * (ORIGIN_OFFSET[level] * CELL[level]);
        let mut t = 0.0f64;
        for (l, cell) in CELL.iter().enumerate().skip(level) {
            let start = if l == level { 0.0 } else { t.max(2.0 * cell) };
            if start >= range {
                return true;
            }
            match self.walk(l, map, o, d, start, range) {
                Walk::Hit => return false,
                Walk::Clear(end) if end >= range => return true,
                Walk::Clear(end) => t = end,
            }
        }
        true
    }

    /// The visibility of direction `d` (unit) from surface point `p` with normal `n`
    /// within the AO range: 1 clear, 0 blocked.
    pub fn sky_visibility(&self, p: DVec3, n: DVec3, d: DVec3) -> f64 {
        let map = stratum(self.options.side(), d) as usize;
        f64::from(u8::from(self.clear(map, p, n, d, self.options.ao_range)))
    }

    /// The ambient occlusion of surface point `p` with normal `n`: the mean visibility of
    /// `samples` cosine-distributed directions drawn from stream `seed`.
    pub fn ambient_occlusion(&self, p: [f64; 3], n: [f64; 3], samples: u32, seed: u32) -> f64 {
        let (p, n) = (DVec3::from(p), DVec3::from(n));
        let sum: f64 = (0..samples)
            .map(|s| {
                let mut rng = Rng::new(seed, 0, s);
                let u = [f64::from(rng.next_f32()), f64::from(rng.next_f32())];
                self.sky_visibility(p, n, cosine(n, u))
            })
            .sum();
        sum / f64::from(samples.max(1))
    }

    /// One sample of the light a diffuse surface of `albedo` at `p` (normal `n`) reflects
    /// toward the viewer, `sky(ω)` being the sky's radiance along `ω` (without the sun's
    /// disc). Draws four numbers from `rng`: the sky direction's two, then the sun's.
    pub fn diffuse(&self, p: DVec3, n: DVec3, albedo: DVec3, sky: &dyn Fn(DVec3) -> DVec3, rng: &mut Rng) -> DVec3 {
        let u = [f64::from(rng.next_f32()), f64::from(rng.next_f32())];
        let us = [f64::from(rng.next_f32()), f64::from(rng.next_f32())];
        let w = cosine(n, u);
        let map = stratum(self.options.side(), w) as usize;
        let mut l = DVec3::ZERO;
        if self.clear(map, p, n, w, self.options.ao_range) {
            l += albedo * sky(w);
        }
        if let Some(sun) = self.light.sun {
            let ws = cone(DVec3::from(sun.direction()), Sun::one_minus_cos(), us);
            let cos = n.dot(ws);
            let sun_map = sun_map(self.options.directions);
            if cos > 0.0 && self.clear(sun_map, p, n, ws, f64::INFINITY) {
                l += albedo / PI * (cos * sun.sample_weight());
            }
        }
        l
    }
}

impl DiffuseTier for CpuRoma<'_> {
    /// [`CpuRoma::diffuse`] under the tracer's sky.
    fn diffuse(
        &self,
        tracer: &CpuPathTracer,
        _: &Hit,
        surface: DVec3,
        n: DVec3,
        albedo: DVec3,
        rng: &mut Rng,
    ) -> DVec3 {
        CpuRoma::diffuse(self, surface, n, albedo, &|w| tracer.sky_seen(w), rng)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_concentric_map_inverts() {
        for i in 0..40 {
            for j in 0..40 {
                let (a, b) = (f64::from(i) / 19.5 - 1.0 + 0.01, f64::from(j) / 19.5 - 1.0 + 0.013);
                let (x, y) = concentric(a, b);
                let (a2, b2) = inverse_concentric(x, y);
                assert!(
                    (a - a2).abs() < 1e-9 && (b - b2).abs() < 1e-9,
                    "({a}, {b}) → ({a2}, {b2})"
                );
            }
        }
    }

    #[test]
    fn a_direction_falls_in_the_stratum_of_its_nearest_candidates() {
        // Every stratum holds its candidate, and a direction's reverse shares its map.
        let mut rng = Rng::new(1, 2, 3);
        for _ in 0..1000 {
            let u = [f64::from(rng.next_f32()), f64::from(rng.next_f32())];
            let d = cosine(DVec3::Y, u);
            let k = stratum(4, d);
            assert_eq!(stratum(4, -d), k);
            // The candidate of its stratum is within the stratum's angular size.
            assert!(candidate(4, k).dot(d) > 0.7, "{d} far from candidate {k}");
        }
    }
}

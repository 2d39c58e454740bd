//! Traversal of the chunk → block → voxel hierarchy, with or without AADF jumps.

use super::ray::{Hit, Ray};
use crate::cell::{self, Aadf, CELL_FIELD_BITS, CHUNK_FIELD_BITS, State};
use crate::world::World;

/// Upper bound on visited cells; unreachable while the AADF safety invariant holds (every
/// step enters a new cell of the finite Amanatides–Woo sequence), kept as a guard.
const MAX_STEPS: u32 = 1 << 24;

/// Traces `ray` with AADF jumps (NAADF-REFERENCE §3.2).
///
/// ```
/// use naadf_world::{World, preset::Preset, traverse::{trace_naadf, Ray}};
/// let src = Preset::Test.source(None, 1).unwrap();
/// let world = World::build(&*src, &|_| {}).unwrap();
/// let down = Ray::new([20.5, 63.5, 20.5], [0.0, -1.0, 0.0]).unwrap();
/// assert!(trace_naadf(&world, &down).is_some());
/// ```
pub fn trace_naadf(world: &World, ray: &Ray) -> Option<Hit> {
    trace::<true>(world, ray)
}

/// Traces `ray` through the same hierarchy without distance fields.
pub fn trace_nodf(world: &World, ray: &Ray) -> Option<Hit> {
    trace::<false>(world, ray)
}

/// What a cell lookup found: a solid material, or how far the empty region extends.
enum Probe {
    Solid(u16),
    Empty([i64; 3]),
}

fn trace<const DF: bool>(world: &World, ray: &Ray) -> Option<Hit> {
    let size = world.size();
    let dims = size.voxels();
    let entry = ray.entry(dims)?;
    let (mut cell, mut t, mut axis) = (entry.cell, entry.t, entry.axis);
    let dir = ray.dir();
    // The AADF field facing the ray on each axis: −a for negative directions, +a otherwise.
    let facing: [usize; 3] = std::array::from_fn(|a| 2 * a + usize::from(dir[a] > 0.0));
    let neg: [bool; 3] = std::array::from_fn(|a| dir[a] <= 0.0);
    let to_edge = |c: i64, a: usize, edge: i64| {
        if neg[a] {
            c & (edge - 1)
        } else {
            edge - 1 - (c & (edge - 1))
        }
    };
    for steps in 1..=MAX_STEPS {
        let p = cell.map(|v| v as u32);
        let probe = probe::<DF>(world, p, &facing, &to_edge);
        match probe {
            Probe::Solid(m) => return Some(ray.hit(cell, t, axis, m, steps)),
            Probe::Empty(skip) => {
                let (nt, na, next) = ray.exit(cell, skip);
                if !(0..3).all(|a| next[a] >= 0 && next[a] < i64::from(dims[a])) {
                    return None;
                }
                (cell, t, axis) = (next, nt, Some(na));
            }
        }
    }
    None
}

#[inline(always)]
fn probe<const DF: bool>(
    world: &World,
    p: [u32; 3],
    facing: &[usize; 3],
    to_edge: &impl Fn(i64, usize, i64) -> i64,
) -> Probe {
    let edges = |edge: i64| -> [i64; 3] { std::array::from_fn(|a| to_edge(i64::from(p[a]), a, edge)) };
    let size = world.size();
    let chunk = world.chunks()[size.chunk_index([p[0] >> 4, p[1] >> 4, p[2] >> 4])];
    match cell::state(chunk) {
        State::Full => Probe::Solid(cell::material(chunk)),
        State::Empty => {
            let e = edges(16);
            Probe::Empty(std::array::from_fn(|a| {
                if DF {
                    e[a] + 16 * i64::from(Aadf::field(chunk, facing[a], CHUNK_FIELD_BITS))
                } else {
                    e[a]
                }
            }))
        }
        State::Mixed => {
            let bi = cell::index4(p[0] >> 2 & 3, p[1] >> 2 & 3, p[2] >> 2 & 3);
            let block = world.blocks()[cell::pointer(chunk) as usize + bi];
            match cell::state(block) {
                State::Full => Probe::Solid(cell::material(block)),
                State::Empty => {
                    let e = edges(4);
                    Probe::Empty(std::array::from_fn(|a| {
                        if DF {
                            e[a] + 4 * i64::from(Aadf::field(block, facing[a], CELL_FIELD_BITS))
                        } else {
                            e[a]
                        }
                    }))
                }
                State::Mixed => {
                    let v = cell::group_voxel(
                        world.voxels(),
                        cell::pointer(block) as usize,
                        cell::index4(p[0] & 3, p[1] & 3, p[2] & 3),
                    );
                    if cell::voxel_is_solid(v) {
                        Probe::Solid(cell::voxel_material(v))
                    } else if DF {
                        Probe::Empty(std::array::from_fn(|a| {
                            i64::from(Aadf::field(u32::from(v), facing[a], CELL_FIELD_BITS))
                        }))
                    } else {
                        Probe::Empty([0; 3])
                    }
                }
            }
        }
    }
}

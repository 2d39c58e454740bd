//! Traversal of the chunk → block → voxel hierarchy, with or without AADF jumps.

use super::entities::{OpenPart, WorldPart};
use super::ray::{Hit, Ray};
use crate::cell::{self, Aadf, CELL_FIELD_BITS, CHUNK_FIELD_BITS, State};
use crate::world::World;

/// Upper bound on visited cells; unreachable while the AADF safety invariant holds (every
/// step enters a new cell of the finite Amanatides–Woo sequence), kept as a guard.
const MAX_STEPS: u32 = 1 << 24;

/// Traces `ray` with AADF jumps (docs/NAADF.md §9).
///
/// ```
/// use naadf_world::{World, preset::Preset, traverse::{trace_naadf, Ray}};
/// let src = Preset::Test.source(None, 1).unwrap();
/// let world = World::build(&*src, &|_| {}).unwrap();
/// let down = Ray::new([20.5, 63.5, 20.5], [0.0, -1.0, 0.0]).unwrap();
/// assert!(trace_naadf(&world, &down).is_some());
/// ```
pub fn trace_naadf(world: &World, ray: &Ray) -> Option<Hit> {
    trace::<true, false>(world, ray)
}

/// Traces `ray` through the same hierarchy without distance fields.
pub fn trace_nodf(world: &World, ray: &Ray) -> Option<Hit> {
    trace::<false, false>(world, ray)
}

/// Whether `ray` meets anything, world or entity, within its step budget: the same as
/// `trace_naadf(world, ray).is_some()`, for rays that only ask whether something is in the
/// way (shadow rays). A ray that hits the static world needs no walk of the instances, since
/// any hit will do.
///
/// ```
/// use naadf_world::{World, preset::Preset, traverse::{occluded_naadf, trace_naadf, Ray}};
/// let src = Preset::Test.source(None, 1).unwrap();
/// let world = World::build(&*src, &|_| {}).unwrap();
/// let down = Ray::new([20.5, 63.5, 20.5], [0.0, -1.0, 0.0]).unwrap();
/// assert_eq!(occluded_naadf(&world, &down), trace_naadf(&world, &down).is_some());
/// ```
pub fn occluded_naadf(world: &World, ray: &Ray) -> bool {
    trace::<true, true>(world, ray).is_some()
}

/// What a cell lookup found: a solid material, or how far the empty region extends.
enum Probe {
    Solid(u16),
    Empty([i64; 3]),
}

/// The world loop, then the instances. With `ANY`, a world hit is returned as it is,
/// without looking for a nearer entity (whether there is a hit is all the caller asks).
fn trace<const DF: bool, const ANY: bool>(world: &World, ray: &Ray) -> Option<Hit> {
    // Worlds without entities run a loop with no entity code at all.
    let Some(view) = world.entity_view() else {
        return trace_static::<DF>(world, ray);
    };
    view.resolve(ray, world_part::<DF, ANY>(world, ray))
}

/// Traces `ray` through the static world alone, as if it had no entities.
pub(crate) fn trace_static<const DF: bool>(world: &World, ray: &Ray) -> Option<Hit> {
    world_loop::<DF, false>(world, ray, &mut (0.0, 0.0, 0))
}

/// [`trace`] (without `ANY`) for each of `rays`, the instance test made for all at once.
pub(crate) fn trace_many<const DF: bool>(world: &World, rays: &[Ray]) -> Vec<Option<Hit>> {
    let Some(view) = world.entity_view() else {
        return rays.iter().map(|r| trace::<DF, false>(world, r)).collect();
    };
    view.resolve_many(rays, |r| world_part::<DF, false>(world, r))
}

/// The world loop's part of a trace through a world with entities.
#[inline(always)]
fn world_part<const DF: bool, const ANY: bool>(world: &World, ray: &Ray) -> WorldPart {
    let mut span = (f64::NAN, f64::NAN, 0);
    let hit = world_loop::<DF, true>(world, ray, &mut span);
    match hit {
        Some(h) if ANY => WorldPart::Done(Some(h)),
        Some(h) => WorldPart::Open(OpenPart {
            world: hit,
            t_entry: span.0,
            t_end: h.t,
            steps: h.steps,
        }),
        // Missed the world, or ran out of steps.
        None if span.1.is_nan() => WorldPart::Done(None),
        None => WorldPart::Open(OpenPart {
            world: None,
            t_entry: span.0,
            t_end: span.1,
            steps: span.2,
        }),
    }
}

/// The hierarchical DDA through the static world: the world hit, if any. With `ENT`, it
/// sets `span.0` to the time the ray entered the world and, if it leaves the world without
/// a hit, `span.1` and `span.2` to the time it left and the cells visited (what the entity
/// test needs). (Out-parameters rather than a richer result keep the entity-free instance as
/// fast as a loop without entity code.)
#[inline(always)]
fn world_loop<const DF: bool, const ENT: bool>(world: &World, ray: &Ray, span: &mut (f64, f64, u32)) -> Option<Hit> {
    let size = world.size();
    let dims = size.voxels();
    let entry = ray.entry(dims)?;
    if ENT {
        span.0 = entry.t;
    }
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
    let mut steps = 0u32;
    // One iteration per chunk visited; the inner loop steps through the chunk's blocks and
    // voxels (an empty chunk is always left in one step), so chunk-level work happens once
    // per chunk.
    loop {
        let chunk_at = cell.map(|v| (v >> 4) as u32);
        let chunk = world.chunks()[size.chunk_index(chunk_at)];
        loop {
            steps += 1;
            if steps > MAX_STEPS {
                return None;
            }
            match probe::<DF>(world, chunk, cell.map(|v| v as u32), &facing, &to_edge) {
                Probe::Solid(m) => return Some(ray.hit(cell, t, axis, m, steps)),
                Probe::Empty(skip) => {
                    let (nt, na, next) = ray.exit(cell, skip);
                    if !(0..3).all(|a| next[a] >= 0 && next[a] < i64::from(dims[a])) {
                        if ENT {
                            // An AADF box may reach beyond the world: the ray left it at
                            // the world's edge, not where it leaves the box.
                            (span.1, span.2) = (ray.leave_time(dims).min(nt), steps);
                        }
                        return None;
                    }
                    (cell, t, axis) = (next, nt, Some(na));
                    if (0..3).any(|a| (next[a] >> 4) as u32 != chunk_at[a]) {
                        break;
                    }
                }
            }
        }
    }
}

/// Looks up voxel `p` in its chunk's cell `chunk`.
#[inline(always)]
fn probe<const DF: bool>(
    world: &World,
    chunk: u32,
    p: [u32; 3],
    facing: &[usize; 3],
    to_edge: &impl Fn(i64, usize, i64) -> i64,
) -> Probe {
    let edges = |edge: i64| -> [i64; 3] { std::array::from_fn(|a| to_edge(i64::from(p[a]), a, edge)) };
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

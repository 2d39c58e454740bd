//! CPU ray traversal: three methods on the same world that must agree exactly.
//!
//! - [`Method::Naadf`]: the reference's multi-axis DDA (docs/NAADF.md §9) that jumps over the
//!   empty cuboid given by the chunk, block and voxel AADFs;
//! - [`Method::Nodf`]: the same hierarchy with the AADFs ignored (empty chunks and blocks
//!   are skipped only to their own edge);
//! - [`Method::Grid`]: Amanatides–Woo over a dense decode ([`DenseGrid`]).
//!
//! All three are exact views of one event model (see [`ray`]): the ray crosses cell
//! boundaries at times `t = (b − o)/d` computed in `f64`, and crossings at equal `t` happen
//! one axis at a time in the order x, y, z. A method may skip a run of events only where
//! every cell in between is known to be empty, so all three visit the same first solid
//! cell and report the same voxel, normal, material and `t`.

mod entities;
pub mod grid;
mod hierarchy;
pub mod ray;

pub use grid::DenseGrid;
pub use hierarchy::{occluded_naadf, trace_naadf, trace_nodf};
pub use ray::{DEFAULT_MAX_STEPS, Hit, MAX_COORD, Ray, same_result};

use crate::world::World;

/// A traversal method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Hierarchical DDA with AADF jumps.
    Naadf,
    /// Hierarchical DDA without distance fields.
    Nodf,
    /// Dense-grid Amanatides–Woo.
    Grid,
}

impl Method {
    /// All methods, in the order benchmarks report them.
    pub const ALL: [Method; 3] = [Method::Naadf, Method::Nodf, Method::Grid];

    /// The method's CLI name.
    pub fn name(self) -> &'static str {
        match self {
            Method::Naadf => "naadf",
            Method::Nodf => "nodf",
            Method::Grid => "grid",
        }
    }

    /// Parses a CLI name.
    pub fn parse(s: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == s)
    }
}

/// A ready-to-use tracer for one method (the grid method owns its dense decode).
pub struct Tracer<'w>(Kind<'w>);

/// What a [`Tracer`] runs.
enum Kind<'w> {
    /// The hierarchy ([`Method::Naadf`] with `DF`, [`Method::Nodf`] without); rays meet the
    /// instances unless `static_only`.
    Hierarchy {
        world: &'w World,
        df: bool,
        static_only: bool,
    },
    /// See [`Method::Grid`].
    Grid(DenseGrid),
}

impl<'w> Tracer<'w> {
    /// Prepares `method` on `world` (the grid method decodes the world densely, which fails
    /// if the decode would not fit in memory).
    pub fn new(world: &'w World, method: Method) -> Result<Self, crate::WorldError> {
        let hierarchy = |df| Kind::Hierarchy {
            world,
            df,
            static_only: false,
        };
        Ok(Tracer(match method {
            Method::Naadf => hierarchy(true),
            Method::Nodf => hierarchy(false),
            Method::Grid => Kind::Grid(DenseGrid::from_world(world)?),
        }))
    }

    /// The same tracer for the static world alone: rays pass through every instance, as
    /// through the world without entities, whose static buffers are this world's byte for
    /// byte (docs/NAADF.md §11). Benchmarks pair it with the full tracer to time the
    /// entities over the same memory (two copies of one world at different addresses
    /// trace at rates a percent or two apart).
    ///
    /// ```
    /// use naadf_world::{World, preset::Preset, traverse::{Method, Ray, Tracer}};
    /// let src = Preset::Test.source(None, 1).unwrap();
    /// let world = World::build(&*src, &|_| {}).unwrap();
    /// let down = Ray::new([20.5, 63.5, 20.5], [0.0, -1.0, 0.0]).unwrap();
    /// let full = Tracer::new(&world, Method::Naadf).unwrap();
    /// let static_only = Tracer::new(&world, Method::Naadf).unwrap().static_only();
    /// // Without entities, both see the same world.
    /// assert_eq!(static_only.trace(&down), full.trace(&down));
    /// ```
    pub fn static_only(self) -> Self {
        Tracer(match self.0 {
            Kind::Hierarchy { world, df, .. } => Kind::Hierarchy {
                world,
                df,
                static_only: true,
            },
            Kind::Grid(g) => Kind::Grid(g.static_only()),
        })
    }

    /// Traces one ray; `None` is a miss.
    #[inline]
    pub fn trace(&self, ray: &Ray) -> Option<Hit> {
        match &self.0 {
            Kind::Hierarchy { world, df, static_only } => match (df, static_only) {
                (true, false) => trace_naadf(world, ray),
                (false, false) => trace_nodf(world, ray),
                (true, true) => hierarchy::trace_static::<true>(world, ray),
                (false, true) => hierarchy::trace_static::<false>(world, ray),
            },
            Kind::Grid(g) => g.trace(ray),
        }
    }

    /// Traces each of `rays`: the same results as [`Tracer::trace`] on each, for less work
    /// in a world with entities, whose instance hierarchy the rays then walk as a batch
    /// ([`crate::entity::bvh::batch`]). Callers with many rays to trace (a frame's camera
    /// or bounce rays, a benchmark's ray set) pass them in slices of a thousand or more.
    ///
    /// ```
    /// use naadf_world::{World, preset::Preset, traverse::{Method, Ray, Tracer}};
    /// let src = Preset::Test.source(None, 1).unwrap();
    /// let world = World::build(&*src, &|_| {}).unwrap();
    /// let tracer = Tracer::new(&world, Method::Naadf).unwrap();
    /// let rays: Vec<Ray> = (0..8)
    ///     .map(|i| Ray::new([20.5 + f64::from(i), 63.5, 20.5], [0.0, -1.0, 0.0]).unwrap())
    ///     .collect();
    /// let one_by_one: Vec<_> = rays.iter().map(|r| tracer.trace(r)).collect();
    /// assert_eq!(tracer.trace_many(&rays), one_by_one);
    /// ```
    pub fn trace_many(&self, rays: &[Ray]) -> Vec<Option<Hit>> {
        match &self.0 {
            Kind::Hierarchy {
                world,
                df,
                static_only: false,
            } => match df {
                true => hierarchy::trace_many::<true>(world, rays),
                false => hierarchy::trace_many::<false>(world, rays),
            },
            Kind::Hierarchy { static_only: true, .. } => rays.iter().map(|r| self.trace(r)).collect(),
            Kind::Grid(g) => g.trace_many(rays),
        }
    }
}

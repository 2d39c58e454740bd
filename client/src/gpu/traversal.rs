//! [`Traversal`]: what a ray walks through the world on the GPU — one of the world's own
//! methods, or a structure of the paper's comparison — and the world loop that walks it.

use super::shaders::Loop;
use naadf_world::baselines::HybridFormat;
use naadf_world::traverse::Method;

/// What a ray-list trace walks: one of the world's traversal methods, or a structure of
/// the paper's comparison (uploaded with [`super::GpuWorld::upload_svo`],
/// [`super::GpuWorld::upload_svdag`] or [`super::GpuWorld::upload_hybrid`]; geometry only, so its hits
/// report material 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Traversal {
    /// A method of the world's own (the grid needs [`super::GpuWorld::upload_grid`]).
    Method(Method),
    /// The SVO.
    Svo,
    /// The SVDAG.
    Svdag,
    /// A hybrid format.
    Hybrid(HybridFormat),
}

impl Traversal {
    /// Every traversal, in the order benchmarks report them.
    pub const ALL: [Traversal; 7] = [
        Traversal::Method(Method::Naadf),
        Traversal::Method(Method::Nodf),
        Traversal::Method(Method::Grid),
        Traversal::Svo,
        Traversal::Svdag,
        Traversal::Hybrid(HybridFormat::R4G7),
        Traversal::Hybrid(HybridFormat::R3G8),
    ];

    /// Its name in reports (a method's CLI name, `svo`, `svdag`, a hybrid format's name).
    pub fn name(self) -> &'static str {
        match self {
            Traversal::Method(m) => m.name(),
            Traversal::Svo => "svo",
            Traversal::Svdag => "svdag",
            Traversal::Hybrid(f) => f.name(),
        }
    }

    /// The world loop, and whether it uses AADFs.
    pub(crate) fn world_loop(self) -> (Loop, bool) {
        match self {
            Traversal::Method(Method::Naadf) => (Loop::Hierarchy, true),
            Traversal::Method(Method::Nodf) => (Loop::Hierarchy, false),
            Traversal::Method(Method::Grid) => (Loop::Grid, false),
            Traversal::Svo => (Loop::Svo, false),
            Traversal::Svdag => (Loop::Svdag, false),
            Traversal::Hybrid(_) => (Loop::Hybrid, false),
        }
    }
}

impl From<Method> for Traversal {
    fn from(m: Method) -> Self {
        Traversal::Method(m)
    }
}

//! The GI pipeline's passes ([`GiPass`], in frame order) and the WGSL each one is built
//! from ([`gi_pass`]).

use super::memory::{GI_CONSTANTS, GiSplit, gi_parts};
use crate::gpu::shaders::{FIRST_HIT, LIGHT, NO_TIER, PassSource, SAMPLE, constants};

/// `shaders/gi_common.wgsl`: the GI passes' bindings, encodings and atmosphere table.
const GI_COMMON: &str = include_str!("../../../../shaders/gi_common.wgsl");
/// `shaders/gi_primary.wgsl`: the GI first hit, TAA gather and TAA merge.
const GI_PRIMARY: &str = include_str!("../../../../shaders/gi_primary.wgsl");
/// `shaders/gi_entities.wgsl`: the entities' poses per TAA slot.
const GI_ENTITIES: &str = include_str!("../../../../shaders/gi_entities.wgsl");
/// `shaders/gi_samples.wgsl`: the ray queue, secondary rays, projection and refinement.
const GI_SAMPLES: &str = include_str!("../../../../shaders/gi_samples.wgsl");
/// `shaders/gi_resample.wgsl`: spatial resampling and the denoiser.
const GI_RESAMPLE: &str = include_str!("../../../../shaders/gi_resample.wgsl");

/// Every GI pass's files after the shared ones: the sample streams, the light model (with
/// no lighting tier), the first-hit chain and the `gi_*` files.
const GI_FILES: &[&str] = &[
    SAMPLE,
    LIGHT,
    NO_TIER,
    FIRST_HIT,
    GI_COMMON,
    GI_ENTITIES,
    GI_PRIMARY,
    GI_SAMPLES,
    GI_RESAMPLE,
];

/// One pass of the pipeline, in frame order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GiPass {
    /// Fills the atmosphere table (first frame of a history only).
    Atmosphere,
    /// The jittered first hit and its mirror chain.
    FirstHit,
    /// The entities' poses into this frame's slot, from the instance records.
    Poses,
    /// The long-term TAA's gather of earlier frames' samples.
    Taa,
    /// Which pixels trace a secondary ray, compacted per region.
    Queue,
    /// The queue's layout, the ring's bookkeeping and the indirect arguments.
    QueueScan,
    /// One secondary path per queued pixel, into the sample ring.
    Trace,
    /// The ring's samples counted into this frame's regions.
    Project,
    /// The winning samples stored in their regions' slots.
    ProjectStore,
    /// At most `MAX_KEPT` levelled samples per region.
    Refine,
    /// Spatial resampling, the visibility ray and the sun.
    Resample,
    /// The denoiser along x.
    DenoiseX,
    /// The denoiser along y.
    DenoiseY,
    /// This frame's colour into the TAA, and the result.
    Merge,
}

impl GiPass {
    /// Every pass, in frame order.
    pub const ALL: [GiPass; 14] = [
        GiPass::Atmosphere,
        GiPass::FirstHit,
        GiPass::Poses,
        GiPass::Taa,
        GiPass::Queue,
        GiPass::QueueScan,
        GiPass::Trace,
        GiPass::Project,
        GiPass::ProjectStore,
        GiPass::Refine,
        GiPass::Resample,
        GiPass::DenoiseX,
        GiPass::DenoiseY,
        GiPass::Merge,
    ];

    /// The WGSL entry point.
    pub fn entry(self) -> &'static str {
        match self {
            GiPass::Atmosphere => "gi_atmosphere",
            GiPass::FirstHit => "gi_first_hit",
            GiPass::Poses => "gi_poses",
            GiPass::Taa => "gi_taa",
            GiPass::Queue => "gi_queue",
            GiPass::QueueScan => "gi_queue_scan",
            GiPass::Trace => "gi_trace",
            GiPass::Project => "gi_project",
            GiPass::ProjectStore => "gi_project_store",
            GiPass::Refine => "gi_refine",
            GiPass::Resample => "gi_resample",
            GiPass::DenoiseX => "gi_denoise_x",
            GiPass::DenoiseY => "gi_denoise_y",
            GiPass::Merge => "gi_merge",
        }
    }
}

/// The WGSL of `pass` with the history's arrays split as `split`: the GI files, the
/// constants the pipeline shares with Rust, and the split arrays' declarations.
pub(crate) fn gi_pass(pass: GiPass, split: GiSplit) -> PassSource {
    PassSource {
        entry: pass.entry(),
        files: GI_FILES,
        generated: constants(&GI_CONSTANTS) + &gi_parts(&split),
    }
}

//! The GI pipeline's memory (docs/RENDERING.md §3c): the sizes of its arrays, where each one
//! starts ([`Layout`]), how the two large ones are split across bindings ([`GiSplit`]), and
//! the WGSL the passes get for them: the constants ([`GI_CONSTANTS`]) and the split arrays'
//! declarations ([`gi_parts`]). shaders/gi_common.wgsl describes each array.

use crate::gpu::shaders::{NO_ENTITY, PartedArray, WgslValue, declare_parts};

/// Frames the long-term TAA keeps a sample of, per pixel.
pub const TAA_SLOTS: u32 = 32;
/// Frames whose cameras are kept: how far back the sample ring's samples may come from.
pub const CAMERA_HISTORY: u32 = 128;
/// vec4 words per camera in `mem`.
pub const CAM_WORDS: u32 = 5;
/// Edge of the atmosphere table in texels.
pub const LUT_SIZE: u32 = 256;
/// Sample slots per region in the projection.
pub const BUCKET_SLOTS: u32 = 32;
/// Samples a region keeps after refinement.
pub const MAX_KEPT: u32 = 7;
/// The ray queue traces a pixel whose TAA holds enough samples one frame in this many, and
/// every frame a pixel with none (docs/RENDERING.md §3c: the paper's 4 lets resampled
/// light, darker than the truth where nearby walls occlude, make up three frames in four).
pub const QUEUE_PERIOD: u32 = 2;
/// `vec4<u32>` per sample in the ring.
pub const RING_VEC4: u32 = 3;
/// After a world change, the TAA and the ring use samples from before it for at most this
/// many more frames near it (or everywhere, after a change of the materials), so that light
/// that changed (an emitter removed or added) updates within them.
pub const EDIT_HISTORY_FRAMES: u32 = 8;
/// Word offset of the secondary rays' indirect arguments in the control words.
pub const CONTROL_TRACE_ARGS: u32 = 0;
/// Word offset of the projection's indirect arguments in the control words.
pub const CONTROL_PROJECT_ARGS: u32 = 4;
/// Control word: pixels queued this frame.
pub const CONTROL_QUEUED: u32 = 8;
/// Control word: where this frame's samples start in the ring.
pub const CONTROL_START: u32 = 9;
/// Control word: samples the ring holds.
pub const CONTROL_VALID: u32 = 10;
/// Control word: the ring's head, where the next sample goes.
pub const CONTROL_HEAD: u32 = 11;
/// Control word where the per-frame sample counts start.
pub const CONTROL_FRAMES: u32 = 16;
/// Control words at the start of `words`: indirect arguments and ring bookkeeping, then the
/// sample count of each of the last [`CAMERA_HISTORY`] frames.
pub const CONTROL_WORDS: u32 = CONTROL_FRAMES + CAMERA_HISTORY;

/// The constants the GI passes share with this module, by WGSL name.
pub const GI_CONSTANTS: [(&str, WgslValue); 17] = [
    ("TAA_SLOTS", WgslValue::U32(TAA_SLOTS)),
    ("CONTROL_WORDS", WgslValue::U32(CONTROL_WORDS)),
    ("CAMERA_HISTORY", WgslValue::U32(CAMERA_HISTORY)),
    ("LUT_SIZE", WgslValue::U32(LUT_SIZE)),
    ("BUCKET_SLOTS", WgslValue::U32(BUCKET_SLOTS)),
    ("MAX_KEPT", WgslValue::U32(MAX_KEPT)),
    ("QUEUE_PERIOD", WgslValue::U32(QUEUE_PERIOD)),
    ("RING_VEC4", WgslValue::U32(RING_VEC4)),
    ("EDIT_HISTORY_FRAMES", WgslValue::U32(EDIT_HISTORY_FRAMES)),
    ("CONTROL_TRACE_ARGS", WgslValue::U32(CONTROL_TRACE_ARGS)),
    ("CONTROL_PROJECT_ARGS", WgslValue::U32(CONTROL_PROJECT_ARGS)),
    ("CAM_WORDS", WgslValue::U32(CAM_WORDS)),
    ("CONTROL_QUEUED", WgslValue::U32(CONTROL_QUEUED)),
    ("CONTROL_START", WgslValue::U32(CONTROL_START)),
    ("CONTROL_VALID", WgslValue::U32(CONTROL_VALID)),
    ("CONTROL_HEAD", WgslValue::U32(CONTROL_HEAD)),
    ("CONTROL_FRAMES", WgslValue::U32(CONTROL_FRAMES)),
];

/// Bytes per pixel of the TAA.
pub(super) const TAA_PIXEL_BYTES: u64 = TAA_SLOTS as u64 * 8;
/// Ring samples per pixel.
pub(super) const RING_PER_PIXEL: u64 = 2;
/// Words of the entity pose table at the end of `words`: per TAA slot, four record words
/// per entity id (shaders/gi_entities.wgsl).
pub(super) const POSE_TABLE_WORDS: u64 = TAA_SLOTS as u64 * NO_ENTITY as u64 * 4;

/// Where each array of `mem` starts (vec4 words) for a frame's pixels and regions, with
/// the cameras first (at 0) and the ring last; and the layout of `words`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Layout {
    /// The atmosphere table.
    pub lut: u32,
    /// The first-hit surfaces.
    pub gbuf: u32,
    /// The first-hit materials.
    pub gmat: u32,
    /// The first-hit light.
    pub emitted: u32,
    /// The TAA's per-pixel sums and ranges (2 vec4 per pixel).
    pub taa_info: u32,
    /// The incoming light.
    pub illum: u32,
    /// The denoiser's intermediate.
    pub illum2: u32,
    /// The results.
    pub result: u32,
    /// The refined samples.
    pub refined: u32,
    /// The regions' statistics.
    pub region_info: u32,
    /// Each pixel's own secondary sample.
    pub own: u32,
    /// Where the sample ring, the last array, starts: the vec4 words of `mem` before it.
    pub ring_start: u64,
    /// Where the queued pixels start in `words`.
    pub queue_list: u32,
    /// Words of `words`.
    pub words: u64,
}

impl Layout {
    /// The layout for `p` pixels and `r` regions.
    pub fn new(p: u64, r: u64) -> Self {
        let mut at = u64::from(CAMERA_HISTORY * CAM_WORDS);
        // Places an array of `size` vec4 words after the ones before it.
        let mut next = |size: u64| {
            let start = at as u32;
            at += size;
            start
        };
        let (lut, gbuf, gmat, emitted) = (next(u64::from(LUT_SIZE * LUT_SIZE)), next(p), next(p), next(p));
        let (taa_info, illum, illum2, result) = (next(2 * p), next(p), next(p), next(p));
        let (refined, region_info, own) = (next(r * u64::from(MAX_KEPT) * 2), next(3 * r), next(p));
        let ring_start = at;
        let queue = u64::from(CONTROL_WORDS) + 2 * r;
        Layout {
            lut,
            gbuf,
            gmat,
            emitted,
            taa_info,
            illum,
            illum2,
            result,
            refined,
            region_info,
            own,
            ring_start,
            queue_list: queue as u32,
            words: queue + 64 * r + POSE_TABLE_WORDS,
        }
    }

    /// The bytes of each array of `mem` before the ring, named.
    pub fn arrays(&self) -> [(&'static str, u64); 12] {
        let vec4s = |from: u32, to: u32| u64::from(to - from) * 16;
        [
            ("cameras", vec4s(0, self.lut)),
            ("atmosphere table", vec4s(self.lut, self.gbuf)),
            ("first-hit surfaces", vec4s(self.gbuf, self.gmat)),
            ("first-hit materials", vec4s(self.gmat, self.emitted)),
            ("first-hit light", vec4s(self.emitted, self.taa_info)),
            ("TAA sums and ranges", vec4s(self.taa_info, self.illum)),
            ("incoming light", vec4s(self.illum, self.illum2)),
            ("denoiser intermediate", vec4s(self.illum2, self.result)),
            ("result", vec4s(self.result, self.refined)),
            ("refined samples", vec4s(self.refined, self.region_info)),
            ("region statistics", vec4s(self.region_info, self.own)),
            ("own samples", vec4s(self.own, self.ring_start as u32)),
        ]
    }
}

/// The memory of a history for one frame size: the layout, the split and the sizes.
#[derive(Clone, Copy, Debug)]
pub(super) struct Plan {
    /// Where each array starts.
    pub layout: Layout,
    /// How `mem` and `taa` are split across bindings.
    pub split: GiSplit,
    /// 8×8 regions of the frame.
    pub regions: u64,
    /// Samples the ring holds.
    pub ring: u64,
    /// Bytes of `mem`.
    pub mem_bytes: u64,
    /// Bytes of `taa`.
    pub taa_bytes: u64,
}

impl Plan {
    /// The memory of a `size` frame, in parts of `part` bytes.
    pub fn new(size: (u32, u32), part: u64) -> Self {
        let pixels = u64::from(size.0) * u64::from(size.1);
        let regions = u64::from(size.0.div_ceil(8)) * u64::from(size.1.div_ceil(8));
        let layout = Layout::new(pixels, regions);
        let ring = pixels * RING_PER_PIXEL;
        let mem_bytes = (layout.ring_start + ring * u64::from(RING_VEC4)) * 16;
        let taa_bytes = pixels * TAA_PIXEL_BYTES;
        Plan {
            layout,
            split: GiSplit {
                part_bytes_shift: part.trailing_zeros(),
                mem_parts: mem_bytes.div_ceil(part) as u32,
                taa_parts: taa_bytes.div_ceil(part) as u32,
            },
            regions,
            ring,
            mem_bytes,
            taa_bytes,
        }
    }
}

/// How a GI history's two large arrays (`mem` and `taa`, shaders/gi_common.wgsl) are split
/// across the bindings of group 1: `mem_parts` and `taa_parts` bindings of
/// `1 << part_bytes_shift` bytes each (the last one may be shorter).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct GiSplit {
    /// log2 of the bytes per binding.
    pub part_bytes_shift: u32,
    /// Bindings of `mem` (vec4 elements).
    pub mem_parts: u32,
    /// Bindings of `taa` (vec2 elements).
    pub taa_parts: u32,
}

impl GiSplit {
    /// The group-1 binding of the per-chunk change marks (`changes`, read-only).
    pub const CHANGES_BINDING: u32 = 5;

    /// Group-1 bindings before `mem`'s: the frame, light and GI state, `words`, `buckets`
    /// and `changes`.
    pub const FIRST_PART_BINDING: u32 = Self::CHANGES_BINDING + 1;

    /// Storage bindings of group 1 in all.
    pub fn bindings(&self) -> u32 {
        Self::FIRST_PART_BINDING + self.mem_parts + self.taa_parts
    }
}

/// The group-1 declarations of the GI history's split arrays: `mem` (vec4, accessors
/// `mem_get`/`mem_set`) and `taa` (vec2, `taa_get`/`taa_set`), after the bindings
/// shaders/gi_common.wgsl declares.
pub fn gi_parts(split: &GiSplit) -> String {
    let mut s = String::from("// Generated by naadf-client (gi/memory.rs): the GI history's split arrays.\n");
    let arrays = [
        ("mem", "vec4<u32>", split.mem_parts, 4, "mem_get", "mem_set"),
        ("taa", "vec2<u32>", split.taa_parts, 3, "taa_get", "taa_set"),
    ];
    let mut binding = GiSplit::FIRST_PART_BINDING;
    for (name, element, parts, element_shift, read, write) in arrays {
        declare_parts(
            &mut s,
            &PartedArray {
                group: 1,
                first_binding: binding,
                name,
                element,
                parts,
                shift: split.part_bytes_shift - element_shift,
                read,
                write: Some(write),
            },
        );
        binding += parts;
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gi_arrays_follow_the_pass_bindings_and_write_through_their_accessors() {
        let g = gi_parts(&GiSplit {
            part_bytes_shift: 16,
            mem_parts: 2,
            taa_parts: 1,
        });
        assert!(g.contains("@group(1) @binding(6) var<storage, read_write> mem_0: array<vec4<u32>>;"));
        assert!(g.contains("@group(1) @binding(7) var<storage, read_write> mem_1: array<vec4<u32>>;"));
        assert!(g.contains("@group(1) @binding(8) var<storage, read_write> taa_0: array<vec2<u32>>;"));
        // 64 KiB parts hold 4096 vec4s.
        assert!(g.contains("fn mem_set(i: u32, v: vec4<u32>) {\n    let j = i & 4095u;\n    switch i >> 12u {"));
        assert!(g.contains("case 0u: { mem_0[j] = v; }"));
        assert!(g.contains("default: { return mem_1[j]; }"));
        assert!(g.contains("fn taa_set(i: u32, v: vec2<u32>) { taa_0[i] = v; }"));
    }

    /// The arrays follow one another without gaps, from the cameras to the ring.
    #[test]
    fn the_arrays_tile_mem_before_the_ring() {
        let l = Layout::new(1000, 20);
        let total: u64 = l.arrays().iter().map(|&(_, bytes)| bytes).sum();
        assert_eq!(total, l.ring_start * 16);
        assert_eq!(l.arrays()[0].1, u64::from(CAMERA_HISTORY * CAM_WORDS) * 16);
        assert_eq!(u64::from(l.queue_list), u64::from(CONTROL_WORDS) + 40);
    }
}

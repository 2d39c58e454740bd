//! The WGSL sources of `shaders/` and how they are put together.
//!
//! WGSL has no includes, so a pass is the concatenation of the shared files, one world
//! loop and the pass's own file, after a generated [`prelude`] that declares what the
//! shaders share with the Rust code:
//! - the world's parameters: `struct WorldInfo`, generated from the Rust [`WorldInfo`]
//!   ([`WgslStruct::wgsl`]), and its read-only storage binding `world_info`;
//! - the [`CONSTANTS`] (cell layout, material kinds, entity layout, render modes), whose
//!   values are the Rust constants themselves;
//! - the world's storage bindings and their accessors: a buffer larger than the adapter's
//!   storage-binding limit is split across several bindings ([`Split`]); its accessor
//!   function (`voxel_word(i)`, …) hides the split from the shaders.
//!
//! The files in `shaders/` declare none of these: WGSL rejects a second declaration of a
//! name, so a hand-written copy fails the naga test of every pass.

use super::gi::{self, GiPass};
use super::params::{FrameInfo, GiInfo, LightInfo, WgslStruct, WorldInfo};
use super::render::Mode;
use naadf_world::cell;
use naadf_world::entity::{self, MAX_ENTITY_ID, pack};
use naadf_world::material::MaterialKind;
use std::fmt::Write;

/// `shaders/world.wgsl`: cell decoding, materials.
pub const WORLD: &str = include_str!("../../../shaders/world.wgsl");
/// `shaders/ray.wgsl`: rays with the int/frac origin split and the event model.
pub const RAY: &str = include_str!("../../../shaders/ray.wgsl");
/// `shaders/trace.wgsl`: a full trace, world loop then entities.
pub const TRACE: &str = include_str!("../../../shaders/trace.wgsl");
/// `shaders/traverse.wgsl`: the hierarchical world loop (`naadf` and `nodf`).
pub const TRAVERSE: &str = include_str!("../../../shaders/traverse.wgsl");
/// `shaders/grid.wgsl`: the dense-grid world loop (`grid`).
pub const GRID: &str = include_str!("../../../shaders/grid.wgsl");
/// `shaders/tree.wgsl`: the world loop over a tree of the paper's comparison (SVO, SVDAG,
/// hybrid format).
pub const TREE: &str = include_str!("../../../shaders/tree.wgsl");
/// `shaders/svo.wgsl`: what an SVO node holds at a cell (`tree_step`).
pub const SVO: &str = include_str!("../../../shaders/svo.wgsl");
/// `shaders/svdag.wgsl`: what an SVDAG node holds at a cell (`tree_step`).
pub const SVDAG: &str = include_str!("../../../shaders/svdag.wgsl");
/// `shaders/hybrid.wgsl`: what a hybrid format's raw grid and DAG nodes hold at a cell.
pub const HYBRID: &str = include_str!("../../../shaders/hybrid.wgsl");
/// `shaders/rays.wgsl`: the ray-list pass.
pub const RAYS: &str = include_str!("../../../shaders/rays.wgsl");
/// `shaders/render.wgsl`: the frame pass.
pub const RENDER: &str = include_str!("../../../shaders/render.wgsl");
/// `shaders/sample.wgsl`: per-sample random streams and jittered camera rays.
pub const SAMPLE: &str = include_str!("../../../shaders/sample.wgsl");
/// `shaders/light.wgsl`: the light model of the lit passes (sky, sun, scattering, paths).
pub const LIGHT: &str = include_str!("../../../shaders/light.wgsl");
/// `shaders/pathtrace.wgsl`: path-traced samples (progressive sums, or one per frame).
pub const PATHTRACE: &str = include_str!("../../../shaders/pathtrace.wgsl");
/// `shaders/taa.wgsl`: the baseline's temporal accumulation.
pub const TAA: &str = include_str!("../../../shaders/taa.wgsl");
/// `shaders/first_hit.wgsl`: the first-hit chain through mirrors (`albedo` and `gi`).
pub const FIRST_HIT: &str = include_str!("../../../shaders/first_hit.wgsl");
/// `shaders/gi_common.wgsl`: the GI passes' bindings, encodings and atmosphere table.
pub const GI_COMMON: &str = include_str!("../../../shaders/gi_common.wgsl");
/// `shaders/gi_primary.wgsl`: the GI first hit, TAA gather and TAA merge.
pub const GI_PRIMARY: &str = include_str!("../../../shaders/gi_primary.wgsl");
/// `shaders/gi_entities.wgsl`: the entities' poses per TAA slot.
pub const GI_ENTITIES: &str = include_str!("../../../shaders/gi_entities.wgsl");
/// `shaders/gi_samples.wgsl`: the ray queue, secondary rays, projection and refinement.
pub const GI_SAMPLES: &str = include_str!("../../../shaders/gi_samples.wgsl");
/// `shaders/gi_resample.wgsl`: spatial resampling and the denoiser.
pub const GI_RESAMPLE: &str = include_str!("../../../shaders/gi_resample.wgsl");

/// The logical storage buffers of group 0, in binding order, with their accessor names.
pub const BUFFERS: [(&str, &str); 8] = [
    ("chunks", "chunk_word"),
    ("chunk_entities", "chunk_entity_word"),
    ("blocks", "block_word"),
    ("voxels", "voxel_word"),
    ("materials", "material_word"),
    ("entity_types", "entity_type_word"),
    ("entity_instances", "instance_word"),
    // The structure a comparison traversal walks instead of the world's hierarchy: the
    // dense grid, an SVO, an SVDAG or a hybrid format (whichever was uploaded last).
    ("structure", "structure_word"),
];

/// The entity id the shaders report for a hit on the world: one past the largest id an
/// entity may have ([`MAX_ENTITY_ID`]).
pub const NO_ENTITY: u32 = MAX_ENTITY_ID + 1;

/// The `u32` constants of the prelude by WGSL name, each the value of its Rust counterpart:
/// the constant of the same name, or an enum's code.
pub const CONSTANTS: [(&str, u32); 32] = [
    // Cells and voxels (naadf_world::cell).
    ("STATE_SHIFT", cell::STATE_SHIFT),
    ("STATE_EMPTY", cell::STATE_EMPTY),
    ("STATE_FULL", cell::STATE_FULL),
    ("STATE_MIXED", cell::STATE_MIXED),
    ("PAYLOAD", cell::PAYLOAD),
    ("MAX_MATERIAL", cell::MAX_MATERIAL as u32),
    ("VOXEL_SOLID", cell::VOXEL_SOLID as u32),
    ("CHUNK_FIELD_BITS", cell::CHUNK_FIELD_BITS),
    ("CELL_FIELD_BITS", cell::CELL_FIELD_BITS),
    // Material kinds (naadf_world::material::MaterialKind).
    ("KIND_DIFFUSE", MaterialKind::Diffuse as u32),
    ("KIND_EMISSIVE", MaterialKind::Emissive as u32),
    ("KIND_METAL", MaterialKind::Metal as u32),
    ("KIND_MIRROR", MaterialKind::Mirror as u32),
    // Entity types and chunk-instance records (naadf_world::entity).
    ("ENTITY_SOLID", entity::ENTITY_SOLID),
    ("TYPE_ALIGN", entity::TYPE_ALIGN as u32),
    ("RECORD_WORDS", pack::RECORD_WORDS as u32),
    ("NO_ENTITY", NO_ENTITY),
    // Frame modes ([`Mode`]).
    ("MODE_ALBEDO", Mode::Albedo.code()),
    ("MODE_MATERIAL", Mode::Material.code()),
    ("MODE_NORMAL", Mode::Normal.code()),
    ("MODE_STEPS", Mode::Steps.code()),
    // The GI pipeline (gi.rs).
    ("TAA_SLOTS", gi::TAA_SLOTS),
    ("CONTROL_WORDS", gi::CONTROL_WORDS),
    ("CAMERA_HISTORY", gi::CAMERA_HISTORY),
    ("LUT_SIZE", gi::LUT_SIZE),
    ("BUCKET_SLOTS", gi::BUCKET_SLOTS),
    ("MAX_KEPT", gi::MAX_KEPT),
    ("QUEUE_PERIOD", gi::QUEUE_PERIOD),
    ("RING_VEC4", gi::RING_VEC4),
    ("EDIT_HISTORY_FRAMES", gi::EDIT_HISTORY_FRAMES),
    ("CONTROL_TRACE_ARGS", gi::CONTROL_TRACE_ARGS),
    ("CONTROL_PROJECT_ARGS", gi::CONTROL_PROJECT_ARGS),
];

/// How the buffers of group 0 are split: each logical buffer has `parts[i]` bindings of
/// `1 << part_shift` words each (the last one may be shorter).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Split {
    /// log2 of the words per binding.
    pub part_shift: u32,
    /// Bindings per logical buffer, in [`BUFFERS`] order.
    pub parts: [u32; 8],
}

impl Split {
    /// Bindings of the world's buffer parts in group 0 (bindings 1, 2, …; `world_info` is
    /// binding 0).
    pub fn bindings(&self) -> u32 {
        self.parts.iter().sum()
    }

    /// Storage bindings of group 0 in all: `world_info` and the buffer parts.
    pub fn storage_bindings(&self) -> u32 {
        1 + self.bindings()
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
    /// Each array in one binding.
    pub const WHOLE: GiSplit = GiSplit {
        part_bytes_shift: 27,
        mem_parts: 1,
        taa_parts: 1,
    };

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

/// Which world loop a pass uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Loop {
    /// The hierarchy (`naadf`/`nodf`, chosen by the `USE_AADF` override).
    Hierarchy,
    /// The dense grid.
    Grid,
    /// The SVO of the paper's comparison.
    Svo,
    /// The SVDAG of the paper's comparison.
    Svdag,
    /// A hybrid format of the paper's comparison.
    Hybrid,
}

impl Loop {
    /// Every world loop.
    pub const ALL: [Loop; 5] = [Loop::Hierarchy, Loop::Grid, Loop::Svo, Loop::Svdag, Loop::Hybrid];

    /// Its files, in order.
    fn files(self) -> &'static [&'static str] {
        match self {
            Loop::Hierarchy => &[TRAVERSE],
            Loop::Grid => &[GRID],
            Loop::Svo => &[TREE, SVO],
            Loop::Svdag => &[TREE, SVDAG],
            Loop::Hybrid => &[TREE, HYBRID],
        }
    }
}

/// A pass's own file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Pass {
    /// [`RAYS`], entry point `trace_rays`.
    Rays,
    /// [`RENDER`], entry point `render`.
    Render,
    /// [`SAMPLE`], [`LIGHT`] and [`PATHTRACE`], entry point `path_trace`.
    PathTrace,
    /// The same files, entry point `path_sample`.
    PathSample,
    /// [`SAMPLE`] and [`TAA`], entry point `taa_resolve`.
    Taa,
    /// A pass of the GI pipeline: [`SAMPLE`], [`LIGHT`], [`FIRST_HIT`] and the `gi_*`
    /// files, entry point [`GiPass::entry`], with the history's arrays split as the
    /// [`GiSplit`] says.
    Gi(GiPass, GiSplit),
}

impl Pass {
    /// Every pass.
    pub const ALL: [Pass; 20] = [
        Pass::Rays,
        Pass::Render,
        Pass::PathTrace,
        Pass::PathSample,
        Pass::Taa,
        Pass::Gi(GiPass::ALL[0], GiSplit::WHOLE),
        Pass::Gi(GiPass::ALL[1], GiSplit::WHOLE),
        Pass::Gi(GiPass::ALL[2], GiSplit::WHOLE),
        Pass::Gi(GiPass::ALL[3], GiSplit::WHOLE),
        Pass::Gi(GiPass::ALL[4], GiSplit::WHOLE),
        Pass::Gi(GiPass::ALL[5], GiSplit::WHOLE),
        Pass::Gi(GiPass::ALL[6], GiSplit::WHOLE),
        Pass::Gi(GiPass::ALL[7], GiSplit::WHOLE),
        Pass::Gi(GiPass::ALL[8], GiSplit::WHOLE),
        Pass::Gi(GiPass::ALL[9], GiSplit::WHOLE),
        Pass::Gi(GiPass::ALL[10], GiSplit::WHOLE),
        Pass::Gi(GiPass::ALL[11], GiSplit::WHOLE),
        Pass::Gi(GiPass::ALL[12], GiSplit::WHOLE),
        Pass::Gi(GiPass::ALL[13], GiSplit::WHOLE),
        Pass::Gi(GiPass::ALL[14], GiSplit::WHOLE),
    ];

    /// The entry point.
    pub fn entry(self) -> &'static str {
        match self {
            Pass::Rays => "trace_rays",
            Pass::Render => "render",
            Pass::PathTrace => "path_trace",
            Pass::PathSample => "path_sample",
            Pass::Taa => "taa_resolve",
            Pass::Gi(p, _) => p.entry(),
        }
    }

    /// The pass's own files, in order, after the shared ones.
    fn files(self) -> &'static [&'static str] {
        match self {
            Pass::Rays => &[RAYS],
            Pass::Render => &[FIRST_HIT, RENDER],
            Pass::PathTrace | Pass::PathSample => &[SAMPLE, LIGHT, PATHTRACE],
            Pass::Taa => &[SAMPLE, TAA],
            Pass::Gi(..) => &[
                SAMPLE,
                LIGHT,
                FIRST_HIT,
                GI_COMMON,
                GI_ENTITIES,
                GI_PRIMARY,
                GI_SAMPLES,
                GI_RESAMPLE,
            ],
        }
    }
}

/// The prelude of every pass: the world's parameters ([`WorldInfo`]) and their binding, the
/// lit passes' parameter structs ([`FrameInfo`], [`LightInfo`], [`GiInfo`]; each pass binds
/// what it uses), the [`CONSTANTS`], and the group-0 storage declarations and accessors for
/// `split`.
pub fn prelude(split: &Split) -> String {
    let mut s = String::from(
        "// Generated by naadf-client (shaders.rs): the world parameters, the constants shared with the\n\
         // Rust code, the world's storage bindings.\n",
    );
    s.push_str(&WorldInfo::wgsl());
    s.push_str("@group(0) @binding(0) var<storage, read> world_info: WorldInfo;\n");
    s.push_str(&FrameInfo::wgsl());
    s.push_str(&LightInfo::wgsl());
    s.push_str(&GiInfo::wgsl());
    for (name, value) in CONSTANTS {
        let _ = writeln!(s, "const {name}: u32 = {value}u;");
    }
    let mut binding = 1;
    for (&(name, accessor), &parts) in BUFFERS.iter().zip(&split.parts) {
        declare_parts(
            &mut s,
            &PartedArray {
                group: 0,
                first_binding: binding,
                name,
                element: "u32",
                parts,
                shift: split.part_shift,
                read: accessor,
                write: None,
            },
        );
        binding += parts;
    }
    s
}

/// A logical storage array declared as `parts` bindings `{name}_0`, `{name}_1`, … of
/// `1 << shift` elements each, with accessor functions that hide the split.
struct PartedArray<'a> {
    group: u32,
    first_binding: u32,
    name: &'a str,
    /// The WGSL element type.
    element: &'a str,
    parts: u32,
    shift: u32,
    /// The reader `fn read(i: u32) -> element`.
    read: &'a str,
    /// The writer `fn write(i: u32, v: element)`, for a read-write array.
    write: Option<&'a str>,
}

/// Declares `a`'s bindings and accessors. With one part the accessors index it directly;
/// with more, they switch on the part.
fn declare_parts(s: &mut String, a: &PartedArray) {
    let (name, element) = (a.name, a.element);
    let access = if a.write.is_some() { "read_write" } else { "read" };
    for p in 0..a.parts {
        let _ = writeln!(
            s,
            "@group({}) @binding({}) var<storage, {access}> {name}_{p}: array<{element}>;",
            a.group,
            a.first_binding + p
        );
    }
    // Each accessor's signature and body (given the element it reads or writes).
    type Body = fn(&str) -> String;
    let mut accessors: Vec<(String, Body)> = vec![(format!("fn {}(i: u32) -> {element}", a.read), |e| {
        format!("return {e};")
    })];
    if let Some(w) = a.write {
        accessors.push((format!("fn {w}(i: u32, v: {element})"), |e| format!("{e} = v;")));
    }
    for (signature, body) in accessors {
        let statement = |part: u32, index: &str| body(&format!("{name}_{part}[{index}]"));
        if a.parts == 1 {
            let _ = writeln!(s, "{signature} {{ {} }}", statement(0, "i"));
            continue;
        }
        let mask = (1u64 << a.shift) - 1;
        let _ = writeln!(
            s,
            "{signature} {{\n    let j = i & {mask}u;\n    switch i >> {}u {{",
            a.shift
        );
        for p in 0..a.parts - 1 {
            let _ = writeln!(s, "        case {p}u: {{ {} }}", statement(p, "j"));
        }
        let _ = writeln!(s, "        default: {{ {} }}\n    }}\n}}", statement(a.parts - 1, "j"));
    }
}

/// The group-1 declarations of the GI history's split arrays: `mem` (vec4, accessors
/// `mem_get`/`mem_set`) and `taa` (vec2, `taa_get`/`taa_set`), after the bindings
/// shaders/gi_common.wgsl declares.
fn gi_parts(split: &GiSplit) -> String {
    let mut s = String::from("// Generated by naadf-client (shaders.rs): the GI history's split arrays.\n");
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

/// The full WGSL of `pass` with world loop `world_loop` over buffers split as `split`.
pub fn source(pass: Pass, world_loop: Loop, split: &Split) -> String {
    let prelude = prelude(split);
    let mut files = vec![prelude.as_str(), WORLD, RAY, TRACE];
    files.extend(world_loop.files());
    files.extend(pass.files());
    let gi = match pass {
        Pass::Gi(_, gi_split) => gi_parts(&gi_split),
        _ => String::new(),
    };
    files.push(&gi);
    files.join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn validate(src: &str) -> Result<(), String> {
        let module = naga::front::wgsl::parse_str(src).map_err(|e| e.emit_to_string(src))?;
        // The capabilities wgpu grants on every backend the client targets.
        let caps = naga::valid::Capabilities::SHADER_FLOAT16_IN_FLOAT32;
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), caps)
            .validate(&module)
            .map_err(|e| e.emit_to_string(src))?;
        Ok(())
    }

    fn parse(src: &str) -> naga::Module {
        naga::front::wgsl::parse_str(src).unwrap_or_else(|e| panic!("{}", e.emit_to_string(src)))
    }

    /// Every buffer in one binding.
    fn whole() -> Split {
        Split {
            part_shift: 25,
            parts: [1; 8],
        }
    }

    #[test]
    fn every_pass_validates_with_naga_for_whole_and_split_buffers() {
        let split = Split {
            part_shift: 14,
            parts: [2, 1, 3, 4, 1, 1, 2, 5],
        };
        let gi_split = GiSplit {
            part_bytes_shift: 16,
            mem_parts: 3,
            taa_parts: 2,
        };
        for s in [whole(), split] {
            for pass in every_pass(gi_split) {
                for lp in Loop::ALL {
                    if let Err(e) = validate(&source(pass, lp, &s)) {
                        panic!("{pass:?} with {lp:?} over {s:?}:\n{e}");
                    }
                }
            }
        }
    }

    /// Every pass: the ones of [`Pass::ALL`], then the GI passes over `gi_split`.
    fn every_pass(gi_split: GiSplit) -> impl Iterator<Item = Pass> {
        Pass::ALL.into_iter().chain(GiPass::ALL.map(|p| Pass::Gi(p, gi_split)))
    }

    /// Lavapipe re-optimises a shader for the values of its uniform buffers at every
    /// dispatch (see `Gpu::params`), so no pass may declare one.
    #[test]
    fn no_pass_declares_a_uniform_buffer() {
        let gi_split = GiSplit {
            part_bytes_shift: 27,
            mem_parts: 1,
            taa_parts: 1,
        };
        for pass in every_pass(gi_split) {
            for lp in Loop::ALL {
                let module = parse(&source(pass, lp, &whole()));
                let uniforms: Vec<_> = module
                    .global_variables
                    .iter()
                    .filter(|(_, v)| v.space == naga::AddressSpace::Uniform)
                    .map(|(_, v)| v.name.clone().unwrap_or_default())
                    .collect();
                assert!(
                    uniforms.is_empty(),
                    "{pass:?} with {lp:?} declares uniform buffers {uniforms:?}"
                );
            }
        }
    }

    /// Checks that the prelude lays `T` out at the Rust offsets and size.
    fn assert_rust_layout<T: WgslStruct>(module: &naga::Module) {
        let (members, span) = module
            .types
            .iter()
            .find_map(|(_, t)| match &t.inner {
                naga::TypeInner::Struct { members, span } if t.name.as_deref() == Some(T::NAME) => {
                    Some((members, *span))
                }
                _ => None,
            })
            .unwrap_or_else(|| panic!("the prelude declares {}", T::NAME));
        let wgsl: Vec<(&str, usize)> = members
            .iter()
            .map(|m| (m.name.as_deref().unwrap_or_default(), m.offset as usize))
            .collect();
        let rust: Vec<(&str, usize)> = T::MEMBERS.iter().map(|m| (m.name, m.offset)).collect();
        assert_eq!(wgsl, rust, "{}", T::NAME);
        assert_eq!(span as usize, size_of::<T>(), "{}", T::NAME);
    }

    #[test]
    fn the_prelude_lays_its_parameters_out_at_the_rust_offsets() {
        let module = parse(&prelude(&whole()));
        assert_rust_layout::<WorldInfo>(&module);
        assert_rust_layout::<FrameInfo>(&module);
        assert_rust_layout::<LightInfo>(&module);
        assert_rust_layout::<GiInfo>(&module);
    }

    #[test]
    fn the_prelude_constants_have_their_rust_values() {
        let module = parse(&prelude(&whole()));
        let wgsl: Vec<(&str, u32)> = module
            .constants
            .iter()
            .map(|(_, c)| {
                let name = c.name.as_deref().unwrap_or_default();
                match module.global_expressions[c.init] {
                    naga::Expression::Literal(naga::Literal::U32(v)) => (name, v),
                    ref e => panic!("{name} is not a u32 literal: {e:?}"),
                }
            })
            .collect();
        assert_eq!(wgsl, CONSTANTS);
    }

    #[test]
    fn split_accessors_pick_the_part() {
        let p = prelude(&Split {
            part_shift: 14,
            parts: [1, 1, 1, 3, 1, 1, 1, 1],
        });
        assert!(p.contains("fn voxel_word(i: u32) -> u32 {\n    let j = i & 16383u;\n    switch i >> 14u {"));
        assert!(p.contains("case 1u: { return voxels_1[j]; }"));
        assert!(p.contains("default: { return voxels_2[j]; }"));
        assert!(p.contains("fn chunk_word(i: u32) -> u32 { return chunks_0[i]; }"));
    }

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
}

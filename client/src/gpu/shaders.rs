//! The WGSL library of `shaders/` and how a pass's source is put together.
//!
//! WGSL has no includes, so a pass is the concatenation of a generated [`prelude`], the
//! shared files, one world loop ([`Loop`]) and the pass's own files, followed by what the
//! pass generates for itself ([`PassSource`]). The prelude declares what every pass shares
//! with the Rust code:
//! - the parameter structs, generated from their Rust definitions ([`WgslStruct::wgsl`]),
//!   and the world's read-only storage binding `world_info`;
//! - the [`CONSTANTS`] (cell layout, material kinds, entity layout, the light model),
//!   whose values are the Rust items themselves;
//! - the world's storage bindings and their accessors: a buffer larger than the adapter's
//!   storage-binding limit is split across several bindings ([`Split`]); its accessor
//!   function (`voxel_word(i)`, …) hides the split from the shaders.
//!
//! A pass adds its own constants ([`constants`]) and split arrays ([`declare_parts`]) the
//! same way, in its own module: nothing here knows the passes. The files in `shaders/`
//! declare none of these names: WGSL rejects a second declaration of a name, so a
//! hand-written copy fails the naga test of every pass.

use super::bindings::{BUFFERS, Split};
use super::params::{FrameInfo, GiInfo, LightInfo, WgslStruct, WorldInfo};
use crate::light::{SURFACE_OFFSET, scatter, sky};
use naadf_world::cell;
use naadf_world::entity::{self, MAX_ENTITY_ID, bvh, pack};
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
/// `shaders/sample.wgsl`: per-sample random streams and jittered camera rays (the lit
/// passes).
pub const SAMPLE: &str = include_str!("../../../shaders/sample.wgsl");
/// `shaders/light.wgsl`: the light model of the lit passes (sky, sun, scattering, paths).
pub const LIGHT: &str = include_str!("../../../shaders/light.wgsl");
/// `shaders/no_tier.wgsl`: no lighting tier, for the passes that trace paths as the light
/// model does (after [`LIGHT`]).
pub const NO_TIER: &str = include_str!("../../../shaders/no_tier.wgsl");
/// `shaders/first_hit.wgsl`: the first-hit chain through mirrors (`albedo` and `gi`).
pub const FIRST_HIT: &str = include_str!("../../../shaders/first_hit.wgsl");

/// The entity id the shaders report for a hit on the world: one past the largest id an
/// entity may have ([`MAX_ENTITY_ID`]).
pub const NO_ENTITY: u32 = MAX_ENTITY_ID + 1;

/// The value of a constant shared with WGSL, in a WGSL type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum WgslValue {
    /// A `u32`.
    U32(u32),
    /// An `i32`.
    I32(i32),
    /// An `f32`.
    F32(f32),
    /// A `vec3<f32>`.
    Vec3(f32, f32, f32),
}

impl WgslValue {
    /// A `vec3<f32>` of the three values.
    pub const fn vec3(v: [f32; 3]) -> Self {
        WgslValue::Vec3(v[0], v[1], v[2])
    }

    /// The WGSL declaration of constant `name` with this value. An `f32` is written as the
    /// shortest decimal that reads back to the same bits, with the `f` suffix, so that
    /// WGSL rounds it to `f32` once, as Rust did.
    pub fn declare(self, name: &str) -> String {
        let f = |v: f32| format!("{v:?}f");
        match self {
            WgslValue::U32(v) => format!("const {name}: u32 = {v}u;\n"),
            WgslValue::I32(v) => format!("const {name}: i32 = {v}i;\n"),
            WgslValue::F32(v) => format!("const {name}: f32 = {};\n", f(v)),
            WgslValue::Vec3(x, y, z) => format!("const {name}: vec3<f32> = vec3<f32>({}, {}, {});\n", f(x), f(y), f(z)),
        }
    }
}

/// The declarations of `list`'s constants, in order.
pub fn constants(list: &[(&str, WgslValue)]) -> String {
    list.iter().map(|&(name, value)| value.declare(name)).collect()
}

/// The constants of the prelude by WGSL name, each the value of its Rust counterpart: the
/// constant of the same name, or an enum's code.
pub const CONSTANTS: [(&str, WgslValue); 39] = [
    // Cells and voxels (naadf_world::cell).
    ("STATE_SHIFT", WgslValue::U32(cell::STATE_SHIFT)),
    ("STATE_EMPTY", WgslValue::U32(cell::STATE_EMPTY)),
    ("STATE_FULL", WgslValue::U32(cell::STATE_FULL)),
    ("STATE_MIXED", WgslValue::U32(cell::STATE_MIXED)),
    ("PAYLOAD", WgslValue::U32(cell::PAYLOAD)),
    ("MAX_MATERIAL", WgslValue::U32(cell::MAX_MATERIAL as u32)),
    ("VOXEL_SOLID", WgslValue::U32(cell::VOXEL_SOLID as u32)),
    ("CHUNK_FIELD_BITS", WgslValue::U32(cell::CHUNK_FIELD_BITS)),
    ("CELL_FIELD_BITS", WgslValue::U32(cell::CELL_FIELD_BITS)),
    // Material kinds (naadf_world::material::MaterialKind).
    ("KIND_DIFFUSE", WgslValue::U32(MaterialKind::Diffuse as u32)),
    ("KIND_EMISSIVE", WgslValue::U32(MaterialKind::Emissive as u32)),
    ("KIND_METAL", WgslValue::U32(MaterialKind::Metal as u32)),
    ("KIND_MIRROR", WgslValue::U32(MaterialKind::Mirror as u32)),
    // Entity types and instance records (naadf_world::entity).
    ("ENTITY_SOLID", WgslValue::U32(entity::ENTITY_SOLID)),
    ("TYPE_ALIGN", WgslValue::U32(entity::TYPE_ALIGN as u32)),
    ("RECORD_WORDS", WgslValue::U32(pack::RECORD_WORDS as u32)),
    ("NO_ENTITY", WgslValue::U32(NO_ENTITY)),
    // The instance hierarchy (naadf_world::entity::bvh).
    ("NODE_WORDS", WgslValue::U32(bvh::NODE_WORDS as u32)),
    ("BVH_STACK", WgslValue::U32(bvh::STACK as u32)),
    ("BVH_LEAF", WgslValue::U32(bvh::LEAF)),
    ("BVH_NONE", WgslValue::U32(bvh::NO_CHILD)),
    ("BVH_FAR", WgslValue::F32(bvh::FAR)),
    // The light model (crate::light): how far a scattered ray starts off its surface, the
    // scattering's smallest roughness, and the physical sky (light/sky.rs).
    ("SURFACE_OFFSET", WgslValue::F32(SURFACE_OFFSET as f32)),
    ("MIN_ALPHA", WgslValue::F32(scatter::MIN_ALPHA as f32)),
    ("PI", WgslValue::F32(std::f32::consts::PI)),
    ("PLANET_RADIUS", WgslValue::F32(sky::PLANET_RADIUS)),
    ("ATMOSPHERE_HEIGHT", WgslValue::F32(sky::ATMOSPHERE_HEIGHT)),
    ("EYE_HEIGHT", WgslValue::F32(sky::EYE_HEIGHT)),
    ("VIEW_STEPS", WgslValue::U32(sky::VIEW_STEPS)),
    ("LIGHT_STEPS", WgslValue::U32(sky::LIGHT_STEPS)),
    ("RAYLEIGH", WgslValue::vec3(sky::RAYLEIGH)),
    ("RAYLEIGH_SCALE", WgslValue::F32(sky::RAYLEIGH_SCALE)),
    ("MIE_SCATTER", WgslValue::F32(sky::MIE_SCATTER)),
    ("MIE_EXTINCTION", WgslValue::F32(sky::MIE_EXTINCTION)),
    ("MIE_SCALE", WgslValue::F32(sky::MIE_SCALE)),
    ("MIE_G", WgslValue::F32(sky::MIE_G)),
    ("OZONE", WgslValue::vec3(sky::OZONE)),
    ("OZONE_CENTRE", WgslValue::F32(sky::OZONE_CENTRE)),
    ("OZONE_HALF_WIDTH", WgslValue::F32(sky::OZONE_HALF_WIDTH)),
];

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

/// A pass's own part of its WGSL: the entry point, the files that follow the shared ones,
/// and what the pass generates for itself (its constants, its split arrays). Each pass's
/// module makes its own, so adding a pass touches nothing here.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PassSource {
    /// The entry point.
    pub entry: &'static str,
    /// The pass's files, in order, after the shared ones and the world loop.
    pub files: &'static [&'static str],
    /// Generated declarations, appended last (WGSL needs no declaration before use).
    pub generated: String,
}

/// How a pass reaches the world's buffers (group 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WorldBindings<'a> {
    /// The native client: `world_info` a read-only storage struct at binding 0, and each
    /// logical buffer in the storage bindings `split` gives it, from binding 1 on.
    Split(&'a Split),
    /// The browser page, which must fit WebGPU's default limits (8 storage buffers per
    /// stage): `world_info` and `world_offsets` (each buffer's first word) as uniforms at
    /// bindings 0 and 1, and every buffer in the one storage array `world` at binding 2.
    Single,
}

/// The prelude of every pass: the world's parameters ([`WorldInfo`]) and their binding, the
/// lit passes' parameter structs ([`FrameInfo`], [`LightInfo`], [`GiInfo`]; each pass binds
/// what it uses), the [`CONSTANTS`], and the group-0 storage declarations and accessors for
/// `world`.
pub fn prelude(world: WorldBindings) -> String {
    let mut s = String::from(
        "// Generated by naadf-client (shaders.rs): the world parameters, the constants shared with the\n\
         // Rust code, the world's storage bindings.\n",
    );
    s.push_str(&WorldInfo::wgsl());
    match world {
        WorldBindings::Split(_) => s.push_str("@group(0) @binding(0) var<storage, read> world_info: WorldInfo;\n"),
        WorldBindings::Single => s.push_str("@group(0) @binding(0) var<uniform> world_info: WorldInfo;\n"),
    }
    s.push_str(&FrameInfo::wgsl());
    s.push_str(&LightInfo::wgsl());
    s.push_str(&GiInfo::wgsl());
    s.push_str(&constants(&CONSTANTS));
    match world {
        WorldBindings::Split(split) => {
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
        }
        WorldBindings::Single => {
            s.push_str("// The first word of each buffer in `world`.\nstruct WorldOffsets {\n");
            for (name, _) in BUFFERS {
                let _ = writeln!(s, "    {name}: u32,");
            }
            s.push_str(
                "}\n@group(0) @binding(1) var<uniform> world_offsets: WorldOffsets;\n\
                 @group(0) @binding(2) var<storage, read> world: array<u32>;\n",
            );
            for (name, accessor) in BUFFERS {
                let _ = writeln!(
                    s,
                    "fn {accessor}(i: u32) -> u32 {{ return world[world_offsets.{name} + i]; }}"
                );
            }
        }
    }
    s
}

/// A logical storage array declared as `parts` bindings `{name}_0`, `{name}_1`, … of
/// `1 << shift` elements each, with accessor functions that hide the split.
pub struct PartedArray<'a> {
    /// The bind group.
    pub group: u32,
    /// The binding of part 0; the others follow.
    pub first_binding: u32,
    /// The array's name; its parts are `{name}_0`, `{name}_1`, ….
    pub name: &'a str,
    /// The WGSL element type.
    pub element: &'a str,
    /// Bindings.
    pub parts: u32,
    /// log2 of the elements per part.
    pub shift: u32,
    /// The reader `fn read(i: u32) -> element`.
    pub read: &'a str,
    /// The writer `fn write(i: u32, v: element)`, for a read-write array.
    pub write: Option<&'a str>,
}

/// Declares `a`'s bindings and accessors. With one part the accessors index it directly;
/// with more, they switch on the part.
pub fn declare_parts(s: &mut String, a: &PartedArray) {
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

/// The full WGSL of `pass` with world loop `world_loop` over the world's buffers bound as
/// `world`. With [`WorldBindings::Single`] the pass's own parameter structs (its read-only
/// storage structs, such as `view: View`) become uniforms too, as WebGPU's default limits
/// need.
pub fn source(pass: &PassSource, world_loop: Loop, world: WorldBindings) -> String {
    let prelude = prelude(world);
    let mut files = vec![prelude.as_str(), WORLD, RAY, TRACE];
    files.extend(world_loop.files());
    files.extend(pass.files);
    files.push(&pass.generated);
    let source = files.join("\n");
    match world {
        WorldBindings::Split(_) => source,
        WorldBindings::Single => uniform_parameters(&source),
    }
}

/// `source` with every read-only storage variable of a struct type (not an array) declared
/// `var<uniform>` instead.
fn uniform_parameters(source: &str) -> String {
    const STORAGE: &str = "var<storage, read> ";
    let mut out = String::with_capacity(source.len());
    for line in source.split_inclusive('\n') {
        match line.split_once(STORAGE) {
            Some((head, decl)) if !decl.contains("array<") => {
                out.push_str(head);
                out.push_str("var<uniform> ");
                out.push_str(decl);
            }
            _ => out.push_str(line),
        }
    }
    out
}

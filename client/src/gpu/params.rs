//! Parameter structs (the values a dispatch reads alike in every invocation) declared once
//! for Rust and WGSL.
//!
//! `wgsl_struct!` declares a `#[repr(C)]` [`bytemuck::Pod`] struct and implements
//! [`WgslStruct`] for it from the same field list: the WGSL declaration the shaders'
//! prelude gets ([`WgslStruct::wgsl`]) has the same fields, in the same order, with types
//! derived from the Rust ones ([`WgslType`]). A unit test in `shaders.rs` checks with naga
//! that WGSL lays the struct out at the Rust offsets.

use std::fmt::Write;

/// A Rust field type with a WGSL counterpart of the same size.
pub trait WgslType: bytemuck::Pod {
    /// The WGSL type.
    const WGSL: &'static str;
}

impl WgslType for u32 {
    const WGSL: &'static str = "u32";
}

impl WgslType for [u32; 3] {
    const WGSL: &'static str = "vec3<u32>";
}

impl WgslType for [i32; 3] {
    const WGSL: &'static str = "vec3<i32>";
}

impl WgslType for f32 {
    const WGSL: &'static str = "f32";
}

impl WgslType for [f32; 3] {
    const WGSL: &'static str = "vec3<f32>";
}

/// One field of a [`WgslStruct`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Member {
    /// The field's name, the same in Rust and WGSL.
    pub name: &'static str,
    /// Its WGSL type.
    pub wgsl: &'static str,
    /// Its byte offset in the Rust struct (`offset_of!`).
    pub offset: usize,
    /// Its doc comment, one entry per line.
    pub doc: &'static [&'static str],
}

/// A struct with one definition for Rust and WGSL (declared with `wgsl_struct!`).
pub trait WgslStruct: bytemuck::Pod {
    /// The struct's name in both languages.
    const NAME: &'static str;
    /// Its fields, in declaration order.
    const MEMBERS: &'static [Member];

    /// The WGSL declaration, doc comments included.
    fn wgsl() -> String {
        let mut s = format!("struct {} {{\n", Self::NAME);
        for m in Self::MEMBERS {
            for line in m.doc {
                let _ = writeln!(s, "    //{line}");
            }
            let _ = writeln!(s, "    {}: {},", m.name, m.wgsl);
        }
        s.push_str("}\n");
        s
    }
}

/// Declares a `#[repr(C)]` Pod struct of documented `pub` fields whose types implement
/// [`WgslType`], and implements [`WgslStruct`] for it from the same field list. Its size
/// must be a multiple of 16 bytes, as WGSL rounds a struct with `vec3` members up to that.
macro_rules! wgsl_struct {
    (
        $(#[doc = $doc:literal])*
        pub struct $name:ident {
            $($(#[doc = $field_doc:literal])+ pub $field:ident: $ty:ty,)+
        }
    ) => {
        $(#[doc = $doc])*
        #[repr(C)]
        #[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
        pub struct $name {
            $($(#[doc = $field_doc])+ pub $field: $ty,)+
        }

        const _: () = assert!(size_of::<$name>() % 16 == 0, "parameter structs are multiples of 16 bytes");

        impl WgslStruct for $name {
            const NAME: &'static str = stringify!($name);
            const MEMBERS: &'static [Member] = &[$(Member {
                name: stringify!($field),
                wgsl: <$ty as WgslType>::WGSL,
                offset: std::mem::offset_of!($name, $field),
                doc: &[$($field_doc),+],
            }),+];
        }
    };
}

wgsl_struct! {
    /// The world's parameters, `world_info` (group 0, binding 0 of every pass): what the shaders
    /// know about the world besides its buffers.
    pub struct WorldInfo {
        /// World size in voxels.
        pub size: [u32; 3],
        /// Slots of the instance buffer on the device, the world's and then the local
        /// instances' (records of 5 words; 0: no instance to trace).
        pub instance_slots: u32,
        /// World size in chunks.
        pub chunks: [u32; 3],
        /// Cells a ray may visit before it counts as a miss.
        pub max_steps: u32,
    }
}

// Two 16-byte rows: a vec3 and a scalar each.
const _: () = assert!(size_of::<WorldInfo>() == 32);

wgsl_struct! {
    /// What a lit pass renders, `frame` (group 1, binding 0 of the lit passes): the camera,
    /// the image size and which sample to add. The camera's rays follow the contract
    /// (docs/CAMERA.md): `dir = forward + sx·right + sy·up` with `right` and `up` already
    /// scaled by `a·W/H` and `a`.
    pub struct FrameInfo {
        /// Camera position, integer part (floor).
        pub cam_int: [i32; 3],
        /// Image width in pixels.
        pub width: u32,
        /// Camera position, fractional part in [0, 1).
        pub cam_frac: [f32; 3],
        /// Image height in pixels.
        pub height: u32,
        /// View direction.
        pub forward: [f32; 3],
        /// The run's seed.
        pub seed: u32,
        /// Image right, scaled by a·W/H.
        pub right: [f32; 3],
        /// Number of the sample this dispatch adds.
        pub sample: u32,
        /// Image up, scaled by a.
        pub up: [f32; 3],
        /// 1 when a temporal pass has a history to blend with (0 for the path tracer).
        pub history: u32,
    }
}

wgsl_struct! {
    /// The light, `light` (group 1, binding 1 of the lit passes; docs/RENDERING.md §3a).
    pub struct LightInfo {
        /// Uniform sky: its radiance. Physical sky: the irradiance of the sun lighting it.
        pub sky: [f32; 3],
        /// 1 for the physical sky.
        pub sky_physical: u32,
        /// Unit vector toward the sun (the sun lighting the physical sky when it is off).
        pub sun_dir: [f32; 3],
        /// 1 when the sun shines (its disc and its samples).
        pub sun_on: u32,
        /// The disc's radiance.
        pub sun_disc: f32,
        /// The weight of one disc sample: radiance times solid angle.
        pub sun_weight: f32,
        /// 1 − cos of the disc's angular radius.
        pub sun_omc: f32,
        /// Scattered rays after the camera ray.
        pub bounces: u32,
    }
}

wgsl_struct! {
    /// The GI pipeline's frame state, `gi` (group 1, binding 2 of the `gi` passes;
    /// docs/RENDERING.md §3c).
    pub struct GiInfo {
        /// Frames rendered in this history before this one.
        pub frame: u32,
        /// The long-term TAA slot this frame writes (`frame % TAA_SLOTS`).
        pub taa_slot: u32,
        /// Earlier frames the TAA may read (at most `TAA_SLOTS − 1`).
        pub taa_valid: u32,
        /// The first frame rendered after the newest change of the materials, or of more
        /// chunks than are marked one by one (0: none): the near-change rule everywhere.
        pub edit_frame: u32,
        /// The first frame rendered after the newest change of any chunk, entity moves
        /// included (0: none): the still path keeps no sample from before it.
        pub change_frame: u32,
        /// This frame's jitter in the pixel, x (a point of a 32-point (0, 5, 2)-net).
        pub jitter_x: f32,
        /// This frame's jitter in the pixel, y.
        pub jitter_y: f32,
        /// 8×8 regions across.
        pub regions_x: u32,
        /// 8×8 regions down.
        pub regions_y: u32,
        /// Samples the sample ring holds.
        pub ring_capacity: u32,
        /// 1 when the bilateral denoiser runs.
        pub denoise: u32,
        /// Where each pixel's own secondary sample starts in `mem` (tagged with the
        /// frame that traced it).
        pub off_own: u32,
        /// Where the atmosphere table starts in `mem` (vec4 words; the cameras start at 0).
        pub off_lut: u32,
        /// Where the first-hit surfaces start in `mem`.
        pub off_gbuf: u32,
        /// Where the first-hit materials start in `mem`.
        pub off_gmat: u32,
        /// Where the first-hit light starts in `mem`.
        pub off_emitted: u32,
        /// Where the TAA's per-pixel sums and ranges start in `mem`.
        pub off_taa_info: u32,
        /// Where the incoming light starts in `mem`.
        pub off_illum: u32,
        /// Where the denoiser's intermediate starts in `mem`.
        pub off_illum2: u32,
        /// Where the results start in `mem`.
        pub off_result: u32,
        /// Where the refined samples start in `mem`.
        pub off_refined: u32,
        /// Where the regions' statistics start in `mem`.
        pub off_region_info: u32,
        /// Where the sample ring starts in `mem`.
        pub off_ring: u32,
        /// Where the queued pixels start in `words`.
        pub off_queue_list: u32,
    }
}

const _: () = assert!(size_of::<FrameInfo>() == 80 && size_of::<LightInfo>() == 48 && size_of::<GiInfo>() == 96);

wgsl_struct! {
    /// What a frame of the render pass shows, `view` (group 1, binding 0 of `render`): the
    /// camera as [`FrameInfo`] holds it, the mode and the sun of the `albedo` sky.
    pub struct View {
        /// Camera position, integer part (floor).
        pub cam_oi: [i32; 3],
        /// The mode's code (`MODE_*`).
        pub mode: u32,
        /// Camera position, fractional part in [0, 1).
        pub cam_of: [f32; 3],
        /// Image width in pixels.
        pub width: u32,
        /// View direction.
        pub forward: [f32; 3],
        /// Image height in pixels.
        pub height: u32,
        /// Image right, scaled by a·W/H.
        pub right: [f32; 3],
        /// Bit 0: write each pixel's first-hit record.
        pub flags: u32,
        /// Image up, scaled by a.
        pub up: [f32; 3],
        /// `1 / log2(1 + STEPS_FULL_SCALE)`: the heat map's scale.
        pub steps_scale: f32,
        /// Unit vector toward the sun.
        pub sun: [f32; 3],
        /// Padding to 16 bytes.
        pub _pad: u32,
    }
}

wgsl_struct! {
    /// How many rays the ray-list pass traces, `ray_count` (group 1, binding 0 of `rays`).
    pub struct RayCount {
        /// Rays in the list.
        pub count: u32,
        /// Invocations per row of the 2D dispatch.
        pub row: u32,
        /// Padding to 16 bytes.
        pub _pad0: u32,
        /// Padding to 16 bytes.
        pub _pad1: u32,
    }
}

wgsl_struct! {
    /// One ray of the ray-list pass's input, `rays_in` (group 1, binding 1 of `rays`): the
    /// origin split into floor and fraction, and the direction (any length).
    pub struct RayIn {
        /// Origin, integer part (floor).
        pub o_int: [i32; 3],
        /// Padding.
        pub _pad0: u32,
        /// Origin, fractional part in [0, 1).
        pub o_frac: [f32; 3],
        /// Padding.
        pub _pad1: u32,
        /// Direction.
        pub d: [f32; 3],
        /// Padding.
        pub _pad2: u32,
    }
}

const _: () = assert!(size_of::<View>() == 96 && size_of::<RayCount>() == 16 && size_of::<RayIn>() == 48);

wgsl_struct! {
    /// What the ROMA sample pass knows of its maps, `roma` (group 1, binding 3 of `roma`'s
    /// sample pass).
    pub struct RomaInfo {
        /// The camera the windows are centred on, in voxels.
        pub camera: [f32; 3],
        /// How far ambient occlusion looks, in voxels.
        pub ao_range: f32,
        /// Candidate directions per axis of the concentric square.
        pub side: u32,
        /// Candidate directions (`side²`); the sun's map follows them.
        pub directions: u32,
        /// Padding to 16 bytes.
        pub _pad0: u32,
        /// Padding to 16 bytes.
        pub _pad1: u32,
    }
}

wgsl_struct! {
    /// One window of one ROMA map at one level, `roma_windows[map · ROMA_LEVELS + level]`:
    /// the map's frame, the level's cell, where its tiles are kept and which tiles it
    /// holds.
    pub struct RomaWindow {
        /// The frame's first row.
        pub t: [f32; 3],
        /// The level's cell edge, in voxels.
        pub cell: f32,
        /// The frame's second row.
        pub b: [f32; 3],
        /// The window's first tile in `roma_bits` (in tiles).
        pub first_tile: u32,
        /// The frame's third row: the map's direction.
        pub w: [f32; 3],
        /// How far off a surface a ray starts, in cells of this level.
        pub offset: f32,
        /// The window's lowest tile, per map axis.
        pub base: [i32; 3],
        /// Padding to 16 bytes.
        pub _pad: u32,
    }
}

wgsl_struct! {
    /// One tile for `roma_build` to write, `roma_jobs[i]`.
    pub struct RomaJob {
        /// The tile's coordinates in its map, in tiles.
        pub tile: [i32; 3],
        /// Its window (`map · ROMA_LEVELS + level`).
        pub window: u32,
        /// 1: the tile lies outside the world, so it is cleared without sampling.
        pub clear: u32,
        /// Padding to 16 bytes.
        pub _pad0: u32,
        /// Padding to 16 bytes.
        pub _pad1: u32,
        /// Padding to 16 bytes.
        pub _pad2: u32,
    }
}

wgsl_struct! {
    /// What the irradiance passes know of the cache, `irr` (`--mode irradiance`).
    pub struct IrradianceInfo {
        /// This frame's stamp (from 1): an entry requested this frame holds it.
        pub stamp: u32,
        /// Slots of the table less one (a power of two less one).
        pub mask: u32,
        /// Room in the request list, in slots.
        pub max_requests: u32,
        /// Entry samples the frame's ray budget pays for.
        pub budget: u32,
        /// Seed of the entries' sample streams.
        pub seed: u32,
        /// Boxes in the invalidation list.
        pub boxes: u32,
        /// Padding to 16 bytes.
        pub _pad0: u32,
        /// Padding to 16 bytes.
        pub _pad1: u32,
    }
}

const _: () = assert!(size_of::<IrradianceInfo>() == 32);

const _: () = assert!(size_of::<RomaInfo>() == 32 && size_of::<RomaWindow>() == 64 && size_of::<RomaJob>() == 32);

// The GI pipeline (`gi`, docs/RENDERING.md §3c): bindings and helpers shared by its passes
// (gi_primary.wgsl, gi_samples.wgsl, gi_resample.wgsl). Every pass binds the same group 1;
// the constants in capitals without a definition here (TAA_SLOTS, CAMERA_HISTORY, CAM_WORDS,
// the control words CONTROL_*, …) are generated after the GI files from their Rust
// definitions in client/src/gpu/gi/memory.rs.

@group(1) @binding(0) var<storage, read> frame: FrameInfo;
@group(1) @binding(1) var<storage, read> light: LightInfo;
@group(1) @binding(2) var<storage, read> gi: GiInfo;
// The pipeline's memory (docs/RENDERING.md §3c). The GI's arrays live in four logical
// buffers, each array at an offset that `gi` carries (computed in gi.rs). `words` and
// `buckets` are bound here; `mem` and `taa` can outgrow one binding of the adapter, so the
// generated declarations after the GI files split each across bindings (from binding 6)
// and give their accessors: `mem_get(i)`, `mem_set(i, v)`, `taa_get(i)`, `taa_set(i, v)`.
// - `mem` (vec4 words; f32 data is stored bitcast):
//   - cams: CAMERA_HISTORY cameras, newest first (index = frames ago), CAM_WORDS each:
//     (position relative to this frame's integer camera position, jitter x), (forward,
//     jitter y), (right, 0), (up, 0), (that frame's integer position minus this one's, 0);
//   - lut: the atmosphere table, LUT_SIZE² latitude–longitude texels of sky radiance;
//   - gbuf, per pixel: the final surface of the first-hit chain relative to the integer
//     camera position, and the chain's length (−1: sky or mirror limit);
//   - gmat, per pixel: x = kind | class << 4 | normal id << 8 | material << 16;
//     y = TAA hash (16 bits) | octahedral normal << 16; z, w = the chain's throughput
//     (f16 r, g | b) with the octahedral outgoing direction in w's high half;
//   - emitted, per pixel: the light the first-hit chain met (sky, sun disc, emission);
//   - taa_info, per pixel, 2 vec4: the accepted history samples' colour sum and count;
//     the least and greatest chain length of the 3×3 neighbourhood (sky: SKY_DIST);
//   - illum, illum2, per pixel: the surface's incoming light before the chain's
//     throughput, and the denoiser's guide (illum2: the denoiser's intermediate);
//   - result, per pixel: the frame's linear radiance after the TAA merge;
//   - refined, per region: MAX_KEPT refined samples, 2 vec4 each;
//   - region_info, per region, 3 vec4: the lit ratio per normal id (0–3), (lit ratio of
//     ids 4 and 5, samples kept, samples projected) and (normal mask, least and greatest
//     chain length, 0);
//   - ring: the sample ring, RING_VEC4 vec4 per secondary sample (gi_samples.wgsl).
// - `words`: the control words (indirect arguments at CONTROL_TRACE_ARGS and
//   CONTROL_PROJECT_ARGS, ring bookkeeping, per-frame sample counts), then per region the
//   queued count and (at R + region) the queue offset, then per region 64 queued pixels.
// - `buckets`: per region BUCKET_SLOTS priorities, BUCKET_SLOTS ring indices, then the
//   lit and unlit counts of each normal id (2 × NORMALS words).
// - `taa`: the long-term TAA, TAA_SLOTS frames of 64-bit samples.
@group(1) @binding(3) var<storage, read_write> words: array<u32>;
@group(1) @binding(4) var<storage, read_write> buckets: array<atomic<u32>>;
// Per chunk (`chunk_index`): the first frame after its newest change, and after the newest
// change within CHANGE_REACH chunks of it (0: none); written by gi.rs from the world's
// changed chunks.
@group(1) @binding(5) var<storage, read> changes: array<vec2<u32>>;

// The chain length of the sky in the TAA (the largest finite f16).
const SKY_DIST: f32 = 65504.0;
// Kinds of final surface (gmat.x bits 4–7).
const CLASS_DIFFUSE: u32 = 0u;
const CLASS_GLOSSY: u32 = 1u;
const CLASS_NONE: u32 = 2u;
const NO_NORMAL: u32 = 7u;
// Normal ids of surfaces (0–5).
const NORMALS: u32 = 6u;

fn pixel_count() -> u32 {
    return frame.width * frame.height;
}

fn region_count() -> u32 {
    return gi.regions_x * gi.regions_y;
}

fn taa_accum(i: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(mem_get(gi.off_taa_info + 2u * i));
}

fn taa_range(i: u32) -> vec2<f32> {
    return bitcast<vec4<f32>>(mem_get(gi.off_taa_info + 2u * i + 1u)).xy;
}

// The unit vector of normal id `id`.
fn normal_of_id(id: u32) -> vec3<f32> {
    let sign = select(-1.0, 1.0, (id & 1u) == 1u);
    return vec3<f32>(select(0.0, sign, id / 2u == 0u), select(0.0, sign, id / 2u == 1u), select(0.0, sign, id / 2u == 2u));
}

// The change marks (`changes`) of the chunk holding the solid voxel behind surface point
// `p` (relative to this frame's integer camera position) of normal `n`; none outside the
// world.
fn changes_at(p: vec3<f32>, n: vec3<f32>) -> vec2<u32> {
    let v = floor(vec3<f32>(frame.cam_int) + p - 0.5 * n);
    if any(v < vec3<f32>(0.0)) || any(v >= vec3<f32>(world_info.size)) {
        return vec2<u32>(0u);
    }
    return changes[chunk_index(vec3<u32>(v) / 16u, world_info.chunks)];
}

fn region_of(x: u32, y: u32) -> u32 {
    return x / 8u + (y / 8u) * gi.regions_x;
}

// ---- Cameras of earlier frames ----

struct Cam {
    pos: vec3<f32>,
    jitter: vec2<f32>,
    forward: vec3<f32>,
    right: vec3<f32>,
    up: vec3<f32>,
    origin: vec3<f32>,
}

// The thread's index in a dispatch of 64-wide groups laid out as x + y · (groups across)
// (`dispatch_2d` on the host, or the queue scan's indirect arguments).
fn flat_id(wid: vec3<u32>, groups: vec3<u32>, li: u32) -> u32 {
    return (wid.x + wid.y * groups.x) * 64u + li;
}

// Earlier frames whose cameras `cams` holds: every one, up to CAMERA_HISTORY − 1.
fn cams_valid() -> u32 {
    return min(gi.frame, CAMERA_HISTORY - 1u);
}

fn cam(age: u32) -> Cam {
    let b = min(age, CAMERA_HISTORY - 1u) * CAM_WORDS;
    let a = bitcast<vec4<f32>>(mem_get(b));
    let f = bitcast<vec4<f32>>(mem_get(b + 1u));
    return Cam(a.xyz, vec2<f32>(a.w, f.w), f.xyz, bitcast<vec4<f32>>(mem_get(b + 2u)).xyz, bitcast<vec4<f32>>(mem_get(b + 3u)).xyz, bitcast<vec4<f32>>(mem_get(b + 4u)).xyz);
}

// Whether two cameras see exactly the same view (position, orientation and field of view;
// their jitters may differ).
fn same_view(a: Cam, b: Cam) -> bool {
    return all(a.pos == b.pos) && all(a.origin == b.origin) && all(a.forward == b.forward)
        && all(a.right == b.right) && all(a.up == b.up);
}

// Where `v` (relative to the camera) falls on camera `c`'s image, in pixels from its
// top-left corner; `z` ≤ 0 when behind it.
struct Projection {
    px: vec2<f32>,
    z: f32,
}

fn project(c: Cam, v: vec3<f32>) -> Projection {
    let z = dot(v, c.forward);
    if z <= 0.0 {
        return Projection(vec2<f32>(-1.0), z);
    }
    let sx = dot(v, c.right) / (z * dot(c.right, c.right));
    let sy = dot(v, c.up) / (z * dot(c.up, c.up));
    return Projection(vec2<f32>((sx + 1.0) * 0.5 * f32(frame.width), (1.0 - sy) * 0.5 * f32(frame.height)), z);
}

fn on_image(p: vec2<f32>) -> bool {
    return all(p >= vec2<f32>(0.0)) && p.x < f32(frame.width) && p.y < f32(frame.height);
}

// The camera ray of pixel `q` of camera `c` through its jittered point.
fn cam_dir(c: Cam, q: vec2<u32>) -> vec3<f32> {
    let sx = 2.0 * (f32(q.x) + c.jitter.x) / f32(frame.width) - 1.0;
    let sy = 1.0 - 2.0 * (f32(q.y) + c.jitter.y) / f32(frame.height);
    return c.forward + sx * c.right + sy * c.up;
}

// ---- Encodings ----

// Normal id: 2·axis + (1 when positive) for the dominant axis.
fn normal_id(n: vec3<f32>) -> u32 {
    let a = abs(n);
    var axis = 2u;
    if a.x >= a.y && a.x >= a.z {
        axis = 0u;
    } else if a.y >= a.z {
        axis = 1u;
    }
    return 2u * axis + select(0u, 1u, n[axis] > 0.0);
}

// A unit vector in 16 bits (octahedral, 8 bits a component, on 255 levels so that 0 and
// ±1 are exact: the world's axis normals survive unchanged).
fn oct_encode(n: vec3<f32>) -> u32 {
    var p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if n.z < 0.0 {
        p = (vec2<f32>(1.0) - abs(p.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
    }
    let q = vec2<u32>(round(clamp(p * 0.5 + 0.5, vec2<f32>(0.0), vec2<f32>(1.0)) * 254.0));
    return q.x | (q.y << 8u);
}

fn oct_decode(e: u32) -> vec3<f32> {
    let p = vec2<f32>(f32(e & 0xFFu), f32((e >> 8u) & 0xFFu)) / 254.0 * 2.0 - 1.0;
    var n = vec3<f32>(p, 1.0 - abs(p.x) - abs(p.y));
    if n.z < 0.0 {
        let xy = (vec2<f32>(1.0) - abs(n.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), n.xy >= vec2<f32>(0.0));
        n = vec3<f32>(xy, n.z);
    }
    return normalize(n);
}

// The pixel's final surface: its normal (from gmat.y) and material (gmat.x).
fn surface_normal(g: vec4<u32>) -> vec3<f32> {
    return oct_decode(g.y >> 16u);
}

fn surface_class(g: vec4<u32>) -> u32 {
    return (g.x >> 4u) & 3u;
}

fn surface_normal_id(g: vec4<u32>) -> u32 {
    return (g.x >> 8u) & 7u;
}

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// ---- The atmosphere table ----

// The table is latitude–longitude: columns are azimuth, rows elevation warped as
// v = sign(e)·sqrt(|e|/(π/2)) to spend rows near the horizon, which lies exactly between
// rows LUT_SIZE/2 − 1 and LUT_SIZE/2, so that no lookup blends the sky with the ground.

// The table coordinates (continuous, texel centres at +0.5) of unit `d`.
fn lut_coords(d: vec3<f32>) -> vec2<f32> {
    let e = asin(clamp(d.y, -1.0, 1.0)) / (0.5 * PI);
    let v = sign(e) * sqrt(abs(e));
    let a = atan2(d.x, d.z) / (2.0 * PI) + 0.5;
    return vec2<f32>(a, v * 0.5 + 0.5) * f32(LUT_SIZE);
}

// The unit direction at the centre of texel `t`.
fn lut_direction(t: vec2<u32>) -> vec3<f32> {
    let uv = (vec2<f32>(t) + 0.5) / f32(LUT_SIZE);
    let v = uv.y * 2.0 - 1.0;
    let e = sign(v) * v * v * 0.5 * PI;
    let a = (uv.x - 0.5) * 2.0 * PI;
    return vec3<f32>(cos(e) * sin(a), sin(e), cos(e) * cos(a));
}

// Texel (x, y) with x wrapping around the azimuth and y clamped to the rows of the
// hemisphere `upper` names.
fn lut_texel(x: i32, y: i32, upper: bool) -> vec3<f32> {
    let half = i32(LUT_SIZE) / 2;
    let cx = u32((x + i32(LUT_SIZE)) % i32(LUT_SIZE));
    let cy = u32(select(clamp(y, 0, half - 1), clamp(y, half, i32(LUT_SIZE) - 1), upper));
    return bitcast<vec4<f32>>(mem_get(gi.off_lut + cx + cy * LUT_SIZE)).rgb;
}

// The sky along unit `d` from the table, bilinearly filtered within its hemisphere.
fn sky_base(d: vec3<f32>) -> vec3<f32> {
    if light.sky_physical == 0u {
        return light.sky;
    }
    let upper = d.y >= 0.0;
    let t = lut_coords(d) - 0.5;
    let b = floor(t);
    let f = t - b;
    let x = i32(b.x);
    let y = i32(b.y);
    let top = mix(lut_texel(x, y, upper), lut_texel(x + 1, y, upper), f.x);
    let bottom = mix(lut_texel(x, y + 1, upper), lut_texel(x + 1, y + 1, upper), f.x);
    return mix(top, bottom, f.y);
}

// Pass `gi_atmosphere`: fills the whole table (when a history starts: the light is part of
// what a history is of).
@compute @workgroup_size(8, 8)
fn gi_atmosphere(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= LUT_SIZE || gid.y >= LUT_SIZE {
        return;
    }
    mem_set(gi.off_lut + gid.x + gid.y * LUT_SIZE, bitcast<vec4<u32>>(vec4<f32>(sky_direct(lut_direction(gid.xy)), 0.0)));
}

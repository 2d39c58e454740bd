// Pass `taa_resolve` of `baseline` (docs/RENDERING.md §3b): the paper's comparison, an
// exponential moving average of 1-spp path-traced frames, α = 0.1, with the history
// clamped to the 3×3 neighbourhood of the current frame in YCoCg.
//
// The history is reprojected: this pixel's sample point (its jittered camera ray, out to
// the first surface, or the direction alone for the sky) is projected into the previous
// camera, and the previous result is read there with a bilinear filter. `prev` holds the
// previous camera with its position relative to the current camera's, so that nothing
// here subtracts two large coordinates.

@group(1) @binding(0) var<storage, read> frame: FrameInfo;
@group(1) @binding(1) var<storage, read> prev: FrameInfo;
// This frame's samples: RGB and the distance to the first surface (−1: sky).
@group(1) @binding(2) var<storage, read> current: array<vec4<f32>>;
// The previous result (RGB).
@group(1) @binding(3) var<storage, read> history: array<vec4<f32>>;
@group(1) @binding(4) var<storage, read_write> resolved: array<vec4<f32>>;

const TAA_ALPHA: f32 = 0.1;

fn to_ycocg(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(0.25 * c.r + 0.5 * c.g + 0.25 * c.b, 0.5 * c.r - 0.5 * c.b, -0.25 * c.r + 0.5 * c.g - 0.25 * c.b);
}

fn from_ycocg(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(c.x + c.y - c.z, c.x + c.z, c.x - c.y - c.z);
}

fn history_at(x: i32, y: i32) -> vec3<f32> {
    let cx = clamp(x, 0, i32(frame.width) - 1);
    let cy = clamp(y, 0, i32(frame.height) - 1);
    return history[u32(cx) + u32(cy) * frame.width].rgb;
}

// The previous result where this pixel's sample was seen, bilinearly filtered; `ok` is
// false when that point was off the previous frame or behind its camera.
struct Reprojected {
    rgb: vec3<f32>,
    ok: bool,
}

fn reproject(gid: vec2<u32>, distance: f32) -> Reprojected {
    let none = Reprojected(vec3<f32>(0.0), false);
    let stream = pixel_stream(frame.seed, gid.x + gid.y * frame.width, frame.sample);
    let dir = normalize(camera_dir(frame, gid, stream.jitter));
    var v = dir;
    if distance >= 0.0 {
        v = dir * distance - (vec3<f32>(prev.cam_int) + prev.cam_frac);
    }
    let z = dot(v, prev.forward);
    if z <= 0.0 {
        return none;
    }
    let sx = dot(v, prev.right) / (z * dot(prev.right, prev.right));
    let sy = dot(v, prev.up) / (z * dot(prev.up, prev.up));
    // Where the sample point lies in the previous image, in pixels from its top-left corner,
    // moved back by the sample's jitter to this pixel's centre; then in texel-centre units.
    let u = vec2<f32>((sx + 1.0) * 0.5 * f32(frame.width), (1.0 - sy) * 0.5 * f32(frame.height));
    let t = u - stream.jitter;
    let size = vec2<f32>(f32(frame.width), f32(frame.height));
    if any(t < vec2<f32>(-0.5)) || any(t > size - 0.5) {
        return none;
    }
    let base = floor(t);
    let f = t - base;
    let x = i32(base.x);
    let y = i32(base.y);
    let top = mix(history_at(x, y), history_at(x + 1, y), f.x);
    let bottom = mix(history_at(x, y + 1), history_at(x + 1, y + 1), f.x);
    return Reprojected(mix(top, bottom, f.y), true);
}

@compute @workgroup_size(8, 8)
fn taa_resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let i = gid.x + gid.y * frame.width;
    let c = current[i];
    var out = c.rgb;
    if prev.history != 0u {
        let h = reproject(gid.xy, c.w);
        if h.ok {
            var lo = vec3<f32>(3.0e38);
            var hi = vec3<f32>(-3.0e38);
            for (var dy = -1; dy <= 1; dy++) {
                for (var dx = -1; dx <= 1; dx++) {
                    let x = i32(gid.x) + dx;
                    let y = i32(gid.y) + dy;
                    if x >= 0 && y >= 0 && x < i32(frame.width) && y < i32(frame.height) {
                        let n = to_ycocg(current[u32(x) + u32(y) * frame.width].rgb);
                        lo = min(lo, n);
                        hi = max(hi, n);
                    }
                }
            }
            let clamped = from_ycocg(clamp(to_ycocg(h.rgb), lo, hi));
            out = mix(clamped, c.rgb, TAA_ALPHA);
        }
    }
    resolved[i] = vec4<f32>(out, c.w);
}

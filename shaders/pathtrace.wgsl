// Passes `path_trace` (progressive path tracing, `pathtrace`) and `path_sample` (one sample
// per pixel per frame, `baseline`), one invocation per pixel (docs/RENDERING.md §3a, §3b).
//
// `path_trace`: each dispatch adds sample number `frame.sample` to every pixel's running
// sum; the host divides by the count. A sample's random stream depends only on (seed, pixel, sample
// number), and every pixel adds its samples in number order, so the sums are the same bit
// for bit however the dispatches are grouped into submissions.
//
// One sample per dispatch, not a loop over samples: lavapipe (Mesa 22.3) miscompiles a
// sample loop around the bounce loop around the traversal loop, and pixels silently lose
// samples.
//
// `FrameInfo` and `LightInfo` are generated in the prelude from their Rust twins.

@group(1) @binding(0) var<storage, read> frame: FrameInfo;
@group(1) @binding(1) var<storage, read> light: LightInfo;
// `path_trace`: running sums (RGB, count). `path_sample`: this frame's sample (RGB, and
// the distance to the first surface, −1 for the sky).
@group(1) @binding(2) var<storage, read_write> radiance: array<vec4<f32>>;

// The path tracer sees the sky as the light model defines it, direction by direction.
fn sky_base(d: vec3<f32>) -> vec3<f32> {
    return sky_direct(d);
}

// Sample `frame.sample` of pixel `gid`.
fn pixel_sample(gid: vec2<u32>) -> PathSample {
    let stream = pixel_stream(frame.seed, gid.x + gid.y * frame.width, frame.sample);
    var rng = stream.rng;
    let r = ray_new(frame.cam_int, frame.cam_frac, camera_dir(frame, gid, stream.jitter));
    return path_radiance(r, light.bounces, true, &rng);
}

@compute @workgroup_size(8, 8)
fn path_trace(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let s = pixel_sample(gid.xy);
    radiance[gid.x + gid.y * frame.width] += vec4<f32>(s.radiance, 1.0);
}

@compute @workgroup_size(8, 8)
fn path_sample(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let s = pixel_sample(gid.xy);
    radiance[gid.x + gid.y * frame.width] = vec4<f32>(s.radiance, s.distance);
}

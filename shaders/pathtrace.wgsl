// Pass: progressive path tracing (`pathtrace`, docs/RENDERING.md), one invocation per
// pixel. Each dispatch adds sample number `frame.sample` to every pixel's running sum; the
// host divides by the count. A sample's random stream depends only on (seed, pixel, sample
// number), and every pixel adds its samples in number order, so the sums are the same bit
// for bit however the dispatches are grouped into submissions.
//
// One sample per dispatch, not a loop over samples: lavapipe (Mesa 22.3) miscompiles a
// sample loop around the bounce loop around the traversal loop, and pixels silently lose
// samples.
//
// `FrameInfo` and `LightInfo` are generated in the prelude from their Rust twins.

@group(1) @binding(0) var<uniform> frame: FrameInfo;
@group(1) @binding(1) var<uniform> light: LightInfo;
@group(1) @binding(2) var<storage, read_write> sums: array<vec4<f32>>;

@compute @workgroup_size(8, 8)
fn path_trace(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let i = gid.x + gid.y * frame.width;
    var rng = rng_new(frame.seed, i, frame.sample);
    let jx = rng_next(&rng);
    let jy = rng_next(&rng);
    let sx = 2.0 * (f32(gid.x) + jx) / f32(frame.width) - 1.0;
    let sy = 1.0 - 2.0 * (f32(gid.y) + jy) / f32(frame.height);
    let r = ray_new(frame.cam_int, frame.cam_frac, frame.forward + sx * frame.right + sy * frame.up);
    sums[i] += vec4<f32>(path_radiance(r, &rng), 1.0);
}

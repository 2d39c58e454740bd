// The samples of the lit passes: random streams (client/src/light/rng.rs), one per sample
// of each pixel, seeded from the run's seed, the pixel's index and the sample's number
// only; and the jittered camera ray of a sample.

fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The stream of sample `sample` of pixel `pixel` under `seed`.
fn rng_new(seed: u32, pixel: u32, sample: u32) -> u32 {
    return pcg_hash(seed ^ pcg_hash(pixel ^ pcg_hash(sample)));
}

// A uniform number in [0, 1) with 24 random bits.
fn rng_next(state: ptr<function, u32>) -> f32 {
    *state = pcg_hash(*state);
    return f32(*state >> 8u) * (1.0 / 16777216.0);
}

// The stream of sample `sample` of pixel `pixel`, after its first two draws: where in the
// pixel the sample's camera ray goes (uniform in [0, 1)²).
struct PixelStream {
    rng: u32,
    jitter: vec2<f32>,
}

fn pixel_stream(seed: u32, pixel: u32, sample: u32) -> PixelStream {
    var rng = rng_new(seed, pixel, sample);
    let jx = rng_next(&rng);
    let jy = rng_next(&rng);
    return PixelStream(rng, vec2<f32>(jx, jy));
}

// The camera's (unnormalised) direction through point `jitter` ([0, 1)²) of pixel `gid` of
// frame `f` (docs/CAMERA.md, with `px + jitter.x` for `px + 0.5`).
fn camera_dir(f: FrameInfo, gid: vec2<u32>, jitter: vec2<f32>) -> vec3<f32> {
    let sx = 2.0 * (f32(gid.x) + jitter.x) / f32(f.width) - 1.0;
    let sy = 1.0 - 2.0 * (f32(gid.y) + jitter.y) / f32(f.height);
    return f.forward + sx * f.right + sy * f.up;
}

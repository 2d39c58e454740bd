// No lighting tier: `path_step` (light.wgsl) traces diffuse surfaces as the light model
// does. Included by the path tracer and the GI passes; `roma` includes roma.wgsl instead.

const DIFFUSE_TIER: bool = false;

fn diffuse_tier(p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, rng: ptr<function, u32>) -> vec3<f32> {
    return vec3<f32>(0.0);
}

// No lighting tier: `path_step` (light.wgsl) traces diffuse surfaces as the light model
// does. Included by the path tracer, the GI passes and the irradiance cache's updates;
// `roma` and `irradiance` include roma.wgsl and irradiance.wgsl instead.

const DIFFUSE_TIER: bool = false;

fn diffuse_tier(h: Hit, p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, rng: ptr<function, u32>) -> vec3<f32> {
    return vec3<f32>(0.0);
}

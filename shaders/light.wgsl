// The light model of the lit modes (docs/RENDERING.md §3a): the physical sky, the sun,
// BRDF sampling and one path's radiance. The GPU twin of client/src/light/ (sky.rs,
// scatter.rs, cpu.rs), written operation by operation like it so that the two path
// tracers agree up to rounding. Needs random.wgsl before it.
//
// The pass binds `light: LightInfo` (generated in the prelude from the Rust `LightInfo`),
// and declares `DIFFUSE_TIER` and `diffuse_tier` (no_tier.wgsl, or a lighting tier such as
// roma.wgsl) for `path_step`.

// PI, SURFACE_OFFSET (how far scattered and shadow rays start off the surface),
// MIN_ALPHA (the smallest GGX α a metal is traced with) and the physical sky's constants
// (PLANET_RADIUS, VIEW_STEPS, RAYLEIGH, MIE_G, OZONE, …) come from the prelude, generated
// from their Rust definitions in client/src/light/ (mod.rs, scatter.rs, sky.rs).

// ---- The physical sky (sky.rs) ----

// Distance from height `h` along zenith cosine `mu` to the sphere at height `top`; a
// negative value when it is not reached going forward.
fn sphere_distance(h: f32, mu: f32, top: f32) -> f32 {
    let r = PLANET_RADIUS + h;
    let disc = (top - h) * (2.0 * PLANET_RADIUS + top + h) + r * r * mu * mu;
    if disc < 0.0 {
        return -1.0;
    }
    let s = sqrt(disc);
    let far = -r * mu + s;
    if far < 0.0 {
        return -1.0;
    }
    let near = -r * mu - s;
    return select(far, near, near > 0.0);
}

struct Medium {
    sigma: vec3<f32>,
    rayleigh: f32,
    mie: f32,
}

fn medium(h: f32) -> Medium {
    let rayleigh = exp(-h / RAYLEIGH_SCALE);
    let mie = exp(-h / MIE_SCALE);
    let ozone = max(1.0 - abs(h - OZONE_CENTRE) / OZONE_HALF_WIDTH, 0.0);
    return Medium(RAYLEIGH * rayleigh + MIE_EXTINCTION * mie + OZONE * ozone, rayleigh, mie);
}

fn sun_transmittance(h: f32, mu: f32) -> vec3<f32> {
    if mu < 0.0 && sphere_distance(h, mu, 0.0) >= 0.0 {
        return vec3<f32>(0.0);
    }
    let length = max(sphere_distance(h, mu, ATMOSPHERE_HEIGHT), 0.0);
    let dt = length / f32(LIGHT_STEPS);
    let r = PLANET_RADIUS + h;
    var depth = vec3<f32>(0.0);
    for (var i = 0u; i < LIGHT_STEPS; i++) {
        let t = (f32(i) + 0.5) * dt;
        let hi = sqrt(t * t + 2.0 * r * mu * t + r * r) - PLANET_RADIUS;
        depth += medium(hi).sigma * dt;
    }
    return exp(-depth);
}

// Sky radiance along unit `dir` for unit sun direction `sun`, per unit of irradiance.
fn sky_physical(dir: vec3<f32>, sun: vec3<f32>) -> vec3<f32> {
    let mu = dir.y;
    let nu = dot(dir, sun);
    let h0 = EYE_HEIGHT;
    let r0 = PLANET_RADIUS + h0;
    var length = sphere_distance(h0, mu, 0.0);
    if !(mu < 0.0 && length >= 0.0) {
        length = max(sphere_distance(h0, mu, ATMOSPHERE_HEIGHT), 0.0);
    }
    let dt = length / f32(VIEW_STEPS);
    let phase_r = 3.0 / (16.0 * PI) * (1.0 + nu * nu);
    let g2 = MIE_G * MIE_G;
    let phase_m = (1.0 - g2) / (4.0 * PI * pow(1.0 + g2 - 2.0 * MIE_G * nu, 1.5));
    var depth = vec3<f32>(0.0);
    var inscatter = vec3<f32>(0.0);
    for (var i = 0u; i < VIEW_STEPS; i++) {
        let t = (f32(i) + 0.5) * dt;
        let r = sqrt(t * t + 2.0 * r0 * mu * t + r0 * r0);
        let h = r - PLANET_RADIUS;
        let mu_sun = (r0 * sun.y + t * nu) / r;
        let m = medium(h);
        let to_sun = sun_transmittance(h, mu_sun);
        let view = exp(-(depth + 0.5 * m.sigma * dt));
        let scatter = RAYLEIGH * m.rayleigh * phase_r + MIE_SCATTER * m.mie * phase_m;
        inscatter += view * to_sun * scatter * dt;
        depth += m.sigma * dt;
    }
    return inscatter;
}

// The sky along unit `d`, evaluated directly (no disc).
fn sky_direct(d: vec3<f32>) -> vec3<f32> {
    if light.sky_physical != 0u {
        return sky_physical(d, light.sun_dir) * light.sky;
    }
    return light.sky;
}

// The sky along unit `d`; with `disc`, the sun's disc too. `sky_base(d)` is the including
// pass's choice: `sky_direct` (the path tracer) or the atmosphere table (`gi`).
fn sky_radiance(d: vec3<f32>, disc: bool) -> vec3<f32> {
    var l = sky_base(d);
    if disc {
        l += sun_disc(d);
    }
    return l;
}

// The sun's disc along unit `d` (0 off the disc, or with the sun off).
fn sun_disc(d: vec3<f32>) -> vec3<f32> {
    if light.sun_on != 0u && 1.0 - dot(d, light.sun_dir) <= light.sun_omc {
        return vec3<f32>(light.sun_disc);
    }
    return vec3<f32>(0.0);
}

// ---- Scattering (scatter.rs) ----

struct Basis {
    t: vec3<f32>,
    b: vec3<f32>,
}

fn basis(n: vec3<f32>) -> Basis {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return Basis(vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), vec3<f32>(b, sign + n.y * n.y * a, -n.y));
}

fn sample_cosine(n: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let f = basis(n);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    return normalize(f.t * (r * cos(phi)) + f.b * (r * sin(phi)) + n * sqrt(max(1.0 - u.x, 0.0)));
}

fn sample_cone(axis: vec3<f32>, omc: f32, u: vec2<f32>) -> vec3<f32> {
    let f = basis(axis);
    let x = u.x * omc;
    let c = 1.0 - x;
    let s = sqrt(max(x * (2.0 - x), 0.0));
    let phi = 2.0 * PI * u.y;
    return normalize(f.t * (s * cos(phi)) + f.b * (s * sin(phi)) + axis * c);
}

fn schlick(f0: vec3<f32>, c: f32) -> vec3<f32> {
    let k = 1.0 - clamp(c, 0.0, 1.0);
    let k2 = k * k;
    return f0 + (vec3<f32>(1.0) - f0) * (k2 * k2 * k);
}

fn smith_lambda(alpha: f32, c: f32) -> f32 {
    let c2 = max(c * c, 1e-12);
    let tan2 = max(1.0 - c2, 0.0) / c2;
    return 0.5 * (-1.0 + sqrt(1.0 + alpha * alpha * tan2));
}

fn ggx_d(alpha: f32, c: f32) -> f32 {
    let a2 = alpha * alpha;
    let k = c * c * (a2 - 1.0) + 1.0;
    return a2 / (PI * k * k);
}

fn ggx(n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, alpha: f32, f0: vec3<f32>) -> vec3<f32> {
    let co = dot(n, wo);
    let ci = dot(n, wi);
    if co <= 0.0 || ci <= 0.0 {
        return vec3<f32>(0.0);
    }
    let h = normalize(wo + wi);
    let g2 = 1.0 / (1.0 + smith_lambda(alpha, co) + smith_lambda(alpha, ci));
    return schlick(f0, dot(wo, h)) * (ggx_d(alpha, dot(n, h)) * g2 / (4.0 * co * ci));
}

struct Scattered {
    dir: vec3<f32>,
    weight: vec3<f32>,
}

fn ggx_sample(n: vec3<f32>, wo: vec3<f32>, alpha: f32, f0: vec3<f32>, u: vec2<f32>) -> Scattered {
    let f = basis(n);
    let v = vec3<f32>(dot(wo, f.t), dot(wo, f.b), dot(wo, n));
    let vh = normalize(vec3<f32>(alpha * v.x, alpha * v.y, v.z));
    let lensq = vh.x * vh.x + vh.y * vh.y;
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if lensq > 0.0 {
        t1 = vec3<f32>(-vh.y, vh.x, 0.0) / sqrt(lensq);
    }
    let t2 = cross(vh, t1);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * sin(phi);
    let nh = t1 * p1 + t2 * p2 + vh * sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0));
    let m = normalize(vec3<f32>(alpha * nh.x, alpha * nh.y, max(nh.z, 0.0)));
    let lwi = m * (2.0 * dot(v, m)) - v;
    let wi = normalize(f.t * lwi.x + f.b * lwi.y + n * lwi.z);
    let lo = smith_lambda(alpha, v.z);
    let li = smith_lambda(alpha, lwi.z);
    return Scattered(wi, schlick(f0, dot(v, m)) * ((1.0 + lo) / (1.0 + lo + li)));
}

// ---- Paths (cpu.rs) ----

// Whether a shadow ray meets anything before leaving the world (a ray out of cells counts
// as blocked).
fn blocked(r: Ray, p: vec3<f32>, dir: vec3<f32>) -> bool {
    return any(occlusion(ray_at(r, p, dir)));
}

// One sample of the sun's disc seen from `p` (relative to `r`'s integer origin, just off a
// surface of normal `n`): its direction, and the irradiance it brings (`E·cosθ`-weighted)
// when it is above the surface and unblocked, else 0. Two random numbers are drawn
// whenever the sun is on (cpu.rs `sun_sample`).
struct SunSample {
    dir: vec3<f32>,
    irradiance: f32,
}

fn sun_sample(r: Ray, p: vec3<f32>, n: vec3<f32>, rng: ptr<function, u32>) -> SunSample {
    if light.sun_on == 0u {
        return SunSample(vec3<f32>(0.0), 0.0);
    }
    let u = vec2<f32>(rng_next(rng), rng_next(rng));
    let wi = sample_cone(light.sun_dir, light.sun_omc, u);
    let c = dot(n, wi);
    if c > 0.0 && !blocked(r, p, wi) {
        return SunSample(wi, c * light.sun_weight);
    }
    return SunSample(wi, 0.0);
}

// One step of a path: what it adds and whether it goes on.
struct PathState {
    r: Ray,
    radiance: vec3<f32>,
    throughput: vec3<f32>,
    sees_disc: bool,
    alive: bool,
    // The normal of the first surface met (zero until then).
    first_normal: vec3<f32>,
}

// Follows the path in `s` to its next surface: adds the light found there and, when
// `scatter`, picks the next ray (or ends the path). Returns the distance to the surface
// (−1 when the ray found none).
fn path_step(s: ptr<function, PathState>, scatter: bool, rng: ptr<function, u32>) -> f32 {
    let r = (*s).r;
    let h = trace(r);
    let d = r.d / r.len;
    (*s).alive = false;
    if h.exhausted {
        return -1.0;
    }
    if !h.hit {
        (*s).radiance += (*s).throughput * sky_radiance(d, (*s).sees_disc);
        return -1.0;
    }
    let distance = h.t * r.len;
    if h.axis == NO_AXIS {
        return distance;
    }
    // Before any other trace: world_normal reads the last trace's entity rotation.
    let n = world_normal(h);
    if all((*s).first_normal == vec3<f32>(0.0)) {
        (*s).first_normal = n;
    }
    let m = material(h.material);
    if m.kind == KIND_EMISSIVE {
        (*s).radiance += (*s).throughput * m.albedo * m.emission;
    }
    // A lighting tier (`roma`, `irradiance`) lights diffuse and emissive surfaces itself,
    // and the path ends there; mirrors and metals scatter on.
    if DIFFUSE_TIER && m.kind != KIND_MIRROR && m.kind != KIND_METAL {
        let surface = vec3<f32>(r.o_int) + ray_local(r, h.t);
        (*s).radiance += (*s).throughput * diffuse_tier(h, surface, n, m.albedo, rng);
        return distance;
    }
    if !scatter {
        return distance;
    }
    let p = ray_local(r, h.t) + n * SURFACE_OFFSET;
    var next: Scattered;
    if m.kind == KIND_MIRROR {
        (*s).sees_disc = true;
        next = Scattered(d - n * (2.0 * dot(d, n)), m.albedo);
    } else {
        let wo = -d;
        let alpha = max(m.roughness, MIN_ALPHA);
        let sun = sun_sample(r, p, n, rng);
        if sun.irradiance > 0.0 {
            var f = m.albedo / PI;
            if m.kind == KIND_METAL {
                f = ggx(n, wo, sun.dir, alpha, m.albedo);
            }
            (*s).radiance += (*s).throughput * f * sun.irradiance;
        }
        let u = vec2<f32>(rng_next(rng), rng_next(rng));
        (*s).sees_disc = false;
        if m.kind == KIND_METAL {
            next = ggx_sample(n, wo, alpha, m.albedo, u);
        } else {
            next = Scattered(sample_cosine(n, u), m.albedo);
        }
    }
    if dot(next.dir, n) > 0.0 {
        (*s).throughput *= next.weight;
        (*s).r = ray_at(r, p, next.dir);
        (*s).alive = true;
    }
    return distance;
}

// One path: the radiance it brought back, the distance from its origin to the first
// surface (−1 for the sky) and that surface's normal.
struct PathSample {
    radiance: vec3<f32>,
    distance: f32,
    normal: vec3<f32>,
}

// The radiance arriving along `primary` when the path may scatter `bounces` more times,
// drawing from `rng`. `sees_disc`: whether the ray sees the sun's disc (camera and mirror
// rays do; rays scattered by other surfaces get the sun by next-event estimation instead).
fn path_radiance(primary: Ray, bounces: u32, sees_disc: bool, rng: ptr<function, u32>) -> PathSample {
    var s = PathState(primary, vec3<f32>(0.0), vec3<f32>(1.0), sees_disc, true, vec3<f32>(0.0));
    let distance = path_step(&s, bounces > 0u, rng);
    for (var bounce = 1u; bounce <= bounces && s.alive; bounce++) {
        path_step(&s, bounce < bounces, rng);
    }
    return PathSample(s.radiance, distance, s.first_normal);
}

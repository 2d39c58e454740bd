// Pass: render one frame, one invocation per pixel (docs/RENDERING.md).
//
// Camera rays follow the camera contract (docs/CAMERA.md): the host passes the camera position
// split into integer and fraction, `forward`, and `right`/`up` already scaled by
// a·W/H and a (a = tan(fov_y/2)), so that dir = forward + sx·right + sy·up with
// sx = 2(px + 0.5)/W − 1 and sy = 1 − 2(py + 0.5)/H.
//
// Modes (MODE_*, generated after the pass from the client's `Mode`): albedo, material,
// normal, steps. Every pixel becomes one RGBA8 word; with bit 0 of `flags`, the pixel's
// first-hit record (the reference's `firstHitData`) is written to `gbuffer` as well.

// `View` is generated after the pass from its Rust definition (client/src/gpu/params.rs).

@group(1) @binding(0) var<storage, read> view: View;
@group(1) @binding(1) var<storage, read_write> pixels: array<u32>;
@group(1) @binding(2) var<storage, read_write> gbuffer: array<vec4<u32>>;

const SUN_COLOR: vec3<f32> = vec3<f32>(1.0, 0.96, 0.88);
// Cosine of the sun disc's angular radius (about 1.8°).
const SUN_DISC_COS: f32 = 0.9995;

fn srgb(c: vec3<f32>) -> vec3<f32> {
    let x = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
    return select(1.055 * pow(x, vec3<f32>(1.0 / 2.4)) - 0.055, 12.92 * x, x <= vec3<f32>(0.0031308));
}

fn pack_rgb(c: vec3<f32>) -> u32 {
    let b = vec3<u32>(floor(clamp(c, vec3<f32>(0.0), vec3<f32>(1.0)) * 255.0 + 0.5));
    return b.x | (b.y << 8u) | (b.z << 16u) | 0xFF000000u;
}

// The sky: a vertical gradient plus the sun disc.
fn sky(d: vec3<f32>) -> vec3<f32> {
    let horizon = vec3<f32>(0.70, 0.80, 0.95);
    var c: vec3<f32>;
    if d.y >= 0.0 {
        c = mix(horizon, vec3<f32>(0.20, 0.40, 0.80), sqrt(d.y));
    } else {
        c = mix(horizon, vec3<f32>(0.30, 0.28, 0.25), sqrt(-d.y));
    }
    if dot(d, view.sun) > SUN_DISC_COS {
        c += 8.0 * SUN_COLOR;
    }
    return c;
}

// ACES filmic fit (Narkowicz 2015).
fn tone_map(c: vec3<f32>) -> vec3<f32> {
    return clamp((c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14), vec3<f32>(0.0), vec3<f32>(1.0));
}

// Step-count heat map: blue → cyan → green → yellow → red over [0, 1].
fn heat(v: f32) -> vec3<f32> {
    let x = clamp(v, 0.0, 1.0) * 4.0;
    return clamp(vec3<f32>(x - 2.0, select(x, 4.0 - x, x > 3.0), 2.0 - x), vec3<f32>(0.0), vec3<f32>(1.0));
}

// Follows the primary hit through up to MAX_SEGMENTS − 1 mirror bounces and shades the
// first non-mirror surface: albedo × (hard sun shadow + ambient) + emission, Schlick
// weights on mirrors, the sky on a miss. Returns the colour and writes the first-hit
// record.
fn shade_path(primary: Ray, first: Hit, gb: ptr<function, vec4<u32>>) -> vec3<f32> {
    let c = first_hit_chain(primary, first, true);
    var light = vec3<f32>(0.0);
    var kind = KIND_DIFFUSE;
    var mat_id = 0u;
    var entity = NO_ENTITY;
    if c.end == CHAIN_SKY {
        light = c.throughput * sky(c.r.d / c.r.len);
    } else if c.end == CHAIN_SURFACE {
        let m = material(c.h.material);
        kind = m.kind;
        mat_id = c.h.material;
        entity = c.h.entity;
        let p = ray_local(c.r, c.h.t) + c.n * SURFACE_OFFSET;
        let lit = select(1.0, 0.0, occlusion(ray_at(c.r, p, view.sun)).x);
        let direct = 2.0 * max(dot(c.n, view.sun), 0.0) * lit;
        let ambient = 0.2 * max(dot(view.sun, normalize(c.n + 1.01 * view.sun)), 0.0);
        var col = m.albedo * (direct + ambient) * SUN_COLOR;
        if m.kind == KIND_EMISSIVE {
            col += m.albedo * m.emission;
        }
        light = c.throughput * col;
    }
    let dist_bits = pack2x16float(vec2<f32>(c.distance, 0.0)) & 0x7FFFu;
    *gb = vec4<u32>(
        entity | (c.planes[0] << 15u),
        select(0u, 1u, kind != KIND_METAL) | (c.planes[1] << 15u),
        mat_id | (c.planes[2] << 15u),
        dist_bits | (c.planes[3] << 15u),
    );
    return light;
}

@compute @workgroup_size(8, 8)
fn render(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= view.width || gid.y >= view.height {
        return;
    }
    let sx = 2.0 * (f32(gid.x) + 0.5) / f32(view.width) - 1.0;
    let sy = 1.0 - 2.0 * (f32(gid.y) + 0.5) / f32(view.height);
    let r = ray_new(view.cam_oi, view.cam_of, view.forward + sx * view.right + sy * view.up);
    let h = trace(r);
    // The diagnostic colour comes first: world_normal reads the entity rotation of the
    // last trace, which shade_path's shadow and mirror traces overwrite.
    var color = vec3<f32>(0.0);
    if view.mode == MODE_MATERIAL {
        color = select(vec3<f32>(0.0), srgb(material(h.material).albedo), h.hit);
    } else if view.mode == MODE_NORMAL {
        color = select(vec3<f32>(0.0), world_normal(h) * 0.5 + 0.5, h.hit);
    } else if view.mode == MODE_STEPS {
        color = heat(log2(1.0 + f32(h.steps)) * view.steps_scale);
    }
    var gb = vec4<u32>(0u);
    if view.mode == MODE_ALBEDO || (view.flags & 1u) != 0u {
        let shaded = srgb(tone_map(shade_path(r, h, &gb)));
        if view.mode == MODE_ALBEDO {
            color = shaded;
        }
    }
    let i = gid.x + gid.y * view.width;
    pixels[i] = pack_rgb(color);
    if (view.flags & 1u) != 0u {
        gbuffer[i] = gb;
    }
}

// The first-hit chain shared by `albedo` (render.wgsl) and `gi` (gi_primary.wgsl): a camera
// ray followed through up to MAX_SEGMENTS − 1 mirror bounces to the first surface that is
// not a mirror, with the bounce planes of the reference's first-hit record
// (docs/RENDERING.md §2, §3c).

// Hit-plane sentinels of the first-hit record (docs/NAADF.md §10).
const HIT_NOTHING: u32 = 0x1FFFFu;
const HIT_UNDEFINED: u32 = 0u;
// Mirror segments a path may follow (the primary segment included).
const MAX_SEGMENTS: u32 = 4u;
// Secondary-ray origins start SURFACE_OFFSET off the surface, along its normal
// (docs/NAADF.md §12; from the prelude).

// How a chain ended.
const CHAIN_SURFACE: u32 = 0u;
const CHAIN_SKY: u32 = 1u;
// The last segment allowed met a mirror too.
const CHAIN_LIMIT: u32 = 2u;

// The 17-bit hit plane: normal id (1 −x, 2 +x, 3 −y, 4 +y, 5 −z, 6 +z; 7 = origin inside
// the voxel) in bits 0–2, the plane's integer coordinate in bits 3–16.
fn encode_plane(h: Hit) -> u32 {
    if h.axis == NO_AXIS {
        return 7u;
    }
    let positive = h.normal[h.axis] > 0;
    let id = 2u * h.axis + select(1u, 2u, positive);
    let coord = u32(h.voxel[h.axis] + select(0, 1, positive)) & 0x3FFFu;
    return id | (coord << 3u);
}

struct Chain {
    // The last segment and what it met (`h.hit` is false for the sky).
    r: Ray,
    h: Hit,
    // The final surface's world normal (read right after its trace: world_normal reads the
    // entity rotation of the last trace).
    n: vec3<f32>,
    // The product of the mirror weights along the chain.
    throughput: vec3<f32>,
    planes: array<u32, 4>,
    // Path length to the final surface; −1 for the sky and the mirror limit.
    distance: f32,
    end: u32,
}

// Follows `primary` (whose first hit is `first`) through mirrors. A mirror weighs the path
// by Schlick's Fresnel with F0 = albedo when `schlick`, by its albedo otherwise (the light
// model's tinted mirror, docs/RENDERING.md §3a).
fn first_hit_chain(primary: Ray, first: Hit, schlick: bool) -> Chain {
    var c = Chain(primary, first, vec3<f32>(0.0), vec3<f32>(1.0),
        array<u32, 4>(HIT_UNDEFINED, HIT_UNDEFINED, HIT_UNDEFINED, HIT_UNDEFINED), 0.0, CHAIN_SURFACE);
    for (var seg = 0u; seg < MAX_SEGMENTS; seg++) {
        if seg > 0u {
            c.h = trace(c.r);
        }
        let dn = c.r.d / c.r.len;
        if !c.h.hit {
            c.planes[seg] = HIT_NOTHING;
            c.distance = -1.0;
            c.end = CHAIN_SKY;
            return c;
        }
        c.planes[seg] = encode_plane(c.h);
        c.distance += c.h.t * c.r.len;
        c.n = world_normal(c.h);
        let m = material(c.h.material);
        if m.kind != KIND_MIRROR {
            return c;
        }
        if seg + 1u == MAX_SEGMENTS {
            c.planes[seg] = HIT_NOTHING;
            c.distance = -1.0;
            c.end = CHAIN_LIMIT;
            return c;
        }
        if schlick {
            let cos_i = clamp(-dot(c.n, dn), 0.0, 1.0);
            c.throughput *= m.albedo + (1.0 - m.albedo) * pow(1.0 - cos_i, 5.0);
        } else {
            c.throughput *= m.albedo;
        }
        let p = ray_local(c.r, c.h.t) + c.n * SURFACE_OFFSET;
        c.r = ray_at(c.r, p, reflect(dn, c.n));
    }
    return c;
}

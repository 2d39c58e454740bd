// The irradiance cache as the diffuse tier of `irradiance` (docs/RENDERING.md §3e): the
// sample pass looks up (and keys) the entry of each diffuse world face it meets, requests
// it for the update pass, and lights the surface with the entry's mean; an entity surface,
// or a face whose entry has no samples yet, is lit by gathering. Included by the sample
// pass before light.wgsl's paths, with irradiance_table.wgsl.

@group(1) @binding(3) var<storage, read> irr: IrradianceInfo;
@group(1) @binding(4) var<storage, read_write> irr_table: array<atomic<u32>>;
@group(1) @binding(5) var<storage, read_write> irr_requests: array<atomic<u32>>;

const DIFFUSE_TIER: bool = true;

// The key of the face of world voxel `voxel` with outward normal `normal` (FaceKey::words).
fn irr_key(voxel: vec3<i32>, normal: vec3<i32>) -> vec2<u32> {
    let v = vec3<u32>(voxel);
    var face = 4u + select(0u, 1u, normal.z < 0);
    if normal.x != 0 {
        face = select(0u, 1u, normal.x < 0);
    } else if normal.y != 0 {
        face = 2u + select(0u, 1u, normal.y < 0);
    }
    return vec2<u32>(v.x | 0x8000u | (v.z << 16u), 0x80000000u | (face << 16u) | v.y);
}

// Sets word `at` to `value` if it is zero; returns what it held before (zero: this
// invocation wrote it). The weak exchange may fail spuriously, finding zero: it is retried.
fn irr_claim(at: u32, value: u32) -> u32 {
    var r = atomicCompareExchangeWeak(&irr_table[at], 0u, value);
    while !r.exchanged && r.old_value == 0u {
        r = atomicCompareExchangeWeak(&irr_table[at], 0u, value);
    }
    return r.old_value;
}

// The slot of `key`, keyed there when absent; IRR_NONE when IRR_PROBES slots were taken.
// Each word is claimed once, so two invocations with one key agree on its slot, and a key
// is never held twice.
fn irr_find(key: vec2<u32>) -> u32 {
    var slot = irr_stream(key) & irr.mask;
    for (var i = 0u; i < IRR_PROBES; i++) {
        let at = slot * IRR_WORDS;
        var a = atomicLoad(&irr_table[at]);
        if a == 0u {
            a = irr_claim(at, key.x);
            if a == 0u {
                a = key.x;
            }
        }
        if a == key.x {
            var b = atomicLoad(&irr_table[at + 1u]);
            if b == 0u {
                b = irr_claim(at + 1u, key.y);
                if b == 0u {
                    b = key.y;
                    atomicAdd(&irr_requests[IRR_OCCUPIED], 1u);
                }
            }
            if b == key.y {
                return slot;
            }
        }
        slot = (slot + 1u) & irr.mask;
    }
    return IRR_NONE;
}

// Asks the update pass to refresh `slot` this frame (once, however many pixels see it).
fn irr_request(slot: u32) {
    let at = slot * IRR_WORDS;
    if atomicExchange(&irr_table[at + 2u], irr.stamp) == irr.stamp {
        return;
    }
    let i = atomicAdd(&irr_requests[IRR_COUNT], 1u);
    if i < irr.max_requests {
        atomicStore(&irr_requests[IRR_LIST + i], slot);
    }
    if atomicLoad(&irr_table[at + 3u]) == 0u {
        atomicAdd(&irr_requests[IRR_FRESH], 1u);
    }
}

// The mean irradiance of `slot` (RGB) and its sample count (w; 0: none yet).
fn irr_mean(slot: u32) -> vec4<f32> {
    let at = slot * IRR_WORDS;
    let count = atomicLoad(&irr_table[at + 3u]);
    if count == 0u {
        return vec4<f32>(0.0);
    }
    let sum = vec3<f32>(
        bitcast<f32>(atomicLoad(&irr_table[at + 4u])),
        bitcast<f32>(atomicLoad(&irr_table[at + 5u])),
        bitcast<f32>(atomicLoad(&irr_table[at + 6u])),
    );
    return vec4<f32>(sum / f32(count), f32(count));
}

// The irradiance at world point `p` (just off a surface of normal `n`) by gathering: one
// sun sample, and π times the radiance of one cosine ray: the sky's, or the emission of
// the surface it meets plus, for a diffuse world face with samples, albedo/π times its
// entry (a face met is keyed and requested, as a face seen is).
fn irr_gather(p: vec3<f32>, n: vec3<f32>, rng: ptr<function, u32>) -> vec3<f32> {
    let base = ray_new(vec3<i32>(0), vec3<f32>(0.0), n);
    var e = vec3<f32>(sun_sample(base, p, n, rng).irradiance);
    let w = sample_cosine(n, vec2<f32>(rng_next(rng), rng_next(rng)));
    let h = trace(ray_at(base, p, w));
    if h.exhausted {
        return e;
    }
    if !h.hit {
        return e + PI * sky_radiance(w, false);
    }
    if h.axis == NO_AXIS {
        return e;
    }
    let m = material(h.material);
    var l = vec3<f32>(0.0);
    if m.kind == KIND_EMISSIVE {
        l += m.albedo * m.emission;
    }
    if h.entity == NO_ENTITY && m.kind != KIND_MIRROR && m.kind != KIND_METAL {
        // The face is near the view: it is keyed and requested too, so that the bounce
        // light of the next frames' gathers finds it.
        let slot = irr_find(irr_key(h.voxel, h.normal));
        if slot != IRR_NONE {
            irr_request(slot);
            l += m.albedo / PI * irr_mean(slot).xyz;
        }
    }
    return e + PI * l;
}

// The light of the diffuse surface of hit `h` at world point `p` with normal `n` (its
// emission excluded: the path adds it).
fn diffuse_tier(h: Hit, p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, rng: ptr<function, u32>) -> vec3<f32> {
    if h.entity == NO_ENTITY {
        let slot = irr_find(irr_key(h.voxel, h.normal));
        if slot != IRR_NONE {
            irr_request(slot);
            let e = irr_mean(slot);
            if e.w > 0.0 {
                return albedo / PI * e.xyz;
            }
        }
    }
    return albedo / PI * irr_gather(p + n * SURFACE_OFFSET, n, rng);
}

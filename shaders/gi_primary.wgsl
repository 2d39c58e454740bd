// The GI pipeline's per-pixel passes around the samples (docs/RENDERING.md §3c): the first
// hit, the long-term TAA's reprojection, and the TAA merge that stores this frame's sample.

// ---- The long-term TAA's 64-bit samples ----
//
// x: the chain length as f16 without its sign bit (15 bits) | the hash << 16.
// y: R, G, B in 8 bits each on a log scale (c = 12·log2(x/100 + 2^(−255/12)) + 255,
//    c = 0 is black, a step is 5.9 %) | normal id << 24 | cls << 27.

const TAA_LOG_FLOOR: f32 = 4.1529e-7; // 2^(−255/12)
const TAA_MAX: f32 = 100.0;
// How far (pixels) a history sample may land from this pixel's sample when reprojected back.
const TAA_RADIUS: f32 = 1.0;

fn taa_read(slot: u32, pixel: u32) -> vec2<u32> {
    let i = slot * pixel_count() + pixel;
    return taa_get(i);
}

fn taa_write(slot: u32, pixel: u32, v: vec2<u32>) {
    let i = slot * pixel_count() + pixel;
    taa_set(i, v);
}

// One channel on the log scale, rounded to the level below or above at random (`u`
// uniform in [0, 1)) with the odds that make the decoded value's mean exactly `x`: the
// TAA's mean is then unbiased in linear light (rounding by the fraction of the log-scale
// position is unbiased in the log domain only, and the decoding's convexity makes that
// brighter on average).
fn taa_channel(x: f32, u: f32) -> u32 {
    if x <= 0.0 {
        return 0u;
    }
    let c = clamp(12.0 * log2(x / TAA_MAX + TAA_LOG_FLOOR) + 255.0, 0.0, 255.0);
    let lo = u32(floor(c));
    if lo >= 255u {
        return 255u;
    }
    let below = taa_decode_channel(lo);
    let above = taa_decode_channel(lo + 1u);
    return select(lo, lo + 1u, u * (above - below) < x - below);
}

fn taa_decode_channel(c: u32) -> f32 {
    if c == 0u {
        return 0.0;
    }
    return max(TAA_MAX * (exp2((f32(c) - 255.0) / 12.0) - TAA_LOG_FLOOR), 0.0);
}

fn taa_colour(y: u32) -> vec3<f32> {
    return vec3<f32>(taa_decode_channel(y & 0xFFu), taa_decode_channel((y >> 8u) & 0xFFu), taa_decode_channel((y >> 16u) & 0xFFu));
}

fn taa_distance(x: u32) -> f32 {
    return unpack2x16float(x & 0x7FFFu).x;
}

// ---- Pass gi_first_hit ----

@compute @workgroup_size(8, 8)
fn gi_first_hit(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let i = gid.x + gid.y * frame.width;
    let r = ray_new(frame.cam_int, frame.cam_frac, camera_dir(frame, gid.xy, vec2<f32>(gi.jitter_x, gi.jitter_y)));
    let c = first_hit_chain(r, trace(r), false);
    let dn = c.r.d / c.r.len;
    var emit = vec3<f32>(0.0);
    var thr = c.throughput;
    var kind = KIND_DIFFUSE;
    var cls = CLASS_NONE;
    var nid = NO_NORMAL;
    var mat_id = 0u;
    var entity = NO_ENTITY;
    var p = vec3<f32>(0.0);
    // A ray that ran out of steps brings no light, as in the path tracer.
    if c.end == CHAIN_SKY && !c.h.exhausted {
        // Evaluated directly, not from the table: a camera ray's sky is seen as it is,
        // and the table's interpolation error would show across every sky pixel.
        emit = c.throughput * (sky_direct(dn) + sun_disc(dn));
    } else if c.end == CHAIN_SURFACE {
        let m = material(c.h.material);
        kind = m.kind;
        mat_id = c.h.material;
        entity = c.h.entity;
        nid = normal_id(c.n);
        p = vec3<f32>(c.r.o_int - frame.cam_int) + ray_local(c.r, c.h.t);
        if m.kind == KIND_EMISSIVE {
            emit = c.throughput * m.albedo * m.emission;
        }
        if m.kind == KIND_METAL {
            cls = CLASS_GLOSSY;
        } else {
            cls = CLASS_DIFFUSE;
            thr *= m.albedo;
        }
    }
    // The hash of what the pixel sees, for the TAA: its cls, its entity and the normals
    // of the mirrors on the way (docs/RENDERING.md §3c).
    var key = cls | (entity << 2u);
    for (var s = 0u; s < MAX_SEGMENTS - 1u; s++) {
        let next = c.planes[s + 1u];
        if next != HIT_UNDEFINED {
            key = pcg_hash(key ^ ((c.planes[s] & 7u) << (3u * s)));
        }
    }
    let hash = pcg_hash(key ^ nid) & 0xFFFFu;
    mem_set(gi.off_gbuf + i, bitcast<vec4<u32>>(vec4<f32>(p, c.distance)));
    let wo = oct_encode(-dn);
    mem_set(gi.off_gmat + i, vec4<u32>(
        kind | (cls << 4u) | (nid << 8u) | (mat_id << 16u),
        hash | (oct_encode(c.n) << 16u),
        pack2x16float(thr.rg),
        (pack2x16float(vec2<f32>(thr.b, 0.0)) & 0xFFFFu) | (wo << 16u),
    ));
    // The entity the pixel sees directly (not in a mirror), whose poses the TAA follows.
    var seen = NO_ENTITY;
    if c.end == CHAIN_SURFACE && c.planes[1] == HIT_UNDEFINED {
        seen = entity;
    }
    mem_set(gi.off_emitted + i, bitcast<vec4<u32>>(vec4<f32>(emit, f32(seen))));
}

// ---- Pass gi_taa: the long-term TAA's gather ----

fn chain_length(i: u32) -> f32 {
    let d = bitcast<vec4<f32>>(mem_get(gi.off_gbuf + i)).w;
    return select(d, SKY_DIST, d < 0.0);
}

fn hash_at(i: u32) -> u32 {
    return mem_get(gi.off_gmat + i).y & 0xFFFFu;
}

@compute @workgroup_size(8, 8)
fn gi_taa(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let i = gid.x + gid.y * frame.width;
    let d = chain_length(i);
    var lo = d;
    var hi = d;
    var hashes = array<u32, 9>(0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u);
    var k = 0u;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let x = clamp(i32(gid.x) + dx, 0, i32(frame.width) - 1);
            let y = clamp(i32(gid.y) + dy, 0, i32(frame.height) - 1);
            let j = u32(x) + u32(y) * frame.width;
            lo = min(lo, chain_length(j));
            hi = max(hi, chain_length(j));
            hashes[k] = hash_at(j);
            k++;
        }
    }
    mem_set(gi.off_taa_info + 2u * i + 1u, bitcast<vec4<u32>>(vec4<f32>(lo, hi, 0.0, 0.0)));
    let sky = d >= SKY_DIST;
    // The point the pixel sees along its unjittered ray, relative to this frame's integer
    // camera position like the cameras (the sky: its direction).
    let dir = normalize(camera_dir(frame, gid.xy, vec2<f32>(0.5)));
    let here = cam(0u);
    var point = here.pos + dir * d;
    if sky {
        point = dir;
    }
    // An entity seen directly: its samples of earlier frames are found where its pose of
    // that frame put the point.
    let seen = u32(bitcast<vec4<f32>>(mem_get(gi.off_emitted + i)).w);
    let follow = seen != NO_ENTITY && !sky;
    var pose_now = Pose(vec3<f32>(0.0), vec4<f32>(0.0, 0.0, 0.0, 1.0));
    if follow {
        pose_now = pose_of(pose_words(gi.taa_slot, seen));
    }
    // How recently the pixel's surface changed, or light near it (none for the sky).
    var marks = vec2<u32>(0u);
    if !sky {
        marks = changes_at(bitcast<vec4<f32>>(mem_get(gi.off_gbuf + i)).xyz, surface_normal(mem_get(gi.off_gmat + i)));
    }
    let edit = max(gi.edit_frame, marks.y);
    var sum = vec3<f32>(0.0);
    var count = 0.0;
    for (var age = 1u; age <= gi.taa_valid; age++) {
        let taken = gi.frame - age;
        // A sample from before the surface's own chunk changed shows what is gone (an
        // entity's own moves change its chunks: its history follows its poses instead).
        if taken < marks.x && !follow {
            break;
        }
        // Light from before a world change near the surface (or a change of the
        // materials) fades out within EDIT_HISTORY_FRAMES frames; so does light resampled
        // from the ring while it still held samples from before the change (the first
        // EDIT_HISTORY_FRAMES frames after it).
        if edit > 0u && taken < edit + EDIT_HISTORY_FRAMES && age > EDIT_HISTORY_FRAMES {
            break;
        }
        let c = cam(age);
        // Where the point was then: an entity's moves carry it.
        var then = point;
        var pose_then = pose_now;
        if follow {
            let w = pose_words((gi.taa_slot + TAA_SLOTS - age) % TAA_SLOTS, seen);
            // The entity did not exist then.
            if all(w == vec4<u32>(0u)) {
                break;
            }
            pose_then = pose_of(w);
            then = carry(point, pose_now, pose_then);
        }
        // From the same view, with nothing in the world changed since, the pixel's own
        // sample shows its footprint at that frame's jitter: it counts as it is. A pixel
        // that spans several voxels (a small model, a far wall) needs every one of its 32
        // jitters: the tests below would keep only those near the surface this frame's
        // jitter hit. A change anywhere ends this: a block removed in front of a far wall,
        // or an entity moved away from a floor, changes no chunk near the surface that
        // the pixel sees now, and yet its earlier samples show what was there.
        let still = same_view(c, here) && taken >= gi.change_frame;
        var qp = gid.xy;
        if !still {
            var v = then;
            if !sky {
                v = then - c.pos;
            }
            let pr = project(c, v);
            let q = pr.px - c.jitter + 0.5;
            if pr.z <= 0.0 || !on_image(q) {
                continue;
            }
            qp = vec2<u32>(q);
        }
        let s = taa_read((gi.taa_slot + TAA_SLOTS - age) % TAA_SLOTS, qp.x + qp.y * frame.width);
        if s.y == 0u && s.x == 0u {
            continue;
        }
        if still {
            sum += taa_colour(s.y);
            count += 1.0;
            continue;
        }
        let sd = taa_distance(s.x);
        let shash = s.x >> 16u;
        // A sample may show any of the 3×3 neighbours' surfaces (the pixel's footprint
        // straddles an edge across the jitters), except one from before a world change:
        // an entity that moved in (or a block placed) would take the old surface's
        // samples where its edge is, so those must show this pixel's own surface.
        var same = shash == hashes[4];
        if edit == 0u || taken >= edit {
            for (var h = 0u; h < 9u; h++) {
                same = same || shash == hashes[h];
            }
        }
        if !same {
            continue;
        }
        // Where the old sample's surface was (or, for the sky, its direction), seen from
        // this camera. On a silhouette the sky and the ground each keep their share: a
        // sample of either kind counts when the 3×3 neighbourhood still holds its kind
        // and it lands on this pixel.
        var back: Projection;
        let old_dir = normalize(cam_dir(c, qp));
        if sd >= SKY_DIST {
            if hi < SKY_DIST {
                continue;
            }
            back = project(here, old_dir);
        } else {
            var old = c.pos + old_dir * sd;
            if follow {
                old = carry(old, pose_then, pose_now);
            }
            let dist = length(old - here.pos);
            if dist < lo * (1022.0 / 1024.0) || dist > hi * (1026.0 / 1024.0) || sd > 2.0 * hi {
                continue;
            }
            back = project(here, old - here.pos);
        }
        let off = back.px - (vec2<f32>(gid.xy) + vec2<f32>(gi.jitter_x, gi.jitter_y));
        if back.z <= 0.0 || dot(off, off) > TAA_RADIUS * TAA_RADIUS {
            continue;
        }
        sum += taa_colour(s.y);
        count += 1.0;
    }
    mem_set(gi.off_taa_info + 2u * i, bitcast<vec4<u32>>(vec4<f32>(sum, count)));
}

// ---- Pass gi_merge: this frame's colour, its TAA sample and the result ----

@compute @workgroup_size(8, 8)
fn gi_merge(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let i = gid.x + gid.y * frame.width;
    let g = mem_get(gi.off_gmat + i);
    let thr = vec3<f32>(unpack2x16float(g.z), unpack2x16float(g.w).x);
    let colour = bitcast<vec4<f32>>(mem_get(gi.off_emitted + i)).rgb + thr * bitcast<vec4<f32>>(mem_get(gi.off_illum + i)).rgb;
    var rng = rng_new(frame.seed ^ 0x5A17u, i, gi.frame);
    var c = colour;
    let peak = max(c.r, max(c.g, c.b));
    if peak > TAA_MAX {
        c *= TAA_MAX / peak;
    }
    let y = taa_channel(c.r, rng_next(&rng)) | (taa_channel(c.g, rng_next(&rng)) << 8u)
        | (taa_channel(c.b, rng_next(&rng)) << 16u) | (((g.x >> 8u) & 7u) << 24u) | (((g.x >> 4u) & 3u) << 27u);
    let dist = chain_length(i);
    let x = (pack2x16float(vec2<f32>(dist, 0.0)) & 0x7FFFu) | ((g.y & 0xFFFFu) << 16u);
    taa_write(gi.taa_slot, i, vec2<u32>(x, y));
    let a = taa_accum(i);
    mem_set(gi.off_result + i, bitcast<vec4<u32>>(vec4<f32>((a.rgb + colour) / (a.w + 1.0), dist)));
}

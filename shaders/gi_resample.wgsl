// The GI pipeline's per-pixel shading (docs/RENDERING.md §3c): spatial resampling of the
// regions' refined samples with one visibility ray, the sun by next-event estimation, and
// the separable sparse bilateral denoiser.

// Candidates per pixel: half in the small window, half in the large one.
const CANDIDATES: u32 = 12u;
// The large window's side as a fraction of the image height; the small one's as a
// fraction of the large one's.
const WINDOW: f32 = 0.35;
const SMALL_WINDOW: f32 = 0.1;
// The denoiser: taps each side at DENOISE_HEIGHT rows (the paper's 1440p; fewer in
// proportion on smaller images, so that it covers the same share of the picture), the
// Gaussian's σ as a share of its reach, the guide's strength, and how much of the
// filtered value it keeps. The taps are 2 px apart.
const DENOISE_TAPS: f32 = 10.0;
const DENOISE_HEIGHT: f32 = 1440.0;
const DENOISE_SIGMA: f32 = 1.0;
const DENOISE_GUIDE: f32 = 8.0;
const DENOISE_BLEND: f32 = 0.92;
// How much nearer than a surface sample (in voxels, before the 4 % margin) the visibility
// ray may stop and still see it: a ray toward a voxel face at a grazing angle often clips
// the neighbouring voxel's edge first.
const VISIBLE_SLACK: f32 = 1.0;

// A coordinate mirrored back into [0, size).
fn mirrored(v: i32, size: i32) -> u32 {
    var x = v;
    if x < 0 {
        x = -x;
    }
    if x >= size {
        x = 2 * size - 2 - x;
    }
    return u32(clamp(x, 0, size - 1));
}

struct Candidate {
    // The integrand (radiance × BRDF × cos) toward the sample, its direction and distance.
    f: vec3<f32>,
    dir: vec3<f32>,
    distance: f32,
    sky: bool,
    goal: f32,
}

// The light a diffuse surface at `p` (normal `n`, id `nid`) of pixel `gid` reflects (before
// its albedo), by resampling the regions' refined samples; w is 0 when no candidate could
// speak for this surface (no estimate, which is not the same as darkness).
fn resampled(gid: vec2<u32>, p: vec3<f32>, n: vec3<f32>, nid: u32, dist_here: f32, rng: ptr<function, u32>) -> vec4<f32> {
    let origin = p + n * (2.0 * SURFACE_OFFSET);
    let base = ray_new(frame.cam_int, vec3<f32>(0.0), n);
    let big = WINDOW * f32(frame.height);
    var wsum = 0.0;
    var count = 0u;
    var chosen = Candidate(vec3<f32>(0.0), n, 0.0, true, 0.0);
    for (var c = 0u; c < CANDIDATES; c++) {
        let side = select(big, big * SMALL_WINDOW, c < CANDIDATES / 2u);
        let off = (vec2<f32>(rng_next(rng), rng_next(rng)) - 0.5) * side;
        let qx = mirrored(i32(gid.x) + i32(round(off.x)), i32(frame.width));
        let qy = mirrored(i32(gid.y) + i32(round(off.y)), i32(frame.height));
        let region = region_of(qx, qy);
        let ratios = bitcast<vec4<f32>>(mem_get(gi.off_region_info + 3u * region));
        let info = bitcast<vec4<f32>>(mem_get(gi.off_region_info + 3u * region + 1u));
        let shape = bitcast<vec4<f32>>(mem_get(gi.off_region_info + 3u * region + 2u));
        let pick = rng_next(rng);
        // A region with no samples says nothing; one whose surfaces differ from this one
        // does not speak for it.
        if info.w == 0.0 || (u32(shape.x) & (1u << nid)) == 0u || dist_here < 0.5 * shape.y || dist_here > 2.0 * shape.z {
            continue;
        }
        let kept = u32(info.z);
        if kept == 0u {
            // Every sample of the region was unlit: a zero that counts.
            count++;
            continue;
        }
        // One of the region's kept samples drawn by a surface facing this way (the others
        // were drawn from other distributions and do not speak for this surface).
        var matching = 0u;
        for (var k = 0u; k < kept; k++) {
            matching += select(0u, 1u, ((mem_get(gi.off_refined + 2u * (region * MAX_KEPT + k)).w >> 4u) & 7u) == nid);
        }
        if matching == 0u {
            continue;
        }
        var want = min(u32(pick * f32(matching)), matching - 1u);
        var at = 0u;
        for (var k = 0u; k < kept; k++) {
            let here_at = 2u * (region * MAX_KEPT + k);
            if ((mem_get(gi.off_refined + here_at).w >> 4u) & 7u) == nid {
                if want == 0u {
                    at = here_at;
                    break;
                }
                want--;
            }
        }
        let r0 = mem_get(gi.off_refined + at);
        let r1 = mem_get(gi.off_refined + at + 1u);
        let sky = (r0.w & 1u) != 0u;
        var dir = bitcast<vec4<f32>>(r0).xyz;
        var distance = 0.0;
        var jac = 1.0;
        if !sky {
            let v = dir - origin;
            distance = length(v);
            dir = v / max(distance, 1e-6);
            jac = abs(dot(oct_decode(r0.w >> 16u), dir)) / max(distance * distance, 1e-8) / max(bitcast<f32>(r1.w), 1e-12);
            if jac < 0.3 || jac > 2.5 {
                continue;
            }
        }
        let cos_now = dot(n, dir);
        let pdf_then = bitcast<f32>(r1.z);
        if cos_now <= 1e-4 || pdf_then < 0.01 {
            continue;
        }
        let f = cos_now / PI;
        let ratio = f / pdf_then;
        if ratio < 0.25 || ratio > 2.0 {
            continue;
        }
        var lit_ratio = info.x;
        if nid < 4u {
            lit_ratio = ratios[nid];
        } else if nid == 5u {
            lit_ratio = info.y;
        }
        let colour = vec3<f32>(unpack2x16float(r1.x), unpack2x16float(r1.y).x) * lit_ratio;
        let fc = colour * f;
        let goal = luminance(fc);
        if goal <= 0.0 {
            continue;
        }
        count++;
        let w = goal / pdf_then * jac;
        wsum += w;
        if rng_next(rng) * wsum < w {
            chosen = Candidate(fc, dir, distance, sky, goal);
        }
    }
    if wsum > 0.0 {
        // One visibility ray toward the chosen sample.
        let h = trace(ray_at(base, origin, chosen.dir));
        var visible = !h.hit && !h.exhausted;
        if !chosen.sky {
            visible = h.hit && (h.t * length(chosen.dir) + VISIBLE_SLACK) * 1.04 >= chosen.distance;
        }
        if visible {
            return vec4<f32>(chosen.f * (wsum / (f32(count) * chosen.goal)), 1.0);
        }
    }
    return vec4<f32>(0.0, 0.0, 0.0, select(0.0, 1.0, count > 0u));
}

// ---- Pass gi_resample ----
@compute @workgroup_size(8, 8)
fn gi_resample(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let i = gid.x + gid.y * frame.width;
    let g = mem_get(gi.off_gmat + i);
    let cls = surface_class(g);
    let a = taa_accum(i);
    let thr = vec3<f32>(unpack2x16float(g.z), unpack2x16float(g.w).x);
    if cls == CLASS_NONE || light.bounces == 0u {
        mem_set(gi.off_illum + i, bitcast<vec4<u32>>(vec4<f32>(0.0)));
        return;
    }
    let p = bitcast<vec4<f32>>(mem_get(gi.off_gbuf + i)).xyz;
    let dist_here = bitcast<vec4<f32>>(mem_get(gi.off_gbuf + i)).w;
    let n = surface_normal(g);
    let nid = surface_normal_id(g);
    let m = material(g.x >> 16u);
    let alpha = max(m.roughness, MIN_ALPHA);
    let wo = oct_decode(g.w >> 16u);
    let base = ray_new(frame.cam_int, vec3<f32>(0.0), n);
    var rng = rng_new(frame.seed ^ 0x2E5Au, i, gi.frame);
    var light_in = vec3<f32>(0.0);
    // A metal traces its own path every frame: its lobe depends on the view, so its
    // neighbours' samples rarely serve it. So does a diffuse surface that no candidate
    // could speak for (rather than count as dark).
    var own = cls == CLASS_GLOSSY;
    if !own {
        let mine = mem_get(gi.off_own + i);
        if mine.w == gi.frame + 1u {
            // The pixel traced its own secondary path this frame (gi_queue): an unbiased
            // estimate of its own light.
            light_in = bitcast<vec3<f32>>(mine.xyz);
        } else {
            let r = resampled(gid.xy, p, n, nid, dist_here, &rng);
            light_in = r.rgb;
            own = r.w == 0.0;
        }
    }
    if own {
        let u = vec2<f32>(rng_next(&rng), rng_next(&rng));
        var s = Scattered(sample_cosine(n, u), vec3<f32>(1.0));
        if cls == CLASS_GLOSSY {
            s = ggx_sample(n, wo, alpha, m.albedo, u);
        }
        if dot(s.dir, n) > 0.0 {
            let r = ray_at(base, p + n * SURFACE_OFFSET, s.dir);
            light_in = s.weight * path_radiance(r, light.bounces - 1u, false, &rng).radiance;
        }
    }
    // The sun, by next-event estimation over its disc.
    if light.sun_on != 0u {
        let u = vec2<f32>(rng_next(&rng), rng_next(&rng));
        let wi = sample_cone(light.sun_dir, light.sun_omc, u);
        let c = dot(n, wi);
        if c > 0.0 && !blocked(base, p + n * SURFACE_OFFSET, wi) {
            var f = vec3<f32>(1.0 / PI);
            if cls == CLASS_GLOSSY {
                f = ggx(n, wo, wi, alpha, m.albedo);
            }
            light_in += f * (c * light.sun_weight);
        }
    }
    // The denoiser's guide: the TAA's brightness without the surface's colour.
    var guide = luminance(light_in);
    if a.w > 1.0 {
        guide = luminance(a.rgb / a.w) / (luminance(thr) + 0.01);
    }
    mem_set(gi.off_illum + i, bitcast<vec4<u32>>(vec4<f32>(light_in, guide)));
}

// ---- Passes gi_denoise_x and gi_denoise_y ----

// The weight of tap `j` for pixel `i`: the same plane and cls, a close guide value, and
// a Gaussian in `k`, the tap's place in the filter's reach (−1 to 1).
fn denoise_weight(i: u32, j: u32, k: f32, gi_: f32, gj: f32) -> f32 {
    let a = mem_get(gi.off_gmat + i);
    let b = mem_get(gi.off_gmat + j);
    if surface_class(a) != surface_class(b) || surface_normal_id(a) != surface_normal_id(b) {
        return 0.0;
    }
    if abs(dot(surface_normal(a), bitcast<vec4<f32>>(mem_get(gi.off_gbuf + j)).xyz - bitcast<vec4<f32>>(mem_get(gi.off_gbuf + i)).xyz)) > 0.05 {
        return 0.0;
    }
    let kk = k / DENOISE_SIGMA;
    return exp(-0.5 * kk * kk) / (1.0 + DENOISE_GUIDE * abs(gj - gi_) / (gi_ + gj + 0.01));
}

// The tap at `k` along `axis` from `gid`, shifted sideways by one pixel half the time.
fn denoise_tap(gid: vec2<u32>, k: i32, axis: u32, rng: ptr<function, u32>) -> u32 {
    var q = vec2<i32>(gid);
    var side = 0;
    if k != 0 && rng_next(rng) < 0.5 {
        side = select(-1, 1, rng_next(rng) < 0.5);
    }
    q[axis] += 2 * k;
    q[1u - axis] += side;
    let x = clamp(q.x, 0, i32(frame.width) - 1);
    let y = clamp(q.y, 0, i32(frame.height) - 1);
    return u32(x) + u32(y) * frame.width;
}

// One denoiser pass along `axis` (0: x, 1: y) from the `mem` array at `src` to the one at
// `dst`: each pixel blended toward the weighted mean of its taps, with the mean guide
// value; `salt` picks the pass's random stream.
fn denoise_pass(gid: vec3<u32>, axis: u32, src: u32, dst: u32, salt: u32) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let i = gid.x + gid.y * frame.width;
    let here = bitcast<vec4<f32>>(mem_get(src + i));
    var rng = rng_new(frame.seed ^ salt, i, gi.frame);
    var sum = vec4<f32>(0.0);
    var wsum = 0.0;
    let taps = i32(round(min(DENOISE_TAPS * f32(frame.height) / DENOISE_HEIGHT, DENOISE_TAPS)));
    // Only diffuse light is denoised: a metal's own path is view-dependent, and spreading
    // its sun glints would brighten its whole surface.
    if surface_class(mem_get(gi.off_gmat + i)) == CLASS_DIFFUSE && taps > 0 {
        for (var k = -taps; k <= taps; k++) {
            let j = denoise_tap(gid.xy, k, axis, &rng);
            let v = bitcast<vec4<f32>>(mem_get(src + j));
            let w = denoise_weight(i, j, f32(k) / f32(taps), here.w, v.w);
            sum += v * w;
            wsum += w;
        }
    }
    var out = here;
    if wsum > 0.0 {
        out = vec4<f32>(mix(here.rgb, sum.rgb / wsum, DENOISE_BLEND), sum.w / wsum);
    }
    mem_set(dst + i, bitcast<vec4<u32>>(out));
}

@compute @workgroup_size(8, 8)
fn gi_denoise_x(@builtin(global_invocation_id) gid: vec3<u32>) {
    denoise_pass(gid, 0u, gi.off_illum, gi.off_illum2, 0xD0E1u);
}

@compute @workgroup_size(8, 8)
fn gi_denoise_y(@builtin(global_invocation_id) gid: vec3<u32>) {
    denoise_pass(gid, 1u, gi.off_illum2, gi.off_illum, 0xD0E2u);
}

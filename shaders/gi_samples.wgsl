// The GI pipeline's secondary samples (docs/RENDERING.md §3c): the ray queue, the secondary
// rays, and the region projection that gathers the samples of earlier frames into this
// frame's 8×8 regions, then refines each region to at most MAX_KEPT samples.
//
// A ring sample is RING_VEC4 = 3 vec4<u32>:
// 0: the primary surface point (relative to its frame's integer camera position), frame;
// 1: the sample point (same frame; for the sky: the direction), flags: sky | cls << 1 |
//    primary normal id << 4 | octahedral normal at the sample point << 16;
// 2: the radiance that came back along the secondary ray, the pdf it was drawn with.

var<workgroup> wg_flags: array<u32, 64>;
var<workgroup> wg_offsets: array<u32, 64>;
var<workgroup> wg_scan: array<u32, 256>;

const NO_PRIORITY: u32 = 0xFFFFFFFFu;

// Offsets in `buckets`.
fn bucket_priority(region: u32, slot: u32) -> u32 {
    return region * BUCKET_SLOTS + slot;
}

fn bucket_index(region: u32, slot: u32) -> u32 {
    return (region_count() + region) * BUCKET_SLOTS + slot;
}

// The lit and unlit counts of `region`, per normal id: lit at + 2·id, unlit at + 2·id + 1.
fn bucket_counts(region: u32) -> u32 {
    return 2u * region_count() * BUCKET_SLOTS + 2u * NORMALS * region;
}

// ---- Pass gi_queue: which pixels trace a secondary ray this frame ----
//
// One workgroup per region. A pixel with m − 1 accepted TAA samples (m ≤ QUEUE_PERIOD) is
// traced one frame in m, on a pattern that rotates every frame for every m:
// (frame + x + 2y) mod m. A traced pixel's path is also its own light that frame.
// The region's queued pixels are compacted in pixel order, so the queue is the same on
// every run. The pass also clears the region's buckets for the projection.
@compute @workgroup_size(8, 8)
fn gi_queue(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wid: vec3<u32>) {
    let region = wid.x + wid.y * gi.regions_x;
    if li < BUCKET_SLOTS {
        atomicStore(&buckets[bucket_priority(region, li)], NO_PRIORITY);
    }
    if li < 2u * NORMALS {
        atomicStore(&buckets[bucket_counts(region) + li], 0u);
    }
    var queued = 0u;
    let i = gid.x + gid.y * frame.width;
    // Only diffuse surfaces share samples; a metal traces its own (gi_resample.wgsl).
    if gid.x < frame.width && gid.y < frame.height && light.bounces > 0u && surface_class(mem_get(gi.off_gmat + i)) == CLASS_DIFFUSE {
        let m = u32(min(taa_accum(i).w, f32(QUEUE_PERIOD - 1u))) + 1u;
        if (gi.frame + gid.x + 2u * gid.y) % m == 0u {
            queued = 1u;
        }
    }
    wg_flags[li] = queued;
    workgroupBarrier();
    if li == 0u {
        var sum = 0u;
        for (var k = 0u; k < 64u; k++) {
            wg_offsets[k] = sum;
            sum += wg_flags[k];
        }
        words[CONTROL_WORDS + region] = sum;
    }
    workgroupBarrier();
    if queued == 1u {
        words[gi.off_queue_list + region * 64u + wg_offsets[li]] = i;
    }
}

// Indirect arguments for `groups` workgroups at `at`: 2D when over 65,535 (wgpu zeroes a
// larger 1D indirect dispatch).
fn write_args(at: u32, groups: u32) {
    words[at] = min(groups, 65535u);
    words[at + 1u] = max((groups + 65534u) / 65535u, 1u);
    words[at + 2u] = 1u;
}

// ---- Pass gi_queue_scan: one workgroup ----
//
// Prefix sums of the regions' queue counts (the queue's layout), this frame's place in the
// sample ring, how many ring samples the projection reads, and both indirect dispatches.
@compute @workgroup_size(256)
fn gi_queue_scan(@builtin(local_invocation_index) li: u32) {
    let regions = region_count();
    var carry = 0u;
    for (var base = 0u; base < regions; base += 256u) {
        let r = base + li;
        var v = 0u;
        if r < regions {
            v = words[CONTROL_WORDS + r];
        }
        wg_scan[li] = v;
        workgroupBarrier();
        for (var off = 1u; off < 256u; off <<= 1u) {
            var add = 0u;
            if li >= off {
                add = wg_scan[li - off];
            }
            workgroupBarrier();
            wg_scan[li] += add;
            workgroupBarrier();
        }
        if r < regions {
            words[CONTROL_WORDS + regions + r] = carry + wg_scan[li] - v;
        }
        carry += wg_scan[255];
        workgroupBarrier();
    }
    if li != 0u {
        return;
    }
    let cap = gi.ring_capacity;
    let total = carry;
    let stored = min(total, cap);
    let start = words[CONTROL_HEAD];
    words[CONTROL_QUEUED] = total;
    words[CONTROL_START] = start;
    words[CONTROL_HEAD] = (start + stored) % cap;
    words[CONTROL_FRAMES + gi.frame % CAMERA_HISTORY] = stored;
    // The newest frames whose samples all fit in the ring (and are still valid).
    var valid = 0u;
    for (var age = 0u; age <= cams_valid(); age++) {
        if gi.frame - age < gi.edit_frame && age > EDIT_HISTORY_FRAMES {
            break;
        }
        let n = words[CONTROL_FRAMES + (gi.frame - age) % CAMERA_HISTORY];
        if valid + n > cap {
            break;
        }
        valid += n;
    }
    words[CONTROL_VALID] = valid;
    write_args(CONTROL_TRACE_ARGS, (stored + 63u) / 64u);
    write_args(CONTROL_PROJECT_ARGS, (valid + 63u) / 64u);
}

// ---- Pass gi_trace: one secondary path per queued pixel ----
@compute @workgroup_size(64)
fn gi_trace(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) li: u32) {
    let t = flat_id(wid, groups, li);
    if t >= min(words[CONTROL_QUEUED], gi.ring_capacity) {
        return;
    }
    // The region holding queue entry t: the last one starting at or before it.
    let regions = region_count();
    var lo = 0u;
    var hi = regions - 1u;
    while lo < hi {
        let mid = (lo + hi + 1u) / 2u;
        if words[CONTROL_WORDS + regions + mid] <= t {
            lo = mid;
        } else {
            hi = mid - 1u;
        }
    }
    let pixel = words[gi.off_queue_list + lo * 64u + t - words[CONTROL_WORDS + regions + lo]];
    // Seeded by the pixel and the frame, never by the queue slot.
    var rng = rng_new(frame.seed, pixel, gi.frame);
    let g = mem_get(gi.off_gmat + pixel);
    let p = bitcast<vec4<f32>>(mem_get(gi.off_gbuf + pixel)).xyz;
    let n = surface_normal(g);
    let cls = surface_class(g);
    let origin = p + n * SURFACE_OFFSET;
    let dir = sample_cosine(n, vec2<f32>(rng_next(&rng), rng_next(&rng)));
    let pdf = max(dot(n, dir), 0.0) / PI;
    var s = PathSample(vec3<f32>(0.0), -1.0, n);
    if pdf > 0.0 {
        let base = ray_new(frame.cam_int, vec3<f32>(0.0), dir);
        s = path_radiance(ray_at(base, origin, dir), light.bounces - 1u, false, &rng);
    }
    let sky = s.distance < 0.0;
    var point = dir;
    var ns = n;
    if !sky {
        point = origin + dir * s.distance;
        ns = s.normal;
    }
    let idx = (words[CONTROL_START] + t) % gi.ring_capacity;
    mem_set(gi.off_ring + RING_VEC4 * idx, vec4<u32>(bitcast<vec3<u32>>(p), gi.frame));
    mem_set(gi.off_ring + RING_VEC4 * idx + 1u, vec4<u32>(bitcast<vec3<u32>>(point),
        select(0u, 1u, sky) | (cls << 1u) | (surface_normal_id(g) << 4u) | (oct_encode(ns) << 16u)));
    let radiance = bitcast<vec3<u32>>(max(s.radiance, vec3<f32>(0.0)));
    mem_set(gi.off_ring + RING_VEC4 * idx + 2u, vec4<u32>(radiance, bitcast<u32>(pdf)));
    // The pixel's own estimate of its incoming light this frame (cosine-weighted, so the
    // radiance itself), tagged with the frame + 1 (the array starts zeroed).
    mem_set(gi.off_own + pixel, vec4<u32>(radiance, gi.frame + 1u));
}

// ---- Passes gi_project and gi_project_store: the ring's samples into this frame's regions ----

struct Projected {
    ok: bool,
    region: u32,
    // The primary surface's normal id.
    nid: u32,
    lit: bool,
    priority: u32,
    idx: u32,
}

// Ring sample number `t` counting back from the newest, projected into this frame: its
// primary surface must land on a pixel of the same cls and normal, on the same plane.
fn project_sample(t: u32) -> Projected {
    let none = Projected(false, 0u, 0u, false, NO_PRIORITY, 0u);
    if t >= words[CONTROL_VALID] {
        return none;
    }
    let cap = gi.ring_capacity;
    let newest = (words[CONTROL_START] + min(words[CONTROL_QUEUED], cap) + cap - 1u) % cap;
    let idx = (newest + cap - t) % cap;
    let e0 = mem_get(gi.off_ring + RING_VEC4 * idx);
    let e1 = mem_get(gi.off_ring + RING_VEC4 * idx + 1u);
    let age = gi.frame - e0.w;
    if age > cams_valid() {
        return none;
    }
    let here = cam(0u);
    let p = bitcast<vec4<f32>>(e0).xyz + cam(age).origin;
    // Light traced before a change of the sample's surface, or of the surface its path
    // hit (a removed or added emitter), is dropped; light traced before a change near
    // either lasts EDIT_HISTORY_FRAMES frames, as after a change of the materials.
    var marks = changes_at(p, normal_of_id((e1.w >> 4u) & 7u));
    if (e1.w & 1u) == 0u {
        marks = max(marks, changes_at(bitcast<vec4<f32>>(e1).xyz + cam(age).origin, oct_decode(e1.w >> 16u)));
    }
    let edit = max(gi.edit_frame, marks.y);
    if e0.w < marks.x || (e0.w < edit && age > EDIT_HISTORY_FRAMES) {
        return none;
    }
    let pr = project(here, p - here.pos);
    if !on_image(pr.px) || pr.z <= 0.0 {
        return none;
    }
    let q = vec2<u32>(pr.px);
    let qi = q.x + q.y * frame.width;
    let g = mem_get(gi.off_gmat + qi);
    if surface_class(g) != ((e1.w >> 1u) & 3u) || surface_normal_id(g) != ((e1.w >> 4u) & 7u) {
        return none;
    }
    let off = abs(dot(surface_normal(g), p - bitcast<vec4<f32>>(mem_get(gi.off_gbuf + qi)).xyz));
    if off > 0.05 + 0.002 * length(p - here.pos) {
        return none;
    }
    let rgb = bitcast<vec4<f32>>(mem_get(gi.off_ring + RING_VEC4 * idx + 2u)).xyz;
    // Drawn anew each frame, so that a region's winners (and the light its pixels
    // resample) change from frame to frame and the TAA averages independent draws.
    let priority = min(pcg_hash(pcg_hash(pcg_hash(e0.w) ^ idx) ^ gi.frame), NO_PRIORITY - 1u);
    return Projected(true, region_of(q.x, q.y), (e1.w >> 4u) & 7u, any(rgb > vec3<f32>(0.0)), priority, idx);
}

// Counts lit and unlit samples per region; each lit sample bids for one of its region's
// BUCKET_SLOTS slots with a priority hashed from its frame, its ring index and this frame,
// so that the winners are a random subset that does not depend on the order threads run in.
@compute @workgroup_size(64)
fn gi_project(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) li: u32) {
    let s = project_sample(flat_id(wid, groups, li));
    if !s.ok {
        return;
    }
    if s.lit {
        atomicAdd(&buckets[bucket_counts(s.region) + 2u * s.nid], 1u);
        atomicMin(&buckets[bucket_priority(s.region, pcg_hash(s.priority) % BUCKET_SLOTS)], s.priority);
    } else {
        atomicAdd(&buckets[bucket_counts(s.region) + 2u * s.nid + 1u], 1u);
    }
}

// The winners write their ring index into their slot.
@compute @workgroup_size(64)
fn gi_project_store(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) li: u32) {
    let s = project_sample(flat_id(wid, groups, li));
    if !s.ok || !s.lit {
        return;
    }
    let slot = pcg_hash(s.priority) % BUCKET_SLOTS;
    if atomicLoad(&buckets[bucket_priority(s.region, slot)]) == s.priority {
        atomicStore(&buckets[bucket_index(s.region, slot)], s.idx);
    }
}

// ---- Pass gi_refine: at most MAX_KEPT samples per region ----
//
// Brightness levelling: a sample whose brightest channel is m, in a region whose brightest
// is M, is kept with probability m/M and then scaled by M/m (unbiased); a removed sample
// counts as unlit. The region's lit ratio is kept / (slots filled + the unlit count scaled
// like the lit one).
@compute @workgroup_size(64)
fn gi_refine(@builtin(global_invocation_id) gid: vec3<u32>) {
    let region = gid.x;
    if region >= region_count() {
        return;
    }
    // What the region's pixels see: their normals and chain lengths.
    var mask = 0u;
    var lo = SKY_DIST;
    var hi = 0.0;
    let x0 = (region % gi.regions_x) * 8u;
    let y0 = (region / gi.regions_x) * 8u;
    for (var k = 0u; k < 64u; k++) {
        let x = x0 + k % 8u;
        let y = y0 + k / 8u;
        if x < frame.width && y < frame.height {
            let i = x + y * frame.width;
            let g = mem_get(gi.off_gmat + i);
            if surface_class(g) != CLASS_NONE {
                mask |= 1u << surface_normal_id(g);
                lo = min(lo, bitcast<vec4<f32>>(mem_get(gi.off_gbuf + i)).w);
                hi = max(hi, bitcast<vec4<f32>>(mem_get(gi.off_gbuf + i)).w);
            }
        }
    }
    // Per normal id: slots filled and samples that survive levelling.
    var filled = array<u32, 6>(0u, 0u, 0u, 0u, 0u, 0u);
    var survivors = array<u32, 6>(0u, 0u, 0u, 0u, 0u, 0u);
    var peak = 0.0;
    for (var s = 0u; s < BUCKET_SLOTS; s++) {
        if atomicLoad(&buckets[bucket_priority(region, s)]) != NO_PRIORITY {
            let idx = atomicLoad(&buckets[bucket_index(region, s)]);
            filled[min((mem_get(gi.off_ring + RING_VEC4 * idx + 1u).w >> 4u) & 7u, NORMALS - 1u)]++;
            let rgb = bitcast<vec4<f32>>(mem_get(gi.off_ring + RING_VEC4 * idx + 2u)).xyz;
            peak = max(peak, max(rgb.r, max(rgb.g, rgb.b)));
        }
    }
    var rng = rng_new(frame.seed ^ 0x7E71u, region, gi.frame);
    var kept = 0u;
    for (var s = 0u; s < BUCKET_SLOTS; s++) {
        if atomicLoad(&buckets[bucket_priority(region, s)]) == NO_PRIORITY {
            continue;
        }
        let idx = atomicLoad(&buckets[bucket_index(region, s)]);
        let e0 = mem_get(gi.off_ring + RING_VEC4 * idx);
        let e1 = mem_get(gi.off_ring + RING_VEC4 * idx + 1u);
        let e2 = mem_get(gi.off_ring + RING_VEC4 * idx + 2u);
        let rgb = bitcast<vec4<f32>>(e2).xyz;
        let m = max(rgb.r, max(rgb.g, rgb.b));
        if rng_next(&rng) * peak >= m {
            continue;
        }
        survivors[min((e1.w >> 4u) & 7u, NORMALS - 1u)]++;
        if kept == MAX_KEPT {
            continue;
        }
        let col = min(rgb * (peak / m), vec3<f32>(65000.0));
        let shift = cam(gi.frame - e0.w).origin;
        let sky = (e1.w & 1u) != 0u;
        var point = bitcast<vec4<f32>>(e1).xyz;
        var jac = 1.0;
        if !sky {
            point += shift;
            let primary = bitcast<vec4<f32>>(e0).xyz + shift;
            let v = point - primary;
            let d2 = max(dot(v, v), 1e-8);
            jac = abs(dot(oct_decode(e1.w >> 16u), v * inverseSqrt(d2))) / d2;
        }
        let at = 2u * (region * MAX_KEPT + kept);
        mem_set(gi.off_refined + at, vec4<u32>(bitcast<vec3<u32>>(point), e1.w & 0xFFFF007Fu));
        mem_set(gi.off_refined + at + 1u, vec4<u32>(pack2x16float(col.rg), pack2x16float(vec2<f32>(col.b, 0.0)), e2.w, bitcast<u32>(jac)));
        kept++;
    }
    // The lit ratio per normal: the light a surface facing one way gets says nothing of
    // another's in the same region.
    var ratio = array<f32, 6>(0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    var total = 0u;
    for (var n = 0u; n < NORMALS; n++) {
        let lit = atomicLoad(&buckets[bucket_counts(region) + 2u * n]);
        let unlit = atomicLoad(&buckets[bucket_counts(region) + 2u * n + 1u]);
        total += lit + unlit;
        let unlit_scaled = f32(unlit) * f32(filled[n]) / max(f32(lit), 1.0);
        ratio[n] = f32(survivors[n]) / max(f32(filled[n]) + unlit_scaled, 1.0);
    }
    let base = gi.off_region_info + 3u * region;
    mem_set(base, bitcast<vec4<u32>>(vec4<f32>(ratio[0], ratio[1], ratio[2], ratio[3])));
    mem_set(base + 1u, bitcast<vec4<u32>>(vec4<f32>(ratio[4], ratio[5], f32(kept), f32(total))));
    mem_set(base + 2u, bitcast<vec4<u32>>(vec4<f32>(f32(mask), lo, hi, 0.0)));
}

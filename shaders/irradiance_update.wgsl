// The irradiance cache's update passes (`irradiance`; docs/RENDERING.md §3e), with
// irradiance_table.wgsl and the path tracer's light.wgsl (no tier):
// - `irradiance_invalidate`, one invocation per slot: clears the samples of every entry
//   whose voxel lies in one of the boxes (the changed chunks grown by the bounce distance);
// - `irradiance_args`, one invocation: the update pass's dispatch from the request count;
// - `irradiance_update`, one invocation per requested slot: takes the entry's next sample
//   when the frame's budget allows (client/src/light/irradiance/ states the sample).

@group(1) @binding(0) var<storage, read> light: LightInfo;
@group(1) @binding(1) var<storage, read> irr: IrradianceInfo;
@group(1) @binding(2) var<storage, read_write> irr_table: array<u32>;
@group(1) @binding(3) var<storage, read_write> irr_requests: array<atomic<u32>>;
@group(1) @binding(4) var<storage, read> irr_boxes: array<vec4<i32>>;
// `irradiance_args` only: the update's indirect dispatch.
@group(1) @binding(5) var<storage, read_write> irr_args: array<u32>;

// Rays leaving a face see the sky as the path tracer does.
fn sky_base(d: vec3<f32>) -> vec3<f32> {
    return sky_direct(d);
}

// The voxel of the key in slot words `at`.
fn irr_voxel(at: u32) -> vec3<i32> {
    let a = irr_table[at];
    return vec3<i32>(vec3<u32>(a & 0x7FFFu, irr_table[at + 1u] & 0xFFFFu, a >> 16u));
}

@compute @workgroup_size(64)
fn irradiance_invalidate(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = gid.x + gid.y * groups.x * 64u;
    if slot > irr.mask {
        return;
    }
    let at = slot * IRR_WORDS;
    if irr_table[at + 1u] == 0u || irr_table[at + 3u] == 0u {
        return;
    }
    let v = irr_voxel(at);
    for (var i = 0u; i < irr.boxes; i++) {
        if all(v >= irr_boxes[2u * i].xyz) && all(v <= irr_boxes[2u * i + 1u].xyz) {
            irr_table[at + 3u] = 0u;
            irr_table[at + 4u] = 0u;
            irr_table[at + 5u] = 0u;
            irr_table[at + 6u] = 0u;
            return;
        }
    }
}

@compute @workgroup_size(1)
fn irradiance_args() {
    let n = min(atomicLoad(&irr_requests[IRR_COUNT]), irr.max_requests);
    irr_args[0] = (n + 63u) / 64u;
    irr_args[1] = 1u;
    irr_args[2] = 1u;
}

@compute @workgroup_size(64)
fn irradiance_update(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = min(atomicLoad(&irr_requests[IRR_COUNT]), irr.max_requests);
    if gid.x >= n {
        return;
    }
    let slot = atomicLoad(&irr_requests[IRR_LIST + gid.x]);
    let at = slot * IRR_WORDS;
    let key = vec2<u32>(irr_table[at], irr_table[at + 1u]);
    let count = irr_table[at + 3u];
    // The budget goes first to entries with no samples, then evenly to the rest; whether
    // an entry is refreshed depends on its key and the frame only, never on the order of
    // the list.
    let fresh = min(atomicLoad(&irr_requests[IRR_FRESH]), n);
    var share = f32(irr.budget) / f32(max(fresh, 1u));
    if count != 0u {
        share = f32(irr.budget - min(irr.budget, fresh)) / f32(max(n - fresh, 1u));
    }
    let stream = irr_stream(key);
    if f32(pcg_hash(stream ^ pcg_hash(irr.stamp)) >> 8u) * (1.0 / 16777216.0) >= share {
        return;
    }
    let taken = irr_table[at + 7u];
    // The direction's R2 offsets, drawn once per entry (CpuIrradiance::sample).
    let offsets = rng_new(irr.seed, stream, 0xFFFFFFFFu);
    let offset = vec2<u32>(pcg_hash(offsets), pcg_hash(pcg_hash(offsets)));
    var rng = rng_new(irr.seed, stream, taken);
    // A point uniform on the face, just off it (FaceKey::point).
    let face = (key.y >> 16u) & 7u;
    let axis = face / 2u;
    let up = face % 2u == 0u;
    var normal = vec3<f32>(0.0);
    normal[axis] = select(-1.0, 1.0, up);
    var p = vec3<f32>(0.0);
    p[axis] = select(-SURFACE_OFFSET, 1.0 + SURFACE_OFFSET, up);
    p[(axis + 1u) % 3u] = rng_next(&rng);
    p[(axis + 2u) % 3u] = rng_next(&rng);
    let base = ray_new(irr_voxel(at), vec3<f32>(0.0), normal);
    var e = vec3<f32>(sun_sample(base, p, normal, &rng).irradiance);
    let u = vec2<f32>((taken * IRR_R2 + offset) >> vec2<u32>(8u)) * (1.0 / 16777216.0);
    let w = sample_cosine(normal, u);
    e += PI * path_radiance(ray_at(base, p, w), 1u, false, &rng).radiance;
    var sum = vec3<f32>(bitcast<f32>(irr_table[at + 4u]), bitcast<f32>(irr_table[at + 5u]), bitcast<f32>(irr_table[at + 6u])) + e;
    var c = count + 1u;
    if c >= IRR_HISTORY {
        sum *= 0.5;
        c = IRR_HISTORY / 2u;
    }
    irr_table[at + 3u] = c;
    irr_table[at + 4u] = bitcast<u32>(sum.x);
    irr_table[at + 5u] = bitcast<u32>(sum.y);
    irr_table[at + 6u] = bitcast<u32>(sum.z);
    irr_table[at + 7u] = taken + 1u;
    atomicAdd(&irr_requests[IRR_TAKEN], 1u);
}

// Pass: trace a list of rays, one invocation each (GPU-against-CPU tests and the
// traversal benchmark). Each result is eight words:
//   0: bit 0 hit, bit 1 step budget exhausted, bits 4–5 entry axis (3 = origin inside),
//      bit 6 set when the normal points along +axis
//   1–3: voxel (world, or entity-local for an entity hit)
//   4: material   5: distance to the entry face (f32 bits)   6: cells visited
//   7: entity id (0x3FFF = none)

// `RayCount` and `RayIn` are generated after the pass from their Rust definitions
// (client/src/gpu/params.rs).

@group(1) @binding(0) var<storage, read> ray_count: RayCount;
@group(1) @binding(1) var<storage, read> rays_in: array<RayIn>;
@group(1) @binding(2) var<storage, read_write> hits_out: array<u32>;

@compute @workgroup_size(64)
fn trace_rays(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * ray_count.row;
    if i >= ray_count.count {
        return;
    }
    let q = rays_in[i];
    let r = ray_new(q.o_int, q.o_frac, q.d);
    let h = trace(r);
    var flags = select(0u, 1u, h.hit) | select(0u, 2u, h.exhausted) | (h.axis << 4u);
    if h.axis != NO_AXIS && h.normal[h.axis] > 0 {
        flags |= 64u;
    }
    let o = 8u * i;
    hits_out[o] = flags;
    hits_out[o + 1u] = u32(h.voxel.x);
    hits_out[o + 2u] = u32(h.voxel.y);
    hits_out[o + 3u] = u32(h.voxel.z);
    hits_out[o + 4u] = h.material;
    hits_out[o + 5u] = bitcast<u32>(h.t * r.len);
    hits_out[o + 6u] = h.steps;
    hits_out[o + 7u] = h.entity;
}

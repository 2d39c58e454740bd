// The world loop over a dense grid (the `grid` method, Amanatides–Woo one voxel at a
// time): the GPU twin of world/src/traverse/grid.rs. `structure_word(i)` holds voxels 2i and
// 2i + 1 (x fastest, then y, then z) as 16-bit material ids, low half first.


// The material of voxel `p` in a world of `size` voxels (`world_info.size`).
fn grid_material(p: vec3<u32>, size: vec3<u32>) -> u32 {
    let i = p.x + size.x * (p.y + size.y * p.z);
    return (structure_word(i / 2u) >> (16u * (i & 1u))) & 0xFFFFu;
}

fn world_loop(r: Ray) -> WorldTrace {
    // The world's parameters, read once (see chunk_index in world.wgsl).
    let size = world_info.size;
    let chunks = world_info.chunks;
    let max_steps = world_info.max_steps;
    let dims = vec3<i32>(size);
    let entry = ray_entry(r, dims);
    if !entry.ok {
        return WorldTrace(no_hit(0u), END_MISSED, 0.0, 0.0);
    }
    var s = dda_start(r, entry);
    // The chunks' entity fields say where entities are (as in traverse.wgsl).
    var last_chunk = 0xFFFFFFFFu;
    for (var steps = 1u; steps <= max_steps; steps++) {
        let p = vec3<u32>(s.cell);
        let ci = chunk_index(p >> vec3<u32>(4u), chunks);
        if ci != last_chunk {
            last_chunk = ci;
            record_field(r, chunk_entity_word(ci), entry.t);
        }
        let m = grid_material(p, size);
        if m != 0u {
            return WorldTrace(make_hit(r, s.cell, s.t, s.axis, m, steps), END_HIT, entry.t, s.t);
        }
        dda_advance(r, &s);
        if any(s.cell < vec3<i32>(0)) || any(s.cell >= dims) {
            return WorldTrace(no_hit(steps), END_LEFT, entry.t, s.t);
        }
    }
    return ran_out(entry.t, s.t);
}

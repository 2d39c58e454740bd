// The world loop over a dense grid (the `grid` method, Amanatides–Woo one voxel at a
// time): the GPU twin of world/src/traverse/grid.rs. `structure_word(i)` holds voxels 2i and
// 2i + 1 (x fastest, then y, then z) as 16-bit material ids, low half first.


// The material of voxel `p` in a world of `size` voxels (`world_info.size`).
fn grid_material(p: vec3<u32>, size: vec3<u32>) -> u32 {
    let i = p.x + size.x * (p.y + size.y * p.z);
    return (structure_word(i / 2u) >> (16u * (i & 1u))) & 0xFFFFu;
}

// Entities are found after the loop (see trace.wgsl).
const TRACES_ENTITIES: bool = true;

fn world_loop(r: Ray) -> WorldTrace {
    // The world's parameters, read once (see chunk_index in world.wgsl).
    let size = world_info.size;
    let max_steps = world_info.max_steps;
    let dims = vec3<i32>(size);
    let entry = ray_entry(r, dims);
    if !entry.ok {
        return WorldTrace(no_hit(0u), END_MISSED, 0.0, 0.0);
    }
    var s = dda_start(r, entry);
    for (var steps = 1u; steps <= max_steps; steps++) {
        let p = vec3<u32>(s.cell);
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

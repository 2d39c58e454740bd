// The world loop over the chunk → block → voxel hierarchy (docs/NAADF.md §9), with
// AADF jumps (`USE_AADF`, the `naadf` method) or without (`nodf`): the GPU twin of
// world/src/traverse/hierarchy.rs. It sees the static world alone: entities are found
// afterwards, through their hierarchy (trace.wgsl).

override USE_AADF: bool = true;
// Entities are found after the loop (see trace.wgsl).
const TRACES_ENTITIES: bool = true;


fn to_edge(c: u32, neg: bool, edge: u32) -> i32 {
    let m = c & (edge - 1u);
    return i32(select(edge - 1u - m, m, neg));
}

fn world_loop(r: Ray) -> WorldTrace {
    let dims = vec3<i32>(world_info.size);
    let entry = ray_entry(r, dims);
    if !entry.ok {
        return WorldTrace(no_hit(0u), END_MISSED, 0.0, 0.0);
    }
    var cell = entry.cell;
    var t = entry.t;
    var axis = entry.axis;
    let neg = r.d <= vec3<f32>(0.0);
    // The AADF field facing the ray on each axis: −a for negative directions, +a otherwise.
    let facing = vec3<u32>(0u, 2u, 4u) + select(vec3<u32>(0u), vec3<u32>(1u), r.d > vec3<f32>(0.0));
    // The world's parameters, read once (see chunk_index in world.wgsl).
    let chunks = world_info.chunks;
    let max_steps = world_info.max_steps;
    for (var steps = 1u; steps <= max_steps; steps++) {
        let p = vec3<u32>(cell);
        let chunk = chunk_word(chunk_index(p >> vec3<u32>(4u), chunks));
        var skip = vec3<i32>(0);
        let cs = cell_state(chunk);
        if cs == STATE_FULL {
            return WorldTrace(make_hit(r, cell, t, axis, chunk & MAX_MATERIAL, steps), END_HIT, entry.t, t);
        } else if cs == STATE_EMPTY {
            for (var a = 0u; a < 3u; a++) {
                skip[a] = to_edge(p[a], neg[a], 16u);
                if USE_AADF {
                    skip[a] += 16 * i32(aadf_field(chunk, facing[a], CHUNK_FIELD_BITS));
                }
            }
        } else {
            let block = block_word((chunk & PAYLOAD) + index4((p >> vec3<u32>(2u)) & vec3<u32>(3u)));
            let bs = cell_state(block);
            if bs == STATE_FULL {
                return WorldTrace(make_hit(r, cell, t, axis, block & MAX_MATERIAL, steps), END_HIT, entry.t, t);
            } else if bs == STATE_EMPTY {
                for (var a = 0u; a < 3u; a++) {
                    skip[a] = to_edge(p[a], neg[a], 4u);
                    if USE_AADF {
                        skip[a] += 4 * i32(aadf_field(block, facing[a], CELL_FIELD_BITS));
                    }
                }
            } else {
                let v = group_voxel(block & PAYLOAD, index4(p & vec3<u32>(3u)));
                if (v & VOXEL_SOLID) != 0u {
                    return WorldTrace(make_hit(r, cell, t, axis, v & MAX_MATERIAL, steps), END_HIT, entry.t, t);
                }
                if USE_AADF {
                    for (var a = 0u; a < 3u; a++) {
                        skip[a] = i32(aadf_field(v, facing[a], CELL_FIELD_BITS));
                    }
                }
            }
        }
        let ex = ray_exit(r, cell, skip);
        if any(ex.next < vec3<i32>(0)) || any(ex.next >= dims) {
            // An AADF box may reach beyond the world: the ray left it at the world's edge.
            return WorldTrace(no_hit(steps), END_LEFT, entry.t, min(ex.t, leave_time(r, dims)));
        }
        cell = ex.next;
        t = ex.t;
        axis = ex.axis;
    }
    return ran_out(entry.t, t);
}

// `tree_step` of the SVDAG (docs/BASELINES.md): an inner node is its child mask and the
// word of each non-empty child in octant order (children may be shared); a node at
// `leaf_level` is a 4³ occupancy leaf of two words, low half first.

fn tree_side_log(depth: u32, leaf_level: u32, level: u32) -> u32 {
    return depth - level;
}

fn tree_step(depth: u32, leaf_level: u32, level: u32, node: u32, cell: vec3<i32>) -> TreeStep {
    if level == leaf_level {
        let p = vec3<u32>(cell) & vec3<u32>(3u);
        let bit = p.x + 4u * p.y + 16u * p.z;
        let half = structure_word(node + bit / 32u);
        return TreeStep(select(STEP_EMPTY, STEP_SOLID, ((half >> (bit & 31u)) & 1u) != 0u), 0u);
    }
    // Inner nodes have children of side 8 or more: never a voxel.
    var s = tree_mask_step(node, cell, depth - 1u - level);
    if s.kind == STEP_NODE {
        s.value = structure_word(node + 1u + s.value);
    }
    return s;
}

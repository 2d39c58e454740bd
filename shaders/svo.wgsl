// `tree_step` of the SVO (docs/BASELINES.md): every node is two words, its valid mask and
// the word of its first child; children are contiguous in octant order, two words each.
// A set bit at a node of side 2 is a solid voxel.

fn tree_side_log(depth: u32, shape: u32, level: u32) -> u32 {
    return depth - level;
}

fn tree_step(depth: u32, shape: u32, level: u32, node: u32, cell: vec3<i32>) -> TreeStep {
    var s = tree_mask_step(node, cell, depth - 1u - level);
    if s.kind == STEP_NODE {
        s.value = structure_word(node + 1u) + 2u * s.value;
    }
    return s;
}

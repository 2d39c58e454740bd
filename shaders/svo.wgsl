// `tree_step` of the SVO (docs/BASELINES.md): every node is two words, its valid mask and
// the word of its first child; children are contiguous in octant order, two words each.
// A set bit at a node of side 2 is a solid voxel.

fn tree_side_log(depth: u32, shape: u32, level: u32) -> u32 {
    return depth - level;
}

fn tree_step(depth: u32, shape: u32, level: u32, node: u32, cell: vec3<i32>) -> TreeStep {
    let k = depth - 1u - level;
    let oct = tree_octant(cell, k);
    let mask = structure_word(node);
    if ((mask >> oct) & 1u) == 0u {
        return TreeStep(STEP_EMPTY, k);
    }
    if k == 0u {
        return TreeStep(STEP_SOLID, 0u);
    }
    return TreeStep(STEP_NODE, structure_word(node + 1u) + 2u * tree_rank(mask, oct));
}

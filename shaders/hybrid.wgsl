// `tree_step` of a hybrid format R(W³) G(L) (docs/BASELINES.md): level 0 is the raw grid of
// 2^W cells a side right after the header (a cell is 0 when empty, else the word of its
// sub-volume's root); below it, DAG nodes of side 2^L down to 2, each its child mask and the
// word of each non-empty child in octant order. A set bit at a node of side 2 is a solid
// voxel. The header's shape word is L; its first word is W + L.

fn tree_side_log(depth: u32, dag: u32, level: u32) -> u32 {
    return select(dag + 1u - level, depth, level == 0u);
}

fn tree_step(depth: u32, dag: u32, level: u32, node: u32, cell: vec3<i32>) -> TreeStep {
    if level == 0u {
        let n = 1u << (depth - dag);
        let c = vec3<u32>(cell) >> vec3<u32>(dag);
        let root = structure_word(TREE_HEADER_WORDS + c.x + n * (c.y + n * c.z));
        if root == 0u {
            return TreeStep(STEP_EMPTY, dag);
        }
        return TreeStep(STEP_NODE, root);
    }
    var s = tree_mask_step(node, cell, dag - level);
    if s.kind == STEP_NODE {
        s.value = structure_word(node + 1u + s.value);
    }
    return s;
}

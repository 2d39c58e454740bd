// The world loop over a tree of the paper's comparison (an SVO, an SVDAG or a hybrid format,
// docs/BASELINES.md): the GPU twin of `trace_tree` in world/src/baselines/mod.rs. The tree
// lies in the comparison-structure binding (`structure_word`) in its GPU layout: a header
// (log2 of the cube's side, the structure's shape word) and then the nodes, root first. The
// file that follows this one (svo.wgsl, svdag.wgsl or hybrid.wgsl) defines `tree_step`, what
// a node holds at a cell, and `tree_side_log`, log2 of the side of a level's nodes. The walk keeps the path from the root to the current cell; after each step it
// climbs only as far as the cell it entered leaves that path, then descends to an empty
// cube (left whole, with the event model every method shares) or a solid voxel. The trees
// hold geometry only: a hit reports material 0, and entities are not traced.

// Entities are not traced (see trace.wgsl).
const TRACES_ENTITIES: bool = false;

const TREE_HEADER_WORDS: u32 = 4u;
// Deeper than any cube: the path holds one node per level.
const TREE_MAX_LEVELS: u32 = 32u;

const STEP_NODE: u32 = 0u;
const STEP_EMPTY: u32 = 1u;
const STEP_SOLID: u32 = 2u;

// What a node holds at a cell: the child node's first word (STEP_NODE), the log2 side of
// the empty cube around the cell (STEP_EMPTY), or a solid voxel.
struct TreeStep {
    kind: u32,
    value: u32,
}

// The octant (bit x + 2y + 4z) of `cell` in a node whose children have side 2^k.
fn tree_octant(cell: vec3<i32>, k: u32) -> u32 {
    let o = (vec3<u32>(cell) >> vec3<u32>(k)) & vec3<u32>(1u);
    return o.x | (o.y << 1u) | (o.z << 2u);
}

// The children before octant `oct` in `mask`: the rank of that child.
fn tree_rank(mask: u32, oct: u32) -> u32 {
    return countOneBits(mask & ((1u << oct) - 1u));
}

// What a node whose first word is its child mask holds at `cell`, its children of side 2^k:
// an empty cube, a solid voxel (k = 0), or a child, as its rank (the caller turns the rank
// into the child's word, which each layout stores its own way).
fn tree_mask_step(node: u32, cell: vec3<i32>, k: u32) -> TreeStep {
    let oct = tree_octant(cell, k);
    let mask = structure_word(node);
    if ((mask >> oct) & 1u) == 0u {
        return TreeStep(STEP_EMPTY, k);
    }
    if k == 0u {
        return TreeStep(STEP_SOLID, 0u);
    }
    return TreeStep(STEP_NODE, tree_rank(mask, oct));
}

fn world_loop(r: Ray) -> WorldTrace {
    let dims = vec3<i32>(world_info.size);
    let entry = ray_entry(r, dims);
    if !entry.ok {
        return WorldTrace(no_hit(0u), END_MISSED, 0.0, 0.0);
    }
    let depth = structure_word(0u);
    let shape = structure_word(1u);
    var cell = entry.cell;
    var t = entry.t;
    var axis = entry.axis;
    let neg = r.d <= vec3<f32>(0.0);
    // path[l]: the level-l node holding `cell`, for l < valid.
    var path: array<u32, TREE_MAX_LEVELS>;
    path[0] = TREE_HEADER_WORDS;
    var valid = 1u;
    let max_steps = world_info.max_steps; // read once (see chunk_index in world.wgsl)
    for (var steps = 1u; steps <= max_steps; steps++) {
        var l = valid - 1u;
        var empty = 0u;
        loop {
            let s = tree_step(depth, shape, l, path[l], cell);
            if s.kind == STEP_SOLID {
                return WorldTrace(make_hit(r, cell, t, axis, 0u, steps), END_HIT, entry.t, t);
            }
            if s.kind == STEP_EMPTY {
                empty = s.value;
                break;
            }
            l += 1u;
            path[l] = s.value;
        }
        valid = l + 1u;
        let inside = cell & vec3<i32>((1 << empty) - 1);
        let skip = select((1 << empty) - 1 - inside, inside, neg);
        let ex = ray_exit(r, cell, skip);
        if any(ex.next < vec3<i32>(0)) || any(ex.next >= dims) {
            return WorldTrace(no_hit(steps), END_LEFT, entry.t, ex.t);
        }
        // The levels whose node still holds the new cell: those whose side reaches past
        // the highest bit in which the two cells differ (the root always does).
        let d = vec3<u32>(cell ^ ex.next);
        let bits = 32u - countLeadingZeros(d.x | d.y | d.z);
        while valid > 1u && tree_side_log(depth, shape, valid - 1u) < bits {
            valid -= 1u;
        }
        cell = ex.next;
        t = ex.t;
        axis = ex.axis;
    }
    return ran_out(entry.t, t);
}

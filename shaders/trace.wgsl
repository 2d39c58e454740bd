// One full trace: the world loop (traverse.wgsl or grid.wgsl) through the static world,
// then the instances whose world boxes the ray crosses before the world's hit or exit,
// found through their hierarchy (docs/NAADF.md §11): the GPU twin of
// world/src/traverse/entities.rs. Only the nearest entity hit (lowest id at equal times)
// survives, and only if it comes strictly before the world's hit or exit. Local instances
// (previews, markers: world/src/entity/local.rs) follow the world's records and carry the id
// NO_ENTITY, so their hits read as static geometry to everything that follows entity ids.

// How the world loop ended.
const END_HIT: u32 = 0u;
const END_LEFT: u32 = 1u;
const END_MISSED: u32 = 2u;
const END_EXHAUSTED: u32 = 3u;

struct WorldTrace {
    hit: Hit,
    end: u32,
    // When the ray entered the world, and when it hit or left it.
    t_entry: f32,
    t_end: f32,
}

// The end of a world loop whose step budget ran out at time `t` (entered at `t_entry`).
fn ran_out(t_entry: f32, t: f32) -> WorldTrace {
    var h = no_hit(world_info.max_steps);
    h.exhausted = true;
    return WorldTrace(h, END_EXHAUSTED, t_entry, t);
}

var<private> best_entity: Hit;
// The inverse rotation of `best_entity`'s instance.
var<private> best_rotation: vec4<f32>;
// Entity-grid cells visited (added to the step count of an entity hit).
var<private> entity_steps: u32;
// Whether the last `trace` returned an instance's hit (a local instance's has no entity id).
var<private> hit_instance: bool;

// Whether the world holds any instance. The host builds a pipeline for each value and
// picks the one that matches its world: a device that runs neighbouring rays in lock step
// may run code that no ray takes, and without instances none of the walk is compiled.
override HAS_INSTANCES: bool = true;

// How many instances the walk finds before it stops to test them.
const INSTANCE_BATCH: u32 = 8u;

// The walk's node stack and found instances, at module scope, so that an invocation holds
// (and zeroes) one of each rather than one for every trace inlined into it.
var<private> bvh_stack: array<u32, BVH_STACK>;
var<private> found_t: array<f32, INSTANCE_BATCH>;
var<private> found_slot: array<u32, INSTANCE_BATCH>;

// Walks the instance hierarchy (world/src/entity/bvh.rs: four-wide nodes of NODE_WORDS
// words, the children's f32 boxes axis by axis, then their references) and tests every
// instance whose box the ray is inside at some t in [t_lo, t_hi] (or up to the best entity
// hit so far). Boxes are padded and rounded outward, so the f32 test never rejects an
// instance the ray can hit. The walk gathers up to INSTANCE_BATCH instances, then tests them
// in the order the ray enters their boxes, stopping at a box that starts after the best hit,
// and goes on while nodes are left. Testing outside the walk's loop keeps that loop small,
// which is what costs on a device that runs neighbouring rays in lock step. With `any_hit`
// it returns at the first hit before `t_hi`.
fn find_instances(r: Ray, t_lo: f32, t_hi: f32, any_hit: bool) {
    // The world loop says whether its structure is traced with entities: the comparison
    // trees hold geometry only.
    if !TRACES_ENTITIES || !HAS_INSTANCES || world_info.instance_slots == 0u {
        return;
    }
    // 1/d, with ±FAR for axes the ray does not move along.
    let inv = select(1.0 / r.d, select(vec3<f32>(BVH_FAR), vec3<f32>(-BVH_FAR), r.d < vec3<f32>(0.0)), r.d == vec3<f32>(0.0));
    let o = vec3<f32>(r.o_int);
    bvh_stack[0] = 0u;
    var sp = 1u;
    while sp > 0u {
        var far_limit = t_hi * 1.000001 + 1e-3;
        if best_entity.hit {
            far_limit = min(far_limit, best_entity.t * 1.000001 + 1e-3);
        }
        // A node adds at most four instances, so one is taken while four places are left.
        var found = 0u;
        while sp > 0u && found + 4u <= INSTANCE_BATCH {
            sp -= 1u;
            let base = bvh_stack[sp] * NODE_WORDS;
            // The four lanes at once, axis by axis.
            let tx0 = ((node_lanes(base) - o.x) - r.o_frac.x) * inv.x;
            let tx1 = ((node_lanes(base + 4u) - o.x) - r.o_frac.x) * inv.x;
            let ty0 = ((node_lanes(base + 8u) - o.y) - r.o_frac.y) * inv.y;
            let ty1 = ((node_lanes(base + 12u) - o.y) - r.o_frac.y) * inv.y;
            let tz0 = ((node_lanes(base + 16u) - o.z) - r.o_frac.z) * inv.z;
            let tz1 = ((node_lanes(base + 20u) - o.z) - r.o_frac.z) * inv.z;
            let near = max(vec4<f32>(t_lo - 1e-3), max(min(tx0, tx1), max(min(ty0, ty1), min(tz0, tz1))));
            let far = min(vec4<f32>(far_limit), min(max(tx0, tx1), min(max(ty0, ty1), max(tz0, tz1))));
            let child = vec4<u32>(hierarchy_word(base + 24u), hierarchy_word(base + 25u), hierarchy_word(base + 26u), hierarchy_word(base + 27u));
            let entered = !(near > far) & (child != vec4<u32>(BVH_NONE));
            // Each lane in turn: no loop, so that no lane's index is dynamic.
            if entered.x {
                keep_lane(child.x, near.x, &sp, &found);
            }
            if entered.y {
                keep_lane(child.y, near.y, &sp, &found);
            }
            if entered.z {
                keep_lane(child.z, near.z, &sp, &found);
            }
            if entered.w {
                keep_lane(child.w, near.w, &sp, &found);
            }
        }
        // Nearest box first, until one starts after the best hit (whose own box started no
        // later: the boxes are padded beyond the f32 test's rounding).
        for (var left = found; left > 0u; left--) {
            var k = 0u;
            for (var j = 1u; j < left; j++) {
                if found_t[j] < found_t[k] {
                    k = j;
                }
            }
            if best_entity.hit && found_t[k] > best_entity.t {
                break;
            }
            test_instance(r, found_slot[k] * RECORD_WORDS, t_lo);
            if any_hit && best_entity.hit && best_entity.t < t_hi {
                return;
            }
            found_t[k] = found_t[left - 1u];
            found_slot[k] = found_slot[left - 1u];
        }
    }
}

// Keeps a lane the ray enters at `near`: an instance among the found ones, or a node on the
// stack.
fn keep_lane(c: u32, near: f32, sp: ptr<function, u32>, found: ptr<function, u32>) {
    if (c & BVH_LEAF) != 0u {
        found_t[*found] = near;
        found_slot[*found] = c & ~BVH_LEAF;
        *found += 1u;
    } else if *sp < BVH_STACK {
        bvh_stack[*sp] = c;
        *sp += 1u;
    }
}

// Four lanes' planes of one axis, from word `at` of the hierarchy.
fn node_lanes(at: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(vec4<u32>(hierarchy_word(at), hierarchy_word(at + 1u), hierarchy_word(at + 2u), hierarchy_word(at + 3u)));
}

// Decodes a smallest-three quaternion (world/src/entity/pack.rs).
fn decode_quat(w0: u32, w1: u32) -> vec4<f32> {
    let s = vec3<f32>(vec3<u32>(w0 & 0x3FFFu, (w0 >> 14u) & 0x3FFFu, (w0 >> 28u) | ((w1 & 0x3FFu) << 4u)));
    let small = (s - 8192.0) / 8192.0;
    let rest = sqrt(max(1.0 - dot(small, small), 0.0));
    let k = (w1 >> 10u) & 3u;
    if k == 0u {
        return vec4<f32>(rest, small.x, small.y, small.z);
    } else if k == 1u {
        return vec4<f32>(small.x, rest, small.y, small.z);
    } else if k == 2u {
        return vec4<f32>(small.x, small.y, rest, small.z);
    }
    return vec4<f32>(small, rest);
}

// Rotates `v` by the unit quaternion `q = (x, y, z, w)`.
fn rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}

fn conjugate(q: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(-q.xyz, q.w);
}

// An instance record's position in 1/128 voxel (record words 0 and 1).
fn record_position(dx: u32, dy: u32) -> vec3<u32> {
    return vec3<u32>(dx & 0x1FFFFFu, (dx >> 21u) | (((dy >> 21u) & 0xFFu) << 11u), dy & 0x1FFFFFu);
}

// An instance record's entity id (record word 4).
fn record_id(e: u32) -> u32 {
    return e & 0x3FFFu;
}

// Tests the instance record at word `at` against the ray; keeps the nearest entity hit.
fn test_instance(r: Ray, at: u32, t_lo: f32) {
    let dx = instance_word(at);
    let dy = instance_word(at + 1u);
    let dz = instance_word(at + 2u);
    let dw = instance_word(at + 3u);
    let e = instance_word(at + 4u);
    let id = record_id(e);
    let size = vec3<u32>((e >> 14u) & 0x7Fu, (e >> 21u) & 0x7Fu, ((e >> 28u) & 0xFu) | (((dy >> 29u) & 7u) << 4u));
    let pos = record_position(dx, dy);
    var limit = T_INF;
    var equal_ok = false;
    if best_entity.hit {
        limit = best_entity.t;
        equal_ok = id < best_entity.entity;
    }
    // The entity lies within |size| of its local-origin corner: reject rays that pass
    // farther (with slack for f32), before transforming anything.
    let rel = vec3<f32>(r.o_int - vec3<i32>(pos >> vec3<u32>(7u))) + (r.o_frac - vec3<f32>(pos & vec3<u32>(127u)) / 128.0);
    let tc = -dot(rel, r.d) / (r.len * r.len);
    let radius = (length(vec3<f32>(size)) + 0.01) / r.len;
    let closest = rel + r.d * tc;
    if dot(closest, closest) > radius * radius * r.len * r.len || tc + radius < t_lo || tc - radius > limit {
        return;
    }
    let q = decode_quat(dz, dw & 0xFFFu);
    let local = ray_from(rotate(q, rel), rotate(q, r.d));
    let isize = vec3<i32>(size);
    let entry = ray_entry(local, isize);
    if !entry.ok {
        return;
    }
    let base = (dw >> 12u) * TYPE_ALIGN;
    var s = dda_start(local, entry);
    loop {
        entity_steps += 1u;
        if s.t > limit || (s.t == limit && !equal_ok) {
            return;
        }
        if s.t >= t_lo {
            let c = vec3<u32>(s.cell);
            let v = entity_type_word(base + c.x + size.x * (c.y + size.y * c.z));
            if (v & ENTITY_SOLID) != 0u {
                var h = make_hit(local, s.cell, s.t, s.axis, v & MAX_MATERIAL, 0u);
                h.entity = id;
                best_entity = h;
                best_rotation = q;
                return;
            }
        }
        dda_advance(local, &s);
        if any(s.cell < vec3<i32>(0)) || any(s.cell >= isize) {
            return;
        }
    }
}

// The world-space normal of the hit the last `trace` returned (entity-local normals are
// rotated back to the world).
fn world_normal(h: Hit) -> vec3<f32> {
    let n = vec3<f32>(h.normal);
    if !hit_instance {
        return n;
    }
    return rotate(conjugate(best_rotation), n);
}

// Clears the entity state of the last trace and runs the world loop: how a trace starts.
fn world_first(r: Ray) -> WorldTrace {
    entity_steps = 0u;
    best_entity = no_hit(0u);
    hit_instance = false;
    return world_loop(r);
}

// Traces `r` through the world and its entities.
fn trace(r: Ray) -> Hit {
    let w = world_first(r);
    if w.end == END_MISSED || w.end == END_EXHAUSTED {
        return w.hit;
    }
    find_instances(r, w.t_entry, w.t_end, false);
    if best_entity.hit && best_entity.t < w.t_end {
        hit_instance = true;
        var h = best_entity;
        h.steps = w.hit.steps + entity_steps;
        return h;
    }
    var h = w.hit;
    h.steps += entity_steps;
    return h;
}

// Whether `trace(r)` would hit (`x`) and whether it would run out of steps (`y`), for rays
// that only ask whether something is in the way (shadow rays): a ray that hits the world
// needs no instance walk, and one that leaves it stops walking at the first instance hit.
fn occlusion(r: Ray) -> vec2<bool> {
    let w = world_first(r);
    if w.end != END_LEFT {
        return vec2<bool>(w.hit.hit, w.hit.exhausted);
    }
    find_instances(r, w.t_entry, w.t_end, true);
    return vec2<bool>(best_entity.hit && best_entity.t < w.t_end, false);
}

// The entities' poses per frame, so that the long-term TAA follows a moving entity
// (docs/RENDERING.md §3c, "Entities in the history").
//
// `words` holds, after the queued pixels, TAA_SLOTS tables of ENTITY_IDS entries: entry
// `id` of slot `s` is words 0–3 of entity `id`'s instance record (position, rotation and
// type; world/src/entity/pack.rs) as of the frame that wrote slot `s`, or zero where the
// entity did not exist (no record is all zero: its rotation word would not be a unit
// quaternion). One pass per frame fills this frame's slot.

const ENTITY_IDS: u32 = NO_ENTITY;

fn pose_word(slot: u32, id: u32) -> u32 {
    return gi.off_queue_list + 64u * region_count() + 4u * (slot * ENTITY_IDS + id);
}

// Entity `id`'s record words 0–3 in TAA slot `slot` (zero: it did not exist).
fn pose_words(slot: u32, id: u32) -> vec4<u32> {
    let at = pose_word(slot, id);
    return vec4<u32>(words[at], words[at + 1u], words[at + 2u], words[at + 3u]);
}

// An entity's placement: its local origin (relative to this frame's integer camera
// position) and the rotation from world to entity axes.
struct Pose {
    origin: vec3<f32>,
    to_local: vec4<f32>,
}

fn pose_of(w: vec4<u32>) -> Pose {
    let pos = record_position(w.x, w.y);
    let origin = vec3<f32>(vec3<i32>(pos >> vec3<u32>(7u)) - frame.cam_int) + vec3<f32>(pos & vec3<u32>(127u)) / 128.0;
    return Pose(origin, decode_quat(w.z, w.w & 0xFFFu));
}

// Point `p` (relative to this frame's integer camera position) of an entity placed at
// `was`, where it lies when the entity is placed at `now`.
fn carry(p: vec3<f32>, was: Pose, now: Pose) -> vec3<f32> {
    return now.origin + rotate(conjugate(now.to_local), rotate(was.to_local, p - was.origin));
}

// ---- Pass gi_poses: one thread per entity id writes its entry of this frame's slot ----

@compute @workgroup_size(64)
fn gi_poses(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let id = flat_id(wg, groups, li);
    if id >= ENTITY_IDS {
        return;
    }
    // The instance buffer holds entity `id`'s record in slot `id` (zero: no such entity;
    // past the world's slots, local instances, whose records carry no entity id).
    var record = vec4<u32>(0u);
    let e = select(0u, instance_word(id * RECORD_WORDS + 4u), id < world_info.instance_slots);
    if e != 0u && record_id(e) == id {
        let r = id * RECORD_WORDS;
        record = vec4<u32>(instance_word(r), instance_word(r + 1u), instance_word(r + 2u), instance_word(r + 3u));
    }
    let at = pose_word(gi.taa_slot, id);
    for (var k = 0u; k < 4u; k++) {
        words[at + k] = record[k];
    }
}

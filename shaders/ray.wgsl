// Rays and the event model every traversal shares (world/src/traverse/ray.rs, in f32).
//
// A ray keeps its origin split into an integer part `o_int` and a fraction `o_frac` in [0, 1)
// (docs/NAADF.md §9), so precision does not depend on where in the world it starts.
// The direction `d` is kept exactly as given (not renormalised, which would move the line
// by an f32 rounding): times are in units of |d| and the ray's `len` converts them to
// distances. Every decision compares plane-crossing times from the one function `t_at`,
// so the traversal is a consistent walk of the event order "(t, axis), x before y before
// z at equal t"; it departs from the CPU's f64 order only where two crossings are within
// f32 rounding of each other.

// A cell bound beyond any world for unconstrained axes (the CPU walk uses 2^40, which no
// i32 holds).
const FAR_CELL: i32 = 1073741824;
const T_INF: f32 = 3.0e38;
const NO_AXIS: u32 = 3u;

struct Ray {
    o_int: vec3<i32>,
    o_frac: vec3<f32>,
    d: vec3<f32>,
    inv: vec3<f32>,
    len: f32,
}

fn ray_new(o_int: vec3<i32>, o_frac: vec3<f32>, d: vec3<f32>) -> Ray {
    // The inverse of a zero component is never read: such axes never cross a plane.
    let safe = select(vec3<f32>(1.0), d, d != vec3<f32>(0.0));
    return Ray(o_int, o_frac, d, 1.0 / safe, length(d));
}

// A ray from an unsplit origin.
fn ray_from(o: vec3<f32>, d: vec3<f32>) -> Ray {
    let fl = floor(o);
    return ray_new(vec3<i32>(fl), min(o - fl, vec3<f32>(0.99999994)), d);
}

// The ray's point at time `t`, relative to its integer origin.
fn ray_local(r: Ray, t: f32) -> vec3<f32> {
    return r.o_frac + r.d * t;
}

// A ray starting at `p` (relative to `r`'s integer origin) along `d`.
fn ray_at(r: Ray, p: vec3<f32>, d: vec3<f32>) -> Ray {
    let fl = floor(p);
    return ray_new(r.o_int + vec3<i32>(fl), min(p - fl, vec3<f32>(0.99999994)), d);
}

// Time at which the ray crosses plane `k` of `axis`.
fn t_at(r: Ray, a: u32, k: i32) -> f32 {
    return (f32(k - r.o_int[a]) - r.o_frac[a]) * r.inv[a];
}

// Whether the crossing of plane `k` of axis `b` comes before the event `(t, a)`.
fn crossed(r: Ray, b: u32, k: i32, t: f32, a: u32) -> bool {
    let tb = t_at(r, b, k);
    return tb < t || (tb == t && b < a);
}

// The cell of axis `b` right after event `(t, a)`, known to lie in `lo..=hi`.
fn cell_after(r: Ray, b: u32, t: f32, a: u32, lo: i32, hi: i32) -> i32 {
    let d = r.d[b];
    if lo == hi || d == 0.0 {
        return lo;
    }
    let p = r.o_frac[b] + d * t;
    let fl = floor(p);
    var k = clamp(i32(fl) + r.o_int[b], lo, hi);
    let f = p - fl;
    // Far from a plane the floor is certain; near one, decide by crossing times.
    let tol = 4e-6 * (abs(d * t) + 1.0);
    if f > tol && f < 1.0 - tol {
        return k;
    }
    if d > 0.0 {
        while k < hi && crossed(r, b, k + 1, t, a) {
            k += 1;
        }
        while k > lo && !crossed(r, b, k, t, a) {
            k -= 1;
        }
    } else {
        while k > lo && crossed(r, b, k, t, a) {
            k -= 1;
        }
        while k < hi && !crossed(r, b, k + 1, t, a) {
            k += 1;
        }
    }
    return k;
}

// Where a ray begins inside the box [0, size): its first cell, the time it is entered and
// the axis whose plane it crossed (NO_AXIS when the origin is inside). `ok` is false when
// the ray misses the box.
struct Entry {
    cell: vec3<i32>,
    t: f32,
    axis: u32,
    ok: bool,
}

fn ray_entry(r: Ray, size: vec3<i32>) -> Entry {
    let start = r.o_int;
    var miss = Entry(vec3<i32>(0), 0.0, NO_AXIS, false);
    if all(start >= vec3<i32>(0)) && all(start < size) {
        return Entry(start, 0.0, NO_AXIS, true);
    }
    // The last slab-entry event, in (t, axis) order.
    var bt = 0.0;
    var ba = NO_AXIS;
    for (var a = 0u; a < 3u; a++) {
        var plane: i32;
        if start[a] < 0 {
            if r.d[a] <= 0.0 {
                return miss;
            }
            plane = 0;
        } else if start[a] >= size[a] {
            if r.d[a] >= 0.0 {
                return miss;
            }
            plane = size[a];
        } else {
            continue;
        }
        let t = t_at(r, a, plane);
        if ba == NO_AXIS || t >= bt {
            bt = t;
            ba = a;
        }
    }
    var cell = vec3<i32>(0);
    for (var b = 0u; b < 3u; b++) {
        if b == ba {
            cell[b] = select(size[b] - 1, 0, r.d[b] > 0.0);
        } else if r.d[b] > 0.0 {
            cell[b] = cell_after(r, b, bt, ba, start[b], FAR_CELL);
        } else if r.d[b] < 0.0 {
            cell[b] = cell_after(r, b, bt, ba, -FAR_CELL, start[b]);
        } else {
            cell[b] = start[b];
        }
    }
    if any(cell < vec3<i32>(0)) || any(cell >= size) {
        return miss;
    }
    return Entry(cell, bt, ba, true);
}

// When a ray inside the box [0, size] leaves it: the first crossing of a far plane it moves
// toward (world/src/traverse/ray.rs `leave_time`).
fn leave_time(r: Ray, size: vec3<i32>) -> f32 {
    var t = T_INF;
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] != 0.0 {
            t = min(t, t_at(r, a, select(0, size[a], r.d[a] > 0.0)));
        }
    }
    return t;
}

// Leaving the empty cuboid made of `cell` extended by `skip` cells toward the ray on each
// axis: the exit event and the cell entered by it.
struct Exit {
    t: f32,
    axis: u32,
    next: vec3<i32>,
}

fn ray_exit(r: Ray, cell: vec3<i32>, skip: vec3<i32>) -> Exit {
    var bound = vec3<i32>(0);
    var bt = T_INF;
    var ba = 0u;
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] == 0.0 {
            continue;
        }
        bound[a] = select(cell[a] - skip[a], cell[a] + 1 + skip[a], r.d[a] > 0.0);
        let t = t_at(r, a, bound[a]);
        if t < bt {
            bt = t;
            ba = a;
        }
    }
    var next = cell;
    for (var b = 0u; b < 3u; b++) {
        if b == ba {
            next[b] = select(bound[b] - 1, bound[b], r.d[b] > 0.0);
        } else if r.d[b] > 0.0 {
            next[b] = cell_after(r, b, bt, ba, cell[b], cell[b] + skip[b]);
        } else if r.d[b] < 0.0 {
            next[b] = cell_after(r, b, bt, ba, cell[b] - skip[b], cell[b]);
        }
    }
    return Exit(bt, ba, next);
}

// Amanatides–Woo state in the same event order (ties step the lowest axis first).
struct Dda {
    cell: vec3<i32>,
    tmax: vec3<f32>,
    t: f32,
    axis: u32,
}

fn dda_start(r: Ray, e: Entry) -> Dda {
    var tmax = vec3<f32>(T_INF);
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] != 0.0 {
            tmax[a] = t_at(r, a, select(e.cell[a], e.cell[a] + 1, r.d[a] > 0.0));
        }
    }
    return Dda(e.cell, tmax, e.t, e.axis);
}

fn dda_advance(r: Ray, s: ptr<function, Dda>) {
    var a = 0u;
    if (*s).tmax[1] < (*s).tmax[a] {
        a = 1u;
    }
    if (*s).tmax[2] < (*s).tmax[a] {
        a = 2u;
    }
    (*s).t = (*s).tmax[a];
    let c = (*s).cell[a] + select(-1, 1, r.d[a] > 0.0);
    (*s).cell[a] = c;
    (*s).axis = a;
    (*s).tmax[a] = t_at(r, a, select(c, c + 1, r.d[a] > 0.0));
}

// The first solid voxel along a ray (of the world, or of an entity: then voxel and normal
// are entity-local).
struct Hit {
    hit: bool,
    // The step budget ran out (counts as a miss).
    exhausted: bool,
    voxel: vec3<i32>,
    // Axis of the entry face (NO_AXIS: the origin was inside the voxel).
    axis: u32,
    // Entry-face normal (zero when the origin was inside).
    normal: vec3<i32>,
    // Time of entry, in units of the ray's |d|.
    t: f32,
    material: u32,
    steps: u32,
    // Entity id, or NO_ENTITY (generated in the prelude).
    entity: u32,
}

fn no_hit(steps: u32) -> Hit {
    return Hit(false, false, vec3<i32>(0), NO_AXIS, vec3<i32>(0), T_INF, 0u, steps, NO_ENTITY);
}

fn make_hit(r: Ray, cell: vec3<i32>, t: f32, axis: u32, material: u32, steps: u32) -> Hit {
    var n = vec3<i32>(0);
    if axis != NO_AXIS {
        n[axis] = select(1, -1, r.d[axis] > 0.0);
    }
    return Hit(true, false, cell, axis, n, t, material, steps, NO_ENTITY);
}

// The instances as the page finds them: each entity's world box from its record in the
// instance buffer (slot = entity id, zero slots empty; docs/FORMAT.md §5.8), and the
// four-wide hierarchy over those boxes that the shaders walk (docs/FORMAT.md §5.10). Both
// are the native client's (naadf_world::entity::bounds and ::bvh) word for word: the same
// binned surface-area build in the same f64 arithmetic, which the browser tests check
// against `naadf_world::entity::hierarchy_words`. It also lays out the page's local
// instances (docs/FORMAT.md §5.11): solid boxes drawn on this page's GPU only, after the
// world's.
import { BVH, ENTITY } from "./gen/layout";

/** Words per instance record. */
export const RECORD_WORDS = ENTITY.RECORD_WORDS;

/** A local instance of the page: an unrotated solid box of one material, its corner at a
 * voxel (a tool's preview). */
export interface LocalBox {
  min: number[];
  size: number[];
  material: number;
}

/** The longest edge of a local box (an entity type's). */
export const MAX_LOCAL_EDGE = 127;

/** The type voxels and records of `boxes` when their types follow the world's first
 * `typeBase` type voxels (a multiple of `ENTITY.TYPE_ALIGN`): each box gets a type grid of
 * its material and a record with the local id and the identity rotation. */
export function localLayout(boxes: LocalBox[], typeBase: number): { types: Uint32Array; records: Uint32Array } {
  const align = (n: number) => Math.ceil(n / ENTITY.TYPE_ALIGN) * ENTITY.TYPE_ALIGN;
  const lengths = boxes.map((b) => align(b.size[0] * b.size[1] * b.size[2]));
  const types = new Uint32Array(lengths.reduce((a, b) => a + b, 0));
  const records = new Uint32Array(boxes.length * RECORD_WORDS);
  let at = 0;
  boxes.forEach((b, k) => {
    types.fill((ENTITY.SOLID | b.material) >>> 0, at, at + b.size[0] * b.size[1] * b.size[2]);
    const [px, py, pz] = b.min.map((v) => v * 128);
    const [sx, sy, sz] = b.size;
    const r = k * RECORD_WORDS;
    records[r] = (px & 0x1fffff) | ((py & 0x7ff) << 21);
    records[r + 1] = (pz & 0x1fffff) | (((py >>> 11) & 0xff) << 21) | (((sz >>> 4) & 7) << 29);
    records[r + 2] = ENTITY.IDENTITY_ROTATION[0];
    records[r + 3] = (ENTITY.IDENTITY_ROTATION[1] & 0xfff) | (((typeBase + at) / ENTITY.TYPE_ALIGN) << 12);
    records[r + 4] = ENTITY.LOCAL_ID | (sx << 14) | (sy << 21) | ((sz & 0xf) << 28);
    at += lengths[k];
  });
  return { types, records };
}

/** An axis-aligned box `[lo, hi]`. */
export type Box = [number[], number[]];

/** Decodes a smallest-three quaternion `[x, y, z, w]` (world/src/entity/pack.rs), in its
 * order of operations. */
function decodeQuat(w0: number, w1: number): number[] {
  const small = [w0 & 0x3fff, (w0 >>> 14) & 0x3fff, (w0 >>> 28) | ((w1 & 0x3ff) << 4)].map((v) => (v - 8192) / 8192);
  const sum = small[0] * small[0] + small[1] * small[1] + small[2] * small[2];
  const rest = Math.sqrt(Math.max(1 - sum, 0));
  small.splice((w1 >>> 10) & 3, 0, rest);
  return small;
}

/** The world box of the instance in `slot` of the instance buffer `words`, padded by
 * `BVH.BOUNDS_PAD` (what the hierarchy is built over), or undefined for an empty slot. */
export function instanceBox(words: Uint32Array, slot: number): Box | undefined {
  const r = slot * RECORD_WORDS;
  const e = words[r + 4];
  if (!e) return undefined;
  const [dx, dy, dz, dw] = [words[r], words[r + 1], words[r + 2], words[r + 3]];
  const size = [(e >>> 14) & 0x7f, (e >>> 21) & 0x7f, ((e >>> 28) & 0xf) | (((dy >>> 29) & 7) << 4)];
  const pos = [dx & 0x1fffff, (dx >>> 21) | (((dy >>> 21) & 0xff) << 11), dy & 0x1fffff].map((v) => v / 128);
  const inv = decodeQuat(dz, dw & 0xfff);
  // The rotation entity → world (the conjugate), applied to each corner `v` as
  // pack.rs's `rotate` does: `v + w·t + u × t` with `t = 2 (u × v)`, in its operations'
  // order (scalars, as this runs for every instance on every change).
  const [ux, uy, uz, w] = [-inv[0], -inv[1], -inv[2], inv[3]];
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (let c = 0; c < 8; c++) {
    const vx = c & 1 ? size[0] : 0;
    const vy = c & 2 ? size[1] : 0;
    const vz = c & 4 ? size[2] : 0;
    const tx = 2 * (uy * vz - uz * vy);
    const ty = 2 * (uz * vx - ux * vz);
    const tz = 2 * (ux * vy - uy * vx);
    const p = [vx + w * tx + (uy * tz - uz * ty), vy + w * ty + (uz * tx - ux * tz), vz + w * tz + (ux * ty - uy * tx)];
    for (let a = 0; a < 3; a++) {
      lo[a] = Math.min(lo[a], p[a] + pos[a]);
      hi[a] = Math.max(hi[a], p[a] + pos[a]);
    }
  }
  return [lo.map((v) => v - BVH.BOUNDS_PAD), hi.map((v) => v + BVH.BOUNDS_PAD)];
}

const F32 = new Float32Array(1);
const F32_BITS = new Int32Array(F32.buffer);

/** `v` as an f32, padded by `BVH.F32_PAD` and rounded outward: up for an upper bound (`up`),
 * down otherwise. */
function outward(v: number, up: boolean): number {
  const p = up ? v + BVH.F32_PAD : v - BVH.F32_PAD;
  F32[0] = p;
  const f = F32[0];
  if (up ? f >= p : f <= p) return f;
  // One step of the f32 grid toward the side of `p`, as Rust's `next_up` and `next_down`.
  if (f === 0) {
    F32_BITS[0] = 1;
    return up ? F32[0] : -F32[0];
  }
  F32_BITS[0] += (f > 0) === up ? 1 : -1;
  return F32[0];
}

/** A node of the binary tree the four-wide one is made from: its box (`lo` then `hi`, as
 * `BoxArray` holds them), and two children or one instance (`prim`). */
interface Binary {
  box: Float64Array;
  kids?: [Binary, Binary];
  prim: number;
}

/** Boxes as six f64 each (`lo.xyz`, `hi.xyz`), so that a build allocates little. */
type BoxArray = Float64Array;

/** Empties box `i` of `b`. */
function clear(b: BoxArray, i: number): void {
  b.fill(Infinity, 6 * i, 6 * i + 3);
  b.fill(-Infinity, 6 * i + 3, 6 * i + 6);
}

/** Grows box `i` of `into` by box `j` of `from`. */
function grow(into: BoxArray, i: number, from: BoxArray, j: number): void {
  for (let a = 0; a < 3; a++) {
    into[6 * i + a] = Math.min(into[6 * i + a], from[6 * j + a]);
    into[6 * i + 3 + a] = Math.max(into[6 * i + 3 + a], from[6 * j + 3 + a]);
  }
}

/** Half the surface area of box `i` of `b` (the native build's, in its operations' order). */
function halfArea(b: BoxArray, i: number): number {
  const x = Math.max(b[6 * i + 3] - b[6 * i], 0);
  const y = Math.max(b[6 * i + 4] - b[6 * i + 1], 0);
  const z = Math.max(b[6 * i + 5] - b[6 * i + 2], 0);
  return x * y + y * z + z * x;
}

function binOf(c: number, lo: number, hi: number): number {
  if (hi <= lo) return 0;
  return Math.min(Math.floor(((c - lo) / (hi - lo)) * BVH.BINS), BVH.BINS - 1);
}

/** Builds the hierarchy's binary tree over the primitives' `boxes` as
 * `naadf_world::entity::bvh` does: the binned SAH down to one primitive per leaf (runs of at
 * most four, and every run below `BVH.SAH_DEPTH` levels, at the median), reordering the
 * primitives in place as it does, so that the trees are the same. */
function buildBinary(boxes: BoxArray): Binary {
  const n = boxes.length / 6;
  // Each primitive's centre, as a box of one point (so that `bound` takes centres too).
  const centres = new Float64Array(6 * n);
  for (let p = 0; p < n; p++) {
    for (let a = 0; a < 3; a++) centres[6 * p + a] = centres[6 * p + 3 + a] = 0.5 * (boxes[6 * p + a] + boxes[6 * p + 3 + a]);
  }
  const prims = Int32Array.from({ length: n }, (_, i) => i);
  const BINS = BVH.BINS;
  const bins = new Float64Array(6 * 3 * BINS);
  const counts = new Int32Array(3 * BINS);
  const acc = new Float64Array(6);
  const aboveArea = new Float64Array(BINS);
  const aboveCount = new Int32Array(BINS);
  // Box 0 of `into` made the bound of the boxes in `of` of the primitives `prims[from..to]`.
  const bound = (into: BoxArray, of: BoxArray, from: number, to: number) => {
    clear(into, 0);
    for (let i = from; i < to; i++) grow(into, 0, of, prims[i]);
  };
  // The range of the centres of a run.
  const range = new Float64Array(6);
  // The cheapest cut of `prims[from..to]` that leaves primitives on both sides.
  const bestCut = (from: number, to: number) => {
    bound(range, centres, from, to);
    const lo = range.slice(0, 3);
    const hi = range.slice(3, 6);
    for (let b = 0; b < 3 * BINS; b++) clear(bins, b);
    counts.fill(0);
    for (let i = from; i < to; i++) {
      const p = prims[i];
      for (let axis = 0; axis < 3; axis++) {
        const bin = axis * BINS + binOf(centres[6 * p + axis], lo[axis], hi[axis]);
        grow(bins, bin, boxes, p);
        counts[bin] += 1;
      }
    }
    let best: { axis: number; lo: number; hi: number; bin: number; cost: number } | undefined;
    for (let axis = 0; axis < 3; axis++) {
      if (hi[axis] <= lo[axis]) continue;
      clear(acc, 0);
      let count = 0;
      for (let k = BINS - 1; k >= 1; k--) {
        grow(acc, 0, bins, axis * BINS + k);
        count += counts[axis * BINS + k];
        aboveArea[k] = halfArea(acc, 0);
        aboveCount[k] = count;
      }
      clear(acc, 0);
      count = 0;
      for (let k = 1; k < BINS; k++) {
        grow(acc, 0, bins, axis * BINS + k - 1);
        count += counts[axis * BINS + k - 1];
        if (count === 0 || aboveCount[k] === 0) continue;
        const cost = halfArea(acc, 0) * count + aboveArea[k] * aboveCount[k];
        if (!best || cost < best.cost) best = { axis, lo: lo[axis], hi: hi[axis], bin: k, cost };
      }
    }
    return best;
  };
  // Orders `prims[from..to]` by centre along the axis where the centres spread most (the
  // last such axis, as Rust's `max_by`; ties by index) and returns the middle.
  const median = (from: number, to: number) => {
    bound(range, centres, from, to);
    let axis = 0;
    for (let a = 1; a < 3; a++) if (range[3 + a] - range[a] >= range[3 + axis] - range[axis]) axis = a;
    prims.subarray(from, to).sort((p, q) => centres[6 * p + axis] - centres[6 * q + axis] || p - q);
    return from + ((to - from) >> 1);
  };
  const split = (from: number, to: number, depth: number): Binary => {
    const box = new Float64Array(6);
    bound(box, boxes, from, to);
    if (to - from === 1) return { box, prim: prims[from] };
    const cut = depth < BVH.SAH_DEPTH && to - from > 4 ? bestCut(from, to) : undefined;
    let mid: number;
    if (cut) {
      const lower = (p: number) => binOf(centres[6 * p + cut.axis], cut.lo, cut.hi) < cut.bin;
      let [i, j] = [from, to];
      while (i < j) {
        if (lower(prims[i])) i += 1;
        else {
          j -= 1;
          [prims[i], prims[j]] = [prims[j], prims[i]];
        }
      }
      mid = i;
    } else {
      mid = median(from, to);
    }
    return { box, kids: [split(from, mid, depth + 1), split(mid, to, depth + 1)], prim: 0 };
  };
  return split(0, n, 0);
}

/** The live instances of the instance buffer `words`: their slots and their boxes (as
 * `BoxArray` holds them), in slot order. */
function liveBoxes(words: Uint32Array): { slots: number[]; boxes: BoxArray } {
  const slots: number[] = [];
  const live: Box[] = [];
  for (let slot = 0; slot < words.length / RECORD_WORDS; slot++) {
    const box = instanceBox(words, slot);
    if (box) {
      live.push(box);
      slots.push(slot);
    }
  }
  const boxes = new Float64Array(6 * live.length);
  live.forEach(([lo, hi], p) => {
    boxes.set(lo, 6 * p);
    boxes.set(hi, 6 * p + 3);
  });
  return { slots, boxes };
}

/** Gives every node of `tree` the box of its primitives in `boxes` (a refit: the same
 * shape, new boxes). */
function refit(tree: Binary, boxes: BoxArray): void {
  clear(tree.box, 0);
  if (!tree.kids) {
    grow(tree.box, 0, boxes, tree.prim);
    return;
  }
  for (const kid of tree.kids) {
    refit(kid, boxes);
    grow(tree.box, 0, kid.box, 0);
  }
}

/** Words of a packed node before its child references: six axis rows of four f32 lanes. */
const ROWS = 24;

/** The packed four-wide form of `tree` (leaves' primitives as their `slots`): each binary
 * node's children and grandchildren become one node's lanes, boxes as f32 axis by axis,
 * then the lanes' references (`BVH.LEAF | slot` for an instance). */
function packed(tree: Binary, slots: number[]): Uint32Array {
  const nodes: Uint32Array[] = [];
  const widen = (b: Binary): number => {
    const index = nodes.length;
    const node = new Uint32Array(BVH.NODE_WORDS);
    const rows = new Float32Array(node.buffer, 0, ROWS);
    rows.fill(BVH.FAR);
    node.fill(BVH.NONE, ROWS);
    nodes.push(node);
    const lanes = b.kids ? b.kids.flatMap((k) => (k.kids ? k.kids : [k])) : [b];
    lanes.forEach((c, lane) => {
      for (let a = 0; a < 3; a++) {
        rows[8 * a + lane] = outward(c.box[a], false);
        rows[8 * a + 4 + lane] = outward(c.box[3 + a], true);
      }
      node[ROWS + lane] = c.kids ? widen(c) : (BVH.LEAF | slots[c.prim]) >>> 0;
    });
    return index;
  };
  widen(tree);
  const out = new Uint32Array(nodes.length * BVH.NODE_WORDS);
  nodes.forEach((n, i) => out.set(n, i * BVH.NODE_WORDS));
  return out;
}

/** The surface-area estimate of the nodes a ray meeting the root visits, from the packed
 * form, as `Bvh::expected_visits` works it out (in its order of operations): 1 plus the
 * inner lanes' areas over the root's. */
function expectedVisits(words: Uint32Array): number {
  const rows = new Float32Array(words.buffer, words.byteOffset, words.length);
  const lane = new Float64Array(6);
  const root = new Float64Array(6);
  clear(root, 0);
  let inner = 0;
  for (let n = 0; n < words.length / BVH.NODE_WORDS; n++) {
    const at = n * BVH.NODE_WORDS;
    for (let l = 0; l < 4; l++) {
      const child = words[at + ROWS + l];
      if (child === BVH.NONE) continue;
      for (let a = 0; a < 3; a++) {
        lane[a] = rows[at + 8 * a + l];
        lane[3 + a] = rows[at + 8 * a + 4 + l];
      }
      if (n === 0) grow(root, 0, lane, 0);
      if (!(child & BVH.LEAF)) inner += halfArea(lane, 0);
    }
  }
  return 1 + inner / halfArea(root, 0);
}

/** The packed four-wide hierarchy over the instances of the instance buffer `words`
 * (empty when there is none), built afresh as `naadf_world::entity::hierarchy_words`
 * builds it. */
export function hierarchyWords(words: Uint32Array): Uint32Array {
  return new InstanceHierarchy().update(words);
}

/** The hierarchy over an instance buffer, kept from one change of the buffer to the next
 * as the native client keeps it (docs/FORMAT.md §5.10): refitted while the same slots hold
 * instances and its expected node visits stay within `BVH.REFIT_SLACK` times its build's,
 * built anew otherwise. */
export class InstanceHierarchy {
  private slots: number[] = [];
  private tree: Binary | undefined;
  private builtVisits = 0;

  /** The packed hierarchy for the instance buffer `words`, which replaces the last one. */
  update(words: Uint32Array): Uint32Array {
    const { slots, boxes } = liveBoxes(words);
    if (slots.length === 0) {
      this.tree = undefined;
      this.slots = [];
      return new Uint32Array(0);
    }
    const sameSlots = slots.length === this.slots.length && slots.every((s, i) => s === this.slots[i]);
    if (this.tree && sameSlots) {
      refit(this.tree, boxes);
      const out = packed(this.tree, slots);
      if (expectedVisits(out) <= BVH.REFIT_SLACK * this.builtVisits) return out;
    }
    this.tree = buildBinary(boxes);
    this.slots = slots;
    const out = packed(this.tree, slots);
    this.builtVisits = expectedVisits(out);
    return out;
  }
}

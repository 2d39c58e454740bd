// The instances as the page finds them: each entity's world box from its record in the
// instance buffer (slot = entity id, zero slots empty; docs/FORMAT.md §5.8), and the
// four-wide hierarchy over those boxes that the shaders walk (docs/FORMAT.md §5.10). The
// native client derives the same packed form in Rust (naadf_world::entity::bvh) with a
// surface-area build; the page splits at the median, which is simpler and only changes how
// many boxes a ray tests, never what it hits. It also lays out the page's local instances
// (docs/FORMAT.md §5.11): solid boxes drawn on this page's GPU only, after the world's.
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

/** Decodes a smallest-three quaternion `[x, y, z, w]` (world/src/entity/pack.rs). */
function decodeQuat(w0: number, w1: number): number[] {
  const small = [w0 & 0x3fff, (w0 >>> 14) & 0x3fff, (w0 >>> 28) | ((w1 & 0x3ff) << 4)].map((v) => (v - 8192) / 8192);
  const rest = Math.sqrt(Math.max(0, 1 - small[0] ** 2 - small[1] ** 2 - small[2] ** 2));
  small.splice((w1 >>> 10) & 3, 0, rest);
  return small;
}

/** Rotates `v` by the unit quaternion `q = [x, y, z, w]`. */
function rotate(q: number[], v: number[]): number[] {
  const cross = (a: number[], b: number[]) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const t = cross(q, v).map((c) => 2 * c);
  const u = cross(q, t);
  return [0, 1, 2].map((a) => v[a] + q[3] * t[a] + u[a]);
}

/** The world box of the instance in `slot` of the instance buffer `words`, padded as the
 * shaders' boxes are (`BVH.PAD`), or undefined for an empty slot. */
export function instanceBox(words: Uint32Array, slot: number): Box | undefined {
  const r = slot * RECORD_WORDS;
  const e = words[r + 4];
  if (!e) return undefined;
  const [dx, dy, dz, dw] = [words[r], words[r + 1], words[r + 2], words[r + 3]];
  const size = [(e >>> 14) & 0x7f, (e >>> 21) & 0x7f, ((e >>> 28) & 0xf) | (((dy >>> 29) & 7) << 4)];
  const pos = [dx & 0x1fffff, (dx >>> 21) | (((dy >>> 21) & 0xff) << 11), dy & 0x1fffff].map((v) => v / 128);
  const inv = decodeQuat(dz, dw & 0xfff);
  const rot = [-inv[0], -inv[1], -inv[2], inv[3]];
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (let c = 0; c < 8; c++) {
    const p = rotate(rot, [0, 1, 2].map((a) => ((c >> a) & 1 ? size[a] : 0)));
    for (let a = 0; a < 3; a++) {
      lo[a] = Math.min(lo[a], pos[a] + p[a] - BVH.PAD);
      hi[a] = Math.max(hi[a], pos[a] + p[a] + BVH.PAD);
    }
  }
  return [lo, hi];
}

/** `v` as an f32, rounded up (`up`) or down. */
function toF32(v: number, up: boolean): number {
  const f = new Float32Array([v]);
  const bits = new Int32Array(f.buffer);
  if (up && f[0] < v) bits[0] += f[0] >= 0 ? 1 : -1;
  if (!up && f[0] > v) bits[0] += f[0] > 0 ? -1 : 1;
  return f[0];
}

interface Binary {
  box: Box;
  kids?: [Binary, Binary];
  slot: number;
}

interface Item {
  slot: number;
  box: Box;
}

const centre = (b: Box, a: number) => (b[0][a] + b[1][a]) / 2;

/** The binary tree over `items`, split at the median of the axis where the centres spread
 * most (ties by slot), down to one instance per leaf: at most 14 levels for 16383. */
function split(items: Item[]): Binary {
  const box: Box = [[0, 1, 2].map((a) => Math.min(...items.map((i) => i.box[0][a]))), [0, 1, 2].map((a) => Math.max(...items.map((i) => i.box[1][a])))];
  if (items.length === 1) return { box, slot: items[0].slot };
  const spread = (a: number) => {
    const c = items.map((i) => centre(i.box, a));
    return Math.max(...c) - Math.min(...c);
  };
  const spreads = [0, 1, 2].map(spread);
  const axis = spreads.indexOf(Math.max(...spreads));
  const sorted = [...items].sort((p, q) => centre(p.box, axis) - centre(q.box, axis) || p.slot - q.slot);
  const mid = sorted.length >> 1;
  return { box, kids: [split(sorted.slice(0, mid)), split(sorted.slice(mid))], slot: 0 };
}

/** The packed four-wide hierarchy over the instances of the instance buffer `words`
 * (empty when there is none): each binary node's children and grandchildren become one
 * node's lanes, boxes as f32 axis by axis, then the lanes' references. */
export function hierarchyWords(words: Uint32Array): Uint32Array {
  const items: Item[] = [];
  for (let slot = 0; slot < words.length / RECORD_WORDS; slot++) {
    const box = instanceBox(words, slot);
    if (box) items.push({ slot, box });
  }
  if (items.length === 0) return new Uint32Array(0);
  const nodes: Uint32Array[] = [];
  const widen = (b: Binary): number => {
    const index = nodes.length;
    const node = new Uint32Array(BVH.NODE_WORDS);
    const boxes = new Float32Array(node.buffer, 0, 24);
    boxes.fill(BVH.FAR);
    node.fill(BVH.NONE, 24);
    nodes.push(node);
    const lanes = b.kids ? b.kids.flatMap((k) => (k.kids ? k.kids : [k])) : [b];
    lanes.forEach((c, lane) => {
      for (let a = 0; a < 3; a++) {
        boxes[8 * a + lane] = toF32(c.box[0][a], false);
        boxes[8 * a + 4 + lane] = toF32(c.box[1][a], true);
      }
      node[24 + lane] = c.kids ? widen(c) : (BVH.LEAF | c.slot) >>> 0;
    });
    return index;
  };
  widen(split(items));
  const out = new Uint32Array(nodes.length * BVH.NODE_WORDS);
  nodes.forEach((n, i) => out.set(n, i * BVH.NODE_WORDS));
  return out;
}

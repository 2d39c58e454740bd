// The editing tools: what each one would change at the voxel under the pointer (the preview)
// and the ops-JSON line it sends when committed (docs/OPS.md).
import { srgb8 } from "./colour";
import type { Mirror } from "./mirror";
import type { Pick, Voxels } from "./pick";
import { MAX_LOCAL_EDGE } from "./instances";
import type { LocalBox } from "./instances";

type V3 = [number, number, number];

/** The tools, in the toolbar's order. */
export const TOOLS = ["voxel", "erase", "box", "sphere", "paint", "flood"] as const;
export type Tool = (typeof TOOLS)[number];

/** The most voxels a flood paint from the page may change. */
export const FLOOD_LIMIT = 65536;

/** The tool in hand. */
export interface ToolState {
  tool: Tool;
  material: number;
  radius: number;
  /** The box tool's first corner, once clicked. */
  anchor: V3 | undefined;
}

/** What a commit would change: a box of voxels (max exclusive), for the preview. */
export interface Region {
  min: V3;
  max: V3;
  /** Why nothing would change, when nothing would. */
  refusal?: string;
}

const add = (a: V3, d: number): V3 => [a[0] + d, a[1] + d, a[2] + d];
const centre = (v: V3): V3 => [v[0] + 0.5, v[1] + 0.5, v[2] + 0.5];

/** The box that a ball of `radius` around `c` touches (voxel centres strictly inside). */
function ballBox(c: V3, radius: number): Region {
  const min = c.map((x) => Math.floor(x - radius - 0.5) + 1) as V3;
  const max = c.map((x) => Math.ceil(x + radius - 0.5)) as V3;
  return { min, max };
}

/** The box with corner voxels `a` and `b`. */
function boxRegion(a: V3, b: V3): Region {
  return { min: a.map((x, i) => Math.min(x, b[i])) as V3, max: a.map((x, i) => Math.max(x, b[i]) + 1) as V3 };
}

/** The voxels a flood paint from `start` would change, as their bounding box. */
function floodRegion(w: Voxels, start: V3, material: number): Region {
  const from = w.cell(start[0], start[1], start[2]).material;
  if (from === material) return { min: start, max: add(start, 1), refusal: "already that material" };
  const seen = new Set<number>();
  const key = (v: V3) => v[0] + w.size[0] * (v[1] + w.size[1] * v[2]);
  const todo: V3[] = [start];
  seen.add(key(start));
  const min: V3 = [...start];
  const max: V3 = add(start, 1);
  while (todo.length) {
    const v = todo.pop()!;
    for (let a = 0; a < 3; a++) {
      min[a] = Math.min(min[a], v[a]);
      max[a] = Math.max(max[a], v[a] + 1);
    }
    for (const [dx, dy, dz] of [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]]) {
      const n: V3 = [v[0] + dx, v[1] + dy, v[2] + dz];
      if (!w.inside(n[0], n[1], n[2]) || seen.has(key(n)) || w.cell(n[0], n[1], n[2]).material !== from) continue;
      if (seen.size >= FLOOD_LIMIT) return { min, max, refusal: `more than ${FLOOD_LIMIT} voxels` };
      seen.add(key(n));
      todo.push(n);
    }
  }
  return { min, max };
}

/** What committing `s` at `at` would change. */
export function preview(s: ToolState, w: Voxels, at: Pick): Region {
  switch (s.tool) {
    case "voxel":
      return { min: at.before, max: add(at.before, 1) };
    case "erase":
      return { min: at.voxel, max: add(at.voxel, 1) };
    case "box":
      return boxRegion(s.anchor ?? at.before, at.before);
    case "sphere":
      return ballBox(centre(at.before), s.radius);
    case "paint":
      return ballBox(centre(at.voxel), s.radius);
    case "flood":
      return floodRegion(w, at.voxel, s.material);
  }
}

/** What a commit of the voxel or box tool would build, as solid local instances for the
 * GPU to draw in place (the other tools' changes are not solid boxes, and keep the
 * overlay's outline alone): empty when nothing would change. */
export function solidPreview(s: ToolState, r: Region | undefined): LocalBox[] {
  if (!r || r.refusal || (s.tool !== "voxel" && s.tool !== "box")) return [];
  const size = r.max.map((v, a) => v - r.min[a]);
  if (size.some((e) => e < 1 || e > MAX_LOCAL_EDGE) || r.min.some((v) => v < 0)) return [];
  return [{ min: [...r.min], size, material: s.material }];
}

/** The ops line committing `s` at `at` sends, or `undefined` when the click only set the
 * box's first corner. */
export function commit(s: ToolState, at: Pick): string | undefined {
  const m = s.material;
  switch (s.tool) {
    case "voxel":
      return JSON.stringify({ op: "set", voxels: [[...at.before, m]] });
    case "erase":
      return JSON.stringify({ op: "set", voxels: [[...at.voxel, 0]] });
    case "box": {
      if (!s.anchor) {
        s.anchor = at.before;
        return undefined;
      }
      const r = boxRegion(s.anchor, at.before);
      s.anchor = undefined;
      return JSON.stringify({ op: "box", min: r.min, max: r.max, material: m });
    }
    case "sphere":
      return JSON.stringify({ op: "sphere", center: centre(at.before), radius: s.radius, material: m });
    case "paint":
      return JSON.stringify({ op: "paint", center: centre(at.voxel), radius: s.radius, material: m });
    case "flood":
      return JSON.stringify({ op: "flood_paint", start: at.voxel, material: m, limit: FLOOD_LIMIT });
  }
}

/** A material of the world's table, for the palette. */
export interface Swatch {
  id: number;
  /** CSS colour of its albedo. */
  colour: string;
  /** Its kind (word 0, bits 0–1): 0 diffuse, 1 emissive, 2 metal, 3 mirror. */
  kind: number;
}

/** Half-float bits to a number. */
function half(h: number): number {
  const e = (h >> 10) & 0x1f;
  const f = h & 0x3ff;
  const s = h & 0x8000 ? -1 : 1;
  if (e === 0) return s * f * 2 ** -24;
  if (e === 31) return f ? NaN : s * Infinity;
  return s * (1 + f / 1024) * 2 ** (e - 15);
}

/** The palette: every material of the table but 0 (empty), with its albedo (docs/FORMAT.md §5.4). */
export function palette(m: Mirror): Swatch[] {
  const words = m.words(4);
  const out: Swatch[] = [];
  for (let id = 1; 4 * id + 3 < words.length; id++) {
    const w1 = words[4 * id + 1];
    const w2 = words[4 * id + 2];
    const [r, g, bl] = [half(w1 & 0xffff), half(w1 >>> 16), half(w2 & 0xffff)];
    out.push({ id, colour: `rgb(${srgb8(r)},${srgb8(g)},${srgb8(bl)})`, kind: words[4 * id] & 3 });
  }
  return out;
}

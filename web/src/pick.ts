// What is under the pointer: the voxels of the mirror read through the world's cell layout
// (docs/FORMAT.md §5.1–5.3), and a ray walked voxel by voxel, empty chunks and blocks
// skipped whole.
import { EMPTY, FULL, MATERIAL_MASK, POINTER_MASK, state } from "./cell";
import type { Mirror } from "./mirror";

type V3 = [number, number, number];

/** Reads the world's cells from a mirror's buffers. */
export class Voxels {
  private readonly chunks: Uint32Array;
  private readonly blocks: Uint32Array;
  private readonly voxels: Uint32Array;
  readonly size: V3;
  private readonly dims: V3;

  constructor(m: Mirror) {
    this.chunks = m.words(0);
    this.blocks = m.words(2);
    this.voxels = m.words(3);
    this.size = m.size;
    this.dims = [m.size[0] >> 4, m.size[1] >> 4, m.size[2] >> 4];
  }

  /** Whether `(x, y, z)` lies in the world. */
  inside(x: number, y: number, z: number): boolean {
    return x >= 0 && y >= 0 && z >= 0 && x < this.size[0] && y < this.size[1] && z < this.size[2];
  }

  /** The material at a voxel (0: empty), and the edge of the empty cell around it (1, 4 or 16). */
  cell(x: number, y: number, z: number): { material: number; edge: number } {
    const [cx, cy, cz] = [x >> 4, y >> 4, z >> 4];
    const chunk = this.chunks[cx + this.dims[0] * (cy + this.dims[1] * cz)];
    const cs = state(chunk);
    if (cs === EMPTY) return { material: 0, edge: 16 };
    if (cs === FULL) return { material: chunk & MATERIAL_MASK, edge: 16 };
    const block = this.blocks[(chunk & POINTER_MASK) + (((x >> 2) & 3) + 4 * ((y >> 2) & 3) + 16 * ((z >> 2) & 3))];
    const bs = state(block);
    if (bs === EMPTY) return { material: 0, edge: 4 };
    if (bs === FULL) return { material: block & MATERIAL_MASK, edge: 4 };
    const i = (x & 3) + 4 * (y & 3) + 16 * (z & 3);
    const word = this.voxels[(block & POINTER_MASK) + (i >> 1)];
    const v = i & 1 ? word >>> 16 : word & 0xffff;
    return { material: v & 0x8000 ? v & MATERIAL_MASK : 0, edge: 1 };
  }
}

/** A ray's first solid voxel, the empty voxel it came from, and the face it crossed. */
export interface Pick {
  voxel: V3;
  before: V3;
  material: number;
}

/** Walks the ray `origin + t·dir` through the world for at most `maxDistance` voxels. */
export function pick(w: Voxels, origin: V3, dir: V3, maxDistance = 4096): Pick | undefined {
  // Enter the world's box first.
  let t = 0;
  let tExit = maxDistance;
  for (let a = 0; a < 3; a++) {
    if (dir[a] === 0) {
      if (origin[a] < 0 || origin[a] >= w.size[a]) return undefined;
      continue;
    }
    const t0 = (0 - origin[a]) / dir[a];
    const t1 = (w.size[a] - origin[a]) / dir[a];
    t = Math.max(t, Math.min(t0, t1));
    tExit = Math.min(tExit, Math.max(t0, t1));
  }
  if (t > tExit) return undefined;
  const eps = 1e-7;
  let before: V3 | undefined;
  while (t <= tExit) {
    const p = origin.map((o, a) => o + dir[a] * (t + eps)) as V3;
    const v = p.map(Math.floor) as V3;
    if (!w.inside(v[0], v[1], v[2])) return undefined;
    const c = w.cell(v[0], v[1], v[2]);
    if (c.material !== 0) return { voxel: v, before: before ?? v, material: c.material };
    before = v;
    // Leave the empty cell (of edge `c.edge`) that holds the voxel.
    let next = Infinity;
    for (let a = 0; a < 3; a++) {
      if (dir[a] === 0) continue;
      const lo = Math.floor(v[a] / c.edge) * c.edge;
      const bound = dir[a] > 0 ? lo + c.edge : lo;
      next = Math.min(next, (bound - origin[a]) / dir[a]);
    }
    // Step into the neighbouring voxel of the cell just left (its last voxel on the way).
    const exit = origin.map((o, a) => o + dir[a] * (next - eps)) as V3;
    before = exit.map(Math.floor) as V3;
    t = Math.max(next, t + eps);
  }
  return undefined;
}

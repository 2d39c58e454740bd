// Which chunks show something else after a change, as the native client works it out
// (world/src/fingerprint.rs): a fingerprint per chunk of what a ray sees there (its voxels'
// materials and its entity records; distance fields left out, since they change across
// wide empty areas after any edit but change nothing a ray sees). The GI's history drops
// or shortens the light on and near the chunks a change touched (docs/RENDERING.md §3c).
import { BLOCKS, FULL, GROUP_WORDS, MATERIAL_MASK, MIXED, POINTER_MASK, state } from "./cell";
import type { Mirror, Touched } from "./mirror";

/** What changed between two versions: these chunks (ascending), or everything (the
 * materials, the entity types or the world's size). */
export type ChunkChanges = number[] | "everything";

/** Words per entity instance record (docs/FORMAT.md §5.8). */
const RECORD_WORDS = 5;

/** The buffers' words, as a chunk's fingerprint reads them. */
interface Words {
  chunks: Uint32Array;
  entities: Uint32Array;
  blocks: Uint32Array;
  voxels: Uint32Array;
  records: Uint32Array;
}

function wordsOf(m: Mirror): Words {
  return { chunks: m.words(0), entities: m.words(1), blocks: m.words(2), voxels: m.words(3), records: m.words(7) };
}

/** A 53-bit hash of a sequence of 32-bit words (cyrb53's mixing), fed a word at a time. */
class Hasher {
  private h1 = 0xdeadbeef;
  private h2 = 0x41c6ce57;

  word(w: number): void {
    this.h1 = Math.imul(this.h1 ^ w, 2654435761);
    this.h2 = Math.imul(this.h2 ^ w, 1597334677);
  }

  words(list: Uint32Array): void {
    for (let i = 0; i < list.length; i++) this.word(list[i]);
  }

  digest(): number {
    let h1 = Math.imul(this.h1 ^ (this.h1 >>> 16), 2246822507);
    h1 ^= Math.imul(this.h2 ^ (this.h2 >>> 13), 3266489909);
    let h2 = Math.imul(this.h2 ^ (this.h2 >>> 16), 2246822507);
    h2 ^= Math.imul(h1 ^ (h1 >>> 13), 3266489909);
    return 4294967296 * (2097151 & h2) + (h1 >>> 0);
  }
}

/** The material a ray sees in a uniform cell (0 for an empty one, whatever its fields). */
const uniform = (cell: number) => (state(cell) === FULL ? cell & MATERIAL_MASK : 0);

/** The fingerprint of chunk `i`: its blocks' materials, its mixed blocks' voxel groups
 * (whose empty voxels' fields change only with the block's content) and its entity records. */
function print(w: Words, i: number): number {
  const h = new Hasher();
  const c = w.chunks[i];
  if (state(c) === MIXED) {
    const array = c & POINTER_MASK;
    for (let k = array; k < array + BLOCKS; k++) {
      const b = w.blocks[k];
      if (state(b) === MIXED) {
        const ptr = b & POINTER_MASK;
        h.word(1);
        h.words(w.voxels.subarray(ptr, ptr + GROUP_WORDS));
      } else {
        h.word(0);
        h.word(uniform(b));
      }
    }
  } else {
    h.word(2);
    h.word(uniform(c));
  }
  const field = w.entities[i] ?? 0;
  const first = (field >>> 8) * RECORD_WORDS;
  h.words(w.records.subarray(first, first + (field & 0xff) * RECORD_WORDS));
  return h.digest();
}

/** Word ranges `[lo, hi)` of one buffer, ascending and merged, that a change wrote. */
function wordRanges(touched: Touched[], id: number): [number, number][] {
  const list = touched
    .filter((t) => t.id === id)
    .map((t): [number, number] => [t.lo >> 2, (t.hi + 3) >> 2])
    .sort((a, b) => a[0] - b[0]);
  const out: [number, number][] = [];
  for (const r of list) {
    const last = out[out.length - 1];
    if (last && r[0] <= last[1]) last[1] = Math.max(last[1], r[1]);
    else out.push(r);
  }
  return out;
}

/** Whether words `start..start + len` meet any of `ranges` (ascending, disjoint). */
function touches(ranges: [number, number][], start: number, len: number): boolean {
  if (len === 0 || ranges.length === 0) return false;
  let lo = 0;
  let hi = ranges.length;
  while (lo < hi) {
    const mid = (lo + hi) >> 1;
    if (ranges[mid][1] <= start) lo = mid + 1;
    else hi = mid;
  }
  return lo < ranges.length && ranges[lo][0] < start + len;
}

/** The fingerprint of every chunk of the mirrored world. */
export class ChunkPrints {
  private prints: Float64Array;

  constructor(m: Mirror) {
    const w = wordsOf(m);
    this.prints = new Float64Array(w.chunks.length);
    for (let i = 0; i < w.chunks.length; i++) this.prints[i] = print(w, i);
  }

  /** Moves to the mirror's current world, which differs from the version these prints
   * are of only in the byte ranges `touched` lists, and says which chunks now show
   * something else. */
  update(m: Mirror, touched: Touched[]): ChunkChanges {
    const w = wordsOf(m);
    const stale = (id: number) => wordRanges(touched, id);
    if (w.chunks.length !== this.prints.length || touched.some((t) => t.id === 4 || t.id === 6)) {
      this.prints = new ChunkPrints(m).prints;
      return "everything";
    }
    const [chunks, entities, blocks, voxels, records] = [0, 1, 2, 3, 7].map(stale);
    if ([chunks, entities, blocks, voxels, records].every((r) => r.length === 0)) return [];
    const candidate = (i: number): boolean => {
      if (touches(chunks, i, 1) || touches(entities, i, 1)) return true;
      const field = w.entities[i] ?? 0;
      if (touches(records, (field >>> 8) * RECORD_WORDS, (field & 0xff) * RECORD_WORDS)) return true;
      const c = w.chunks[i];
      if (state(c) !== MIXED) return false;
      const array = c & POINTER_MASK;
      if (touches(blocks, array, BLOCKS)) return true;
      if (voxels.length === 0) return false;
      for (let k = array; k < array + BLOCKS; k++) {
        const b = w.blocks[k];
        if (state(b) === MIXED && touches(voxels, b & POINTER_MASK, GROUP_WORDS)) return true;
      }
      return false;
    };
    const changed: number[] = [];
    for (let i = 0; i < w.chunks.length; i++) {
      if (!candidate(i)) continue;
      const p = print(w, i);
      if (p !== this.prints[i]) {
        this.prints[i] = p;
        changed.push(i);
      }
    }
    return changed;
  }
}

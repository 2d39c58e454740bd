// Which chunks show something else after a change, as the native client works it out
// (world/src/fingerprint.rs): a fingerprint per chunk of what a ray sees of the static world
// there (its voxels' materials; distance fields left out, since they change across wide
// empty areas after any edit but change nothing a ray sees), and, for the entities, which
// instance records changed: each marks the chunks its world box overlaps, before and after.
// The GI's history drops or shortens the light on and near the chunks a change touched
// (docs/RENDERING.md §3c).
import { BLOCKS, FULL, GROUP_WORDS, MATERIAL_MASK, MIXED, POINTER_MASK, state } from "./cell";
import { RECORD_WORDS, instanceBox } from "./instances";
import type { Mirror, Touched } from "./mirror";

/** What changed between two versions: these chunks (ascending), or everything (the
 * materials, the entity types or the world's size). */
export type ChunkChanges = number[] | "everything";

/** The buffers' words, as a chunk's fingerprint reads them. */
interface Words {
  chunks: Uint32Array;
  blocks: Uint32Array;
  voxels: Uint32Array;
}

function wordsOf(m: Mirror): Words {
  return { chunks: m.words(0), blocks: m.words(2), voxels: m.words(3) };
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

/** The fingerprint of chunk `i`: its blocks' materials and its mixed blocks' voxel groups
 * (whose empty voxels' fields change only with the block's content). */
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

/** The chunks (indices into a world of `chunks` chunks) that `box` overlaps. */
export function overlappedChunks(box: number[][], chunks: number[]): number[] {
  const lo = [0, 1, 2].map((a) => Math.max(0, Math.floor(box[0][a] / 16)));
  const hi = [0, 1, 2].map((a) => Math.min(chunks[a] - 1, Math.floor(box[1][a] / 16)));
  const out: number[] = [];
  for (let z = lo[2]; z <= hi[2]; z++)
    for (let y = lo[1]; y <= hi[1]; y++) for (let x = lo[0]; x <= hi[0]; x++) out.push(x + chunks[0] * (y + chunks[1] * z));
  return out;
}

/** The fingerprint of every chunk of the mirrored world, and the instance records. */
export class ChunkPrints {
  private prints: Float64Array;
  private records: Uint32Array;

  constructor(m: Mirror) {
    const w = wordsOf(m);
    this.prints = new Float64Array(w.chunks.length);
    for (let i = 0; i < w.chunks.length; i++) this.prints[i] = print(w, i);
    this.records = m.words(7).slice();
  }

  /** Moves to the mirror's current world, which differs from the version these prints
   * are of only in the byte ranges `touched` lists, and says which chunks now show
   * something else. */
  update(m: Mirror, touched: Touched[]): ChunkChanges {
    const w = wordsOf(m);
    const stale = (id: number) => wordRanges(touched, id);
    if (w.chunks.length !== this.prints.length || touched.some((t) => t.id === 4 || t.id === 6)) {
      const fresh = new ChunkPrints(m);
      this.prints = fresh.prints;
      this.records = fresh.records;
      return "everything";
    }
    const [chunks, blocks, voxels, records] = [0, 2, 3, 7].map(stale);
    const candidate = (i: number): boolean => {
      if (touches(chunks, i, 1)) return true;
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
    const changed = new Set<number>();
    if (chunks.length + blocks.length + voxels.length > 0) {
      for (let i = 0; i < w.chunks.length; i++) {
        if (!candidate(i)) continue;
        const p = print(w, i);
        if (p !== this.prints[i]) {
          this.prints[i] = p;
          changed.add(i);
        }
      }
    }
    if (records.length > 0) {
      const [before, after] = [this.records, m.words(7)];
      const dims = m.size.map((v) => Math.ceil(v / 16));
      const slots = Math.max(before.length, after.length) / RECORD_WORDS;
      for (let slot = 0; slot < slots; slot++) {
        const r = slot * RECORD_WORDS;
        let same = true;
        for (let k = r; k < r + RECORD_WORDS; k++) same &&= (before[k] ?? 0) === (after[k] ?? 0);
        if (same) continue;
        for (const words of [before, after]) {
          const box = slot < words.length / RECORD_WORDS ? instanceBox(words, slot) : undefined;
          if (box) for (const c of overlappedChunks(box, dims)) changed.add(c);
        }
      }
      this.records = after.slice();
    }
    return [...changed].sort((a, b) => a - b);
  }
}

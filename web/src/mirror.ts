// The world as the page holds it: the eight digested buffers, filled from a snapshot's
// pages (a patch-form snapshot carries all eight) and kept current by the patch form's deltas (docs/PROTOCOL.md, "The patch form").
// Every snapshot and every delta is checked against the server's digest.
import { fromBinary } from "@bufbuild/protobuf";
import { decompress } from "fzstd";
import type { Delta, Header, Page } from "./gen/naadf/v1/naadf_pb";
import { RunsSchema } from "./gen/naadf/v1/naadf_pb";
import { PAGE_BYTES, pageHash } from "./digest";

/** The digested buffers: 0 chunks, 1 chunk entities, 2 blocks, 3 voxels, 4 materials,
 * 5 models, 6 entity types, 7 entity instances. */
export const BUFFER_COUNT = 8;
/** The first entity buffer: a snapshot header lists 6 and 7 only when they are not empty. */
const ENTITY_BUFFERS = 6;

/** A byte range of one buffer that a change wrote. */
export interface Touched {
  id: number;
  lo: number;
  hi: number;
}

/** The mirror diverged from the server, or the server sent something it cannot hold. */
export class MirrorError extends Error {}

/** One buffer: its bytes (with room to grow) at its logical length, and its page hashes.
 * A resize leaves the pages it changed stale until `settle`, so that pages about to be
 * written are hashed once, after they are. */
class WorldBuffer {
  bytes = new Uint8Array(0);
  len = 0;
  hashes: bigint[] = [];
  private readonly stale = new Set<number>();
  /** The XOR of `hashes`, kept as they change (a delta rehashes a few pages of many). */
  private xor = 0n;

  constructor(readonly id: number) {}

  /** Sets the logical length: truncates, or extends with zero bytes. */
  resize(len: number): void {
    if (len > this.bytes.length) {
      const grown = new Uint8Array(Math.max(len, Math.ceil(this.bytes.length * 1.5)));
      grown.set(this.bytes.subarray(0, this.len));
      this.bytes = grown;
    } else if (len < this.len) {
      this.bytes.fill(0, len, this.len);
    }
    const pages = Math.ceil(len / PAGE_BYTES);
    const before = this.hashes.length;
    this.len = len;
    for (let p = pages; p < before; p++) this.xor ^= this.hashes[p] ?? 0n;
    this.hashes.length = pages;
    for (const p of this.stale) if (p >= pages) this.stale.delete(p);
    // The old last page may have changed length, and pages past the old end are new.
    for (let p = Math.max(0, Math.min(before, pages) - 1); p < pages; p++) this.stale.add(p);
  }

  /** Marks page `p` as written. */
  touch(p: number): void {
    this.stale.add(p);
  }

  /** Recomputes the hashes of the stale pages. */
  settle(): void {
    for (const p of this.stale) {
      const lo = p * PAGE_BYTES;
      const hash = pageHash(this.id, p, this.bytes.subarray(lo, Math.min(lo + PAGE_BYTES, this.len)));
      this.xor ^= (this.hashes[p] ?? 0n) ^ hash;
      this.hashes[p] = hash;
    }
    this.stale.clear();
  }

  /** The XOR of its page hashes. */
  digest(): bigint {
    this.settle();
    return this.xor;
  }
}

/** The world's state as a stream has left it. */
export class Mirror {
  readonly buffers: WorldBuffer[] = Array.from({ length: BUFFER_COUNT }, (_, id) => new WorldBuffer(id));
  size: [number, number, number] = [0, 0, 0];
  version = 0n;
  growthSeq = 0;
  quiescent = false;
  digest = 0n;
  /** Whether the buffers hold a verified world (a snapshot completed). */
  holdsWorld = false;
  private expected: Header | undefined;
  private pagesLeft = 0;

  /** The page hashes of the buffers, to announce as `JoinRequest.cached`. They hash
   * the bytes held, so they are true even of a mirror that diverged: the server then sends
   * only the pages that differ. */
  cached(): { buffer: number; pageHashes: bigint[] }[] {
    return this.buffers.map((b) => {
      b.settle();
      return { buffer: b.id, pageHashes: [...b.hashes] };
    });
  }

  /** The bytes of buffer `id` at its logical length. */
  bytes(id: number): Uint8Array {
    const b = this.buffers[id];
    return b.bytes.subarray(0, b.len);
  }

  /** The whole little-endian `u32` words of buffer `id` (a view, not a copy). */
  words(id: number): Uint32Array {
    const b = this.bytes(id);
    return new Uint32Array(b.buffer, b.byteOffset, b.length >> 2);
  }

  /** Takes a state the page cached: the buffers from their pages, checked against the
   * digest. Returns whether the mirror now holds that world. */
  restore(
    state: { size: [number, number, number]; version: bigint; growthSeq: number; quiescent: boolean; digest: bigint; lengths: number[] },
    pages: Uint8Array[][],
  ): boolean {
    if (pages.length !== BUFFER_COUNT || state.lengths.length !== BUFFER_COUNT) return false;
    for (let id = 0; id < BUFFER_COUNT; id++) {
      const b = this.buffers[id];
      b.resize(state.lengths[id]);
      pages[id].forEach((page, p) => {
        b.bytes.set(page.subarray(0, Math.max(0, Math.min(PAGE_BYTES, b.len - p * PAGE_BYTES))), p * PAGE_BYTES);
        b.touch(p);
      });
    }
    this.size = state.size;
    this.version = state.version;
    this.growthSeq = state.growthSeq;
    this.quiescent = state.quiescent;
    this.digest = this.computeDigest();
    this.holdsWorld = this.digest === state.digest;
    return this.holdsWorld;
  }

  /** Starts a snapshot (or a resume). Returns whether pages follow. */
  header(h: Header): boolean {
    if (h.resume) {
      if (!this.holdsWorld || h.version !== this.version || h.digest !== this.digest) {
        throw new MirrorError("the server resumed a state this page does not hold");
      }
      this.growthSeq = h.growthSeq;
      this.quiescent = h.quiescent;
      return false;
    }
    if (h.size.length !== 3) throw new MirrorError("the header's world size is not three numbers");
    this.holdsWorld = false;
    this.size = [h.size[0], h.size[1], h.size[2]];
    for (const l of h.buffers) {
      if (l.buffer >= BUFFER_COUNT) throw new MirrorError(`the header names buffer ${l.buffer}`);
    }
    for (let id = 0; id < BUFFER_COUNT; id++) {
      const l = h.buffers.find((b) => b.buffer === id);
      // The entity buffers (6, 7) are listed only when they hold anything.
      if (!l && id < ENTITY_BUFFERS) throw new MirrorError(`the header lacks the length of buffer ${id}`);
      this.buffers[id].resize(l ? Number(l.bytes) : 0);
    }
    this.expected = h;
    this.pagesLeft = h.pages;
    if (this.pagesLeft === 0) this.finishSnapshot();
    return this.pagesLeft > 0;
  }

  /** Takes one group of pages; returns whether the snapshot is complete. */
  page(p: Page): boolean {
    if (!this.expected || this.pagesLeft === 0) throw new MirrorError("a page arrived outside a snapshot");
    const b = this.buffers[p.buffer];
    if (!b) throw new MirrorError(`a page of buffer ${p.buffer}`);
    const bytes = decompress(p.zstd);
    let at = 0;
    for (const index of p.indices) {
      const lo = index * PAGE_BYTES;
      const n = Math.min(PAGE_BYTES, b.len - lo);
      if (n <= 0 || at + n > bytes.length) throw new MirrorError(`page ${index} of buffer ${p.buffer} does not fit`);
      b.bytes.set(bytes.subarray(at, at + n), lo);
      at += n;
      b.touch(index);
    }
    this.pagesLeft -= 1;
    if (this.pagesLeft === 0) {
      this.finishSnapshot();
      return true;
    }
    return false;
  }

  private finishSnapshot(): void {
    const h = this.expected!;
    this.version = h.version;
    this.growthSeq = h.growthSeq;
    this.quiescent = h.quiescent;
    this.digest = this.computeDigest();
    this.expected = undefined;
    if (this.digest !== h.digest) {
      throw new MirrorError("the snapshot's pages do not give the header's digest");
    }
    this.holdsWorld = true;
  }

  /** Applies a patch-form delta; returns the byte ranges it wrote and whether a length changed. */
  delta(d: Delta): { touched: Touched[]; resized: boolean } {
    const p = d.patch;
    if (!this.holdsWorld) throw new MirrorError("a delta arrived before a snapshot");
    if (!p) throw new MirrorError("a delta without a patch (the page joins in the patch form)");
    for (const l of p.lengths) {
      const b = this.buffers[l.buffer];
      if (!b) throw new MirrorError(`a patch resizes buffer ${l.buffer}`);
      b.resize(Number(l.bytes));
    }
    const runs = p.zstd.length > 0 ? fromBinary(RunsSchema, decompress(p.zstd)).runs : p.runs;
    const touched: Touched[] = [];
    for (const r of runs) {
      const b = this.buffers[r.buffer];
      const lo = Number(r.offset);
      const hi = lo + r.bytes.length;
      if (!b || hi > b.len) throw new MirrorError(`a run reaches past buffer ${r.buffer}`);
      b.bytes.set(r.bytes, lo);
      for (let q = Math.floor(lo / PAGE_BYTES); q * PAGE_BYTES < hi; q++) b.touch(q);
      touched.push({ id: r.buffer, lo, hi });
    }
    this.version = p.version;
    this.growthSeq = p.growthSeq;
    this.quiescent = p.quiescent;
    this.digest = this.computeDigest();
    if (this.digest !== d.digest) {
      this.holdsWorld = false;
      throw new MirrorError(`the page diverged from the server at version ${p.version}`);
    }
    return { touched, resized: p.lengths.length > 0 };
  }

  private computeDigest(): bigint {
    let d = 0n;
    for (const b of this.buffers) d ^= b.digest();
    return d;
  }
}

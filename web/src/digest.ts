// The world digest (docs/FORMAT.md §8): XOR over the digested buffers of
// xxh3_64(buffer id u32 LE ‖ page index u32 LE ‖ page bytes), page by 64 KiB page.
import { createXXHash3 } from "hash-wasm";
import type { IHasher } from "hash-wasm";

/** Bytes per digest page. */
export const PAGE_BYTES = 64 * 1024;

let hasher: IHasher | undefined;

/** Loads the hash function (WebAssembly); call once before hashing. */
export async function loadHasher(): Promise<void> {
  hasher ??= await createXXHash3(0, 0);
}

/** The digest contribution of page `index` of buffer `id`, whose bytes are `page`. */
export function pageHash(id: number, index: number, page: Uint8Array): bigint {
  if (!hasher) throw new Error("loadHasher() was not awaited");
  const head = new Uint8Array(8);
  const view = new DataView(head.buffer);
  view.setUint32(0, id, true);
  view.setUint32(4, index, true);
  hasher.init();
  hasher.update(head);
  hasher.update(page);
  return BigInt("0x" + hasher.digest("hex"));
}

/** A digest as `naadf status --json` prints it: 16 lowercase hex digits. */
export function digestHex(d: bigint): string {
  return d.toString(16).padStart(16, "0");
}

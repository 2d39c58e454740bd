// The page's cache in IndexedDB: the world's pages by their digest hash, and the state
// they make up, so that a reload downloads nothing the page holds. On the next visit the
// mirror is rebuilt from the cache, checked against its digest, and the page joins
// announcing it (`JoinRequest.cached` and a `ResumePoint`).
import { PAGE_BYTES } from "./digest";
import type { Mirror } from "./mirror";
import { BUFFER_COUNT } from "./mirror";

const DB = "naadf";
const PAGES = "pages";
const STATES = "states";

/** What the cache holds of a world, besides its pages. */
interface CachedState {
  size: [number, number, number];
  version: bigint;
  growthSeq: number;
  quiescent: boolean;
  digest: bigint;
  lengths: number[];
  hashes: bigint[][];
}

const key = (id: number, hash: bigint) => `${id}:${hash.toString(16)}`;

function request<T>(r: IDBRequest<T>): Promise<T> {
  return new Promise((resolve, reject) => {
    r.onsuccess = () => resolve(r.result);
    r.onerror = () => reject(r.error);
  });
}

function done(t: IDBTransaction): Promise<void> {
  return new Promise((resolve, reject) => {
    t.oncomplete = () => resolve();
    t.onerror = t.onabort = () => reject(t.error);
  });
}

/** The cache of one server (the page's origin). */
export class PageCache {
  private constructor(private readonly db: IDBDatabase) {}

  /** Opens the cache; `undefined` where IndexedDB is unavailable (private windows). */
  static async open(): Promise<PageCache | undefined> {
    try {
      const r = indexedDB.open(DB, 1);
      r.onupgradeneeded = () => {
        r.result.createObjectStore(PAGES);
        r.result.createObjectStore(STATES);
      };
      return new PageCache(await request(r));
    } catch {
      return undefined;
    }
  }

  /** Rebuilds `mirror` from the cache; whether it now holds a verified world. */
  async restore(mirror: Mirror): Promise<boolean> {
    const t = this.db.transaction([PAGES, STATES], "readonly");
    const state = (await request(t.objectStore(STATES).get(location.origin))) as CachedState | undefined;
    if (!state) return false;
    const pages = t.objectStore(PAGES);
    const read = state.hashes.map((hs, id) => Promise.all(hs.map((h) => request(pages.get(key(id, h))) as Promise<Uint8Array | undefined>)));
    const buffers = await Promise.all(read);
    if (buffers.some((b) => b.some((p) => !p))) return false;
    return mirror.restore(state, buffers as Uint8Array[][]);
  }

  /** Stores what `mirror` holds: its new pages and its state; drops pages no longer held. */
  async save(mirror: Mirror): Promise<void> {
    if (!mirror.holdsWorld) return;
    const t = this.db.transaction([PAGES, STATES], "readwrite");
    const pages = t.objectStore(PAGES);
    const held = new Set((await request(pages.getAllKeys())).map(String));
    const wanted = new Set<string>();
    const hashes: bigint[][] = [];
    const lengths: number[] = [];
    for (let id = 0; id < BUFFER_COUNT; id++) {
      const b = mirror.buffers[id];
      b.settle();
      lengths.push(b.len);
      hashes.push([...b.hashes]);
      b.hashes.forEach((h, p) => {
        const k = key(id, h);
        wanted.add(k);
        if (!held.has(k)) pages.put(b.bytes.slice(p * PAGE_BYTES, Math.min((p + 1) * PAGE_BYTES, b.len)), k);
      });
    }
    for (const k of held) if (!wanted.has(k)) pages.delete(k);
    const state: CachedState = {
      size: mirror.size,
      version: mirror.version,
      growthSeq: mirror.growthSeq,
      quiescent: mirror.quiescent,
      digest: mirror.digest,
      lengths,
      hashes,
    };
    t.objectStore(STATES).put(state, location.origin);
    await done(t);
  }
}

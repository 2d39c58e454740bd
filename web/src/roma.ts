// `roma` on the page (docs/RENDERING.md §3d): the native ROMA passes (gen/roma.wgsl,
// gen/roma_build.wgsl) with the maps kept the way client/src/gpu/roma.rs keeps them, with
// the default directions, AO range and light. Each frame writes the tiles its windows
// gained as the camera moved and the tiles over the chunks the world changed in; the
// samples then add up as the path tracer's do while the view and the world stay the same.
import romaWgsl from "./gen/roma.wgsl?raw";
import romaBuildWgsl from "./gen/roma_build.wgsl?raw";
import { GI_LIGHT_WORDS, ROMA, RomaInfo, RomaJob, RomaWindow } from "./gen/layout";
import { WorldGroup, bindBuffers, dispatchPixels, passPipeline, submitGroups, writeStruct } from "./compute";
import type { Variants } from "./compute";
import type { Camera } from "./camera";
import type { GpuWorld } from "./gpu";
import { ProgressiveSums } from "./progressive";

type Vec3 = [number, number, number];

const MAPS = ROMA.DIRECTIONS + 1;
const WINDOWS = MAPS * ROMA.LEVELS;
const WINDOW_TILE_COUNT = ROMA.WINDOW_TILES ** 3;
const TILE_BYTES = ROMA.TILE_WORDS * 4;

/** Row `r` (0 t, 1 b, 2 w) of map `map`'s frame. */
function row(map: number, r: number): Vec3 {
  const f = ROMA.FRAMES[map];
  return [f[3 * r], f[3 * r + 1], f[3 * r + 2]];
}

const dot = (a: Vec3, b: Vec3) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];

/** `p` in map `map`'s coordinates, in voxels. */
function toMap(map: number, p: Vec3): Vec3 {
  return [dot(row(map, 0), p), dot(row(map, 1), p), dot(row(map, 2), p)];
}

/** The base tile of map `map`'s window at `level` around `camera` (client/src/light/roma/ `window_base`). */
function windowBase(map: number, level: number, camera: Vec3): Vec3 {
  const m = toMap(map, camera).map((v) => v / ROMA.CELL[level]);
  return m.map((v) => Math.floor(v / ROMA.TILE) - ROMA.WINDOW_TILES / 2) as Vec3;
}

/** The inclusive tile range covering the world box [lo, hi] in map `map` at `level`. */
function tileRange(map: number, level: number, lo: Vec3, hi: Vec3): [Vec3, Vec3] {
  const a: Vec3 = [Infinity, Infinity, Infinity];
  const b: Vec3 = [-Infinity, -Infinity, -Infinity];
  for (let k = 0; k < 8; k++) {
    const corner: Vec3 = [k & 1 ? hi[0] : lo[0], k & 2 ? hi[1] : lo[1], k & 4 ? hi[2] : lo[2]];
    const m = toMap(map, corner);
    for (let i = 0; i < 3; i++) {
      a[i] = Math.min(a[i], m[i]);
      b[i] = Math.max(b[i], m[i]);
    }
  }
  const scale = ROMA.CELL[level] * ROMA.TILE;
  return [a.map((v) => Math.floor(v / scale)) as Vec3, b.map((v) => Math.floor(v / scale)) as Vec3];
}

const within = (t: Vec3, a: Vec3, b: Vec3) => t.every((v, i) => v >= a[i] && v <= b[i]);

/** The `roma` renderer: the maps on the device, and the running sums of its samples. */
export class RomaRenderer {
  private readonly sample: Variants;
  private readonly sampleLayout: GPUBindGroupLayout;
  private readonly build: Variants;
  private readonly buildLayout: GPUBindGroupLayout;
  private readonly light: GPUBuffer;
  private readonly info: GPUBuffer;
  private readonly windows: GPUBuffer;
  private readonly bits: GPUBuffer;
  /** Each window's base tile as the device holds it (null: nothing written yet). */
  private bases: (Vec3 | null)[] = new Array(WINDOWS).fill(null);
  /** The world's generation and size the tiles show. */
  private generation = -1;
  private size = "";
  private readonly sums: ProgressiveSums;

  constructor(
    readonly device: GPUDevice,
    private readonly world: WorldGroup,
  ) {
    ({ pipeline: this.sample, layout: this.sampleLayout } = passPipeline(device, world, "roma.wgsl", romaWgsl, "path_trace", [
      "uniform",
      "uniform",
      "storage",
      "uniform",
      "read-only-storage",
      "read-only-storage",
    ]));
    ({ pipeline: this.build, layout: this.buildLayout } = passPipeline(device, world, "roma_build.wgsl", romaBuildWgsl, "roma_build", [
      "read-only-storage",
      "read-only-storage",
      "storage",
    ]));
    const uniform = (size: number) => device.createBuffer({ size, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    this.light = uniform(GI_LIGHT_WORDS.length * 4);
    device.queue.writeBuffer(this.light, 0, new Uint32Array(GI_LIGHT_WORDS));
    this.info = uniform(RomaInfo.size);
    this.windows = device.createBuffer({
      label: "roma windows",
      size: WINDOWS * RomaWindow.size,
      usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST,
    });
    this.bits = device.createBuffer({ label: "roma maps", size: WINDOWS * WINDOW_TILE_COUNT * TILE_BYTES, usage: GPUBufferUsage.STORAGE });
    this.sums = new ProgressiveSums(device, "roma");
  }

  /** Writes the tiles `camera`'s windows gained and those over the chunks `world` changed
   * in, and the windows' records (client/src/gpu/roma.rs `update`). */
  private async update(world: GpuWorld, camera: Camera): Promise<void> {
    const size = JSON.stringify(world.chunks);
    const changes = this.generation < 0 || size !== this.size ? "everything" : world.changesSince(this.generation);
    const everything = changes === "everything";
    const jobs = new Map<string, { tile: Vec3; window: number }>();
    const add = (window: number, tile: Vec3) => jobs.set(`${window}:${tile}`, { tile, window });
    const records = new Uint8Array(WINDOWS * RomaWindow.size);
    const n = ROMA.WINDOW_TILES;
    for (let i = 0; i < WINDOWS; i++) {
      const [map, level] = [Math.floor(i / ROMA.LEVELS), i % ROMA.LEVELS];
      const base = windowBase(map, level, camera.pos as Vec3);
      const old = everything ? null : this.bases[i];
      if (!old || old.some((v, k) => v !== base[k])) {
        for (let t = 0; t < n * n * n; t++) {
          const tile: Vec3 = [base[0] + (t % n), base[1] + (Math.floor(t / n) % n), base[2] + Math.floor(t / (n * n))];
          const held = old && tile.every((v, k) => v - old[k] >= 0 && v - old[k] < n);
          if (!held) add(i, tile);
        }
      }
      this.bases[i] = base;
      const record = writeStruct(RomaWindow, {
        t: row(map, 0),
        cell: ROMA.CELL[level],
        b: row(map, 1),
        first_tile: i * WINDOW_TILE_COUNT,
        w: row(map, 2),
        offset: ROMA.OFFSET[level],
        base,
      });
      records.set(new Uint8Array(record), i * RomaWindow.size);
    }
    if (!everything) {
      const [cx, cy] = world.chunks;
      for (const c of changes) {
        const lo: Vec3 = [(c % cx) * 16, (Math.floor(c / cx) % cy) * 16, Math.floor(c / (cx * cy)) * 16];
        const hi: Vec3 = [lo[0] + 16, lo[1] + 16, lo[2] + 16];
        for (let i = 0; i < WINDOWS; i++) {
          const [a, b] = tileRange(Math.floor(i / ROMA.LEVELS), i % ROMA.LEVELS, lo, hi);
          const base = this.bases[i]!;
          const from = a.map((v, k) => Math.max(v, base[k])) as Vec3;
          const to = b.map((v, k) => Math.min(v, base[k] + n - 1)) as Vec3;
          for (let z = from[2]; z <= to[2]; z++)
            for (let y = from[1]; y <= to[1]; y++) for (let x = from[0]; x <= to[0]; x++) add(i, [x, y, z]);
        }
      }
    }
    this.generation = world.generation;
    this.size = size;
    this.device.queue.writeBuffer(this.windows, 0, records);
    if (jobs.size === 0) return;
    // Per window, the tiles that may hold a point of the world: a tile outside is cleared
    // without sampling.
    const worldHi: Vec3 = world.chunks.map((c) => c * 16) as Vec3;
    const worldTiles = Array.from({ length: WINDOWS }, (_, i) => tileRange(Math.floor(i / ROMA.LEVELS), i % ROMA.LEVELS, [0, 0, 0], worldHi));
    const list = new Uint8Array(jobs.size * RomaJob.size);
    let k = 0;
    for (const { tile, window } of jobs.values()) {
      const [a, b] = worldTiles[window];
      list.set(new Uint8Array(writeStruct(RomaJob, { tile, window, clear: within(tile, a, b) ? 0 : 1 })), k * RomaJob.size);
      k += 1;
    }
    const jobBuffer = this.device.createBuffer({ label: "roma jobs", size: list.byteLength, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST });
    this.device.queue.writeBuffer(jobBuffer, 0, list);
    const group = bindBuffers(this.device, this.buildLayout, [this.windows, jobBuffer, this.bits]);
    await submitGroups(this.device, this.build(world.hasInstances), this.world.of(world), group, jobs.size);
    jobBuffer.destroy();
  }

  /** Samples per pixel in the current view's sums. */
  get samples(): number {
    return this.sums.samples;
  }

  /** Adds one sample per pixel of `camera`'s view of `world` (the first, if the view or
   * the world changed) and returns the tone-mapped mean. */
  async render(world: GpuWorld, camera: Camera, width: number, height: number): Promise<ImageData> {
    world.trackChanges();
    await this.update(world, camera);
    const sums = this.sums.next(world, camera, width, height);
    this.device.queue.writeBuffer(
      this.info,
      0,
      writeStruct(RomaInfo, { camera: camera.pos, ao_range: ROMA.AO_RANGE, side: ROMA.SIDE, directions: ROMA.DIRECTIONS }),
    );
    const group = bindBuffers(this.device, this.sampleLayout, [this.sums.frame, this.light, sums, this.info, this.windows, this.bits]);
    const enc = await dispatchPixels(this.device, this.sample(world.hasInstances), this.world.of(world), group, width, height);
    return this.sums.finish(enc, width, height);
  }
}

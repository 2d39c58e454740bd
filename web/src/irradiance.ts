// `irradiance` on the page (docs/RENDERING.md §3e): the native irradiance cache's passes
// (gen/irradiance.wgsl, gen/irradiance_update.wgsl) with the table kept the way
// client/src/gpu/irradiance.rs keeps it, with the default ray budget and light. Each frame
// clears the entries near the chunks the world changed in, adds one sample per pixel (which
// keys and requests the faces it meets), and refreshes the requested entries the budget pays
// for; the samples add up as the path tracer's do while the view and the world stay the same.
import irradianceWgsl from "./gen/irradiance.wgsl?raw";
import irradianceUpdateWgsl from "./gen/irradiance_update.wgsl?raw";
import { DEFAULT_SEED, GI_LIGHT_WORDS, IRR, IrradianceInfo, LightInfo } from "./gen/layout";
import { WorldGroup, bindBuffers, dispatchPixels, passPipeline, submitGroups, writeStruct } from "./compute";
import type { Variants } from "./compute";
import type { Camera } from "./camera";
import type { GpuWorld } from "./gpu";
import { ProgressiveSums } from "./progressive";

/** Whether the page's light (the default: physical sky and sun) has a sun. */
const SUN = GI_LIGHT_WORDS[LightInfo.fields.sun_on.offset / 4] !== 0;

/** Entry samples per frame the default ray budget pays for (`IrradianceOptions::samples_per_frame`). */
export const BUDGET = Math.max(1, Math.floor(IRR.DEFAULT_RAYS / (SUN ? IRR.RAYS_PER_SAMPLE_SUN : IRR.RAYS_PER_SAMPLE)));

/** Slots of a table for frames of `pixels`: a power of two, at least `IRR.MIN_SLOTS` and two
 * per pixel (a frame keys at most two entries per pixel), as `slots_for` chooses them. */
export function slotsFor(pixels: number): number {
  let slots = IRR.MIN_SLOTS;
  while (slots < 2 * pixels) slots *= 2;
  return slots;
}

type Box = [number, number, number, number];

/** The boxes (pairs of `[lo, hi]` voxel corners, inclusive, as `vec4<i32>`) within
 * `IRR.BOUNCE_DISTANCE` of the changed chunks `chunks` of a world of `dims` chunks: one per
 * chunk, or per 4³ chunks when there are too many, or a single bounding box
 * (client/src/gpu/irradiance.rs `changed_boxes`). */
export function changedBoxes(dims: readonly number[], chunks: readonly number[]): Int32Array {
  const reach = IRR.BOUNCE_DISTANCE;
  const coords = (c: number) => [c % dims[0], Math.floor(c / dims[0]) % dims[1], Math.floor(c / (dims[0] * dims[1]))];
  // The distinct groups of `edge`³ chunks, in the order of their coordinates (x, then y, then z).
  const groupsOf = (edge: number): number[][] => {
    const seen = new Map<string, number[]>();
    for (const c of chunks) {
      const g = coords(c).map((v) => Math.floor(v / edge));
      seen.set(g.join(","), g);
    }
    return [...seen.values()].sort((a, b) => a[0] - b[0] || a[1] - b[1] || a[2] - b[2]);
  };
  const asBoxes = (groups: number[][], edge: number): Box[] => {
    const size = 16 * edge;
    return groups.flatMap((g) => {
      const lo = g.map((v) => v * size - reach);
      const hi = g.map((v) => v * size + size - 1 + reach);
      return [
        [lo[0], lo[1], lo[2], 0],
        [hi[0], hi[1], hi[2], 0],
      ] as Box[];
    });
  };
  const single = groupsOf(1);
  if (single.length <= IRR.MAX_BOXES) return new Int32Array(asBoxes(single, 1).flat());
  const grouped = groupsOf(4);
  if (grouped.length <= IRR.MAX_BOXES) return new Int32Array(asBoxes(grouped, 4).flat());
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (const c of chunks) {
    const v = coords(c);
    for (let a = 0; a < 3; a++) {
      lo[a] = Math.min(lo[a], v[a] * 16 - reach);
      hi[a] = Math.max(hi[a], v[a] * 16 + 15 + reach);
    }
  }
  return new Int32Array([lo[0], lo[1], lo[2], 0, hi[0], hi[1], hi[2], 0]);
}

/** What the last frame did to the cache (its request list's counters, read back with the
 * frame), as `IrradianceStats` reports it natively, and the frame's stamp. */
export interface IrradianceStats {
  /** Entries the frame requested. */
  requested: number;
  /** Those that had no samples. */
  fresh: number;
  /** Samples the update took. */
  samples: number;
  /** Slots keyed in the table. */
  keyed: number;
  /** Slots of the table. */
  slots: number;
  /** The frame's stamp: frames since the table was made (from 1). */
  stamp: number;
}

/** The cache on the device (client/src/gpu/irradiance.rs `Cache`). */
interface Cache {
  /** The world's size (in chunks) the entries belong to. */
  size: string;
  slots: number;
  table: GPUBuffer;
  requests: GPUBuffer;
  /** The update's indirect dispatch, written by `irradiance_args`. */
  args: GPUBuffer;
  /** The world's generation the entries show. */
  generation: number;
  /** Frames since the table was made: the stamp of the next is one more. */
  stamp: number;
  /** Slots keyed in the table after the last frame (read back with it). */
  keyed: number;
}

/** The `irradiance` renderer: the cache on the device, and the running sums of its samples. */
export class IrradianceRenderer {
  private readonly sample: Variants;
  private readonly sampleLayout: GPUBindGroupLayout;
  /** The update module's passes. `irradiance_invalidate` and `irradiance_update` bind the
   * light, the cache's parameters, the table, the request list and the boxes;
   * `irradiance_args` also the dispatch. */
  private readonly invalidate: Variants;
  private readonly invalidateLayout: GPUBindGroupLayout;
  private readonly update: Variants;
  private readonly updateLayout: GPUBindGroupLayout;
  private readonly args: Variants;
  private readonly argsLayout: GPUBindGroupLayout;
  private readonly light: GPUBuffer;
  /** The cache's parameters of the frame's passes, and of the invalidation (with its boxes). */
  private readonly info: GPUBuffer;
  private readonly invalidateInfo: GPUBuffer;
  /** The boxes the update passes bind: none. */
  private readonly noBoxes: GPUBuffer;
  /** The request list's counters, read back with each frame. */
  private readonly counters: GPUBuffer;
  private cache: Cache | undefined;
  private readonly sums: ProgressiveSums;
  /** What the last frame did (null before the first). */
  stats: IrradianceStats | null = null;

  constructor(
    readonly device: GPUDevice,
    private readonly world: WorldGroup,
  ) {
    ({ pipeline: this.sample, layout: this.sampleLayout } = passPipeline(device, world, "irradiance.wgsl", irradianceWgsl, "path_trace", [
      "uniform",
      "uniform",
      "storage",
      "uniform",
      "storage",
      "storage",
    ]));
    const update: GPUBufferBindingType[] = ["uniform", "uniform", "storage", "storage", "read-only-storage"];
    const pass = (entry: string, group1: GPUBufferBindingType[]) =>
      passPipeline(device, world, "irradiance_update.wgsl", irradianceUpdateWgsl, entry, group1);
    ({ pipeline: this.invalidate, layout: this.invalidateLayout } = pass("irradiance_invalidate", update));
    ({ pipeline: this.update, layout: this.updateLayout } = pass("irradiance_update", update));
    ({ pipeline: this.args, layout: this.argsLayout } = pass("irradiance_args", [...update, "storage"]));
    const uniform = (size: number) => device.createBuffer({ size, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    this.light = uniform(GI_LIGHT_WORDS.length * 4);
    device.queue.writeBuffer(this.light, 0, new Uint32Array(GI_LIGHT_WORDS));
    this.info = uniform(IrradianceInfo.size);
    this.invalidateInfo = uniform(IrradianceInfo.size);
    this.noBoxes = device.createBuffer({ label: "irradiance no boxes", size: 32, usage: GPUBufferUsage.STORAGE });
    this.counters = device.createBuffer({
      label: "irradiance counters",
      size: IRR.LIST * 4,
      usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST,
    });
    this.sums = new ProgressiveSums(device, "irradiance");
  }

  /** Samples per pixel in the current view's sums. */
  get samples(): number {
    return this.sums.samples;
  }

  /** An empty cache of `slots` slots for a world of `size` (new buffers are zeroed: every
   * slot empty, every counter zero). */
  private allocate(size: string, slots: number, generation: number, stamp: number): Cache {
    this.drop();
    const storage = GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC | GPUBufferUsage.COPY_DST;
    return {
      size,
      slots,
      table: this.device.createBuffer({ label: "irradiance table", size: slots * IRR.WORDS * 4, usage: storage }),
      requests: this.device.createBuffer({
        label: "irradiance requests",
        size: (IRR.LIST + Math.min(slots, IRR.MAX_REQUESTS)) * 4,
        usage: storage,
      }),
      args: this.device.createBuffer({ label: "irradiance dispatch", size: 16, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.INDIRECT }),
      generation,
      stamp,
      keyed: 0,
    };
  }

  /** Frees the cache's buffers. */
  private drop(): void {
    if (!this.cache) return;
    for (const b of [this.cache.table, this.cache.requests, this.cache.args]) b.destroy();
    this.cache = undefined;
  }

  /** The cache's parameters for the frame of stamp `cache.stamp`, with `boxes` boxes. */
  private infoBytes(cache: Cache, boxes: number): ArrayBuffer {
    return writeStruct(IrradianceInfo, {
      stamp: cache.stamp,
      mask: cache.slots - 1,
      max_requests: Math.min(cache.slots, IRR.MAX_REQUESTS),
      budget: BUDGET,
      seed: DEFAULT_SEED,
      boxes,
    });
  }

  /** Brings the cache up to date for frames of `pixels` of `world` (client/src/gpu/irradiance.rs
   * `prepare`): a new one when the world's size changed or the table is too small, when the
   * table is more than half full, and when the change log says everything changed; else the
   * entries near the chunks changed since the last frame are cleared. */
  private async prepare(world: GpuWorld, pixels: number): Promise<Cache> {
    const size = JSON.stringify(world.chunks);
    const slots = slotsFor(pixels);
    const limit = Math.min(this.device.limits.maxStorageBufferBindingSize, this.device.limits.maxBufferSize);
    if (slots * IRR.WORDS * 4 > limit) {
      throw new Error(`an irradiance cache for ${pixels} pixels needs ${slots * IRR.WORDS * 4} bytes, over this adapter's ${limit}-byte binding`);
    }
    let cache = this.cache;
    if (!cache || cache.size !== size || cache.slots < slots || cache.generation > world.generation) {
      // An empty cache shows no change: nothing to invalidate.
      cache = this.cache = this.allocate(size, slots, world.generation, 0);
    }
    // The native renderer renews a table more than half full, reading the keyed count back
    // once a bound on it (two keys per pixel per frame) passes half the slots: the count
    // never exceeds the bound, so that is the count of the last frame past half. Here it
    // comes back with every frame's pixels, at no extra wait.
    if (cache.keyed > cache.slots / 2) {
      cache = this.cache = this.allocate(size, cache.slots, cache.generation, cache.stamp);
    }
    const changes = world.changesSince(cache.generation);
    cache.generation = world.generation;
    cache.stamp += 1;
    if (changes === "everything") {
      cache = this.cache = this.allocate(size, cache.slots, world.generation, cache.stamp);
      return cache;
    }
    this.device.queue.writeBuffer(cache.requests, 0, new Uint32Array(3));
    if (changes.length === 0) return cache;
    const boxes = changedBoxes(world.chunks, changes);
    const list = this.device.createBuffer({ label: "irradiance boxes", size: boxes.byteLength, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST });
    this.device.queue.writeBuffer(list, 0, boxes);
    this.device.queue.writeBuffer(this.invalidateInfo, 0, this.infoBytes(cache, boxes.length / 8));
    const group = bindBuffers(this.device, this.invalidateLayout, [this.light, this.invalidateInfo, cache.table, cache.requests, list]);
    await submitGroups(this.device, this.invalidate(world.hasInstances), this.world.of(world), group, Math.ceil(cache.slots / 64));
    list.destroy();
    return cache;
  }

  /** Adds one sample per pixel of `camera`'s view of `world` (the first, if the view or
   * the world changed), lighting diffuse world surfaces from the cache, then refreshes the
   * entries the sample requested; returns the tone-mapped mean. */
  async render(world: GpuWorld, camera: Camera, width: number, height: number): Promise<ImageData> {
    world.trackChanges();
    const cache = await this.prepare(world, width * height);
    const sums = this.sums.next(world, camera, width, height);
    this.device.queue.writeBuffer(this.info, 0, this.infoBytes(cache, 0));
    const buffers = [this.light, this.info, cache.table, cache.requests, this.noBoxes, cache.args];
    const sampleGroup = bindBuffers(this.device, this.sampleLayout, [this.sums.frame, this.light, sums, this.info, cache.table, cache.requests]);
    const group0 = this.world.of(world);
    const enc = await dispatchPixels(this.device, this.sample(world.hasInstances), group0, sampleGroup, width, height);
    const [args, update] = await Promise.all([this.args(world.hasInstances), this.update(world.hasInstances)]);
    let pass = enc.beginComputePass({ label: "irradiance_args" });
    pass.setPipeline(args);
    pass.setBindGroup(0, group0);
    pass.setBindGroup(1, bindBuffers(this.device, this.argsLayout, buffers));
    pass.dispatchWorkgroups(1);
    pass.end();
    // A pass of its own: the dispatch reads what the one before wrote.
    pass = enc.beginComputePass({ label: "irradiance_update" });
    pass.setPipeline(update);
    pass.setBindGroup(0, group0);
    pass.setBindGroup(1, bindBuffers(this.device, this.updateLayout, buffers.slice(0, 5)));
    pass.dispatchWorkgroupsIndirect(cache.args, 0);
    pass.end();
    enc.copyBufferToBuffer(cache.requests, 0, this.counters, 0, IRR.LIST * 4);
    const image = await this.sums.finish(enc, width, height);
    // The frame's submission is done (its sums came back): the counters are there too.
    await this.counters.mapAsync(GPUMapMode.READ);
    const words = new Uint32Array(this.counters.getMappedRange().slice(0));
    this.counters.unmap();
    cache.keyed = words[IRR.OCCUPIED];
    this.stats = {
      requested: words[IRR.COUNT],
      fresh: words[IRR.FRESH],
      samples: words[IRR.TAKEN],
      keyed: words[IRR.OCCUPIED],
      slots: cache.slots,
      stamp: cache.stamp,
    };
    return image;
  }
}

// The `gi` mode (docs/RENDERING.md §3c): the native client's GI pipeline, run by the page.
// The fifteen passes are entry points of gen/gi.wgsl, composed by the Rust client from the
// same shaders; this module is the host side of client/src/gpu/gi: the history's memory
// (each large array in one binding, the frame halved until they fit the adapter), the
// cameras of earlier frames, the change marks, the parameters and the frame's dispatches.
import giWgsl from "./gen/gi.wgsl?raw";
import { DEFAULT_EXPOSURE, DEFAULT_SEED, FrameInfo, GI, GI_LIGHT_WORDS, GI_PASSES, GiInfo } from "./gen/layout";
import type { Camera } from "./camera";
import { cameraRays } from "./camera";
import { toneMapped } from "./colour";
import type { WorldGroup } from "./compute";
import { entry, pipelineVariants, readBack, viewKey, writeStruct } from "./compute";
import type { Variants } from "./compute";
import type { GpuWorld } from "./gpu";

/** Where each array of `mem` starts (vec4 words): the cameras at 0, the sample ring last;
 * and the layout of `words` (client/src/gpu/gi/memory.rs, `Layout`). */
interface Layout {
  lut: number;
  gbuf: number;
  gmat: number;
  emitted: number;
  taaInfo: number;
  illum: number;
  illum2: number;
  result: number;
  refined: number;
  regionInfo: number;
  own: number;
  ringStart: number;
  queueList: number;
  words: number;
}

/** The memory of a history for one frame size (memory.rs, `Plan`). */
interface Plan {
  width: number;
  height: number;
  pixels: number;
  regions: number;
  layout: Layout;
  ring: number;
  memBytes: number;
  taaBytes: number;
}

function planOf(width: number, height: number): Plan {
  const pixels = width * height;
  const regions = Math.ceil(width / 8) * Math.ceil(height / 8);
  let at = GI.CAMERA_HISTORY * GI.CAM_WORDS;
  const next = (size: number) => {
    const start = at;
    at += size;
    return start;
  };
  const [lut, gbuf, gmat, emitted] = [next(GI.LUT_SIZE * GI.LUT_SIZE), next(pixels), next(pixels), next(pixels)];
  const [taaInfo, illum, illum2, result] = [next(2 * pixels), next(pixels), next(pixels), next(pixels)];
  const [refined, regionInfo, own] = [next(regions * GI.MAX_KEPT * 2), next(3 * regions), next(pixels)];
  const queueList = GI.CONTROL_WORDS + 2 * regions;
  const layout = {
    lut,
    gbuf,
    gmat,
    emitted,
    taaInfo,
    illum,
    illum2,
    result,
    refined,
    regionInfo,
    own,
    ringStart: at,
    queueList,
    words: queueList + 64 * regions + GI.POSE_TABLE_WORDS,
  };
  const ring = pixels * GI.RING_PER_PIXEL;
  return {
    width,
    height,
    pixels,
    regions,
    layout,
    ring,
    memBytes: (layout.ringStart + ring * GI.RING_VEC4) * 16,
    taaBytes: pixels * GI.TAA_PIXEL_BYTES,
  };
}

/** The GI's internal frame size for a `width × height` frame: halved until each of the
 * history's arrays fits one binding of `device` (the page binds each whole). */
export function giSize(device: GPUDevice, width: number, height: number): [number, number] {
  const limit = Math.min(device.limits.maxStorageBufferBindingSize, device.limits.maxBufferSize);
  let [w, h] = [width, height];
  for (;;) {
    const p = planOf(w, h);
    if (Math.max(p.memBytes, p.taaBytes, p.layout.words * 4) <= limit || (w === 1 && h === 1)) return [w, h];
    [w, h] = [Math.ceil(w / 2), Math.ceil(h / 2)];
  }
}

/** The jitter of frame `frame` in the pixel: point `frame mod 32` of a 32-point
 * (0, 5, 2)-net, centred in its strata (history.rs, `jitter`: van der Corput in x, the
 * second Sobol dimension in y, digitally shifted by ½). */
export function jitter(frame: number): [number, number] {
  const i = frame % GI.TAA_SLOTS;
  let x = 0;
  for (let b = 0; b < 32; b++) if (i & (1 << b)) x |= 1 << (31 - b);
  let [y, v, rest] = [0, 0x80000000, i];
  while (rest > 0) {
    if (rest & 1) y = (y ^ v) >>> 0;
    rest >>>= 1;
    v = (v ^ (v >>> 1)) >>> 0;
  }
  const half = Math.fround(0.5 / GI.TAA_SLOTS);
  const unit = (bits: number) => Math.fround(Math.fround(((bits ^ 0x80000000) >>> 0) / 4294967296) + half);
  return [unit(x >>> 0), unit(y)];
}

/** What the GI keeps from frame to frame (history.rs, `GiHistory`). */
class History {
  frames = 0;
  /** The cameras of this frame and earlier ones, newest first, with their jitters. */
  private readonly cameras: { camera: Camera; jitter: [number, number] }[] = [];
  /** Per chunk, the first frame after its newest change and after the newest change
   * within `CHANGE_REACH` of it (0: none); `changes` on the device. */
  private readonly marks: Uint32Array;
  /** The world generation of the last frame. */
  private generation: number;
  /** The first frame after the newest change of the materials or of many chunks, and
   * after the newest change of any chunk (0: none). */
  private editFrame = 0;
  private changeFrame = 0;
  readonly words: GPUBuffer;
  private readonly changes: GPUBuffer;
  readonly args: GPUBuffer;
  readonly mem: GPUBuffer;
  readonly staging: GPUBuffer;
  private readonly owned: GPUBuffer[];
  readonly group: GPUBindGroup;

  constructor(
    private readonly device: GPUDevice,
    layout: GPUBindGroupLayout,
    params: GPUBuffer[],
    readonly plan: Plan,
    readonly chunks: [number, number, number],
    world: GpuWorld,
  ) {
    const buffer = (label: string, size: number, usage: number) => device.createBuffer({ label, size: Math.max(16, size), usage });
    const storage = GPUBufferUsage.STORAGE;
    this.words = buffer("gi words", plan.layout.words * 4, storage | GPUBufferUsage.COPY_SRC);
    const buckets = buffer("gi buckets", plan.regions * (2 * GI.BUCKET_SLOTS + 12) * 4, storage);
    const chunkCount = chunks[0] * chunks[1] * chunks[2];
    this.changes = buffer("gi chunk changes", chunkCount * 8, storage | GPUBufferUsage.COPY_DST);
    this.mem = buffer("gi mem", plan.memBytes, storage | GPUBufferUsage.COPY_DST | GPUBufferUsage.COPY_SRC);
    const taa = buffer("gi taa", plan.taaBytes, storage);
    this.args = buffer("gi indirect args", GI.ARGS_BYTES, GPUBufferUsage.INDIRECT | GPUBufferUsage.COPY_DST);
    this.staging = buffer("gi result", plan.pixels * 16, GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST);
    this.owned = [this.words, buckets, this.changes, this.mem, taa, this.args, this.staging];
    this.marks = new Uint32Array(chunkCount * 2);
    this.generation = world.generation;
    this.group = device.createBindGroup({
      layout,
      entries: [...params, this.words, buckets, this.changes, this.mem, taa].map((b, binding) => ({ binding, resource: { buffer: b } })),
    });
  }

  destroy(): void {
    this.owned.forEach((b) => b.destroy());
  }

  /** Takes in what changed in `world` since the last frame: the chunks it names are
   * marked, and a change too large to mark chunk by chunk counts everywhere. */
  noteChanges(world: GpuWorld): void {
    if (this.generation === world.generation) return;
    const changed = world.changesSince(this.generation);
    if (changed === "everything" || changed.length > GI.MAX_LOCAL_CHANGES) {
      [this.editFrame, this.changeFrame] = [this.frames, this.frames];
    } else if (changed.length > 0) {
      this.mark(changed);
      this.changeFrame = this.frames;
    }
    this.generation = world.generation;
  }

  /** Marks `changed` chunks, and those within `CHANGE_REACH` of them, as changed before
   * this frame, and uploads the marks that moved. */
  private mark(changed: number[]): void {
    const [cx, cy, cz] = this.chunks;
    const reach = GI.CHANGE_REACH;
    let [lo, hi] = [Infinity, 0];
    const set = (i: number, k: number) => {
      this.marks[2 * i + k] = this.frames;
      [lo, hi] = [Math.min(lo, i), Math.max(hi, i + 1)];
    };
    for (const c of changed) {
      const [x0, y0, z0] = [c % cx, Math.floor(c / cx) % cy, Math.floor(c / (cx * cy))];
      set(c, 0);
      for (let z = Math.max(0, z0 - reach); z <= Math.min(cz - 1, z0 + reach); z++) {
        for (let y = Math.max(0, y0 - reach); y <= Math.min(cy - 1, y0 + reach); y++) {
          for (let x = Math.max(0, x0 - reach); x <= Math.min(cx - 1, x0 + reach); x++) set(x + cx * (y + cy * z), 1);
        }
      }
    }
    if (lo < hi) this.device.queue.writeBuffer(this.changes, lo * 8, this.marks, lo * 2, (hi - lo) * 2);
  }

  /** Starts this frame's camera: `camera`, with this frame's jitter, is the newest of the
   * cameras kept, and all are uploaded relative to this frame's integer position `int`, so
   * that nothing on the device subtracts two large coordinates. Returns the jitter. */
  uploadCameras(camera: Camera, int: number[]): [number, number] {
    const jit = jitter(this.frames);
    this.cameras.unshift({ camera, jitter: jit });
    this.cameras.length = Math.min(this.cameras.length, GI.CAMERA_HISTORY);
    const words = GI.CAM_WORDS * 4;
    const cams = new Float32Array(GI.CAMERA_HISTORY * words);
    this.cameras.forEach((past, age) => {
      const relative: Camera = { ...past.camera, pos: past.camera.pos.map((p, a) => p - int[a]) as Camera["pos"] };
      const r = cameraRays(relative, this.plan.width, this.plan.height);
      const pos = r.int.map((n, a) => Math.fround(Math.fround(n) + r.frac[a]));
      cams.set([...pos, past.jitter[0], ...r.forward, past.jitter[1], ...r.right, 0, ...r.up, 0, ...r.int, 0], age * words);
    });
    this.device.queue.writeBuffer(this.mem, 0, cams);
    return jit;
  }

  /** The GI state of this frame (`GiInfo`), with its `jitter`. */
  info(jitter: [number, number]): ArrayBuffer {
    const { plan, frames } = this;
    const l = plan.layout;
    return writeStruct(GiInfo, {
      frame: frames,
      taa_slot: frames % GI.TAA_SLOTS,
      taa_valid: Math.min(frames, GI.TAA_SLOTS - 1),
      edit_frame: this.editFrame,
      change_frame: this.changeFrame,
      jitter_x: jitter[0],
      jitter_y: jitter[1],
      regions_x: Math.ceil(plan.width / 8),
      regions_y: Math.ceil(plan.height / 8),
      ring_capacity: plan.ring,
      denoise: 1,
      off_own: l.own,
      off_lut: l.lut,
      off_gbuf: l.gbuf,
      off_gmat: l.gmat,
      off_emitted: l.emitted,
      off_taa_info: l.taaInfo,
      off_illum: l.illum,
      off_illum2: l.illum2,
      off_result: l.result,
      off_refined: l.refined,
      off_region_info: l.regionInfo,
      off_ring: l.ringStart,
      off_queue_list: l.queueList,
    });
  }
}

/** The GI renderer: one history, kept while the frame size and the world's size stay (the
 * camera may move and the world may change within it). */
export class GiRenderer {
  private readonly pipelines: Variants[];
  private readonly group1: GPUBindGroupLayout;
  /** The frame, light and GI-state parameters (group 1, bindings 0–2). */
  private readonly params: GPUBuffer[];
  private history: History | undefined;
  private lastView = "";
  /** Frames drawn since the view or the world last changed. */
  still = 0;

  constructor(
    readonly device: GPUDevice,
    private readonly world: WorldGroup,
  ) {
    // Three parameter uniforms, `words`, `buckets`, the read-only change marks, `mem`, `taa`.
    const types: GPUBufferBindingType[] = ["uniform", "uniform", "uniform", "storage", "storage", "read-only-storage", "storage", "storage"];
    this.group1 = device.createBindGroupLayout({ entries: types.map((t, i) => entry(i, t)) });
    const layout = device.createPipelineLayout({ bindGroupLayouts: [world.layout, this.group1] });
    const module = device.createShaderModule({ label: "gi.wgsl", code: giWgsl });
    this.pipelines = GI_PASSES.map((entryPoint) => pipelineVariants(device, { layout, compute: { module, entryPoint } }));
    const uniform = (label: string, size: number) => device.createBuffer({ label, size, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    this.params = [uniform("gi frame", FrameInfo.size), uniform("gi light", GI_LIGHT_WORDS.length * 4), uniform("gi state", GiInfo.size)];
    device.queue.writeBuffer(this.params[1], 0, new Uint32Array(GI_LIGHT_WORDS));
  }

  /** Renders the next frame of `camera`'s view of `world` at `width × height` (or the
   * largest halving of it that fits); resolves to it, tone-mapped, once read back. */
  async render(world: GpuWorld, camera: Camera, width: number, height: number): Promise<ImageData> {
    const device = this.device;
    const [w, h] = giSize(device, width, height);
    world.trackChanges();
    let hist = this.history;
    if (!hist || hist.plan.width !== w || hist.plan.height !== h || hist.chunks.join() !== world.chunks.join()) {
      hist?.destroy();
      hist = this.history = new History(device, this.group1, this.params, planOf(w, h), [...world.chunks], world);
    }
    hist.noteChanges(world);
    const view = viewKey(camera, w, h, world);
    this.still = view === this.lastView ? this.still + 1 : 1;
    this.lastView = view;

    const now = cameraRays(camera, w, h);
    const jit = hist.uploadCameras(camera, now.int);
    const frames = hist.frames;
    device.queue.writeBuffer(
      this.params[0],
      0,
      writeStruct(FrameInfo, {
        cam_int: now.int,
        width: w,
        cam_frac: now.frac,
        height: h,
        forward: now.forward,
        seed: DEFAULT_SEED,
        right: now.right,
        sample: frames,
        up: now.up,
        history: frames > 0 ? 1 : 0,
      }),
    );
    device.queue.writeBuffer(this.params[2], 0, hist.info(jit));

    const pipes = await Promise.all(this.pipelines.map((p) => p(world.hasInstances)));
    const enc = device.createCommandEncoder();
    GI_PASSES.forEach((pass, k) => {
      // The atmosphere table is filled when a history starts.
      if (pass === "gi_atmosphere" && frames > 0) return;
      // A dispatch cannot read its arguments from a buffer it binds: copy them out first.
      if (pass === "gi_trace") enc.copyBufferToBuffer(hist.words, 0, hist.args, 0, GI.ARGS_BYTES);
      const cp = enc.beginComputePass({ label: pass });
      cp.setPipeline(pipes[k]);
      cp.setBindGroup(0, this.world.of(world));
      cp.setBindGroup(1, hist.group);
      switch (pass) {
        case "gi_atmosphere":
          cp.dispatchWorkgroups(GI.LUT_SIZE / 8, GI.LUT_SIZE / 8);
          break;
        case "gi_queue_scan":
          cp.dispatchWorkgroups(1);
          break;
        case "gi_trace":
          cp.dispatchWorkgroupsIndirect(hist.args, GI.CONTROL_TRACE_ARGS * 4);
          break;
        case "gi_project":
        case "gi_project_store":
          cp.dispatchWorkgroupsIndirect(hist.args, GI.CONTROL_PROJECT_ARGS * 4);
          break;
        case "gi_refine":
          cp.dispatchWorkgroups(Math.ceil(hist.plan.regions / 64));
          break;
        case "gi_poses":
          cp.dispatchWorkgroups(Math.ceil(GI.NO_ENTITY / 64));
          break;
        default:
          cp.dispatchWorkgroups(Math.ceil(w / 8), Math.ceil(h / 8));
      }
      cp.end();
    });
    hist.frames += 1;
    const result = hist.plan.layout.result * 16;
    const px = new Float32Array(await readBack(device, enc, hist.mem, result, hist.staging, hist.plan.pixels * 16));
    return toneMapped(px, w, h, DEFAULT_EXPOSURE, false);
  }
}

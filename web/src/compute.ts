// What every compute pass of the page shares: parameter structs written by their generated
// layouts, group 0 (the world), pipelines compiled in the background, dispatches over a
// frame's pixels and read-backs.
import type { StructLayout } from "./gen/layout";
import type { Camera } from "./camera";
import type { GpuWorld } from "./gpu";

/** What an accumulating pass's samples depend on: the camera, the size and the world's
 * bytes. Samples taken under another key do not add up. */
export function viewKey(camera: Camera, width: number, height: number, world: GpuWorld): string {
  return JSON.stringify([camera, width, height, world.generation]);
}

/** Writes `values` into `layout`'s fields of a struct's bytes. */
export function writeStruct(layout: StructLayout, values: Record<string, number | number[]>): ArrayBuffer {
  const bytes = new ArrayBuffer(layout.size);
  const view = new DataView(bytes);
  for (const [name, value] of Object.entries(values)) {
    const f = layout.fields[name];
    if (!f) throw new Error(`no field ${name}`);
    const list = Array.isArray(value) ? value : [value];
    list.forEach((v, i) => {
      const at = f.offset + 4 * i;
      if (f.type.includes("f32")) view.setFloat32(at, v, true);
      else if (f.type.includes("i32")) view.setInt32(at, v, true);
      else view.setUint32(at, v, true);
    });
  }
  return bytes;
}

/** A compute-stage buffer binding. */
export const entry = (binding: number, type: GPUBufferBindingType): GPUBindGroupLayoutEntry => ({
  binding,
  visibility: GPUShaderStage.COMPUTE,
  buffer: { type },
});

/** Group 0 of every pass: `world_info`, `world_offsets` and `world`, rebound when the
 * world's buffer is replaced. */
export class WorldGroup {
  readonly layout: GPUBindGroupLayout;
  private group: GPUBindGroup | undefined;
  private layoutGeneration = -1;

  constructor(private readonly device: GPUDevice) {
    this.layout = device.createBindGroupLayout({
      entries: [entry(0, "uniform"), entry(1, "uniform"), entry(2, "read-only-storage")],
    });
  }

  of(world: GpuWorld): GPUBindGroup {
    if (!this.group || this.layoutGeneration !== world.layoutGeneration) {
      this.group = this.device.createBindGroup({
        layout: this.layout,
        entries: [
          { binding: 0, resource: { buffer: world.info } },
          { binding: 1, resource: { buffer: world.offsets } },
          { binding: 2, resource: { buffer: world.buffer! } },
        ],
      });
      this.layoutGeneration = world.layoutGeneration;
    }
    return this.group;
  }
}

/** A pass's pipeline for a world with instances (`true`) or without: the override
 * `HAS_INSTANCES` leaves the instance walk out of the second, which SwiftShader, running
 * invocations in lock step, would otherwise pay for in every frame (docs/WEB.md). */
export type Variants = (hasInstances: boolean) => Promise<GPUComputePipeline>;

/** The two variants of the pipeline `desc`, each compiled in the background when first
 * asked for, and the other one right after it, so that a world that gains its first
 * instance or loses its last does not wait for a compile. */
export function pipelineVariants(device: GPUDevice, desc: GPUComputePipelineDescriptor): Variants {
  const made = new Map<boolean, Promise<GPUComputePipeline>>();
  const make = (has: boolean): Promise<GPUComputePipeline> => {
    let p = made.get(has);
    if (!p) {
      const constants = { ...desc.compute.constants, HAS_INSTANCES: has ? 1 : 0 };
      p = device.createComputePipelineAsync({ ...desc, compute: { ...desc.compute, constants } });
      made.set(has, p);
      // The other variant only once this one is built, so that it does not slow this one.
      // (A failed compile is reported by whoever asks for that variant.)
      p.then(() => make(!has)).catch(() => undefined);
    }
    return p;
  };
  return make;
}

/** A pass's pipelines over group 0 and its own group 1 of `group1` bindings, compiled in
 * the background (a big pass takes seconds on a software adapter): the compile overlaps
 * the world's download, and a mode never drawn is never compiled. */
export function passPipeline(device: GPUDevice, world: WorldGroup, label: string, code: string, entryPoint: string, group1: GPUBufferBindingType[]) {
  const layout = device.createBindGroupLayout({ entries: group1.map((t, i) => entry(i, t)) });
  const pipeline = pipelineVariants(device, {
    layout: device.createPipelineLayout({ bindGroupLayouts: [world.layout, layout] }),
    compute: { module: device.createShaderModule({ label, code }), entryPoint },
  });
  return { pipeline, layout };
}

/** A bind group of `layout` binding `buffers` at 0, 1, 2, … in order. */
export function bindBuffers(device: GPUDevice, layout: GPUBindGroupLayout, buffers: GPUBuffer[]): GPUBindGroup {
  return device.createBindGroup({ layout, entries: buffers.map((buffer, binding) => ({ binding, resource: { buffer } })) });
}

/** Submits one dispatch of `groups` workgroups of `pipeline` (split in two dimensions at
 * the adapter's limit), with the world as group 0 and `group1`. */
export async function submitGroups(
  device: GPUDevice,
  pipeline: Promise<GPUComputePipeline>,
  world: GPUBindGroup,
  group1: GPUBindGroup,
  groups: number,
): Promise<void> {
  const enc = device.createCommandEncoder();
  const pass = enc.beginComputePass();
  pass.setPipeline(await pipeline);
  pass.setBindGroup(0, world);
  pass.setBindGroup(1, group1);
  const max = device.limits.maxComputeWorkgroupsPerDimension;
  pass.dispatchWorkgroups(Math.min(groups, max), Math.ceil(groups / max));
  pass.end();
  device.queue.submit([enc.finish()]);
}

/** An encoder holding one dispatch of `pipeline` over `width × height` pixels in 8×8
 * workgroups, with the world as group 0 and `group1`. */
export async function dispatchPixels(
  device: GPUDevice,
  pipeline: Promise<GPUComputePipeline>,
  world: GPUBindGroup,
  group1: GPUBindGroup,
  width: number,
  height: number,
): Promise<GPUCommandEncoder> {
  const enc = device.createCommandEncoder();
  const pass = enc.beginComputePass();
  pass.setPipeline(await pipeline);
  pass.setBindGroup(0, world);
  pass.setBindGroup(1, group1);
  pass.dispatchWorkgroups(Math.ceil(width / 8), Math.ceil(height / 8));
  pass.end();
  return enc;
}

/** Copies `bytes` of `source` from byte `offset` to `staging` after `enc`'s work, submits,
 * and resolves to the bytes. */
export async function readBack(
  device: GPUDevice,
  enc: GPUCommandEncoder,
  source: GPUBuffer,
  offset: number,
  staging: GPUBuffer,
  bytes: number,
): Promise<ArrayBuffer> {
  enc.copyBufferToBuffer(source, offset, staging, 0, bytes);
  device.queue.submit([enc.finish()]);
  await staging.mapAsync(GPUMapMode.READ);
  const out = staging.getMappedRange().slice(0);
  staging.unmap();
  return out;
}


// What the progressive modes (`pathtrace`, `roma`) share: running sums of one sample per
// pixel per frame, kept while the view and the world stay the same and shown as
// sRGB(ACES(mean)).
import { DEFAULT_EXPOSURE, DEFAULT_SEED, FrameInfo } from "./gen/layout";
import { readBack, viewKey, writeStruct } from "./compute";
import type { Camera } from "./camera";
import { cameraRays } from "./camera";
import { toneMapped } from "./colour";
import type { GpuWorld } from "./gpu";

/** The running sums of a progressive pass and the `frame` parameters of its next sample. */
export class ProgressiveSums {
  /** The `frame` uniform (`FrameInfo`) of the next sample. */
  readonly frame: GPUBuffer;
  private sums: GPUBuffer | undefined;
  private staging: GPUBuffer | undefined;
  private key = "";
  /** Samples per pixel in the sums. */
  samples = 0;

  constructor(
    readonly device: GPUDevice,
    private readonly label: string,
  ) {
    this.frame = device.createBuffer({ size: FrameInfo.size, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
  }

  /** The sums buffer for the next sample of `camera`'s view of `world` (new, zeroed sums
   * when the view or the world changed), with `frame` written for it. */
  next(world: GpuWorld, camera: Camera, width: number, height: number): GPUBuffer {
    const bytes = width * height * 16;
    const key = viewKey(camera, width, height, world);
    if (key !== this.key || !this.sums) {
      this.sums?.destroy();
      this.staging?.destroy();
      // New buffers are zeroed: the sums start over.
      this.sums = this.device.createBuffer({ label: `${this.label} sums`, size: bytes, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC });
      this.staging = this.device.createBuffer({ label: `${this.label} frame`, size: bytes, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
      this.key = key;
      this.samples = 0;
    }
    const rays = cameraRays(camera, width, height);
    this.device.queue.writeBuffer(
      this.frame,
      0,
      writeStruct(FrameInfo, {
        cam_int: rays.int,
        width,
        cam_frac: rays.frac,
        height,
        forward: rays.forward,
        seed: DEFAULT_SEED,
        right: rays.right,
        sample: this.samples,
        up: rays.up,
        history: 0,
      }),
    );
    return this.sums;
  }

  /** Submits `enc` (which adds the sample), reads the sums back and returns their
   * tone-mapped mean. */
  async finish(enc: GPUCommandEncoder, width: number, height: number): Promise<ImageData> {
    this.samples += 1;
    const sums = new Float32Array(await readBack(this.device, enc, this.sums!, 0, this.staging!, width * height * 16));
    return toneMapped(sums, width, height, DEFAULT_EXPOSURE, true);
  }
}

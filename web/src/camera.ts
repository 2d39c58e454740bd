// The camera contract (docs/CAMERA.md): JSON, basis, and the rays the render pass takes.

/** A camera as its JSON gives it. */
export interface Camera {
  pos: [number, number, number];
  yaw: number;
  pitch: number;
  fov_y: number;
}

/** Largest coordinate the shaders take (2^30). */
const MAX_COORD = 2 ** 30;
/** The largest f32 below 1: a fraction never rounds up to 1. */
const BELOW_ONE = Math.fround(0.99999994);

/** Parses camera JSON as `Camera::from_json` does; throws a message on bad input. */
export function parseCamera(text: string): Camera {
  let v: unknown;
  try {
    v = JSON.parse(text);
  } catch (e) {
    throw new Error(`camera JSON: ${(e as Error).message}`);
  }
  if (typeof v !== "object" || v === null) throw new Error("camera JSON: not an object");
  const o = v as Record<string, unknown>;
  const pos = o.pos;
  if (!Array.isArray(pos) || pos.length !== 3 || pos.some((c) => typeof c !== "number")) {
    throw new Error("camera JSON: pos must be three numbers");
  }
  for (const k of ["yaw", "pitch"]) {
    if (typeof o[k] !== "number") throw new Error(`camera JSON: missing number ${k}`);
  }
  if (o.fov_y !== undefined && typeof o.fov_y !== "number") throw new Error("camera JSON: fov_y must be a number");
  const c: Camera = {
    pos: [pos[0], pos[1], pos[2]],
    yaw: o.yaw as number,
    pitch: o.pitch as number,
    fov_y: (o.fov_y as number | undefined) ?? 90,
  };
  const finite = [...c.pos, c.yaw, c.pitch, c.fov_y].every(Number.isFinite);
  if (!finite || !(c.fov_y > 0 && c.fov_y < 180)) {
    throw new Error("camera values must be finite and 0 < fov_y < 180");
  }
  return c;
}

/** The camera as JSON, in the contract's field order. */
export function cameraJson(c: Camera): string {
  return JSON.stringify({ pos: c.pos, yaw: c.yaw, pitch: c.pitch, fov_y: c.fov_y });
}

const radians = (deg: number) => deg * (Math.PI / 180);
type V3 = [number, number, number];
const cross = (a: V3, b: V3): V3 => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const normalize = (a: V3): V3 => {
  const l = Math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  return [a[0] / l, a[1] / l, a[2] / l];
};

/** The orthonormal basis of a camera (pitch clamped to ±89.9°), in f64. */
export function basis(c: Camera): { forward: V3; right: V3; up: V3 } {
  const yaw = radians(c.yaw);
  const pitch = radians(Math.min(89.9, Math.max(-89.9, c.pitch)));
  const forward: V3 = [Math.sin(yaw) * Math.cos(pitch), Math.sin(pitch), Math.cos(yaw) * Math.cos(pitch)];
  const right = normalize(cross([0, 1, 0], forward));
  const up = cross(forward, right);
  return { forward, right, up };
}

/** The camera as the render pass takes it: the position's floor and f32 fraction, and the
 * basis with `right` and `up` scaled by a·W/H and a, in f32. */
export function cameraRays(c: Camera, width: number, height: number) {
  if (c.pos.some((p) => Math.abs(p) > MAX_COORD)) throw new Error("camera position is out of range (within ±2^30)");
  const b = basis(c);
  const a = Math.tan(radians(c.fov_y) / 2);
  const aspect = width / height;
  const int = c.pos.map(Math.floor) as V3;
  const frac = c.pos.map((p, i) => Math.min(Math.fround(p - int[i]), BELOW_ONE)) as V3;
  const scale = (v: V3, s: number) => v.map((x) => Math.fround(x * s)) as V3;
  return { int, frac, forward: scale(b.forward, 1), right: scale(b.right, a * aspect), up: scale(b.up, a) };
}

/** The default view of a world of `size` voxels: the first of the fixed cameras that the
 * status page and the benchmarks use (`raysets::fixed_cameras`). */
export function defaultCamera(size: [number, number, number]): Camera {
  return { pos: [0.5 * size[0], 0.7 * size[1], 0.05 * size[2]], yaw: 0, pitch: -15, fov_y: 70 };
}

// What is drawn over the frame: the other people here (the name over each camera's marker
// box, which the GPU draws as a local instance, markers.ts; their pointer voxel outlined)
// and the active tool's preview, projected with the camera contract.
import type { Camera } from "./camera";
import { basis } from "./camera";
import type { PresenceEntry } from "./gen/naadf/v1/naadf_pb";
import { labelAnchor, plausible } from "./markers";
import type { Region } from "./tools";

type V3 = [number, number, number];

/** The name label drawn for another client, and where its camera is on the frame (render
 * pixels; where the label is when the camera is behind this one's). */
export interface Marker {
  name: string;
  x: number;
  y: number;
}

/** Projects world point `p` onto a `w × h` frame of `camera`; undefined behind it. */
export function project(camera: Camera, w: number, h: number, p: V3): [number, number] | undefined {
  const b = basis(camera);
  const d = p.map((x, i) => x - camera.pos[i]) as V3;
  const dot = (u: V3, v: V3) => u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
  const z = dot(d, b.forward);
  if (z <= 1e-3) return undefined;
  const a = Math.tan((camera.fov_y * Math.PI) / 360);
  const sx = dot(d, b.right) / (z * a * (w / h));
  const sy = dot(d, b.up) / (z * a);
  return [((sx + 1) / 2) * w, ((1 - sy) / 2) * h];
}

/** The ray through frame point `(x, y)` of a `w × h` frame (docs/CAMERA.md), unnormalised. */
export function rayThrough(camera: Camera, w: number, h: number, x: number, y: number): V3 {
  const b = basis(camera);
  const a = Math.tan((camera.fov_y * Math.PI) / 360);
  const sx = ((2 * x) / w - 1) * a * (w / h);
  const sy = (1 - (2 * y) / h) * a;
  return [0, 1, 2].map((i) => b.forward[i] + sx * b.right[i] + sy * b.up[i]) as V3;
}

/** Outlines the box `[min, max)` in `colour`. */
function drawBox(ctx: CanvasRenderingContext2D, camera: Camera, min: V3, max: V3, colour: string): void {
  const { width: w, height: h } = ctx.canvas;
  const corner = (i: number): V3 => [i & 1 ? max[0] : min[0], i & 2 ? max[1] : min[1], i & 4 ? max[2] : min[2]];
  ctx.strokeStyle = colour;
  ctx.lineWidth = 2;
  ctx.beginPath();
  for (let i = 0; i < 8; i++) {
    for (const bit of [1, 2, 4]) {
      if (i & bit) continue;
      const a = project(camera, w, h, corner(i));
      const b = project(camera, w, h, corner(i | bit));
      if (!a || !b) continue;
      ctx.moveTo(a[0], a[1]);
      ctx.lineTo(b[0], b[1]);
    }
  }
  ctx.stroke();
}

/** Draws the overlay: the preview `region`, and the pointer voxels and names of `others`;
 * returns the names drawn (those whose camera is in front and inside the frame). */
export function drawOverlay(
  ctx: CanvasRenderingContext2D,
  camera: Camera,
  region: Region | undefined,
  others: PresenceEntry[],
): Marker[] {
  const { width: w, height: h } = ctx.canvas;
  ctx.clearRect(0, 0, w, h);
  if (region) drawBox(ctx, camera, region.min, region.max, region.refusal ? "#f44" : "#ff0");
  const drawn: Marker[] = [];
  ctx.font = `${Math.max(11, Math.round(h / 40))}px system-ui, sans-serif`;
  for (const e of others) {
    const name = e.name || e.user || "anonymous";
    if (e.pointer.length === 3) {
      const v = e.pointer.map(Number) as V3;
      drawBox(ctx, camera, v, [v[0] + 1, v[1] + 1, v[2] + 1], "#0ff");
    }
    if (!plausible(e.position)) continue;
    // Centred over the marker box, a little above its top face, when that point is on the
    // frame (as in the native viewer). (Written so that a NaN would be left out too.)
    const label = project(camera, w, h, labelAnchor(e.position));
    if (!label || !(label[0] >= 0 && label[1] >= 0 && label[0] < w && label[1] < h)) continue;
    const at = project(camera, w, h, e.position as V3) ?? label;
    ctx.fillStyle = "#fff";
    ctx.textAlign = "center";
    ctx.textBaseline = "bottom";
    ctx.fillText(name, label[0], label[1] - 2);
    drawn.push({ name, x: at[0], y: at[1] });
  }
  return drawn;
}

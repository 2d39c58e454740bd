// The other people here as local instances (docs/FORMAT.md §5.11): a small solid box at
// each one's camera, in a material of the world's palette that their presence session
// picks, so that the GPU draws them in the world, lit, hiding what is behind them and
// hidden behind the terrain. The overlay (overlay.ts) only writes their names over them.
import type { PresenceEntry } from "./gen/naadf/v1/naadf_pb";
import type { LocalBox } from "./instances";
import type { Swatch } from "./tools";

/** The edge of a marker box in voxels: odd, so that the voxel holding the camera is its
 * centre. */
export const MARKER_EDGE = 3;

/** The materials a marker may take, in id order: those of the palette that neither emit
 * light nor mirror (diffuse and metal: a marker shows its own colour and does not light the
 * scene on one client alone), or the whole palette when it has none of those. The native
 * viewer picks from the same list. */
export function markerMaterials(swatches: Swatch[]): number[] {
  const plain = swatches.filter((s) => s.kind === 0 || s.kind === 2);
  return (plain.length > 0 ? plain : swatches).map((s) => s.id);
}

/** The material of the marker of presence session `session`: one of `materials` (as
 * `markerMaterials` lists them), the one at index `session` modulo their count, the same
 * for as long as the session and the palette last; undefined when the list is empty. */
export function markerMaterial(session: bigint, materials: number[]): number | undefined {
  if (materials.length === 0) return undefined;
  return materials[Number(BigInt.asUintN(64, session) % BigInt(materials.length))];
}

/** Whether a position another client published can be a camera: three finite numbers, far
 * inside the range where voxel arithmetic stays exact (below 1e15 in magnitude). Anything
 * else gets neither box nor name, as in the native viewer. */
export function plausible(pos: number[]): boolean {
  return pos.length === 3 && pos.every((v) => Number.isFinite(v) && Math.abs(v) < 1e15);
}

/** The marker box of a camera at `pos` in a world of `size` voxels: `MARKER_EDGE` voxels a
 * side around the voxel holding `pos`, clipped to the world; undefined when no voxel of it
 * is inside the world, when `pos` is not `plausible`, or when `eye` (this page's camera) is
 * inside it (a box around the viewer would hide everything). */
export function markerBox(pos: number[], size: number[], material: number, eye?: number[]): LocalBox | undefined {
  if (!plausible(pos)) return undefined;
  const corner = unclippedCorner(pos);
  const min = corner.map((c) => Math.max(0, c));
  const max = corner.map((c, a) => Math.min(size[a], c + MARKER_EDGE));
  if (min.some((v, a) => v >= max[a])) return undefined;
  if (eye && eye.every((e, a) => e >= min[a] && e < max[a])) return undefined;
  return { min, size: max.map((v, a) => v - min[a]), material };
}

/** The lowest corner of the marker box of a `plausible` camera at `pos`, before clipping:
 * `MARKER_EDGE` voxels a side, centred on the voxel holding `pos`. */
function unclippedCorner(pos: number[]): number[] {
  return pos.map((p) => Math.floor(p) - (MARKER_EDGE >> 1));
}

/** Where the name of the `plausible` camera at `pos` is written: the middle of its marker
 * box's top face, before clipping, so that the name stands over the box. */
export function labelAnchor(pos: number[]): [number, number, number] {
  const [x, y, z] = unclippedCorner(pos);
  return [x + MARKER_EDGE / 2, y + MARKER_EDGE, z + MARKER_EDGE / 2];
}

/** The marker boxes of `others` (presence entries with a position) in a world of `size`
 * voxels, in `materials` (as `markerMaterials` lists them), seen from `eye`: in the order
 * of their sessions, so that the same people give the same list. */
export function markerBoxes(others: PresenceEntry[], size: number[], materials: number[], eye?: number[]): LocalBox[] {
  const boxes: LocalBox[] = [];
  for (const e of [...others].sort((p, q) => (p.session < q.session ? -1 : p.session > q.session ? 1 : 0))) {
    const material = markerMaterial(e.session, materials);
    const box = material === undefined ? undefined : markerBox(e.position, size, material, eye);
    if (box) boxes.push(box);
  }
  return boxes;
}

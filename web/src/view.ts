// The view a link names: `?camera=…&mode=…&size=WxH` (docs/WEB.md). An invalid parameter
// is reported and its default used instead; camera and mode are kept current in the URL.
import type { Camera } from "./camera";
import { cameraJson, parseCamera } from "./camera";
import { RENDER_MODES } from "./gen/layout";

/** The modes of docs/RENDERING.md, in the order the page offers them. */
export const MODES = ["albedo", "material", "normal", "steps", "gi", "pathtrace"] as const;

/** The most samples per pixel the path tracer adds to one view. */
const DEFAULT_MAX_SPP = 4096;
/** Largest render edge, as the native renderer allows. */
const MAX_EDGE = 8192;

/** What the URL asked for, and what was wrong with it. */
export interface LinkedView {
  camera: Camera | undefined;
  mode: string | undefined;
  size: [number, number] | undefined;
  /** The most samples per pixel `pathtrace` adds (`spp`). */
  spp: number;
  problems: string[];
}

/** Reads the view from `search` (a `location.search`). */
export function readLink(search: string): LinkedView {
  const q = new URLSearchParams(search);
  const out: LinkedView = { camera: undefined, mode: undefined, size: undefined, spp: DEFAULT_MAX_SPP, problems: [] };
  const camera = q.get("camera");
  if (camera !== null) {
    try {
      out.camera = parseCamera(camera);
    } catch (e) {
      out.problems.push(`camera: ${(e as Error).message}; using the default view`);
    }
  }
  const mode = q.get("mode");
  if (mode !== null) {
    if ((MODES as readonly string[]).includes(mode)) out.mode = mode;
    else out.problems.push(`mode: '${mode}' is not one of ${MODES.join(", ")}; using the default`);
  }
  const size = q.get("size");
  if (size !== null) {
    const m = /^(\d{1,5})x(\d{1,5})$/.exec(size);
    const [w, h] = m ? [Number(m[1]), Number(m[2])] : [0, 0];
    if (w >= 1 && h >= 1 && w <= MAX_EDGE && h <= MAX_EDGE) out.size = [w, h];
    else out.problems.push(`size: '${size}' is not WxH with edges 1..=${MAX_EDGE}; using the canvas size`);
  }
  const spp = q.get("spp");
  if (spp !== null) {
    const n = Number(spp);
    if (Number.isInteger(n) && n >= 1 && n <= DEFAULT_MAX_SPP) out.spp = n;
    else out.problems.push(`spp: '${spp}' is not a whole number in 1..=${DEFAULT_MAX_SPP}; using ${DEFAULT_MAX_SPP}`);
  }
  return out;
}

/** Writes camera and mode into the URL (keeping `size` only when it was given). */
export function writeLink(camera: Camera, mode: string, size: [number, number] | undefined): void {
  const q = new URLSearchParams();
  q.set("camera", cameraJson(camera));
  q.set("mode", mode);
  if (size) q.set("size", `${size[0]}x${size[1]}`);
  history.replaceState(null, "", `${location.pathname}?${q.toString().replace(/\+/g, "%20")}`);
}

/** The mode the page draws for `wanted`: the render pass's modes and `pathtrace`; `gi`
 * is drawn as `pathtrace` until the page has the GI pipeline's passes. */
export function drawnMode(wanted: string): string {
  return wanted in RENDER_MODES || wanted === "pathtrace" ? wanted : "pathtrace";
}

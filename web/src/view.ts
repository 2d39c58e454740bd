// The view a link names: `?camera=…&mode=…&size=WxH` (docs/WEB.md). An invalid parameter
// is reported and its default used instead; camera and mode are kept current in the URL.
import type { Camera } from "./camera";
import { cameraJson, parseCamera } from "./camera";
import { GI } from "./gen/layout";

/** The modes of docs/RENDERING.md, in the order the page offers them. */
export const MODES = ["albedo", "material", "normal", "steps", "gi", "roma", "irradiance", "pathtrace"] as const;

/** The most samples per pixel the path tracer adds to one view, and the most `spp` takes. */
const DEFAULT_MAX_SPP = 4096;
/** The most frames the GI draws of a view that stays still: its TAA is full twice over. */
const DEFAULT_GI_FRAMES = 2 * GI.TAA_SLOTS;
/** Largest render edge, as the native renderer allows. */
const MAX_EDGE = 8192;

/** What the URL asked for, and what was wrong with it. */
export interface LinkedView {
  camera: Camera | undefined;
  mode: string | undefined;
  size: [number, number] | undefined;
  /** The most samples per pixel `pathtrace`, `roma` or `irradiance` adds, or frames `gi` draws, to a
   * still view (`spp`), when given. */
  spp: number | undefined;
  problems: string[];
}

/** Reads the view from `search` (a `location.search`). */
export function readLink(search: string): LinkedView {
  const q = new URLSearchParams(search);
  const out: LinkedView = { camera: undefined, mode: undefined, size: undefined, spp: undefined, problems: [] };
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
    else out.problems.push(`spp: '${spp}' is not a whole number in 1..=${DEFAULT_MAX_SPP}; using the mode's default`);
  }
  return out;
}

/** Writes camera and mode into the URL (keeping `size` and `spp` only when they were given). */
export function writeLink(camera: Camera, mode: string, link: LinkedView): void {
  const q = new URLSearchParams();
  q.set("camera", cameraJson(camera));
  q.set("mode", mode);
  if (link.size) q.set("size", `${link.size[0]}x${link.size[1]}`);
  if (link.spp) q.set("spp", String(link.spp));
  history.replaceState(null, "", `${location.pathname}?${q.toString().replace(/\+/g, "%20")}`);
}

/** How far an accumulating mode goes with a still view: `spp` when given, else 4096
 * samples per pixel for `pathtrace`, `roma` and `irradiance` and 64 frames for `gi`. */
export function accumulationCap(mode: string, link: LinkedView): number {
  return link.spp ?? (mode === "gi" ? DEFAULT_GI_FRAMES : DEFAULT_MAX_SPP);
}

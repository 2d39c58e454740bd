// The page: joins the world that served it, draws it with WebGPU, and lets a person fly,
// edit and see who else is here. `window.naadf` is its state for tests and scripts
// (docs/WEB.md).
import { create } from "@bufbuild/protobuf";
import { Code, ConnectError } from "@connectrpc/connect";
import { EditRequestSchema, HistoryRequestSchema, PresenceRequestSchema } from "./gen/naadf/v1/naadf_pb";
import type { PresenceEntry } from "./gen/naadf/v1/naadf_pb";
import type { Camera } from "./camera";
import { basis, defaultCamera } from "./camera";
import { PageCache } from "./cache";
import { digestHex, loadHasher } from "./digest";
import { GpuWorld, NoWebGpu, Renderer, openDevice } from "./gpu";
import type { LocalBox } from "./instances";
import { InstanceHierarchy, hierarchyWords } from "./instances";
import type { IrradianceStats } from "./irradiance";
import { markerBoxes, markerMaterials } from "./markers";
import type { Marker } from "./overlay";
import { drawOverlay, rayThrough } from "./overlay";
import type { Pick } from "./pick";
import { Voxels, pick } from "./pick";
import { Session } from "./session";
import type { SessionState } from "./session";
import type { Region, ToolState } from "./tools";
import { TOOLS, commit, palette, preview, solidPreview } from "./tools";
import { touchControls } from "./touch";
import { MODES, accumulationCap, readLink, writeLink } from "./view";

/** The page's state, as `window.naadf` shows it. */
interface PageState {
  state: SessionState | "no-webgpu";
  version: number;
  growthSeq: number;
  quiescent: boolean;
  digest: string;
  users: string[];
  mode: string;
  frameMs: number;
  /** Why the page is in `need-token`, `no-webgpu` or `error`, or what the last refusal said. */
  message: string;
  /** The caller's role, once known (`viewer` pages cannot edit). */
  role: string;
  /** `Join` streams opened, snapshots taken (a resume takes none) and world bytes received. */
  joins: number;
  snapshots: number;
  bytesReceived: number;
  /** Bytes of the last snapshot (or resume): its header and pages. */
  snapshotBytes: number;
  /** The other clients' name labels drawn on the last frame. */
  markers: Marker[];
  /** Calls retried after the server's rate limit turned them away. */
  rateLimited: number;
  /** Milliseconds from navigation to each step of opening: `device`, `restored` (the
   * cache), `live` and `firstFrame`. */
  timings: Record<string, number>;
  /** The version the canvas shows. */
  shownVersion: number;
  /** The GPU world's generation the canvas shows (`generation()`): local instances too. */
  shownGeneration: number;
  /** The local instances the active tool's preview shows. */
  previewInstances: number;
  /** The local instances that mark the other clients' cameras (markers.ts). */
  markerInstances: number;
  /** Their materials, in the order of the other clients' presence sessions. */
  markerMaterials: number[];
  /** This page's presence session, in decimal (what picks its marker's material on the
   * other clients). */
  presenceSession: string;
  /** The path tracer's (or `roma`'s, or `irradiance`'s) samples per pixel, or the GI's
   * frames, since the view last changed. */
  samples: number;
  /** What `irradiance`'s last frame did to its cache (null before its first frame). */
  irradiance: IrradianceStats | null;
  /** The voxel under the pointer and the empty voxel before it (where placing tools build). */
  pointer: { voxel: number[]; before: number[] } | null;
  /** The display name this page publishes. */
  name: string;
  capture(): Promise<string>;
  /** The material of a voxel as the page holds it (0: empty). */
  voxel(x: number, y: number, z: number): number;
  /** Draws the next frame even if nothing changed (benchmarks). */
  redraw(): void;
  /** Counts the changes of the world's bytes on the GPU. */
  generation(): number;
  /** The chunks that show something else than at `generation` (`"everything"` when that
   * is too old), as the GI's history learns them; tracked once `gi` has drawn. */
  changedChunks(since: number): number[] | "everything";
  /** Sends one ops-JSON line (docs/OPS.md) as an edit; resolves to the new version. */
  edit(ops: string): Promise<number>;
  undo(): Promise<number>;
  redo(): Promise<number>;
  /** The instance hierarchy the page builds over an instance buffer (the words of its
   * records), as the shaders read it; tests compare it with the native build's. */
  hierarchy(records: number[]): number[];
  /** The hierarchy the page keeps for `records` after it held one for `previous`
   * (refitted or built anew, as the native client decides). */
  hierarchyAfter(previous: number[], records: number[]): number[];
}

const $ = <T extends HTMLElement>(id: string) => document.getElementById(id) as T;
const canvas = $<HTMLCanvasElement>("view");
const overlay = $<HTMLCanvasElement>("overlay");
const hud = $<HTMLDivElement>("hud");
const notice = $<HTMLDivElement>("notice");

const link = readLink(location.search);
const naadf: PageState = {
  state: "connecting",
  version: 0,
  growthSeq: 0,
  quiescent: false,
  digest: "",
  users: [],
  mode: link.mode ?? "albedo",
  frameMs: 0,
  message: link.problems.join("\n"),
  role: "",
  joins: 0,
  snapshots: 0,
  bytesReceived: 0,
  snapshotBytes: 0,
  markers: [],
  rateLimited: 0,
  timings: {},
  shownVersion: -1,
  shownGeneration: -1,
  previewInstances: 0,
  markerInstances: 0,
  markerMaterials: [],
  presenceSession: "",
  samples: 0,
  irradiance: null,
  pointer: null,
  name: "",
  voxel: () => 0,
  capture: () => Promise.reject(new Error("no frame yet")),
  redraw: () => {},
  generation: () => 0,
  changedChunks: () => "everything",
  edit: () => Promise.reject(new Error("not joined")),
  undo: () => Promise.reject(new Error("not joined")),
  redo: () => Promise.reject(new Error("not joined")),
  hierarchy: (records) => Array.from(hierarchyWords(Uint32Array.from(records))),
  hierarchyAfter: (previous, records) => {
    const kept = new InstanceHierarchy();
    kept.update(Uint32Array.from(previous));
    return Array.from(kept.update(Uint32Array.from(records)));
  },
};
(window as unknown as { naadf: PageState }).naadf = naadf;

function showNotice(text: string): void {
  notice.textContent = text;
  notice.hidden = text === "";
}
showNotice(naadf.message);

let camera: Camera | undefined = link.camera;
let rtt = 0;

function renderSize(): [number, number] {
  if (link.size) return link.size;
  const dpr = window.devicePixelRatio || 1;
  return [Math.max(1, Math.round(canvas.clientWidth * dpr)), Math.max(1, Math.round(canvas.clientHeight * dpr))];
}

function drawHud(): void {
  const lines = [
    `${naadf.state}${naadf.role ? ` · ${naadf.role}` : ""}`,
    `version ${naadf.version}${naadf.growthSeq ? `.${naadf.growthSeq}` : ""}${naadf.quiescent ? "" : " (settling)"}`,
    `digest ${naadf.digest.slice(0, 8)}`,
    `${naadf.users.length} online${naadf.users.length ? `: ${naadf.users.join(", ")}` : ""}`,
    `rtt ${rtt.toFixed(0)} ms · frame ${naadf.frameMs.toFixed(1)} ms · ${naadf.mode}`,
  ];
  hud.textContent = lines.join("\n");
}

/** The frame point (render pixels) under a mouse event on the canvas, which is drawn
 * letterboxed (`object-fit: contain`); the centre under pointer lock. */
function framePoint(e: MouseEvent | undefined): [number, number] {
  const [w, h] = [canvas.width, canvas.height];
  if (!e || document.pointerLockElement === canvas) return [w / 2, h / 2];
  const r = canvas.getBoundingClientRect();
  const scale = Math.min(r.width / w, r.height / h);
  const [ox, oy] = [(r.width - w * scale) / 2, (r.height - h * scale) / 2];
  return [(e.clientX - r.left - ox) / scale, (e.clientY - r.top - oy) / scale];
}

async function main(): Promise<void> {
  await loadHasher();
  let device: GPUDevice;
  let fallback: boolean;
  try {
    ({ device, fallback } = await openDevice());
  } catch (e) {
    if (e instanceof NoWebGpu) {
      naadf.state = "no-webgpu";
      naadf.message = `${e.message}. Open this page in a browser with WebGPU (https://, or http://localhost), or use the native viewer: naadf view --server <address>`;
      showNotice(naadf.message);
      drawHud();
      return;
    }
    throw e;
  }
  naadf.timings.device = performance.now();
  if (!link.mode) naadf.mode = fallback ? "albedo" : "gi";
  const context = canvas.getContext("2d")!;
  const marks = overlay.getContext("2d")!;
  const world = new GpuWorld(device);
  const renderer = new Renderer(device, naadf.mode);
  let voxels: Voxels | undefined;
  let others: PresenceEntry[] = [];
  // The local instances' parts: the tool's solid preview, and the palette's materials that
  // the other clients' markers take theirs from.
  let previewBoxes: LocalBox[] = [];
  let markerIds: number[] = [];
  // `dirty`: the next animation frame renders the world again; `overlayDirty`: it only
  // redraws the overlay (the other clients' names and pointers, the tool's outline) over
  // the frame shown.
  let dirty = true;
  let overlayDirty = false;
  let shownView: Camera | undefined;
  const tool: ToolState = { tool: "voxel", material: 1, radius: 4, anchor: undefined };
  let pointer: Pick | undefined;
  let region: Region | undefined;
  let lastMouse: MouseEvent | undefined;

  const presenceSession = BigInt(Math.floor(Math.random() * 2 ** 52));
  naadf.presenceSession = presenceSession.toString();
  const upload = (m: typeof session.mirror) => {
    world.uploadAll(m);
    camera ??= defaultCamera(m.size);
    fillPalette();
    sync(m);
  };
  const session = new Session({
    state(s, why) {
      naadf.state = s;
      naadf.bytesReceived = session.bytesReceived;
      naadf.snapshotBytes = session.snapshotBytes;
      if (s === "live") naadf.timings.live ??= performance.now();
      if (why !== undefined) {
        naadf.message = why;
        showNotice(s === "need-token" ? `${why}: enter a token` : why);
        if (s === "need-token") askToken(why);
      }
      drawHud();
    },
    joined() {
      naadf.joins += 1;
    },
    snapshot(m) {
      naadf.snapshots += 1;
      upload(m);
    },
    restored: upload,
    patched(m, touched, resized) {
      world.update(m, touched, resized);
      if (touched.some((t) => t.id === 4)) fillPalette();
      sync(m);
    },
    presence(entries) {
      naadf.users = entries.map((e) => e.name || e.user || "anonymous").sort();
      others = entries.filter((e) => e.session !== presenceSession);
      showLocals();
      overlayDirty = true;
      drawHud();
    },
  }, await PageCache.open());
  function sync(m: typeof session.mirror): void {
    voxels = new Voxels(m);
    naadf.version = Number(m.version);
    naadf.growthSeq = m.growthSeq;
    naadf.quiescent = m.quiescent;
    naadf.digest = digestHex(m.digest);
    naadf.bytesReceived = session.bytesReceived;
    naadf.snapshotBytes = session.snapshotBytes;
    dirty = true;
    drawHud();
  }

  // Calls: a refusal is shown as the server said it; a rate limit is retried with the same
  // client_seq, so the edit is applied once.
  let seq = BigInt(Date.now()) * 1000n;
  const call = async (f: (clientSeq: bigint) => Promise<{ version: bigint }>): Promise<number> => {
    const clientSeq = (seq += 1n);
    for (let attempt = 0; ; attempt++) {
      const t0 = performance.now();
      try {
        const reply = await f(clientSeq);
        rtt = performance.now() - t0;
        if (attempt > 0) showNotice("");
        drawHud();
        return Number(reply.version);
      } catch (e) {
        const err = ConnectError.from(e);
        if (err.code === Code.ResourceExhausted && attempt < 8) {
          naadf.rateLimited += 1;
          showNotice(`rate-limited: ${err.rawMessage}; retrying`);
          await new Promise((r) => setTimeout(r, 250 * 2 ** attempt));
          continue;
        }
        naadf.message = err.rawMessage;
        showNotice(`refused: ${err.rawMessage}`);
        throw err;
      }
    }
  };
  naadf.edit = (ops) => call((clientSeq) => session.client.edit(create(EditRequestSchema, { ops, clientSeq }), session.callOptions()));
  naadf.undo = () => call((clientSeq) => session.client.undo(create(HistoryRequestSchema, { clientSeq }), session.callOptions()));
  naadf.redo = () => call((clientSeq) => session.client.redo(create(HistoryRequestSchema, { clientSeq }), session.callOptions()));
  naadf.redraw = () => {
    dirty = true;
  };
  naadf.generation = () => world.generation;
  naadf.changedChunks = (since) => world.changesSince(since);
  naadf.capture = async () => {
    const image = renderer.last;
    if (!image) throw new Error("no frame yet");
    const c = document.createElement("canvas");
    c.width = image.width;
    c.height = image.height;
    c.getContext("2d")!.putImageData(image, 0, 0);
    return c.toDataURL("image/png");
  };

  function askToken(why: string): void {
    const form = $<HTMLFormElement>("token");
    form.hidden = false;
    $<HTMLSpanElement>("token-why").textContent = why;
    form.onsubmit = (ev) => {
      ev.preventDefault();
      form.hidden = true;
      session.setToken($<HTMLInputElement>("token-value").value);
      void session.run();
      void identify();
    };
  }
  async function identify(): Promise<void> {
    try {
      const me = await session.whoAmI();
      naadf.role = me.role;
      const viewer = me.role === "viewer";
      $<HTMLDivElement>("tools").classList.toggle("disabled", viewer);
      if (viewer) showNotice("viewer token: editing is disabled (ask for an editor token to edit)");
      drawHud();
    } catch {
      // The stream reports refusals.
    }
  }

  // Presence: who this page is, where it looks and what it points at: at most every 100 ms
  // while that changes, and every second regardless (entries leave the table after 5 s).
  const name = sessionStorage.getItem("naadf.name") ?? `guest-${Math.floor(Math.random() * 1e4)}`;
  sessionStorage.setItem("naadf.name", name);
  naadf.name = name;
  naadf.voxel = (x, y, z) => (voxels?.inside(x, y, z) ? voxels.cell(x, y, z).material : 0);
  let published = "";
  let publishedAt = 0;
  setInterval(() => {
    if (naadf.state !== "live" || !camera) return;
    const msg = {
      session: presenceSession,
      name,
      position: [...camera.pos],
      forward: basis(camera).forward,
      pointer: pointer ? pointer.voxel.map(BigInt) : [],
      tool: tool.tool,
    };
    const key = JSON.stringify(msg, (_, v) => (typeof v === "bigint" ? String(v) : v));
    const now = performance.now();
    if (key === published && now - publishedAt < 1000) return;
    published = key;
    publishedAt = now;
    session.client.publish(create(PresenceRequestSchema, msg), session.callOptions()).catch(() => {});
  }, 100);

  // Tools: the toolbar, the palette and the pointer.
  const toolSelect = $<HTMLSelectElement>("tool");
  for (const t of TOOLS) toolSelect.add(new Option(t, t));
  toolSelect.onchange = () => {
    tool.tool = toolSelect.value as ToolState["tool"];
    tool.anchor = undefined;
    overlayDirty = true;
  };
  const radius = $<HTMLInputElement>("radius");
  radius.onchange = () => {
    tool.radius = Math.max(0, Number(radius.value) || 0);
    overlayDirty = true;
  };
  function fillPalette(): void {
    const swatches = palette(session.mirror);
    markerIds = markerMaterials(swatches);
    const box = $<HTMLDivElement>("palette");
    box.replaceChildren(
      ...swatches.map((s) => {
        const b = document.createElement("button");
        b.className = s.id === tool.material ? "swatch chosen" : "swatch";
        b.style.background = s.colour;
        b.title = `material ${s.id}`;
        b.onclick = () => {
          tool.material = s.id;
          fillPalette();
        };
        return b;
      }),
    );
  }
  /** Picks the voxel under the pointer in the frame shown, seen from `view`. */
  function aim(view: Camera): void {
    if (!voxels || canvas.width === 0) return;
    const [x, y] = framePoint(lastMouse);
    pointer = pick(voxels, [...view.pos], rayThrough(view, canvas.width, canvas.height, x, y));
    region = pointer && naadf.role !== "viewer" ? preview(tool, voxels, pointer) : undefined;
    naadf.pointer = pointer ? { voxel: pointer.voxel, before: pointer.before } : null;
    // The voxel and box tools show what they would build where it would go.
    previewBoxes = hovering ? solidPreview(tool, region) : [];
    showLocals();
  }
  /** Gives the GPU the page's local instances: the tool's preview, then a marker box at
   * each other client's camera (none around this page's own camera); the frame is drawn
   * again when they changed. */
  function showLocals(): void {
    const generation = world.generation;
    const marked = markerBoxes(others, session.mirror.size, markerIds, camera?.pos);
    world.setLocals([...previewBoxes, ...marked]);
    naadf.previewInstances = previewBoxes.length;
    naadf.markerInstances = marked.length;
    naadf.markerMaterials = marked.map((b) => b.material);
    if (world.generation !== generation) dirty = true;
  }
  // The solid preview shows only while the mouse is over the view: the frame of a page
  // nobody points at shows the world alone.
  let hovering = false;
  canvas.addEventListener("mousemove", (e) => {
    lastMouse = e;
    hovering = true;
    overlayDirty = true;
  });
  canvas.addEventListener("mouseleave", () => {
    hovering = false;
    overlayDirty = true;
  });
  canvas.addEventListener("contextmenu", (e) => e.preventDefault());
  canvas.addEventListener("mousedown", (e) => {
    if (e.button === 2 && document.pointerLockElement !== canvas) {
      canvas.requestPointerLock?.();
      return;
    }
    if (e.button !== 0 || naadf.role === "viewer" || !shownView) return;
    lastMouse = e;
    aim(shownView);
    if (!pointer || region?.refusal) {
      if (region?.refusal) showNotice(`${tool.tool}: ${region.refusal}`);
      return;
    }
    const ops = commit(tool, pointer);
    overlayDirty = true;
    if (ops) naadf.edit(ops).then(() => showNotice(""), () => {});
  });

  // Flying: WASD (Space up, Shift down) and the mouse under pointer lock (right click);
  // the wheel sets the speed. Ctrl+Z undoes this user's last batch, Ctrl+Shift+Z redoes.
  const keys = new Set<string>();
  let speed = 32;
  addEventListener("keydown", (e) => {
    if ((e.ctrlKey || e.metaKey) && e.code === "KeyZ") {
      e.preventDefault();
      (e.shiftKey ? naadf.redo() : naadf.undo()).catch(() => {});
      return;
    }
    if (e.target instanceof HTMLInputElement) return;
    keys.add(e.code);
  });
  addEventListener("keyup", (e) => keys.delete(e.code));
  /** Turns the view by a pointer's move of `dx`, `dy` pixels. */
  const look = (dx: number, dy: number) => {
    if (!camera) return;
    camera.yaw += dx * 0.15;
    camera.pitch = Math.max(-89.9, Math.min(89.9, camera.pitch - dy * 0.15));
    dirty = true;
  };
  addEventListener("mousemove", (e) => {
    if (document.pointerLockElement === canvas) look(e.movementX, e.movementY);
  });
  // Touch: a finger looks round as the mouse does; two fingers fly 1/64 of the speed
  // (voxels a second) per pixel.
  touchControls(canvas, {
    look,
    fly(forward, right) {
      if (!camera) return;
      const b = basis(camera);
      camera.pos.forEach((_, i) => (camera!.pos[i] += (b.forward[i] * forward + b.right[i] * right) * (speed / 64)));
      dirty = true;
    },
  });
  canvas.addEventListener("wheel", (e) => {
    speed = Math.max(1, Math.min(4096, speed * (e.deltaY < 0 ? 1.25 : 0.8)));
    e.preventDefault();
  });

  const frameTimes: number[] = [];
  let lastTick = performance.now();
  // The link follows the view at most twice a second, and always ends on the last view.
  let lastUrl = 0;
  let linkPending = false;
  function linkLater(): void {
    if (linkPending) return;
    linkPending = true;
    setTimeout(() => {
      linkPending = false;
      lastUrl = performance.now();
      if (camera) writeLink(camera, naadf.mode, link);
    }, Math.max(0, 500 - (performance.now() - lastUrl)));
  }
  let drawing = false;
  function frame(now: number): void {
    const dt = Math.min(0.1, (now - lastTick) / 1000);
    lastTick = now;
    if (camera && keys.size > 0) {
      const b = basis(camera);
      const move = (v: number[], s: number) => v.forEach((c, i) => (camera!.pos[i] += c * s * speed * dt));
      if (keys.has("KeyW")) move(b.forward, 1);
      if (keys.has("KeyS")) move(b.forward, -1);
      if (keys.has("KeyD")) move(b.right, 1);
      if (keys.has("KeyA")) move(b.right, -1);
      if (keys.has("Space")) move([0, 1, 0], 1);
      if (keys.has("ShiftLeft")) move([0, 1, 0], -1);
      dirty = true;
    }
    if (world.buffer && camera && dirty && !drawing) {
      // The markers skip the one the camera has flown into.
      showLocals();
      dirty = false;
      drawing = true;
      const [w, h] = renderSize();
      const t0 = performance.now();
      const version = naadf.version;
      const generation = world.generation;
      const view: Camera = { ...camera, pos: [...camera.pos] };
      renderer
        .render(world, view, w, h, naadf.mode)
        .then((image) => {
          for (const c of [canvas, overlay]) {
            // `gi` may draw a smaller frame than asked for (its history must fit the adapter).
            if (c.width !== image.width || c.height !== image.height) [c.width, c.height] = [image.width, image.height];
          }
          context.putImageData(image, 0, 0);
          shownView = view;
          overlayDirty = true;
          frameTimes.push(performance.now() - t0);
          if (frameTimes.length > 30) frameTimes.shift();
          naadf.frameMs = frameTimes.reduce((a, b) => a + b, 0) / frameTimes.length;
          naadf.shownVersion = version;
          naadf.shownGeneration = generation;
          naadf.timings.firstFrame ??= performance.now();
          // The path tracer and the GI keep improving while nothing changes.
          naadf.samples = renderer.samples(naadf.mode);
          naadf.irradiance = renderer.irradianceStats;
          if (Renderer.accumulates(naadf.mode) && naadf.samples < accumulationCap(naadf.mode, link)) dirty = true;
          drawHud();
        })
        .catch((e) => console.error(`frame: ${e}`))
        .finally(() => (drawing = false));
      linkLater();
    }
    if (overlayDirty && shownView) {
      overlayDirty = false;
      aim(shownView);
      naadf.markers = drawOverlay(marks, shownView, region, others);
    }
    requestAnimationFrame(frame);
  }
  requestAnimationFrame(frame);

  const modeSelect = $<HTMLSelectElement>("mode");
  for (const m of MODES) modeSelect.add(new Option(m, m, false, m === naadf.mode));
  modeSelect.onchange = () => {
    naadf.mode = modeSelect.value;
    dirty = true;
  };
  $<HTMLButtonElement>("undo").onclick = () => naadf.undo().catch(() => {});
  $<HTMLButtonElement>("redo").onclick = () => naadf.redo().catch(() => {});
  $<HTMLButtonElement>("shot").onclick = async () => {
    const a = document.createElement("a");
    a.href = await naadf.capture();
    a.download = `naadf-${naadf.version}.png`;
    a.click();
  };
  addEventListener("resize", () => (dirty = true));
  void identify();
  if (await session.restore()) naadf.timings.restored = performance.now();
  await session.run();
}

main().catch((e) => {
  naadf.state = "error";
  naadf.message = String(e instanceof Error ? e.message : e);
  showNotice(naadf.message);
  drawHud();
});

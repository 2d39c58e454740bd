// The page: joins the world that served it, draws it with WebGPU, and lets a person fly,
// edit and see who else is here. `window.naadf` is its state for tests and scripts
// (docs/WEB.md).
import { create } from "@bufbuild/protobuf";
import { ConnectError } from "@connectrpc/connect";
import { EditRequestSchema, HistoryRequestSchema, PresenceRequestSchema } from "./gen/naadf/v1/naadf_pb";
import type { Camera } from "./camera";
import { defaultCamera, basis } from "./camera";
import { digestHex, loadHasher } from "./digest";
import { GpuWorld, NoWebGpu, Renderer, openDevice } from "./gpu";
import { Session } from "./session";
import type { SessionState } from "./session";
import { MODES, drawnMode, readLink, writeLink } from "./view";

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
  /** The caller's role, once known. */
  role: string;
  /** Bytes of world messages received since the page opened. */
  bytesReceived: number;
  capture(): Promise<string>;
  /** Sends one ops-JSON line (docs/OPS.md) as an edit; resolves to the new version. */
  edit(ops: string): Promise<number>;
  undo(): Promise<number>;
  redo(): Promise<number>;
}

const $ = <T extends HTMLElement>(id: string) => document.getElementById(id) as T;
const canvas = $<HTMLCanvasElement>("view");
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
  bytesReceived: 0,
  capture: () => Promise.reject(new Error("no frame yet")),
  edit: () => Promise.reject(new Error("not joined")),
  undo: () => Promise.reject(new Error("not joined")),
  redo: () => Promise.reject(new Error("not joined")),
};
(window as unknown as { naadf: PageState }).naadf = naadf;

function showNotice(text: string): void {
  notice.textContent = text;
  notice.hidden = text === "";
}
showNotice(naadf.message);

let camera: Camera | undefined = link.camera;
let dirty = true;
const frameTimes: number[] = [];
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

async function main(): Promise<void> {
  await loadHasher();
  let device: GPUDevice;
  let fallback: boolean;
  try {
    ({ device, fallback } = await openDevice());
  } catch (e) {
    if (e instanceof NoWebGpu) {
      naadf.state = "no-webgpu";
      naadf.message = `${e.message}. Open this page in a browser with WebGPU, or use the native viewer: naadf view --server <address>`;
      showNotice(naadf.message);
      drawHud();
      return;
    }
    throw e;
  }
  if (!link.mode) naadf.mode = fallback ? "albedo" : "gi";
  const context = canvas.getContext("2d")!;
  const world = new GpuWorld(device);
  const renderer = new Renderer(device);
  let hasWorld = false;

  const session = new Session({
    state(s, why) {
      naadf.state = s;
      if (why !== undefined) {
        naadf.message = why;
        showNotice(s === "need-token" ? `${why}: enter a token` : why);
        if (s === "need-token") askToken(why);
      }
      drawHud();
    },
    snapshot(m) {
      world.uploadAll(m);
      hasWorld = true;
      camera ??= defaultCamera(m.size);
      sync(m);
    },
    patched(m, touched, resized) {
      world.update(m, touched, resized);
      sync(m);
    },
    presence(entries) {
      naadf.users = entries.map((e) => e.name || e.user || "anonymous").sort();
      drawHud();
    },
  });
  function sync(m: typeof session.mirror): void {
    naadf.version = Number(m.version);
    naadf.growthSeq = m.growthSeq;
    naadf.quiescent = m.quiescent;
    naadf.digest = digestHex(m.digest);
    naadf.bytesReceived = session.bytesReceived;
    dirty = true;
    drawHud();
  }

  const seq = { next: BigInt(Date.now()) * 1000n };
  const call = async (f: () => Promise<{ version: bigint }>): Promise<number> => {
    const t0 = performance.now();
    try {
      const reply = await f();
      rtt = performance.now() - t0;
      return Number(reply.version);
    } catch (e) {
      const err = ConnectError.from(e);
      naadf.message = err.rawMessage;
      showNotice(`refused: ${err.rawMessage}`);
      throw err;
    }
  };
  naadf.edit = (ops) => {
    const clientSeq = (seq.next += 1n);
    return call(() => session.client.edit(create(EditRequestSchema, { ops, clientSeq }), session.callOptions()));
  };
  naadf.undo = () =>
    call(() => session.client.undo(create(HistoryRequestSchema, { clientSeq: (seq.next += 1n) }), session.callOptions()));
  naadf.redo = () =>
    call(() => session.client.redo(create(HistoryRequestSchema, { clientSeq: (seq.next += 1n) }), session.callOptions()));
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
      if (me.role === "viewer") showNotice("viewer token: editing is disabled");
      drawHud();
    } catch {
      // The stream reports refusals.
    }
  }

  // Presence: who this page is and where it looks, about 10 times a second while it moves.
  const name = sessionStorage.getItem("naadf.name") ?? `guest-${Math.floor(Math.random() * 1e4)}`;
  sessionStorage.setItem("naadf.name", name);
  const presenceSession = BigInt(Math.floor(Math.random() * 2 ** 52));
  setInterval(() => {
    if (naadf.state !== "live" || !camera) return;
    const f = basis(camera).forward;
    session.client
      .publish(
        create(PresenceRequestSchema, { session: presenceSession, name, position: camera.pos, forward: f, tool: "view" }),
        session.callOptions(),
      )
      .catch(() => {});
  }, 200);

  // Flying: WASD (Space up, Shift down) and the mouse under pointer lock; the wheel sets the speed.
  const keys = new Set<string>();
  let speed = 32;
  addEventListener("keydown", (e) => keys.add(e.code));
  addEventListener("keyup", (e) => keys.delete(e.code));
  canvas.addEventListener("click", () => canvas.requestPointerLock?.());
  addEventListener("mousemove", (e) => {
    if (document.pointerLockElement !== canvas || !camera) return;
    camera.yaw += e.movementX * 0.15;
    camera.pitch = Math.max(-89.9, Math.min(89.9, camera.pitch - e.movementY * 0.15));
    dirty = true;
  });
  canvas.addEventListener("wheel", (e) => {
    speed = Math.max(1, Math.min(4096, speed * (e.deltaY < 0 ? 1.25 : 0.8)));
    e.preventDefault();
  });
  let lastTick = performance.now();
  let drawing = false;
  let lastUrl = 0;

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
    if (hasWorld && camera && dirty && !drawing) {
      dirty = false;
      drawing = true;
      const [w, h] = renderSize();
      const t0 = performance.now();
      const version = naadf.version;
      renderer
        .render(world, camera, w, h, drawnMode(naadf.mode))
        .then((image) => {
          if (canvas.width !== w || canvas.height !== h) {
            canvas.width = w;
            canvas.height = h;
          }
          context.putImageData(image, 0, 0);
          frameTimes.push(performance.now() - t0);
          if (frameTimes.length > 30) frameTimes.shift();
          naadf.frameMs = frameTimes.reduce((a, b) => a + b, 0) / frameTimes.length;
          document.body.dataset.shownVersion = String(version);
          drawHud();
        })
        .catch((e) => console.error(`frame: ${e}`))
        .finally(() => (drawing = false));
      if (now - lastUrl > 500) {
        lastUrl = now;
        writeLink(camera, naadf.mode, link.size);
      }
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
  $<HTMLButtonElement>("shot").onclick = async () => {
    const a = document.createElement("a");
    a.href = await naadf.capture();
    a.download = `naadf-${naadf.version}.png`;
    a.click();
  };
  addEventListener("resize", () => (dirty = true));
  void identify();
  await session.run();
}

main().catch((e) => {
  naadf.state = "error";
  naadf.message = String(e instanceof Error ? e.message : e);
  showNotice(naadf.message);
  drawHud();
});

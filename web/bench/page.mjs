// The page's benchmarks (BENCHMARKS.md, "The browser page"), against a running server:
//
//   node web/bench/page.mjs --server http://127.0.0.1:50051 --naadf target/release/naadf [--edits 200] [--reps 3]
//        [--parts open,edits,frames] [--modes albedo,material,normal,steps,gi,pathtrace] [--open-mode albedo]
//
// - page open to first frame in `--open-mode`, cold (a new browser profile) and from the
//   page's cache (a reload), alternated, `--reps` times each;
// - bytes at join, against `naadf mirror --once --json --no-cache` of the same server;
// - edit to visible, page to page: page A sends `--edits` one-voxel edits one after another,
//   and the time from A's call to B showing that version is taken, at 320×180;
// - frame ms per mode at 640×360 (`gi` and `pathtrace`: each frame after the first, which
//   builds on the ones before).
//
// It edits the world (voxels at y = size.y − 2, where terrain seldom reaches). Prints one
// JSON object.
import { execFileSync } from "node:child_process";
import { mkdtempSync, rmSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";
import { parseArgs } from "node:util";
import { chromium } from "playwright-core";
import { FLAGS, executablePath } from "../tests/chromium.mjs";

const { values: args } = parseArgs({
  options: {
    server: { type: "string", default: "http://127.0.0.1:50051" },
    naadf: { type: "string", default: "naadf" },
    edits: { type: "string", default: "200" },
    reps: { type: "string", default: "3" },
    parts: { type: "string", default: "open,edits,frames" },
    modes: { type: "string", default: "albedo,material,normal,steps,gi,pathtrace" },
    "open-mode": { type: "string", default: "albedo" },
  },
});

/** A browser with a profile of its own (so its IndexedDB starts empty). */
async function launch() {
  const dir = mkdtempSync(join(tmpdir(), "naadf-bench-"));
  const context = await chromium.launchPersistentContext(dir, { executablePath, args: FLAGS, viewport: { width: 640, height: 360 } });
  return { context, close: async () => (await context.close(), rmSync(dir, { recursive: true, force: true })) };
}

const state = (page) => page.evaluate(() => JSON.parse(JSON.stringify(window.naadf ?? null)));
async function until(page, test, ms = 600000) {
  const end = Date.now() + ms;
  for (;;) {
    const s = await state(page);
    if (s && test(s)) return s;
    if (Date.now() > end) throw new Error(`timed out; last state ${JSON.stringify(s)}`);
    await new Promise((r) => setTimeout(r, 5));
  }
}
const firstFrame = (s) => s.state === "live" && s.shownVersion === s.version && s.frameMs > 0;
const quantile = (xs, q) => {
  const s = [...xs].sort((a, b) => a - b);
  return s[Math.min(s.length - 1, Math.floor(q * s.length))];
};
const summary = (xs) => ({ median: quantile(xs, 0.5), min: Math.min(...xs), max: Math.max(...xs), runs: xs.map((x) => Math.round(x)) });
const url = (query) => `${args.server}/?${query}`;

const out = { server: args.server };
const status = JSON.parse(execFileSync(args.naadf, ["status", "--server", args.server, "--json"]).toString());
out.world = status.size;

const parts = args.parts.split(",");

// Page open to first frame: cold, then a reload from the cache, alternated.
if (parts.includes("open")) {
  const cold = [];
  const cached = [];
  let bytes;
  for (let i = 0; i < Number(args.reps); i++) {
    const b = await launch();
    const page = await b.context.newPage();
    let t0 = performance.now();
    await page.goto(url(`mode=${args["open-mode"]}`));
    const s = await until(page, firstFrame);
    cold.push(performance.now() - t0);
    bytes = s.snapshotBytes;
    await new Promise((r) => setTimeout(r, 3000)); // the cache is written within a second
    t0 = performance.now();
    await page.reload();
    const r = await until(page, firstFrame);
    cached.push(performance.now() - t0);
    out.cachedJoinBytes = r.bytesReceived;
    await b.close();
  }
  out.openToFirstFrameMs = { cold: summary(cold), cached: summary(cached) };
  const dir = mkdtempSync(join(tmpdir(), "naadf-bench-"));
  const native = JSON.parse(
    execFileSync(args.naadf, ["mirror", "--server", args.server, "--once", "--json", "--no-cache", "-o", join(dir, "w.naadf")]).toString(),
  );
  rmSync(dir, { recursive: true, force: true });
  out.joinBytes = { page: bytes, native: native.bytes, equal: bytes === native.bytes };
}

// Edit to visible, page to page.
if (parts.includes("edits")) {
  const b = await launch();
  const a = await b.context.newPage();
  const v = await b.context.newPage();
  for (const p of [a, v]) {
    await p.goto(url("mode=albedo&size=320x180"));
    await until(p, (s) => firstFrame(s) && s.quiescent);
  }
  const [sx, sy, sz] = status.size;
  const times = [];
  for (let i = 0; i < Number(args.edits); i++) {
    const x = 1 + ((i * 37) % (sx - 2));
    const z = 1 + ((i * 91) % (sz - 2));
    const ops = JSON.stringify({ op: "set", voxels: [[x, sy - 2, z, 1 + (i % 2)]] });
    const t0 = performance.now();
    const version = await a.evaluate((o) => window.naadf.edit(o), ops);
    await until(v, (s) => s.shownVersion >= version, 60000);
    times.push(performance.now() - t0);
  }
  out.editToVisibleMs = { size: "320x180", edits: times.length, p50: quantile(times, 0.5), p99: quantile(times, 0.99), max: Math.max(...times) };
  await b.close();
}

// Frame ms per mode at 640×360.
if (parts.includes("frames")) {
  const b = await launch();
  const page = await b.context.newPage();
  out.frameMs = { size: "640x360" };
  for (const mode of args.modes.split(",")) {
    await page.goto(url(`mode=${mode}&size=640x360`));
    await until(page, firstFrame);
    const times = [];
    for (let i = 0; i < 10; i++) {
      const before = (await state(page)).frameMs;
      const t0 = performance.now();
      await page.evaluate(() => window.naadf.redraw());
      await until(page, (s) => s.frameMs !== before);
      times.push(performance.now() - t0);
    }
    out.frameMs[mode] = summary(times);
  }
  await b.close();
}
console.log(JSON.stringify(out, null, 2));

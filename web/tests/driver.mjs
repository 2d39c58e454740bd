// node driver.mjs: drives pages in headless Chromium for the Rust tests (tests/web_page.rs)
// and benchmarks. Reads one JSON command per line on stdin, answers one JSON line each:
// {"ok":true,"value":…} or {"ok":false,"error":"…"}.
//
//   {"op":"open","id":"a","url":"…"}                 opens a page (`"insecure":true` accepts
//                                                     a self-signed certificate)
//   {"op":"wait","id":"a","until":"n.state === 'live'","ms":60000}
//                                                     polls the expression over n = window.naadf
//   {"op":"eval","id":"a","js":"return n.version"}     runs an async function body (n = window.naadf)
//   {"op":"click","id":"a","x":0.5,"y":0.5}           clicks the canvas at a fraction of its size
//   {"op":"select","id":"a","selector":"#tool","value":"sphere"}
//   {"op":"fill","id":"a","selector":"#radius","value":"3"}
//   {"op":"capture","id":"a","path":"f.png"}           writes the last frame as PNG
//   {"op":"reload","id":"a"}                         reloads the page
//   {"op":"close","id":"a"}
import { createInterface } from "node:readline";
import { writeFileSync } from "node:fs";
import { chromium } from "playwright-core";
import { FLAGS, executablePath } from "./chromium.mjs";


const browser = await chromium.launch({ executablePath, args: FLAGS });
const pages = new Map();

async function evaluate(page, body) {
  return page.evaluate(async (b) => {
    const n = window.naadf;
    const f = new Function("n", `return (async () => { ${b} })();`);
    const v = await f(n);
    return v === undefined ? null : JSON.parse(JSON.stringify(v, (_, x) => (typeof x === "bigint" ? String(x) : x)));
  }, body);
}

const commands = {
  async open({ id, url, insecure = false }) {
    const context = await browser.newContext({ viewport: { width: 640, height: 360 }, ignoreHTTPSErrors: insecure });
    const page = await context.newPage();
    page.on("console", (m) => process.stderr.write(`[${id}] ${m.type()}: ${m.text()}\n`));
    page.on("pageerror", (e) => process.stderr.write(`[${id}] error: ${e.message}\n`));
    await page.goto(url);
    pages.set(id, page);
  },
  async wait({ id, until, ms = 60000 }) {
    const page = pages.get(id);
    const end = Date.now() + ms;
    let last;
    while (Date.now() < end) {
      last = await evaluate(page, `return { state: JSON.parse(JSON.stringify(n ?? null)), ok: !!(n && (${until})) };`);
      if (last.ok) return last.state;
      await new Promise((r) => setTimeout(r, 20));
    }
    throw new Error(`${id}: not (${until}) after ${ms} ms; last state: ${JSON.stringify(last?.state)}`);
  },
  eval: ({ id, js }) => evaluate(pages.get(id), js),
  async click({ id, x, y }) {
    const page = pages.get(id);
    const box = await page.locator("#view").boundingBox();
    await page.mouse.click(box.x + x * box.width, box.y + y * box.height);
  },
  select: ({ id, selector, value }) => pages.get(id).selectOption(selector, value).then(() => null),
  async fill({ id, selector, value }) {
    const l = pages.get(id).locator(selector);
    await l.fill(value);
    await l.dispatchEvent("change");
  },
  async capture({ id, path }) {
    const url = await evaluate(pages.get(id), "return await n.capture()");
    writeFileSync(path, Buffer.from(url.slice(url.indexOf(",") + 1), "base64"));
  },
  reload: ({ id }) => pages.get(id).reload().then(() => null),
  async close({ id }) {
    await pages.get(id).context().close();
    pages.delete(id);
  },
};

for await (const line of createInterface({ input: process.stdin })) {
  if (!line.trim()) continue;
  let answer;
  try {
    const cmd = JSON.parse(line);
    const run = commands[cmd.op];
    if (!run) throw new Error(`unknown op ${cmd.op}`);
    answer = { ok: true, value: (await run(cmd)) ?? null };
  } catch (e) {
    answer = { ok: false, error: String(e?.message ?? e) };
  }
  process.stdout.write(JSON.stringify(answer) + "\n");
}
await browser.close();

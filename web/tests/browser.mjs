// Headless Chromium (Debian's, with WebGPU on SwiftShader) driven by playwright-core, for
// the page's tests and benchmarks (docs/WEB.md). Each scenario script prints one JSON line.
import { chromium } from "playwright-core";

/** Chromium's flags: WebGPU on, and nothing that reaches the network by itself. */
const FLAGS = [
  "--headless=new",
  "--no-sandbox",
  "--enable-unsafe-webgpu",
  "--disable-background-networking",
  "--disable-component-update",
  "--disable-sync",
  "--disable-quic",
  "--no-first-run",
];

/** Starts Chromium (`NAADF_CHROMIUM`, or /usr/bin/chromium). */
export async function launch() {
  return chromium.launch({
    executablePath: process.env.NAADF_CHROMIUM || "/usr/bin/chromium",
    args: FLAGS,
  });
}

/** Opens `url` in a new page; the page's console goes to stderr, prefixed with `tag`. */
export async function open(browser, url, tag = "page") {
  const page = await browser.newPage({ viewport: { width: 640, height: 360 } });
  page.on("console", (m) => process.stderr.write(`[${tag}] ${m.type()}: ${m.text()}\n`));
  page.on("pageerror", (e) => process.stderr.write(`[${tag}] error: ${e.message}\n`));
  await page.goto(url);
  return page;
}

/** `window.naadf` without its functions. */
export async function state(page) {
  return page.evaluate(() => {
    const n = window.naadf;
    return n && JSON.parse(JSON.stringify(n));
  });
}

/** Waits until `test(state)` holds, polling every 50 ms, for at most `ms`. */
export async function until(page, test, ms = 60000, what = "the page") {
  const end = Date.now() + ms;
  let last;
  while (Date.now() < end) {
    last = await state(page);
    if (last && test(last)) return last;
    await new Promise((r) => setTimeout(r, 50));
  }
  throw new Error(`${what} did not get there in ${ms} ms; last state: ${JSON.stringify(last)}`);
}

/** The page's last frame as PNG bytes. */
export async function capture(page) {
  const url = await page.evaluate(() => window.naadf.capture());
  return Buffer.from(url.slice(url.indexOf(",") + 1), "base64");
}

/** Runs `main` and prints its result as one JSON line; failures exit 1 with the message. */
export function run(main) {
  main().then(
    (out) => {
      process.stdout.write(JSON.stringify(out) + "\n");
      process.exit(0);
    },
    (e) => {
      process.stderr.write(`${e.stack || e}\n`);
      process.exit(1);
    },
  );
}

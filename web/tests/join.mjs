// node join.mjs URL PNG: opens the page at URL, waits until it is live on a quiescent world,
// writes its frame to PNG and prints its state.
import { writeFileSync } from "node:fs";
import { capture, launch, open, run, until } from "./browser.mjs";

run(async () => {
  const [url, png] = process.argv.slice(2);
  const browser = await launch();
  const page = await open(browser, url);
  const s = await until(page, (s) => s.state === "live" && s.quiescent && s.frameMs > 0);
  writeFileSync(png, await capture(page));
  await browser.close();
  return s;
});

// Writes build-inputs.sha256: the SHA-256 of every file the built page comes from (the
// service's .proto, the sources, the generated files, the lockfile) and of the built files
// in dist/, in `sha256sum` format. The Rust test `the_built_page_is_up_to_date` recomputes
// it, so a change that was not rebuilt (`npm run build`) fails the tests.
import { createHash } from "node:crypto";
import { readdirSync, readFileSync, statSync, writeFileSync } from "node:fs";
import { join, relative } from "node:path";

const web = new URL("..", import.meta.url).pathname;
const files = (dir) =>
  readdirSync(join(web, dir))
    .flatMap((name) => {
      const path = join(dir, name);
      return statSync(join(web, path)).isDirectory() ? files(path) : [path];
    });
const inputs = [
  "../proto/proto/naadf/v1/naadf.proto",
  "buf.gen.yaml",
  "index.html",
  "package.json",
  "package-lock.json",
  "tsconfig.json",
  "vite.config.ts",
  ...files("src"),
  ...files("dist"),
];
const lines = inputs
  .map((p) => relative(web, join(web, p)).split("\\").join("/"))
  .sort()
  .map((p) => `${createHash("sha256").update(readFileSync(join(web, p))).digest("hex")}  ${p}`);
writeFileSync(join(web, "build-inputs.sha256"), lines.join("\n") + "\n");

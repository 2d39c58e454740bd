// The page is built into dist/, which the Rust server embeds and serves (server/src/net/page.rs).
// The WGSL that the Rust client generates into src/gen/ is imported as text (`?raw`).
import { defineConfig } from "vite";

export default defineConfig({
  base: "/",
  build: {
    outDir: "dist",
    emptyOutDir: true,
    assetsDir: "assets",
    target: "es2022",
    // The server answers every file itself: keep them few and content-hashed.
    modulePreload: { polyfill: false },
    chunkSizeWarningLimit: 2048,
  },
});

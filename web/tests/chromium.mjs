// How the page's tests and benchmarks start Debian's Chromium: WebGPU on (SwiftShader
// without a GPU), and nothing that reaches the network by itself.
export const FLAGS = [
  "--headless=new",
  "--no-sandbox",
  "--enable-unsafe-webgpu",
  "--disable-background-networking",
  "--disable-component-update",
  "--disable-sync",
  "--disable-quic",
  "--no-first-run",
];

/** The browser to run: `NAADF_CHROMIUM`, or Debian's. */
export const executablePath = process.env.NAADF_CHROMIUM || "/usr/bin/chromium";

// The tone mapping of the native client (client/src/light/hdr.rs): radiance to sRGB bytes.

/** ACES filmic fit (Narkowicz 2015), clamped to [0, 1]. */
export const aces = (x: number) => Math.min(1, Math.max(0, (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)));

/** The sRGB transfer function of a linear value, as an 8-bit channel (clamped). */
export const srgb8 = (c: number) =>
  Math.min(255, Math.max(0, Math.floor((c <= 0.0031308 ? 12.92 * c : 1.055 * c ** (1 / 2.4) - 0.055) * 255 + 0.5)));

/** A frame of linear radiance, a vec4 per pixel, as sRGB(ACES(L · exposure)) bytes. With
 * `mean`, a pixel's fourth value counts the samples its first three sum. */
export function toneMapped(px: Float32Array, width: number, height: number, exposure: number, mean: boolean): ImageData {
  const rgba = new Uint8ClampedArray(width * height * 4);
  for (let i = 0; i < width * height; i++) {
    const n = mean ? px[4 * i + 3] || 1 : 1;
    for (let c = 0; c < 3; c++) rgba[4 * i + c] = srgb8(aces(Math.max(0, px[4 * i + c] / n) * exposure));
    rgba[4 * i + 3] = 255;
  }
  return new ImageData(rgba, width, height);
}

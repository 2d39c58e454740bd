// The tone mapping of the native client (client/src/light/hdr.rs): radiance to sRGB bytes.

/** ACES filmic fit (Narkowicz 2015), clamped to [0, 1]. */
export const aces = (x: number) => Math.min(1, Math.max(0, (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)));

/** The sRGB transfer function of a linear value, as an 8-bit channel (clamped). */
export const srgb8 = (c: number) =>
  Math.min(255, Math.max(0, Math.floor((c <= 0.0031308 ? 12.92 * c : 1.055 * c ** (1 / 2.4) - 0.055) * 255 + 0.5)));

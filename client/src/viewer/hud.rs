//! The heads-up display: a few lines of text and a colour swatch drawn into a frame's
//! RGBA pixels on the CPU, with the public-domain 8×8 glyphs of `font8x8`. The viewer
//! reads every frame back anyway (for presenting and screenshots), so text costs a few
//! thousand pixel writes and no extra pipeline.

use font8x8::legacy::BASIC_LEGACY;

/// Glyph pixels are drawn as `SCALE × SCALE` squares.
const SCALE: u32 = 2;
/// Glyph cell edge in frame pixels.
pub(crate) const CELL: u32 = 8 * SCALE;
/// Frame pixels that [`Canvas::text`] takes across for `text` (its height is [`CELL`]).
pub(crate) fn text_width(text: &str) -> u32 {
    text.chars().count() as u32 * CELL
}

/// Space around the text block.
const MARGIN: u32 = 6;

/// Draws `lines` in the top-left corner of a `width × height` RGBA frame over a darkened
/// panel, and, when given, a swatch of colour `swatch` after the last line.
///
/// ```
/// let (w, h) = (200, 60);
/// let mut rgba = vec![0u8; (w * h * 4) as usize];
/// naadf_client::viewer::draw_hud(&mut rgba, w, h, &["fps 60".to_string()], Some([255, 0, 0]));
/// assert!(rgba.chunks(4).any(|p| p[..3] == [255, 255, 255])); // text
/// assert!(rgba.chunks(4).any(|p| p[..3] == [255, 0, 0])); // swatch
/// ```
pub fn draw_hud(rgba: &mut [u8], width: u32, height: u32, lines: &[String], swatch: Option<[u8; 3]>) {
    let text_w = lines.iter().map(|l| text_width(l)).max().unwrap_or(0);
    let panel_w = (2 * MARGIN + text_w + 2 * CELL * u32::from(swatch.is_some())).min(width);
    let panel_h = (2 * MARGIN + lines.len() as u32 * (CELL + 2)).min(height);
    let mut canvas = Canvas { rgba, width, height };
    for y in 0..panel_h {
        for x in 0..panel_w {
            canvas.put(x, y, [0, 0, 0], true);
        }
    }
    let mut y0 = MARGIN;
    for line in lines {
        canvas.text(MARGIN, y0, line, [255; 3]);
        y0 += CELL + 2;
    }
    if let (Some(c), Some(last)) = (swatch, lines.last()) {
        let x0 = MARGIN + text_width(last) + CELL;
        let y0 = MARGIN + (lines.len() as u32 - 1) * (CELL + 2);
        canvas.fill(x0, y0, CELL, CELL, c);
    }
}

/// A frame's RGBA pixels to draw into; everything outside the frame is clipped.
pub(crate) struct Canvas<'a> {
    /// The pixels, row by row.
    pub rgba: &'a mut [u8],
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
}

impl Canvas<'_> {
    /// Sets pixel `(x, y)` to `c`, or, with `blend`, darkens it to a third and adds `c`.
    pub fn put(&mut self, x: u32, y: u32, c: [u8; 3], blend: bool) {
        if x < self.width && y < self.height {
            let i = ((y * self.width + x) * 4) as usize;
            if let Some(p) = self.rgba.get_mut(i..i + 4) {
                for (dst, src) in p.iter_mut().zip(c) {
                    *dst = if blend { (*dst / 3).saturating_add(src) } else { src };
                }
                p[3] = 255;
            }
        }
    }

    /// Fills the `w × h` rectangle at `(x0, y0)` with `c`.
    pub fn fill(&mut self, x0: u32, y0: u32, w: u32, h: u32, c: [u8; 3]) {
        for y in 0..h {
            for x in 0..w {
                self.put(x0 + x, y0 + y, c, false);
            }
        }
    }

    /// Writes `text` with its top-left corner at `(x0, y0)` in colour `c`.
    pub fn text(&mut self, x0: u32, y0: u32, text: &str, c: [u8; 3]) {
        for (i, ch) in text.chars().enumerate() {
            let glyph = BASIC_LEGACY.get(ch as usize).unwrap_or(&BASIC_LEGACY[b'?' as usize]);
            let x = x0 + i as u32 * CELL;
            for (gy, row) in glyph.iter().enumerate() {
                for gx in 0..8 {
                    if row >> gx & 1 != 0 {
                        self.fill(x + gx * SCALE, y0 + gy as u32 * SCALE, SCALE, SCALE, c);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_stays_inside_the_frame_and_the_rest_is_untouched() {
        let (w, h) = (40, 20);
        let mut rgba = vec![200u8; (w * h * 4) as usize];
        // Far more text than fits: must clip, not panic.
        draw_hud(
            &mut rgba,
            w,
            h,
            &["a long line of text".into(), "and more".into()],
            Some([1, 2, 3]),
        );
        assert_eq!(rgba.len(), (w * h * 4) as usize);
        let mut rgba = vec![200u8; 400 * 200 * 4];
        draw_hud(&mut rgba, 400, 200, &["x".into()], None);
        let untouched = |x: usize, y: usize| rgba[(y * 400 + x) * 4..][..4] == [200; 4];
        assert!(untouched(399, 199) && untouched(100, 5), "outside the panel");
        assert!(!untouched(2, 2), "the panel is darkened");
    }
}

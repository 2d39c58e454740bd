//! Radiance images: the linear output of the lit modes, written as PFM or OpenEXR, and
//! tone-mapped to the 8-bit frames every other output uses.

use crate::frame::Frame;
use std::io::Write;
use std::path::Path;

/// A linear-radiance image (RGB, rows from the top).
#[derive(Clone, Debug, PartialEq)]
pub struct Radiance {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// One RGB radiance per pixel, rows from the top.
    pub rgb: Vec<[f32; 3]>,
}

/// ACES filmic fit (Narkowicz 2015), the curve the shaders' `albedo` mode uses too.
fn aces(x: f32) -> f32 {
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

/// The sRGB transfer function of a value in [0, 1], as an 8-bit channel.
fn srgb8(c: f32) -> u8 {
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
}

impl Radiance {
    /// The PNG-ready frame: `sRGB(ACES(L · exposure))` per channel.
    ///
    /// ```
    /// use naadf_client::light::hdr::Radiance;
    /// let img = Radiance { width: 2, height: 1, rgb: vec![[0.0; 3], [1e9; 3]] };
    /// let f = img.tone_mapped(1.0);
    /// assert_eq!(&f.rgba[..4], &[0, 0, 0, 255]);
    /// assert_eq!(&f.rgba[4..], &[255, 255, 255, 255]);
    /// ```
    pub fn tone_mapped(&self, exposure: f32) -> Frame {
        let rgba = self
            .rgb
            .iter()
            .flat_map(|p| {
                let [r, g, b] = p.map(|c| srgb8(aces(c.max(0.0) * exposure)));
                [r, g, b, 255]
            })
            .collect();
        Frame {
            width: self.width,
            height: self.height,
            rgba,
            gbuffer: None,
        }
    }

    /// The image as a PFM file: `PF\nW H\n-1.0\n`, then little-endian `f32` RGB with the
    /// rows from the bottom of the image up.
    pub fn write_pfm(&self, out: &mut dyn Write) -> std::io::Result<()> {
        write!(out, "PF\n{} {}\n-1.0\n", self.width, self.height)?;
        let w = self.width as usize;
        let mut bytes = Vec::with_capacity(self.rgb.len() * 12);
        for row in self.rgb.chunks_exact(w.max(1)).rev() {
            bytes.extend(row.iter().flatten().flat_map(|c| c.to_le_bytes()));
        }
        out.write_all(&bytes)
    }

    /// Writes the image to `path`: OpenEXR when it ends in `.exr`, PFM otherwise.
    pub fn save(&self, path: &Path) -> Result<(), String> {
        let what = |e: &dyn std::fmt::Display| format!("cannot write {}: {e}", path.display());
        if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) {
            let data: Vec<f32> = self.rgb.iter().flatten().copied().collect();
            let img = image::Rgb32FImage::from_raw(self.width, self.height, data)
                .ok_or_else(|| what(&"image size and pixel count disagree"))?;
            return img
                .save_with_format(path, image::ImageFormat::OpenExr)
                .map_err(|e| what(&e));
        }
        let file = std::fs::File::create(path).map_err(|e| what(&e))?;
        let mut out = std::io::BufWriter::new(file);
        self.write_pfm(&mut out)
            .and_then(|()| out.flush())
            .map_err(|e| what(&e))
    }

    /// Mean radiance over the pixels `keep` accepts: per channel, and the standard error of
    /// the mean of the channels' average.
    pub fn mean_where(&self, keep: impl Fn(u32, u32) -> bool) -> Option<([f64; 3], f64)> {
        let w = self.width.max(1);
        let values: Vec<[f64; 3]> = self
            .rgb
            .iter()
            .enumerate()
            .filter(|(i, _)| keep(*i as u32 % w, *i as u32 / w))
            .map(|(_, p)| p.map(f64::from))
            .collect();
        let n = values.len() as f64;
        if values.is_empty() {
            return None;
        }
        let mean: [f64; 3] = std::array::from_fn(|c| values.iter().map(|v| v[c]).sum::<f64>() / n);
        let grey = (mean[0] + mean[1] + mean[2]) / 3.0;
        let var = values
            .iter()
            .map(|v| ((v[0] + v[1] + v[2]) / 3.0 - grey).powi(2))
            .sum::<f64>()
            / (n - 1.0).max(1.0);
        Some((mean, (var / n).sqrt()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pfm_rows_run_from_the_bottom() {
        let img = Radiance {
            width: 1,
            height: 2,
            rgb: vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]],
        };
        let mut out = Vec::new();
        img.write_pfm(&mut out).unwrap();
        let header = b"PF\n1 2\n-1.0\n";
        assert_eq!(&out[..header.len()], header);
        let floats: Vec<f32> = out[header.len()..]
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
            .collect();
        assert_eq!(floats, [4.0, 5.0, 6.0, 1.0, 2.0, 3.0]);
    }

    #[test]
    fn exr_files_hold_the_radiance() {
        let img = Radiance {
            width: 3,
            height: 2,
            rgb: (0..6)
                .map(|i| [i as f32 * 0.5, 1e3 + i as f32, 1e-3 * i as f32])
                .collect(),
        };
        let path = std::env::temp_dir().join(format!("naadf-hdr-{}.exr", std::process::id()));
        img.save(&path).unwrap();
        let back = image::open(&path).unwrap().into_rgb32f();
        let _ = std::fs::remove_file(&path);
        assert_eq!(back.dimensions(), (3, 2));
        let rgb: Vec<[f32; 3]> = back.pixels().map(|p| p.0).collect();
        assert_eq!(rgb, img.rgb, "rows from the top, f32 exactly");
        let missing = std::path::Path::new("/nonexistent-dir/x.pfm");
        assert!(
            img.save(missing)
                .unwrap_err()
                .contains("cannot write /nonexistent-dir/x.pfm")
        );
    }
}

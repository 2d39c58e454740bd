//! How close a rendered image is to a reference: the figures `naadf bench gi` reports.
//!
//! - FLIP (Andersson et al. 2020, NVIDIA's implementation through the `nv-flip` crate) on
//!   the tone-mapped 8-bit images, at its default 67 pixels per degree, pooled as the mean;
//! - the relative mean squared error of the radiance, `mean((t − r)² / (r² + 0.01))` over
//!   pixels and channels;
//! - the mean-luminance bias, `(L̄_test − L̄_ref) / L̄_ref` with Rec. 709 luminance.

use super::hdr::Radiance;

/// The differences of an image from its reference.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Quality {
    /// Mean FLIP error of the tone-mapped images (0 = identical, 1 = as different as can be).
    pub flip: f64,
    /// Relative mean squared error of the radiance.
    pub rel_mse: f64,
    /// Relative difference of the mean luminance.
    pub bias: f64,
}

fn luminance(c: &[f32; 3]) -> f64 {
    0.2126 * f64::from(c[0]) + 0.7152 * f64::from(c[1]) + 0.0722 * f64::from(c[2])
}

/// The mean Rec. 709 luminance of an image (0 for an empty one).
pub fn mean_luminance(img: &Radiance) -> f64 {
    img.rgb.iter().map(luminance).sum::<f64>() / img.rgb.len().max(1) as f64
}

/// The temporal flicker between two frames of the same view: the mean absolute difference
/// of their luminance, relative to the mean luminance of the first; `None` when their sizes
/// differ or the first is black.
///
/// ```
/// use naadf_client::light::{hdr::Radiance, quality::flicker};
/// let a = Radiance { width: 2, height: 1, rgb: vec![[1.0; 3], [1.0; 3]] };
/// let b = Radiance { rgb: vec![[1.5; 3], [0.5; 3]], ..a.clone() };
/// assert!((flicker(&a, &b).unwrap() - 0.5).abs() < 1e-9);
/// ```
pub fn flicker(a: &Radiance, b: &Radiance) -> Option<f64> {
    let mean = mean_luminance(a);
    if (a.width, a.height) != (b.width, b.height) || mean <= 0.0 {
        return None;
    }
    let diff: f64 = a
        .rgb
        .iter()
        .zip(&b.rgb)
        .map(|(x, y)| (luminance(x) - luminance(y)).abs())
        .sum();
    Some(diff / a.rgb.len() as f64 / mean)
}

impl Quality {
    /// Measures `test` against `reference`, both tone-mapped with `exposure` for FLIP;
    /// `None` when their sizes differ or they are empty.
    ///
    /// ```
    /// use naadf_client::light::{hdr::Radiance, quality::Quality};
    /// let a = Radiance { width: 8, height: 8, rgb: vec![[0.5, 0.4, 0.3]; 64] };
    /// let q = Quality::measure(&a, &a, 1.0).unwrap();
    /// assert_eq!((q.flip, q.rel_mse, q.bias), (0.0, 0.0, 0.0));
    /// let brighter = Radiance { rgb: vec![[1.0, 0.8, 0.6]; 64], ..a.clone() };
    /// let q = Quality::measure(&brighter, &a, 1.0).unwrap();
    /// assert!(q.flip > 0.0 && (q.bias - 1.0).abs() < 1e-6);
    /// ```
    pub fn measure(test: &Radiance, reference: &Radiance, exposure: f32) -> Option<Quality> {
        if (test.width, test.height) != (reference.width, reference.height) || test.rgb.is_empty() {
            return None;
        }
        let rgb8 = |img: &Radiance| {
            let frame = img.tone_mapped(exposure);
            let rgb: Vec<u8> = frame.rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
            nv_flip::FlipImageRgb8::with_data(img.width, img.height, &rgb)
        };
        let error = nv_flip::flip(rgb8(reference), rgb8(test), nv_flip::DEFAULT_PIXELS_PER_DEGREE);
        let flip = f64::from(nv_flip::FlipPool::from_image(&error).mean());
        let n = test.rgb.len() as f64;
        let rel_mse = test
            .rgb
            .iter()
            .zip(&reference.rgb)
            .map(|(t, r)| {
                (0..3)
                    .map(|c| f64::from(t[c] - r[c]).powi(2) / (f64::from(r[c]).powi(2) + 0.01))
                    .sum::<f64>()
            })
            .sum::<f64>()
            / (3.0 * n);
        let mean = |img: &Radiance| img.rgb.iter().map(luminance).sum::<f64>() / n;
        let (lt, lr) = (mean(test), mean(reference));
        let bias = if lr > 0.0 { (lt - lr) / lr } else { lt };
        Some(Quality { flip, rel_mse, bias })
    }
}

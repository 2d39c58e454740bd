//! The settings of `--mode irradiance` (`--irradiance-rays`), apart from the cache, so that
//! the lit options can hold them without the rest of the tier.

/// Rays per frame the cache may spend on refreshing its entries when none are given.
pub const DEFAULT_RAYS: u32 = 1 << 18;
/// The fewest rays per frame: one sample of one entry (two rays without the sun, four with).
pub const MIN_RAYS: u32 = 4;
/// The most rays per frame.
pub const MAX_RAYS: u32 = 1 << 26;

/// The settings of `--mode irradiance`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IrradianceOptions {
    /// Rays per frame spent on refreshing cache entries (`--irradiance-rays`).
    pub rays: u32,
}

impl Default for IrradianceOptions {
    fn default() -> Self {
        IrradianceOptions { rays: DEFAULT_RAYS }
    }
}

impl IrradianceOptions {
    /// Checks the ray budget: [`MIN_RAYS`] to [`MAX_RAYS`].
    ///
    /// ```
    /// use naadf_client::light::irradiance::IrradianceOptions;
    /// assert!(IrradianceOptions::default().check().is_ok());
    /// assert!(IrradianceOptions { rays: 2 }.check().is_err());
    /// ```
    pub fn check(&self) -> Result<(), String> {
        if !(MIN_RAYS..=MAX_RAYS).contains(&self.rays) {
            return Err(format!(
                "{} irradiance rays per frame: must lie in {MIN_RAYS}..={MAX_RAYS}",
                self.rays
            ));
        }
        Ok(())
    }

    /// Rays one sample of an entry costs: a cosine ray, and at its end a scattered ray;
    /// with the sun, a shadow ray at each of the two surfaces too.
    pub fn rays_per_sample(sun: bool) -> u32 {
        if sun { 4 } else { 2 }
    }

    /// Entry samples per frame the budget pays for.
    pub fn samples_per_frame(&self, sun: bool) -> u32 {
        (self.rays / Self::rays_per_sample(sun)).max(1)
    }
}

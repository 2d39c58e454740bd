//! The settings of `--mode roma` (`--roma-directions`, `--ao-range`), apart from the maps,
//! so that the lit options can hold them without the rest of ROMA.

/// The most candidate directions per axis of the concentric square (`--roma-directions`
/// is its square, at most 16: the maps of all levels then fit one 128 MiB binding).
pub const MAX_SIDE: u32 = 4;
/// Candidate directions when none are given.
pub const DEFAULT_DIRECTIONS: u32 = 16;
/// The AO range when none is given, in voxels.
pub const DEFAULT_AO_RANGE: f64 = 32.0;
/// The most AO range, in voxels: a ray reaches at most two levels' windows.
pub const MAX_AO_RANGE: f64 = 256.0;

/// The settings of `--mode roma`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RomaOptions {
    /// Candidate directions (a square: 1, 4, 9 or 16).
    pub directions: u32,
    /// How far ambient occlusion looks, in voxels.
    pub ao_range: f64,
}

impl Default for RomaOptions {
    fn default() -> Self {
        RomaOptions {
            directions: DEFAULT_DIRECTIONS,
            ao_range: DEFAULT_AO_RANGE,
        }
    }
}

impl RomaOptions {
    /// Checks the settings: a square number of directions up to [`MAX_SIDE`]², and an AO
    /// range in `(0, MAX_AO_RANGE]`.
    ///
    /// ```
    /// use naadf_client::light::roma::RomaOptions;
    /// assert!(RomaOptions { directions: 16, ao_range: 32.0 }.check().is_ok());
    /// assert!(RomaOptions { directions: 12, ao_range: 32.0 }.check().is_err());
    /// assert!(RomaOptions { directions: 4, ao_range: 0.0 }.check().is_err());
    /// ```
    pub fn check(&self) -> Result<(), String> {
        let side = self.side();
        if !(1..=MAX_SIDE).contains(&side) || side * side != self.directions {
            return Err(format!(
                "{} ROMA directions: give a square number from 1 to {}",
                self.directions,
                MAX_SIDE * MAX_SIDE
            ));
        }
        if !(self.ao_range > 0.0 && self.ao_range <= MAX_AO_RANGE) {
            return Err(format!(
                "AO range {}: must lie in (0, {MAX_AO_RANGE}] voxels",
                self.ao_range
            ));
        }
        Ok(())
    }

    /// Candidate directions per axis of the concentric square.
    pub fn side(&self) -> u32 {
        (f64::from(self.directions).sqrt().round()) as u32
    }

    /// Maps per level: the candidates and the sun's.
    pub fn maps(&self) -> usize {
        self.directions as usize + 1
    }
}

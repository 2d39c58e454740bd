//! World dimensions: whole chunk groups (multiples of 64 voxels), at most
//! 16384 × 4096 × 16384.

use crate::error::WorldError;
use std::fmt;

/// Voxels along a chunk-group edge; world sizes are multiples of it.
pub const GROUP_EDGE: u32 = 64;
/// Largest world, per axis.
pub const MAX_SIZE: [u32; 3] = [16384, 4096, 16384];

/// The size of a world in voxels. Always whole chunk groups.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct WorldSize {
    v: [u32; 3],
}

impl WorldSize {
    /// A validated size.
    ///
    /// ```
    /// use naadf_world::WorldSize;
    /// assert!(WorldSize::new(128, 64, 64).is_ok());
    /// assert!(WorldSize::new(100, 64, 64).is_err());
    /// ```
    pub fn new(x: u32, y: u32, z: u32) -> Result<Self, WorldError> {
        let v = [x, y, z];
        for a in 0..3 {
            if v[a] == 0 || !v[a].is_multiple_of(GROUP_EDGE) || v[a] > MAX_SIZE[a] {
                return Err(WorldError::InvalidSize(format!(
                    "{x}×{y}×{z}: each axis must be a positive multiple of {GROUP_EDGE}, at most {}×{}×{}",
                    MAX_SIZE[0], MAX_SIZE[1], MAX_SIZE[2]
                )));
            }
        }
        Ok(Self { v })
    }

    /// The smallest valid size that holds `x × y × z` voxels (each axis rounded up to 64).
    pub fn round_up(x: u32, y: u32, z: u32) -> Result<Self, WorldError> {
        let r = |n: u32| n.max(1).div_ceil(GROUP_EDGE) * GROUP_EDGE;
        Self::new(r(x), r(y), r(z))
    }

    /// Parses `X,Y,Z` (or `XxYxZ`).
    pub fn parse(s: &str) -> Result<Self, WorldError> {
        let parts: Vec<&str> = s.split([',', 'x', 'X']).map(str::trim).collect();
        let bad = || WorldError::InvalidSize(format!("'{s}': expected X,Y,Z"));
        if parts.len() != 3 {
            return Err(bad());
        }
        let n: Vec<u32> = parts
            .iter()
            .map(|p| p.parse::<u32>().map_err(|_| bad()))
            .collect::<Result<_, _>>()?;
        Self::new(n[0], n[1], n[2])
    }

    /// Size in voxels per axis.
    pub fn voxels(self) -> [u32; 3] {
        self.v
    }

    /// Size in chunks per axis.
    pub fn chunks(self) -> [u32; 3] {
        self.v.map(|n| n / 16)
    }

    /// Number of chunks.
    pub fn chunk_count(self) -> usize {
        self.chunks().iter().map(|&n| n as usize).product()
    }

    /// Number of voxels.
    pub fn voxel_count(self) -> u64 {
        self.v.iter().map(|&n| u64::from(n)).product()
    }

    /// Linear chunk index `x + y·Cx + z·Cx·Cy`.
    #[inline]
    pub fn chunk_index(self, c: [u32; 3]) -> usize {
        let n = self.chunks();
        c[0] as usize + n[0] as usize * (c[1] as usize + n[1] as usize * c[2] as usize)
    }

    /// Chunk coordinates of a linear chunk index.
    #[inline]
    pub fn chunk_coords(self, i: usize) -> [u32; 3] {
        let n = self.chunks().map(|v| v as usize);
        [
            (i % n[0]) as u32,
            ((i / n[0]) % n[1]) as u32,
            (i / (n[0] * n[1])) as u32,
        ]
    }

    /// Whether integer voxel coordinates lie inside the world.
    #[inline]
    pub fn contains(self, p: [i64; 3]) -> bool {
        (0..3).all(|a| p[a] >= 0 && p[a] < i64::from(self.v[a]))
    }
}

impl fmt::Display for WorldSize {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}×{}×{}", self.v[0], self.v[1], self.v[2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation() {
        assert!(WorldSize::new(16384, 4096, 16384).is_ok());
        assert!(WorldSize::new(16384 + 64, 64, 64).is_err());
        assert!(WorldSize::new(64, 4160, 64).is_err());
        assert!(WorldSize::new(0, 64, 64).is_err());
        assert_eq!(WorldSize::round_up(65, 1, 64).unwrap().voxels(), [128, 64, 64]);
        assert_eq!(WorldSize::parse("64,128,192").unwrap().voxels(), [64, 128, 192]);
        assert!(WorldSize::parse("64,128").is_err());
    }

    #[test]
    fn chunk_indexing_roundtrip() {
        let s = WorldSize::new(128, 64, 192).unwrap();
        for i in 0..s.chunk_count() {
            assert_eq!(s.chunk_index(s.chunk_coords(i)), i);
        }
    }
}

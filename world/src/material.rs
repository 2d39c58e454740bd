//! Materials: 15-bit ids mapped to 16-byte GPU entries (docs/FORMAT.md §5.4, docs/NAADF.md §3).
//!
//! Entry layout (four little-endian `u32` words of half floats):
//! - w0 = kind (bits 0–1) | layer 0 (bits 2–3) | half(roughness) << 16
//! - w1 = half(albedo.r) | half(albedo.g) << 16
//! - w2 = half(albedo.b) | half(emission) << 16
//! - w3 = 0 (the reference's unused layer colour)

use crate::cell::MAX_MATERIAL;
use crate::error::WorldError;
use half::f16;
use serde::{Deserialize, Serialize};

/// How a material scatters light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MaterialKind {
    /// Lambertian.
    Diffuse = 0,
    /// Diffuse albedo plus emitted radiance `albedo · emission`.
    Emissive = 1,
    /// Rough metal (GGX with `roughness`).
    Metal = 2,
    /// Perfect mirror.
    Mirror = 3,
}

impl MaterialKind {
    /// Parses `diffuse|emissive|metal|mirror`.
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "diffuse" => Self::Diffuse,
            "emissive" => Self::Emissive,
            "metal" => Self::Metal,
            "mirror" => Self::Mirror,
            _ => return None,
        })
    }

    fn from_bits(b: u32) -> Self {
        match b & 3 {
            0 => Self::Diffuse,
            1 => Self::Emissive,
            2 => Self::Metal,
            _ => Self::Mirror,
        }
    }
}

/// One material.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Scattering model.
    pub kind: MaterialKind,
    /// Linear albedo, 0..1 per channel.
    pub albedo: [f32; 3],
    /// Emission strength (emissive materials).
    pub emission: f32,
    /// GGX roughness (metals).
    pub roughness: f32,
}

impl Material {
    /// A diffuse material of linear albedo `rgb`.
    pub const fn diffuse(rgb: [f32; 3]) -> Self {
        Self {
            kind: MaterialKind::Diffuse,
            albedo: rgb,
            emission: 0.0,
            roughness: 0.0,
        }
    }

    /// The 16-byte GPU entry. Values are rounded to half precision.
    pub fn encode(&self) -> [u32; 4] {
        let h = |v: f32| u32::from(f16::from_f32(v).to_bits());
        [
            (self.kind as u32) | (h(self.roughness) << 16),
            h(self.albedo[0]) | (h(self.albedo[1]) << 16),
            h(self.albedo[2]) | (h(self.emission) << 16),
            0,
        ]
    }

    /// Decodes a GPU entry.
    pub fn decode(w: [u32; 4]) -> Self {
        let f = |bits: u32| f16::from_bits((bits & 0xFFFF) as u16).to_f32();
        Self {
            kind: MaterialKind::from_bits(w[0]),
            roughness: f(w[0] >> 16),
            albedo: [f(w[1]), f(w[1] >> 16), f(w[2])],
            emission: f(w[2] >> 16),
        }
    }

    /// Checks that every value is finite and in range.
    pub fn validate(&self) -> Result<(), WorldError> {
        let ok = self.albedo.iter().all(|c| c.is_finite() && (0.0..=1.0).contains(c))
            && self.emission.is_finite()
            && (0.0..=65504.0).contains(&self.emission)
            && self.roughness.is_finite()
            && (0.0..=1.0).contains(&self.roughness);
        if ok {
            Ok(())
        } else {
            Err(WorldError::InvalidMaterial(format!(
                "{self:?}: albedo and roughness must lie in 0..1 and emission in 0..65504"
            )))
        }
    }
}

/// The material table: dense ids `0..len`, id 0 the reserved "empty" entry.
///
/// Its GPU form is `len` entries of 16 bytes ([`MaterialTable::words`]).
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialTable {
    words: Vec<u32>,
}

impl Default for MaterialTable {
    fn default() -> Self {
        Self { words: vec![0; 4] }
    }
}

impl MaterialTable {
    /// A table with the given materials as ids 1, 2, ….
    pub fn from_materials(materials: &[Material]) -> Result<Self, WorldError> {
        let mut t = Self::default();
        for (i, m) in materials.iter().enumerate() {
            t.set(i as u16 + 1, *m)?;
        }
        Ok(t)
    }

    /// Rebuilds a table from its GPU words (a loaded file).
    pub fn from_words(words: Vec<u32>) -> Result<Self, WorldError> {
        if words.len() < 4 || !words.len().is_multiple_of(4) || words.len() / 4 > usize::from(MAX_MATERIAL) + 1 {
            return Err(WorldError::InvalidMaterial(format!(
                "material table of {} words",
                words.len()
            )));
        }
        if words[..4] != [0; 4] {
            return Err(WorldError::InvalidMaterial("entry 0 must be zero".into()));
        }
        Ok(Self { words })
    }

    /// Defines (or redefines) material `id`, growing the table with default grey
    /// diffuse entries if `id` is past the end.
    pub fn set(&mut self, id: u16, m: Material) -> Result<(), WorldError> {
        if id == 0 || id > MAX_MATERIAL {
            return Err(WorldError::InvalidMaterial(format!("id {id} outside 1..=32767")));
        }
        m.validate()?;
        let filler = Material::diffuse([0.5; 3]).encode();
        while self.len() <= usize::from(id) {
            self.words.extend_from_slice(&filler);
        }
        let at = usize::from(id) * 4;
        self.words[at..at + 4].copy_from_slice(&m.encode());
        Ok(())
    }

    /// Number of entries, including the empty entry 0.
    pub fn len(&self) -> usize {
        self.words.len() / 4
    }

    /// Whether only the empty entry exists.
    pub fn is_empty(&self) -> bool {
        self.len() <= 1
    }

    /// Whether `id` is a defined material (1..len).
    pub fn contains(&self, id: u16) -> bool {
        id != 0 && usize::from(id) < self.len()
    }

    /// Material `id`, if defined.
    pub fn get(&self, id: u16) -> Option<Material> {
        self.contains(id).then(|| {
            let at = usize::from(id) * 4;
            Material::decode(self.words[at..at + 4].try_into().expect("4 words"))
        })
    }

    /// The GPU buffer: four words per entry.
    pub fn words(&self) -> &[u32] {
        &self.words
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encode_decode_roundtrip() {
        let m = Material {
            kind: MaterialKind::Emissive,
            albedo: [1.0, 0.5, 0.25],
            emission: 8.0,
            roughness: 0.125,
        };
        assert_eq!(Material::decode(m.encode()), m);
        let e = m.encode();
        assert_eq!(e[0] & 3, 1);
        assert_eq!(e[3], 0);
    }

    #[test]
    fn table_rules() {
        let mut t = MaterialTable::default();
        assert!(t.is_empty());
        t.set(3, Material::diffuse([0.1, 0.2, 0.3])).unwrap();
        assert_eq!(t.len(), 4);
        assert!(t.contains(1) && t.contains(3) && !t.contains(4) && !t.contains(0));
        assert!(t.set(0, Material::diffuse([0.0; 3])).is_err());
        assert!(t.set(1, Material::diffuse([2.0, 0.0, 0.0])).is_err());
        assert!(MaterialTable::from_words(vec![1, 0, 0, 0]).is_err());
    }
}

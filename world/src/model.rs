//! Named voxel models that travel with a world (for `place` and entity types).

use crate::cell::MAX_MATERIAL;
use crate::error::WorldError;
use std::collections::BTreeMap;

/// Largest model edge, in voxels (entity grids pack sizes in 7 bits).
pub const MAX_MODEL_EDGE: u32 = 127;

/// A dense voxel model: material ids, x fastest, then y, then z (0 = empty).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Model {
    size: [u32; 3],
    voxels: Vec<u16>,
}

impl Model {
    /// A model of `size` with the given material ids.
    pub fn new(size: [u32; 3], voxels: Vec<u16>) -> Result<Self, WorldError> {
        if size.iter().any(|&n| n == 0 || n > MAX_MODEL_EDGE) {
            return Err(WorldError::InvalidSize(format!(
                "model {size:?}: each edge must be 1..={MAX_MODEL_EDGE}"
            )));
        }
        let n = size.iter().map(|&v| v as usize).product::<usize>();
        if voxels.len() != n {
            return Err(WorldError::InvalidSize(format!(
                "model {size:?} needs {n} voxels, got {}",
                voxels.len()
            )));
        }
        if let Some(m) = voxels.iter().find(|&&m| m > MAX_MATERIAL) {
            return Err(WorldError::InvalidMaterial(format!("model voxel material {m}")));
        }
        Ok(Self { size, voxels })
    }

    /// Size in voxels.
    pub fn size(&self) -> [u32; 3] {
        self.size
    }

    /// Material ids, x fastest.
    pub fn voxels(&self) -> &[u16] {
        &self.voxels
    }
}

/// Models by name, in name order (so their encoding is canonical).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ModelTable {
    models: BTreeMap<String, Model>,
}

impl ModelTable {
    /// Adds or replaces a model.
    pub fn insert(&mut self, name: String, model: Model) {
        self.models.insert(name, model);
    }

    /// The model called `name`.
    pub fn get(&self, name: &str) -> Option<&Model> {
        self.models.get(name)
    }

    /// Number of models.
    pub fn len(&self) -> usize {
        self.models.len()
    }

    /// Whether there are no models.
    pub fn is_empty(&self) -> bool {
        self.models.is_empty()
    }

    /// Canonical little-endian bytes, used by the world file and the digest: per model in
    /// name order, `u32` name length, UTF-8 name, three `u32` sizes, then `u16` voxels.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::new();
        for (name, m) in &self.models {
            out.extend_from_slice(&(name.len() as u32).to_le_bytes());
            out.extend_from_slice(name.as_bytes());
            for s in m.size {
                out.extend_from_slice(&s.to_le_bytes());
            }
            for v in &m.voxels {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        out
    }

    /// Inverse of [`ModelTable::encode`]; rejects malformed input with a clear error.
    pub fn decode(mut bytes: &[u8]) -> Result<Self, WorldError> {
        let bad = |what: &str| WorldError::BadFile(format!("model table: {what}"));
        let take = |n: usize, bytes: &mut &[u8]| -> Result<Vec<u8>, WorldError> {
            if bytes.len() < n {
                return Err(bad("truncated"));
            }
            let (a, b) = bytes.split_at(n);
            *bytes = b;
            Ok(a.to_vec())
        };
        let mut t = Self::default();
        while !bytes.is_empty() {
            let u32_at = |v: Vec<u8>| u32::from_le_bytes(v.try_into().expect("4 bytes"));
            let len = u32_at(take(4, &mut bytes)?) as usize;
            if len > 4096 {
                return Err(bad("name too long"));
            }
            let name = String::from_utf8(take(len, &mut bytes)?).map_err(|_| bad("name is not UTF-8"))?;
            let mut size = [0u32; 3];
            for s in &mut size {
                *s = u32_at(take(4, &mut bytes)?);
            }
            if size.iter().any(|&n| n == 0 || n > MAX_MODEL_EDGE) {
                return Err(bad("model size out of range"));
            }
            let n = size.iter().map(|&v| v as usize).product::<usize>();
            let raw = take(2 * n, &mut bytes)?;
            let voxels = raw.chunks_exact(2).map(|c| u16::from_le_bytes([c[0], c[1]])).collect();
            if t.models.contains_key(&name) {
                return Err(bad("duplicate model name"));
            }
            t.insert(name, Model::new(size, voxels)?);
        }
        Ok(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encode_decode_roundtrip() {
        let mut t = ModelTable::default();
        t.insert("b".into(), Model::new([1, 2, 1], vec![3, 0]).unwrap());
        t.insert("a".into(), Model::new([2, 1, 1], vec![1, 2]).unwrap());
        let bytes = t.encode();
        assert_eq!(ModelTable::decode(&bytes).unwrap(), t);
        assert!(ModelTable::decode(&bytes[..bytes.len() - 1]).is_err());
        assert!(Model::new([0, 1, 1], vec![]).is_err());
    }
}

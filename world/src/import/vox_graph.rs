//! MagicaVoxel scene graphs: packed rotations, integer transforms, and flattening the
//! `nTRN`/`nGRP`/`nSHP` graph at frame 0 into a list of placed models.
//!
//! Conventions (MagicaVoxel, as read by ogt_vox and vengi):
//! - `_r` is a row-major signed permutation matrix `R` packed in a byte: bits 0–1 the
//!   column of row 0's non-zero entry, bits 2–3 that of row 1 (row 2 takes the remaining
//!   column), bits 4/5/6 the signs of rows 0/1/2 (1 = negative). A point maps as `R·v`.
//! - `_t` is an integer translation `"x y z"`.
//! - A transform node maps its child's space into its parent's: `v ↦ R·v + t`; nested
//!   transforms compose as `parent ∘ child` (the parent's rotation also turns the child's
//!   translation).
//! - A model of size `s` sits in its shape's space with its pivot `floor(s/2)` at the
//!   origin; voxel `p` covers the unit cube whose centre is `p − floor(s/2) + ½`, and it
//!   lands on the voxel holding the transformed centre: `floor(R·(p − floor(s/2) + ½) + t)`
//!   `= R·(p − floor(s/2)) + t − [row i of R is negative]`.

use dot_vox::{DotVoxData, Frame, SceneNode};

/// Deepest scene-graph path accepted (MagicaVoxel graphs are a few levels deep; a cycle
/// would otherwise never end).
pub(crate) const MAX_GRAPH_DEPTH: u32 = 256;
/// Most scene-graph nodes that flattening may queue (a group that lists the same subtree
/// many times, nested, grows exponentially).
pub(crate) const MAX_NODE_VISITS: usize = 1 << 22;
/// Most placed models in one scene.
pub(crate) const MAX_INSTANCES: usize = 1 << 18;

/// A signed permutation matrix (MagicaVoxel's packed rotation): row `i` has its one
/// non-zero entry in column `col[i]`, equal to −1 when `neg[i]`, else +1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Rotation {
    /// Column of each row's non-zero entry.
    pub col: [u8; 3],
    /// Whether each row's entry is −1.
    pub neg: [bool; 3],
}

impl Rotation {
    /// The identity (packed byte 4).
    pub const IDENTITY: Self = Self {
        col: [0, 1, 2],
        neg: [false; 3],
    };

    /// Decodes a packed rotation byte; `None` if the two stored columns are equal or 3.
    /// Bit 7 is unused and ignored.
    pub fn from_byte(b: u8) -> Option<Self> {
        let c0 = b & 3;
        let c1 = (b >> 2) & 3;
        if c0 > 2 || c1 > 2 || c0 == c1 {
            return None;
        }
        Some(Self {
            col: [c0, c1, 3 - c0 - c1],
            neg: [b >> 4 & 1 == 1, b >> 5 & 1 == 1, b >> 6 & 1 == 1],
        })
    }

    /// `R·v`.
    pub fn apply(self, v: [i64; 3]) -> [i64; 3] {
        std::array::from_fn(|i| {
            let x = v[usize::from(self.col[i])];
            if self.neg[i] { -x } else { x }
        })
    }

    /// The product `self · inner` (apply `inner` first).
    pub fn compose(self, inner: Rotation) -> Rotation {
        Rotation {
            col: std::array::from_fn(|i| inner.col[usize::from(self.col[i])]),
            neg: std::array::from_fn(|i| self.neg[i] ^ inner.neg[usize::from(self.col[i])]),
        }
    }
}

/// An integer rigid transform `v ↦ rot·v + t` in MagicaVoxel (z-up) axes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Transform {
    /// Rotation (signed permutation).
    pub rot: Rotation,
    /// Translation.
    pub t: [i64; 3],
}

impl Transform {
    /// The identity.
    pub const IDENTITY: Self = Self {
        rot: Rotation::IDENTITY,
        t: [0; 3],
    };

    /// `self ∘ child`: the child's space mapped through `self`.
    pub fn compose(self, child: Transform) -> Transform {
        let t = self.rot.apply(child.t);
        Transform {
            rot: self.rot.compose(child.rot),
            t: std::array::from_fn(|i| t[i] + self.t[i]),
        }
    }
}

/// One model placed by the scene graph.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Placement {
    /// Index into `DotVoxData::models`.
    pub model: usize,
    /// The accumulated transform, or `None` for a file without a scene graph (the model's
    /// voxel `p` lies at `p`, not centred).
    pub transform: Option<Transform>,
}

/// The frame index `_f` of a frame or shape-model dictionary (absent or malformed: 0).
fn frame_index(d: &dot_vox::Dict) -> u32 {
    d.get("_f").and_then(|s| s.trim().parse::<u32>().ok()).unwrap_or(0)
}

/// Whether a node's attributes mark it hidden.
fn hidden(d: &dot_vox::Dict) -> bool {
    d.get("_hidden").is_some_and(|v| v.trim() == "1")
}

/// Parses `_t` (`"x y z"`, 32-bit integers).
fn parse_translation(s: &str) -> Option<[i64; 3]> {
    let mut it = s.split_whitespace().map(|p| p.parse::<i32>().ok());
    let v = [it.next()??, it.next()??, it.next()??];
    it.next().is_none().then(|| v.map(i64::from))
}

/// The transform of a frame: `_t` and `_r`, each optional.
pub(crate) fn frame_transform(frame: &Frame, node: u32) -> Result<Transform, String> {
    let mut xf = Transform::IDENTITY;
    if let Some(t) = frame.attributes.get("_t") {
        xf.t = parse_translation(t).ok_or_else(|| format!("transform node {node}: bad translation _t = {t:?}"))?;
    }
    if let Some(r) = frame.attributes.get("_r") {
        xf.rot = r
            .trim()
            .parse::<u8>()
            .ok()
            .and_then(Rotation::from_byte)
            .ok_or_else(|| format!("transform node {node}: invalid rotation _r = {r:?}"))?;
    }
    Ok(xf)
}

/// Flattens the scene graph of `data` at frame 0, depth first from node 0, children in
/// the order listed. Hidden nodes (`_hidden = 1`) and nodes on hidden layers are skipped
/// with their subtrees. A file without a scene graph places every model at the origin,
/// in file order.
///
/// Node `k` is the `k`-th scene chunk in the file (how MagicaVoxel numbers them; dot_vox
/// keeps no node ids).
pub(crate) fn flatten(data: &DotVoxData) -> Result<Vec<Placement>, String> {
    if data.scenes.is_empty() {
        return Ok((0..data.models.len())
            .map(|model| Placement { model, transform: None })
            .collect());
    }
    let n = data.scenes.len();
    let layer_hidden = |id: u32| data.layers.get(id as usize).is_some_and(|l| hidden(&l.attributes));
    let mut out = Vec::new();
    let mut stack: Vec<(u32, Transform, u32)> = vec![(0, Transform::IDENTITY, 0)];
    let mut queued = 1usize;
    let mut push = |stack: &mut Vec<(u32, Transform, u32)>,
                    from: u32,
                    node: u32,
                    xf: Transform,
                    depth: u32|
     -> Result<(), String> {
        if node as usize >= n {
            return Err(format!(
                "scene node {from} refers to node {node}, but the file has only {n} nodes"
            ));
        }
        if depth > MAX_GRAPH_DEPTH {
            return Err(format!(
                "scene graph deeper than {MAX_GRAPH_DEPTH} levels (is it cyclic?)"
            ));
        }
        queued += 1;
        if queued > MAX_NODE_VISITS {
            return Err(format!("scene graph expands to more than {MAX_NODE_VISITS} nodes"));
        }
        stack.push((node, xf, depth));
        Ok(())
    };
    while let Some((id, xf, depth)) = stack.pop() {
        match &data.scenes[id as usize] {
            SceneNode::Transform {
                attributes,
                frames,
                child,
                layer_id,
            } => {
                if hidden(attributes) || layer_hidden(*layer_id) {
                    continue;
                }
                let local = match frames.iter().min_by_key(|f| frame_index(&f.attributes)) {
                    Some(f) => frame_transform(f, id)?,
                    None => Transform::IDENTITY,
                };
                push(&mut stack, id, *child, xf.compose(local), depth + 1)?;
            }
            SceneNode::Group { attributes, children } => {
                if hidden(attributes) {
                    continue;
                }
                for &c in children.iter().rev() {
                    push(&mut stack, id, c, xf, depth + 1)?;
                }
            }
            SceneNode::Shape { attributes, models } => {
                if hidden(attributes) {
                    continue;
                }
                let Some(m) = models.iter().min_by_key(|m| frame_index(&m.attributes)) else {
                    continue;
                };
                let model = m.model_id as usize;
                if model >= data.models.len() {
                    return Err(format!(
                        "shape node {id} refers to model {}, but the file has only {} models",
                        m.model_id,
                        data.models.len()
                    ));
                }
                if out.len() >= MAX_INSTANCES {
                    return Err(format!("the scene places more than {MAX_INSTANCES} models"));
                }
                out.push(Placement {
                    model,
                    transform: Some(xf),
                });
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 48 valid rotation bytes.
    fn valid_bytes() -> Vec<u8> {
        (0..128u8).filter(|&b| Rotation::from_byte(b).is_some()).collect()
    }

    /// `R` as a row-major matrix from dot_vox's own decoding (column-major arrays).
    fn dot_vox_matrix(b: u8) -> [[i64; 3]; 3] {
        let cols = dot_vox::Rotation::from_byte(b).to_cols_array_2d();
        std::array::from_fn(|r| std::array::from_fn(|c| cols[c][r] as i64))
    }

    fn mat_vec(m: [[i64; 3]; 3], v: [i64; 3]) -> [i64; 3] {
        std::array::from_fn(|r| (0..3).map(|c| m[r][c] * v[c]).sum())
    }

    #[test]
    fn rotation_byte_decoding() {
        assert_eq!(valid_bytes().len(), 48);
        assert_eq!(Rotation::from_byte(4), Some(Rotation::IDENTITY));
        // The spec's example: R = [[0,1,0],[0,0,-1],[-1,0,0]].
        let r = Rotation::from_byte(1 | 2 << 2 | 1 << 5 | 1 << 6).unwrap();
        assert_eq!(r.apply([1, 0, 0]), [0, 0, -1]);
        assert_eq!(r.apply([0, 1, 0]), [1, 0, 0]);
        assert_eq!(r.apply([0, 0, 1]), [0, -1, 0]);
        assert_eq!(r.apply([2, 3, 5]), [3, -5, -2]);
        // Invalid: equal columns, or column 3.
        for b in [0u8, 5, 10, 3, 12, 15, 0x70] {
            assert!(Rotation::from_byte(b).is_none(), "{b}");
        }
        // Bit 7 is ignored.
        assert_eq!(Rotation::from_byte(4 | 0x80), Some(Rotation::IDENTITY));
    }

    #[test]
    fn rotation_matches_dot_vox_for_every_byte() {
        let probes = [[1, 0, 0], [0, 1, 0], [0, 0, 1], [3, -7, 11]];
        for b in valid_bytes() {
            let r = Rotation::from_byte(b).unwrap();
            let m = dot_vox_matrix(b);
            for v in probes {
                assert_eq!(r.apply(v), mat_vec(m, v), "byte {b}, v {v:?}");
            }
        }
    }

    #[test]
    fn composition_is_the_matrix_product() {
        let v = [2, -3, 5];
        for a in valid_bytes() {
            for b in valid_bytes() {
                let (ra, rb) = (Rotation::from_byte(a).unwrap(), Rotation::from_byte(b).unwrap());
                assert_eq!(ra.compose(rb).apply(v), ra.apply(rb.apply(v)));
            }
        }
        // Transforms: the parent's rotation turns the child's translation.
        let parent = Transform {
            rot: Rotation::from_byte(1 | 1 << 4).unwrap(), // x' = -y, y' = x
            t: [10, 20, 30],
        };
        let child = Transform {
            rot: Rotation::IDENTITY,
            t: [1, 2, 3],
        };
        let c = parent.compose(child);
        assert_eq!(c.t, [10 - 2, 20 + 1, 30 + 3]);
        assert_eq!(c.rot, parent.rot);
    }

    #[test]
    fn translation_parsing() {
        assert_eq!(parse_translation("1 -2 3"), Some([1, -2, 3]));
        assert_eq!(parse_translation("  4   5 6 "), Some([4, 5, 6]));
        assert_eq!(parse_translation("1 2"), None);
        assert_eq!(parse_translation("1 2 3 4"), None);
        assert_eq!(parse_translation("1 x 3"), None);
        assert_eq!(parse_translation("99999999999 0 0"), None);
    }
}

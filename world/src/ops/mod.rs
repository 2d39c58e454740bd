//! Edit operations (docs/OPS.md): the ops JSON, its validation, and its resolution into voxel
//! writes on a [`Canvas`].
//!
//! One ops-JSON line is one [`Batch`]: a single op object, or `{"batch":[op,...]}`. The world
//! layer applies a batch to a copy-on-write view of its voxels (a [`Canvas`]) and to working
//! copies of its tables with [`apply_batch`]; any error rejects the whole batch.
//!
//! ```
//! use naadf_world::ops::{apply_batch, Batch, Canvas, DenseCanvas, Limits};
//! use naadf_world::model::ModelTable;
//! use naadf_world::{MaterialTable, WorldSize};
//!
//! let line = r#"{"batch":[
//!     {"op":"define_material","id":1,"kind":"diffuse","albedo":[0.8,0.2,0.2]},
//!     {"op":"box","min":[0,0,0],"max":[4,1,4],"material":1},
//!     {"op":"sphere","center":[2,0,2],"radius":1.5,"material":0}]}"#;
//! let batch = Batch::parse_line(&line.replace('\n', "")).unwrap();
//! let mut canvas = DenseCanvas::new(WorldSize::new(64, 64, 64).unwrap());
//! let (mut materials, mut models) = (MaterialTable::default(), ModelTable::default());
//! apply_batch(&batch, &mut canvas, &mut materials, &mut models, &Limits::default()).unwrap();
//! assert_eq!(canvas.get([0, 0, 0]), 1);
//! assert_eq!(canvas.get([2, 0, 2]), 0);
//! assert_eq!(Batch::parse_line(&batch.to_json_line()).unwrap(), batch);
//! ```

mod apply;
mod dense;

pub use apply::{MAX_MODEL_NAME, apply_batch};

/// Most characters of a client-supplied string (an op, model or field name, a value) that
/// an error message quotes; longer ones are cut with [`clip_input`]. An error travels back to the
/// client in gRPC metadata and into logs, so it must stay small whatever the input.
pub const MAX_QUOTED_CHARS: usize = 64;

/// Most characters of a parse error message (serde's, with every quoted input clipped):
/// a bound for the rare input that defeats the quoting, e.g. a name holding a backtick.
const MAX_PARSE_MESSAGE_CHARS: usize = 512;

/// A client-supplied string as an error message may quote it: unchanged when it has at most
/// `max` characters, else its first `max` characters, an ellipsis and its length in bytes.
///
/// ```
/// use naadf_world::ops::clip_input;
/// assert_eq!(clip_input("tree", 64), "tree");
/// assert_eq!(clip_input(&"x".repeat(100), 3), "xxx… (100 bytes)");
/// ```
pub fn clip_input(s: &str, max: usize) -> String {
    match s.char_indices().nth(max) {
        None => s.to_owned(),
        Some((cut, _)) => format!("{}… ({} bytes)", &s[..cut], s.len()),
    }
}

/// A serde message with every `` `quoted` `` or `"quoted"` part clipped to
/// [`MAX_QUOTED_CHARS`] (serde quotes the unknown variant or field, or the string of a
/// wrong type, verbatim), and the whole clipped to [`MAX_PARSE_MESSAGE_CHARS`].
fn clip_quoted(msg: &str) -> String {
    let mut out = String::new();
    let mut rest = msg;
    while let Some(open) = rest.find(['`', '"']) {
        let delim = &rest[open..=open];
        out.push_str(&rest[..=open]);
        let inner = &rest[open + 1..];
        let (quoted, tail) = match inner.find(delim) {
            Some(close) => (&inner[..close], &inner[close..]),
            None => (inner, ""),
        };
        out.push_str(&clip_input(quoted, MAX_QUOTED_CHARS));
        rest = tail;
        if let Some(after) = rest.strip_prefix(delim) {
            out.push_str(delim);
            rest = after;
        }
    }
    out.push_str(rest);
    clip_input(&out, MAX_PARSE_MESSAGE_CHARS)
}

/// A parse error of the op at `index` (named `name` in the JSON, if it has a name), with
/// serde's message `e`; every client string in it clipped.
fn op_parse_error(index: usize, name: Option<&str>, e: &impl std::fmt::Display) -> EditError {
    let name = name.map_or_else(|| "?".to_owned(), |n| clip_input(n, MAX_QUOTED_CHARS));
    EditError::Parse(format!("op {index} ({name}): {}", clip_quoted(&e.to_string())))
}
pub use dense::DenseCanvas;

use crate::material::MaterialKind;
use crate::size::WorldSize;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// One edit operation, exactly as in docs/OPS.md. Material 0 erases.
///
/// Serde form: an object internally tagged by `"op"` with the snake_case variant name;
/// unknown ops and unknown fields are rejected.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "op", rename_all = "snake_case", deny_unknown_fields)]
pub enum Op {
    /// `{"op":"set","voxels":[[x,y,z,m],...]}`: single voxels; every coordinate must lie
    /// inside the world; later entries win.
    Set {
        /// `[x, y, z, material]` entries.
        voxels: Vec<[i64; 4]>,
    },
    /// `{"op":"box","min":[x,y,z],"max":[x,y,z],"material":m}`: fills `[min, max)`, clipped.
    Box {
        /// Inclusive lower corner.
        min: [i64; 3],
        /// Exclusive upper corner.
        max: [i64; 3],
        /// Material to write (0 erases).
        material: u16,
    },
    /// `{"op":"sphere","center":[x,y,z],"radius":r,"material":m}`: voxel `(x,y,z)` is inside
    /// iff `(x+0.5−cx)² + (y+0.5−cy)² + (z+0.5−cz)² < r²` (f64), clipped.
    Sphere {
        /// Centre, in voxel units (voxel `(x,y,z)` spans `[x, x+1)` per axis).
        center: [f64; 3],
        /// Radius in voxels.
        radius: f64,
        /// Material to write (0 erases).
        material: u16,
    },
    /// `{"op":"paint","center":[x,y,z],"radius":r,"material":m}`: the sphere test, but only
    /// solid voxels are retyped; material 0 is an error.
    Paint {
        /// Centre, as for [`Op::Sphere`].
        center: [f64; 3],
        /// Radius in voxels.
        radius: f64,
        /// New material of the solid voxels inside (not 0).
        material: u16,
    },
    /// `{"op":"flood_paint","start":[x,y,z],"material":m,"limit":n}`: retypes the 6-connected
    /// voxels of the start voxel's material; an error if more than `limit` would change.
    FloodPaint {
        /// A solid voxel inside the world.
        start: [i64; 3],
        /// New material (0 erases the region).
        material: u16,
        /// Most voxels the op may paint.
        limit: u64,
    },
    /// `{"op":"copy","min":[..],"max":[..],"to":[x,y,z]}`: copies the box `[min, max)`
    /// (empties included) so that `min` lands on `to`; the whole source is read first.
    Copy {
        /// Inclusive lower source corner.
        min: [i64; 3],
        /// Exclusive upper source corner.
        max: [i64; 3],
        /// Where `min` lands.
        to: [i64; 3],
    },
    /// `{"op":"place","model":"NAME","at":[x,y,z]}`: the solid voxels of a stored model, its
    /// voxel `(0,0,0)` at `at`, clipped.
    Place {
        /// Model name.
        model: String,
        /// World position of the model's voxel `(0,0,0)`.
        at: [i64; 3],
    },
    /// `{"op":"spawn_entity","id":n,"model":"NAME","pos":[x,y,z],"rot":[x,y,z,w]}`.
    SpawnEntity {
        /// Entity id.
        id: u32,
        /// Model name.
        model: String,
        /// World position of the model's local-origin corner.
        pos: [f64; 3],
        /// Rotation quaternion `[x, y, z, w]` (any non-zero length).
        rot: [f64; 4],
    },
    /// `{"op":"move_entity","id":n,"pos":[..],"rot":[..]}`.
    MoveEntity {
        /// Entity id.
        id: u32,
        /// New position of the local-origin corner.
        pos: [f64; 3],
        /// New rotation quaternion `[x, y, z, w]`.
        rot: [f64; 4],
    },
    /// `{"op":"despawn_entity","id":n}`.
    DespawnEntity {
        /// Entity id.
        id: u32,
    },
    /// `{"op":"define_material","id":n,"kind":"diffuse|emissive|metal|mirror","albedo":[r,g,b],"emission":e,"roughness":r}`.
    DefineMaterial {
        /// Material id, 1..=32767.
        id: u16,
        /// Scattering model.
        kind: MaterialKind,
        /// Linear albedo, 0..1 per channel.
        #[serde(deserialize_with = "finite_f32s")]
        albedo: [f32; 3],
        /// Emission strength (default 0).
        #[serde(default, deserialize_with = "finite_f32")]
        emission: f32,
        /// GGX roughness (default 0).
        #[serde(default, deserialize_with = "finite_f32")]
        roughness: f32,
    },
    /// `{"op":"define_model","name":"NAME","size":[x,y,z],"voxels":[[x,y,z,m],...]}`.
    DefineModel {
        /// Model name (1..=64 bytes).
        name: String,
        /// Size in voxels, each edge 1..=127.
        size: [u32; 3],
        /// Solid voxels `[x, y, z, material]` inside the size; the rest is empty.
        voxels: Vec<[i64; 4]>,
    },
}

/// One request = one batch = one version.
#[derive(Clone, Debug, PartialEq)]
pub struct Batch {
    /// The ops, applied in order.
    pub ops: Vec<Op>,
}

/// The `{"batch":[...]}` line form. `user` and `version` are informational (`naadf
/// export-log` writes them: who sent the batch and the version it made); applying ignores
/// them.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BatchLine {
    batch: Vec<Op>,
    #[serde(default, rename = "user")]
    _user: Option<String>,
    #[serde(default, rename = "version")]
    _version: Option<u64>,
}

/// The `{"batch":[...]}` line form, for writing.
#[derive(Serialize)]
struct BatchLineRef<'a> {
    batch: &'a [Op],
}

impl Batch {
    /// Fails with a `Limit` error if the batch holds more than `limits.max_ops` ops, and
    /// with an `Invalid` one if an op names a model by more than [`MAX_MODEL_NAME`] bytes
    /// (a fixed limit of the format, whatever `limits` say).
    pub fn check_size(&self, limits: &Limits) -> Result<(), EditError> {
        self.check_names()?;
        if self.ops.len() <= limits.max_ops {
            return Ok(());
        }
        let index = limits.max_ops;
        Err(EditError::Limit {
            index,
            op: self.ops[index].name(),
            reason: format!(
                "a batch holds at most {} ops, this one {}",
                limits.max_ops,
                self.ops.len()
            ),
        })
    }

    /// Fails with an `Invalid` error at the first op that names a model by more than
    /// [`MAX_MODEL_NAME`] bytes.
    pub fn check_names(&self) -> Result<(), EditError> {
        self.ops
            .iter()
            .enumerate()
            .try_for_each(|(i, op)| op.check_model_name(i))
    }

    /// Parses one ops-JSON line: a single op object, or `{"batch":[op,...]}`, and checks
    /// its model names ([`Batch::check_names`]).
    ///
    /// Errors are [`EditError::Parse`] with serde's message, prefixed by the op's index and
    /// name where they are known; client strings quoted in them are clipped ([`clip_input`]).
    pub fn parse_line(line: &str) -> Result<Batch, EditError> {
        let batch = Self::parse_ops(line)?;
        batch.check_names()?;
        Ok(batch)
    }

    /// [`Batch::parse_line`] without the name check.
    fn parse_ops(line: &str) -> Result<Batch, EditError> {
        let line = line.trim();
        if line.is_empty() {
            return Err(EditError::Parse(
                "empty line: expected an op object or {\"batch\":[...]}".into(),
            ));
        }
        if first_key(line).as_deref() == Some("batch") {
            match serde_json::from_str::<BatchLine>(line) {
                Ok(b) => Ok(Batch { ops: b.batch }),
                Err(e) => Err(explain_batch_error(line, e)),
            }
        } else {
            match serde_json::from_str::<Op>(line) {
                Ok(op) => Ok(Batch { ops: vec![op] }),
                Err(e) => {
                    let name = serde_json::from_str::<serde_json::Value>(line)
                        .ok()
                        .and_then(|v| v.get("op").and_then(|n| n.as_str()).map(str::to_owned));
                    Err(match name {
                        Some(name) => op_parse_error(0, Some(&name), &e),
                        None => EditError::Parse(clip_quoted(&e.to_string())),
                    })
                }
            }
        }
    }

    /// Canonical compact JSON: a single op object when there is one op, else
    /// `{"batch":[...]}`. `parse_line(to_json_line(b)) == b` for every batch of finite values.
    pub fn to_json_line(&self) -> String {
        let r = if self.ops.len() == 1 {
            serde_json::to_string(&self.ops[0])
        } else {
            serde_json::to_string(&BatchLineRef { batch: &self.ops })
        };
        r.expect("ops serialize to JSON")
    }

    /// Whether the batch contains entity ops (spawn, move, despawn).
    pub fn has_entity_ops(&self) -> bool {
        self.ops.iter().any(Op::is_entity_op)
    }
}

/// An `f32` field: a JSON number that fits. serde narrows a larger number to infinity,
/// which the canonical line would then write as `null`, so it is refused here, as an
/// integer field refuses a number outside its type.
fn finite_f32<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f32, D::Error> {
    let v = <f64 as serde::Deserialize>::deserialize(d)?;
    let narrowed = v as f32;
    if narrowed.is_finite() {
        Ok(narrowed)
    } else {
        Err(serde::de::Error::custom(format!("{v} does not fit a 32-bit float")))
    }
}

/// Three [`finite_f32`] numbers.
fn finite_f32s<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[f32; 3], D::Error> {
    let v = <[f64; 3] as serde::Deserialize>::deserialize(d)?;
    let mut out = [0.0; 3];
    for (o, x) in out.iter_mut().zip(v) {
        *o = x as f32;
        if !o.is_finite() {
            return Err(serde::de::Error::custom(format!("{x} does not fit a 32-bit float")));
        }
    }
    Ok(out)
}

/// The first key of a JSON object line, if the line starts like one.
fn first_key(line: &str) -> Option<String> {
    let rest = line.strip_prefix('{')?.trim_start();
    if !rest.starts_with('"') {
        return None;
    }
    let bytes = rest.as_bytes();
    let mut i = 1;
    while i < bytes.len() {
        match bytes[i] {
            b'\\' => i += 2,
            b'"' => return serde_json::from_str(&rest[..=i]).ok(),
            _ => i += 1,
        }
    }
    None
}

/// Turns a batch-level serde error into one that names the failing op, where possible.
fn explain_batch_error(line: &str, e: serde_json::Error) -> EditError {
    if let Ok(serde_json::Value::Object(obj)) = serde_json::from_str::<serde_json::Value>(line)
        && let Some(serde_json::Value::Array(items)) = obj.get("batch")
    {
        for (i, item) in items.iter().enumerate() {
            if let Err(item_err) = Op::deserialize(item) {
                return op_parse_error(i, item.get("op").and_then(|n| n.as_str()), &item_err);
            }
        }
    }
    EditError::Parse(format!("batch: {}", clip_quoted(&e.to_string())))
}

/// Limits that keep one request bounded.
#[derive(Clone, Debug)]
pub struct Limits {
    /// Most ops in one batch (default 4096).
    pub max_ops: usize,
    /// Most entries in one `set` (default 2²⁰).
    pub max_set_voxels: usize,
    /// Most voxels one box, sphere, paint, copy or place may cover after clipping to the
    /// world (spheres and paints: their clipped bounding box) (default 2²⁷).
    pub max_fill_volume: u64,
    /// Largest `limit` a `flood_paint` may ask for (default 2²⁴).
    pub max_flood_limit: u64,
    /// Most voxels of one `define_model`: its volume and its entry count (default 127³).
    pub max_model_voxels: u64,
}

impl Limits {
    /// No limits beyond what the world itself allows: for re-applying batches that a
    /// server already accepted (log replay, mirrors), whatever limits it was configured with.
    pub fn unbounded() -> Self {
        Self {
            max_ops: usize::MAX,
            max_set_voxels: usize::MAX,
            max_fill_volume: u64::MAX,
            max_flood_limit: u64::MAX,
            max_model_voxels: u64::MAX,
        }
    }
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_ops: 4096,
            max_set_voxels: 1 << 20,
            max_fill_volume: 1 << 27,
            max_flood_limit: 1 << 24,
            max_model_voxels: 127 * 127 * 127,
        }
    }
}

/// What the ops write into and read from: the world's voxels seen through a batch overlay.
///
/// Coordinates passed to `get` and `set` always lie inside [`Canvas::size`].
pub trait Canvas {
    /// The world size.
    fn size(&self) -> WorldSize;
    /// The material at `p` (0 = empty), including earlier writes of the batch.
    fn get(&self, p: [u32; 3]) -> u16;
    /// Writes material `material` (0 = empty) at `p`.
    fn set(&mut self, p: [u32; 3], material: u16);
}

/// Errors of edits; every message says which op (index in the batch and op name) and what
/// is wrong.
#[derive(Debug, Error)]
pub enum EditError {
    /// The line is not valid ops JSON (bad syntax, unknown op or field, wrong type).
    #[error("cannot parse ops JSON: {0}")]
    Parse(String),
    /// An op that names an unknown material or model, a coordinate outside the world, or a
    /// malformed value.
    #[error("op {index} ({op}): {reason}")]
    Invalid {
        /// Position of the op in its batch.
        index: usize,
        /// The op's name.
        op: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// An op (or batch) larger than [`Limits`] allow.
    #[error("op {index} ({op}): over limit: {reason}")]
    Limit {
        /// Position of the op in its batch.
        index: usize,
        /// The op's name.
        op: &'static str,
        /// Which limit, and by how much.
        reason: String,
    },
    /// An op this layer does not apply (entity ops go to the world).
    #[error("op {index} ({op}): {reason}")]
    Unsupported {
        /// Position of the op in its batch.
        index: usize,
        /// The op's name.
        op: &'static str,
        /// Why.
        reason: String,
    },
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn parse_err(line: &str) -> String {
        match Batch::parse_line(line) {
            Err(e @ EditError::Parse(_)) => e.to_string(),
            other => panic!("expected a parse error for {line}, got {other:?}"),
        }
    }

    #[test]
    fn parses_every_op() {
        let lines = [
            r#"{"op":"set","voxels":[[1,2,3,4],[0,0,0,0]]}"#,
            r#"{"op":"box","min":[0,0,0],"max":[4,5,6],"material":2}"#,
            r#"{"op":"sphere","center":[1.5,2,3],"radius":4,"material":0}"#,
            r#"{"op":"paint","center":[1,2,3],"radius":2.5,"material":3}"#,
            r#"{"op":"flood_paint","start":[1,2,3],"material":3,"limit":100}"#,
            r#"{"op":"copy","min":[0,0,0],"max":[2,2,2],"to":[-1,5,7]}"#,
            r#"{"op":"place","model":"tree","at":[3,4,5]}"#,
            r#"{"op":"spawn_entity","id":7,"model":"car","pos":[1,2,3],"rot":[0,0,0,1]}"#,
            r#"{"op":"move_entity","id":7,"pos":[1,2,3.5],"rot":[0,0.7,0,0.7]}"#,
            r#"{"op":"despawn_entity","id":7}"#,
            r#"{"op":"define_material","id":5,"kind":"emissive","albedo":[1,0.5,0],"emission":4,"roughness":0.5}"#,
            r#"{"op":"define_material","id":6,"kind":"mirror","albedo":[1,1,1]}"#,
            r#"{"op":"define_model","name":"m","size":[2,1,1],"voxels":[[1,0,0,3]]}"#,
        ];
        for line in lines {
            let b = Batch::parse_line(line).unwrap_or_else(|e| panic!("{line}: {e}"));
            assert_eq!(b.ops.len(), 1);
            assert_eq!(Batch::parse_line(&b.to_json_line()).unwrap(), b);
        }
        let b = Batch::parse_line(r#"{"op":"box","min":[0,0,0],"max":[4,5,6],"material":2}"#).unwrap();
        assert_eq!(
            b.ops[0],
            Op::Box {
                min: [0, 0, 0],
                max: [4, 5, 6],
                material: 2
            }
        );
        let d = Batch::parse_line(lines[11]).unwrap();
        assert_eq!(
            d.ops[0],
            Op::DefineMaterial {
                id: 6,
                kind: MaterialKind::Mirror,
                albedo: [1.0; 3],
                emission: 0.0,
                roughness: 0.0
            }
        );
        assert!(!b.has_entity_ops());
        assert!(Batch::parse_line(lines[9]).unwrap().has_entity_ops());
    }

    #[test]
    fn parses_batches() {
        let b = Batch::parse_line(
            r#" {"batch":[{"op":"despawn_entity","id":1},{"op":"box","min":[0,0,0],"max":[1,1,1],"material":0}]} "#,
        )
        .unwrap();
        assert_eq!(b.ops.len(), 2);
        assert!(b.has_entity_ops());
        assert_eq!(b.ops[1].name(), "box");
        let line = b.to_json_line();
        assert!(line.starts_with(r#"{"batch":[{"op":"despawn_entity""#), "{line}");
        assert_eq!(Batch::parse_line(&line).unwrap(), b);
        // One op in a batch is the same batch as the op alone.
        let one = Batch::parse_line(r#"{"batch":[{"op":"despawn_entity","id":1}]}"#).unwrap();
        assert_eq!(one, Batch::parse_line(r#"{"op":"despawn_entity","id":1}"#).unwrap());
        assert_eq!(one.to_json_line(), r#"{"op":"despawn_entity","id":1}"#);
        // An escaped key is still the batch key.
        let esc = Batch::parse_line(r#"{"b\u0061tch":[{"op":"despawn_entity","id":1}]}"#).unwrap();
        assert_eq!(esc, one);
        let empty = Batch::parse_line(r#"{"batch":[]}"#).unwrap();
        assert!(empty.ops.is_empty());
        assert_eq!(empty.to_json_line(), r#"{"batch":[]}"#);
    }

    #[test]
    fn rejects_with_clear_messages() {
        let e = parse_err(r#"{"op":"cube","min":[0,0,0]}"#);
        assert!(e.contains("unknown variant `cube`"), "{e}");
        let e = parse_err(r#"{"op":"box","min":[0,0,0],"max":[1,1,1],"material":1,"colour":3}"#);
        assert!(e.contains("op 0 (box)") && e.contains("unknown field `colour`"), "{e}");
        let e = parse_err(r#"{"op":"box","min":[0,0,0],"max":[1,1,1]}"#);
        assert!(e.contains("missing field `material`"), "{e}");
        let e = parse_err(r#"{"batch":[{"op":"despawn_entity","id":1},{"op":"set","voxels":[[1,2,3]]}]}"#);
        assert!(e.contains("op 1 (set)"), "{e}");
        let e = parse_err(r#"{"batch":[{"op":"despawn_entity","id":1}],"extra":1}"#);
        assert!(e.contains("unknown field `extra`"), "{e}");
        let e = parse_err(r#"{"batch":[{"op":"nope"}]}"#);
        assert!(e.contains("op 0 (nope)") && e.contains("unknown variant"), "{e}");
        let e = parse_err(r#"{"op":"box","min":[0,0,0],"max":[1,1,1],"material":70000}"#);
        assert!(e.contains("70000"), "{e}");
        let e = parse_err(r#"{"op":"box","min":[0,0,0],"max":[1,1,1],"material":1,"material":2}"#);
        assert!(e.contains("duplicate field"), "{e}");
        let e = parse_err(r#"{"op":"define_material","id":1,"kind":"glass","albedo":[1,1,1]}"#);
        assert!(e.contains("glass"), "{e}");
        for bad in ["", "   ", "[1,2]", "{\"op\":\"box\"", "nonsense", "{}", r#"{"id":1}"#] {
            let e = parse_err(bad);
            assert!(e.starts_with("cannot parse ops JSON"), "{e}");
        }
    }

    /// Long client strings are cut in every message that quotes them: model names at parse
    /// time, op and field names and values in serde's messages.
    #[test]
    fn long_inputs_give_short_errors() {
        let long = "n".repeat(20_000);
        let cut = format!("{}… (20000 bytes)", "n".repeat(MAX_QUOTED_CHARS));
        let lines = [
            format!(r#"{{"op":"place","model":"{long}","at":[0,0,0]}}"#),
            format!(r#"{{"op":"spawn_entity","id":1,"model":"{long}","pos":[0,0,0],"rot":[0,0,0,1]}}"#),
            format!(
                r#"{{"batch":[{{"op":"despawn_entity","id":1}},{{"op":"define_model","name":"{long}","size":[1,1,1],"voxels":[]}}]}}"#
            ),
            format!(r#"{{"op":"{long}","min":[0,0,0]}}"#),
            format!(r#"{{"batch":[{{"op":"{long}"}}]}}"#),
            format!(r#"{{"op":"box","min":[0,0,0],"max":[1,1,1],"material":1,"{long}":3}}"#),
            format!(r#"{{"op":"define_material","id":1,"kind":"{long}","albedo":[1,1,1]}}"#),
            format!(r#"{{"op":"box","min":"{long}","max":[1,1,1],"material":1}}"#),
            format!(r#"{{"batch":[],"{long}":1}}"#),
        ];
        for line in &lines {
            let e = Batch::parse_line(line).expect_err("a long name is refused").to_string();
            assert!(e.len() < 700, "{} bytes: {e}", e.len());
            assert!(e.contains(&cut), "{e}");
        }
        // The limit is the model name's byte length: 64 bytes pass, 65 do not.
        let place = |name: &str| format!(r#"{{"op":"place","model":"{name}","at":[0,0,0]}}"#);
        assert!(Batch::parse_line(&place(&"é".repeat(32))).is_ok());
        let e = Batch::parse_line(&place(&"n".repeat(MAX_MODEL_NAME + 1))).unwrap_err();
        assert!(
            matches!(
                e,
                EditError::Invalid {
                    index: 0,
                    op: "place",
                    ..
                }
            ) && e.to_string().contains("longer than 64 bytes"),
            "{e}"
        );
        // A quoted string holding a delimiter still ends in a short message.
        let tricky = format!(r#"{{"op":"box","min":[0,0,0],"max":[1,1,1],"material":1,"a`{long}":3}}"#);
        let e = Batch::parse_line(&tricky).unwrap_err().to_string();
        assert!(e.len() < 700, "{} bytes", e.len());
    }

    #[test]
    fn clip_counts_characters_and_reports_bytes() {
        assert_eq!(clip_input("", 3), "");
        assert_eq!(clip_input("abc", 3), "abc");
        assert_eq!(clip_input("éééé", 3), "ééé… (8 bytes)");
        assert_eq!(
            clip_quoted("unknown variant `abcdef`, expected `set`"),
            "unknown variant `abcdef`, expected `set`"
        );
    }

    fn coord() -> impl Strategy<Value = i64> {
        prop_oneof![-300i64..300, any::<i64>()]
    }

    fn coords3() -> impl Strategy<Value = [i64; 3]> {
        [coord(), coord(), coord()]
    }

    /// Whether serde_json parses every float exactly (its `float_roundtrip` feature). Without
    /// it, numbers of 17 significant digits or with exponents beyond ±22 may come back one ulp
    /// off; those with at most 15 digits and small exponents are always exact.
    fn exact_float_parsing() -> bool {
        [1.4567122439477925e-86, 7.581573879229685e-221, 0.1 + 0.2]
            .iter()
            .all(|&x| serde_json::from_str::<f64>(&serde_json::to_string(&x).unwrap()).unwrap() == x)
    }

    fn float() -> impl Strategy<Value = f64> {
        // n / 10^k with |n| < 10^12: at most 12 digits, exponent ≥ -6 — exact either way.
        let decimal = (-1_000_000_000_000i64..1_000_000_000_000, 0i32..7).prop_map(|(n, k)| n as f64 / 10f64.powi(k));
        let eighths = (-1000i32..1000).prop_map(|v| f64::from(v) / 8.0);
        if exact_float_parsing() {
            prop_oneof![
                decimal,
                eighths,
                -200.0f64..200.0,
                proptest::num::f64::NORMAL | proptest::num::f64::SUBNORMAL | proptest::num::f64::ZERO,
            ]
            .boxed()
        } else {
            prop_oneof![decimal, eighths].boxed()
        }
    }

    fn float3() -> impl Strategy<Value = [f64; 3]> {
        [float(), float(), float()]
    }

    fn unit_f32() -> impl Strategy<Value = f32> {
        prop_oneof![0.0f32..=1.0, proptest::num::f32::NORMAL]
    }

    fn voxels() -> impl Strategy<Value = Vec<[i64; 4]>> {
        proptest::collection::vec(
            (coord(), coord(), coord(), 0i64..40000).prop_map(|(x, y, z, m)| [x, y, z, m]),
            0..6,
        )
    }

    fn name() -> impl Strategy<Value = String> {
        prop_oneof![Just(String::new()), "[a-z]{1,8}", ".{0,12}"]
    }

    fn op() -> impl Strategy<Value = Op> {
        let kind = prop_oneof![
            Just(MaterialKind::Diffuse),
            Just(MaterialKind::Emissive),
            Just(MaterialKind::Metal),
            Just(MaterialKind::Mirror)
        ];
        prop_oneof![
            voxels().prop_map(|voxels| Op::Set { voxels }),
            (coords3(), coords3(), any::<u16>()).prop_map(|(min, max, material)| Op::Box { min, max, material }),
            (float3(), float(), any::<u16>()).prop_map(|(center, radius, material)| Op::Sphere {
                center,
                radius,
                material
            }),
            (float3(), float(), any::<u16>()).prop_map(|(center, radius, material)| Op::Paint {
                center,
                radius,
                material
            }),
            (coords3(), any::<u16>(), any::<u64>()).prop_map(|(start, material, limit)| Op::FloodPaint {
                start,
                material,
                limit
            }),
            (coords3(), coords3(), coords3()).prop_map(|(min, max, to)| Op::Copy { min, max, to }),
            (name(), coords3()).prop_map(|(model, at)| Op::Place { model, at }),
            (any::<u32>(), name(), float3(), [float(), float(), float(), float()])
                .prop_map(|(id, model, pos, rot)| Op::SpawnEntity { id, model, pos, rot }),
            (any::<u32>(), float3(), [float(), float(), float(), float()]).prop_map(|(id, pos, rot)| Op::MoveEntity {
                id,
                pos,
                rot
            }),
            any::<u32>().prop_map(|id| Op::DespawnEntity { id }),
            (
                any::<u16>(),
                kind,
                [unit_f32(), unit_f32(), unit_f32()],
                unit_f32(),
                unit_f32()
            )
                .prop_map(|(id, kind, albedo, emission, roughness)| Op::DefineMaterial {
                    id,
                    kind,
                    albedo,
                    emission,
                    roughness
                }),
            (name(), [0u32..200, 0u32..200, 0u32..200], voxels()).prop_map(|(name, size, voxels)| Op::DefineModel {
                name,
                size,
                voxels
            }),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        #[test]
        fn json_round_trip(ops in proptest::collection::vec(op(), 0..5)) {
            let b = Batch { ops };
            let line = b.to_json_line();
            prop_assert!(!line.contains('\n'));
            let back = Batch::parse_line(&line).map_err(|e| TestCaseError::fail(format!("{line}: {e}")))?;
            prop_assert_eq!(back, b);
        }
    }
}

//! HashDAG edit replays (docs/REPLAY.md): the CSV files of "Interactively Modifying
//! Compressed Sparse Voxel Representations" (Careil, Billeter, Eisemann 2020) turned into
//! replay-script lines.
//!
//! A file holds one action per row: the action's name, then its fields, comma-separated
//! (`EditSphere,x,y,z,radius,add`). Some files pad every row with empty cells up to a fixed
//! width; like HashDAG, the converter drops trailing empty cells before counting fields.
//!
//! Edit coordinates are HashDAG voxel coordinates at the replay's depth; one affine map
//! ([`HashdagMapping`]) places them in our world. Camera rows use the same map.
//!
//! ```
//! use naadf_world::replay::hashdag::{HashdagMapping, to_script_lines};
//! let csv = "EditSphere,10,20,30,4,true\nEndFrame\n";
//! let m = HashdagMapping { scale: 0.5, offset: [1.0, 0.0, 0.0], material: 3 };
//! let lines = to_script_lines(csv, &m).unwrap();
//! assert_eq!(lines[0], (1, r#"{"op":"sphere","center":[6.0,10.0,15.0],"radius":2.0,"material":3}"#.to_string()));
//! assert_eq!(lines[1], (2, r#"{"end_frame":true}"#.to_string()));
//! ```

use crate::camera::Camera;
use crate::ops::{Batch, Op};
use serde::Serialize;

/// How HashDAG coordinates map into a world: `world = hashdag · scale + offset` per axis,
/// radii `· scale`.
///
/// HashDAG itself multiplies replay coordinates by `2^(scene depth − replay depth)` before
/// editing; fold that factor into `scale`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HashdagMapping {
    /// Voxels of our world per HashDAG unit; finite and positive.
    pub scale: f64,
    /// Where HashDAG's origin lands, in voxels; finite.
    pub offset: [f64; 3],
    /// Material that adding edits and paints write (default 1); removing edits write 0.
    pub material: u16,
}

impl Default for HashdagMapping {
    fn default() -> Self {
        Self {
            scale: 1.0,
            offset: [0.0; 3],
            material: 1,
        }
    }
}

impl HashdagMapping {
    /// Checks that the mapping can produce valid ops: a finite positive scale, a finite
    /// offset, and a material paint can use (1..=32767).
    pub fn validate(&self) -> Result<(), HashdagError> {
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err(HashdagError::Mapping(format!(
                "scale {} must be finite and positive",
                self.scale
            )));
        }
        if self.offset.iter().any(|v| !v.is_finite()) {
            return Err(HashdagError::Mapping(format!(
                "offset {:?} must be finite",
                self.offset
            )));
        }
        if !(1..=32767).contains(&self.material) {
            return Err(HashdagError::Mapping(format!(
                "material {} must be in 1..=32767 (paint cannot write 0)",
                self.material
            )));
        }
        Ok(())
    }

    /// Maps a HashDAG point into world voxel coordinates.
    fn point(&self, p: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|a| p[a] * self.scale + self.offset[a])
    }
}

/// Errors of [`to_script_lines`]; row numbers are 1-based physical lines of the file.
#[derive(Debug, thiserror::Error)]
pub enum HashdagError {
    /// A malformed row: unknown action, wrong field count, a field that is not a finite
    /// number or not a boolean, or a value that maps to something invalid.
    #[error("row {row}: {msg}")]
    Row {
        /// 1-based line number.
        row: usize,
        /// What is wrong.
        msg: String,
    },
    /// A well-known HashDAG action that has no exact counterpart among our ops
    /// (`EditFill`, `EditCopy`).
    #[error("unsupported row {row}: {kind}")]
    Unsupported {
        /// 1-based line number.
        row: usize,
        /// The action name.
        kind: String,
    },
    /// The mapping itself is unusable (see [`HashdagMapping::validate`]).
    #[error("invalid HashDAG mapping: {0}")]
    Mapping(String),
}

/// HashDAG's vertical field of view: its tracer spans `±sin 30°` up against `cos 30°`
/// forward, i.e. 60°.
const HASHDAG_FOV_Y: f64 = 60.0;

/// A camera line of the script.
#[derive(Serialize)]
struct CameraLine {
    camera: Camera,
}

/// The camera state a replay builds up; HashDAG starts at the origin with the identity
/// rotation, whose forward row is +Z.
struct CameraState {
    pos: [f64; 3],
    forward: [f64; 3],
}

/// Converts a whole CSV file to replay-script lines (JSON text, no trailing newline), in
/// order, each with the 1-based CSV row it came from (so that errors can name the row).
///
/// Blank lines are skipped. Every row is checked, so an error means no partial output.
pub fn to_script_lines(csv: &str, m: &HashdagMapping) -> Result<Vec<(usize, String)>, HashdagError> {
    m.validate()?;
    let mut out = Vec::new();
    let mut camera = CameraState {
        pos: [0.0; 3],
        forward: [0.0, 0.0, 1.0],
    };
    for (i, raw) in csv.lines().enumerate() {
        let row = i + 1;
        if raw.trim().is_empty() {
            continue;
        }
        let mut cells: Vec<&str> = raw.split(',').map(str::trim).collect();
        // Spreadsheet exports pad rows with empty cells; HashDAG drops trailing ones too.
        while cells.len() > 1 && cells.last().is_some_and(|c| c.is_empty()) {
            cells.pop();
        }
        let (kind, fields) = (cells[0], &cells[1..]);
        let r = Row { row, kind, fields };
        match kind {
            "EditSphere" => {
                r.count(&[5])?;
                let (c, radius) = r.sphere_fields(m)?;
                let material = if r.flag(4)? { m.material } else { 0 };
                out.push((
                    row,
                    op_line(Op::Sphere {
                        center: c,
                        radius,
                        material,
                    }),
                ));
            }
            "EditCube" => {
                r.count(&[5])?;
                let c = [r.num(0)?, r.num(1)?, r.num(2)?];
                let half = r.radius(3)?;
                let add = r.flag(4)?;
                // HashDAG edits every voxel whose unit cube overlaps the open box
                // (c − half, c + half): exactly [floor(lo), ceil(hi)) per axis.
                let lo = m.point(c.map(|v| v - half));
                let hi = m.point(c.map(|v| v + half));
                let min = r.bounds(lo, f64::floor)?;
                let max = r.bounds(hi, f64::ceil)?;
                out.push((
                    row,
                    op_line(Op::Box {
                        min,
                        max,
                        material: if add { m.material } else { 0 },
                    }),
                ));
            }
            "EditPaint" => {
                r.count(&[4])?;
                let (center, radius) = r.sphere_fields(m)?;
                out.push((
                    row,
                    op_line(Op::Paint {
                        center,
                        radius,
                        material: m.material,
                    }),
                ));
            }
            "Undo" => {
                r.count(&[0])?;
                out.push((row, r#"{"undo":true}"#.to_owned()));
            }
            "Redo" => {
                r.count(&[0])?;
                out.push((row, r#"{"redo":true}"#.to_owned()));
            }
            "EndFrame" => {
                r.count(&[0])?;
                out.push((row, r#"{"end_frame":true}"#.to_owned()));
            }
            "SetLocation" => {
                r.count(&[3])?;
                camera.pos = r.finite(m.point([r.num(0)?, r.num(1)?, r.num(2)?]), "location")?;
                out.push((row, camera_line(&camera)));
            }
            "SetRotation" => {
                r.count(&[9])?;
                // Row-major 3×3; HashDAG's CameraView takes row 2 as forward, row 1 as up
                // and the negated row 0 as right.
                let f = [r.num(6)?, r.num(7)?, r.num(8)?];
                let len = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
                for k in 0..6 {
                    r.num(k)?;
                }
                if !(len.is_finite() && len > 1e-9) {
                    return Err(r.err(format!("forward row {f:?} has no direction")));
                }
                camera.forward = f.map(|v| v / len);
                out.push((row, camera_line(&camera)));
            }
            "SetToolParameters" => {
                // The tool cursor and the selected tool: interface state, not edits.
                r.count(&[11])?;
                for k in 0..11 {
                    r.num(k)?;
                }
            }
            "EditFill" | "EditCopy" => {
                return Err(HashdagError::Unsupported {
                    row,
                    kind: kind.to_owned(),
                });
            }
            _ => {
                return Err(r.err(format!(
                    "unknown row kind {kind:?} (expected EditSphere, EditCube, EditPaint, Undo, Redo, \
                     SetLocation, SetRotation, SetToolParameters or EndFrame)"
                )));
            }
        }
    }
    Ok(out)
}

/// One op as a script line.
fn op_line(op: Op) -> String {
    Batch { ops: vec![op] }.to_json_line()
}

/// The current camera as a script line: yaw = atan2(fx, fz), pitch = asin(fy), in degrees,
/// which reproduces the forward vector exactly under our camera convention.
fn camera_line(c: &CameraState) -> String {
    let f = c.forward;
    let camera = Camera {
        pos: c.pos,
        yaw: f[0].atan2(f[2]).to_degrees(),
        pitch: f[1].clamp(-1.0, 1.0).asin().to_degrees(),
        fov_y: HASHDAG_FOV_Y,
    };
    serde_json::to_string(&CameraLine { camera }).expect("finite camera serialises")
}

/// One row being converted: its number, action name and non-padding fields.
struct Row<'a> {
    row: usize,
    kind: &'a str,
    fields: &'a [&'a str],
}

impl Row<'_> {
    fn err(&self, msg: String) -> HashdagError {
        HashdagError::Row { row: self.row, msg }
    }

    /// Checks the field count against the allowed ones.
    fn count(&self, allowed: &[usize]) -> Result<(), HashdagError> {
        if allowed.contains(&self.fields.len()) {
            return Ok(());
        }
        let want: Vec<String> = allowed.iter().map(ToString::to_string).collect();
        Err(self.err(format!(
            "{} takes {} fields, this row has {}",
            self.kind,
            want.join(" or "),
            self.fields.len()
        )))
    }

    /// Field `k` (0-based after the action name) as a finite number.
    fn num(&self, k: usize) -> Result<f64, HashdagError> {
        let s = self.fields[k];
        match s.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(self.err(format!("{} field {}: {s:?} is not finite", self.kind, k + 1))),
            Err(_) => Err(self.err(format!("{} field {}: {s:?} is not a number", self.kind, k + 1))),
        }
    }

    /// Field `k` as a radius: finite and at least 0.
    fn radius(&self, k: usize) -> Result<f64, HashdagError> {
        let r = self.num(k)?;
        if r < 0.0 {
            return Err(self.err(format!("{} radius {r} is negative", self.kind)));
        }
        Ok(r)
    }

    /// Field `k` as HashDAG's add flag: `true` or `false` in any letter case.
    fn flag(&self, k: usize) -> Result<bool, HashdagError> {
        let s = self.fields[k];
        if s.eq_ignore_ascii_case("true") {
            Ok(true)
        } else if s.eq_ignore_ascii_case("false") {
            Ok(false)
        } else {
            Err(self.err(format!("{} field {}: {s:?} is not true or false", self.kind, k + 1)))
        }
    }

    /// The mapped centre and radius of fields 1 to 4.
    fn sphere_fields(&self, m: &HashdagMapping) -> Result<([f64; 3], f64), HashdagError> {
        let c = self.finite(m.point([self.num(0)?, self.num(1)?, self.num(2)?]), "center")?;
        let r = self.radius(3)? * m.scale;
        if !r.is_finite() {
            return Err(self.err(format!("{} radius maps to {r}", self.kind)));
        }
        Ok((c, r))
    }

    /// Rejects mapped values that overflowed.
    fn finite(&self, p: [f64; 3], what: &str) -> Result<[f64; 3], HashdagError> {
        if p.iter().all(|v| v.is_finite()) {
            Ok(p)
        } else {
            Err(self.err(format!("{} {what} maps to {p:?}", self.kind)))
        }
    }

    /// Rounds mapped box corners to integer bounds, refusing ones beyond ±2⁵³ where f64
    /// stops being exact.
    fn bounds(&self, p: [f64; 3], round: fn(f64) -> f64) -> Result<[i64; 3], HashdagError> {
        const LIMIT: f64 = 9_007_199_254_740_992.0;
        let r = p.map(round);
        if r.iter().any(|v| !(v.is_finite() && v.abs() <= LIMIT)) {
            return Err(self.err(format!("{} corner maps to {p:?}, outside ±2^53", self.kind)));
        }
        Ok(r.map(|v| v as i64))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::replay::script;

    fn conv(csv: &str) -> Vec<String> {
        text(to_script_lines(csv, &HashdagMapping::default()).unwrap())
    }

    /// The lines without their row numbers.
    fn text(lines: Vec<(usize, String)>) -> Vec<String> {
        lines.into_iter().map(|(_, l)| l).collect()
    }

    fn err(csv: &str) -> String {
        to_script_lines(csv, &HashdagMapping::default())
            .unwrap_err()
            .to_string()
    }

    /// Every output line must be a valid script line, and op lines valid ops JSON.
    fn check_parses(lines: &[String]) {
        for l in lines {
            if l.starts_with("{\"op\"") || l.starts_with("{\"batch\"") {
                let b = Batch::parse_line(l).unwrap_or_else(|e| panic!("{l}: {e}"));
                assert_eq!(&b.to_json_line(), l);
            }
            script::parse_line(l).unwrap_or_else(|e| panic!("{l}: {e}"));
        }
    }

    #[test]
    fn every_row_kind_converts() {
        let csv = "SetLocation,1,2,3\n\
                   SetRotation,-1,0,0,0,1,0,0,0,1\n\
                   SetToolParameters,0,0,0,0,0,0,0,0,0,2300.000000,0\n\
                   EditSphere,10,20,30,4,true\n\
                   EditSphere,10,20,30,4,false\n\
                   EditCube,10.5,20,30,2,TRUE\n\
                   EditCube,10,20,30,0.5,False\n\
                   EditPaint,1,2,3,5\n\
                   Undo\n\
                   \n\
                   Redo\n\
                   EndFrame\n";
        let lines = conv(csv);
        let want = [
            r#"{"camera":{"pos":[1.0,2.0,3.0],"yaw":0.0,"pitch":0.0,"fov_y":60.0}}"#,
            r#"{"camera":{"pos":[1.0,2.0,3.0],"yaw":0.0,"pitch":0.0,"fov_y":60.0}}"#,
            r#"{"op":"sphere","center":[10.0,20.0,30.0],"radius":4.0,"material":1}"#,
            r#"{"op":"sphere","center":[10.0,20.0,30.0],"radius":4.0,"material":0}"#,
            r#"{"op":"box","min":[8,18,28],"max":[13,22,32],"material":1}"#,
            r#"{"op":"box","min":[9,19,29],"max":[11,21,31],"material":0}"#,
            r#"{"op":"paint","center":[1.0,2.0,3.0],"radius":5.0,"material":1}"#,
            r#"{"undo":true}"#,
            r#"{"redo":true}"#,
            r#"{"end_frame":true}"#,
        ];
        assert_eq!(lines, want);
        check_parses(&lines);
    }

    #[test]
    fn flags_are_case_insensitive_and_strict() {
        for (flag, material) in [
            ("true", 1),
            ("TRUE", 1),
            ("True", 1),
            ("false", 0),
            ("FALSE", 0),
            ("fAlSe", 0),
        ] {
            let l = conv(&format!("EditSphere,0,0,0,1,{flag}"));
            assert!(
                l[0].ends_with(&format!("\"material\":{material}}}")),
                "{flag}: {}",
                l[0]
            );
        }
        for bad in ["1", "0", "yes", ""] {
            let e = err(&format!("EditSphere,0,0,0,1,{bad},7"));
            assert!(e.starts_with("row 1:"), "{bad}: {e}");
        }
    }

    #[test]
    fn scale_and_offset_are_exact() {
        let m = HashdagMapping {
            scale: 0.125,
            offset: [-3.0, 0.5, 1000.0],
            material: 7,
        };
        let lines = text(
            to_script_lines(
                "EditSphere,14483,33332,24591,3,true\nEditCube,8,8,8,4,true\nSetLocation,16,0,-8\nEditPaint,1,1,1,1",
                &m,
            )
            .unwrap(),
        );
        let b = Batch::parse_line(&lines[0]).unwrap();
        assert_eq!(
            b.ops[0],
            Op::Sphere {
                center: [14483.0 / 8.0 - 3.0, 33332.0 / 8.0 + 0.5, 24591.0 / 8.0 + 1000.0],
                radius: 0.375,
                material: 7
            }
        );
        // Corners (8 ∓ 4)·⅛ + o: x 0.5−3, 1.5−3 → [-3, -1); y 1.0, 2.0 → [1, 2); z 1000.5, 1001.5.
        assert_eq!(
            lines[1],
            r#"{"op":"box","min":[-3,1,1000],"max":[-1,2,1002],"material":7}"#
        );
        assert_eq!(
            lines[2],
            r#"{"camera":{"pos":[-1.0,0.5,999.0],"yaw":0.0,"pitch":0.0,"fov_y":60.0}}"#
        );
        assert_eq!(
            lines[3],
            r#"{"op":"paint","center":[-2.875,0.625,1000.125],"radius":0.125,"material":7}"#
        );
        check_parses(&lines);
    }

    #[test]
    fn cube_bounds_match_hashdag_coverage() {
        // Radius 0 on a voxel boundary covers nothing, inside a voxel exactly that voxel.
        assert_eq!(
            conv("EditCube,5,5,5,0,true")[0],
            r#"{"op":"box","min":[5,5,5],"max":[5,5,5],"material":1}"#
        );
        assert_eq!(
            conv("EditCube,5.5,5.5,5.5,0,true")[0],
            r#"{"op":"box","min":[5,5,5],"max":[6,6,6],"material":1}"#
        );
    }

    #[test]
    fn rotation_becomes_yaw_and_pitch() {
        // HashDAG's first citadel frame: forward row (0.818522, 0.041585, −0.572969).
        let l =
            conv("SetRotation,-0.573465,0.000000,-0.819230,-0.034067,0.999135,0.023847,0.818522,0.041585,-0.572969");
        let v: serde_json::Value = serde_json::from_str(&l[0]).unwrap();
        let c = Camera::from_json(&v["camera"].to_string()).unwrap();
        let f = c.basis().forward;
        let len = (0.818522f64.powi(2) + 0.041585f64.powi(2) + 0.572969f64.powi(2)).sqrt();
        for (got, want) in f.iter().zip([0.818522 / len, 0.041585 / len, -0.572969 / len]) {
            assert!((got - want).abs() < 1e-12, "{f:?}");
        }
        // Straight forward rows of each axis.
        let yaw_pitch = |row: &str| {
            let l = conv(&format!("SetRotation,1,0,0,0,1,0,{row}"));
            let v: serde_json::Value = serde_json::from_str(&l[0]).unwrap();
            (
                v["camera"]["yaw"].as_f64().unwrap(),
                v["camera"]["pitch"].as_f64().unwrap(),
            )
        };
        assert_eq!(yaw_pitch("1,0,0"), (90.0, 0.0));
        assert_eq!(yaw_pitch("0,0,-2"), (180.0, 0.0));
        assert_eq!(yaw_pitch("0,1,0"), (0.0, 90.0));
    }

    #[test]
    fn camera_keeps_the_last_location_and_rotation() {
        let l = conv("SetRotation,0,0,-1,0,1,0,1,0,0\nSetLocation,4,5,6\nSetLocation,7,8,9");
        assert_eq!(l.len(), 3);
        assert_eq!(
            l[0],
            r#"{"camera":{"pos":[0.0,0.0,0.0],"yaw":90.0,"pitch":0.0,"fov_y":60.0}}"#
        );
        assert_eq!(
            l[2],
            r#"{"camera":{"pos":[7.0,8.0,9.0],"yaw":90.0,"pitch":0.0,"fov_y":60.0}}"#
        );
        check_parses(&l);
    }

    #[test]
    fn padding_cells_and_crlf_are_tolerated() {
        let l = conv(
            "SetLocation,1,2,3,,,,,,\r\nSetRotation,0,0,-1,0,1,0,1,0,0\r\nEndFrame,,,,,,,,,\r\nEditSphere,2775,1328,2063,10,FALSE,,,,\r\n",
        );
        assert_eq!(l.len(), 4);
        assert_eq!(l[2], r#"{"end_frame":true}"#);
        assert_eq!(
            l[3],
            r#"{"op":"sphere","center":[2775.0,1328.0,2063.0],"radius":10.0,"material":0}"#
        );
    }

    #[test]
    fn errors_name_the_row() {
        let cases = [
            ("EndFrame\n\nEditFill,1,2,3,4", "unsupported row 3: EditFill"),
            (
                "EndFrame\nEndFrame\nEditCopy,1,2,3,4,5,6,7,8,9,10",
                "unsupported row 3: EditCopy",
            ),
            ("EndFrame\nEndFrame\nTeleport,1", "row 3: unknown row kind \"Teleport\""),
            (
                "EndFrame\nEndFrame\nEditSphere,1,2,3,true",
                "row 3: EditSphere takes 5 fields, this row has 4",
            ),
            (
                "EndFrame\nEndFrame\nEditSphere,1,x,3,4,true",
                "row 3: EditSphere field 2: \"x\" is not a number",
            ),
            (
                "EndFrame\nEndFrame\nEditSphere,1,NaN,3,4,true",
                "row 3: EditSphere field 2: \"NaN\" is not finite",
            ),
            ("EndFrame\nEndFrame\nEditCube,1,inf,3,4,true", "not finite"),
            (
                "EndFrame\nEndFrame\nEditSphere,1,2,3,-4,true",
                "row 3: EditSphere radius -4 is negative",
            ),
            (
                "EndFrame\nEndFrame\nEditSphere,1,,3,4,true",
                "row 3: EditSphere field 2: \"\" is not a number",
            ),
            (
                "EndFrame\nEndFrame\nEditPaint,1,2,3,4,5",
                "row 3: EditPaint takes 4 fields",
            ),
            ("EndFrame\nEndFrame\nUndo,1", "row 3: Undo takes 0 fields"),
            (
                "EndFrame\nEndFrame\nSetLocation,1,2",
                "row 3: SetLocation takes 3 fields",
            ),
            (
                "EndFrame\nEndFrame\nSetRotation,1,0,0,0,1,0,0,0,0",
                "row 3: forward row",
            ),
            (
                "EndFrame\nEndFrame\nSetRotation,1,0,0,0,1,0,0,0",
                "row 3: SetRotation takes 9 fields",
            ),
            (
                "EndFrame\nEndFrame\nSetToolParameters,0,0,0",
                "row 3: SetToolParameters takes 11 fields",
            ),
            ("EndFrame\nEndFrame\nEditSphere,1e308,2,3,4,true", "row 3"),
            ("EndFrame\nEndFrame\nEndframe", "row 3: unknown row kind"),
        ];
        for (csv, needle) in cases {
            let m = HashdagMapping {
                scale: 10.0,
                ..HashdagMapping::default()
            };
            let e = to_script_lines(csv, &m).unwrap_err().to_string();
            assert!(e.contains(needle), "{csv:?}: {e}");
        }
    }

    #[test]
    fn bad_mappings_are_rejected() {
        for m in [
            HashdagMapping {
                scale: 0.0,
                ..HashdagMapping::default()
            },
            HashdagMapping {
                scale: f64::NAN,
                ..HashdagMapping::default()
            },
            HashdagMapping {
                offset: [0.0, f64::INFINITY, 0.0],
                ..HashdagMapping::default()
            },
            HashdagMapping {
                material: 0,
                ..HashdagMapping::default()
            },
        ] {
            assert!(
                matches!(to_script_lines("EndFrame", &m), Err(HashdagError::Mapping(_))),
                "{m:?}"
            );
        }
    }

    /// The published citadel replay, where the developer machine has it next to the repo.
    #[test]
    fn converts_the_citadel_replay() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../shared/data/replays/hashdag/epiccitadel_edits.csv");
        let Ok(csv) = std::fs::read_to_string(&path) else {
            eprintln!("skipping: HashDAG replay {} is not present", path.display());
            return;
        };
        let m = HashdagMapping {
            scale: 0.25,
            offset: [0.0; 3],
            material: 2,
        };
        let lines = text(to_script_lines(&csv, &m).unwrap());
        let count = |p: &str| lines.iter().filter(|l| l.starts_with(p)).count();
        assert_eq!(count(r#"{"op":"sphere""#), 451);
        assert_eq!(count(r#"{"end_frame":true}"#), 536);
        assert_eq!(count(r#"{"camera":"#), 2 * 536);
        assert_eq!(lines.len(), 451 + 3 * 536);
        check_parses(&lines);
    }
}

//! The replay script format (docs/REPLAY.md): JSON Lines, each line either an ops line
//! (docs/OPS.md: `{"op":…}` or `{"batch":[…]}`: one batch, one version) or one control line.
//!
//! Parsing checks the whole script before anything runs, so a broken script changes
//! nothing; every error names its 1-based line.
//!
//! ```
//! use naadf_world::replay::script::{Line, parse_script};
//! let script = r#"
//! {"as_user":"alice"}
//! {"op":"sphere","center":[10,10,10],"radius":4,"material":2}
//! {"end_frame":true,"fps":30}
//! {"expect_digest":"0123456789abcdef"}
//! "#;
//! let lines = parse_script(script).unwrap();
//! assert_eq!(lines.len(), 4);
//! assert!(matches!(lines[1].line, Line::Ops(_)));
//! assert_eq!(lines[3].number, 5);
//! let err = parse_script("{\"undo\":true}\n{\"op\":\"warp\"}").unwrap_err();
//! assert!(err.to_string().starts_with("line 2:"));
//! ```

use super::random::RandomEdits;
use crate::camera::Camera;
use crate::digest::Digest;
use crate::ops::Batch;
use serde::Deserialize;
use serde_json::Value;

/// A render request of a script: the frame the render client would produce.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderLine {
    /// Camera; the script's current camera (the last `camera` line) when absent.
    #[serde(default)]
    pub camera: Option<Camera>,
    /// Image size `[width, height]`.
    pub size: [u32; 2],
    /// Render mode (`albedo`, `material`, `normal`, `steps`).
    #[serde(default = "default_mode")]
    pub mode: String,
    /// PNG to write (relative paths are relative to the script's folder).
    pub out: String,
}

fn default_mode() -> String {
    "albedo".into()
}

/// An image expectation: the last rendered frame against a reference PNG.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExpectImage {
    /// Reference PNG (relative paths are relative to the script's folder).
    pub file: String,
    /// Largest allowed mean absolute difference over the R, G and B bytes (0–255).
    pub max_mean_abs_diff: f64,
}

/// One line of a script.
#[derive(Clone, Debug, PartialEq)]
pub enum Line {
    /// A batch of ops, applied atomically as one version by the current user.
    Ops(Batch),
    /// Sets the current camera (used by `render` lines without one).
    Camera(Camera),
    /// Ends a frame; with `fps`, the replay waits so that frames follow at that rate.
    EndFrame {
        /// Frames per second of real time, or `None` to run as fast as possible.
        fps: Option<f64>,
    },
    /// Waits until the world reaches this version (other users may produce it).
    WaitVersion(u64),
    /// Checks the digest once the world is quiescent (distance-field growth converged).
    ExpectDigest(Digest),
    /// Renders a frame.
    Render(RenderLine),
    /// Compares the last rendered frame with a reference image.
    ExpectImage(ExpectImage),
    /// Later lines act as this user (a token when replaying against a server).
    AsUser(String),
    /// Undoes the current user's latest edit.
    Undo,
    /// Redoes the current user's latest undo.
    Redo,
    /// Expands into deterministic random edit batches.
    RandomEdits(RandomEdits),
}

/// A parsed line and where it was.
#[derive(Clone, Debug, PartialEq)]
pub struct ScriptLine {
    /// 1-based line number in the script.
    pub number: usize,
    /// What the line says.
    pub line: Line,
}

/// A script error, naming the line.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("line {line}: {message}")]
pub struct ScriptError {
    /// 1-based line number.
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

/// The frame rates `end_frame` accepts: one frame in ~17 minutes to 10,000 per second.
pub const MIN_FPS: f64 = 1e-3;
/// See [`MIN_FPS`].
pub const MAX_FPS: f64 = 1e4;

/// The control keys, in the order docs/REPLAY.md lists them.
const CONTROL_KEYS: [&str; 10] = [
    "camera",
    "end_frame",
    "wait_version",
    "expect_digest",
    "render",
    "expect_image",
    "as_user",
    "undo",
    "redo",
    "random_edits",
];

/// Parses a whole script; blank lines and lines starting with `#` or `//` are skipped.
pub fn parse_script(text: &str) -> Result<Vec<ScriptLine>, ScriptError> {
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let t = raw.trim();
        if t.is_empty() || t.starts_with('#') || t.starts_with("//") {
            continue;
        }
        let line = parse_line(t).map_err(|message| ScriptError { line: i + 1, message })?;
        out.push(ScriptLine { number: i + 1, line });
    }
    Ok(out)
}

/// Parses one non-blank line.
pub fn parse_line(text: &str) -> Result<Line, String> {
    let value: Value = serde_json::from_str(text).map_err(|e| format!("not JSON: {e}"))?;
    let Value::Object(obj) = value else {
        return Err("a line must be a JSON object".into());
    };
    if obj.contains_key("op") || obj.contains_key("batch") {
        return Batch::parse_line(text).map(Line::Ops).map_err(|e| e.to_string());
    }
    let key = CONTROL_KEYS
        .iter()
        .copied()
        .find(|k| obj.contains_key(*k))
        .ok_or_else(|| {
            let keys: Vec<_> = obj.keys().map(String::as_str).collect();
            format!(
                "unknown line {{{}}}: expected an op, a batch or one of {}",
                keys.join(", "),
                CONTROL_KEYS.join(", ")
            )
        })?;
    let allowed: &[&str] = if key == "end_frame" {
        &["end_frame", "fps"]
    } else {
        &[key]
    };
    if let Some(extra) = obj.keys().find(|k| !allowed.contains(&k.as_str())) {
        return Err(format!("unexpected field '{extra}' in a {key} line"));
    }
    let v = &obj[key];
    let field = |what: &str| format!("{key}: {what}");
    Ok(match key {
        "camera" => Line::Camera(Camera::from_json(&v.to_string()).map_err(|e| field(&e.to_string()))?),
        "end_frame" => {
            if v != &Value::Bool(true) {
                return Err(field("must be true"));
            }
            let fps = obj
                .get("fps")
                .map(|f| f.as_f64().filter(|f| (MIN_FPS..=MAX_FPS).contains(f)));
            match fps {
                Some(None) => return Err(format!("fps: must be a number from {MIN_FPS} to {MAX_FPS}")),
                Some(Some(f)) => Line::EndFrame { fps: Some(f) },
                None => Line::EndFrame { fps: None },
            }
        }
        "wait_version" => Line::WaitVersion(v.as_u64().ok_or_else(|| field("must be a version number"))?),
        "expect_digest" => {
            let s = v.as_str().ok_or_else(|| field("must be a hex string"))?;
            Line::ExpectDigest(s.parse().map_err(|e: String| field(&e))?)
        }
        "render" => {
            let r: RenderLine = typed(v).map_err(|e| field(&e))?;
            if let Some(c) = &r.camera {
                // The camera contract's checks (finite, field of view) apply here too.
                let json = serde_json::to_string(c).map_err(|e| field(&e.to_string()))?;
                Camera::from_json(&json).map_err(|e| field(&e.to_string()))?;
            }
            Line::Render(r)
        }
        "expect_image" => {
            let e: ExpectImage = typed(v).map_err(|e| field(&e))?;
            if !(e.max_mean_abs_diff.is_finite() && e.max_mean_abs_diff >= 0.0) {
                return Err(field("max_mean_abs_diff must be a number ≥ 0"));
            }
            Line::ExpectImage(e)
        }
        "as_user" => {
            let s = v
                .as_str()
                .filter(|s| !s.is_empty())
                .ok_or_else(|| field("must be a non-empty string"))?;
            Line::AsUser(s.to_owned())
        }
        "undo" | "redo" => {
            if v != &Value::Bool(true) {
                return Err(field("must be true"));
            }
            if key == "undo" { Line::Undo } else { Line::Redo }
        }
        _ => {
            let r: RandomEdits = typed(v).map_err(|e| field(&e))?;
            r.validate().map_err(|e| field(&e))?;
            Line::RandomEdits(r)
        }
    })
}

/// Deserialises a control line's value into its type, with serde's message on failure.
fn typed<T: for<'de> Deserialize<'de>>(v: &Value) -> Result<T, String> {
    T::deserialize(v).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_line_kind_parses() {
        let text = r#"
# a comment
{"op":"set","voxels":[[1,2,3,4]]}
{"batch":[{"op":"box","min":[0,0,0],"max":[2,2,2],"material":1}]}
{"camera":{"pos":[1,2,3],"yaw":10,"pitch":-5}}
{"end_frame":true}
{"end_frame":true,"fps":24}
{"wait_version":7}
{"expect_digest":"00000000000000ff"}
{"render":{"size":[64,48],"mode":"material","out":"a.png"}}
{"expect_image":{"file":"a.png","max_mean_abs_diff":0.5}}
{"as_user":"bob"}
{"undo":true}
{"redo":true}
{"random_edits":{"count":3,"seed":9}}
"#;
        let lines = parse_script(text).unwrap();
        assert_eq!(lines.len(), 13);
        assert_eq!(lines[0].number, 3);
        assert_eq!(lines[4].line, Line::EndFrame { fps: Some(24.0) });
        assert_eq!(lines[5].line, Line::WaitVersion(7));
        assert_eq!(lines[6].line, Line::ExpectDigest(Digest(255)));
        let Line::Render(r) = &lines[7].line else { panic!() };
        assert_eq!((r.size, r.mode.as_str(), r.camera), ([64, 48], "material", None));
        assert_eq!(lines[9].line, Line::AsUser("bob".into()));
        assert_eq!(lines[11].line, Line::Redo);
    }

    #[test]
    fn errors_name_the_line_and_the_problem() {
        let cases = [
            ("{\"op\":\"warp\"}", "warp"),
            ("not json", "not JSON"),
            ("[1,2]", "JSON object"),
            ("{\"teleport\":1}", "unknown line {teleport}"),
            ("{\"undo\":false}", "undo: must be true"),
            ("{\"undo\":true,\"redo\":true}", "unexpected field"),
            ("{\"end_frame\":true,\"fps\":-1}", "fps"),
            ("{\"end_frame\":true,\"fps\":1e-30}", "fps"),
            ("{\"expect_digest\":\"xyz\"}", "expect_digest"),
            ("{\"render\":{\"size\":[1,1]}}", "out"),
            ("{\"random_edits\":{\"count\":1}}", "seed"),
            ("{\"camera\":{\"pos\":[1,2],\"yaw\":0,\"pitch\":0}}", "camera"),
            ("{\"as_user\":\"\"}", "as_user"),
        ];
        for (bad, needle) in cases {
            let text = format!("{{\"undo\":true}}\n\n{bad}\n{{\"redo\":true}}");
            let e = parse_script(&text).unwrap_err();
            assert_eq!(e.line, 3, "{bad}");
            assert!(e.to_string().contains(needle), "{bad}: {e}");
        }
    }
}

//! Deterministic random edits (docs/REPLAY.md): the script line
//! `{"random_edits":{"count":N,"seed":S,…}}` expands into N one-op batches.
//!
//! The edits depend only on the knobs, the world size and its material count, and every
//! draw is spelled out with integer or exactly-rounded arithmetic on ChaCha8's output, so
//! another implementation can reproduce them bit for bit. Distribution helpers of the
//! `rand` family are avoided on purpose: their algorithms may change between versions.
//!
//! ```
//! use naadf_world::replay::random::RandomEdits;
//! use naadf_world::WorldSize;
//! let r: RandomEdits = serde_json::from_str(r#"{"count":3,"seed":9,"ops":["box"]}"#).unwrap();
//! r.validate().unwrap();
//! let batches = r.batches(WorldSize::new(64, 64, 64).unwrap(), 4);
//! assert_eq!(batches.len(), 3);
//! assert_eq!(batches, r.batches(WorldSize::new(64, 64, 64).unwrap(), 4));
//! ```

use crate::ops::{Batch, Op};
use crate::size::WorldSize;
use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::{RngCore, SeedableRng};

/// Most edits one line may ask for: a million one-op batches is already a long replay.
pub const MAX_COUNT: u32 = 1_000_000;

/// Largest `max_radius`: keeps every drawn box (side ≤ 511) and sphere within the default
/// fill-volume limit of 2²⁷ voxels.
pub const MAX_RADIUS: f64 = 256.0;

/// Region coordinates stay within ±2³¹ so that no draw or bound can overflow.
const MAX_REGION_COORD: i64 = 1 << 31;

/// The op names `ops` may list, in the default order.
pub const OP_NAMES: [&str; 4] = ["set", "box", "sphere", "paint"];

fn default_max_radius() -> f64 {
    8.0
}

/// The value of a `random_edits` script line.
#[derive(Clone, Debug, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RandomEdits {
    /// Number of edits (batches), at most [`MAX_COUNT`].
    pub count: u32,
    /// Seed of the ChaCha8 generator.
    pub seed: u64,
    /// Largest sphere or paint radius, and largest box half-extent, in voxels; in
    /// (0, [`MAX_RADIUS`]] (default 8).
    #[serde(default = "default_max_radius")]
    pub max_radius: f64,
    /// Materials to draw from (0 erases; repeats weight the draw). Default: 1 to
    /// min(8, the world's material count − 1).
    #[serde(default)]
    pub materials: Option<Vec<u16>>,
    /// Op kinds to draw from, among `set`, `box`, `sphere`, `paint` (repeats weight the
    /// draw). Default: all four in that order.
    #[serde(default)]
    pub ops: Option<Vec<String>>,
    /// Half-open box `[min, max)` that edit positions are drawn from. Default: the whole
    /// world.
    #[serde(default)]
    pub region: Option<[[i64; 3]; 2]>,
}

/// An op kind of a random edit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Set,
    Box,
    Sphere,
    Paint,
}

impl Kind {
    fn parse(name: &str) -> Option<Kind> {
        match name {
            "set" => Some(Kind::Set),
            "box" => Some(Kind::Box),
            "sphere" => Some(Kind::Sphere),
            "paint" => Some(Kind::Paint),
            _ => None,
        }
    }
}

impl RandomEdits {
    /// Validates knobs (count ≤ 1 000 000, radius finite in (0, 256], non-empty lists of
    /// known ops and valid materials, no erasing paint, a region that is not inside-out)
    /// with clear errors.
    pub fn validate(&self) -> Result<(), String> {
        if self.count > MAX_COUNT {
            return Err(format!("count {} is over the limit of {MAX_COUNT}", self.count));
        }
        if !(self.max_radius.is_finite() && self.max_radius > 0.0 && self.max_radius <= MAX_RADIUS) {
            return Err(format!("max_radius {} must be in (0, {MAX_RADIUS}]", self.max_radius));
        }
        let kinds = self.kinds()?;
        if let Some(materials) = &self.materials {
            if materials.is_empty() {
                return Err("materials must not be empty".into());
            }
            if let Some(m) = materials.iter().find(|&&m| m > 32767) {
                return Err(format!("material {m} is outside 0..=32767"));
            }
            if materials.contains(&0) && kinds.contains(&Kind::Paint) {
                return Err("materials holds 0 (erase), which paint cannot use: drop \"paint\" from ops".into());
            }
        }
        if let Some([min, max]) = self.region {
            for a in 0..3 {
                if min[a] >= max[a] {
                    return Err(format!(
                        "region {:?}..{:?} is empty or inside-out along {}",
                        min,
                        max,
                        ["x", "y", "z"][a]
                    ));
                }
                if min[a].abs() > MAX_REGION_COORD || max[a].abs() > MAX_REGION_COORD {
                    return Err(format!("region {min:?}..{max:?} reaches beyond ±2^31"));
                }
            }
        }
        Ok(())
    }

    /// The batches, one op each, for a world of `size` with `material_count` materials
    /// (the length of its material table, empty entry 0 included).
    ///
    /// Call [`RandomEdits::validate`] first: knobs it rejects may panic here.
    pub fn batches(&self, size: WorldSize, material_count: usize) -> Vec<Batch> {
        let kinds = self.kinds().expect("validated ops");
        let materials = self
            .materials
            .clone()
            .unwrap_or_else(|| default_materials(material_count));
        let (lo, hi) = self.draw_box(size);
        let width: [u64; 3] = std::array::from_fn(|a| (hi[a] - lo[a]) as u64);
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let mut out = Vec::with_capacity(self.count as usize);
        for _ in 0..self.count {
            // Six draws per edit, always, whatever the kind: the stream stays aligned.
            let kind = kinds[pick(rng.next_u64(), kinds.len())];
            let material = materials[pick(rng.next_u64(), materials.len())];
            let p: [i64; 3] = std::array::from_fn(|a| lo[a] + (rng.next_u64() % width[a]) as i64);
            // 53 random bits as u in [0, 1); 1 − u is exact, so r lies in (0, max_radius].
            let u = (rng.next_u64() >> 11) as f64 * (-53f64).exp2();
            let r = self.max_radius * (1.0 - u);
            let centre = p.map(|v| v as f64 + 0.5);
            let op = match kind {
                Kind::Set => Op::Set {
                    voxels: vec![[p[0], p[1], p[2], i64::from(material)]],
                },
                Kind::Box => {
                    // Voxels within Chebyshev distance e − 1 of p: side 2e − 1, centred on p.
                    let e = r.ceil() as i64;
                    Op::Box {
                        min: p.map(|v| v - (e - 1)),
                        max: p.map(|v| v + e),
                        material,
                    }
                }
                Kind::Sphere => Op::Sphere {
                    center: centre,
                    radius: r,
                    material,
                },
                Kind::Paint => Op::Paint {
                    center: centre,
                    radius: r,
                    material,
                },
            };
            out.push(Batch { ops: vec![op] });
        }
        out
    }

    /// The op kinds to draw from, in list order.
    fn kinds(&self) -> Result<Vec<Kind>, String> {
        let Some(names) = &self.ops else {
            return Ok(vec![Kind::Set, Kind::Box, Kind::Sphere, Kind::Paint]);
        };
        if names.is_empty() {
            return Err("ops must not be empty".into());
        }
        names
            .iter()
            .map(|n| {
                Kind::parse(n).ok_or_else(|| format!("unknown op {n:?} in ops (expected {})", OP_NAMES.join(", ")))
            })
            .collect()
    }

    /// The half-open box positions are drawn from: the region clipped to the world, or the
    /// region as given where it misses the world entirely (its edits then fall outside:
    /// fills clip to nothing and the world rejects the sets).
    fn draw_box(&self, size: WorldSize) -> ([i64; 3], [i64; 3]) {
        let n = size.voxels().map(i64::from);
        let Some([min, max]) = self.region else {
            return ([0; 3], n);
        };
        let lo: [i64; 3] = std::array::from_fn(|a| min[a].max(0));
        let hi: [i64; 3] = std::array::from_fn(|a| max[a].min(n[a]));
        if (0..3).all(|a| lo[a] < hi[a]) {
            (lo, hi)
        } else {
            (min, max)
        }
    }
}

/// The default materials: 1 to min(8, `material_count` − 1), or `[1]` for a world without
/// materials (whose edits the world then rejects, naming the undefined material).
fn default_materials(material_count: usize) -> Vec<u16> {
    let top = material_count.saturating_sub(1).min(8) as u16;
    if top == 0 { vec![1] } else { (1..=top).collect() }
}

/// Index `draw mod len`.
fn pick(draw: u64, len: usize) -> usize {
    (draw % len as u64) as usize
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::World;
    use crate::ops::Limits;
    use crate::preset::Preset;

    fn parse(json: &str) -> RandomEdits {
        let r: RandomEdits = serde_json::from_str(json).unwrap();
        r.validate().unwrap();
        r
    }

    fn size64() -> WorldSize {
        WorldSize::new(64, 64, 64).unwrap()
    }

    #[test]
    fn same_seed_same_edits_and_different_seed_different_edits() {
        let a = parse(r#"{"count":50,"seed":7}"#).batches(size64(), 5);
        let b = parse(r#"{"count":50,"seed":7}"#).batches(size64(), 5);
        let c = parse(r#"{"count":50,"seed":8}"#).batches(size64(), 5);
        assert_eq!(a.len(), 50);
        assert_eq!(a, b);
        assert_ne!(a, c);
        // A longer run starts with the shorter one.
        assert_eq!(parse(r#"{"count":60,"seed":7}"#).batches(size64(), 5)[..50], a[..]);
    }

    #[test]
    fn pinned_first_edits() {
        // Fails on any change of the draw order or formulas, or of the generator.
        let b = parse(r#"{"count":4,"seed":1}"#).batches(size64(), 4);
        let lines: Vec<String> = b.iter().map(Batch::to_json_line).collect();
        // Checked against an independent implementation of docs/REPLAY.md.
        let want = [
            r#"{"op":"box","min":[35,0,35],"max":[40,5,40],"material":3}"#,
            r#"{"op":"paint","center":[19.5,8.5,49.5],"radius":3.3823269029303367,"material":1}"#,
            r#"{"op":"paint","center":[34.5,29.5,29.5],"radius":0.7011605748693572,"material":1}"#,
            r#"{"op":"box","min":[36,31,26],"max":[51,46,41],"material":3}"#,
        ];
        assert_eq!(lines, want);
    }

    #[test]
    fn every_batch_applies_to_a_generated_world() {
        let src = Preset::Test.source(None, 1).unwrap();
        let mut world = World::build(&*src, &|_| {}).unwrap();
        let count = world.materials().len();
        let r = parse(r#"{"count":300,"seed":3,"max_radius":12}"#);
        let batches = r.batches(world.size(), count);
        let mut seen = [false; 4];
        for (i, batch) in batches.iter().enumerate() {
            assert_eq!(batch.ops.len(), 1);
            let k = OP_NAMES.iter().position(|n| *n == batch.ops[0].name()).unwrap();
            seen[k] = true;
            world
                .apply(batch, &Limits::default())
                .unwrap_or_else(|e| panic!("edit {i} {}: {e}", batch.to_json_line()));
        }
        assert_eq!(seen, [true; 4]);
        // A region partly outside the world clips; the largest radius stays within limits.
        let r = parse(r#"{"count":40,"seed":4,"max_radius":256,"region":[[-10,-10,-10],[8,70,8]]}"#);
        for batch in r.batches(world.size(), count) {
            world.apply(&batch, &Limits::default()).unwrap();
        }
    }

    #[test]
    fn knobs_restrict_the_draws() {
        let r = parse(
            r#"{"count":200,"seed":5,"max_radius":3,"materials":[4,0],"ops":["box","sphere"],"region":[[10,20,30],[12,21,40]]}"#,
        );
        for b in r.batches(size64(), 2) {
            match &b.ops[0] {
                Op::Box { min, max, material } => {
                    assert!([0, 4].contains(material));
                    let p = *min;
                    let side: Vec<i64> = (0..3).map(|a| max[a] - p[a]).collect();
                    assert!(side.iter().all(|&s| s == side[0] && s % 2 == 1 && s <= 5), "{b:?}");
                    let c: Vec<i64> = (0..3).map(|a| p[a] + side[a] / 2).collect();
                    assert!(
                        (10..12).contains(&c[0]) && c[1] == 20 && (30..40).contains(&c[2]),
                        "{b:?}"
                    );
                }
                Op::Sphere {
                    center,
                    radius,
                    material,
                } => {
                    assert!([0, 4].contains(material));
                    assert!(*radius > 0.0 && *radius <= 3.0);
                    assert!((10.5..12.0).contains(&center[0]) && center[1] == 20.5, "{b:?}");
                }
                other => panic!("unexpected op {other:?}"),
            }
        }
    }

    #[test]
    fn default_materials_follow_the_table() {
        assert_eq!(default_materials(0), [1]);
        assert_eq!(default_materials(1), [1]);
        assert_eq!(default_materials(4), [1, 2, 3]);
        assert_eq!(default_materials(100), [1, 2, 3, 4, 5, 6, 7, 8]);
    }

    #[test]
    fn invalid_knobs_are_explained() {
        let cases = [
            (r#"{"count":1000001,"seed":1}"#, "count"),
            (r#"{"count":1,"seed":1,"max_radius":0}"#, "max_radius"),
            (r#"{"count":1,"seed":1,"max_radius":256.5}"#, "max_radius"),
            (r#"{"count":1,"seed":1,"materials":[]}"#, "materials must not be empty"),
            (r#"{"count":1,"seed":1,"materials":[40000]}"#, "40000"),
            (r#"{"count":1,"seed":1,"materials":[0,1]}"#, "paint"),
            (r#"{"count":1,"seed":1,"ops":[]}"#, "ops must not be empty"),
            (r#"{"count":1,"seed":1,"ops":["copy"]}"#, "unknown op \"copy\""),
            (
                r#"{"count":1,"seed":1,"region":[[0,0,0],[4,0,4]]}"#,
                "inside-out along y",
            ),
            (r#"{"count":1,"seed":1,"region":[[0,0,0],[4,4,4294967296]]}"#, "2^31"),
        ];
        for (json, needle) in cases {
            let r: RandomEdits = serde_json::from_str(json).unwrap();
            let e = r.validate().unwrap_err();
            assert!(e.contains(needle), "{json}: {e}");
        }
        assert!(serde_json::from_str::<RandomEdits>(r#"{"count":1,"seed":1,"radius":2}"#).is_err());
        assert!(serde_json::from_str::<RandomEdits>(r#"{"count":1}"#).is_err());
        let r = parse(r#"{"count":1,"seed":1,"materials":[0],"ops":["set","box","sphere"]}"#);
        assert_eq!(r.max_radius, 8.0);
    }
}

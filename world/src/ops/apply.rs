//! Resolution of ops into voxel writes on a [`Canvas`] and table updates.

use super::{Batch, Canvas, EditError, Limits, Op};
use crate::cell::MAX_MATERIAL;
use crate::material::{Material, MaterialTable};
use crate::model::{MAX_MODEL_EDGE, Model, ModelTable};
use crate::size::WorldSize;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Longest model name, in bytes.
pub const MAX_MODEL_NAME: usize = 64;

impl Op {
    /// The op's name as in the JSON (`"set"`, `"box"`, ...).
    pub fn name(&self) -> &'static str {
        match self {
            Op::Set { .. } => "set",
            Op::Box { .. } => "box",
            Op::Sphere { .. } => "sphere",
            Op::Paint { .. } => "paint",
            Op::FloodPaint { .. } => "flood_paint",
            Op::Copy { .. } => "copy",
            Op::Place { .. } => "place",
            Op::SpawnEntity { .. } => "spawn_entity",
            Op::MoveEntity { .. } => "move_entity",
            Op::DespawnEntity { .. } => "despawn_entity",
            Op::DefineMaterial { .. } => "define_material",
            Op::DefineModel { .. } => "define_model",
        }
    }

    /// Whether this is an entity op (spawn, move, despawn), which the world applies itself.
    pub fn is_entity_op(&self) -> bool {
        matches!(
            self,
            Op::SpawnEntity { .. } | Op::MoveEntity { .. } | Op::DespawnEntity { .. }
        )
    }

    /// Checks the shape of an entity op: finite `pos`, `rot` a non-zero finite quaternion,
    /// and (spawn) a model that `models` defines. Whether the entity id exists is the
    /// world's business. Other ops pass unchecked.
    pub fn validate_entity(&self, index: usize, models: &ModelTable) -> Result<(), EditError> {
        let cx = Ctx { index, op: self.name() };
        let check_pose = |pos: &[f64; 3], rot: &[f64; 4]| {
            if pos.iter().any(|v| !v.is_finite()) {
                return Err(cx.invalid(format!("pos {pos:?} must be finite")));
            }
            let n2: f64 = rot.iter().map(|v| v * v).sum();
            if rot.iter().any(|v| !v.is_finite()) || !n2.is_finite() || n2 == 0.0 {
                return Err(cx.invalid(format!("rot {rot:?} must be a non-zero finite quaternion [x,y,z,w]")));
            }
            Ok(())
        };
        match self {
            Op::SpawnEntity { model, pos, rot, .. } => {
                check_pose(pos, rot)?;
                if models.get(model).is_none() {
                    return Err(cx.invalid(format!("model '{model}' is not defined")));
                }
                Ok(())
            }
            Op::MoveEntity { pos, rot, .. } => check_pose(pos, rot),
            _ => Ok(()),
        }
    }

    /// Applies one voxel or table op to `canvas` and the batch's working copies of the
    /// tables. `index` is the op's position in the batch (for messages).
    ///
    /// Entity ops are validated ([`Op::validate_entity`]) and then return
    /// [`EditError::Unsupported`]: the world layer handles them itself. On any error the
    /// canvas may hold part of the op's writes; the caller discards it.
    pub fn apply(
        &self,
        index: usize,
        canvas: &mut dyn Canvas,
        materials: &mut MaterialTable,
        models: &mut ModelTable,
        limits: &Limits,
    ) -> Result<(), EditError> {
        let cx = Ctx { index, op: self.name() };
        let size = canvas.size();
        match self {
            Op::Set { voxels } => apply_set(&cx, voxels, canvas, materials, limits),
            Op::Box { min, max, material } => {
                cx.material(*material, materials)?;
                let Some((lo, hi)) = cx.clip_box(*min, *max, size)? else {
                    return Ok(());
                };
                cx.volume_limit(volume(lo, hi), limits)?;
                for z in lo[2]..hi[2] {
                    for y in lo[1]..hi[1] {
                        for x in lo[0]..hi[0] {
                            canvas.set([x, y, z], *material);
                        }
                    }
                }
                Ok(())
            }
            Op::Sphere {
                center,
                radius,
                material,
            } => {
                cx.material(*material, materials)?;
                let ball = Ball::new(&cx, *center, *radius, size)?;
                cx.volume_limit(ball.bbox_volume, limits)?;
                ball.for_each(|p| canvas.set(p, *material));
                Ok(())
            }
            Op::Paint {
                center,
                radius,
                material,
            } => {
                if *material == 0 {
                    return Err(
                        cx.invalid("paint with material 0 (paint only retypes solid voxels; use sphere to erase)")
                    );
                }
                cx.material(*material, materials)?;
                let ball = Ball::new(&cx, *center, *radius, size)?;
                cx.volume_limit(ball.bbox_volume, limits)?;
                ball.for_each(|p| {
                    if canvas.get(p) != 0 {
                        canvas.set(p, *material);
                    }
                });
                Ok(())
            }
            Op::FloodPaint { start, material, limit } => {
                apply_flood(&cx, *start, *material, *limit, canvas, materials, limits)
            }
            Op::Copy { min, max, to } => apply_copy(&cx, *min, *max, *to, canvas, limits),
            Op::Place { model, at } => {
                let Some(m) = models.get(model) else {
                    return Err(cx.invalid(format!("model '{model}' is not defined")));
                };
                apply_place(&cx, model, m, *at, canvas, materials, limits)
            }
            Op::SpawnEntity { .. } | Op::MoveEntity { .. } | Op::DespawnEntity { .. } => {
                self.validate_entity(index, models)?;
                Err(EditError::Unsupported {
                    index,
                    op: cx.op,
                    reason: "entity ops are applied by the world, not the voxel canvas".into(),
                })
            }
            Op::DefineMaterial {
                id,
                kind,
                albedo,
                emission,
                roughness,
            } => {
                let m = Material {
                    kind: *kind,
                    albedo: *albedo,
                    emission: *emission,
                    roughness: *roughness,
                };
                materials.set(*id, m).map_err(|e| cx.invalid(e.to_string()))
            }
            Op::DefineModel { name, size, voxels } => {
                apply_define_model(&cx, name, *size, voxels, materials, models, limits)
            }
        }
    }
}

/// Applies every op of a batch in order. Stops at the first error (the caller discards the
/// canvas and the table copies then). A batch of more than `limits.max_ops` ops is rejected
/// before anything runs. Entity ops make this fail with [`EditError::Unsupported`]: a world
/// that supports them applies the ops one by one.
pub fn apply_batch(
    batch: &Batch,
    canvas: &mut dyn Canvas,
    materials: &mut MaterialTable,
    models: &mut ModelTable,
    limits: &Limits,
) -> Result<(), EditError> {
    batch.check_size(limits)?;
    for (i, op) in batch.ops.iter().enumerate() {
        op.apply(i, canvas, materials, models, limits)?;
    }
    Ok(())
}

/// Which op an error is about.
struct Ctx {
    index: usize,
    op: &'static str,
}

impl Ctx {
    fn invalid(&self, reason: impl Into<String>) -> EditError {
        EditError::Invalid {
            index: self.index,
            op: self.op,
            reason: reason.into(),
        }
    }

    fn limit(&self, reason: impl Into<String>) -> EditError {
        EditError::Limit {
            index: self.index,
            op: self.op,
            reason: reason.into(),
        }
    }

    /// Material 0 (erase) or a defined material.
    fn material(&self, m: u16, materials: &MaterialTable) -> Result<(), EditError> {
        if m > MAX_MATERIAL {
            Err(self.invalid(format!("material {m} outside 0..={MAX_MATERIAL}")))
        } else if m != 0 && !materials.contains(m) {
            Err(self.invalid(format!("material {m} is not defined")))
        } else {
            Ok(())
        }
    }

    /// A material given as `i64` in a voxel list.
    fn material_i64(&self, m: i64, materials: &MaterialTable, what: impl FnOnce() -> String) -> Result<u16, EditError> {
        match u16::try_from(m) {
            Ok(v) if v <= MAX_MATERIAL => {
                if v != 0 && !materials.contains(v) {
                    Err(self.invalid(format!("{}: material {v} is not defined", what())))
                } else {
                    Ok(v)
                }
            }
            _ => Err(self.invalid(format!("{}: material {m} outside 0..={MAX_MATERIAL}", what()))),
        }
    }

    fn volume_limit(&self, v: u64, limits: &Limits) -> Result<(), EditError> {
        if v > limits.max_fill_volume {
            Err(self.limit(format!(
                "covers {v} voxels inside the world, more than the {} allowed per op",
                limits.max_fill_volume
            )))
        } else {
            Ok(())
        }
    }

    /// `[min, max)` clipped to the world; `None` when empty. `min > max` on an axis is an error.
    fn clip_box(&self, min: [i64; 3], max: [i64; 3], size: WorldSize) -> Result<Option<Span>, EditError> {
        if (0..3).any(|a| min[a] > max[a]) {
            return Err(self.invalid(format!("min {min:?} exceeds max {max:?}")));
        }
        Ok(clip(min, max, size))
    }
}

/// A non-empty half-open box `[lo, hi)` inside the world.
type Span = ([u32; 3], [u32; 3]);

/// `[min, max)` clipped to the world; `None` when empty.
fn clip(min: [i64; 3], max: [i64; 3], size: WorldSize) -> Option<Span> {
    let n = size.voxels();
    let mut lo = [0u32; 3];
    let mut hi = [0u32; 3];
    for a in 0..3 {
        let end = i64::from(n[a]);
        lo[a] = min[a].clamp(0, end) as u32;
        hi[a] = max[a].clamp(0, end) as u32;
        if lo[a] >= hi[a] {
            return None;
        }
    }
    Some((lo, hi))
}

fn volume(lo: [u32; 3], hi: [u32; 3]) -> u64 {
    (0..3).map(|a| u64::from(hi[a].saturating_sub(lo[a]))).product()
}

fn apply_set(
    cx: &Ctx,
    voxels: &[[i64; 4]],
    canvas: &mut dyn Canvas,
    materials: &MaterialTable,
    limits: &Limits,
) -> Result<(), EditError> {
    if voxels.len() > limits.max_set_voxels {
        return Err(cx.limit(format!(
            "{} voxels, more than the {} allowed",
            voxels.len(),
            limits.max_set_voxels
        )));
    }
    let size = canvas.size();
    for (i, v) in voxels.iter().enumerate() {
        let p = [v[0], v[1], v[2]];
        if !size.contains(p) {
            return Err(cx.invalid(format!("voxel {i} at {p:?} lies outside the world {size}")));
        }
        cx.material_i64(v[3], materials, || format!("voxel {i} at {p:?}"))?;
    }
    for v in voxels {
        canvas.set([v[0] as u32, v[1] as u32, v[2] as u32], v[3] as u16);
    }
    Ok(())
}

/// A sphere's voxel set: `(x+0.5−cx)² + (y+0.5−cy)² + (z+0.5−cz)² < r²`, evaluated in f64
/// left to right, clipped to the world.
struct Ball {
    c: [f64; 3],
    r2: f64,
    /// Slack (voxels) that covers every rounding error of the row bounds.
    slack: f64,
    /// Iteration box (clipped, widened by the slack), half-open.
    lo: [i64; 3],
    hi: [i64; 3],
    /// Volume of the clipped nominal bounding box (what the limit counts).
    bbox_volume: u64,
}

impl Ball {
    fn new(cx: &Ctx, c: [f64; 3], r: f64, size: WorldSize) -> Result<Ball, EditError> {
        if c.iter().any(|v| !v.is_finite()) {
            return Err(cx.invalid(format!("center {c:?} must be finite")));
        }
        if !r.is_finite() || r < 0.0 {
            return Err(cx.invalid(format!("radius {r} must be finite and at least 0")));
        }
        let n = size.voxels();
        // Rounding errors of the bounds are far below this (relative 2⁻⁵² of the magnitudes
        // involved; the row half-width's sqrt adds at most r·2⁻²⁵).
        let magnitude = c.iter().map(|v| v.abs()).sum::<f64>() + r + 65536.0;
        let slack = 2.0 + r * (2.0f64).powi(-20) + magnitude * (2.0f64).powi(-40);
        let mut lo = [0i64; 3];
        let mut hi = [0i64; 3];
        let mut bbox_volume = 1u64;
        for a in 0..3 {
            let end = f64::from(n[a]);
            // Nominal: x + 0.5 in (c − r, c + r).
            let nlo = ((c[a] - r - 0.5).floor() + 1.0).clamp(0.0, end);
            let nhi = (c[a] + r - 0.5).ceil().clamp(0.0, end);
            bbox_volume = bbox_volume.saturating_mul((nhi - nlo).max(0.0) as u64);
            lo[a] = (nlo - slack.ceil() - 1.0).clamp(0.0, end) as i64;
            hi[a] = (nhi + slack.ceil() + 1.0).clamp(0.0, end) as i64;
        }
        Ok(Ball {
            c,
            r2: r * r,
            slack,
            lo,
            hi,
            bbox_volume,
        })
    }

    /// Calls `f` for every voxel inside, z then y then x ascending.
    #[inline]
    fn for_each(&self, mut f: impl FnMut([u32; 3])) {
        let [cx, cy, cz] = self.c;
        let r2 = self.r2;
        let (xlo, xhi) = (self.lo[0], self.hi[0]);
        if xlo >= xhi {
            return;
        }
        for z in self.lo[2]..self.hi[2] {
            let dz = z as f64 + 0.5 - cz;
            let dz2 = dz * dz;
            for y in self.lo[1]..self.hi[1] {
                let dy = y as f64 + 0.5 - cy;
                let dy2 = dy * dy;
                // fl(fl(dx² + dy²) + dz²) ≥ fl(dy² + dz²) (rounding is monotone), so no
                // voxel of this row can pass when the latter already fails. (No NaN here:
                // the inputs are finite, so the sums are at worst +inf.)
                let yz = dy2 + dz2;
                if yz >= r2 {
                    continue;
                }
                let inside = |x: i64| {
                    let dx = x as f64 + 0.5 - cx;
                    dx * dx + dy2 + dz2 < r2
                };
                let w = (r2 - yz).sqrt();
                let mut a = ((cx - 0.5 - w).floor() - self.slack).max(xlo as f64) as i64;
                let mut b = ((cx - 0.5 + w).ceil() + self.slack).min((xhi - 1) as f64) as i64;
                // The inside set of a row is an interval (the test is monotone on either
                // side of the centre); widen if rounding ever put an end outside [a, b].
                while a > xlo && a <= b && inside(a - 1) {
                    a -= 1;
                }
                while b < xhi - 1 && a <= b && inside(b + 1) {
                    b += 1;
                }
                for x in a..=b {
                    if inside(x) {
                        f([x as u32, y as u32, z as u32]);
                    }
                }
            }
        }
    }
}

/// A fast hasher for packed integer keys (FxHash's mixing).
#[derive(Default)]
struct FxHasher(u64);

impl Hasher for FxHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

/// A sparse set of voxel positions: 8³ bricks of bits.
#[derive(Default)]
struct VoxelSet {
    bricks: HashMap<u64, [u64; 8], BuildHasherDefault<FxHasher>>,
}

impl VoxelSet {
    /// Inserts `p`; whether it was new.
    #[inline]
    fn insert(&mut self, p: [u32; 3]) -> bool {
        let key = u64::from(p[0] >> 3) | (u64::from(p[1] >> 3) << 21) | (u64::from(p[2] >> 3) << 42);
        let bit = (p[0] & 7) | ((p[1] & 7) << 3) | ((p[2] & 7) << 6);
        let word = &mut self.bricks.entry(key).or_insert([0; 8])[(bit >> 6) as usize];
        let mask = 1u64 << (bit & 63);
        let new = *word & mask == 0;
        *word |= mask;
        new
    }
}

fn apply_flood(
    cx: &Ctx,
    start: [i64; 3],
    material: u16,
    limit: u64,
    canvas: &mut dyn Canvas,
    materials: &MaterialTable,
    limits: &Limits,
) -> Result<(), EditError> {
    cx.material(material, materials)?;
    if limit > limits.max_flood_limit {
        return Err(cx.limit(format!(
            "limit {limit} is more than the {} allowed",
            limits.max_flood_limit
        )));
    }
    let size = canvas.size();
    if !size.contains(start) {
        return Err(cx.invalid(format!("start {start:?} lies outside the world {size}")));
    }
    let s = [start[0] as u32, start[1] as u32, start[2] as u32];
    let from = canvas.get(s);
    if from == 0 {
        return Err(cx.invalid(format!("flood_paint from an empty voxel at {start:?}")));
    }
    if from == material {
        return Ok(());
    }
    let n = size.voxels();
    let mut seen = VoxelSet::default();
    seen.insert(s);
    // Breadth-first; the list is the queue and, at the end, the voxels to paint.
    let mut region: Vec<[u32; 3]> = vec![s];
    let mut head = 0;
    while head < region.len() {
        let p = region[head];
        head += 1;
        for (axis, up) in [(0, false), (0, true), (1, false), (1, true), (2, false), (2, true)] {
            let mut q = p;
            if up {
                if q[axis] + 1 >= n[axis] {
                    continue;
                }
                q[axis] += 1;
            } else {
                if q[axis] == 0 {
                    continue;
                }
                q[axis] -= 1;
            }
            if canvas.get(q) == from && seen.insert(q) {
                region.push(q);
                if region.len() as u64 > limit {
                    return Err(cx.limit(format!(
                        "the region of material {from} at {start:?} has more than {limit} voxels (nothing painted)"
                    )));
                }
            }
        }
    }
    if region.len() as u64 > limit {
        return Err(cx.limit(format!(
            "the region of material {from} at {start:?} has more than {limit} voxels (nothing painted)"
        )));
    }
    for p in region {
        canvas.set(p, material);
    }
    Ok(())
}

fn apply_copy(
    cx: &Ctx,
    min: [i64; 3],
    max: [i64; 3],
    to: [i64; 3],
    canvas: &mut dyn Canvas,
    limits: &Limits,
) -> Result<(), EditError> {
    let size = canvas.size();
    let Some((slo, shi)) = cx.clip_box(min, max, size)? else {
        return Ok(());
    };
    cx.volume_limit(volume(slo, shi), limits)?;
    // Only the source voxels whose destination lies in the world matter.
    let n = size.voxels();
    let mut lo = [0u32; 3];
    let mut hi = [0u32; 3];
    let mut off = [0i64; 3];
    for a in 0..3 {
        let d = i128::from(to[a]) - i128::from(min[a]);
        let l = i128::from(slo[a]).max(-d);
        let h = i128::from(shi[a]).min(i128::from(n[a]) - d);
        if l >= h {
            return Ok(());
        }
        lo[a] = l as u32;
        hi[a] = h as u32;
        // |d| < 2·16384 here, since both l and l + d lie in the world.
        off[a] = d as i64;
    }
    let mut buf = Vec::with_capacity(volume(lo, hi) as usize);
    for z in lo[2]..hi[2] {
        for y in lo[1]..hi[1] {
            for x in lo[0]..hi[0] {
                buf.push(canvas.get([x, y, z]));
            }
        }
    }
    let dst = |v: u32, a: usize| (i64::from(v) + off[a]) as u32;
    let mut it = buf.into_iter();
    for z in lo[2]..hi[2] {
        for y in lo[1]..hi[1] {
            for x in lo[0]..hi[0] {
                let m = it.next().expect("one value per source voxel");
                canvas.set([dst(x, 0), dst(y, 1), dst(z, 2)], m);
            }
        }
    }
    Ok(())
}

fn apply_place(
    cx: &Ctx,
    name: &str,
    model: &Model,
    at: [i64; 3],
    canvas: &mut dyn Canvas,
    materials: &MaterialTable,
    limits: &Limits,
) -> Result<(), EditError> {
    let ms = model.size();
    let voxels = model.voxels();
    let mut checked = 0u16;
    for &m in voxels {
        if m != 0 && m != checked {
            if m > MAX_MATERIAL || !materials.contains(m) {
                return Err(cx.invalid(format!("model '{name}' uses material {m}, which is not defined")));
            }
            checked = m;
        }
    }
    let max = [0, 1, 2].map(|a| at[a].saturating_add(i64::from(ms[a])));
    let Some((lo, hi)) = clip(at, max, canvas.size()) else {
        return Ok(());
    };
    cx.volume_limit(volume(lo, hi), limits)?;
    let local = |v: u32, a: usize| (i64::from(v) - at[a]) as usize;
    for z in lo[2]..hi[2] {
        for y in lo[1]..hi[1] {
            let row = (local(y, 1) + ms[1] as usize * local(z, 2)) * ms[0] as usize;
            for x in lo[0]..hi[0] {
                let m = voxels[row + local(x, 0)];
                if m != 0 {
                    canvas.set([x, y, z], m);
                }
            }
        }
    }
    Ok(())
}

fn apply_define_model(
    cx: &Ctx,
    name: &str,
    size: [u32; 3],
    voxels: &[[i64; 4]],
    materials: &MaterialTable,
    models: &mut ModelTable,
    limits: &Limits,
) -> Result<(), EditError> {
    if name.is_empty() || name.len() > MAX_MODEL_NAME {
        return Err(cx.invalid(format!(
            "model name '{name}' must be 1..={MAX_MODEL_NAME} bytes, not {}",
            name.len()
        )));
    }
    if size.iter().any(|&v| v == 0 || v > MAX_MODEL_EDGE) {
        return Err(cx.invalid(format!("size {size:?}: each edge must be 1..={MAX_MODEL_EDGE}")));
    }
    let count: u64 = size.iter().map(|&v| u64::from(v)).product();
    if count > limits.max_model_voxels || voxels.len() as u64 > limits.max_model_voxels {
        return Err(cx.limit(format!(
            "model of {count} voxels with {} entries; at most {} allowed",
            voxels.len(),
            limits.max_model_voxels
        )));
    }
    let mut dense = vec![0u16; count as usize];
    for (i, v) in voxels.iter().enumerate() {
        let p = [v[0], v[1], v[2]];
        if (0..3).any(|a| p[a] < 0 || p[a] >= i64::from(size[a])) {
            return Err(cx.invalid(format!("voxel {i} at {p:?} lies outside the model size {size:?}")));
        }
        let m = cx.material_i64(v[3], materials, || format!("voxel {i} at {p:?}"))?;
        let idx = p[0] as usize + size[0] as usize * (p[1] as usize + size[1] as usize * p[2] as usize);
        dense[idx] = m;
    }
    let model = Model::new(size, dense).map_err(|e| cx.invalid(e.to_string()))?;
    models.insert(name.to_owned(), model);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::DenseCanvas;
    use super::*;
    use crate::material::MaterialKind;
    use proptest::prelude::*;

    const N: u32 = 64;

    fn size() -> WorldSize {
        WorldSize::new(N, N, N).unwrap()
    }

    /// Materials 1..=9 defined.
    fn materials() -> MaterialTable {
        let mut t = MaterialTable::default();
        for i in 1..=9u16 {
            t.set(i, Material::diffuse([f32::from(i) / 10.0; 3])).unwrap();
        }
        t
    }

    /// A canvas with some random-ish content (several materials, empties), from `seed`.
    fn noisy(seed: u64, fill: u32) -> DenseCanvas {
        let mut c = DenseCanvas::new(size());
        let mut s = seed | 1;
        for z in 0..N {
            for y in 0..N {
                for x in 0..N {
                    s ^= s << 13;
                    s ^= s >> 7;
                    s ^= s << 17;
                    let m = if (s % 100) < u64::from(fill) {
                        (s >> 32) % 3 + 1
                    } else {
                        0
                    };
                    c.set([x, y, z], m as u16);
                }
            }
        }
        c
    }

    fn run(op: &Op, c: &mut DenseCanvas) -> Result<(), EditError> {
        let mut mats = materials();
        let mut models = ModelTable::default();
        op.apply(3, c, &mut mats, &mut models, &Limits::default())
    }

    fn all() -> impl Iterator<Item = [u32; 3]> {
        (0..N).flat_map(|z| (0..N).flat_map(move |y| (0..N).map(move |x| [x, y, z])))
    }

    fn brute_inside(c: [f64; 3], r: f64, p: [u32; 3]) -> bool {
        let d = [0, 1, 2].map(|a| f64::from(p[a]) + 0.5 - c[a]);
        d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < r * r
    }

    fn in_box(min: [i64; 3], max: [i64; 3], p: [u32; 3]) -> bool {
        (0..3).all(|a| min[a] <= i64::from(p[a]) && i64::from(p[a]) < max[a])
    }

    fn coord() -> impl Strategy<Value = i64> {
        prop_oneof![-20i64..84, Just(0i64), Just(64), Just(63)]
    }

    fn fcoord() -> impl Strategy<Value = f64> {
        prop_oneof![
            -20.0f64..84.0,
            (-40i32..170).prop_map(|v| f64::from(v) / 2.0),
            Just(0.0),
            Just(64.0),
        ]
    }

    fn radius() -> impl Strategy<Value = f64> {
        prop_oneof![
            0.0f64..40.0,
            (0i32..60).prop_map(|v| f64::from(v) / 2.0),
            Just(0.0),
            (0i32..40).prop_map(|v| f64::from(v).sqrt()),
            100.0f64..200.0,
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(96))]

        #[test]
        fn box_matches_brute_force(min in [coord(), coord(), coord()], ext in [0i64..40, 0i64..40, 0i64..40],
                                   m in 0u16..4, seed in any::<u64>()) {
            let max = [0, 1, 2].map(|a| min[a] + ext[a]);
            let mut c = noisy(seed, 30);
            let before = c.clone();
            run(&Op::Box { min, max, material: m }, &mut c).unwrap();
            for p in all() {
                let want = if in_box(min, max, p) { m } else { before.get(p) };
                prop_assert_eq!(c.get(p), want, "at {:?}", p);
            }
        }

        #[test]
        fn sphere_and_paint_match_brute_force(center in [fcoord(), fcoord(), fcoord()], r in radius(),
                                              m in 1u16..4, erase in any::<bool>(), seed in any::<u64>()) {
            let before = noisy(seed, 40);
            let sm = if erase { 0 } else { m };
            let mut s = before.clone();
            run(&Op::Sphere { center, radius: r, material: sm }, &mut s).unwrap();
            let mut p = before.clone();
            run(&Op::Paint { center, radius: r, material: m }, &mut p).unwrap();
            for q in all() {
                let inside = brute_inside(center, r, q);
                let old = before.get(q);
                prop_assert_eq!(s.get(q), if inside { sm } else { old }, "sphere at {:?}", q);
                prop_assert_eq!(p.get(q), if inside && old != 0 { m } else { old }, "paint at {:?}", q);
            }
        }

        #[test]
        fn copy_matches_brute_force(min in [coord(), coord(), coord()], ext in [0i64..40, 0i64..40, 0i64..40],
                                    to in [coord(), coord(), coord()], seed in any::<u64>()) {
            let max = [0, 1, 2].map(|a| min[a] + ext[a]);
            let before = noisy(seed, 50);
            let mut c = before.clone();
            run(&Op::Copy { min, max, to }, &mut c).unwrap();
            let mut want = before.clone();
            for p in all() {
                if in_box(min, max, p) {
                    let d = [0, 1, 2].map(|a| i64::from(p[a]) - min[a] + to[a]);
                    if size().contains(d) {
                        want.set(d.map(|v| v as u32), before.get(p));
                    }
                }
            }
            prop_assert!(c == want);
        }

        #[test]
        fn flood_matches_brute_force(start in [0i64..64, 0i64..64, 0i64..64], m in 0u16..5, fill in 30u32..=100,
                                     seed in any::<u64>(), limit in prop_oneof![0u64..2000, Just(1u64 << 24)]) {
            let before = noisy(seed, fill);
            let mut c = before.clone();
            let s = start.map(|v| v as u32);
            let r = run(&Op::FloodPaint { start, material: m, limit }, &mut c);
            let from = before.get(s);
            if from == 0 {
                prop_assert!(matches!(r, Err(EditError::Invalid { .. })), "{:?}", r);
                prop_assert!(c == before);
                return Ok(());
            }
            if from == m {
                prop_assert!(r.is_ok());
                prop_assert!(c == before);
                return Ok(());
            }
            // Oracle: depth-first search over a dense visited grid.
            let mut reach = vec![false; before.voxels().len()];
            reach[before.index(s)] = true;
            let mut stack = vec![s];
            while let Some(p) = stack.pop() {
                for a in 0..3 {
                    for d in [-1i64, 1] {
                        let v = i64::from(p[a]) + d;
                        if !(0..i64::from(N)).contains(&v) {
                            continue;
                        }
                        let mut q = p;
                        q[a] = v as u32;
                        let i = before.index(q);
                        if !reach[i] && before.get(q) == from {
                            reach[i] = true;
                            stack.push(q);
                        }
                    }
                }
            }
            let count = reach.iter().filter(|&&v| v).count() as u64;
            if count > limit {
                prop_assert!(matches!(r, Err(EditError::Limit { .. })), "{:?}", r);
                prop_assert!(c == before, "nothing written");
            } else {
                prop_assert!(r.is_ok(), "{:?}", r);
                for p in all() {
                    let want = if reach[before.index(p)] { m } else { before.get(p) };
                    prop_assert_eq!(c.get(p), want);
                }
            }
        }

        #[test]
        fn place_matches_brute_force(at in [coord(), coord(), coord()], ms in [1u32..20, 1u32..20, 1u32..20],
                                     seed in any::<u64>(), mseed in any::<u64>()) {
            let before = noisy(seed, 30);
            let mut mats = materials();
            let mut models = ModelTable::default();
            let n = (ms[0] * ms[1] * ms[2]) as usize;
            let mut s = mseed | 1;
            let mv: Vec<u16> = (0..n).map(|_| { s ^= s << 13; s ^= s >> 7; s ^= s << 17; [0, 0, 5, 6][(s % 4) as usize] }).collect();
            models.insert("m".into(), Model::new(ms, mv.clone()).unwrap());
            let mut c = before.clone();
            Op::Place { model: "m".into(), at }.apply(0, &mut c, &mut mats, &mut models, &Limits::default()).unwrap();
            for p in all() {
                let l = [0, 1, 2].map(|a| i64::from(p[a]) - at[a]);
                let mut want = before.get(p);
                if (0..3).all(|a| l[a] >= 0 && l[a] < i64::from(ms[a])) {
                    let v = mv[(l[0] + i64::from(ms[0]) * (l[1] + i64::from(ms[1]) * l[2])) as usize];
                    if v != 0 { want = v; }
                }
                prop_assert_eq!(c.get(p), want, "at {:?}", p);
            }
        }

        #[test]
        fn set_matches_brute_force(vs in proptest::collection::vec([0i64..64, 0i64..64, 0i64..64, 0i64..10], 0..200),
                                   seed in any::<u64>()) {
            let before = noisy(seed, 30);
            let mut c = before.clone();
            run(&Op::Set { voxels: vs.clone() }, &mut c).unwrap();
            let mut want = before.clone();
            for v in &vs {
                want.set([v[0] as u32, v[1] as u32, v[2] as u32], v[3] as u16);
            }
            prop_assert!(c == want);
        }
    }

    /// A canvas that counts calls and stays blank, to watch what ops touch.
    struct Counting {
        size: WorldSize,
        sets: u64,
    }

    impl Canvas for Counting {
        fn size(&self) -> WorldSize {
            self.size
        }
        fn get(&self, _: [u32; 3]) -> u16 {
            1
        }
        fn set(&mut self, _: [u32; 3], _: u16) {
            self.sets += 1;
        }
    }

    #[test]
    fn sphere_edge_cases() {
        // Radius 0: nothing, wherever the centre.
        for c in [[0.5, 0.5, 0.5], [0.0; 3], [10.25, 3.0, 63.5]] {
            let mut k = noisy(1, 50);
            let before = k.clone();
            run(
                &Op::Sphere {
                    center: c,
                    radius: 0.0,
                    material: 2,
                },
                &mut k,
            )
            .unwrap();
            assert!(k == before);
        }
        // A tiny radius around a voxel centre picks exactly that voxel.
        let mut k = DenseCanvas::new(size());
        run(
            &Op::Sphere {
                center: [3.5, 4.5, 5.5],
                radius: 1e-9,
                material: 2,
            },
            &mut k,
        )
        .unwrap();
        assert_eq!(k.voxels().iter().filter(|&&v| v != 0).count(), 1);
        assert_eq!(k.get([3, 4, 5]), 2);
        // Exactly on the boundary is outside: radius 1 around a voxel centre leaves the six
        // axis neighbours (d² = 1) out.
        let mut k = DenseCanvas::new(size());
        run(
            &Op::Sphere {
                center: [10.5, 10.5, 10.5],
                radius: 1.0,
                material: 1,
            },
            &mut k,
        )
        .unwrap();
        assert_eq!(k.voxels().iter().filter(|&&v| v != 0).count(), 1, "d² == r² is outside");
        // Radius 1 around a voxel corner: the 8 voxels around it (d² = 0.75).
        let mut k = DenseCanvas::new(size());
        run(
            &Op::Sphere {
                center: [10.0, 0.0, 64.0],
                radius: 1.0,
                material: 1,
            },
            &mut k,
        )
        .unwrap();
        assert_eq!(
            k.voxels().iter().filter(|&&v| v != 0).count(),
            2,
            "clipped to 2 of the 8"
        );
        // A sphere far outside the world, and one swallowing it.
        let mut k = DenseCanvas::new(size());
        run(
            &Op::Sphere {
                center: [-1e12, 5.0, 5.0],
                radius: 1e3,
                material: 1,
            },
            &mut k,
        )
        .unwrap();
        assert!(k.voxels().iter().all(|&v| v == 0));
        run(
            &Op::Sphere {
                center: [-1e9, 5.0, 5.0],
                radius: 2e9,
                material: 1,
            },
            &mut k,
        )
        .unwrap();
        assert!(k.voxels().iter().all(|&v| v == 1));
        run(
            &Op::Sphere {
                center: [1e300, 5.0, 5.0],
                radius: 1e300,
                material: 2,
            },
            &mut k,
        )
        .unwrap();
        for p in all() {
            let want = if brute_inside([1e300, 5.0, 5.0], 1e300, p) {
                2
            } else {
                1
            };
            assert_eq!(k.get(p), want);
        }
    }

    #[test]
    fn sphere_iterates_only_its_bounding_box() {
        let big = WorldSize::new(1024, 1024, 1024).unwrap();
        let mut c = Counting { size: big, sets: 0 };
        let mut mats = materials();
        let mut models = ModelTable::default();
        let op = Op::Sphere {
            center: [512.0, 512.0, 512.0],
            radius: 64.0,
            material: 1,
        };
        let t = std::time::Instant::now();
        op.apply(0, &mut c, &mut mats, &mut models, &Limits::default()).unwrap();
        let dt = t.elapsed();
        // 4/3·π·64³ ≈ 1.098M voxels.
        assert!((1_090_000..1_105_000).contains(&c.sets), "{}", c.sets);
        eprintln!("sphere r=64: {} voxels in {dt:?}", c.sets);
    }

    #[test]
    fn materials_are_checked() {
        let mut c = noisy(5, 40);
        let before = c.clone();
        let ops = [
            Op::Box {
                min: [0; 3],
                max: [1; 3],
                material: 10,
            },
            Op::Box {
                min: [0; 3],
                max: [0; 3],
                material: 10,
            },
            Op::Sphere {
                center: [0.0; 3],
                radius: 3.0,
                material: 33000,
            },
            Op::Paint {
                center: [0.0; 3],
                radius: 3.0,
                material: 12,
            },
            Op::FloodPaint {
                start: [0, 0, 0],
                material: 11,
                limit: 10,
            },
            Op::Set {
                voxels: vec![[0, 0, 0, 1], [1, 1, 1, 10]],
            },
            Op::Set {
                voxels: vec![[0, 0, 0, -1]],
            },
            Op::Set {
                voxels: vec![[0, 0, 0, 40000]],
            },
        ];
        for op in ops {
            let e = run(&op, &mut c).unwrap_err();
            assert!(matches!(e, EditError::Invalid { index: 3, .. }), "{e:?}");
            let msg = e.to_string();
            assert!(msg.starts_with(&format!("op 3 ({}): ", op.name())), "{msg}");
            assert!(msg.contains("material"), "{msg}");
        }
        let e = run(
            &Op::Paint {
                center: [0.0; 3],
                radius: 3.0,
                material: 0,
            },
            &mut c,
        )
        .unwrap_err();
        assert!(e.to_string().contains("paint with material 0"), "{e}");
        assert!(c == before);
    }

    #[test]
    fn set_rejects_outside_and_later_entries_win() {
        let mut c = DenseCanvas::new(size());
        for p in [[-1, 0, 0], [0, 64, 0], [0, 0, 64], [i64::MIN, 0, 0]] {
            let e = run(
                &Op::Set {
                    voxels: vec![[1, 1, 1, 1], [p[0], p[1], p[2], 1]],
                },
                &mut c,
            )
            .unwrap_err();
            let msg = e.to_string();
            assert!(matches!(e, EditError::Invalid { .. }), "{msg}");
            assert!(
                msg.contains(&format!("{p:?}")) && msg.contains("outside the world"),
                "{msg}"
            );
        }
        assert!(c.voxels().iter().all(|&v| v == 0), "nothing written by a rejected set");
        run(
            &Op::Set {
                voxels: vec![[1, 2, 3, 1], [1, 2, 3, 2], [4, 4, 4, 3], [4, 4, 4, 0]],
            },
            &mut c,
        )
        .unwrap();
        assert_eq!(c.get([1, 2, 3]), 2);
        assert_eq!(c.get([4, 4, 4]), 0);
    }

    #[test]
    fn shape_errors() {
        let mut c = DenseCanvas::new(size());
        let bad = [
            Op::Box {
                min: [5, 0, 0],
                max: [4, 9, 9],
                material: 1,
            },
            Op::Copy {
                min: [0, 0, 9],
                max: [9, 9, 8],
                to: [0; 3],
            },
            Op::Sphere {
                center: [f64::NAN, 0.0, 0.0],
                radius: 1.0,
                material: 1,
            },
            Op::Sphere {
                center: [0.0; 3],
                radius: -1.0,
                material: 1,
            },
            Op::Sphere {
                center: [0.0; 3],
                radius: f64::INFINITY,
                material: 1,
            },
            Op::Paint {
                center: [0.0, f64::INFINITY, 0.0],
                radius: 1.0,
                material: 1,
            },
            Op::FloodPaint {
                start: [64, 0, 0],
                material: 1,
                limit: 10,
            },
            Op::FloodPaint {
                start: [0, 0, 0],
                material: 1,
                limit: 10,
            },
            Op::Place {
                model: "nope".into(),
                at: [0; 3],
            },
            Op::DefineMaterial {
                id: 0,
                kind: MaterialKind::Diffuse,
                albedo: [0.5; 3],
                emission: 0.0,
                roughness: 0.0,
            },
            Op::DefineMaterial {
                id: 40000,
                kind: MaterialKind::Diffuse,
                albedo: [0.5; 3],
                emission: 0.0,
                roughness: 0.0,
            },
            Op::DefineMaterial {
                id: 4,
                kind: MaterialKind::Diffuse,
                albedo: [1.5, 0.0, 0.0],
                emission: 0.0,
                roughness: 0.0,
            },
            Op::DefineModel {
                name: String::new(),
                size: [1; 3],
                voxels: vec![],
            },
            Op::DefineModel {
                name: "x".repeat(65),
                size: [1; 3],
                voxels: vec![],
            },
            Op::DefineModel {
                name: "m".into(),
                size: [0, 1, 1],
                voxels: vec![],
            },
            Op::DefineModel {
                name: "m".into(),
                size: [128, 1, 1],
                voxels: vec![],
            },
            Op::DefineModel {
                name: "m".into(),
                size: [2, 2, 2],
                voxels: vec![[2, 0, 0, 1]],
            },
            Op::DefineModel {
                name: "m".into(),
                size: [2, 2, 2],
                voxels: vec![[0, -1, 0, 1]],
            },
            Op::DefineModel {
                name: "m".into(),
                size: [2, 2, 2],
                voxels: vec![[0, 0, 0, 20]],
            },
            Op::SpawnEntity {
                id: 1,
                model: "m".into(),
                pos: [0.0; 3],
                rot: [0.0, 0.0, 0.0, 1.0],
            },
            Op::MoveEntity {
                id: 1,
                pos: [0.0, f64::NAN, 0.0],
                rot: [0.0, 0.0, 0.0, 1.0],
            },
            Op::MoveEntity {
                id: 1,
                pos: [0.0; 3],
                rot: [0.0; 4],
            },
            Op::MoveEntity {
                id: 1,
                pos: [0.0; 3],
                rot: [1e300, 0.0, 0.0, 1.0],
            },
        ];
        for op in bad {
            let e = run(&op, &mut c).unwrap_err();
            assert!(matches!(e, EditError::Invalid { index: 3, .. }), "{op:?}: {e:?}");
            assert!(e.to_string().starts_with(&format!("op 3 ({})", op.name())), "{e}");
        }
        assert!(c.voxels().iter().all(|&v| v == 0));
    }

    #[test]
    fn limits() {
        let mut c = DenseCanvas::new(size());
        let mut mats = materials();
        let mut models = ModelTable::default();
        let small = Limits {
            max_ops: 2,
            max_set_voxels: 2,
            max_fill_volume: 1000,
            max_flood_limit: 50,
            max_model_voxels: 8,
        };
        let sq = |n: i64| ([0i64; 3], [n, n, n]);
        let over = [
            Op::Set {
                voxels: vec![[0, 0, 0, 1]; 3],
            },
            Op::Box {
                min: sq(11).0,
                max: sq(11).1,
                material: 1,
            },
            Op::Sphere {
                center: [5.0; 3],
                radius: 6.0,
                material: 1,
            },
            Op::Paint {
                center: [5.0; 3],
                radius: 6.0,
                material: 1,
            },
            Op::Copy {
                min: sq(11).0,
                max: sq(11).1,
                to: [20; 3],
            },
            Op::FloodPaint {
                start: [0; 3],
                material: 1,
                limit: 51,
            },
            Op::DefineModel {
                name: "m".into(),
                size: [3, 3, 1],
                voxels: vec![],
            },
            Op::DefineModel {
                name: "m".into(),
                size: [2, 2, 2],
                voxels: vec![[0, 0, 0, 1]; 9],
            },
        ];
        for op in &over {
            let e = op.apply(1, &mut c, &mut mats, &mut models, &small).unwrap_err();
            assert!(matches!(e, EditError::Limit { index: 1, .. }), "{op:?}: {e:?}");
            assert!(
                e.to_string().starts_with(&format!("op 1 ({}): over limit", op.name())),
                "{e}"
            );
        }
        assert!(c.voxels().iter().all(|&v| v == 0));
        // Exactly at the limit (clipped volume counts): fine.
        let ok = [
            Op::Set {
                voxels: vec![[0, 0, 0, 1]; 2],
            },
            Op::Box {
                min: sq(10).0,
                max: sq(10).1,
                material: 1,
            },
            Op::Box {
                min: [-100, -100, -100],
                max: [10, 10, 10],
                material: 1,
            },
            Op::Sphere {
                center: [0.0; 3],
                radius: 10.0,
                material: 1,
            },
            Op::Sphere {
                center: [5.0; 3],
                radius: 5.0,
                material: 1,
            },
            Op::Copy {
                min: [-50, -50, -50],
                max: [10, 10, 10],
                to: [20; 3],
            },
            Op::DefineModel {
                name: "m".into(),
                size: [2, 2, 2],
                voxels: vec![[0, 0, 0, 1]; 8],
            },
        ];
        for op in &ok {
            op.apply(1, &mut c, &mut mats, &mut models, &small).unwrap();
        }
        // A place over the fill limit.
        models.insert("big".into(), Model::new([11, 11, 11], vec![1; 1331]).unwrap());
        let e = Op::Place {
            model: "big".into(),
            at: [0; 3],
        }
        .apply(1, &mut c, &mut mats, &mut models, &small);
        assert!(matches!(e, Err(EditError::Limit { .. })), "{e:?}");
        Op::Place {
            model: "big".into(),
            at: [-1, -1, -1],
        }
        .apply(1, &mut c, &mut mats, &mut models, &small)
        .unwrap();
        // Too many ops.
        let batch = Batch {
            ops: vec![Op::DespawnEntity { id: 1 }; 3],
        };
        let e = apply_batch(&batch, &mut c, &mut mats, &mut models, &small).unwrap_err();
        assert!(matches!(e, EditError::Limit { index: 2, .. }), "{e:?}");
    }

    #[test]
    fn flood_limit_writes_nothing() {
        let mut c = DenseCanvas::new(size());
        run(
            &Op::Box {
                min: [0; 3],
                max: [10, 10, 10],
                material: 1,
            },
            &mut c,
        )
        .unwrap();
        let before = c.clone();
        let e = run(
            &Op::FloodPaint {
                start: [3, 3, 3],
                material: 2,
                limit: 999,
            },
            &mut c,
        )
        .unwrap_err();
        assert!(matches!(e, EditError::Limit { .. }), "{e:?}");
        assert!(e.to_string().contains("more than 999"), "{e}");
        assert!(c == before);
        run(
            &Op::FloodPaint {
                start: [3, 3, 3],
                material: 2,
                limit: 1000,
            },
            &mut c,
        )
        .unwrap();
        assert_eq!(c.voxels().iter().filter(|&&v| v == 2).count(), 1000);
        // Same material: a no-op, whatever the limit.
        run(
            &Op::FloodPaint {
                start: [3, 3, 3],
                material: 2,
                limit: 0,
            },
            &mut c,
        )
        .unwrap();
        // Erasing a region is allowed.
        run(
            &Op::FloodPaint {
                start: [3, 3, 3],
                material: 0,
                limit: 1000,
            },
            &mut c,
        )
        .unwrap();
        assert!(c.voxels().iter().all(|&v| v == 0));
    }

    #[test]
    fn copy_reads_before_writing() {
        // Overlapping shift by one along x: a row 1,2,3,... becomes 1,1,2,3,...
        let mut c = DenseCanvas::new(size());
        for x in 0..8 {
            c.set([x, 0, 0], (x % 9 + 1) as u16);
        }
        run(
            &Op::Copy {
                min: [0, 0, 0],
                max: [8, 1, 1],
                to: [1, 0, 0],
            },
            &mut c,
        )
        .unwrap();
        let row: Vec<u16> = (0..10).map(|x| c.get([x, 0, 0])).collect();
        assert_eq!(row, [1, 1, 2, 3, 4, 5, 6, 7, 8, 0]);
        // Extreme coordinates don't overflow; destinations outside the world are dropped.
        let before = c.clone();
        run(
            &Op::Copy {
                min: [i64::MIN; 3],
                max: [i64::MAX; 3],
                to: [i64::MAX; 3],
            },
            &mut c,
        )
        .unwrap();
        run(
            &Op::Copy {
                min: [i64::MIN, 0, 0],
                max: [i64::MAX, 1, 1],
                to: [0, 5, 5],
            },
            &mut c,
        )
        .unwrap();
        assert!(c == before);
        run(
            &Op::Copy {
                min: [-1, 0, 0],
                max: [5, 1, 1],
                to: [-3, 0, 0],
            },
            &mut c,
        )
        .unwrap();
        assert_eq!((0..6).map(|x| c.get([x, 0, 0])).collect::<Vec<_>>(), [2, 3, 4, 3, 4, 5]);
        let mut mats = materials();
        let mut models = ModelTable::default();
        let unlimited = Limits {
            max_fill_volume: u64::MAX,
            ..Limits::default()
        };
        Op::Copy {
            min: [i64::MIN, 0, 0],
            max: [i64::MAX, 1, 1],
            to: [i64::MAX, 5, 5],
        }
        .apply(0, &mut c, &mut mats, &mut models, &unlimited)
        .unwrap();
        Op::Copy {
            min: [-5, 0, 0],
            max: [3, 1, 1],
            to: [i64::MIN, 5, 5],
        }
        .apply(0, &mut c, &mut mats, &mut models, &unlimited)
        .unwrap();
    }

    #[test]
    fn tables_within_a_batch() {
        let mut c = DenseCanvas::new(size());
        let mut mats = MaterialTable::default();
        let mut models = ModelTable::default();
        let batch = Batch {
            ops: vec![
                Op::DefineMaterial {
                    id: 2,
                    kind: MaterialKind::Metal,
                    albedo: [0.9; 3],
                    emission: 0.0,
                    roughness: 0.3,
                },
                Op::DefineModel {
                    name: "pole".into(),
                    size: [1, 3, 1],
                    voxels: vec![[0, 0, 0, 2], [0, 2, 0, 2]],
                },
                Op::Place {
                    model: "pole".into(),
                    at: [5, 62, 5],
                },
            ],
        };
        apply_batch(&batch, &mut c, &mut mats, &mut models, &Limits::default()).unwrap();
        assert_eq!(mats.get(2).unwrap().kind, MaterialKind::Metal);
        assert!(mats.contains(1), "filler entry below the new id");
        assert_eq!(models.get("pole").unwrap().voxels(), &[2, 0, 2]);
        assert_eq!([c.get([5, 62, 5]), c.get([5, 63, 5])], [2, 0]);
        // A model whose material is unknown here can't be placed.
        let mut other = MaterialTable::default();
        let e = Op::Place {
            model: "pole".into(),
            at: [0; 3],
        }
        .apply(0, &mut c, &mut other, &mut models, &Limits::default());
        assert!(matches!(e, Err(EditError::Invalid { .. })), "{e:?}");
    }

    #[test]
    fn entity_ops_are_unsupported_here() {
        let mut c = DenseCanvas::new(size());
        let mut mats = materials();
        let mut models = ModelTable::default();
        models.insert("car".into(), Model::new([1, 1, 1], vec![1]).unwrap());
        for op in [
            Op::SpawnEntity {
                id: 1,
                model: "car".into(),
                pos: [1.0; 3],
                rot: [0.0, 0.0, 0.0, 2.0],
            },
            Op::MoveEntity {
                id: 1,
                pos: [-1.0; 3],
                rot: [0.1, 0.0, 0.0, 0.0],
            },
            Op::DespawnEntity { id: 1 },
        ] {
            assert!(op.is_entity_op());
            op.validate_entity(0, &models).unwrap();
            let e = op
                .apply(0, &mut c, &mut mats, &mut models, &Limits::default())
                .unwrap_err();
            assert!(matches!(e, EditError::Unsupported { .. }), "{e:?}");
            assert!(e.to_string().contains("entity ops are applied by the world"), "{e}");
        }
    }
}

//! Resolution of ops into voxel writes on a [`Canvas`] and table updates.

use super::{Batch, Canvas, EditError, Limits, MAX_QUOTED_CHARS, Op, clip_input};
use crate::cell::MAX_MATERIAL;
use crate::material::{Material, MaterialTable};
use crate::model::{MAX_MODEL_EDGE, Model, ModelTable};
use crate::size::WorldSize;
use rustc_hash::FxHashMap;

/// Longest model name, in bytes: checked when a line is parsed, for every op that names a
/// model (`place`, `spawn_entity`, `define_model`).
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

    /// Fails with an `Invalid` error if the op names a model by more than
    /// [`MAX_MODEL_NAME`] bytes. `index` is the op's position in its batch.
    pub fn check_model_name(&self, index: usize) -> Result<(), EditError> {
        let name = match self {
            Op::Place { model, .. } | Op::SpawnEntity { model, .. } => model,
            Op::DefineModel { name, .. } => name,
            _ => return Ok(()),
        };
        if name.len() <= MAX_MODEL_NAME {
            return Ok(());
        }
        Err(Ctx { index, op: self.name() }.invalid(format!(
            "model name '{}' is longer than {MAX_MODEL_NAME} bytes",
            clip_input(name, MAX_QUOTED_CHARS)
        )))
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
                    return Err(cx.invalid(format!(
                        "model '{}' is not defined",
                        clip_input(model, MAX_QUOTED_CHARS)
                    )));
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
                    return Err(cx.invalid(format!(
                        "model '{}' is not defined",
                        clip_input(model, MAX_QUOTED_CHARS)
                    )));
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
                self.check_model_name(index)?;
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

/// A sparse set of voxel positions: 8³ bricks of bits.
#[derive(Default)]
struct VoxelSet {
    bricks: FxHashMap<u64, [u64; 8]>,
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
    if name.is_empty() {
        return Err(cx.invalid(format!(
            "the model name is empty; it must be 1..={MAX_MODEL_NAME} bytes"
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

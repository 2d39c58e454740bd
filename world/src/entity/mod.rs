//! Dynamic entities (docs/OPS.md "Entities", docs/NAADF.md §11): rigid voxel models placed at
//! arbitrary positions and rotations on top of the voxel world.
//!
//! - An **entity type** is made from a model of the world's [`ModelTable`] the first time an
//!   entity of that model is spawned; types keep that order of first use (they are never
//!   removed, and a type follows its model if the model is redefined). A type is a dense
//!   grid of `u32` voxels, x fastest: solid = `0x8000_0000 | material`; empty = a 5-bit-per-
//!   direction AADF in the chunk layout (bits `5k`, order −x, +x, −y, +y, −z, +z), the lock-
//!   step field of the grid bounded by the grid ([`crate::aadf::grid_aadf`], 31 levels).
//!   Types are laid out one after the other in the **entity-type buffer**, each starting at
//!   a multiple of 64 voxels (`voxelStart` counts units of 64).
//! - An **instance** has an id (`0..=16382`; 16383 = `0x3FFF` is the GPU's "no entity"), a
//!   model, a position (world coordinates of the model's local-origin corner) and a rotation
//!   (unit quaternion `[x, y, z, w]`, local → world). The world keeps the **quantised**
//!   pose, exactly what the packed record decodes to ([`pack::quantise_pose`]), so every CPU
//!   test and every GPU mirror sees the same entity.
//! - The **instance buffer** holds each instance's packed 5-word record
//!   ([`pack::InstanceRecord`]) in the slot of its id (words `5·id .. 5·id + 5`); slots of
//!   ids without an entity are zero, and the buffer ends after the highest id's record. It
//!   is rebuilt after every batch that changes entities or models, so it is a pure
//!   function of the entity table, the type order and the models; a move rewrites just its
//!   entity's slot.
//! - The static world knows nothing of entities (a deviation from the reference, docs/
//!   NAADF.md §11): the chunk entity buffer stays zero and no distance field is cut around
//!   an instance. Rays find instances through a hierarchy over their world boxes
//!   ([`bvh::Bvh`]), which every machine derives from the instance buffer (`set.rs`) when
//!   it first traces a ray or uploads the hierarchy after a change, not at every batch.

pub(crate) mod bounds;
pub mod bvh;
pub mod local;
pub mod pack;
pub(crate) mod set;

pub use set::REFIT_SLACK;

use crate::aadf::grid_aadf;
use crate::cell::CHUNK_FIELD_BITS;
use crate::error::WorldError;
use crate::material::MaterialTable;
use crate::model::{MAX_MODEL_EDGE, Model, ModelTable};
use crate::ops::{EditError, Op};
use crate::size::WorldSize;
use bounds::world_box;
use pack::{InstanceRecord, MAX_VOXEL_START, RECORD_WORDS, quantise_pose};
use rustc_hash::FxHashMap;
use std::collections::BTreeMap;
use std::sync::{Arc, OnceLock};

/// Largest entity id (14 bits; `0x3FFF` means "no entity" on the GPU).
pub const MAX_ENTITY_ID: u32 = 0x3FFE;
/// Entity-type grids start at multiples of this many voxels.
pub const TYPE_ALIGN: usize = 64;
/// Padding of the world AABB of an instance, in voxels: absorbs rounding between the AABB
/// and the ray test's own transform.
const AABB_PAD: f64 = 1e-6;
/// Bit of a solid entity voxel.
pub const ENTITY_SOLID: u32 = 0x8000_0000;

/// The state of one entity: model and quantised pose.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Pose {
    /// Model name (its entity type).
    pub model: String,
    /// World position of the local-origin corner, a multiple of 1/128.
    pub pos: [f64; 3],
    /// Rotation `[x, y, z, w]` (local → world), as decoded from the packed record.
    pub rot: [f64; 4],
}

/// Everything that defines a world's entities: the entity types in order of first use
/// (model names) and the instances by id. The buffers are derived from it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EntityTable {
    /// Model names of the entity types, in type order.
    pub types: Vec<String>,
    /// Instances by id.
    pub instances: BTreeMap<u32, Pose>,
}

/// Longest model name an entity table stores (the model table's own bound).
const MAX_NAME_BYTES: usize = 4096;

impl EntityTable {
    /// Whether there are no types and no instances.
    pub fn is_empty(&self) -> bool {
        self.types.is_empty() && self.instances.is_empty()
    }

    /// Canonical little-endian bytes (the world file's entity section, docs/FORMAT.md):
    /// `u32` type count, then per type its model name (`u32` length, UTF-8); `u32`
    /// instance count, then per instance by ascending id: `u32` id, model name, 3 × `f64`
    /// position, 4 × `f64` rotation `[x, y, z, w]`.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::new();
        let name = |out: &mut Vec<u8>, n: &str| {
            out.extend_from_slice(&(n.len() as u32).to_le_bytes());
            out.extend_from_slice(n.as_bytes());
        };
        out.extend_from_slice(&(self.types.len() as u32).to_le_bytes());
        for t in &self.types {
            name(&mut out, t);
        }
        out.extend_from_slice(&(self.instances.len() as u32).to_le_bytes());
        for (id, p) in &self.instances {
            out.extend_from_slice(&id.to_le_bytes());
            name(&mut out, &p.model);
            for v in p.pos.iter().chain(&p.rot) {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        out
    }

    /// Inverse of [`EntityTable::encode`]; malformed bytes give a clear error (the values
    /// themselves are validated by [`crate::World::from_parts`]).
    pub fn decode(mut bytes: &[u8]) -> Result<Self, WorldError> {
        let bad = |what: String| WorldError::BadFile(format!("entity table: {what}"));
        fn take<'a>(n: usize, bytes: &mut &'a [u8]) -> Result<&'a [u8], WorldError> {
            if bytes.len() < n {
                return Err(WorldError::BadFile("entity table: truncated".into()));
            }
            let (a, b) = bytes.split_at(n);
            *bytes = b;
            Ok(a)
        }
        let u32_of = |bytes: &mut &[u8]| -> Result<u32, WorldError> {
            Ok(u32::from_le_bytes(take(4, bytes)?.try_into().expect("4 bytes")))
        };
        let name_of = |bytes: &mut &[u8]| -> Result<String, WorldError> {
            let len = u32_of(bytes)? as usize;
            if len > MAX_NAME_BYTES {
                return Err(bad(format!("model name of {len} bytes")));
            }
            String::from_utf8(take(len, bytes)?.to_vec()).map_err(|_| bad("model name is not UTF-8".into()))
        };
        let mut t = EntityTable::default();
        let types = u32_of(&mut bytes)?;
        for _ in 0..types {
            let n = name_of(&mut bytes)?;
            if t.types.contains(&n) {
                return Err(bad(format!("model '{n}' has two entity types")));
            }
            t.types.push(n);
        }
        let count = u32_of(&mut bytes)?;
        if count > MAX_ENTITY_ID + 1 {
            return Err(bad(format!("{count} instances (at most {})", MAX_ENTITY_ID + 1)));
        }
        for _ in 0..count {
            let id = u32_of(&mut bytes)?;
            if t.instances.last_key_value().is_some_and(|(&last, _)| last >= id) {
                return Err(bad(format!("instance ids not strictly ascending at {id}")));
            }
            let model = name_of(&mut bytes)?;
            let mut v = [0f64; 7];
            for x in &mut v {
                *x = f64::from_le_bytes(take(8, &mut bytes)?.try_into().expect("8 bytes"));
            }
            let pose = Pose {
                model,
                pos: [v[0], v[1], v[2]],
                rot: [v[3], v[4], v[5], v[6]],
            };
            t.instances.insert(id, pose);
        }
        if !bytes.is_empty() {
            return Err(bad(format!("{} bytes after the last instance", bytes.len())));
        }
        Ok(t)
    }
}

/// The entity table and the buffers derived from it.
#[derive(Clone, Debug, Default)]
pub(crate) struct Entities {
    pub table: EntityTable,
    /// Entity-type voxels (the entity-type buffer).
    pub type_voxels: Vec<u32>,
    /// Per type: `voxelStart` (units of 64 voxels).
    pub type_starts: Vec<u32>,
    /// The instance buffer: each instance's 5-word record in the slot of its id.
    pub instances: Vec<u32>,
    /// What a ray test reads of the instances, derived from `instances` when first asked
    /// for ([`Entities::set`]): a machine that only mirrors moves (a server, a CPU mirror)
    /// never pays for boxes and a hierarchy it does not trace.
    set: OnceLock<Arc<set::InstanceSet>>,
    /// The set last derived for an earlier instance buffer, if any: the one to refit.
    earlier: Option<Arc<set::InstanceSet>>,
}

/// The voxels of an entity type made from `model`.
pub fn type_grid(model: &Model) -> Vec<u32> {
    let s = model.size().map(|v| v as usize);
    let empty: Vec<bool> = model.voxels().iter().map(|&m| m == 0).collect();
    let fields = grid_aadf(s, &empty, 31, false);
    model
        .voxels()
        .iter()
        .zip(fields)
        .map(|(&m, f)| {
            if m != 0 {
                ENTITY_SOLID | u32::from(m)
            } else {
                f.pack(CHUNK_FIELD_BITS)
            }
        })
        .collect()
}

/// The packed instance hierarchy (docs/FORMAT.md §5.10) over the records of an instance
/// buffer `words`, whose leaves name the records' slots: what a device walks when its
/// instance buffer holds more than the world's records (local instances after them).
pub fn hierarchy_words(words: &[u32]) -> Vec<u32> {
    set::InstanceSet::of_buffer(words).hierarchy_words()
}

/// The padded world box of every live record of an instance buffer `words`, in slot
/// order: what the hierarchy is built over ([`bvh::Bvh::build`], or refitted to).
pub fn instance_boxes(words: &[u32]) -> Vec<bvh::Aabb> {
    set::InstanceSet::boxes_of(words)
}

/// The inclusive chunk range an instance of `size` at `pos`/`rot` overlaps, clipped to the
/// world; `None` if its AABB misses the world.
pub fn chunk_range(world: WorldSize, size: [u32; 3], pos: [f64; 3], rot: [f64; 4]) -> Option<([u32; 3], [u32; 3])> {
    let (lo, hi) = world_box(size, pos, rot);
    let dims = world.chunks();
    let mut out = ([0u32; 3], [0u32; 3]);
    for a in 0..3 {
        let a0 = ((lo[a] - AABB_PAD) / 16.0).floor();
        let a1 = ((hi[a] + AABB_PAD) / 16.0).floor();
        if a1 < 0.0 || a0 >= f64::from(dims[a]) {
            return None;
        }
        out.0[a] = a0.max(0.0) as u32;
        out.1[a] = a1.min(f64::from(dims[a] - 1)) as u32;
    }
    Some(out)
}

/// Why a set of entities cannot be laid out.
#[derive(Debug)]
pub(crate) struct LayoutError(pub String);

/// Validates an op's pose and returns the quantised one (values and packed words).
pub(crate) fn checked_pose(pos: [f64; 3], rot: [f64; 4]) -> Result<pack::Quantised, String> {
    let n2: f64 = rot.iter().map(|v| v * v).sum();
    if rot.iter().any(|v| !v.is_finite()) || !n2.is_finite() || n2 == 0.0 {
        return Err(format!("rot {rot:?} must be a non-zero finite quaternion [x,y,z,w]"));
    }
    quantise_pose(pos, rot).ok_or_else(|| {
        format!(
            "pos {pos:?} must lie in [0, 16384) × [0, 4096) × [0, 16384) once rounded to 1/128 voxel \
             (the packed entity position)"
        )
    })
}

/// Checks a model for use as an entity type: edges within 7 bits, materials defined.
pub(crate) fn check_model(name: &str, model: &Model, materials: &MaterialTable) -> Result<(), String> {
    if model.size().iter().any(|&e| e == 0 || e > MAX_MODEL_EDGE) {
        return Err(format!(
            "model '{name}' of size {:?} is too large for an entity",
            model.size()
        ));
    }
    let mut checked = 0u16;
    for &m in model.voxels() {
        if m != 0 && m != checked {
            if !materials.contains(m) {
                return Err(format!("model '{name}' uses material {m}, which is not defined"));
            }
            checked = m;
        }
    }
    Ok(())
}

impl Entities {
    /// Whether there is any instance (traversals test entities only then).
    #[inline]
    pub fn present(&self) -> bool {
        !self.table.instances.is_empty()
    }

    /// What a ray test reads of the instances: derived on the first call after the instance
    /// buffer changed, refitting the set derived last if it fits ([`set::InstanceSet::moved_to`]).
    pub fn set(&self) -> &set::InstanceSet {
        self.set.get_or_init(|| {
            Arc::new(match &self.earlier {
                Some(earlier) => earlier.moved_to(&self.instances),
                None => set::InstanceSet::of_buffer(&self.instances),
            })
        })
    }

    /// Derives every buffer for `table` from scratch (types made from `models`).
    pub fn build(table: EntityTable, models: &ModelTable) -> Result<Self, LayoutError> {
        Self::default().rebuild(table, &ModelTable::default(), models)
    }

    /// Derives the buffers for `table` and `models`, reusing the grids of this state's
    /// types whose model is unchanged (`old_models` are the models this state was built
    /// with).
    pub fn rebuild(
        &self,
        table: EntityTable,
        old_models: &ModelTable,
        models: &ModelTable,
    ) -> Result<Self, LayoutError> {
        // Types, in order, each at a multiple of 64 voxels.
        let mut type_voxels = Vec::new();
        let mut type_starts = Vec::with_capacity(table.types.len());
        let mut type_of: FxHashMap<&str, (u32, [u32; 3])> = FxHashMap::default();
        for (k, name) in table.types.iter().enumerate() {
            let model = models
                .get(name)
                .ok_or_else(|| LayoutError(format!("entity type {k}: model '{name}' is not defined")))?;
            if type_of.contains_key(name.as_str()) {
                return Err(LayoutError(format!("entity type {k}: model '{name}' has two types")));
            }
            let start = type_voxels.len() / TYPE_ALIGN;
            if start > MAX_VOXEL_START as usize {
                return Err(LayoutError(format!(
                    "the entity types need more than the {} voxels a 20-bit voxelStart can address",
                    (MAX_VOXEL_START as usize + 1) * TYPE_ALIGN
                )));
            }
            let n = model.voxels().len();
            let reuse = self.table.types.get(k) == Some(name) && old_models.get(name) == Some(model);
            if reuse {
                let at = self.type_starts[k] as usize * TYPE_ALIGN;
                type_voxels.extend_from_slice(&self.type_voxels[at..at + n]);
            } else {
                type_voxels.extend(type_grid(model));
            }
            type_voxels.resize(type_voxels.len().next_multiple_of(TYPE_ALIGN), 0);
            type_starts.push(start as u32);
            type_of.insert(name, (start as u32, model.size()));
        }
        // Each instance's record, in the slot of its id.
        let slots = table.instances.last_key_value().map_or(0, |(&id, _)| id as usize + 1);
        let mut instances = vec![0u32; slots * RECORD_WORDS];
        for (&id, pose) in &table.instances {
            let &(voxel_start, msize) = type_of
                .get(pose.model.as_str())
                .ok_or_else(|| LayoutError(format!("entity {id}: model '{}' has no entity type", pose.model)))?;
            let q = quantise_pose(pose.pos, pose.rot)
                .ok_or_else(|| LayoutError(format!("entity {id}: position {:?} out of range", pose.pos)))?;
            let record = InstanceRecord {
                id,
                size: msize,
                voxel_start,
                pos: q.fixed,
                inv_rot: q.inv_rot,
            };
            instances[id as usize * RECORD_WORDS..][..RECORD_WORDS].copy_from_slice(&record.pack());
        }
        Ok(Entities {
            table,
            type_voxels,
            type_starts,
            instances,
            set: OnceLock::new(),
            earlier: self.set.get().or(self.earlier.as_ref()).cloned(),
        })
    }
}

/// The models a batch has found fit for entities ([`check_model`]) since its model and
/// material tables last changed: a batch moving a thousand entities checks their model once.
#[derive(Default)]
pub(crate) struct FitModels(rustc_hash::FxHashSet<String>);

/// Applies one entity op (spawn, move, despawn) to a batch's working entity table.
///
/// Checks, besides [`Op::validate_entity`]: ids `0..=16382`; spawn needs a free id, move and
/// despawn an existing one; the model fits an entity (edges ≤ 127, defined materials); the
/// position, once rounded to 1/128 voxel, fits the packed record (`0 ≤ x, z < 16384`,
/// `0 ≤ y < 4096`); and the entity's world AABB touches the world (an entity entirely
/// outside could never be seen or hit, so placing it there is treated as a mistake).
pub(crate) fn apply_op(
    index: usize,
    op: &Op,
    table: &mut EntityTable,
    models: &ModelTable,
    materials: &MaterialTable,
    size: WorldSize,
    fit: &mut FitModels,
) -> Result<(), EditError> {
    op.validate_entity(index, models)?;
    let invalid = |reason: String| EditError::Invalid {
        index,
        op: op.name(),
        reason,
    };
    let id_ok = |id: u32| {
        if id > MAX_ENTITY_ID {
            Err(invalid(format!("entity id {id} outside 0..={MAX_ENTITY_ID}")))
        } else {
            Ok(())
        }
    };
    let mut place = |id: u32, model: &str, pos: [f64; 3], rot: [f64; 4]| -> Result<Pose, EditError> {
        let m = models
            .get(model)
            .ok_or_else(|| invalid(format!("model '{model}' is not defined")))?;
        if !fit.0.contains(model) {
            check_model(model, m, materials).map_err(invalid)?;
            fit.0.insert(model.to_owned());
        }
        let q = checked_pose(pos, rot).map_err(invalid)?;
        let (pos, rot) = (q.pos, q.rot);
        if chunk_range(size, m.size(), pos, rot).is_none() {
            return Err(invalid(format!(
                "entity {id} of model '{model}' at {pos:?} would lie entirely outside the {size} world"
            )));
        }
        Ok(Pose {
            model: model.to_owned(),
            pos,
            rot,
        })
    };
    match op {
        Op::SpawnEntity { id, model, pos, rot } => {
            id_ok(*id)?;
            if table.instances.contains_key(id) {
                return Err(invalid(format!("entity {id} already exists")));
            }
            let pose = place(*id, model, *pos, *rot)?;
            if !table.types.iter().any(|t| t == model) {
                table.types.push(model.clone());
            }
            table.instances.insert(*id, pose);
        }
        Op::MoveEntity { id, pos, rot } => {
            id_ok(*id)?;
            let Some(old) = table.instances.get(id) else {
                return Err(invalid(format!("entity {id} does not exist")));
            };
            let model = old.model.clone();
            let pose = place(*id, &model, *pos, *rot)?;
            table.instances.insert(*id, pose);
        }
        Op::DespawnEntity { id } => {
            id_ok(*id)?;
            if table.instances.remove(id).is_none() {
                return Err(invalid(format!("entity {id} does not exist")));
            }
        }
        _ => unreachable!("apply_op is called with entity ops only"),
    }
    Ok(())
}

//! [`LocalInstances`]: instances a client draws that are not in the world, such as the
//! preview of what a click would place or a marker of another user (docs/FORMAT.md §5.11).
//!
//! They use the packed record of world instances (§5.8) and the same entity-type grids, so
//! the shaders draw and hit them through the same hierarchy walk. What sets them apart:
//! - their models are **local**: kept here, outside the world's model and type tables;
//! - their records carry the id `0x3FFF`, the GPU's "no entity", so nothing that follows
//!   entity ids (picking, the GI's per-entity poses) mistakes one for an entity;
//! - a GPU mirror places their type grids and records after the world's, beyond the
//!   logical lengths it mirrors and digests, so the world's buffers stay byte for byte the
//!   server's;
//! - the CPU traversal, the raycast and picking never see them.

use super::pack::{InstanceRecord, MAX_VOXEL_START};
use super::{Pose, TYPE_ALIGN, check_model, checked_pose, type_grid};
use crate::material::MaterialTable;
use crate::model::Model;
use std::collections::BTreeMap;

/// The id field of every local instance record: the GPU's "no entity".
pub const LOCAL_ID: u32 = 0x3FFF;
/// The most local instances a set holds.
pub const MAX_LOCAL_INSTANCES: usize = 4096;

/// A client's local models and the local instances placed with them, by a caller-chosen
/// key.
///
/// ```
/// use naadf_world::entity::local::LocalInstances;
/// use naadf_world::material::{Material, MaterialTable};
/// use naadf_world::model::Model;
/// let materials = MaterialTable::from_materials(&[Material::diffuse([0.5; 3])]).unwrap();
/// let mut locals = LocalInstances::default();
/// locals.define_model("cursor", Model::new([1, 1, 1], vec![1]).unwrap(), &materials).unwrap();
/// locals.place(7, "cursor", [10.0, 20.0, 30.0], [0.0, 0.0, 0.0, 1.0]).unwrap();
/// let layout = locals.layout(128).unwrap();
/// // One record, whose type grid follows the world's 128 type voxels.
/// assert_eq!(layout.records.len(), 5);
/// assert_eq!(layout.type_voxels.len(), 64);
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LocalInstances {
    models: BTreeMap<String, Model>,
    instances: BTreeMap<u32, Pose>,
}

/// Where a set's type grids and records go on a device, after the world's own.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LocalLayout {
    /// The type grids of the models in use, each starting at a multiple of 64 voxels,
    /// to be placed at voxel `type_base` of the entity-type buffer.
    pub type_voxels: Vec<u32>,
    /// One packed record per instance, in key order.
    pub records: Vec<u32>,
}

impl LocalInstances {
    /// Defines (or redefines) local model `name`; its materials must be defined in
    /// `materials` and its edges at most 127, as for an entity type.
    pub fn define_model(&mut self, name: &str, model: Model, materials: &MaterialTable) -> Result<(), String> {
        check_model(name, &model, materials)?;
        self.models.insert(name.to_owned(), model);
        Ok(())
    }

    /// Places (or moves) the instance under `key`, with local model `model` at `pos`
    /// (its local-origin corner) rotated by `rot` (`[x, y, z, w]`, local → world). The pose
    /// is quantised as a world entity's is.
    pub fn place(&mut self, key: u32, model: &str, pos: [f64; 3], rot: [f64; 4]) -> Result<(), String> {
        if !self.models.contains_key(model) {
            return Err(format!("local model '{model}' is not defined"));
        }
        if !self.instances.contains_key(&key) && self.instances.len() >= MAX_LOCAL_INSTANCES {
            return Err(format!("at most {MAX_LOCAL_INSTANCES} local instances"));
        }
        let q = checked_pose(pos, rot)?;
        let pose = Pose {
            model: model.to_owned(),
            pos: q.pos,
            rot: q.rot,
        };
        self.instances.insert(key, pose);
        Ok(())
    }

    /// Removes the instance under `key`; whether there was one.
    pub fn remove(&mut self, key: u32) -> bool {
        self.instances.remove(&key).is_some()
    }

    /// Removes every instance whose key `keep` refuses.
    pub fn retain(&mut self, mut keep: impl FnMut(u32) -> bool) {
        self.instances.retain(|&k, _| keep(k));
    }

    /// The instance under `key`, with its quantised pose.
    pub fn get(&self, key: u32) -> Option<&Pose> {
        self.instances.get(&key)
    }

    /// How many instances there are.
    pub fn len(&self) -> usize {
        self.instances.len()
    }

    /// Whether there is no instance.
    pub fn is_empty(&self) -> bool {
        self.instances.is_empty()
    }

    /// Whether every model an instance uses is still fit for `materials` (a world may
    /// redefine its materials after a model was defined).
    pub fn fits(&self, materials: &MaterialTable) -> Result<(), String> {
        for (name, model) in &self.models {
            if self.instances.values().any(|p| &p.model == name) {
                check_model(name, model, materials)?;
            }
        }
        Ok(())
    }

    /// The type grids and records of the set, for a device whose world type grids take the
    /// first `type_base` voxels (a multiple of 64) of the entity-type buffer.
    pub fn layout(&self, type_base: usize) -> Result<LocalLayout, String> {
        debug_assert_eq!(type_base % TYPE_ALIGN, 0);
        let mut out = LocalLayout::default();
        let mut starts: BTreeMap<&str, u32> = BTreeMap::new();
        for pose in self.instances.values() {
            if starts.contains_key(pose.model.as_str()) {
                continue;
            }
            let start = (type_base + out.type_voxels.len()) / TYPE_ALIGN;
            if start > MAX_VOXEL_START as usize {
                return Err("the local models do not fit after the world's entity types".into());
            }
            out.type_voxels.extend(type_grid(&self.models[&pose.model]));
            out.type_voxels
                .resize(out.type_voxels.len().next_multiple_of(TYPE_ALIGN), 0);
            starts.insert(&pose.model, start as u32);
        }
        for pose in self.instances.values() {
            out.records
                .extend(self.record(pose, starts[pose.model.as_str()]).pack());
        }
        Ok(out)
    }

    /// The records of the instances that differ between `self` and `before` (added,
    /// removed, moved or of a redefined model), as they are in either: what a renderer's
    /// light history must forget. Their `voxel_start` is left zero.
    pub fn changed_since(&self, before: &LocalInstances) -> Vec<InstanceRecord> {
        let mut out = Vec::new();
        let same = |a: &LocalInstances, b: &LocalInstances, key: u32| {
            let (pa, pb) = (a.instances.get(&key), b.instances.get(&key));
            pa == pb && pa.is_none_or(|p| a.models.get(&p.model) == b.models.get(&p.model))
        };
        for (set, other) in [(self, before), (before, self)] {
            for (&key, pose) in &set.instances {
                if !same(set, other, key) {
                    out.push(set.record(pose, 0));
                }
            }
        }
        out
    }

    /// The record of `pose` with its type at `voxel_start`.
    fn record(&self, pose: &Pose, voxel_start: u32) -> InstanceRecord {
        let q = checked_pose(pose.pos, pose.rot).expect("a placed pose is valid");
        InstanceRecord {
            id: LOCAL_ID,
            size: self.models[&pose.model].size(),
            voxel_start,
            pos: q.fixed,
            inv_rot: q.inv_rot,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::entity::pack::RECORD_WORDS;

    fn materials() -> MaterialTable {
        MaterialTable::from_materials(&[crate::material::Material::diffuse([0.5; 3])]).unwrap()
    }

    fn cube(m: u16) -> Model {
        Model::new([2, 2, 2], vec![m; 8]).unwrap()
    }

    #[test]
    fn models_must_fit_and_poses_must_pack() {
        let materials = materials();
        let mut l = LocalInstances::default();
        assert!(l.define_model("bad", cube(200), &materials).is_err());
        assert!(l.place(0, "missing", [0.0; 3], [0.0, 0.0, 0.0, 1.0]).is_err());
        l.define_model("c", cube(1), &materials).unwrap();
        assert!(l.place(0, "c", [-5.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]).is_err());
        assert!(l.place(0, "c", [1.0, 2.0, 3.0], [0.0; 4]).is_err());
        l.place(0, "c", [1.0, 2.0, 3.0], [0.0, 0.0, 0.0, 1.0]).unwrap();
        assert_eq!(l.len(), 1);
    }

    #[test]
    fn the_layout_follows_the_world_types_and_shares_grids() {
        let materials = materials();
        let mut l = LocalInstances::default();
        l.define_model("c", cube(1), &materials).unwrap();
        l.define_model("unused", cube(1), &materials).unwrap();
        for k in 0..3 {
            l.place(k, "c", [f64::from(k) * 4.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0])
                .unwrap();
        }
        let layout = l.layout(640).unwrap();
        // One grid (the unused model takes none), after the world's 640 voxels.
        assert_eq!(layout.type_voxels.len(), 64);
        for r in layout.records.chunks(RECORD_WORDS) {
            let r = InstanceRecord::unpack(r);
            assert_eq!((r.id, r.voxel_start, r.size), (LOCAL_ID, 10, [2, 2, 2]));
        }
        assert_eq!(layout.records.len(), 3 * RECORD_WORDS);
    }

    #[test]
    fn changes_name_the_moved_removed_and_redefined_instances() {
        let materials = materials();
        let mut a = LocalInstances::default();
        a.define_model("c", cube(1), &materials).unwrap();
        a.place(1, "c", [0.0; 3], [0.0, 0.0, 0.0, 1.0]).unwrap();
        a.place(2, "c", [8.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]).unwrap();
        assert!(a.changed_since(&a.clone()).is_empty());
        let mut b = a.clone();
        b.place(2, "c", [9.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]).unwrap();
        // The new pose and the old one.
        let moved = b.changed_since(&a);
        assert_eq!(moved.len(), 2);
        assert_eq!(moved[0].pos[0], 9 * 128);
        assert_eq!(moved[1].pos[0], 8 * 128);
        let mut c = a.clone();
        c.remove(1);
        assert_eq!(c.changed_since(&a).len(), 1);
        let mut d = a.clone();
        d.define_model(
            "c",
            Model::new([2, 2, 2], vec![1, 0, 0, 0, 0, 0, 0, 1]).unwrap(),
            &materials,
        )
        .unwrap();
        assert_eq!(d.changed_since(&a).len(), 4);
    }
}

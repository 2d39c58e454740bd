//! Content-level undo records (docs/OPS.md, "Undo and redo"): what a batch overwrote, and the batch that puts
//! it back where nobody has changed it since.

use super::overlay::Touched;
use crate::entity::{EntityTable, Pose};
use crate::ops::{Batch, Op};
use crate::world::World;

/// What a batch overwrote: the voxels it changed, `(position, before, after)` in chunk
/// then voxel order, and the entities it changed, `(id, before, after)` by ascending id
/// (`None` = no entity with that id; poses are the quantised ones).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct UndoRecord {
    /// Changed voxels.
    pub voxels: Vec<([u32; 3], u16, u16)>,
    /// Changed entities.
    pub entities: Vec<(u32, Option<Pose>, Option<Pose>)>,
}

impl UndoRecord {
    /// The voxels that differ between the touched chunks' old and new content, and the
    /// entities that differ between the world's table and `entities` (the new table, if
    /// the batch changed entities).
    pub(crate) fn diff(world: &World, touched: &[Touched], entities: Option<&EntityTable>) -> Self {
        let mut voxels = Vec::new();
        for t in touched {
            let c = world.size().chunk_coords(t.index);
            for (k, (&before, &after)) in t.old.iter().zip(t.new.iter()).enumerate() {
                if before != after {
                    let k = k as u32;
                    voxels.push((
                        [c[0] * 16 + (k & 15), c[1] * 16 + (k >> 4 & 15), c[2] * 16 + (k >> 8)],
                        before,
                        after,
                    ));
                }
            }
        }
        let mut changed = Vec::new();
        if let Some(new) = entities {
            let old = &world.entity_table().instances;
            let ids: std::collections::BTreeSet<u32> = old.keys().chain(new.instances.keys()).copied().collect();
            for id in ids {
                let (a, b) = (old.get(&id), new.instances.get(&id));
                if a != b {
                    changed.push((id, a.cloned(), b.cloned()));
                }
            }
        }
        UndoRecord {
            voxels,
            entities: changed,
        }
    }

    /// Whether the batch changed no voxel and no entity.
    pub fn is_empty(&self) -> bool {
        self.voxels.is_empty() && self.entities.is_empty()
    }

    /// The undo batch: every voxel that still holds what this batch wrote gets its previous
    /// value back, and every entity still in the state this batch left it in gets its
    /// previous state back (despawn, spawn, or move; a changed model is a despawn then a
    /// spawn); voxels and entities changed since by anyone else are left alone. Applying it
    /// returns the record that redoes the batch.
    pub fn undo_batch(&self, world: &World) -> Batch {
        let voxels: Vec<[i64; 4]> = self
            .voxels
            .iter()
            .filter(|(p, _, after)| world.material_at(*p) == *after)
            .map(|&(p, before, _)| [i64::from(p[0]), i64::from(p[1]), i64::from(p[2]), i64::from(before)])
            .collect();
        let mut ops = if voxels.is_empty() {
            Vec::new()
        } else {
            vec![Op::Set { voxels }]
        };
        for (id, before, after) in &self.entities {
            if world.entity(*id) != after.as_ref() {
                continue;
            }
            let id = *id;
            match (before, after) {
                (None, None) => {}
                (None, Some(_)) => ops.push(Op::DespawnEntity { id }),
                (Some(b), Some(a)) if a.model == b.model => ops.push(Op::MoveEntity {
                    id,
                    pos: b.pos,
                    rot: b.rot,
                }),
                (Some(b), after) => {
                    if after.is_some() {
                        ops.push(Op::DespawnEntity { id });
                    }
                    ops.push(Op::SpawnEntity {
                        id,
                        model: b.model.clone(),
                        pos: b.pos,
                        rot: b.rot,
                    });
                }
            }
        }
        Batch { ops }
    }
}

//! Content-level undo records (BRIEF §4): what a batch overwrote, and the batch that puts
//! it back where nobody has changed it since.

use super::overlay::Touched;
use crate::ops::{Batch, Op};
use crate::world::World;

/// The voxels a batch changed: `(position, before, after)`, in chunk then voxel order.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct UndoRecord {
    /// Changed voxels.
    pub voxels: Vec<([u32; 3], u16, u16)>,
}

impl UndoRecord {
    /// The voxels that differ between the touched chunks' old and new content.
    pub(crate) fn diff(world: &World, touched: &[Touched]) -> Self {
        let mut voxels = Vec::new();
        for t in touched {
            let c = world.size().chunk_coords(t.index);
            for (k, (&before, &after)) in t.old.iter().zip(t.new.iter()).enumerate() {
                if before != after {
                    let k = k as u32;
                    voxels.push(([c[0] * 16 + (k & 15), c[1] * 16 + (k >> 4 & 15), c[2] * 16 + (k >> 8)], before, after));
                }
            }
        }
        UndoRecord { voxels }
    }

    /// Whether the batch changed no voxel.
    pub fn is_empty(&self) -> bool {
        self.voxels.is_empty()
    }

    /// The undo batch: every voxel that still holds what this batch wrote gets its previous
    /// value back; voxels changed since by anyone else are left alone. Applying it returns
    /// the record that redoes the batch.
    pub fn undo_batch(&self, world: &World) -> Batch {
        let voxels: Vec<[i64; 4]> = self
            .voxels
            .iter()
            .filter(|(p, _, after)| world.material_at(*p) == *after)
            .map(|&(p, before, _)| [i64::from(p[0]), i64::from(p[1]), i64::from(p[2]), i64::from(before)])
            .collect();
        Batch {
            ops: if voxels.is_empty() {
                Vec::new()
            } else {
                vec![Op::Set { voxels }]
            },
        }
    }
}

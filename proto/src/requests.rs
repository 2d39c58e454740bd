//! Entity RPC requests as edit batches: every request the server applies becomes one
//! [`Batch`] (one version), so the write-ahead log, undo and replays see only batches.

use crate::v1::{DespawnEntitiesRequest, EntityPose, EntitySpawn, MoveEntitiesRequest, SpawnEntitiesRequest};
use crate::{WireError, bad};
use naadf_world::ops::{Batch, Op};

/// The position and rotation of a wire pose, checked for length.
fn pose(p: &EntityPose) -> Result<([f64; 3], [f64; 4]), WireError> {
    let pos: [f64; 3] = p
        .pos
        .as_slice()
        .try_into()
        .map_err(|_| bad(format!("entity {}: pos needs 3 numbers, got {}", p.id, p.pos.len())))?;
    let rot: [f64; 4] = p.rot.as_slice().try_into().map_err(|_| {
        bad(format!(
            "entity {}: rot needs 4 numbers [x, y, z, w], got {}",
            p.id,
            p.rot.len()
        ))
    })?;
    Ok((pos, rot))
}

/// A `SpawnEntities` request as a batch of `spawn_entity` ops.
pub fn spawn_batch(r: &SpawnEntitiesRequest) -> Result<Batch, WireError> {
    let ops = r
        .entities
        .iter()
        .map(|s| {
            let p = s.pose.as_ref().ok_or_else(|| bad("spawn without a pose"))?;
            let (pos, rot) = pose(p)?;
            Ok(Op::SpawnEntity {
                id: p.id,
                model: s.model.clone(),
                pos,
                rot,
            })
        })
        .collect::<Result<_, WireError>>()?;
    Ok(Batch { ops })
}

/// A `MoveEntities` request as a batch of `move_entity` ops.
pub fn move_batch(r: &MoveEntitiesRequest) -> Result<Batch, WireError> {
    let ops = r
        .moves
        .iter()
        .map(|p| {
            let (pos, rot) = pose(p)?;
            Ok(Op::MoveEntity { id: p.id, pos, rot })
        })
        .collect::<Result<_, WireError>>()?;
    Ok(Batch { ops })
}

/// A `DespawnEntities` request as a batch of `despawn_entity` ops.
pub fn despawn_batch(r: &DespawnEntitiesRequest) -> Batch {
    Batch {
        ops: r.ids.iter().map(|&id| Op::DespawnEntity { id }).collect(),
    }
}

/// The wire pose of an entity.
pub fn entity_pose(id: u32, pos: [f64; 3], rot: [f64; 4]) -> EntityPose {
    EntityPose {
        id,
        pos: pos.to_vec(),
        rot: rot.to_vec(),
    }
}

/// A spawn request entry.
pub fn entity_spawn(id: u32, model: &str, pos: [f64; 3], rot: [f64; 4]) -> EntitySpawn {
    EntitySpawn {
        model: model.to_owned(),
        pose: Some(entity_pose(id, pos, rot)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_become_the_equivalent_ops() {
        let spawn = SpawnEntitiesRequest {
            entities: vec![entity_spawn(7, "car", [1.0, 2.0, 3.5], [0.0, 0.0, 0.0, 1.0])],
            client_seq: 1,
        };
        let b = spawn_batch(&spawn).unwrap();
        let line = b.to_json_line();
        assert_eq!(
            Batch::parse_line(r#"{"op":"spawn_entity","id":7,"model":"car","pos":[1,2,3.5],"rot":[0,0,0,1]}"#).unwrap(),
            b,
            "{line}"
        );
        let mv = MoveEntitiesRequest {
            moves: vec![entity_pose(7, [4.0, 5.0, 6.0], [0.0, 1.0, 0.0, 0.0])],
            client_seq: 2,
        };
        assert_eq!(
            move_batch(&mv).unwrap().ops,
            vec![Op::MoveEntity {
                id: 7,
                pos: [4.0, 5.0, 6.0],
                rot: [0.0, 1.0, 0.0, 0.0]
            }]
        );
        let de = DespawnEntitiesRequest {
            ids: vec![7, 8],
            client_seq: 3,
        };
        assert_eq!(despawn_batch(&de).ops.len(), 2);
    }

    #[test]
    fn malformed_poses_are_errors() {
        let mv = MoveEntitiesRequest {
            moves: vec![EntityPose {
                id: 1,
                pos: vec![1.0],
                rot: vec![0.0, 0.0, 0.0, 1.0],
            }],
            client_seq: 0,
        };
        assert!(move_batch(&mv).unwrap_err().to_string().contains("pos needs 3"));
        let spawn = SpawnEntitiesRequest {
            entities: vec![EntitySpawn {
                model: "m".into(),
                pose: None,
            }],
            client_seq: 0,
        };
        assert!(spawn_batch(&spawn).is_err());
    }
}

//! The compact, self-describing encoding of a change (what the server streams).
//!
//! Encoded with postcard (varints throughout). A batch that is a single `set` op travels as
//! binary voxels, so a one-voxel edit is about a dozen bytes; a batch of entity moves travels
//! as packed quantised poses, 15 bytes per entity ([`MOVE_BYTES`]); any other batch travels
//! as its canonical ops JSON, zstd-compressed when that is smaller. Growth steps travel as
//! explicit chunk writes.

use crate::entity::checked_pose;
use crate::entity::pack::{POS_SCALE, conjugate, decode_quat};
use crate::ops::{Batch, EditError, Op};
use serde::{Deserialize, Serialize};

/// Bytes of one packed move: the id (14 bits), the position in 1/128 voxel (21, 19 and 21
/// bits) and the packed inverse rotation (32 + 12 bits), 119 bits little-endian.
pub const MOVE_BYTES: usize = 15;

/// What a mirror needs to reproduce a change.
#[derive(Clone, Debug, PartialEq)]
pub enum Record {
    /// An edit batch, re-applied by the mirror through the same code path.
    Batch(Batch),
    /// Chunk cells written by background growth: `(chunk index, new cell)`.
    Chunks(Vec<(u32, u32)>),
}

/// JSON batches longer than this are zstd-compressed.
const COMPRESS_OVER: usize = 256;

#[derive(Serialize, Deserialize)]
enum Wire {
    Set(Header, Vec<[u32; 4]>),
    Json(Header, String),
    Zstd(Header, Vec<u8>),
    Chunks(Header, Vec<(u32, u32)>),
    Moves(Header, Vec<u8>),
}

#[derive(Serialize, Deserialize, Clone, Copy)]
struct Header {
    version: u64,
    growth_seq: u32,
    quiescent: bool,
}

/// A decoded change: its place in the version sequence and its record.
#[derive(Clone, Debug, PartialEq)]
pub struct Decoded {
    /// Version after the change.
    pub version: u64,
    /// Growth sub-step (0 for a batch).
    pub growth_seq: u32,
    /// Whether the world is quiescent after it.
    pub quiescent: bool,
    /// The record.
    pub record: Record,
}

impl Record {
    /// The record of an applied batch.
    pub fn of_batch(batch: &Batch) -> Record {
        Record::Batch(batch.clone())
    }

    /// Encodes the record with its version, growth step and quiescent flag.
    pub fn encode(&self, version: u64, growth_seq: u32, quiescent: bool) -> Vec<u8> {
        let h = Header {
            version,
            growth_seq,
            quiescent,
        };
        let wire = match self {
            Record::Chunks(w) => Wire::Chunks(h, w.clone()),
            Record::Batch(b) => match pack_moves(&b.ops) {
                Some(moves) => Wire::Moves(h, moves),
                None => match b.ops.as_slice() {
                    [Op::Set { voxels }]
                        if voxels
                            .iter()
                            .all(|v| v.iter().all(|&c| (0..=i64::from(u32::MAX)).contains(&c))) =>
                    {
                        Wire::Set(h, voxels.iter().map(|v| v.map(|c| c as u32)).collect())
                    }
                    _ => {
                        let json = b.to_json_line();
                        if json.len() > COMPRESS_OVER {
                            Wire::Zstd(h, zstd::bulk::compress(json.as_bytes(), 3).expect("in-memory zstd"))
                        } else {
                            Wire::Json(h, json)
                        }
                    }
                },
            },
        };
        postcard::to_allocvec(&wire).expect("in-memory postcard")
    }

    /// Decodes an encoded change, with a clear error for malformed bytes.
    pub fn decode(bytes: &[u8]) -> Result<Decoded, EditError> {
        let bad = |e: String| EditError::Parse(format!("change record: {e}"));
        let wire: Wire = postcard::from_bytes(bytes).map_err(|e| bad(e.to_string()))?;
        let (h, record) = match wire {
            Wire::Set(h, v) => (
                h,
                Record::Batch(Batch {
                    ops: vec![Op::Set {
                        voxels: v.iter().map(|p| p.map(i64::from)).collect(),
                    }],
                }),
            ),
            Wire::Json(h, s) => (h, Record::Batch(Batch::parse_line(&s)?)),
            Wire::Zstd(h, z) => {
                // Bounded: a record never expands past 64 MiB of JSON.
                let s = zstd::bulk::decompress(&z, 64 << 20).map_err(|e| bad(e.to_string()))?;
                (
                    h,
                    Record::Batch(Batch::parse_line(
                        &String::from_utf8(s).map_err(|e| bad(e.to_string()))?,
                    )?),
                )
            }
            Wire::Chunks(h, w) => (h, Record::Chunks(w)),
            Wire::Moves(h, m) => (h, Record::Batch(unpack_moves(&m).map_err(bad)?)),
        };
        Ok(Decoded {
            version: h.version,
            growth_seq: h.growth_seq,
            quiescent: h.quiescent,
            record,
        })
    }
}

/// A batch made only of entity moves, packed ([`MOVE_BYTES`] each) with the poses the world
/// will keep: quantising them again gives them back bit for bit, so the mirror that applies
/// the unpacked batch ends in the same state. `None` for any other batch, or a move whose
/// pose does not quantise (that batch was refused anyway).
fn pack_moves(ops: &[Op]) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(ops.len() * MOVE_BYTES);
    for op in ops {
        let Op::MoveEntity { id, pos, rot } = op else {
            return None;
        };
        let q = checked_pose(*pos, *rot).ok()?;
        if *id > 0x3FFF {
            return None;
        }
        let [x, y, z] = q.fixed.map(u128::from);
        let v = u128::from(*id)
            | x << 14
            | y << 35
            | z << 54
            | u128::from(q.inv_rot[0]) << 75
            | u128::from(q.inv_rot[1] & 0xFFF) << 107;
        out.extend_from_slice(&v.to_le_bytes()[..MOVE_BYTES]);
    }
    (!out.is_empty()).then_some(out)
}

/// The batch of moves [`pack_moves`] packed.
fn unpack_moves(bytes: &[u8]) -> Result<Batch, String> {
    if bytes.is_empty() || !bytes.len().is_multiple_of(MOVE_BYTES) {
        return Err(format!(
            "{} bytes of moves is not whole {MOVE_BYTES}-byte moves",
            bytes.len()
        ));
    }
    let ops = bytes
        .chunks_exact(MOVE_BYTES)
        .map(|m| {
            let mut b = [0u8; 16];
            b[..MOVE_BYTES].copy_from_slice(m);
            let v = u128::from_le_bytes(b);
            let bits = |at: u32, n: u32| (v >> at) as u32 & ((1u64 << n) - 1) as u32;
            let fixed = [bits(14, 21), bits(35, 19), bits(54, 21)];
            Op::MoveEntity {
                id: bits(0, 14),
                pos: fixed.map(|f| f64::from(f) / POS_SCALE),
                rot: conjugate(decode_quat([bits(75, 32), bits(107, 12)])),
            }
        })
        .collect();
    Ok(Batch { ops })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::entity::pack::quantise_pose;

    #[test]
    fn single_voxel_edit_is_tiny_and_roundtrips() {
        let b = Batch {
            ops: vec![Op::Set {
                voxels: vec![[1000, 300, 2000, 7]],
            }],
        };
        let r = Record::of_batch(&b);
        let bytes = r.encode(123_456, 0, false);
        assert!(bytes.len() <= 16, "{} bytes", bytes.len());
        let d = Record::decode(&bytes).unwrap();
        assert_eq!((d.version, d.growth_seq, d.quiescent, d.record), (123_456, 0, false, r));
        let g = Record::Chunks(vec![(5, 0x1234), (900_000, 0)]);
        assert_eq!(Record::decode(&g.encode(9, 2, true)).unwrap().record, g);
        assert!(Record::decode(&bytes[..bytes.len() - 1]).is_err());
        assert!(Record::decode(&[9, 9, 9]).is_err());
    }

    /// A batch of moves packs to 15 bytes per entity plus a small header, and unpacks to
    /// the quantised poses, which quantise to themselves.
    #[test]
    fn moves_pack_to_fifteen_bytes_each() {
        let mut rng = crate::raysets::SplitMix64(5);
        let ops: Vec<Op> = (0..1000)
            .map(|id| Op::MoveEntity {
                id: id * 16,
                pos: [rng.unit() * 16000.0, rng.unit() * 4000.0, rng.unit() * 16000.0],
                rot: [rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5, rng.unit() - 0.5],
            })
            .collect();
        let r = Record::of_batch(&Batch { ops: ops.clone() });
        let bytes = r.encode(u64::MAX, 0, true);
        assert!(bytes.len() <= 1000 * 16 + 32, "{} bytes", bytes.len());
        assert!(bytes.len() <= 1000 * MOVE_BYTES + 20, "{} bytes", bytes.len());
        let Record::Batch(back) = Record::decode(&bytes).unwrap().record else {
            panic!("not a batch");
        };
        for (a, b) in ops.iter().zip(&back.ops) {
            let (
                Op::MoveEntity { id, pos, rot },
                Op::MoveEntity {
                    id: id2,
                    pos: pos2,
                    rot: rot2,
                },
            ) = (a, b)
            else {
                panic!("not moves");
            };
            assert_eq!(id, id2);
            let q = quantise_pose(*pos, *rot).unwrap();
            assert_eq!((q.pos, q.rot), (*pos2, *rot2));
            let again = quantise_pose(*pos2, *rot2).unwrap();
            assert_eq!((again.fixed, again.inv_rot), (q.fixed, q.inv_rot));
        }
        // A move among other ops travels as JSON; truncated moves are an error.
        let mixed = Batch {
            ops: vec![ops[0].clone(), Op::DespawnEntity { id: 3 }],
        };
        assert!(
            matches!(Record::decode(&Record::of_batch(&mixed).encode(1, 0, false)).unwrap().record,
            Record::Batch(b) if b == mixed)
        );
        assert!(unpack_moves(&[0; 14]).is_err());
    }
}

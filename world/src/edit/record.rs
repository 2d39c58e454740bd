//! The compact, self-describing encoding of a change (what the server streams).
//!
//! Encoded with postcard (varints throughout). A batch that is a single `set` op travels as
//! binary voxels, so a one-voxel edit is about a dozen bytes; any other batch travels as its
//! canonical ops JSON, zstd-compressed when that is smaller. Growth steps travel as explicit
//! chunk writes.

use crate::ops::{Batch, EditError, Op};
use serde::{Deserialize, Serialize};

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
            Record::Batch(b) => match b.ops.as_slice() {
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
        };
        Ok(Decoded {
            version: h.version,
            growth_seq: h.growth_seq,
            quiescent: h.quiescent,
            record,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}

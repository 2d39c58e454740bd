//! Bit layouts of the three cell levels (docs/FORMAT.md §5, docs/NAADF.md §2).
//!
//! Chunk and block cells are `u32` with a 2-bit state in bits 30–31:
//! - `0` empty: bits 0–29 hold an AADF (six 5-bit fields for chunks, six 2-bit fields in
//!   bits 0–11 for blocks), in the order −x, +x, −y, +y, −z, +z;
//! - `1` uniform full: bits 0–14 hold the material;
//! - `2` mixed: bits 0–29 hold a pointer (chunks: index of 64 block cells in `blocks`;
//!   blocks: word index of a 32-word voxel group in `voxels`).
//!
//! Voxels are 16-bit, two per `u32` word (low half = even voxel). Bit 15 = solid with the
//! material in bits 0–14; an empty voxel holds a 2-bit-per-direction AADF in bits 0–11.

/// Voxels along one edge of a block or of a chunk's block grid (cells are 4³).
pub const EDGE: u32 = 4;
/// Cells in a 4³ cell array.
pub const CELLS: usize = 64;
/// Voxels along a chunk edge.
pub const CHUNK_EDGE: u32 = 16;
/// Voxels in one chunk (16³).
pub const CHUNK_VOXELS: usize = 4096;
/// Words in one voxel group (64 voxels, two per word).
pub const GROUP_WORDS: usize = 32;
/// Largest material id (15 bits). Id 0 means empty.
pub const MAX_MATERIAL: u16 = 0x7FFF;

/// Cell state in bits 30–31.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum State {
    /// Empty: the payload is an AADF.
    Empty,
    /// Uniformly full of one material.
    Full,
    /// Mixed: the payload points at the next level.
    Mixed,
}

/// Bit position of the 2-bit state of a chunk or block cell.
pub const STATE_SHIFT: u32 = 30;
/// State bits of an empty cell ([`State::Empty`]).
pub const STATE_EMPTY: u32 = 0;
/// State bits of a uniformly full cell ([`State::Full`]).
pub const STATE_FULL: u32 = 1;
/// State bits of a mixed cell ([`State::Mixed`]; 3 decodes as mixed too).
pub const STATE_MIXED: u32 = 2;
/// Mask of the 30-bit payload.
pub const PAYLOAD: u32 = (1 << STATE_SHIFT) - 1;

/// Decodes the state of a chunk or block cell. State 3 is never produced; it decodes as
/// mixed so that traversal treats it like the hardware does (bit 31 set).
#[inline]
pub fn state(cell: u32) -> State {
    match cell >> STATE_SHIFT {
        STATE_EMPTY => State::Empty,
        STATE_FULL => State::Full,
        _ => State::Mixed,
    }
}

/// A uniform cell of `material` (0 gives the empty cell with a zero AADF).
#[inline]
pub fn uniform(material: u16) -> u32 {
    if material == 0 { 0 } else { full(material) }
}

/// A full cell of `material` (1..=32767).
#[inline]
pub fn full(material: u16) -> u32 {
    (STATE_FULL << STATE_SHIFT) | u32::from(material & MAX_MATERIAL)
}

/// A mixed cell pointing at `ptr`.
#[inline]
pub fn mixed(ptr: u32) -> u32 {
    debug_assert!(ptr <= PAYLOAD);
    (STATE_MIXED << STATE_SHIFT) | ptr
}

/// Material of a full cell.
#[inline]
pub fn material(cell: u32) -> u16 {
    (cell & u32::from(MAX_MATERIAL)) as u16
}

/// Pointer of a mixed cell.
#[inline]
pub fn pointer(cell: u32) -> u32 {
    cell & PAYLOAD
}

/// The solid flag of a 16-bit voxel.
pub const VOXEL_SOLID: u16 = 0x8000;

/// A solid voxel of `material`, or the raw empty voxel 0 for material 0.
#[inline]
pub fn voxel(material: u16) -> u16 {
    if material == 0 {
        0
    } else {
        VOXEL_SOLID | (material & MAX_MATERIAL)
    }
}

/// Whether a 16-bit voxel is solid.
#[inline]
pub fn voxel_is_solid(v: u16) -> bool {
    v & VOXEL_SOLID != 0
}

/// Material of a 16-bit voxel (0 when empty).
#[inline]
pub fn voxel_material(v: u16) -> u16 {
    if voxel_is_solid(v) { v & MAX_MATERIAL } else { 0 }
}

/// Voxel `i` of the group starting at word `ptr`.
#[inline]
pub fn group_voxel(voxels: &[u32], ptr: usize, i: usize) -> u16 {
    (voxels[ptr + i / 2] >> ((i & 1) * 16)) as u16
}

/// Index of `(x, y, z)` inside a 4³ cell array.
#[inline]
pub fn index4(x: u32, y: u32, z: u32) -> usize {
    (x + 4 * y + 16 * z) as usize
}

/// Index of the voxel at chunk-local `(x, y, z)` in a 16³ raw chunk (x fastest).
#[inline]
pub fn index16(x: u32, y: u32, z: u32) -> usize {
    (x + 16 * y + 256 * z) as usize
}

/// One axis-aligned distance field: six extents in the order −x, +x, −y, +y, −z, +z.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Aadf(pub [u8; 6]);

impl Aadf {
    /// Unpacks six `bits`-wide fields from the low bits of `word`.
    #[inline]
    pub fn unpack(word: u32, bits: u32) -> Self {
        let mask = (1u32 << bits) - 1;
        let mut f = [0u8; 6];
        for (k, v) in f.iter_mut().enumerate() {
            *v = ((word >> (bits * k as u32)) & mask) as u8;
        }
        Aadf(f)
    }

    /// Packs the six fields, `bits` wide each, into the low bits of a word.
    #[inline]
    pub fn pack(self, bits: u32) -> u32 {
        self.0
            .iter()
            .enumerate()
            .fold(0, |w, (k, &v)| w | (u32::from(v) << (bits * k as u32)))
    }

    /// Field `dir` (0..6, order −x, +x, −y, +y, −z, +z) of a packed AADF.
    #[inline]
    pub fn field(word: u32, dir: usize, bits: u32) -> u32 {
        (word >> (bits * dir as u32)) & ((1 << bits) - 1)
    }
}

/// Bits per AADF field in a chunk cell (and in entity grids).
pub const CHUNK_FIELD_BITS: u32 = 5;
/// Bits per AADF field in block cells and voxels.
pub const CELL_FIELD_BITS: u32 = 2;
/// Largest chunk AADF field (in chunks).
pub const MAX_CHUNK_FIELD: u8 = 31;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aadf_pack_roundtrip_and_layout() {
        let a = Aadf([1, 2, 3, 4, 5, 31]);
        let w = a.pack(CHUNK_FIELD_BITS);
        assert_eq!(Aadf::unpack(w, CHUNK_FIELD_BITS), a);
        // +x of a chunk is bits 5..10, +z bits 25..30.
        assert_eq!((w >> 5) & 31, 2);
        assert_eq!((w >> 25) & 31, 31);
        assert_eq!(w >> 30, 0);
        let b = Aadf([3, 0, 1, 2, 3, 1]);
        let w = b.pack(CELL_FIELD_BITS);
        assert_eq!(w >> 12, 0);
        assert_eq!(Aadf::field(w, 3, CELL_FIELD_BITS), 2);
    }

    #[test]
    fn states_and_voxels() {
        assert_eq!(state(uniform(0)), State::Empty);
        assert_eq!(state(full(7)), State::Full);
        assert_eq!(material(full(32767)), 32767);
        assert_eq!(state(mixed(123)), State::Mixed);
        assert_eq!(pointer(mixed(PAYLOAD)), PAYLOAD);
        assert_eq!(voxel(5), 0x8005);
        assert_eq!(voxel_material(voxel(5)), 5);
        assert_eq!(voxel_material(0x0FFF), 0);
        let words = [0x8002_8001u32];
        assert_eq!(group_voxel(&words, 0, 0), 0x8001);
        assert_eq!(group_voxel(&words, 0, 1), 0x8002);
    }
}

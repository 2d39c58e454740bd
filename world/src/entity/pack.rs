//! The packed chunk-instance record (docs/FORMAT.md §5.8), exactly as the GPU reads it.
//!
//! A record is five `u32` words (`uint4` + `uint`, 20 bytes):
//!
//! ```text
//! d.x = posX (21 bits) | (posY & 0x7FF) << 21
//! d.y = posZ (21 bits) | (posY >> 11) (8 bits) << 21 | (size.z >> 4) (3 bits) << 29
//! d.z = quaternion word 0
//! d.w = quaternion word 1 (12 bits) | voxelStart << 12 (20 bits)
//! e   = id (14 bits) | size.x << 14 (7 bits) | size.y << 21 (7 bits) | (size.z & 0xF) << 28
//! ```
//!
//! Positions are fixed point at 1/128 voxel (x and z below 16384, y below 4096). The stored
//! quaternion is the **inverse** rotation (world → entity), in "smallest three" form: the
//! largest component (made positive) is dropped, the other three are stored in index order
//! as `clamp(int((v + 1)·8192 + 0.5), 0, 16383)`; `word0 = a | b << 14 | (c & 0xF) << 28`,
//! `word1 = (c >> 4) | maxIndex << 10`. Decoding gives `(s − 8192)/8192` for the three and
//! `sqrt(1 − a² − b² − c²)` for the dropped one. Components are in the order `[x, y, z, w]`.

/// Fixed-point scale of positions (1/128 voxel).
pub const POS_SCALE: f64 = 128.0;
/// Exclusive upper bound of a packed position per axis, in fixed-point units (21, 19, 21 bits).
pub const POS_LIMIT: [u32; 3] = [1 << 21, 1 << 19, 1 << 21];
/// Words per chunk-instance record.
pub const RECORD_WORDS: usize = 5;
/// Largest `voxelStart` (20 bits, in units of 64 voxels).
pub const MAX_VOXEL_START: u32 = (1 << 20) - 1;

/// One decoded chunk-instance record.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InstanceRecord {
    /// Entity id (14 bits).
    pub id: u32,
    /// Grid size of the entity type (each 1..=127).
    pub size: [u32; 3],
    /// Start of the type's voxels in the entity-type buffer, in units of 64 voxels.
    pub voxel_start: u32,
    /// Position of the local-origin corner in 1/128 voxels.
    pub pos: [u32; 3],
    /// The inverse rotation, packed ([`encode_quat`]).
    pub inv_rot: [u32; 2],
}

impl InstanceRecord {
    /// The five words of the record.
    pub fn pack(&self) -> [u32; RECORD_WORDS] {
        let [px, py, pz] = self.pos;
        let [sx, sy, sz] = self.size;
        [
            (px & 0x1F_FFFF) | (py & 0x7FF) << 21,
            (pz & 0x1F_FFFF) | (py >> 11 & 0xFF) << 21 | (sz >> 4 & 7) << 29,
            self.inv_rot[0],
            (self.inv_rot[1] & 0xFFF) | self.voxel_start << 12,
            (self.id & 0x3FFF) | (sx & 0x7F) << 14 | (sy & 0x7F) << 21 | (sz & 0xF) << 28,
        ]
    }

    /// Decodes five words (any bits; the inverse of [`InstanceRecord::pack`] for valid
    /// records).
    pub fn unpack(w: &[u32]) -> Self {
        let (dx, dy, dz, dw, e) = (w[0], w[1], w[2], w[3], w[4]);
        InstanceRecord {
            id: e & 0x3FFF,
            size: [e >> 14 & 0x7F, e >> 21 & 0x7F, (e >> 28 & 0xF) | (dy >> 29 & 7) << 4],
            voxel_start: dw >> 12,
            pos: [dx & 0x1F_FFFF, (dx >> 21) | (dy >> 21 & 0xFF) << 11, dy & 0x1F_FFFF],
            inv_rot: [dz, dw & 0xFFF],
        }
    }

    /// The position in voxels, as the GPU decodes it.
    pub fn position(&self) -> [f64; 3] {
        self.pos.map(|p| f64::from(p) / POS_SCALE)
    }

    /// The inverse rotation (world → entity), as decoded.
    pub fn inv_rotation(&self) -> [f64; 4] {
        decode_quat(self.inv_rot)
    }
}

/// Quantises a position to 1/128 voxel (round to nearest); `None` outside the packed range.
pub fn quantise_pos(pos: [f64; 3]) -> Option<[u32; 3]> {
    let mut out = [0u32; 3];
    for a in 0..3 {
        let n = (pos[a] * POS_SCALE).round();
        if !(n >= 0.0 && n < f64::from(POS_LIMIT[a])) {
            return None;
        }
        out[a] = n as u32;
    }
    Some(out)
}

/// Index of the component with the largest magnitude (the first one on ties).
fn largest(q: &[f64; 4]) -> usize {
    let mut k = 0;
    for i in 1..4 {
        if q[i].abs() > q[k].abs() {
            k = i;
        }
    }
    k
}

/// Packs the three small components and the index of the dropped one.
fn pack_small(s: [u32; 3], k: usize) -> [u32; 2] {
    [s[0] | s[1] << 14 | (s[2] & 0xF) << 28, s[2] >> 4 | (k as u32) << 10]
}

/// Smallest-three encoding of a non-zero quaternion (normalised here).
///
/// The encoding is chosen so that it is a fixed point: `encode_quat(decode_quat(w)) == w`
/// for every `w` this returns, which keeps a world's quantised poses stable when they are
/// stored and re-read, or re-sent as ops. Components are rounded to nearest as the
/// reference does; in the rare near-tie where the rebuilt largest component would no
/// longer be the largest, the small components are rounded toward zero instead (which
/// cannot shrink the rebuilt one), so the decoded quaternion encodes back to the same words.
pub fn encode_quat(q: [f64; 4]) -> [u32; 2] {
    let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    let k = largest(&q);
    let sign = if q[k] < 0.0 { -1.0 } else { 1.0 };
    let others: [usize; 3] = match k {
        0 => [1, 2, 3],
        1 => [0, 2, 3],
        2 => [0, 1, 3],
        _ => [0, 1, 2],
    };
    let v = others.map(|i| q[i] * sign / n);
    let nearest = v.map(|x| ((x + 1.0) * 8192.0 + 0.5).floor().clamp(0.0, 16383.0) as u32);
    let w = pack_small(nearest, k);
    if largest(&decode_quat(w)) == k {
        return w;
    }
    // Toward zero, then further toward zero while the rebuilt component is not the largest.
    let mut s = v.map(|x| {
        let m = (x.abs() * 8192.0).floor().min(8191.0) as u32;
        if x < 0.0 { 8192 - m } else { 8192 + m }
    });
    loop {
        let w = pack_small(s, k);
        let d = decode_quat(w);
        if largest(&d) == k {
            return w;
        }
        for (j, &i) in others.iter().enumerate() {
            if d[i].abs() >= d[k] {
                s[j] = if s[j] > 8192 { s[j] - 1 } else { s[j] + 1 };
            }
        }
    }
}

/// Decodes a smallest-three quaternion (unit length up to rounding).
pub fn decode_quat(w: [u32; 2]) -> [f64; 4] {
    let s = [w[0] & 0x3FFF, w[0] >> 14 & 0x3FFF, w[0] >> 28 | (w[1] & 0x3FF) << 4];
    let k = (w[1] >> 10 & 3) as usize;
    let small = s.map(|v| (f64::from(v) - 8192.0) / 8192.0);
    let rest = (1.0 - small.iter().map(|v| v * v).sum::<f64>()).max(0.0).sqrt();
    let mut q = [0.0; 4];
    let mut j = 0;
    for (i, c) in q.iter_mut().enumerate() {
        if i == k {
            *c = rest;
        } else {
            *c = small[j];
            j += 1;
        }
    }
    q
}

/// The conjugate (the inverse of a unit quaternion).
#[inline]
pub fn conjugate(q: [f64; 4]) -> [f64; 4] {
    [-q[0], -q[1], -q[2], q[3]]
}

/// Rotates `v` by the unit quaternion `q = [x, y, z, w]` (`q v q*`).
#[inline]
pub fn rotate(q: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let u = [q[0], q[1], q[2]];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let t = cross(u, v).map(|c| 2.0 * c);
    let ut = cross(u, t);
    [0, 1, 2].map(|a| v[a] + q[3] * t[a] + ut[a])
}

/// A pose as packed: the effective values and their packed forms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quantised {
    /// Position, a multiple of 1/128 voxel.
    pub pos: [f64; 3],
    /// Rotation `[x, y, z, w]` (local → world), as decoded from `inv_rot`.
    pub rot: [f64; 4],
    /// Position in 1/128 voxels.
    pub fixed: [u32; 3],
    /// The packed inverse rotation.
    pub inv_rot: [u32; 2],
}

/// The pose an entity effectively has once packed: the position rounded to 1/128 voxel and
/// the rotation as decoded from the record's inverse quaternion. `None` if the position is
/// outside the packed range. `rot` must be finite and non-zero.
///
/// Idempotent: quantising a quantised pose gives it back bit for bit.
pub fn quantise_pose(pos: [f64; 3], rot: [f64; 4]) -> Option<Quantised> {
    let fixed = quantise_pos(pos)?;
    let inv_rot = encode_quat(conjugate(rot));
    Some(Quantised {
        pos: fixed.map(|v| f64::from(v) / POS_SCALE),
        rot: conjugate(decode_quat(inv_rot)),
        fixed,
        inv_rot,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Rotation distance between two unit quaternions (0 when equal up to sign).
    fn distance(a: [f64; 4], b: [f64; 4]) -> f64 {
        let dot: f64 = (0..4).map(|i| a[i] * b[i]).sum();
        1.0 - dot.abs()
    }

    fn unit(q: [f64; 4]) -> [f64; 4] {
        let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        q.map(|v| v / n)
    }

    #[test]
    fn record_layout_is_the_reference_one() {
        let r = InstanceRecord {
            id: 0x1234,
            size: [127, 5, 0x5A],
            voxel_start: 0xABCDE,
            pos: [0x1F_FFFF, 0x7_FFFF, 3],
            inv_rot: [0xDEAD_BEEF, 0xFFF],
        };
        let w = r.pack();
        assert_eq!(w[0], 0x1F_FFFF | 0x7FF << 21);
        assert_eq!(w[1], 3 | 0xFF << 21 | 5 << 29);
        assert_eq!(w[2], 0xDEAD_BEEF);
        assert_eq!(w[3], 0xFFF | 0xABCDE << 12);
        assert_eq!(w[4], 0x1234 | 127 << 14 | 5 << 21 | 0xA << 28);
        assert_eq!(InstanceRecord::unpack(&w), r);
    }

    #[test]
    fn identity_and_axis_rotations_are_exact() {
        for q in [
            [0.0, 0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 0.0, 0.0, -1.0],
            [0.5, 0.5, 0.5, 0.5],
        ] {
            let d = decode_quat(encode_quat(q));
            assert!(distance(d, q) < 1e-15, "{q:?} → {d:?}");
        }
        // 90° about y maps +x to −z.
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let v = rotate([0.0, s, 0.0, s], [1.0, 0.0, 0.0]);
        assert!((v[0]).abs() < 1e-12 && (v[2] + 1.0).abs() < 1e-12, "{v:?}");
    }

    #[test]
    fn near_ties_still_encode_to_a_fixed_point() {
        let s = std::f64::consts::FRAC_1_SQRT_2;
        for q in [
            [s, s, 0.0, 0.0],
            [s, -s, 0.0, 0.0],
            [0.0, 0.0, s, s],
            [0.5, 0.5, 0.5, -0.5],
            [0.5000001, 0.5, 0.4999999, 0.5],
        ] {
            let w = encode_quat(q);
            let d = decode_quat(w);
            assert_eq!(encode_quat(d), w, "{q:?}");
            assert!(distance(unit(q), d) < 1e-7, "{q:?} → {d:?}");
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]

        #[test]
        fn quaternions_round_trip(q in prop::array::uniform4(-1.0f64..1.0), scale in 0.01f64..100.0) {
            prop_assume!(q.iter().map(|v| v * v).sum::<f64>() > 1e-6);
            let q = q.map(|v| v * scale);
            let w = encode_quat(q);
            let d = decode_quat(w);
            // Within three quantisation steps (3/8192) per component, up to sign, and a
            // fixed point. One step is the rounding; near a tie between the two largest
            // components the encoder moves the others further toward zero until the rebuilt
            // one is the largest, and the rebuilt one absorbs those moves.
            let u = unit(q);
            let sign = if (0..4).map(|i| u[i] * d[i]).sum::<f64>() < 0.0 { -1.0 } else { 1.0 };
            for i in 0..4 {
                prop_assert!((u[i] - sign * d[i]).abs() < 3.0 / 8192.0, "{:?} → {:?}", u, d);
            }
            prop_assert!(((0..4).map(|i| d[i] * d[i]).sum::<f64>() - 1.0).abs() < 1e-12);
            prop_assert_eq!(encode_quat(d), w);
            prop_assert_eq!(w[1] >> 12, 0);
        }

        #[test]
        fn records_round_trip(id in 0u32..16384, size in prop::array::uniform3(1u32..128), start in 0u32..(1 << 20),
                              pos in [0.0f64..16384.0, 0.0f64..4096.0, 0.0f64..16384.0],
                              q in prop::array::uniform4(-1.0f64..1.0)) {
            prop_assume!(q.iter().map(|v| v * v).sum::<f64>() > 1e-6);
            let Some(Quantised { pos: p, rot, fixed, inv_rot: inv }) = quantise_pose(pos, q) else {
                // Only positions that round up to the limit are refused.
                prop_assert!((0..3).any(|a| (pos[a] * 128.0).round() >= f64::from(POS_LIMIT[a])));
                return Ok(());
            };
            for a in 0..3 {
                prop_assert!((p[a] - pos[a]).abs() <= 0.5 / 128.0);
            }
            let r = InstanceRecord { id, size, voxel_start: start, pos: fixed, inv_rot: inv };
            let back = InstanceRecord::unpack(&r.pack());
            prop_assert_eq!(back, r);
            prop_assert_eq!(back.position(), p);
            prop_assert_eq!(conjugate(back.inv_rotation()), rot);
            prop_assert!(distance(unit(q), rot) < 1e-7);
            // Quantising the quantised pose changes nothing.
            let again = quantise_pose(p, rot).unwrap();
            prop_assert_eq!((again.pos, again.rot, again.fixed, again.inv_rot), (p, rot, fixed, inv));
            // The inverse really is the inverse.
            let v = [1.25, -3.5, 7.0];
            let back_v = rotate(back.inv_rotation(), rotate(rot, v));
            for a in 0..3 {
                prop_assert!((back_v[a] - v[a]).abs() < 1e-12);
            }
        }
    }
}

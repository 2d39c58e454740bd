//! [`Hybrid`]: a hybrid format `R(W³) G(L)` of the hybrid-voxel-formats paper (Arbore et
//! al.), built and traversed.
//!
//! The format is a list of two levels in one buffer of `u32` words: a raw grid of
//! `2^W × 2^W × 2^W` cells, each a word (0 when empty, else the word offset of its
//! sub-volume), over SVDAGs of depth `L` that go down to single voxels. A DAG node is a
//! child-mask word (bit `x + 2y + 4z` per non-empty child octant) followed by one word per
//! non-empty child, the offset of the child node; below side 2 a child is a voxel, one
//! terminating word (its colour; geometry only, so every voxel is the same word). Nodes are
//! deduplicated over the whole level: identical sub-volumes under different raw cells are
//! stored once (the paper's whole-level dedup, never larger).
//!
//! Bytes (docs/BASELINES.md) are the buffer's: 4 × (raw cells + Σ over distinct nodes of
//! (1 + children) + distinct voxels).
//!
//! The DAG levels of side 8 and up are the [`Svdag`]'s own (deduplicated per level already);
//! each distinct 4³ leaf of the SVDAG becomes a side-4 node over side-2 nodes, one per
//! distinct 2³ octant mask.

use super::svdag::Svdag;
use super::{GPU_HEADER_WORDS, MAX_REFS, Step, Tree, check_refs, mask_step, trace_tree};
use crate::WorldError;
use crate::traverse::{Hit, Ray};
use rayon::prelude::*;

/// A hybrid format `R(top³) G(dag)` of a world's static geometry.
#[derive(Clone, Debug)]
pub struct Hybrid {
    /// The world's size in voxels (rays enter and leave its box).
    size: [u32; 3],
    /// log2 of the raw grid's cells per side (`W`).
    top: u32,
    /// Depth of the DAGs under the raw cells (`L`): a raw cell spans `2^L` voxels a side.
    dag: u32,
    /// The GPU layout: the [header](GPU_HEADER_WORDS) (`top + dag`, `dag`, two reserved
    /// words), then the format's buffer, its offsets counted from the header's first word:
    /// the raw grid (cell `x + n·(y + n·z)`, `n = 2^top`), the DAG nodes level by level
    /// from side `2^dag` down to side 2, and the voxel word. The CPU walk reads the same
    /// words.
    words: Vec<u32>,
}

/// The hybrid formats the hybrid-formats paper found Pareto-optimal on every model at
/// 2048³, the two `naadf bench paper` measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum HybridFormat {
    /// `R(4³) G(7)`: 16³ raw cells over DAGs of depth 7.
    R4G7,
    /// `R(3³) G(8)`: 8³ raw cells over DAGs of depth 8.
    R3G8,
}

impl HybridFormat {
    /// Both formats.
    pub const ALL: [HybridFormat; 2] = [HybridFormat::R4G7, HybridFormat::R3G8];

    /// Its name in the paper's notation.
    pub fn name(self) -> &'static str {
        match self {
            HybridFormat::R4G7 => "R(4³)G(7)",
            HybridFormat::R3G8 => "R(3³)G(8)",
        }
    }

    /// `(W, L)`: log2 of the raw cells a side, and the DAGs' depth.
    pub fn split(self) -> (u32, u32) {
        match self {
            HybridFormat::R4G7 => (4, 7),
            HybridFormat::R3G8 => (3, 8),
        }
    }
}

/// The terminating word of a solid voxel (opaque white RGBA8: the structure holds
/// geometry only).
const VOXEL: u32 = u32::MAX;

impl Hybrid {
    /// Builds `R(top³) G(dag)` for the geometry of `svdag`. Fails when the format spans
    /// fewer voxels a side (`2^(top + dag)`) than the world's cube, when `dag < 3`, or when
    /// the buffer would exceed 32-bit offsets.
    ///
    /// ```
    /// use naadf_world::{World, preset::Preset, baselines::{Hybrid, Svdag}};
    /// let src = Preset::Test.source(None, 1).unwrap();
    /// let dag = Svdag::build(&World::build(&*src, &|_| {}).unwrap()).unwrap();
    /// let hybrid = Hybrid::build(&dag, 3, 8).unwrap();
    /// assert_eq!(hybrid.name(), "R(3³)G(8)");
    /// assert!(hybrid.bytes() > 4 * 8 * 8 * 8);
    /// ```
    pub fn build(svdag: &Svdag, top: u32, dag: u32) -> Result<Self, WorldError> {
        Self::build_within(svdag, top, dag, MAX_REFS)
    }

    /// Builds one of the paper's recommended formats (see [`Hybrid::build`]).
    pub fn of(svdag: &Svdag, format: HybridFormat) -> Result<Self, WorldError> {
        let (top, dag) = format.split();
        Self::build(svdag, top, dag)
    }

    /// [`Hybrid::build`] with at most `limit` words (tests reach the limit with small
    /// worlds).
    pub(crate) fn build_within(svdag: &Svdag, top: u32, dag: u32, limit: u64) -> Result<Self, WorldError> {
        let depth = svdag.depth;
        if dag < 3 || top > 10 {
            return Err(WorldError::Capacity(format!(
                "R({top}³) G({dag}): the DAGs need a depth of 3 or more and the raw grid at most 2^10 cells a side"
            )));
        }
        if depth > top + dag {
            return Err(WorldError::Capacity(format!(
                "R({top}³) G({dag}) spans {} voxels a side, less than the world's cube of {}",
                1u64 << (top + dag),
                1u64 << depth
            )));
        }
        // The SVDAG's levels of side 8 up to 2^min(depth, dag); the raw grid replaces those
        // above, and a DAG deeper than the world's cube starts with single-child nodes.
        let levels = &svdag.levels[svdag.levels.len() - svdag.levels.len().min(dag as usize - 2)..];
        let chain = dag.saturating_sub(depth) as usize;
        let (head, raw) = (GPU_HEADER_WORDS, 1usize << (3 * top));

        // Where everything goes: raw cells, chain nodes, the kept levels, the side-4 nodes
        // (one per SVDAG leaf), the side-2 nodes (one per distinct octant mask), the voxel.
        let mut at = head + raw + 2 * chain;
        let mut level_base = Vec::with_capacity(levels.len());
        for level in levels {
            level_base.push(at as u64);
            at += level.len();
        }
        // Each leaf's eight octant masks, once (in parallel: the one costly part).
        let octants: Vec<[u8; 8]> = svdag.leaves.par_iter().map(|&leaf| octant_masks(leaf)).collect();
        let mut side4 = Vec::with_capacity(octants.len());
        let mut side2 = [None::<u32>; 256];
        let mut side2_masks = Vec::new();
        let mut words_needed = at as u64;
        for o in &octants {
            side4.push(words_needed);
            words_needed += 1 + o.iter().filter(|&&m| m != 0).count() as u64;
        }
        for o in &octants {
            for &m in o.iter().filter(|&&m| m != 0) {
                if side2[usize::from(m)].is_none() {
                    side2[usize::from(m)] = Some(side2_masks.len() as u32);
                    side2_masks.push(m);
                }
            }
        }
        let side2_base = words_needed;
        let side2_at: Vec<u64> = side2_masks
            .iter()
            .scan(side2_base, |w, &m| {
                let here = *w;
                *w += 1 + u64::from(m.count_ones());
                Some(here)
            })
            .collect();
        let voxel_at = side2_base + side2_masks.iter().map(|&m| 1 + u64::from(m.count_ones())).sum::<u64>();
        check_refs(voxel_at + 1, limit, "a hybrid format's words")?;
        let (voxel_at, side2_base) = (voxel_at as u32, side2_base as u32);

        let mut words = vec![0u32; head + raw];
        words[..2].copy_from_slice(&[top + dag, dag]);
        // The raw cells: each the root of its sub-volume, found by descending the SVDAG from
        // its root; or the chain above the SVDAG's root in cell 0.
        let first = level_base[0] as u32;
        if chain > 0 {
            words[head] = (head + raw) as u32;
            for c in 0..chain {
                let next = if c + 1 == chain {
                    first
                } else {
                    (head + raw + 2 * (c + 1)) as u32
                };
                words.extend([1, next]);
            }
        } else {
            let above = depth - dag;
            let cells = 1u32 << above;
            for z in 0..cells {
                for y in 0..cells {
                    for x in 0..cells {
                        let p = [x, y, z].map(|v| i64::from(v) << dag);
                        let mut node = Some(0u32);
                        for l in 0..above as usize {
                            node = node.and_then(|n| {
                                let w = &svdag.levels[l][n as usize..];
                                match mask_step(w[0], p, depth - 1 - l as u32, |rank| w[1 + rank as usize]) {
                                    Step::Node(child) => Some(child),
                                    _ => None,
                                }
                            });
                        }
                        let n = 1usize << top;
                        let cell = x as usize + n * (y as usize + n * z as usize);
                        words[head + cell] = node.map_or(0, |o| first + o);
                    }
                }
            }
        }
        // The kept levels, references made absolute: word offsets into the next level, or
        // below side 8 leaf indices, now the side-4 nodes made from them.
        for (l, level) in levels.iter().enumerate() {
            let child_at = |r: u32| match level_base.get(l + 1) {
                Some(&b) => (b + u64::from(r)) as u32,
                None => side4[r as usize] as u32,
            };
            let mut i = 0;
            while i < level.len() {
                let children = level[i].count_ones() as usize;
                words.push(level[i]);
                words.extend(level[i + 1..=i + children].iter().map(|&r| child_at(r)));
                i += 1 + children;
            }
        }
        for masks in &octants {
            let mut mask = 0;
            let at = words.len();
            words.push(0);
            for (o, &m) in masks.iter().enumerate() {
                if m != 0 {
                    mask |= 1 << o;
                    words.push(side2_at[side2[usize::from(m)].unwrap() as usize] as u32);
                }
            }
            words[at] = mask;
        }
        debug_assert_eq!(words.len() as u32, side2_base);
        for &m in &side2_masks {
            words.push(u32::from(m));
            words.extend(std::iter::repeat_n(voxel_at, m.count_ones() as usize));
        }
        words.push(VOXEL);
        Ok(Hybrid {
            size: svdag.size,
            top,
            dag,
            words,
        })
    }

    /// The paper's named format this is, if it is one.
    pub fn format(&self) -> Option<HybridFormat> {
        HybridFormat::ALL
            .into_iter()
            .find(|f| f.split() == (self.top, self.dag))
    }

    /// The format's name in the paper's notation, e.g. `R(4³)G(7)`.
    pub fn name(&self) -> String {
        format!("R({}³)G({})", self.top, self.dag)
    }

    /// Bytes by the paper's count: the whole buffer (the GPU header is not counted).
    pub fn bytes(&self) -> u64 {
        4 * (self.words.len() - GPU_HEADER_WORDS) as u64
    }

    /// The format as one array of words for the GPU traversal (`shaders/hybrid.wgsl`):
    /// the header, then the buffer, offsets counted from the header's first word.
    pub fn gpu_words(&self) -> &[u32] {
        &self.words
    }

    /// The first solid voxel along `ray` (material 0: geometry only), with the voxel, face
    /// and `t` that `naadf` gives.
    pub fn trace(&self, ray: &Ray) -> Option<Hit> {
        trace_tree(self, ray)
    }
}

impl Tree for Hybrid {
    fn size(&self) -> [u32; 3] {
        self.size
    }

    /// The raw grid spans the format's whole cube; DAG level `l ≥ 1` has nodes of side
    /// `2^(dag + 1 − l)`.
    fn side_log(&self, level: usize) -> u32 {
        match level {
            0 => self.top + self.dag,
            l => self.dag + 1 - l as u32,
        }
    }

    fn step(&self, level: usize, node: u32, cell: [i64; 3]) -> Step {
        if level == 0 {
            let n = 1usize << self.top;
            let c = cell.map(|v| (v >> self.dag) as usize);
            return match self.words[GPU_HEADER_WORDS + c[0] + n * (c[1] + n * c[2])] {
                0 => Step::Empty(self.dag),
                root => Step::Node(root),
            };
        }
        let words = &self.words[node as usize..];
        mask_step(words[0], cell, self.dag - level as u32, |rank| words[1 + rank as usize])
    }
}

/// The eight 2³ octant masks of a 4³ leaf mask (bit `x + 4y + 16z`), in octant order (bit
/// `x + 2y + 4z` of the octant); bit `v` of a mask is voxel `x + 2y + 4z` of the octant.
fn octant_masks(leaf: u64) -> [u8; 8] {
    std::array::from_fn(|o| {
        let q = [o & 1, o >> 1 & 1, o >> 2 & 1].map(|b| 2 * b);
        (0..8).fold(0u8, |x, v| {
            let bit = (q[0] + (v & 1)) + 4 * (q[1] + (v >> 1 & 1)) + 16 * (q[2] + (v >> 2 & 1));
            x | ((leaf >> bit & 1) as u8) << v
        })
    })
}

//! MagicaVoxel `.vox` import (docs/CLI.md, "Formats"; docs/NAADF.md §13).
//!
//! Mapping:
//! - the scene graph (`nTRN`/`nGRP`/`nSHP`) is flattened at frame 0 (module `vox_graph`
//!   documents the rotation rules): transforms compose parent ∘ child, and a model of
//!   size `s` under the accumulated transform `(R, t)` (`R` the signed permutation of the
//!   `_r` byte, rows as stored) puts its voxel `p` on
//!   `floor(R·(p − floor(s/2) + ½) + t) = R·(p − floor(s/2)) + t − [row i of R is negative]`,
//!   as MagicaVoxel, ogt_vox and vengi do; hidden nodes and hidden layers are skipped; a
//!   file without a scene graph places every model with its voxel `p` at `p`;
//! - vox `(x, y, z)` → world `(x, z, y)` (z-up becomes y-up; this mirrors the scene);
//! - the scene's bounding box (the union of the placed models' boxes, after the swap) has
//!   its minimum corner moved to the world origin; the world size is that box rounded up
//!   to 64 voxels per axis;
//! - material id = the colour index stored in the XYZI chunk (1..=255); all 255 palette
//!   entries become materials 1..=255, colour `(c/255)^2.2`; a `MATL` of type `_emit`
//!   (or with no `_type`) and `_emit > 0` is emissive with strength
//!   `emit·(1+flux)²·5` (flux absent: 0), capped at the half-float maximum; every other
//!   material is diffuse;
//! - **overlaps**: placed models are painted in scene order (depth first, children in the
//!   listed order; file order without a scene graph) and a later model's solid voxels
//!   overwrite earlier ones; empty voxels never erase.
//!
//! Nothing dense of the whole scene is ever allocated: each used model keeps one dense
//! grid of its own size (≤ 256³ bytes, shared by all its placements), and a coarse index
//! of 64³-voxel cells lists the placements whose boxes touch each cell, so a chunk only
//! samples the few placements that overlap it.
//!
//! Robustness: every malformed input gives [`WorldError::Import`]. The container is
//! pre-scanned (chunk nesting is bounded: dot_vox parses nested chunks recursively and
//! would overflow the stack, which no `catch_unwind` can catch); model sizes, voxel
//! coordinates, scene-graph references, depth and fan-out, the scene extent and the total
//! size of the dense model grids are checked before anything is allocated from them; and
//! the dot_vox parse runs under `catch_unwind`, so a panic inside the parser (a bug we
//! cannot fix from here) becomes an import error rather than taking the caller down.

use super::vox_graph::{self, Placement, Transform};
use crate::build::ChunkSource;
use crate::cell::CHUNK_VOXELS;
use crate::error::WorldError;
use crate::material::{Material, MaterialKind, MaterialTable};
use crate::size::{MAX_SIZE, WorldSize};
use crate::world::World;
use dot_vox::DotVoxData;
use std::fmt;
use std::path::Path;

/// Largest model edge MagicaVoxel writes.
pub const MAX_VOX_MODEL_EDGE: u32 = 256;
/// Deepest chunk nesting accepted in the container (MagicaVoxel uses 2: MAIN and its
/// children).
const MAX_CHUNK_NESTING: usize = 8;
/// Largest total size of the dense model grids, in bytes (one byte per voxel).
const MAX_GRID_BYTES: u64 = 4 << 30;
/// Edge of a cell of the coarse placement index, in voxels.
const CELL: u32 = 64;
/// vox axis feeding each world axis.
const SWAP: [usize; 3] = [0, 2, 1];

/// One used model: dense colour indices (0 = empty), `x + sx·(y + sy·z)`.
#[derive(Clone)]
struct Grid {
    size: [u32; 3],
    voxels: Vec<u8>,
}

/// One placed model, in world axes relative to the scene's minimum corner.
#[derive(Clone, Copy, Debug)]
struct Instance {
    /// Index into `VoxScene::grids`.
    grid: u32,
    /// Box, inclusive.
    lo: [u32; 3],
    hi: [u32; 3],
    /// For each world axis: the model axis it runs along ...
    axis: [u8; 3],
    /// ... and whether it runs backwards (model coordinate 0 at `hi`).
    neg: [bool; 3],
}

impl Instance {
    /// Model coordinates of world voxel `w` (which must lie in the box).
    #[inline]
    fn local(&self, w: [u32; 3]) -> [u32; 3] {
        let mut p = [0; 3];
        for a in 0..3 {
            p[usize::from(self.axis[a])] = if self.neg[a] {
                self.hi[a] - w[a]
            } else {
                w[a] - self.lo[a]
            };
        }
        p
    }

    #[inline]
    fn contains(&self, w: [u32; 3]) -> bool {
        (0..3).all(|a| self.lo[a] <= w[a] && w[a] <= self.hi[a])
    }
}

/// Placements per coarse cell, in compressed rows, in scene order.
#[derive(Clone)]
struct CellIndex {
    dims: [u32; 3],
    offsets: Vec<u32>,
    entries: Vec<u32>,
}

impl CellIndex {
    fn build(extent: [u32; 3], instances: &[Instance]) -> Self {
        let dims = extent.map(|e| e.div_ceil(CELL).max(1));
        let n = dims.iter().map(|&d| d as usize).product::<usize>();
        let cell = |c: [u32; 3]| c[0] as usize + dims[0] as usize * (c[1] as usize + dims[1] as usize * c[2] as usize);
        let each = |inst: &Instance, f: &mut dyn FnMut(usize)| {
            let (lo, hi) = (inst.lo.map(|v| v / CELL), inst.hi.map(|v| v / CELL));
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    for x in lo[0]..=hi[0] {
                        f(cell([x, y, z]));
                    }
                }
            }
        };
        let mut offsets = vec![0u32; n + 1];
        for inst in instances {
            each(inst, &mut |c| offsets[c + 1] += 1);
        }
        // Counts sit one past their cell, so an inclusive running sum gives row starts.
        let mut acc = 0u32;
        for o in &mut offsets {
            acc += *o;
            *o = acc;
        }
        let mut fill = offsets.clone();
        let mut entries = vec![0u32; offsets[n] as usize];
        for (k, inst) in instances.iter().enumerate() {
            each(inst, &mut |c| {
                entries[fill[c] as usize] = k as u32;
                fill[c] += 1;
            });
        }
        Self { dims, offsets, entries }
    }

    /// Placements listed in the cell holding voxel `p`.
    #[inline]
    fn at(&self, p: [u32; 3]) -> &[u32] {
        let c = p.map(|v| v / CELL);
        let d = self.dims;
        let i = c[0] as usize + d[0] as usize * (c[1] as usize + d[1] as usize * c[2] as usize);
        &self.entries[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    /// Placements whose cells touch the box `lo..=hi`, in scene order, into `out`.
    fn collect(&self, lo: [u32; 3], hi: [u32; 3], out: &mut Vec<u32>) {
        out.clear();
        let (c0, c1) = (lo.map(|v| v / CELL), hi.map(|v| v / CELL));
        for z in c0[2]..=c1[2] {
            for y in c0[1]..=c1[1] {
                for x in c0[0]..=c1[0] {
                    out.extend_from_slice(self.at([x * CELL, y * CELL, z * CELL]));
                }
            }
        }
        if c0 != c1 {
            out.sort_unstable();
            out.dedup();
        }
    }
}

/// An imported MagicaVoxel scene: the placed models, ready to be sampled chunk by chunk.
///
/// As a [`ChunkSource`] it is the scene at the world origin in a world of
/// [`VoxScene::world_size`].
#[derive(Clone)]
pub struct VoxScene {
    extent: [u32; 3],
    size: WorldSize,
    materials: MaterialTable,
    grids: Vec<Grid>,
    instances: Vec<Instance>,
    cells: CellIndex,
}

impl fmt::Debug for VoxScene {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("VoxScene")
            .field("extent", &self.extent)
            .field("world_size", &self.size)
            .field("models", &self.grids.len())
            .field("instances", &self.instances.len())
            .finish()
    }
}

fn import_err(m: impl Into<String>) -> WorldError {
    WorldError::Import(m.into())
}

/// Checks the `VOX ` header and walks the chunk tree the way dot_vox will, refusing
/// nesting deeper than [`MAX_CHUNK_NESTING`] (dot_vox recurses once per level).
fn check_container(bytes: &[u8]) -> Result<(), WorldError> {
    if bytes.len() < 8 || &bytes[..4] != b"VOX " {
        return Err(import_err(
            "not a MagicaVoxel .vox file (it does not start with \"VOX \")",
        ));
    }
    fn walk(mut b: &[u8], depth: usize) -> Result<(), WorldError> {
        while b.len() >= 12 {
            let word = |i: usize| u32::from_le_bytes(b[i..i + 4].try_into().expect("4 bytes")) as usize;
            let (content, children) = (word(4), word(8));
            let rest = &b[12..];
            if content > rest.len() || children > rest.len() - content {
                break;
            }
            if children > 0 {
                if depth >= MAX_CHUNK_NESTING {
                    return Err(import_err(format!("chunks nested more than {MAX_CHUNK_NESTING} deep")));
                }
                walk(&rest[content..content + children], depth + 1)?;
            }
            b = &rest[content + children..];
        }
        Ok(())
    }
    walk(&bytes[8..], 0)
}

/// Runs the dot_vox parser, turning a panic inside it into an import error.
///
/// dot_vox promises not to panic, but it parses attacker-controlled bytes and some of its
/// helpers do assert (e.g. `Rotation::from_byte`); a bug there must not take a server
/// down, so the parse is isolated with `catch_unwind` as a last line of defence. (The
/// parser holds no state of ours, so unwinding out of it leaves nothing inconsistent.)
fn parse_guarded(bytes: &[u8]) -> Result<DotVoxData, WorldError> {
    match std::panic::catch_unwind(|| dot_vox::load_bytes(bytes)) {
        Ok(Ok(data)) => Ok(data),
        Ok(Err(e)) => Err(import_err(format!("malformed .vox file: {e}"))),
        Err(_) => Err(import_err("malformed .vox file: the MagicaVoxel parser failed on it")),
    }
}

/// Emission strength of a `MATL` entry, if it makes an emissive material.
fn emission(m: &dot_vox::Material) -> Option<f32> {
    match m.properties.get("_type").map(|s| s.trim()) {
        None | Some("_emit") => {}
        Some(_) => return None,
    }
    let emit = m.emission().filter(|e| e.is_finite())?;
    let flux = m.radiant_flux().filter(|f| f.is_finite()).unwrap_or(0.0).max(0.0);
    let s = emit * (1.0 + flux).powi(2) * 5.0;
    (s > 0.0).then(|| s.min(65504.0))
}

/// The 255 materials: palette entry `k − 1` (the RGBA chunk's `k`-th colour) is material
/// `k`. Missing palette entries take MagicaVoxel's default palette.
fn materials_of(data: &DotVoxData) -> Result<MaterialTable, WorldError> {
    let mats: Vec<Material> = (1..=255u32)
        .map(|k| {
            let i = k as usize - 1;
            let c = data
                .palette
                .get(i)
                .or_else(|| dot_vox::DEFAULT_PALETTE.get(i))
                .copied()
                .unwrap_or(dot_vox::Color {
                    r: 128,
                    g: 128,
                    b: 128,
                    a: 255,
                });
            let albedo = [c.r, c.g, c.b].map(|v| (f32::from(v) / 255.0).powf(2.2));
            // The last MATL for an id wins.
            match data.materials.iter().rev().find(|m| m.id == k).and_then(emission) {
                Some(e) => Material {
                    kind: MaterialKind::Emissive,
                    albedo,
                    emission: e,
                    roughness: 0.0,
                },
                None => Material::diffuse(albedo),
            }
        })
        .collect();
    MaterialTable::from_materials(&mats).map_err(|e| import_err(format!("palette gives an invalid material: {e}")))
}

/// Checks every model: sizes 1..=256 per axis, voxels inside their model.
fn check_models(data: &DotVoxData) -> Result<(), WorldError> {
    if data.models.is_empty() {
        return Err(import_err("the file holds no models"));
    }
    for (k, m) in data.models.iter().enumerate() {
        let s = [m.size.x, m.size.y, m.size.z];
        if s.contains(&0) {
            return Err(import_err(format!(
                "model {k} has zero size {}×{}×{}",
                s[0], s[1], s[2]
            )));
        }
        if s.iter().any(|&n| n > MAX_VOX_MODEL_EDGE) {
            return Err(import_err(format!(
                "model {k} is {}×{}×{}; MagicaVoxel models are at most {MAX_VOX_MODEL_EDGE} per axis",
                s[0], s[1], s[2]
            )));
        }
        if let Some(v) = m
            .voxels
            .iter()
            .find(|v| u32::from(v.x) >= s[0] || u32::from(v.y) >= s[1] || u32::from(v.z) >= s[2])
        {
            return Err(import_err(format!(
                "model {k}: voxel ({}, {}, {}) lies outside its size {}×{}×{}",
                v.x, v.y, v.z, s[0], s[1], s[2]
            )));
        }
    }
    Ok(())
}

/// Box (inclusive, vox axes) and per-vox-axis (model axis, reversed) of a placement.
fn placement_box(size: [u32; 3], xf: Option<Transform>) -> ([i64; 3], [i64; 3], [u8; 3], [bool; 3]) {
    let (mut lo, mut hi, mut axis, mut neg) = ([0i64; 3], [0i64; 3], [0u8; 3], [false; 3]);
    for i in 0..3 {
        match xf {
            None => {
                axis[i] = i as u8;
                hi[i] = i64::from(size[i]) - 1;
            }
            Some(xf) => {
                let m = xf.rot.col[i];
                let s = i64::from(size[usize::from(m)]);
                let pivot = s / 2;
                let t = xf.t[i];
                axis[i] = m;
                neg[i] = xf.rot.neg[i];
                // Voxel p lands on R·(p − pivot) + t, minus 1 on reversed rows.
                if neg[i] {
                    lo[i] = t + pivot - s;
                    hi[i] = t + pivot - 1;
                } else {
                    lo[i] = t - pivot;
                    hi[i] = t - pivot + s - 1;
                }
            }
        }
    }
    (lo, hi, axis, neg)
}

impl VoxScene {
    /// Imports a `.vox` file's bytes. Any malformed, hostile or unsupported input (bad
    /// header or chunks, model sizes of 0 or above 256, voxels outside their model, a
    /// broken scene graph, a scene larger than the largest world) gives
    /// [`WorldError::Import`] with a message saying what is wrong; never a panic.
    pub fn from_bytes(bytes: &[u8]) -> Result<VoxScene, WorldError> {
        check_container(bytes)?;
        let data = parse_guarded(bytes)?;
        Self::from_data(&data)
    }

    /// Reads and imports a `.vox` file (see [`VoxScene::from_bytes`]).
    pub fn open(path: &Path) -> Result<VoxScene, WorldError> {
        let bytes = std::fs::read(path).map_err(|e| WorldError::io(path.display().to_string(), e))?;
        Self::from_bytes(&bytes)
    }

    fn from_data(data: &DotVoxData) -> Result<VoxScene, WorldError> {
        check_models(data)?;
        let placements: Vec<Placement> = vox_graph::flatten(data).map_err(import_err)?;
        if placements.is_empty() {
            return Err(import_err("the scene places no visible models"));
        }

        // Boxes in world axes (before the shift), and the scene's bounding box.
        let mut boxes = Vec::with_capacity(placements.len());
        let (mut min, mut max) = ([i64::MAX; 3], [i64::MIN; 3]);
        for p in &placements {
            let m = &data.models[p.model];
            let (lo, hi, axis, neg) = placement_box([m.size.x, m.size.y, m.size.z], p.transform);
            let (lo, hi) = (SWAP.map(|v| lo[v]), SWAP.map(|v| hi[v]));
            for a in 0..3 {
                min[a] = min[a].min(lo[a]);
                max[a] = max[a].max(hi[a]);
            }
            boxes.push((lo, hi, SWAP.map(|v| axis[v]), SWAP.map(|v| neg[v])));
        }
        let ext: [i64; 3] = std::array::from_fn(|a| max[a] - min[a] + 1);
        if (0..3).any(|a| ext[a] > i64::from(MAX_SIZE[a])) {
            return Err(import_err(format!(
                "the scene is {}×{}×{} voxels (x, y up, z), larger than the largest world {}×{}×{}",
                ext[0], ext[1], ext[2], MAX_SIZE[0], MAX_SIZE[1], MAX_SIZE[2]
            )));
        }
        let extent = ext.map(|e| e as u32);
        let size =
            WorldSize::round_up(extent[0], extent[1], extent[2]).map_err(|e| import_err(format!("scene size: {e}")))?;

        // Dense grids of the used models, in order of first use, within a byte budget.
        let mut grid_of = vec![u32::MAX; data.models.len()];
        let mut used = Vec::new();
        let mut bytes = 0u64;
        for p in &placements {
            if grid_of[p.model] == u32::MAX {
                grid_of[p.model] = used.len() as u32;
                used.push(p.model);
                let s = &data.models[p.model].size;
                bytes += u64::from(s.x) * u64::from(s.y) * u64::from(s.z);
            }
        }
        if bytes > MAX_GRID_BYTES {
            return Err(import_err(format!(
                "the scene's models need {} MiB of voxel grids, more than the {} MiB allowed",
                bytes >> 20,
                MAX_GRID_BYTES >> 20
            )));
        }
        let grids = used
            .iter()
            .map(|&k| {
                let m = &data.models[k];
                let (sx, sy) = (m.size.x as usize, m.size.y as usize);
                let mut voxels = vec![0u8; sx * sy * m.size.z as usize];
                for v in &m.voxels {
                    // dot_vox reports the stored index minus one (saturating: 0 and 1 both
                    // read as 0); stored indices are 1..=255.
                    voxels[usize::from(v.x) + sx * (usize::from(v.y) + sy * usize::from(v.z))] = v.i.saturating_add(1);
                }
                Grid {
                    size: [m.size.x, m.size.y, m.size.z],
                    voxels,
                }
            })
            .collect();

        let instances: Vec<Instance> = placements
            .iter()
            .zip(boxes)
            .map(|(p, (lo, hi, axis, neg))| Instance {
                grid: grid_of[p.model],
                lo: std::array::from_fn(|a| (lo[a] - min[a]) as u32),
                hi: std::array::from_fn(|a| (hi[a] - min[a]) as u32),
                axis,
                neg,
            })
            .collect();
        let cells = CellIndex::build(extent, &instances);
        Ok(VoxScene {
            extent,
            size,
            materials: materials_of(data)?,
            grids,
            instances,
            cells,
        })
    }

    /// The scene's size in world axes (x, y up, z), after the axis swap.
    pub fn extent(&self) -> [u32; 3] {
        self.extent
    }

    /// The material table: the 255 palette entries as materials 1..=255.
    pub fn materials(&self) -> MaterialTable {
        self.materials.clone()
    }

    /// Number of placed models (after flattening the scene graph).
    pub fn instance_count(&self) -> usize {
        self.instances.len()
    }

    /// The material at world-axis voxel `p`, relative to the scene's minimum corner
    /// (0 = empty, and outside the extent).
    pub fn material_at(&self, p: [u32; 3]) -> u16 {
        if (0..3).any(|a| p[a] >= self.extent[a]) {
            return 0;
        }
        for &k in self.cells.at(p).iter().rev() {
            let inst = &self.instances[k as usize];
            if inst.contains(p) {
                let g = &self.grids[inst.grid as usize];
                let l = inst.local(p);
                let v =
                    g.voxels[l[0] as usize + g.size[0] as usize * (l[1] as usize + g.size[1] as usize * l[2] as usize)];
                if v != 0 {
                    return u16::from(v);
                }
            }
        }
        0
    }

    /// The world size: the extent rounded up to 64 per axis. (Scenes larger than the
    /// largest world are refused at import, so this does not fail for an imported scene.)
    pub fn world_size(&self) -> Result<WorldSize, WorldError> {
        Ok(self.size)
    }

    /// Whether no placement touches the box `lo..lo+dims` (scene coordinates).
    fn box_is_empty(&self, lo: [u32; 3], dims: [u32; 3], scratch: &mut Vec<u32>) -> bool {
        if dims.contains(&0) {
            return true;
        }
        let hi: [u32; 3] = std::array::from_fn(|a| lo[a] + dims[a] - 1);
        self.cells.collect(lo, hi, scratch);
        !scratch.iter().any(|&k| {
            let i = &self.instances[k as usize];
            (0..3).all(|a| i.lo[a] <= hi[a] && lo[a] <= i.hi[a])
        })
    }

    /// Paints the solid voxels of the scene box `src..src+dims` into chunk buffer `out`
    /// (`x + 16y + 256z`) at offset `dst`, placements in scene order.
    fn paint(
        &self,
        src: [u32; 3],
        dims: [u32; 3],
        dst: [u32; 3],
        out: &mut [u16; CHUNK_VOXELS],
        scratch: &mut Vec<u32>,
    ) {
        if dims.contains(&0) {
            return;
        }
        let hi: [u32; 3] = std::array::from_fn(|a| src[a] + dims[a] - 1);
        self.cells.collect(src, hi, scratch);
        for &k in scratch.iter() {
            let inst = &self.instances[k as usize];
            let a0: [u32; 3] = std::array::from_fn(|a| src[a].max(inst.lo[a]));
            let a1: [u32; 3] = std::array::from_fn(|a| hi[a].min(inst.hi[a]));
            if (0..3).any(|a| a0[a] > a1[a]) {
                continue;
            }
            let g = &self.grids[inst.grid as usize];
            let stride = [1isize, g.size[0] as isize, g.size[0] as isize * g.size[1] as isize];
            let step: [isize; 3] = std::array::from_fn(|a| {
                let s = stride[usize::from(inst.axis[a])];
                if inst.neg[a] { -s } else { s }
            });
            let l = inst.local(a0);
            let base = l[0] as isize + stride[1] * l[1] as isize + stride[2] * l[2] as isize;
            for z in a0[2]..=a1[2] {
                let iz = base + step[2] * (z - a0[2]) as isize;
                let oz = 256 * (dst[2] + z - src[2]) as usize;
                for y in a0[1]..=a1[1] {
                    let iy = iz + step[1] * (y - a0[1]) as isize;
                    let oy = oz + 16 * (dst[1] + y - src[1]) as usize;
                    for x in a0[0]..=a1[0] {
                        let v = g.voxels[(iy + step[0] * (x - a0[0]) as isize) as usize];
                        if v != 0 {
                            out[oy + (dst[0] + x - src[0]) as usize] = u16::from(v);
                        }
                    }
                }
            }
        }
    }

    /// The part of chunk `c` inside the extent: its scene origin and dimensions.
    fn chunk_box(&self, c: [u32; 3]) -> ([u32; 3], [u32; 3]) {
        let lo = c.map(|v| v * 16);
        let dims = std::array::from_fn(|a| self.extent[a].saturating_sub(lo[a]).min(16));
        (lo, dims)
    }
}

impl ChunkSource for VoxScene {
    fn size(&self) -> WorldSize {
        self.size
    }

    fn materials(&self) -> MaterialTable {
        self.materials.clone()
    }

    fn uniform_hint(&self, chunk: [u32; 3]) -> Option<u16> {
        let (lo, dims) = self.chunk_box(chunk);
        self.box_is_empty(lo, dims, &mut Vec::new()).then_some(0)
    }

    fn fill_chunk(&self, chunk: [u32; 3], out: &mut [u16; CHUNK_VOXELS]) {
        out.fill(0);
        let (lo, dims) = self.chunk_box(chunk);
        self.paint(lo, dims, [0; 3], out, &mut Vec::new());
    }
}

/// A scene repeated over a world: tiled along X and Z with period = the scene's extent,
/// once along Y (empty above the scene).
#[derive(Clone, Debug)]
pub struct TiledVox {
    scene: VoxScene,
    size: WorldSize,
}

impl TiledVox {
    /// Tiles `scene` over a world of `size`.
    pub fn new(scene: VoxScene, size: WorldSize) -> TiledVox {
        TiledVox { scene, size }
    }

    /// The tiled scene.
    pub fn scene(&self) -> &VoxScene {
        &self.scene
    }

    /// The runs `(chunk offset, scene coordinate, length)` covering the 16 voxels from
    /// world coordinate `start` along an axis of period `period`.
    fn runs(start: u32, period: u32) -> impl Iterator<Item = (u32, u32, u32)> {
        let mut done = 0u32;
        std::iter::from_fn(move || {
            (done < 16).then(|| {
                let s = (start + done) % period;
                let len = (period - s).min(16 - done);
                let run = (done, s, len);
                done += len;
                run
            })
        })
    }

    /// Calls `f(dst, src, dims)` for each piece of chunk `c` in scene coordinates.
    fn pieces(&self, c: [u32; 3], mut f: impl FnMut([u32; 3], [u32; 3], [u32; 3]) -> bool) {
        let e = self.scene.extent;
        let y0 = c[1] * 16;
        if y0 >= e[1] {
            return;
        }
        let dy = (e[1] - y0).min(16);
        for (oz, sz, lz) in Self::runs(c[2] * 16, e[2]) {
            for (ox, sx, lx) in Self::runs(c[0] * 16, e[0]) {
                if !f([ox, 0, oz], [sx, y0, sz], [lx, dy, lz]) {
                    return;
                }
            }
        }
    }
}

impl ChunkSource for TiledVox {
    fn size(&self) -> WorldSize {
        self.size
    }

    fn materials(&self) -> MaterialTable {
        self.scene.materials.clone()
    }

    fn uniform_hint(&self, chunk: [u32; 3]) -> Option<u16> {
        let mut scratch = Vec::new();
        let mut empty = true;
        self.pieces(chunk, |_, src, dims| {
            empty = self.scene.box_is_empty(src, dims, &mut scratch);
            empty
        });
        empty.then_some(0)
    }

    fn fill_chunk(&self, chunk: [u32; 3], out: &mut [u16; CHUNK_VOXELS]) {
        out.fill(0);
        let mut scratch = Vec::new();
        self.pieces(chunk, |dst, src, dims| {
            self.scene.paint(src, dims, dst, out, &mut scratch);
            true
        });
    }
}

/// Imports a `.vox` file into a [`World`] (the CLI's `import`); `progress` receives the
/// number of chunks built so far.
pub fn import_vox(path: &Path, progress: &(dyn Fn(u64) + Sync)) -> Result<World, WorldError> {
    let scene = VoxScene::open(path)?;
    World::build(&scene, progress)
}

#[cfg(test)]
mod tests {
    use super::*;
    use dot_vox::{Model, Size, Voxel};

    fn data(models: Vec<Model>) -> DotVoxData {
        DotVoxData {
            version: 150,
            index_map: dot_vox::DEFAULT_INDEX_MAP.to_vec(),
            models,
            palette: dot_vox::DEFAULT_PALETTE.to_vec(),
            materials: vec![],
            scenes: vec![],
            layers: vec![],
        }
    }

    #[test]
    fn axis_swap_without_scene_graph() {
        let m = Model {
            size: Size { x: 3, y: 5, z: 7 },
            voxels: vec![
                Voxel { x: 2, y: 0, z: 0, i: 0 },
                Voxel { x: 0, y: 4, z: 1, i: 9 },
                Voxel {
                    x: 1,
                    y: 2,
                    z: 6,
                    i: 254,
                },
            ],
        };
        let s = VoxScene::from_data(&data(vec![m])).unwrap();
        assert_eq!(s.extent(), [3, 7, 5]);
        assert_eq!(s.material_at([2, 0, 0]), 1);
        assert_eq!(s.material_at([0, 1, 4]), 10);
        assert_eq!(s.material_at([1, 6, 2]), 255);
        assert_eq!(s.material_at([0, 4, 1]), 0);
        assert_eq!(s.material_at([9, 9, 9]), 0);
    }

    #[test]
    fn placement_boxes_follow_pivot_and_reversal() {
        let r = |b| {
            Some(Transform {
                rot: vox_graph::Rotation::from_byte(b).unwrap(),
                t: [0; 3],
            })
        };
        // Even and odd sizes, identity: pivot floor(s/2) at the origin.
        assert_eq!(placement_box([4, 3, 1], r(4)).0, [-2, -1, 0]);
        assert_eq!(placement_box([4, 3, 1], r(4)).1, [1, 1, 0]);
        // Mirror every axis (signs on all rows): even sizes keep their box, odd ones
        // move down by one, as floor(R·(p − pivot + ½)) gives.
        let (lo, hi, axis, neg) = placement_box([4, 3, 1], r(4 | 0x70));
        assert_eq!((lo, hi, axis, neg), ([-2, -2, -1], [1, 0, -1], [0, 1, 2], [true; 3]));
    }
}

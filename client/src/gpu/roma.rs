//! [`Roma`]: `--mode roma` on the GPU (docs/RENDERING.md §3d). Diffuse surfaces are lit
//! through ROMA visibility ([`crate::light::roma`] states the rules; `shaders/roma.wgsl`
//! walks the maps, `shaders/roma_build.wgsl` writes them); mirrors and metals are traced as
//! the baseline traces them, and the frames are accumulated by the baseline's TAA.
//!
//! The maps live in one storage buffer: per map and level a window of
//! [`WINDOW_TILE_COUNT`] tiles of [`TILE_WORDS`] words, a tile kept in the slot of its
//! coordinates modulo the window's edge. A frame rebuilds only what changed: the tiles a
//! window gained as the camera moved, the tiles over the chunks the world changed in since
//! the last frame (edits and entity moves alike), the sun's map when the sun moved, and
//! everything only when the directions or the world's size change.

use super::baseline::Baseline;
use super::context::{Gpu, GpuError};
use super::params::{RomaInfo, RomaJob, RomaWindow, WgslStruct};
use super::pathtrace::PATHTRACE;
use super::pipeline::PassPipelines;
use super::shaders::{LIGHT, PassSource, SAMPLE, WgslValue, constants};
use super::shot::Shot;
use super::temporal::Temporal;
use super::world::GpuWorld;
use crate::light::hdr::Radiance;
use crate::light::roma::{
    CELL, LEVELS, MAX_COLUMNS, MapFrame, ORIGIN_OFFSET, REACH, RomaOptions, TILE, TILE_WORDS, WINDOW_TILE_COUNT,
    WINDOW_TILES, map_frames, window_base,
};
use crate::light::{Light, Sun};
use glam::{DVec3, IVec3};
use naadf_world::fingerprint::ChunkChanges;
use std::collections::BTreeSet;
use wgpu::util::DeviceExt;

/// `shaders/roma.wgsl`: the maps' walk and the diffuse tier.
const ROMA: &str = include_str!("../../../shaders/roma.wgsl");
/// `shaders/roma_build.wgsl`: writing tiles.
const ROMA_BUILD: &str = include_str!("../../../shaders/roma_build.wgsl");

/// Bytes of one tile.
const TILE_BYTES: u64 = TILE_WORDS as u64 * 4;

// The shaders find a tile and a column with shifts and masks.
const _: () = assert!(TILE == 32 && WINDOW_TILES.count_ones() == 1 && TILE_WORDS.is_multiple_of(64));
const _: () = assert!(CELL[0] == 1.0 && CELL[1] == 4.0 && CELL[2] == 16.0);

/// The constants and structs both ROMA passes share with the Rust code.
fn generated() -> String {
    let list = [
        ("ROMA_LEVELS", WgslValue::U32(LEVELS as u32)),
        ("ROMA_TILE", WgslValue::I32(TILE)),
        ("ROMA_TILE_SHIFT", WgslValue::U32(TILE.trailing_zeros())),
        ("ROMA_TILE_WORDS", WgslValue::U32(TILE_WORDS as u32)),
        ("ROMA_WINDOW_TILES", WgslValue::U32(WINDOW_TILES as u32)),
        ("ROMA_REACH", WgslValue::F32(REACH as f32)),
        ("ROMA_MAX_COLUMNS", WgslValue::U32(MAX_COLUMNS)),
        ("ROMA_FAR", WgslValue::F32(1e30)),
    ];
    constants(&list) + &RomaInfo::wgsl() + &RomaWindow::wgsl() + &RomaJob::wgsl()
}

/// The ROMA sample pass: the path tracer's `path_sample` with [`ROMA`] as its diffuse
/// tier.
pub(crate) fn roma_sample_pass() -> PassSource {
    PassSource {
        entry: "path_sample",
        files: &[SAMPLE, LIGHT, ROMA, PATHTRACE],
        generated: generated(),
    }
}

/// The tile-writing pass.
pub(crate) fn roma_build_pass() -> PassSource {
    PassSource {
        entry: "roma_build",
        files: &[ROMA_BUILD],
        generated: generated(),
    }
}

/// The maps on the device and what they were built for.
struct Maps {
    options: RomaOptions,
    /// The sun the sun's map is aligned with.
    sun: Option<Sun>,
    size: [u32; 3],
    frames: Vec<MapFrame>,
    /// Per map and level (`map · LEVELS + level`), as the device holds them.
    windows: Vec<RomaWindow>,
    windows_buffer: wgpu::Buffer,
    bits: wgpu::Buffer,
    /// The world's generation the tiles show.
    generation: u64,
}

/// The ROMA renderer.
pub struct Roma {
    build: PassPipelines,
    frames: Baseline,
    options: RomaOptions,
    maps: Option<Maps>,
    /// Tiles written by the last frame (for benchmarks and tests).
    last_jobs: usize,
}

impl Roma {
    /// Prepares the passes (pipelines are built on first use).
    pub fn new(gpu: &Gpu) -> Self {
        Roma {
            build: PassPipelines::new(gpu, roma_build_pass(), 0, &[true, true, false]),
            frames: Baseline::with_sample_pass(gpu, roma_sample_pass(), &[true, true, true]),
            options: RomaOptions::default(),
            maps: None,
            last_jobs: 0,
        }
    }

    /// Sets the directions and the AO range of the next frames (checked then).
    pub fn set_options(&mut self, options: RomaOptions) {
        self.options = options;
    }

    /// Forgets the maps: the next frame allocates them again and writes every tile (what a
    /// benchmark times as a whole build).
    pub fn forget_maps(&mut self) {
        self.maps = None;
    }

    /// The tiles the last frame wrote.
    pub fn tiles_written(&self) -> usize {
        self.last_jobs
    }

    /// Bytes of the maps on the device (0 before the first frame).
    pub fn map_bytes(&self) -> u64 {
        self.maps.as_ref().map_or(0, |m| m.bits.size())
    }

    /// Swaps the TAA history with `other` (one per camera stream, as the baseline's).
    pub fn swap_history(&mut self, other: &mut Option<super::baseline::History>) {
        self.frames.swap_history(other);
    }

    /// Brings the maps up to date for `shot` of `world`: allocates them when the settings
    /// or the world's size changed, and writes every tile that changed.
    fn update(&mut self, gpu: &Gpu, world: &GpuWorld, shot: &Shot) -> Result<(), GpuError> {
        self.options.check().map_err(GpuError::Unsupported)?;
        let size = world_size(world);
        let fresh = match &self.maps {
            Some(m) => m.options != self.options || m.size != size,
            None => true,
        };
        if fresh {
            self.maps = Some(allocate(gpu, self.options, &shot.light, size)?);
        }
        let maps = self.maps.as_mut().expect("allocated above");
        let camera = DVec3::from(shot.camera.pos);
        let mut jobs = BTreeSet::new();
        // The sun's map turns with the sun: all of its windows are rebuilt.
        let sun_moved = maps.sun != shot.light.sun;
        if sun_moved {
            maps.sun = shot.light.sun;
            maps.frames = map_frames(&maps.options, shot.light.sun.as_ref());
        }
        // The chunks changed since the tiles were written (read once: it walks the log).
        let changes = world.changes_since(maps.generation);
        let everything = fresh || changes == ChunkChanges::Everything;
        let sun_map = maps.options.maps() - 1;
        for map in 0..maps.options.maps() {
            for level in 0..LEVELS {
                let i = map * LEVELS + level;
                let frame = &maps.frames[map];
                let base = window_base(frame, level, camera);
                let old = maps.windows[i];
                let moved = IVec3::from(old.base) != base;
                let whole = everything || (map == sun_map && sun_moved);
                maps.windows[i] = window(frame, level, base, old.first_tile);
                for tile in window_tiles(base) {
                    let rel = tile - IVec3::from(old.base);
                    let was_held = rel.min_element() >= 0 && rel.max_element() < WINDOW_TILES;
                    if whole || (moved && !was_held) {
                        jobs.insert((i, tile.to_array()));
                    }
                }
            }
        }
        if !everything && let ChunkChanges::Chunks(chunks) = changes {
            let dims = world.chunk_dims();
            for c in chunks {
                let (x, y, z) = (c % dims[0], c / dims[0] % dims[1], c / (dims[0] * dims[1]));
                let lo = DVec3::new(f64::from(x), f64::from(y), f64::from(z)) * 16.0;
                for (i, w) in maps.windows.iter().enumerate() {
                    let frame = &maps.frames[i / LEVELS];
                    for tile in tiles_over(frame, i % LEVELS, lo, lo + 16.0, IVec3::from(w.base)) {
                        jobs.insert((i, tile.to_array()));
                    }
                }
            }
        }
        maps.generation = world.generation();
        // Per window, the tiles that may hold a point of the world: a tile outside is
        // cleared without sampling.
        let world_hi = DVec3::from(size.map(f64::from));
        let world_tiles: Vec<(IVec3, IVec3)> = (0..maps.windows.len())
            .map(|i| tile_range(&maps.frames[i / LEVELS], i % LEVELS, DVec3::ZERO, world_hi))
            .collect();
        let jobs: Vec<RomaJob> = jobs
            .into_iter()
            .map(|(i, tile)| {
                let tile = IVec3::from(tile);
                let (lo, hi) = world_tiles[i];
                let outside = !(tile.cmpge(lo).all() && tile.cmple(hi).all());
                RomaJob {
                    tile: tile.to_array(),
                    window: i as u32,
                    clear: u32::from(outside),
                    _pad0: 0,
                    _pad1: 0,
                    _pad2: 0,
                }
            })
            .collect();
        self.last_jobs = jobs.len();
        gpu.queue
            .write_buffer(&maps.windows_buffer, 0, bytemuck::cast_slice(&maps.windows));
        if jobs.is_empty() {
            return Ok(());
        }
        let job_buffer = gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("roma jobs"),
            contents: bytemuck::cast_slice(&jobs),
            usage: wgpu::BufferUsages::STORAGE,
        });
        self.build.submit(
            gpu,
            world,
            &[&maps.windows_buffer, &job_buffer, &maps.bits],
            jobs.len() as u32,
        )
    }
}

impl Temporal for Roma {
    /// Brings the maps up to date, then renders the next frame as the baseline does with
    /// ROMA lighting diffuse surfaces.
    fn frame(&mut self, gpu: &Gpu, world: &GpuWorld, shot: &Shot) -> Result<(), GpuError> {
        self.update(gpu, world, shot)?;
        let maps = self.maps.as_ref().expect("updated above");
        let info = RomaInfo {
            camera: shot.camera.pos.map(|v| v as f32),
            ao_range: maps.options.ao_range as f32,
            side: maps.options.side(),
            directions: maps.options.directions,
            _pad0: 0,
            _pad1: 0,
        };
        let info = gpu.params("roma", bytemuck::bytes_of(&info));
        self.frames
            .frame_with(gpu, world, shot, &[&info, &maps.windows_buffer, &maps.bits])
    }

    fn radiance(&self, gpu: &Gpu) -> Result<Radiance, GpuError> {
        self.frames.radiance(gpu)
    }
}

/// The world's size in voxels on the device.
fn world_size(world: &GpuWorld) -> [u32; 3] {
    world.chunk_dims().map(|c| c * 16)
}

/// New maps for `options` under `light` (every window to be written).
fn allocate(gpu: &Gpu, options: RomaOptions, light: &Light, size: [u32; 3]) -> Result<Maps, GpuError> {
    let tiles = (options.maps() * LEVELS * WINDOW_TILE_COUNT) as u64;
    let bytes = tiles * TILE_BYTES;
    let limits = gpu.device.limits();
    let limit = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
    if bytes > limit {
        return Err(GpuError::Unsupported(format!(
            "ROMA maps of {} directions need {bytes} bytes, over this device's {limit}-byte storage binding",
            options.directions
        )));
    }
    let frames = map_frames(&options, light.sun.as_ref());
    let windows: Vec<RomaWindow> = (0..options.maps() * LEVELS)
        .map(|i| {
            let first_tile = (i * WINDOW_TILE_COUNT) as u32;
            // A base no camera gives, so that the first frame writes every tile.
            window(&frames[i / LEVELS], i % LEVELS, IVec3::splat(i32::MIN / 2), first_tile)
        })
        .collect();
    let bits = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("roma maps"),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE,
        mapped_at_creation: false,
    });
    let windows_buffer = gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("roma windows"),
        contents: bytemuck::cast_slice(&windows),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
    });
    Ok(Maps {
        options,
        sun: light.sun,
        size,
        frames,
        windows,
        windows_buffer,
        bits,
        generation: 0,
    })
}

/// The device's record of a window.
fn window(frame: &MapFrame, level: usize, base: IVec3, first_tile: u32) -> RomaWindow {
    let row = |r: DVec3| r.as_vec3().to_array();
    RomaWindow {
        t: row(frame.rows[0]),
        cell: CELL[level] as f32,
        b: row(frame.rows[1]),
        first_tile,
        w: row(frame.rows[2]),
        offset: ORIGIN_OFFSET[level] as f32,
        base: base.to_array(),
        _pad: 0,
    }
}

/// The tiles of the window based at `base`.
fn window_tiles(base: IVec3) -> impl Iterator<Item = IVec3> {
    let n = WINDOW_TILES;
    (0..n * n * n).map(move |i| base + IVec3::new(i % n, i / n % n, i / (n * n)))
}

/// The map-space tile range (inclusive) covering the world box `[lo, hi]` in `frame` at
/// `level`.
fn tile_range(frame: &MapFrame, level: usize, lo: DVec3, hi: DVec3) -> (IVec3, IVec3) {
    let (mut a, mut b) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for k in 0..8 {
        let corner = DVec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        let m = DVec3::new(
            frame.rows[0].dot(corner),
            frame.rows[1].dot(corner),
            frame.rows[2].dot(corner),
        );
        a = a.min(m);
        b = b.max(m);
    }
    let scale = CELL[level] * f64::from(TILE);
    let tile = |v: DVec3| {
        let f = (v / scale).floor();
        IVec3::new(f.x as i32, f.y as i32, f.z as i32)
    };
    (tile(a), tile(b))
}

/// The tiles of the window based at `base` over the world box `[lo, hi]`.
fn tiles_over(frame: &MapFrame, level: usize, lo: DVec3, hi: DVec3, base: IVec3) -> impl Iterator<Item = IVec3> {
    let (a, b) = tile_range(frame, level, lo, hi);
    let (a, b) = (a.max(base), b.min(base + IVec3::splat(WINDOW_TILES - 1)));
    (a.z..=b.z).flat_map(move |z| (a.y..=b.y).flat_map(move |y| (a.x..=b.x).map(move |x| IVec3::new(x, y, z))))
}

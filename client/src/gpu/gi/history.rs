//! [`GiHistory`]: what the GI pipeline keeps from frame to frame (its buffers, the cameras
//! of earlier frames, the chunks a change touched), and how each frame starts it: the
//! change marks, the cameras' upload and the frame's parameters.

use super::memory::{BUCKET_SLOTS, CAM_WORDS, CAMERA_HISTORY, GiSplit, Layout, Plan, TAA_SLOTS};
use crate::gpu::context::{Gpu, GpuError};
use crate::gpu::params::{FrameInfo, GiInfo, LightInfo};
use crate::gpu::shot::{CameraRays, Shot};
use crate::gpu::world::{GpuWorld, new_part};
use naadf_world::camera::Camera;
use naadf_world::fingerprint::ChunkChanges;
use std::collections::VecDeque;

/// How near a changed chunk (in chunks, along each axis) the light counts as changed: the
/// TAA and ring samples of surfaces there follow `EDIT_HISTORY_FRAMES`. Samples of the
/// changed chunks themselves, and ring samples whose light came from them, are dropped at
/// once; history elsewhere is kept.
pub const CHANGE_REACH: u32 = 2;
/// Above this many changed chunks in one frame, the change counts as global.
pub const MAX_LOCAL_CHANGES: usize = 4096;
/// Bytes of indirect arguments at the start of `words`, copied each frame into a buffer of
/// their own (a dispatch cannot read its arguments from a buffer it binds).
pub(super) const ARGS_BYTES: u64 = 32;

/// A camera of an earlier frame and the jitter it was rendered with.
#[derive(Clone, Copy, Debug)]
struct Past {
    camera: Camera,
    jitter: [f32; 2],
}

/// The buffers and state of a running GI history.
pub struct GiHistory {
    /// The shot of the newest frame: a shot that does not continue it starts a new
    /// history, as does a new world size.
    pub(super) shot: Shot,
    /// The world's size in chunks (the change marks are per chunk).
    chunks: [u32; 3],
    pub(super) layout: Layout,
    /// How `mem` and `taa` are split across bindings.
    pub(super) split: GiSplit,
    /// `words` and `buckets` (docs in gi_common.wgsl).
    pub(super) words: wgpu::Buffer,
    pub(super) buckets: wgpu::Buffer,
    /// The parts of `mem` and of `taa`.
    pub(super) mem: Vec<wgpu::Buffer>,
    pub(super) taa: Vec<wgpu::Buffer>,
    /// Per chunk, the first frame after its newest change and after the newest change
    /// within [`CHANGE_REACH`] of it (0: none); `marks` on the device.
    marks: Vec<[u32; 2]>,
    changes: wgpu::Buffer,
    /// The indirect arguments, copied from `words`.
    pub(super) args: wgpu::Buffer,
    pub(super) ring_capacity: u32,
    /// Frames rendered so far.
    pub(super) frames: u32,
    /// The cameras of this frame and earlier ones, newest first.
    cameras: VecDeque<Past>,
    /// The world generation of the last frame.
    generation: u64,
    /// The first frame after the newest change of the materials or of more chunks than
    /// are marked one by one (0: none).
    edit_frame: u32,
    /// The first frame after the newest change of any chunk, entity moves included (0:
    /// none).
    change_frame: u32,
}

impl GiHistory {
    /// Marks `changed` chunks, and those within [`CHANGE_REACH`] of them, as changed
    /// before this frame, and uploads the marks that moved.
    fn mark(&mut self, gpu: &Gpu, changed: &[u32]) {
        let [cx, cy, cz] = self.chunks;
        let reach = CHANGE_REACH as i64;
        // The lowest and one past the highest mark set.
        let (mut lo, mut hi) = (usize::MAX, 0);
        let mut set = |i: usize, k: usize, marks: &mut Vec<[u32; 2]>| {
            marks[i][k] = self.frames;
            (lo, hi) = (lo.min(i), hi.max(i + 1));
        };
        for &c in changed {
            let c = c as i64;
            let at = [
                c % i64::from(cx),
                c / i64::from(cx) % i64::from(cy),
                c / (i64::from(cx) * i64::from(cy)),
            ];
            set(c as usize, 0, &mut self.marks);
            for z in (at[2] - reach).max(0)..=(at[2] + reach).min(i64::from(cz) - 1) {
                for y in (at[1] - reach).max(0)..=(at[1] + reach).min(i64::from(cy) - 1) {
                    for x in (at[0] - reach).max(0)..=(at[0] + reach).min(i64::from(cx) - 1) {
                        let i = x + i64::from(cx) * (y + i64::from(cy) * z);
                        set(i as usize, 1, &mut self.marks);
                    }
                }
            }
        }
        if lo < hi {
            gpu.queue
                .write_buffer(&self.changes, lo as u64 * 8, bytemuck::cast_slice(&self.marks[lo..hi]));
        }
    }

    /// A new history of `shot` of `world`, laid out as `plan` says.
    fn new(gpu: &Gpu, world: &GpuWorld, shot: &Shot, plan: &Plan) -> Self {
        let chunks = world.chunk_dims();
        let chunk_count = chunks.iter().map(|&c| c as usize).product::<usize>();
        let part = 1 << plan.split.part_bytes_shift;
        let storage_buffer = |label: &str, bytes: u64| new_part(&gpu.device, label, bytes);
        let parts = |label: &str, bytes: u64| -> Vec<wgpu::Buffer> {
            (0..bytes.div_ceil(part))
                .map(|p| storage_buffer(label, (bytes - p * part).min(part)))
                .collect()
        };
        GiHistory {
            shot: *shot,
            chunks,
            split: plan.split,
            words: storage_buffer("gi words", plan.layout.words * 4),
            buckets: storage_buffer("gi buckets", plan.regions * (2 * u64::from(BUCKET_SLOTS) + 12) * 4),
            mem: parts("gi mem", plan.mem_bytes),
            taa: parts("gi taa", plan.taa_bytes),
            marks: vec![[0; 2]; chunk_count],
            changes: storage_buffer("gi chunk changes", (chunk_count as u64 * 8).max(16)),
            layout: plan.layout,
            args: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("gi indirect args"),
                size: ARGS_BYTES,
                usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            ring_capacity: plan.ring as u32,
            frames: 0,
            cameras: VecDeque::new(),
            generation: world.generation(),
            edit_frame: 0,
            change_frame: 0,
        }
    }

    /// The history in `slot` if `shot` of `world` continues it, with the world's changes
    /// since its last frame taken in; otherwise a new one in its place.
    pub(super) fn follow<'a>(
        slot: &'a mut Option<GiHistory>,
        gpu: &Gpu,
        world: &GpuWorld,
        shot: &Shot,
        plan: &Plan,
    ) -> &'a mut GiHistory {
        let h = match slot.take() {
            Some(h) if shot.continues(&h.shot) && h.chunks == world.chunk_dims() => h,
            _ => GiHistory::new(gpu, world, shot, plan),
        };
        let h = slot.insert(h);
        h.note_changes(gpu, world);
        h
    }

    /// Takes in what changed in `world` since the last frame: the chunks it names are
    /// marked, and a change too large to mark chunk by chunk counts everywhere.
    fn note_changes(&mut self, gpu: &Gpu, world: &GpuWorld) {
        if self.generation == world.generation() {
            return;
        }
        match world.changes_since(self.generation) {
            ChunkChanges::Chunks(list) if list.is_empty() => {}
            ChunkChanges::Chunks(list) if list.len() <= MAX_LOCAL_CHANGES => {
                self.mark(gpu, &list);
                self.change_frame = self.frames;
            }
            _ => (self.edit_frame, self.change_frame) = (self.frames, self.frames),
        }
        self.generation = world.generation();
    }

    /// Starts this frame's camera: `shot`'s, with this frame's jitter, is the newest of the
    /// cameras kept, and all of them are uploaded relative to this frame's integer position
    /// (`now`), so that nothing on the device subtracts two large coordinates. Returns the
    /// jitter.
    pub(super) fn upload_cameras(&mut self, gpu: &Gpu, shot: &Shot, now: &CameraRays) -> Result<[f32; 2], GpuError> {
        let jit = jitter(self.frames);
        self.shot = *shot;
        self.cameras.push_front(Past {
            camera: shot.camera,
            jitter: jit,
        });
        self.cameras.truncate(CAMERA_HISTORY as usize);
        let floor_now = now.int.map(f64::from);
        let words = CAM_WORDS as usize;
        let mut cams = vec![[0f32; 4]; CAMERA_HISTORY as usize * words];
        for (age, past) in self.cameras.iter().enumerate() {
            let relative = Camera {
                pos: std::array::from_fn(|a| past.camera.pos[a] - floor_now[a]),
                ..past.camera
            };
            let r = CameraRays::new(&relative, shot.size)?;
            let pos: [f32; 3] = std::array::from_fn(|a| r.int[a] as f32 + r.frac[a]);
            let origin: [f32; 3] = std::array::from_fn(|a| r.int[a] as f32);
            let c = &mut cams[age * words..(age + 1) * words];
            c[0] = [pos[0], pos[1], pos[2], past.jitter[0]];
            c[1] = [r.forward[0], r.forward[1], r.forward[2], past.jitter[1]];
            c[2] = [r.right[0], r.right[1], r.right[2], 0.0];
            c[3] = [r.up[0], r.up[1], r.up[2], 0.0];
            c[4] = [origin[0], origin[1], origin[2], 0.0];
        }
        gpu.queue.write_buffer(&self.mem[0], 0, bytemuck::cast_slice(&cams));
        Ok(jit)
    }

    /// This frame's parameter buffers: the frame (`now`, the camera's rays), the light and
    /// the GI state, with this frame's `jitter` and the denoiser on or off.
    pub(super) fn params(&self, gpu: &Gpu, now: &CameraRays, jitter: [f32; 2], denoise: bool) -> [wgpu::Buffer; 3] {
        let (size, l) = (self.shot.size, &self.layout);
        let info = GiInfo {
            frame: self.frames,
            taa_slot: self.frames % TAA_SLOTS,
            taa_valid: self.frames.min(TAA_SLOTS - 1),
            edit_frame: self.edit_frame,
            change_frame: self.change_frame,
            jitter_x: jitter[0],
            jitter_y: jitter[1],
            regions_x: size.0.div_ceil(8),
            regions_y: size.1.div_ceil(8),
            ring_capacity: self.ring_capacity,
            denoise: u32::from(denoise),
            off_own: l.own,
            off_lut: l.lut,
            off_gbuf: l.gbuf,
            off_gmat: l.gmat,
            off_emitted: l.emitted,
            off_taa_info: l.taa_info,
            off_illum: l.illum,
            off_illum2: l.illum2,
            off_result: l.result,
            off_refined: l.refined,
            off_region_info: l.region_info,
            off_ring: l.ring_start as u32,
            off_queue_list: l.queue_list,
        };
        let frame = FrameInfo::new(now, size, self.shot.seed, self.frames, self.frames > 0);
        [
            gpu.params("frame", bytemuck::bytes_of(&frame)),
            gpu.params("light", bytemuck::bytes_of(&LightInfo::new(&self.shot.light))),
            gpu.params("gi", bytemuck::bytes_of(&info)),
        ]
    }

    /// The group-1 buffers of every pass, in binding order: `params`, then the history's.
    pub(super) fn bindings<'a>(&'a self, params: &'a [wgpu::Buffer; 3]) -> Vec<&'a wgpu::Buffer> {
        params
            .iter()
            .chain([&self.words, &self.buckets, &self.changes])
            .chain(&self.mem)
            .chain(&self.taa)
            .collect()
    }
}

/// The jitter of frame `frame` in the pixel: point `frame mod 32` of a 32-point (0, 5, 2)-net
/// (the van der Corput sequence in x, the second Sobol dimension in y: Halton's base 2 and
/// its base-2 partner, digitally shifted by ½), each point moved to the centre of its 1/32
/// stratum. Every axis is then stratified exactly and the mean jitter is the pixel's centre. The reference's
/// Halton (3, 7) over 32 frames is not: its mean y is 0.459, which shifted every edge by
/// 0.04 pixel and brightened the row below a bright horizon (docs/RENDERING.md §3c).
fn jitter(frame: u32) -> [f32; 2] {
    let i = frame % TAA_SLOTS;
    // Both dimensions as 32-bit fractions: x reverses the bits of i; y XORs the Sobol
    // direction numbers of the set bits of i (v₁ = 2⁻¹, v_{k+1} = v_k ⊕ v_k / 2).
    let x = i.reverse_bits();
    let (mut y, mut v, mut rest) = (0u32, 1u32 << 31, i);
    while rest > 0 {
        if rest & 1 == 1 {
            y ^= v;
        }
        rest >>= 1;
        v ^= v >> 1;
    }
    // A digital shift by ½ (XOR of the top bit) keeps the net and puts the first point,
    // the only one of a single frame, at the pixel's centre.
    let half_stratum = 0.5 / TAA_SLOTS as f32;
    [x, y].map(|b| ((b ^ 1 << 31) as f64 / 4_294_967_296.0) as f32 + half_stratum)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 32 jitters are a (0, 5, 2)-net centred in its strata: every elementary box of
    /// area 1/32 (1/32 × 1, 1/16 × 1/2, …, 1 × 1/32) holds exactly one, and the mean is the
    /// pixel's centre; the sequence restarts with the TAA's slots.
    #[test]
    fn the_jitters_stratify_the_pixel() {
        let points: Vec<[f32; 2]> = (0..TAA_SLOTS).map(jitter).collect();
        for a in 0..=5u32 {
            let (nx, ny) = (1u32 << a, 1u32 << (5 - a));
            let mut boxes = vec![0u32; 32];
            for p in &points {
                assert!(p.iter().all(|j| (0.0..1.0).contains(j)), "{p:?}");
                boxes[(p[0] * nx as f32) as usize + nx as usize * (p[1] * ny as f32) as usize] += 1;
            }
            assert!(boxes.iter().all(|&n| n == 1), "{nx} × {ny} boxes: {boxes:?}");
        }
        for axis in 0..2 {
            let mean = points.iter().map(|p| f64::from(p[axis])).sum::<f64>() / 32.0;
            assert!((mean - 0.5).abs() < 1e-6, "axis {axis}: mean {mean}");
        }
        assert_eq!(jitter(TAA_SLOTS), jitter(0));
        assert_eq!(jitter(0), [0.5 + 1.0 / 64.0, 0.5 + 1.0 / 64.0]);
    }
}

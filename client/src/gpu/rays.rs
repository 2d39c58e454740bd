//! [`RayTracer`]: traces lists of rays on the GPU with any traversal method, for the
//! GPU-against-CPU tests and the traversal benchmark.

use super::context::{Gpu, GpuError};
use super::params::{RayCount, RayIn, WgslStruct};
use super::pipeline::{PassPipelines, dispatch_2d};
use super::shaders::{Loop, NO_ENTITY, PassSource};
use super::shot::split_origin;
use super::traversal::Traversal;
use super::world::GpuWorld;
use naadf_world::traverse::{Hit, Ray};
use wgpu::util::DeviceExt;

/// `shaders/rays.wgsl`: the ray-list pass.
const RAYS: &str = include_str!("../../../shaders/rays.wgsl");

/// Workgroup size of the ray pass (`shaders/rays.wgsl`).
const WORKGROUP: u32 = 64;
/// Words per result.
const RESULT_WORDS: usize = 8;

/// A ray as the GPU receives it: the origin is split into its floor (`i32`) and an `f32`
/// fraction, the direction is rounded to `f32` and **not** renormalised (renormalising in
/// `f32` would move the line; the GPU measures distances with the direction's length).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpuRay {
    /// Origin.
    pub origin: [f64; 3],
    /// Direction (any length).
    pub dir: [f64; 3],
}

impl From<&Ray> for GpuRay {
    fn from(r: &Ray) -> Self {
        GpuRay {
            origin: r.origin(),
            dir: r.dir(),
        }
    }
}

/// One GPU result: the hit (as the CPU reports it), and whether the step budget ran out
/// (which counts as a miss).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpuHit {
    /// The first solid voxel, or `None`.
    pub hit: Option<Hit>,
    /// The ray ran out of steps.
    pub exhausted: bool,
    /// Cells visited (also for misses).
    pub steps: u32,
}

/// Rays uploaded once, traced any number of times (benchmarks time [`RayTracer::run`]).
pub struct RayBatch {
    count: u32,
    hits: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

/// The ray-list pass.
pub struct RayTracer {
    pipes: PassPipelines,
}

/// The ray-list pass's WGSL: [`RAYS`] and its structs.
pub(crate) fn rays_pass() -> PassSource {
    PassSource {
        entry: "trace_rays",
        files: &[RAYS],
        generated: RayCount::wgsl() + &RayIn::wgsl(),
    }
}

impl RayTracer {
    /// Prepares the pass (pipelines are built on first use).
    pub fn new(gpu: &Gpu) -> Self {
        RayTracer {
            pipes: PassPipelines::new(gpu, rays_pass(), 1, &[true, false]),
        }
    }

    /// The most rays one [`RayBatch`] may hold on `gpu`: the ray list (the larger of the
    /// batch's two buffers) must fit one storage binding.
    pub fn max_batch(gpu: &Gpu) -> usize {
        let bytes = gpu
            .limits
            .max_storage_buffer_binding_size
            .min(gpu.limits.max_buffer_size);
        (bytes / size_of::<RayIn>() as u64).min(u64::from(u32::MAX)) as usize
    }

    /// Uploads `rays` (at most [`RayTracer::max_batch`]).
    pub fn upload(&self, gpu: &Gpu, rays: &[GpuRay]) -> Result<RayBatch, GpuError> {
        let count = u32::try_from(rays.len())
            .ok()
            .filter(|_| rays.len() <= Self::max_batch(gpu))
            .ok_or_else(|| GpuError::Unsupported(format!("{} rays exceed one batch", rays.len())))?;
        let mut list: Vec<RayIn> = rays
            .iter()
            .map(|r| {
                let (o_int, o_frac) = split_origin(r.origin);
                RayIn {
                    o_int,
                    o_frac,
                    d: r.dir.map(|v| v as f32),
                    ..bytemuck::Zeroable::zeroed()
                }
            })
            .collect();
        if list.is_empty() {
            // A binding must not be empty.
            list.push(bytemuck::Zeroable::zeroed());
        }
        let (gx, _) = dispatch_2d(count.div_ceil(WORKGROUP));
        let ray_count = RayCount {
            count,
            row: gx * WORKGROUP,
            ..bytemuck::Zeroable::zeroed()
        };
        let params = gpu.params("ray count", bytemuck::bytes_of(&ray_count));
        let rays_buf = gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("rays"),
            contents: bytemuck::cast_slice(&list),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let hits = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("hits"),
            size: (u64::from(count) * RESULT_WORDS as u64 * 4).max(32),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let bind_group = self.pipes.group1(gpu, &[&params, &rays_buf, &hits]);
        Ok(RayBatch {
            count,
            hits,
            bind_group,
        })
    }

    /// Traces every ray of `batch` with `traversal` and waits for the device to finish.
    /// The grid, the SVO and the SVDAG must have been uploaded to `world` last (see
    /// [`Traversal`]); otherwise this fails.
    pub fn run(
        &mut self,
        gpu: &Gpu,
        world: &GpuWorld,
        batch: &RayBatch,
        traversal: impl Into<Traversal>,
    ) -> Result<(), GpuError> {
        let traversal = traversal.into();
        let (lp, aadf) = traversal.world_loop();
        if lp != Loop::Hierarchy && world.structure() != Some(traversal) {
            return Err(GpuError::Unsupported(format!(
                "the {} traversal needs its structure uploaded to the GPU world first",
                traversal.name()
            )));
        }
        let pipeline = self.pipes.get(gpu, world, lp, aadf)?;
        gpu.checked(|| {
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_compute_pass(&Default::default());
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, world.bind_group(), &[]);
                pass.set_bind_group(1, &batch.bind_group, &[]);
                let (gx, gy) = dispatch_2d(batch.count.div_ceil(WORKGROUP));
                pass.dispatch_workgroups(gx, gy, 1);
            }
            gpu.queue.submit([enc.finish()]);
        })?;
        gpu.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        Ok(())
    }

    /// The results of the last [`RayTracer::run`] of `batch`.
    pub fn results(&self, gpu: &Gpu, batch: &RayBatch) -> Result<Vec<GpuHit>, GpuError> {
        let bytes = gpu.read_buffer(&batch.hits, u64::from(batch.count) * RESULT_WORDS as u64 * 4)?;
        // A byte vector need not be 4-aligned: copy, do not cast in place.
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes);
        Ok(words.chunks_exact(RESULT_WORDS).map(decode).collect())
    }

    /// Uploads, traces and reads back `rays` in one go.
    pub fn trace(
        &mut self,
        gpu: &Gpu,
        world: &GpuWorld,
        rays: &[GpuRay],
        traversal: impl Into<Traversal>,
    ) -> Result<Vec<GpuHit>, GpuError> {
        let batch = self.upload(gpu, rays)?;
        self.run(gpu, world, &batch, traversal)?;
        self.results(gpu, &batch)
    }
}

fn decode(w: &[u32]) -> GpuHit {
    let flags = w[0];
    let hit = (flags & 1 != 0).then(|| {
        let axis = (flags >> 4 & 3) as usize;
        let mut normal = [0i32; 3];
        if axis < 3 {
            normal[axis] = if flags & 64 != 0 { 1 } else { -1 };
        }
        Hit {
            voxel: [w[1], w[2], w[3]],
            normal,
            t: f64::from(f32::from_bits(w[5])),
            material: w[4] as u16,
            steps: w[6],
            entity: (w[7] != NO_ENTITY).then_some(w[7]),
        }
    });
    GpuHit {
        hit,
        exhausted: flags & 2 != 0,
        steps: w[6],
    }
}

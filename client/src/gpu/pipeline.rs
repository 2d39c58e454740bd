//! Compute pipelines of one pass, built on demand for each buffer split and variant.

use super::bindings::{Split, storage_entry};
use super::context::{Gpu, GpuError, checked_on};
use super::shaders::{self, Loop, PassSource};
use super::world::GpuWorld;
use std::collections::HashMap;

/// A pipeline's key: the world's split, the world loop, whether AADFs are used, and
/// whether the world has instances.
type Key = (Split, Loop, bool, bool);

/// A cached pipeline, or one being built on a thread of its own
/// ([`Gpu::prepare_instance_variants`]).
enum Slot {
    Ready(wgpu::ComputePipeline),
    Building(std::thread::JoinHandle<Result<wgpu::ComputePipeline, GpuError>>),
}

/// The pipelines of one pass: group 0 is the world ([`GpuWorld::layout`]), group 1 the
/// pass's own bindings (parameter buffers, then its other storage buffers). Every binding
/// is a storage buffer: see [`Gpu::params`] for why none is a uniform buffer.
pub(crate) struct PassPipelines {
    pass: PassSource,
    group1: wgpu::BindGroupLayout,
    cache: HashMap<Key, Slot>,
}

impl PassPipelines {
    /// Pipelines for `pass`, whose group 1 is `params` parameter buffers (read-only, made
    /// by [`Gpu::params`]) followed by storage buffers with the given read-only flags.
    pub fn new(gpu: &Gpu, pass: PassSource, params: u32, storage_read_only: &[bool]) -> Self {
        let read_only = (0..params).map(|_| true).chain(storage_read_only.iter().copied());
        let entries: Vec<_> = read_only
            .enumerate()
            .map(|(i, read_only)| storage_entry(i as u32, read_only))
            .collect();
        let group1 = gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(pass.entry),
            entries: &entries,
        });
        PassPipelines {
            pass,
            group1,
            cache: HashMap::new(),
        }
    }

    /// A group-1 bind group of the pass's own buffers: its parameters, then its storage
    /// buffers, at bindings 0, 1, 2, … in that order.
    pub fn group1(&self, gpu: &Gpu, buffers: &[&wgpu::Buffer]) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.pass.entry),
            layout: &self.group1,
            entries: &entries,
        })
    }

    /// The pipeline for the world's current split, world loop `lp`, (for the hierarchy)
    /// whether AADFs are used, and whether the world has instances (a cheap handle to the
    /// cached pipeline). A world without instances gets a pipeline without the instance
    /// walk: a device that runs neighbouring invocations in lock step, such as Mesa's
    /// lavapipe, may run every branch of a shader whether or not any invocation takes it.
    /// After [`Gpu::prepare_instance_variants`], the variant for the other instance state
    /// is built in the background.
    pub fn get(
        &mut self,
        gpu: &Gpu,
        world: &GpuWorld,
        lp: Loop,
        aadf: bool,
    ) -> Result<wgpu::ComputePipeline, GpuError> {
        let key = (world.split(), lp, aadf, world.has_instances());
        if let Some(Slot::Ready(p)) = self.cache.get(&key) {
            return Ok(p.clone());
        }
        // Built now, or taken from its background build; then its other variant is started.
        let pipeline = match self.cache.remove(&key) {
            Some(Slot::Building(job)) => job
                .join()
                .map_err(|_| GpuError::Validation(format!("building the {} pipeline panicked", self.pass.entry)))?,
            _ => self.build(gpu, world, key)(),
        }?;
        self.cache.insert(key, Slot::Ready(pipeline.clone()));
        let other = (key.0, key.1, key.2, !key.3);
        if gpu.prepares_instance_variants() && !self.cache.contains_key(&other) {
            let job = std::thread::spawn(self.build(gpu, world, other));
            self.cache.insert(other, Slot::Building(job));
        }
        Ok(pipeline)
    }

    /// The work of building the pipeline for `key`: everything it needs is moved into it,
    /// so that it can run on another thread.
    fn build(
        &self,
        gpu: &Gpu,
        world: &GpuWorld,
        key: Key,
    ) -> impl FnOnce() -> Result<wgpu::ComputePipeline, GpuError> + Send + 'static {
        let (split, lp, aadf, instances) = key;
        let src = shaders::source(&self.pass, lp, shaders::WorldBindings::Split(&split));
        let (device, entry) = (gpu.device.clone(), self.pass.entry);
        let layouts = [world.layout().clone(), self.group1.clone()];
        move || {
            checked_on(&device, || {
                let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some(entry),
                    source: wgpu::ShaderSource::Wgsl(src.into()),
                });
                let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some(entry),
                    bind_group_layouts: &[Some(&layouts[0]), Some(&layouts[1])],
                    immediate_size: 0,
                });
                let flag = |on: bool| if on { 1.0 } else { 0.0 };
                let instances = ("HAS_INSTANCES", flag(instances));
                let constants: &[(&str, f64)] = match lp {
                    Loop::Hierarchy => &[("USE_AADF", flag(aadf)), instances],
                    Loop::Grid | Loop::Svo | Loop::Svdag | Loop::Hybrid => &[instances],
                };
                device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout: Some(&layout),
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants,
                        ..Default::default()
                    },
                    cache: None,
                })
            })
        }
    }

    /// Runs `groups` workgroups (split by [`dispatch_2d`]) of the pass's hierarchy pipeline
    /// over `world`, with `buffers` as its group 1, in a submission of its own.
    pub fn submit(
        &mut self,
        gpu: &Gpu,
        world: &GpuWorld,
        buffers: &[&wgpu::Buffer],
        groups: u32,
    ) -> Result<(), GpuError> {
        let pipeline = self.get(gpu, world, Loop::Hierarchy, true)?;
        let (gx, gy) = dispatch_2d(groups);
        gpu.checked(|| {
            let group = self.group1(gpu, buffers);
            let mut enc = gpu.device.create_command_encoder(&Default::default());
            {
                let mut pass = enc.begin_compute_pass(&Default::default());
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, world.bind_group(), &[]);
                pass.set_bind_group(1, &group, &[]);
                pass.dispatch_workgroups(gx, gy, 1);
            }
            gpu.queue.submit([enc.finish()]);
        })
    }
}

/// Splits `groups` workgroups into a 2D dispatch within the per-dimension limit; returns
/// `(x, y)` with `x · y ≥ groups`.
pub(crate) fn dispatch_2d(groups: u32) -> (u32, u32) {
    const MAX: u32 = 65535;
    if groups <= MAX {
        (groups.max(1), 1)
    } else {
        (MAX, groups.div_ceil(MAX))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::rays::rays_pass;
    use naadf_world::World;
    use naadf_world::ops::{Batch, Limits, Op};
    use naadf_world::preset::Preset;

    /// A device that prepares instance variants starts building the other variant as soon
    /// as one is built, and the world's switch then takes that build instead of compiling.
    #[test]
    fn the_other_instance_variant_is_built_in_the_background() {
        let gpu = match Gpu::new() {
            Ok(g) => g,
            Err(e) => return eprintln!("skipping the background build test: {e}"),
        };
        gpu.prepare_instance_variants();
        let src = Preset::Test.source(None, 1).unwrap();
        let mut world = World::build(&*src, &|_| {}).unwrap();
        let mut gw = GpuWorld::new(&gpu, &world).unwrap();
        let mut pipes = PassPipelines::new(&gpu, rays_pass(), 1, &[true, false]);
        assert!(!gw.has_instances());
        pipes.get(&gpu, &gw, Loop::Hierarchy, true).unwrap();
        let with = (gw.split(), Loop::Hierarchy, true, true);
        assert!(matches!(pipes.cache.get(&with), Some(Slot::Building(_))));
        let ops = vec![
            Op::DefineModel {
                name: "cube".into(),
                size: [2, 2, 2],
                voxels: vec![[0, 0, 0, 1], [1, 1, 1, 2]],
            },
            Op::SpawnEntity {
                id: 1,
                model: "cube".into(),
                pos: [20.0, 50.0, 20.0],
                rot: [0.0, 0.0, 0.0, 1.0],
            },
        ];
        world.apply(&Batch { ops }, &Limits::default()).unwrap();
        gw.sync(&world).unwrap();
        assert!(gw.has_instances());
        assert_eq!(gw.split(), with.0, "the same split before and after the spawn");
        pipes.get(&gpu, &gw, Loop::Hierarchy, true).unwrap();
        // Both variants are ready, and none is built again.
        assert_eq!(pipes.cache.len(), 2);
        assert!(pipes.cache.values().all(|s| matches!(s, Slot::Ready(_))));
    }
}

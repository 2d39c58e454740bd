//! Compute pipelines of one pass, built on demand for each buffer split and variant.

use super::bindings::{Split, storage_entry};
use super::context::{Gpu, GpuError};
use super::shaders::{self, Loop, PassSource};
use super::world::GpuWorld;
use std::collections::HashMap;

/// The pipelines of one pass: group 0 is the world ([`GpuWorld::layout`]), group 1 the
/// pass's own bindings (parameter buffers, then its other storage buffers). Every binding
/// is a storage buffer: see [`Gpu::params`] for why none is a uniform buffer.
pub(crate) struct PassPipelines {
    pass: PassSource,
    group1: wgpu::BindGroupLayout,
    cache: HashMap<(Split, Loop, bool, bool), wgpu::ComputePipeline>,
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
    pub fn get(
        &mut self,
        gpu: &Gpu,
        world: &GpuWorld,
        lp: Loop,
        aadf: bool,
    ) -> Result<wgpu::ComputePipeline, GpuError> {
        let key = (world.split(), lp, aadf, world.has_instances());
        if !self.cache.contains_key(&key) {
            let src = shaders::source(&self.pass, lp, shaders::WorldBindings::Split(&key.0));
            let pipeline = gpu.checked(|| {
                let module = gpu.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some(self.pass.entry),
                    source: wgpu::ShaderSource::Wgsl(src.into()),
                });
                let layout = gpu.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some(self.pass.entry),
                    bind_group_layouts: &[Some(world.layout()), Some(&self.group1)],
                    immediate_size: 0,
                });
                let flag = |on: bool| if on { 1.0 } else { 0.0 };
                let instances = ("HAS_INSTANCES", flag(key.3));
                let constants: &[(&str, f64)] = match lp {
                    Loop::Hierarchy => &[("USE_AADF", flag(aadf)), instances],
                    Loop::Grid | Loop::Svo | Loop::Svdag | Loop::Hybrid => &[instances],
                };
                gpu.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(self.pass.entry),
                    layout: Some(&layout),
                    module: &module,
                    entry_point: Some(self.pass.entry),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants,
                        ..Default::default()
                    },
                    cache: None,
                })
            })?;
            self.cache.insert(key, pipeline);
        }
        Ok(self.cache[&key].clone())
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

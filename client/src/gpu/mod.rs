//! The GPU side of the client (wgpu): the world buffers on the device, the WGSL traversal
//! and the renderer.
//!
//! - [`Gpu`]: instance, adapter, device and queue, chosen from the environment
//!   (`WGPU_BACKEND`, `WGPU_ADAPTER_NAME`, `WGPU_POWER_PREF`), so the same code runs on
//!   Mesa lavapipe and on a real GPU;
//! - [`GpuWorld`]: the world buffers, byte for byte, kept in step with a [`World`] by
//!   uploading the 64 KiB pages whose digest hash changed;
//! - [`shaders`]: the WGSL of `shaders/`, assembled per pass after a generated prelude:
//!   the bindings the world's current buffer split needs, the [`WorldInfo`] parameters and
//!   the constants the shaders share with the Rust code;
//! - [`WorldInfo`], [`FrameInfo`], [`LightInfo`], [`GiInfo`]: the passes' parameter
//!   structs, one definition for Rust and WGSL each ([`WgslStruct`]), bound as read-only
//!   storage buffers (never uniform buffers: see [`Gpu::params`]);
//! - [`RayTracer`]: traces lists of rays with any traversal method (tests against the
//!   CPU, benchmarks);
//! - [`Renderer`]: renders camera frames in the modes of [`Mode`];
//! - [`PathTracer`]: the progressive path tracer of the light model
//!   ([`crate::light`]), the ground truth of the lit modes;
//! - [`Baseline`]: 1-spp path tracing with an exponential TAA, the paper's comparison;
//! - [`Gi`]: the paper's GI pipeline (first hit, long-term TAA, ray queue, sample ring,
//!   region projection, spatial resampling, denoiser);
//! - [`Headless`]: a device, a renderer and a GPU copy that follows a changing world.
//!
//! [`World`]: naadf_world::World

mod baseline;
mod context;
mod gi;
mod headless;
mod params;
mod pathtrace;
mod pipeline;
mod rays;
mod render;
pub mod shaders;
mod temporal;
mod world;

pub use baseline::Baseline;
pub use context::{Gpu, GpuError};
pub use gi::{CHANGE_REACH, Gi, GiHistory, GiPass};
pub use headless::Headless;
pub use params::{FrameInfo, GiInfo, LightInfo, Member, WgslStruct, WgslType, WorldInfo};
pub use pathtrace::PathTracer;
pub use rays::{GpuHit, GpuRay, RayBatch, RayTracer, Traversal};
pub use render::{DEFAULT_SUN, Frame, GBUFFER_MAGIC, Mode, Renderer, STEPS_FULL_SCALE, write_gbuffer};
pub use temporal::Temporal;
pub use world::{DEFAULT_MAX_STEPS, GPU_BUFFERS, GpuWorld, Upload};

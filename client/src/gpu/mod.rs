//! The GPU side of the client (wgpu): the world buffers on the device, the WGSL traversal
//! and the renderer.
//!
//! The modules stand on one another, from the floor up:
//! - [`Gpu`] (`context`): instance, adapter, device and queue, chosen from the environment
//!   (`WGPU_BACKEND`, `WGPU_ADAPTER_NAME`, `WGPU_POWER_PREF`), so the same code runs on
//!   Mesa lavapipe and on a real GPU;
//! - `params`: the structs the shaders share with Rust ([`WorldInfo`], [`FrameInfo`],
//!   [`LightInfo`], [`GiInfo`], [`View`], [`RayIn`]), one definition for Rust and WGSL
//!   each ([`WgslStruct`]), bound as read-only storage buffers (never uniform buffers: see
//!   `Gpu::params`);
//! - `bindings`: the world's bind group ([`Split`]: how its buffers are split across
//!   bindings);
//! - [`shaders`]: the WGSL of `shaders/`, assembled per pass after a generated prelude of
//!   the bindings, the parameter structs and the constants the shaders share with Rust;
//! - [`Traversal`] (`traversal`): what a ray walks, and the world loop that walks it;
//! - [`GpuWorld`] (`world`): the world buffers, byte for byte, kept in step with a
//!   [`World`] by uploading the 64 KiB pages whose digest hash changed;
//! - `pipeline`: the compute pipelines of a pass, over the world's bind group;
//! - [`Shot`] (`shot`): what a lit frame is of, and the camera's rays as the passes take
//!   them;
//! - the passes, each in its module with its own WGSL: [`RayTracer`] (lists of rays with
//!   any traversal, for tests against the CPU and benchmarks), [`Renderer`] (camera frames
//!   in the modes of [`Mode`]), [`PathTracer`] (the progressive path tracer of the light
//!   model, [`crate::light`], the ground truth of the lit modes), [`Baseline`] (1-spp path
//!   tracing with an exponential TAA, the paper's comparison) and [`Gi`] (the paper's GI
//!   pipeline), the last two behind [`Temporal`];
//! - [`browser`]: the browser page's WGSL and buffer layout, generated from the same
//!   definitions;
//! - [`Headless`]: a device, the renderers and a GPU copy that follows a changing world.
//!
//! [`World`]: naadf_world::World
//! [`Mode`]: crate::Mode

mod baseline;
mod bindings;
pub mod browser;
mod context;
mod gi;
mod headless;
mod irradiance;
mod params;
mod pathtrace;
mod pipeline;
mod rays;
mod render;
mod renderers;
mod roma;
pub mod shaders;
mod shot;
mod temporal;
mod traversal;
mod world;

#[cfg(test)]
mod tests;

pub use baseline::Baseline;
pub use bindings::Split;
pub use context::{Gpu, GpuError};
pub use gi::{CHANGE_REACH, Gi, GiHistory, GiPass, GiSplit};
pub use headless::Headless;
pub use irradiance::Irradiance;
pub use params::{FrameInfo, GiInfo, LightInfo, Member, RayIn, View, WgslStruct, WgslType, WorldInfo};
pub use pathtrace::PathTracer;
pub use rays::{GpuHit, GpuRay, RayBatch, RayTracer};
pub use render::{DEFAULT_SUN, Renderer, STEPS_FULL_SCALE};
pub(crate) use renderers::Renderers;
pub use roma::Roma;
pub use shot::{MAX_EDGE, Shot};
pub use temporal::Temporal;
pub use traversal::Traversal;
pub use world::{GPU_BUFFERS, GpuWorld, Upload};

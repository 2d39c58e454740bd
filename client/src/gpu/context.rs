//! Device selection and the errors of the GPU client.

use crate::frame::FrameError;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use thiserror::Error;

/// Errors of the GPU client.
#[derive(Debug, Error)]
pub enum GpuError {
    /// No adapter could be found or the device could not be created.
    #[error("no usable GPU adapter: {0} (install Mesa's Vulkan driver, lavapipe, for software rendering)")]
    NoAdapter(String),
    /// The device rejected a shader, pipeline or dispatch.
    #[error("GPU validation failed: {0}")]
    Validation(String),
    /// Reading results back failed.
    #[error("GPU readback failed: {0}")]
    Readback(String),
    /// A request the GPU client cannot serve (too large an image, a world that does not
    /// fit the adapter's limits, …).
    #[error("{0}")]
    Unsupported(String),
}

impl From<FrameError> for GpuError {
    fn from(e: FrameError) -> Self {
        match e {
            FrameError::Decode(_) => GpuError::Unsupported(e.to_string()),
            FrameError::Encode(_) => GpuError::Readback(e.to_string()),
        }
    }
}

/// A wgpu device and its queue.
pub struct Gpu {
    /// The adapter the device was opened on.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// What the adapter reported about itself.
    pub info: wgpu::AdapterInfo,
    /// The limits the device was created with.
    pub limits: wgpu::Limits,
    /// The optional features the device was created with (timestamp queries).
    pub features: wgpu::Features,
    /// See [`Gpu::prepare_instance_variants`].
    instance_variants: AtomicBool,
}

impl std::fmt::Debug for Gpu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Gpu({} on {:?})", self.info.name, self.info.backend)
    }
}

impl Gpu {
    /// Opens the default adapter, honouring `WGPU_BACKEND`, `WGPU_ADAPTER_NAME` and
    /// `WGPU_POWER_PREF`, with the adapter's own limits (large buffers need them). Without
    /// `WGPU_BACKEND`, the primary backends (Vulkan, Metal, DX12) are tried before GL, so
    /// that a working Vulkan never pays for (or logs) a failed EGL probe.
    pub fn new() -> Result<Self, GpuError> {
        let (gpu, _) = Self::open(wgpu::InstanceDescriptor::new_without_display_handle_from_env, |_| {
            Ok(None)
        })?;
        Ok(gpu)
    }

    /// Like [`Gpu::new`], but the adapter must be able to present to `window`; returns the
    /// window's surface too.
    pub fn for_window<W>(window: Arc<W>) -> Result<(Self, wgpu::Surface<'static>), GpuError>
    where
        W: wgpu::WindowHandle + wgpu::rwh::HasDisplayHandle + std::fmt::Debug + 'static,
    {
        let (gpu, surface) = Self::open(
            || wgpu::InstanceDescriptor::new_with_display_handle_from_env(Box::new(window.clone())),
            |instance| {
                let surface = instance
                    .create_surface(window.clone())
                    .map_err(|e| GpuError::NoAdapter(format!("cannot create a surface for the window: {e}")))?;
                Ok(Some(surface))
            },
        )?;
        let surface = surface.ok_or_else(|| GpuError::NoAdapter("no surface".into()))?;
        Ok((gpu, surface))
    }

    /// Opens an instance from `desc` (per backend set tried), the optional surface
    /// `surface` makes on it, a compatible adapter, and the device.
    fn open(
        desc: impl Fn() -> wgpu::InstanceDescriptor,
        surface: impl Fn(&wgpu::Instance) -> Result<Option<wgpu::Surface<'static>>, GpuError>,
    ) -> Result<(Self, Option<wgpu::Surface<'static>>), GpuError> {
        let try_backends = |backends: Option<wgpu::Backends>| {
            let mut d = desc();
            if let Some(b) = backends {
                d.backends = b;
            }
            let instance = wgpu::Instance::new(d);
            let surface = surface(&instance)?;
            let adapter = pollster::block_on(wgpu::util::initialize_adapter_from_env_or_default(
                &instance,
                surface.as_ref(),
            ))
            .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
            Ok::<_, GpuError>((adapter, surface))
        };
        let (adapter, surface) = if std::env::var_os("WGPU_BACKEND").is_some() {
            try_backends(None)
        } else {
            try_backends(Some(wgpu::Backends::PRIMARY)).or_else(|primary| {
                try_backends(Some(wgpu::Backends::GL))
                    .map_err(|gl| GpuError::NoAdapter(format!("Vulkan/Metal/DX12: {primary}; GL: {gl}")))
            })
        }?;
        let limits = adapter.limits();
        // Timestamps time the GI passes where the adapter has them.
        let features = adapter.features() & wgpu::Features::TIMESTAMP_QUERY;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("naadf"),
            required_limits: limits.clone(),
            required_features: features,
            ..Default::default()
        }))
        .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        tracing::info!(adapter = %info.name, backend = ?info.backend, driver = %info.driver_info, "GPU device ready");
        let gpu = Gpu {
            adapter,
            device,
            queue,
            info,
            limits,
            features,
            instance_variants: AtomicBool::new(false),
        };
        Ok((gpu, surface))
    }

    /// From now on, each pipeline built for a world with instances (or without) also starts
    /// building its variant for the other case, on a thread of its own, so that a world
    /// that gains its first instance slot (a spawn, a preview, another client's marker) or
    /// loses its last switches pipelines without waiting for a compile. For long-lived
    /// clients (the viewer, render nodes): it doubles the compile work, which a one-shot
    /// render would pay for nothing.
    pub fn prepare_instance_variants(&self) {
        self.instance_variants.store(true, Ordering::Relaxed);
    }

    /// Whether [`Gpu::prepare_instance_variants`] was called.
    pub(crate) fn prepares_instance_variants(&self) -> bool {
        self.instance_variants.load(Ordering::Relaxed)
    }

    /// The adapter in words, e.g. `llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)`.
    pub fn describe(&self) -> String {
        format!("{} ({:?})", self.info.name, self.info.backend)
    }

    /// Runs `f` with validation errors captured, turning them into [`GpuError::Validation`].
    pub(crate) fn checked<T>(&self, f: impl FnOnce() -> T) -> Result<T, GpuError> {
        checked_on(&self.device, f)
    }

    /// A parameter buffer holding `contents`, for a read-only storage binding.
    ///
    /// Parameters are never bound as uniform buffers: Mesa's lavapipe inlines the values of
    /// a uniform buffer that a shader branches or loops on and re-optimises the shader with
    /// them at every dispatch (tens of milliseconds for the render, path-tracing and TAA
    /// passes, whatever the frame size), and crashes doing so on some GI passes. It never
    /// inlines storage buffers, and on a real GPU a small read-only storage buffer costs
    /// the same.
    pub(crate) fn params(&self, label: &str, contents: &[u8]) -> wgpu::Buffer {
        use wgpu::util::DeviceExt;
        self.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage: wgpu::BufferUsages::STORAGE,
        })
    }

    /// Copies `size` bytes of `src` (a `COPY_SRC` buffer) back to the host.
    pub(crate) fn read_buffer(&self, src: &wgpu::Buffer, size: u64) -> Result<Vec<u8>, GpuError> {
        self.read_buffer_at(src, 0, size)
    }

    /// The `size` bytes from byte `offset` of a logical buffer split into `parts` of
    /// `part_bytes` each (the last may be shorter), read part by part.
    pub(crate) fn read_parts(
        &self,
        parts: &[wgpu::Buffer],
        part_bytes: u64,
        offset: u64,
        size: u64,
    ) -> Result<Vec<u8>, GpuError> {
        let mut out = Vec::with_capacity(size as usize);
        let end = offset + size;
        let mut at = offset;
        while at < end {
            let within = at % part_bytes;
            let n = (end - at).min(part_bytes - within);
            let part = parts
                .get((at / part_bytes) as usize)
                .ok_or_else(|| GpuError::Readback(format!("byte {at} lies past the buffer's {} parts", parts.len())))?;
            out.extend(self.read_buffer_at(part, within, n)?);
            at += n;
        }
        Ok(out)
    }

    /// [`Gpu::read_buffer`] of the `size` bytes from `offset` (both multiples of 4).
    pub(crate) fn read_buffer_at(&self, src: &wgpu::Buffer, offset: u64, size: u64) -> Result<Vec<u8>, GpuError> {
        if size == 0 {
            return Ok(Vec::new());
        }
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(src, offset, &staging, 0, size);
        self.queue.submit([enc.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        staging.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        rx.recv()
            .map_err(|e| GpuError::Readback(e.to_string()))?
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        let bytes = staging
            .get_mapped_range(..)
            .map_err(|e| GpuError::Readback(e.to_string()))?
            .to_vec();
        staging.unmap();
        Ok(bytes)
    }
}

/// Runs `f` with `device`'s validation errors captured (wgpu's default handler would panic
/// on them), turning them into [`GpuError::Validation`].
pub(crate) fn checked_on<T>(device: &wgpu::Device, f: impl FnOnce() -> T) -> Result<T, GpuError> {
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let out = f();
    match pollster::block_on(scope.pop()) {
        Some(e) => Err(GpuError::Validation(e.to_string())),
        None => Ok(out),
    }
}

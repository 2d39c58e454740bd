//! [`Presenter`]: shows rendered frames in a window's surface.
//!
//! Frames arrive as sRGB-encoded RGBA8 bytes (the renderer's output, already read back for
//! the HUD and screenshots), so presenting is one `write_texture` into the swap-chain
//! image, with a non-sRGB format so that the bytes are shown as they are.

use crate::frame::Frame;
use crate::gpu::{Gpu, GpuError};

/// A configured window surface.
pub struct Presenter {
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    /// The surface stores blue first: frames are swizzled on the way.
    bgra: bool,
    scratch: Vec<u8>,
}

impl Presenter {
    /// Configures `surface` for `size` (physical pixels).
    pub fn new(gpu: &Gpu, surface: wgpu::Surface<'static>, size: (u32, u32)) -> Result<Self, GpuError> {
        let caps = surface.get_capabilities(&gpu.adapter);
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| matches!(f, wgpu::TextureFormat::Rgba8Unorm | wgpu::TextureFormat::Bgra8Unorm))
            .ok_or_else(|| GpuError::Unsupported(format!("no 8-bit RGBA surface format among {:?}", caps.formats)))?;
        if !caps.usages.contains(wgpu::TextureUsages::COPY_DST) {
            return Err(GpuError::Unsupported(
                "the window surface does not accept copies".into(),
            ));
        }
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::COPY_DST,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: size.0.max(1),
            height: size.1.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: Vec::new(),
        };
        let p = Presenter {
            surface,
            config,
            bgra: format == wgpu::TextureFormat::Bgra8Unorm,
            scratch: Vec::new(),
        };
        gpu.checked(|| p.surface.configure(&gpu.device, &p.config))?;
        Ok(p)
    }

    /// The size frames must have.
    pub fn size(&self) -> (u32, u32) {
        (self.config.width, self.config.height)
    }

    /// Follows a window resize (a minimised window keeps its last size).
    pub fn resize(&mut self, gpu: &Gpu, size: (u32, u32)) -> Result<(), GpuError> {
        if size.0 > 0 && size.1 > 0 && size != self.size() {
            self.config.width = size.0;
            self.config.height = size.1;
            gpu.checked(|| self.surface.configure(&gpu.device, &self.config))?;
        }
        Ok(())
    }

    /// Shows `frame` (of [`Presenter::size`]); a frame the surface cannot take now
    /// (minimised, outdated) is skipped, and an outdated surface reconfigured.
    pub fn present(&mut self, gpu: &Gpu, frame: &Frame) -> Result<(), GpuError> {
        if (frame.width, frame.height) != self.size() {
            return Ok(());
        }
        let texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                return gpu.checked(|| self.surface.configure(&gpu.device, &self.config));
            }
            wgpu::CurrentSurfaceTexture::Validation => {
                return Err(GpuError::Validation("acquiring the surface texture failed".into()));
            }
            _ => return Ok(()),
        };
        let bytes: &[u8] = if self.bgra {
            self.scratch.clear();
            self.scratch
                .extend(frame.rgba.chunks_exact(4).flat_map(|p| [p[2], p[1], p[0], p[3]]));
            &self.scratch
        } else {
            &frame.rgba
        };
        gpu.queue.write_texture(
            texture.texture.as_image_copy(),
            bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(frame.width * 4),
                rows_per_image: Some(frame.height),
            },
            wgpu::Extent3d {
                width: frame.width,
                height: frame.height,
                depth_or_array_layers: 1,
            },
        );
        // Submitting flushes the pending write; a texture presented with no work is cleared.
        gpu.queue.submit([]);
        gpu.queue.present(texture);
        Ok(())
    }
}

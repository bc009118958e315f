//! The window's surface: configured for the window's size (and again when it changes,
//! is outdated or lost), and the copy of the finished frame onto it.

use std::sync::Arc;

use winit::window::Window;

use crate::render::bindings::present;
use crate::render::{FrameTargets, Renderer, fragment_texture, fullscreen_pipeline, shader_module};

pub struct Presenter {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    /// The frame and the surface, both seen without sRGB encoding, so that the frame's
    /// bytes are copied as they are; or, where views cannot be reinterpreted (GL), both
    /// with it, so that they are decoded and encoded again (exactly, at 8 bits).
    source_format: wgpu::TextureFormat,
    view_format: wgpu::TextureFormat,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::RenderPipeline,
}

/// What became of one attempt to present.
pub enum Presented {
    Shown,
    /// Nothing shown this time (minimized, occluded, timed out, reconfigured): try at
    /// the next redraw.
    Skipped,
}

impl Presenter {
    /// Draws into `surface`, made for `window` by the renderer's instance.
    pub fn new(
        renderer: &Renderer,
        window: Arc<Window>,
        surface: wgpu::Surface<'static>,
    ) -> anyhow::Result<Presenter> {
        let gpu = &renderer.gpu;
        let caps = surface.get_capabilities(&gpu.adapter);
        let source_format = gpu.overlay_format();
        let format = *caps
            .formats
            .iter()
            .find(|f| f.is_srgb() == source_format.is_srgb())
            .or(caps.formats.first())
            .ok_or_else(|| anyhow::anyhow!("the GPU cannot draw into this window"))?;
        let view_format = if gpu.view_formats {
            format.remove_srgb_suffix()
        } else {
            format
        };
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            color_space: wgpu::SurfaceColorSpace::Auto,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: if view_format == format {
                vec![]
            } else {
                vec![view_format]
            },
        };
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("present"),
            entries: &[fragment_texture(present::FINISHED.binding)],
        });
        let module = shader_module(device, "present");
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("present"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = fullscreen_pipeline(
            device,
            &pipeline_layout,
            &module,
            "fs_present",
            &[view_format],
        );
        let presenter = Presenter {
            window,
            surface,
            config,
            source_format,
            view_format,
            layout,
            pipeline,
        };
        if presenter.config.width > 0 && presenter.config.height > 0 {
            presenter.surface.configure(device, &presenter.config);
        }
        Ok(presenter)
    }

    /// The window's drawable size in pixels; (0, 0) when minimized.
    pub fn window_size(&self) -> (u32, u32) {
        let s = self.window.inner_size();
        (s.width, s.height)
    }

    /// Configures the surface for the window's current size (skipped at size 0).
    pub fn resize(&mut self, renderer: &Renderer) {
        let (w, h) = self.window_size();
        if w == 0 || h == 0 {
            return;
        }
        self.config.width = w;
        self.config.height = h;
        self.surface.configure(&renderer.gpu.device, &self.config);
    }

    /// Records the copy of `targets.output` onto the next surface texture, submits
    /// `encoder` and presents. The surface is reconfigured when outdated or lost.
    pub fn present(
        &mut self,
        renderer: &Renderer,
        encoder: wgpu::CommandEncoder,
        targets: &FrameTargets,
    ) -> Presented {
        let queue = &renderer.gpu.queue;
        let texture = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) => t,
            wgpu::CurrentSurfaceTexture::Suboptimal(t) => {
                // Shown, then reconfigured for the next frame.
                self.copy_and_present(renderer, encoder, targets, t);
                self.resize(renderer);
                return Presented::Shown;
            }
            wgpu::CurrentSurfaceTexture::Outdated => {
                queue.submit([encoder.finish()]);
                self.resize(renderer);
                return Presented::Skipped;
            }
            wgpu::CurrentSurfaceTexture::Lost => {
                queue.submit([encoder.finish()]);
                // A new surface for the same window; if that fails too, the next
                // redraw tries again.
                if let Ok(surface) = renderer.gpu.instance.create_surface(self.window.clone()) {
                    self.surface = surface;
                    self.resize(renderer);
                }
                return Presented::Skipped;
            }
            _ => {
                queue.submit([encoder.finish()]);
                return Presented::Skipped;
            }
        };
        if (texture.texture.width(), texture.texture.height()) != targets.size {
            // The window changed size since this frame was drawn.
            queue.submit([encoder.finish()]);
            drop(texture);
            self.resize(renderer);
            return Presented::Skipped;
        }
        self.copy_and_present(renderer, encoder, targets, texture);
        Presented::Shown
    }

    fn copy_and_present(
        &self,
        renderer: &Renderer,
        mut encoder: wgpu::CommandEncoder,
        targets: &FrameTargets,
        texture: wgpu::SurfaceTexture,
    ) {
        let device = &renderer.gpu.device;
        let source = targets.overlay_view(self.source_format);
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("present"),
            layout: &self.layout,
            entries: &[wgpu::BindGroupEntry {
                binding: present::FINISHED.binding,
                resource: wgpu::BindingResource::TextureView(&source),
            }],
        });
        let view = texture.texture.create_view(&wgpu::TextureViewDescriptor {
            format: Some(self.view_format),
            ..Default::default()
        });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("present"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.draw(0..3, 0..1);
        }
        renderer.gpu.queue.submit([encoder.finish()]);
        self.window.pre_present_notify();
        renderer.gpu.queue.present(texture);
    }
}

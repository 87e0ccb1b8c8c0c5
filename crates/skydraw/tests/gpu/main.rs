//! The runtime on a real Vulkan device (lavapipe without a GPU): drawing into a pass and depth
//! buffer the test owns (`draw`), the radiance cube against cube sampling (`cube`), the update
//! policies over a sequence of frames (`policies`).

mod cube;
mod draw;
mod policies;

use skydraw::{Frame, Sky, SkyOptions, SkySource};

/// A colour target the test reads back: Rgba32Float, row 0 at the top.
pub struct Canvas {
    pub texture: wgpu::Texture,
    pub view: wgpu::TextureView,
    pub width: u32,
    pub height: u32,
}

impl Canvas {
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("test canvas"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        Self { texture, view, width, height }
    }

    /// The pixels, row 0 first.
    pub fn read(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Vec<[f32; 4]> {
        read_texture(device, queue, &self.texture, 0, self.width, self.height)
    }
}

/// Reads layer `layer` (mip 0) of an Rgba32Float texture.
pub fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    layer: u32,
    width: u32,
    height: u32,
) -> Vec<[f32; 4]> {
    let row = (width * 16).div_ceil(256) * 256;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: u64::from(row * height),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d { x: 0, y: 0, z: layer },
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: Some(height) },
        },
        wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
    );
    queue.submit([encoder.finish()]);
    buffer.slice(..).map_async(wgpu::MapMode::Read, |r| r.expect("maps"));
    device.poll(wgpu::PollType::wait_indefinitely()).expect("the device finishes");
    let data = buffer.slice(..).get_mapped_range().expect("mapped").to_vec();
    (0..height)
        .flat_map(|y| {
            let start = (y * row) as usize;
            data[start..start + (width * 16) as usize]
                .chunks_exact(16)
                .map(|t| std::array::from_fn(|c| f32::from_le_bytes(t[4 * c..4 * c + 4].try_into().expect("4 bytes"))))
                .collect::<Vec<[f32; 4]>>()
        })
        .collect()
}

/// One frame through the runtime into `canvas` (cleared to `clear` first), without depth.
pub fn frame(gpu: &skyrun::Gpu, sky: &mut Sky, canvas: &Canvas, frame: &Frame) -> skydraw::FrameReport {
    let (device, queue) = (gpu.device(), gpu.queue());
    sky.update(queue, frame, canvas.width, canvas.height);
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    let report = sky.prepare(&mut encoder);
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("test pass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &canvas.view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        sky.draw(&mut pass);
    }
    queue.submit([encoder.finish()]);
    report
}

/// The runtime for `converted` on `gpu` with `options`.
pub fn sky(gpu: &skyrun::Gpu, converted: &skytest::Converted, options: SkyOptions) -> Sky {
    Sky::new(gpu.device(), gpu.queue(), SkySource { wgsl: &converted.wgsl, reflection: &converted.reflection }, options)
        .unwrap_or_else(|e| panic!("the runtime refuses {}: {e}", converted.reflection.shader))
}

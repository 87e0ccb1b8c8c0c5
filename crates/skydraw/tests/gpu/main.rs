//! The runtime on a real Vulkan device (lavapipe without a GPU): drawing into a pass and depth
//! buffer the test owns (`draw`), the radiance cube against cube sampling (`cube`), the update
//! policies over a sequence of frames (`policies`).

mod cube;
mod draw;
mod policies;
mod targets;

use skydraw::{Frame, Sky, SkyOptions, SkySource};
use skytest::canvas::Canvas;

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

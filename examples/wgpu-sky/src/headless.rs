//! `--headless OUT.exr`: the frames rendered without a window on any Vulkan adapter (lavapipe
//! in CI), the last one read back and written as OpenEXR, each frame's report printed.

use crate::scene::{self, Look, SceneRenderer};
use crate::{Args, Failure};
use exr::prelude::{Encoding, SpecificChannels, Vec2, WritableImage};
use std::io::Cursor;
use std::path::Path;
use std::time::Instant;

/// Exact values: the frame is compared with `gdsky render`'s float image.
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

pub fn run(args: &Args, out: &Path) -> Result<(), Failure> {
    let png = match out.extension().and_then(|e| e.to_str()) {
        Some("exr") => false,
        Some("png") => true,
        _ => return Err(Failure::input(format!("--headless {}: expected OUT.exr or OUT.png", out.display()))),
    };
    let converted = scene::convert(args.shader.as_deref())?;
    let textures = scene::load_textures(&args.textures, &converted.reflection)?;
    let (device, queue) = open_device()?;
    let size = args.size.unwrap_or((256, 128));
    let mut renderer = SceneRenderer::new(&device, &queue, &converted, &textures, FORMAT, size, !args.no_mesh)?;
    let mut look = Look {
        yaw_deg: args.yaw,
        pitch_deg: args.pitch,
        fov_deg: args.fov,
        sun_elevation_deg: args.sun.0,
        sun_azimuth_deg: args.sun.1,
        time: args.time,
    };
    for frame in 0..args.frames {
        look.time = args.time + frame as f32 / 60.0;
        let started = Instant::now();
        let mut encoder = device.create_command_encoder(&Default::default());
        let report = renderer.render(&queue, &mut encoder, &look.scene());
        queue.submit([encoder.finish()]);
        device.poll(wgpu::PollType::wait_indefinitely()).map_err(Failure::environment)?;
        println!(
            "frame {frame}: TIME {:.4} s, radiance faces {}, sky {:?}, {:.1} ms",
            look.time,
            report.radiance_faces,
            report.drawn,
            started.elapsed().as_secs_f64() * 1e3
        );
    }
    let pixels = read_back(&device, &queue, renderer.color())?;
    let bytes = if png { encode_png(size, &pixels)? } else { encode_exr(size, &pixels)? };
    skycore::io::write_atomically(out, &bytes).map_err(|e| Failure::environment(format!("{}: {e}", out.display())))?;
    println!("wrote {}", out.display());
    Ok(())
}

fn open_device() -> Result<(wgpu::Device, wgpu::Queue), Failure> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle());
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
        .map_err(|e| Failure::environment(format!("no GPU adapter (Vulkan; lavapipe without a GPU): {e}")))?;
    eprintln!("adapter: {}", adapter.get_info().name);
    pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor::default()))
        .map_err(|e| Failure::environment(format!("the adapter gave no device: {e}")))
}

fn read_back(device: &wgpu::Device, queue: &wgpu::Queue, texture: &wgpu::Texture) -> Result<Vec<[f32; 4]>, Failure> {
    let (width, height) = (texture.width(), texture.height());
    let row = (width * 16).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read-back"),
        size: u64::from(row) * u64::from(height),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: Some(height) },
        },
        texture.size(),
    );
    queue.submit([encoder.finish()]);
    let (sender, receiver) = std::sync::mpsc::channel();
    buffer.slice(..).map_async(wgpu::MapMode::Read, move |result| {
        let _ = sender.send(result);
    });
    device.poll(wgpu::PollType::wait_indefinitely()).map_err(Failure::environment)?;
    receiver
        .try_recv()
        .map_err(|_| Failure::environment("the read-back was not mapped"))?
        .map_err(Failure::environment)?;
    let data = buffer.slice(..).get_mapped_range().map_err(Failure::environment)?;
    let pixels = data
        .chunks_exact(row as usize)
        .flat_map(|line| {
            line[..width as usize * 16].chunks_exact(16).map(|texel| {
                let channel =
                    |c: usize| f32::from_le_bytes([texel[4 * c], texel[4 * c + 1], texel[4 * c + 2], texel[4 * c + 3]]);
                [channel(0), channel(1), channel(2), channel(3)]
            })
        })
        .collect();
    Ok(pixels)
}

/// RGBA 32-bit float, lossless ZIP, row 0 at the top.
fn encode_exr((width, height): (u32, u32), pixels: &[[f32; 4]]) -> Result<Vec<u8>, Failure> {
    let width = width as usize;
    let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
        let [r, g, b, a] = pixels[y * width + x];
        (r, g, b, a)
    });
    let image =
        exr::prelude::Image::from_encoded_channels((width, height as usize), Encoding::SMALL_LOSSLESS, channels);
    let mut bytes = Cursor::new(Vec::new());
    image.write().to_buffered(&mut bytes).map_err(Failure::environment)?;
    Ok(bytes.into_inner())
}

/// An 8-bit preview tone mapped as `gdsky render`'s PNG: 1 − exp(−L·0.5), gamma 2.2.
fn encode_png((width, height): (u32, u32), pixels: &[[f32; 4]]) -> Result<Vec<u8>, Failure> {
    let encode = |c: f32| ((1.0 - (-c.max(0.0) * 0.5).exp()).powf(1.0 / 2.2) * 255.0).round() as u8;
    let rgb: Vec<u8> = pixels.iter().flat_map(|p| [encode(p[0]), encode(p[1]), encode(p[2])]).collect();
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, width, height);
    encoder.set_color(png::ColorType::Rgb);
    let mut writer = encoder.write_header().map_err(Failure::environment)?;
    writer.write_image_data(&rgb).map_err(Failure::environment)?;
    writer.finish().map_err(Failure::environment)?;
    Ok(bytes)
}

//! What the runtime saves, on the Vulkan adapter (lavapipe where there is no GPU), side by side
//! in one run, with the bundled Freeman sky (a ray-marched physical sky: what a real sky costs):
//!
//! * `background`: one 1024×512 frame (update, prepare, draw, submit to idle) with the sky
//!   shaded per pixel, against the same frame sampled from the radiance cube
//!   ([`Background::FromRadiance`], 256² and 512² faces) while nothing the shader reads
//!   changes. Before the timings the bench prints the cached background's error against the
//!   per-pixel frame: mean and p99 relative error (floor 1e-4), and the largest.
//! * `policy`: 24 frames at 256×128 with a 128² radiance cube, the camera turning: the sun still
//!   under `OnChange` (the cube once: 6 faces) and `EveryFrame` (144 faces); the sun moving under
//!   `OnChange` real-time (144) and incremental (24: a face a frame).
//!
//! `cargo bench -p skydraw --bench runtime`

use criterion::{Criterion, criterion_group, criterion_main};
use skydraw::{
    Background, Drawn, Frame, ProcessMode, RadianceOptions, Sky, SkyLight, SkyOptions, SkySource, Target, UpdatePolicy,
};
use skytest::canvas::Canvas;
use std::cell::Cell;
use std::time::Duration;

const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
const FREEMAN: &str = include_str!("../../../fixtures/freeman_sky.gdshader");

fn sky(gpu: &skyrun::Gpu, converted: &skytest::Converted, options: SkyOptions) -> Sky {
    let source = SkySource { wgsl: &converted.wgsl, reflection: &converted.reflection };
    Sky::new(gpu.device(), gpu.queue(), source, options).expect("the runtime takes the Freeman sky")
}

/// The camera turned `yaw` radians, the sun at `elevation` degrees toward −Z.
fn frame(yaw: f32, elevation: f32) -> Frame {
    let e = elevation.to_radians();
    Frame {
        view: skydraw::View::Rotation { camera_to_world: glam::Mat3::from_rotation_y(yaw), fov_y: 1.2 },
        position: glam::Vec3::new(0.0, 1.0, 0.0),
        lights: [
            SkyLight::toward([0.0, e.sin(), -e.cos()], 1.0, [1.0; 3], 0.01),
            SkyLight::default(),
            SkyLight::default(),
            SkyLight::default(),
        ],
        ..Frame::default()
    }
}

/// One frame into `canvas`, waited for.
fn draw(gpu: &skyrun::Gpu, sky: &mut Sky, canvas: &Canvas, frame: &Frame) -> skydraw::FrameReport {
    let (device, queue) = (gpu.device(), gpu.queue());
    sky.update(queue, frame, canvas.width, canvas.height);
    let mut encoder = device.create_command_encoder(&Default::default());
    let report = sky.prepare(&mut encoder);
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &canvas.view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
            })],
            ..Default::default()
        });
        sky.draw(&mut pass);
    }
    queue.submit([encoder.finish()]);
    device.poll(wgpu::PollType::wait_indefinitely()).expect("the device finishes");
    report
}

fn background(c: &mut Criterion) {
    let gpu = skytest::gpu();
    let freeman = skytest::convert("freeman_sky.gdshader", FREEMAN);
    let canvas = Canvas::new(gpu.device(), 1024, 512);
    let still = frame(0.3, 12.0);
    let mut per_pixel = sky(&gpu, &freeman, SkyOptions::new(Target::color(FORMAT)));
    draw(&gpu, &mut per_pixel, &canvas, &still);
    let reference = canvas.read(gpu.device(), gpu.queue());
    let mut cached = Vec::new();
    for size in [256, 512] {
        let options = SkyOptions {
            radiance: Some(RadianceOptions { size, ..Default::default() }),
            background: Background::FromRadiance,
            ..SkyOptions::new(Target::color(FORMAT))
        };
        let mut sky = sky(&gpu, &freeman, options);
        // The first frame renders the cube (and shades per pixel); from the second on the
        // cube is current.
        draw(&gpu, &mut sky, &canvas, &still);
        let report = draw(&gpu, &mut sky, &canvas, &still);
        assert_eq!(report.drawn, Drawn::FromRadiance, "the cube is current on the second frame");
        let m = skyrun::compare(&canvas.read(gpu.device(), gpu.queue()), &reference, 1e-4);
        println!(
            "background from a {size}² radiance cube against per pixel, 1024×512: mean {:.3e}, p99 {:.3e}, max {:.3e} relative error",
            m.mean_rel, m.p99_rel, m.max_rel
        );
        cached.push((size, sky));
    }
    let mut group = c.benchmark_group("background");
    group.sample_size(10).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(8));
    group.bench_function("per_pixel", |b| b.iter(|| draw(&gpu, &mut per_pixel, &canvas, &still)));
    for (size, sky) in &mut cached {
        group.bench_function(format!("from_radiance_{size}"), |b| b.iter(|| draw(&gpu, sky, &canvas, &still)));
    }
    group.finish();
}

fn policy(c: &mut Criterion) {
    let gpu = skytest::gpu();
    let freeman = skytest::convert("freeman_sky.gdshader", FREEMAN);
    let canvas = Canvas::new(gpu.device(), 256, 128);
    let mut group = c.benchmark_group("policy");
    group.sample_size(10).warm_up_time(Duration::from_secs(1)).measurement_time(Duration::from_secs(10));
    let modes = [
        ("still_sun_on_change", UpdatePolicy::OnChange, ProcessMode::RealTime, false),
        ("still_sun_every_frame", UpdatePolicy::EveryFrame, ProcessMode::RealTime, false),
        ("moving_sun_on_change", UpdatePolicy::OnChange, ProcessMode::RealTime, true),
        ("moving_sun_incremental", UpdatePolicy::OnChange, ProcessMode::Incremental, true),
    ];
    for (name, update, process, moving) in modes {
        let options = SkyOptions {
            radiance: Some(RadianceOptions { size: 128, update, process, ..Default::default() }),
            ..SkyOptions::new(Target::color(FORMAT))
        };
        let mut sky = sky(&gpu, &freeman, options);
        // Each sequence starts from a sun the cube has not seen, so a still sun costs one cube
        // per sequence, as the first frames after a change do.
        let sequence = Cell::new(0u32);
        let run = |sky: &mut Sky| {
            let start = 10.0 + 0.01 * sequence.replace(sequence.get() + 1) as f32;
            (0..24)
                .map(|n| {
                    let elevation = if moving { start + 0.5 * n as f32 } else { start };
                    draw(&gpu, sky, &canvas, &frame(0.05 * n as f32, elevation)).radiance_faces
                })
                .sum::<u32>()
        };
        println!("policy/{name}: {} radiance faces in 24 frames", run(&mut sky));
        group.bench_function(name, |b| b.iter(|| run(&mut sky)));
    }
    group.finish();
}

criterion_group!(benches, background, policy);
criterion_main!(benches);

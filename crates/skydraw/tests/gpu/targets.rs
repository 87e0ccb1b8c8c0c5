//! The targets besides a plain single-sampled one: an MSAA colour and depth target resolved into
//! the caller's texture gives the single-sampled sky (the sky is shaded once per pixel, at its
//! centre, so every sample of a pixel holds the same colour), and the background sampled from the
//! radiance cube (`Background::FromRadiance`) is the sky it caches, to the cube's interpolation,
//! and is used only once the cube is complete.

use skydraw::{Background, Drawn, Frame, ProcessMode, RadianceOptions, SkyLight, SkyOptions, Target};
use skytest::canvas::Canvas;

const LIT: &str = "shader_type sky;\nvoid sky() { COLOR = vec3(max(dot(EYEDIR, LIGHT0_DIRECTION), 0.0), 0.5 + 0.5 * EYEDIR.y, 0.2); }\n";

fn lit_frame() -> Frame {
    Frame {
        view: skydraw::View::Rotation { camera_to_world: glam::Mat3::from_rotation_y(0.4), fov_y: 1.3 },
        lights: [
            SkyLight::toward([0.3, 0.5, -0.8], 1.0, [1.0; 3], 0.01),
            SkyLight::default(),
            SkyLight::default(),
            SkyLight::default(),
        ],
        ..Frame::default()
    }
}

fn texture(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    samples: u32,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some("test target"),
        size: wgpu::Extent3d { width: 64, height: 32, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: samples,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// The sky drawn into a 64×32 Rgba16Float target of `samples` samples with a depth buffer,
/// resolved when multisampled; read back as f32.
fn draw_rgba16(gpu: &skyrun::Gpu, converted: &skytest::Converted, samples: u32) -> Vec<[f32; 4]> {
    let (device, queue) = (gpu.device(), gpu.queue());
    let format = wgpu::TextureFormat::Rgba16Float;
    let depth_format = wgpu::TextureFormat::Depth32Float;
    let target = Target {
        color_format: format,
        depth: Some((depth_format, skycore::DepthConvention::Standard)),
        sample_count: samples,
    };
    let mut sky = crate::sky(gpu, converted, SkyOptions::new(target));
    let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
    let resolved = texture(device, format, 1, attachment | wgpu::TextureUsages::COPY_SRC);
    let multisampled = (samples > 1).then(|| texture(device, format, samples, attachment));
    let depth = texture(device, depth_format, samples, attachment).create_view(&Default::default());
    let resolved_view = resolved.create_view(&Default::default());
    let (view, resolve_target) = match &multisampled {
        Some(ms) => (ms.create_view(&Default::default()), Some(&resolved_view)),
        None => (resolved_view.clone(), None),
    };
    sky.update(queue, &lit_frame(), 64, 32);
    let mut encoder = device.create_command_encoder(&Default::default());
    sky.prepare(&mut encoder);
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }),
                stencil_ops: None,
            }),
            ..Default::default()
        });
        sky.draw(&mut pass);
    }
    queue.submit([encoder.finish()]);
    skytest::canvas::read_texture(device, queue, &resolved, 0, 64, 32)
}

#[test]
fn an_msaa_target_resolves_to_the_single_sampled_sky() {
    let gpu = skytest::gpu();
    let converted = skytest::convert("lit.gdshader", LIT);
    let single = draw_rgba16(&gpu, &converted, 1);
    let resolved = draw_rgba16(&gpu, &converted, 4);
    assert!(single.iter().any(|p| p[0] > 0.1), "the single-sampled sky is lit");
    let differ = single.iter().zip(&resolved).filter(|(a, b)| a != b).count();
    assert_eq!(differ, 0, "{differ} of {} resolved pixels differ from the single-sampled sky", single.len());
}

#[test]
fn the_cached_background_is_the_sky_it_caches() {
    let gpu = skytest::gpu();
    let converted = skytest::convert("lit.gdshader", LIT);
    let canvas = Canvas::new(gpu.device(), 128, 64);
    let target = Target::color(wgpu::TextureFormat::Rgba32Float);
    let mut per_pixel = crate::sky(&gpu, &converted, SkyOptions::new(target));
    crate::frame(&gpu, &mut per_pixel, &canvas, &lit_frame());
    let reference = canvas.read(gpu.device(), gpu.queue());

    // Incremental: a face a frame; until the sixth the sky is shaded per pixel.
    let options = |process| SkyOptions {
        radiance: Some(RadianceOptions { size: 256, process, ..Default::default() }),
        background: Background::FromRadiance,
        ..SkyOptions::new(target)
    };
    let mut incremental = crate::sky(&gpu, &converted, options(ProcessMode::Incremental));
    for n in 1..=6 {
        let report = crate::frame(&gpu, &mut incremental, &canvas, &lit_frame());
        let drawn = if n < 6 { Drawn::Shaded } else { Drawn::FromRadiance };
        assert_eq!((report.radiance_faces, report.drawn), (1, drawn), "incremental frame {n}");
        if n < 6 {
            assert_eq!(canvas.read(gpu.device(), gpu.queue()), reference, "frame {n} is shaded per pixel");
        }
    }
    // Real time: the six faces are rendered before the sky is drawn, in the first frame.
    let mut cached = crate::sky(&gpu, &converted, options(ProcessMode::RealTime));
    let first = crate::frame(&gpu, &mut cached, &canvas, &lit_frame());
    assert_eq!((first.radiance_faces, first.drawn), (6, Drawn::FromRadiance));
    let cached_pixels = canvas.read(gpu.device(), gpu.queue());
    let m = skyrun::compare(&cached_pixels, &reference, 1e-2);
    let max_abs = cached_pixels
        .iter()
        .zip(&reference)
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
        .fold(0.0f32, f32::max);
    eprintln!(
        "cached background against per pixel: mean {:.2e}, p99 {:.2e} relative (floor 1e-2), max {:.2e} absolute",
        m.mean_rel, m.p99_rel, max_abs
    );
    // Bilinear interpolation of a smooth sky in 256² Rgba16Float faces: the half floats round
    // to 2⁻¹¹ (4.9e-4) relative, and interpolating max(dot, 0) across its kink misses by up to
    // a quarter of a texel's change of a unit-slope function (a texel spans up to
    // (π/2)/256 = 6.1e-3 rad: 1.5e-3), twice that where the face's texels are largest. A cube
    // flipped or rotated gives errors of order 1.
    assert!(m.p99_rel < 2e-3 && max_abs < 4e-3, "p99 {:.2e}, max absolute {max_abs:.2e}", m.p99_rel);
}

/// The Freeman sky shaded at half and quarter resolution and upsampled in the caller's frame is
/// `gdsky render --sky-resolution half|quarter`'s bit for bit: both shade the reduced pass into
/// Rgba16Float and upsample it with the GPU's bilinear filter at the same texel centres.
#[test]
fn a_reduced_sky_resolution_is_gdsky_renders() {
    let gpu = skytest::gpu();
    let converted = skytest::convert("freeman_sky.gdshader", include_str!("../../../../fixtures/freeman_sky.gdshader"));
    let (width, height) = (96, 64);
    let scene = skytest::SET_UPS[0].scene();
    let material =
        skyrun::material_with_defaults(converted.front.shader.as_ref().expect("checked"), &converted.lowered, &[])
            .expect("the defaults");
    let shader =
        skyrun::SkyShader::new(&gpu, &converted.wgsl, skyrun::SubPasses::default()).expect("skyrun compiles it");
    let builtins = skyrun::SkyBuiltins::from_scene(&scene, width, height);
    for resolution in [skycore::SkyResolution::Half, skycore::SkyResolution::Quarter] {
        let options = skyrun::RenderOptions { resolution, ..Default::default() };
        let reference = shader
            .render_with(&gpu, skycore::Projection::Camera, width, height, &builtins, &material, &options)
            .expect("skyrun renders it")
            .pixels;
        let canvas = Canvas::new(gpu.device(), width, height);
        let sky_options = SkyOptions { resolution, ..SkyOptions::new(Target::color(wgpu::TextureFormat::Rgba32Float)) };
        let mut sky = crate::sky(&gpu, &converted, sky_options);
        let report = crate::frame(&gpu, &mut sky, &canvas, &Frame::from_scene(&scene));
        assert_eq!(report.drawn, Drawn::Upsampled);
        let m = skyrun::compare(&canvas.read(gpu.device(), gpu.queue()), &reference, 1e-4);
        eprintln!("{resolution:?}: p99.9 {:.2e}, max {:.2e} against skyrun", m.p999_rel, m.max_rel);
        assert_eq!(m.max_rel, 0.0, "{resolution:?}: max relative error {:.2e} (p99.9 {:.2e})", m.max_rel, m.p999_rel);
    }
}

/// A radiance cube the caller made (`RadianceOptions::texture`) receives the same six faces as
/// the cube the runtime makes for itself.
#[test]
fn the_radiance_renders_into_a_cube_the_caller_owns() {
    let gpu = skytest::gpu();
    let (device, queue) = (gpu.device(), gpu.queue());
    let converted = skytest::convert("lit.gdshader", LIT);
    let canvas = Canvas::new(device, 16, 8);
    let side = 32;
    let usage =
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC;
    let own = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("the caller's radiance"),
        size: wgpu::Extent3d { width: side, height: side, depth_or_array_layers: 6 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba16Float,
        usage,
        view_formats: &[],
    });
    let options = |texture| SkyOptions {
        radiance: Some(RadianceOptions { size: side, mip_levels: Some(1), texture, ..Default::default() }),
        ..SkyOptions::new(Target::color(wgpu::TextureFormat::Rgba32Float))
    };
    let mut theirs = crate::sky(&gpu, &converted, options(None));
    let mut ours = crate::sky(&gpu, &converted, options(Some(own.clone())));
    assert_eq!(crate::frame(&gpu, &mut theirs, &canvas, &lit_frame()).radiance_faces, 6);
    assert_eq!(crate::frame(&gpu, &mut ours, &canvas, &lit_frame()).radiance_faces, 6);
    let made = theirs.radiance_texture().expect("the runtime's cube").clone();
    assert_eq!(
        made.usage() & wgpu::TextureUsages::COPY_SRC,
        wgpu::TextureUsages::COPY_SRC,
        "the runtime's cube can be read"
    );
    for face in 0..6 {
        let want = skytest::canvas::read_texture(device, queue, &made, face, side, side);
        assert!(want.iter().any(|p| p != &[0.0; 4]), "face {face} was rendered");
        assert_eq!(skytest::canvas::read_texture(device, queue, &own, face, side, side), want, "face {face}");
    }
}

//! The runtime records into a pass and depth buffer the test owns, with a mesh in front: the
//! sky's pixels are `gdsky render`'s for the same scene (skyrun, the renderer behind the
//! command, with the scene's built-ins), bit for bit; the pixels the mesh covers keep the
//! mesh's colour; and a second frame creates no buffer, texture, view, bind group, sampler or
//! pipeline (wgpu's own live-object counters).

use skycore::DepthConvention;
use skydraw::{Frame, SkyOptions, Target};
use skytest::canvas::Canvas;

const WIDTH: u32 = 96;
const HEIGHT: u32 = 64;
const MESH_COLOR: [f32; 4] = [1.0, 0.0, 1.0, 1.0];
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// A quad over the left third of the target at depth ½, writing depth and `MESH_COLOR`.
const MESH_WGSL: &str = "
@vertex fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    var xy = array<vec2<f32>, 6>(vec2(-1.0, -1.0), vec2(-1.0 / 3.0, -1.0), vec2(-1.0, 1.0),
                                 vec2(-1.0, 1.0), vec2(-1.0 / 3.0, -1.0), vec2(-1.0 / 3.0, 1.0));
    return vec4<f32>(xy[i], 0.5, 1.0);
}
@fragment fn fs_main() -> @location(0) vec4<f32> { return vec4<f32>(1.0, 0.0, 1.0, 1.0); }
";

fn mesh_pipeline(device: &wgpu::Device) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("mesh"),
        source: wgpu::ShaderSource::Wgsl(MESH_WGSL.into()),
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("mesh"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        }),
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: wgpu::TextureFormat::Rgba32Float,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// wgpu's live objects of the kinds a frame must not make.
fn live(device: &wgpu::Device) -> [(&'static str, isize); 6] {
    let c = device.get_internal_counters().hal;
    [
        ("buffers", c.buffers.read()),
        ("textures", c.textures.read()),
        ("texture views", c.texture_views.read()),
        ("bind groups", c.bind_groups.read()),
        ("samplers", c.samplers.read()),
        ("render pipelines", c.render_pipelines.read()),
    ]
}

#[test]
fn the_sky_draws_behind_the_callers_mesh_as_gdsky_render_draws_it() {
    let gpu = skytest::gpu();
    let (device, queue) = (gpu.device(), gpu.queue());
    let converted = skytest::convert(
        "freeman_sky.gdshader",
        &std::fs::read_to_string(skytest::root_path("fixtures/freeman_sky.gdshader")).expect("the fixture"),
    );
    let target = Target {
        color_format: wgpu::TextureFormat::Rgba32Float,
        depth: Some((DEPTH_FORMAT, DepthConvention::Standard)),
        sample_count: 1,
    };
    let mut sky = crate::sky(&gpu, &converted, SkyOptions::new(target));
    let canvas = Canvas::new(device, WIDTH, HEIGHT);
    let depth = device
        .create_texture(&wgpu::TextureDescriptor {
            label: Some("test depth"),
            size: wgpu::Extent3d { width: WIDTH, height: HEIGHT, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        })
        .create_view(&wgpu::TextureViewDescriptor::default());
    let mesh = mesh_pipeline(device);
    let scene = skytest::SET_UPS[0].scene();
    let frame = Frame::from_scene(&scene);

    let mut record = |counts: Option<&mut Vec<(&'static str, isize)>>| {
        sky.update(queue, &frame, WIDTH, HEIGHT);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        sky.prepare(&mut encoder);
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("the caller's pass"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &canvas.view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&mesh);
            pass.draw(0..6, 0..1);
            sky.draw(&mut pass);
        }
        if let Some(counts) = counts {
            counts.extend(live(device));
        }
        queue.submit([encoder.finish()]);
        device.poll(wgpu::PollType::wait_indefinitely()).expect("the frame finishes");
    };
    record(None);
    let before = live(device);
    assert!(before[0].1 > 0 && before[3].1 > 0, "wgpu's counters are on: {before:?}");
    let mut during = Vec::new();
    record(Some(&mut during));
    assert_eq!(before.to_vec(), during, "the second frame made objects");

    let pixels = canvas.read(device, queue);
    let builtins = skyrun::SkyBuiltins::from_scene(&scene, WIDTH, HEIGHT);
    let material =
        skyrun::material_with_defaults(converted.front.shader.as_ref().expect("checked"), &converted.lowered, &[])
            .expect("the defaults");
    let reference = skyrun::SkyShader::new(&gpu, &converted.wgsl, skyrun::SubPasses::default())
        .expect("skyrun compiles it")
        .render(&gpu, skycore::Projection::Camera, WIDTH, HEIGHT, &builtins, &material)
        .expect("skyrun renders it")
        .pixels;
    let (mut covered, mut sky_pixels, mut differ) = (0, 0, Vec::new());
    for (i, (ours, theirs)) in pixels.iter().zip(&reference).enumerate() {
        let x = (i as u32) % WIDTH;
        if x < WIDTH / 3 {
            covered += 1;
            assert_eq!(*ours, MESH_COLOR, "pixel {i} is the mesh's");
        } else {
            sky_pixels += 1;
            if ours != theirs {
                differ.push(format!("pixel {i}: {ours:?} against {theirs:?}"));
            }
        }
    }
    eprintln!("{covered} pixels covered by the mesh, {sky_pixels} sky pixels; counts {before:?}");
    assert!(differ.is_empty(), "{} sky pixels differ from skyrun's:\n{}", differ.len(), differ.join("\n"));
}

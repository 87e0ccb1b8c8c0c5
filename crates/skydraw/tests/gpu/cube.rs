//! The runtime's radiance cube is the cube that cube sampling reads: for three asymmetric
//! skies, `textureSampleLevel(cube, dir)` at the 26 directions of the cube's faces, seams and
//! corners gives the sky's colour along `dir` to the tolerance of linear interpolation
//! (`skytest::cube::tolerance`) plus the rounding of its Rgba16Float texels (2⁻¹¹ relative,
//! under 5e-4 for these colours in [0, 1]).

use skydraw::{RadianceOptions, SkyOptions, Target};
use skytest::canvas::read_texture;
use skytest::cube;

const FACE: u32 = 64;
const HALF_FLOAT: f64 = 5e-4;

/// Samples `cube` along each of `directions` into a `directions.len()`×1 Rgba32Float image.
fn sample(gpu: &skyrun::Gpu, cube: &wgpu::Texture, directions: &[glam::DVec3]) -> Vec<[f32; 4]> {
    let (device, queue) = (gpu.device(), gpu.queue());
    let list: Vec<String> =
        directions.iter().map(|d| format!("vec3<f32>({:.9}, {:.9}, {:.9})", d.x, d.y, d.z)).collect();
    let source = format!(
        "@group(0) @binding(0) var cube: texture_cube<f32>;
         @group(0) @binding(1) var cube_sampler: sampler;
         const DIRS = array<vec3<f32>, {n}>({});
         @vertex fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {{
             let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
             return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
         }}
         @fragment fn fs_main(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {{
             return textureSampleLevel(cube, cube_sampler, DIRS[u32(p.x)], 0.0);
         }}",
        list.join(", "),
        n = directions.len()
    );
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("probe"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("probe"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
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
    });
    let view = cube.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::Cube),
        ..Default::default()
    });
    let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..Default::default()
    });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("probe"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) },
            wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&sampler) },
        ],
    });
    let canvas = skytest::canvas::Canvas::new(device, directions.len() as u32, 1);
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("probe"),
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
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.draw(0..3, 0..1);
    }
    queue.submit([encoder.finish()]);
    read_texture(device, queue, &canvas.texture, 0, directions.len() as u32, 1)
}

#[test]
fn the_runtime_s_radiance_cube_samples_as_the_sky() {
    let gpu = skytest::gpu();
    let directions = cube::directions();
    let mut failures = Vec::new();
    for case in &cube::SKIES {
        let converted = skytest::convert(&format!("{}.gdshader", case.name), case.source);
        let options = SkyOptions {
            radiance: Some(RadianceOptions { size: FACE, ..RadianceOptions::default() }),
            ..SkyOptions::new(Target::color(wgpu::TextureFormat::Rgba32Float))
        };
        let mut sky = crate::sky(&gpu, &converted, options);
        let canvas = skytest::canvas::Canvas::new(gpu.device(), 8, 8);
        let report = crate::frame(&gpu, &mut sky, &canvas, &skydraw::Frame::default());
        assert_eq!(report.radiance_faces, 6, "the first frame renders every face");
        let texture = sky.radiance_texture().expect("a radiance cube");
        let sampled = sample(&gpu, texture, &directions);
        failures.extend(cube::misses(case, &sampled, FACE, HALF_FLOAT));
    }
    assert!(
        failures.is_empty(),
        "{} of {} samples off:\n{}",
        failures.len(),
        3 * directions.len(),
        failures.join("\n")
    );
}

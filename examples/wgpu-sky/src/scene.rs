//! The part of wgpu-sky that belongs in a renderer: the sky and a mesh drawn into one HDR
//! colour target with a reversed-Z depth buffer. Per frame: `Sky::update` with the camera,
//! `Sky::prepare` (the radiance cube when an input the shader reads changed), one render pass
//! with the mesh first and the sky last, so the pixels the mesh covers are never shaded.

use crate::Failure;
use glam::{Mat3, Mat4, Vec3};
use skycore::{DepthConvention, Scene, TexelFormat, TextureData};
use skydraw::{Frame, FrameReport, RadianceOptions, Sky, SkyOptions, SkySource, Target};
use std::path::Path;

/// Reversed Z: the far plane (where the sky lies) at depth 0, cleared to 0.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The converted shader, read and converted in memory (no files written).
pub fn convert(shader: Option<&Path>) -> Result<gdsky::Converted, Failure> {
    // The module puts the sky on the far plane of the target's depth convention.
    let options = gdsky::Options::default().depth(DepthConvention::Reversed);
    let converted = match shader {
        Some(path) => {
            gdsky::convert_file(path, &options).map_err(|e| Failure::environment(format!("{}: {e}", path.display())))?
        }
        None => {
            gdsky::convert("freeman_sky.gdshader", include_str!("../../../fixtures/freeman_sky.gdshader"), &options)
        }
    };
    let converted = converted.map_err(Failure::input)?;
    eprint!("{}", converted.warnings);
    Ok(converted)
}

/// `--texture NAME=PATH` as the sky's textures: 8-bit PNGs, sRGB for `source_color` uniforms.
pub fn load_textures(flags: &[String], reflection: &gdsky::Reflection) -> Result<Vec<(String, TextureData)>, Failure> {
    let mut textures = Vec::new();
    for flag in flags {
        let Some((name, path)) = flag.split_once('=') else {
            return Err(Failure::input(format!("--texture {flag}: expected NAME=PATH")));
        };
        let Some(entry) = reflection.bindings.textures.iter().find(|t| t.name == name) else {
            let names: Vec<&str> = reflection.bindings.textures.iter().map(|t| t.name.as_str()).collect();
            return Err(Failure::input(format!(
                "--texture {flag}: the shader has no texture `{name}` (it has: {names:?})"
            )));
        };
        textures.push((name.to_string(), read_png(Path::new(path), entry.srgb)?));
    }
    Ok(textures)
}

fn read_png(path: &Path, srgb: bool) -> Result<TextureData, Failure> {
    let fail = |e: &dyn std::fmt::Display| Failure::environment(format!("{}: {e}", path.display()));
    let file = std::fs::File::open(path).map_err(|e| fail(&e))?;
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().map_err(|e| fail(&e))?;
    let mut pixels = vec![0; reader.output_buffer_size().ok_or_else(|| fail(&"too large"))?];
    let info = reader.next_frame(&mut pixels).map_err(|e| fail(&e))?;
    let rgba: Vec<u8> = pixels[..info.buffer_size()]
        .chunks_exact(info.color_type.samples())
        .flat_map(|px| match *px {
            [l] => [l, l, l, 255],
            [l, a] => [l, l, l, a],
            [r, g, b] => [r, g, b, 255],
            [r, g, b, a, ..] => [r, g, b, a],
            [] => [0; 4],
        })
        .collect();
    let format = if srgb { TexelFormat::Rgba8UnormSrgb } else { TexelFormat::Rgba8Unorm };
    TextureData::new(info.width, info.height, format, rgba).map_err(|e| fail(&e))
}

/// The camera and the sun as the CLI's scene flags give them.
#[derive(Clone, Copy, Debug)]
pub struct Look {
    pub yaw_deg: f64,
    pub pitch_deg: f64,
    pub fov_deg: f64,
    pub sun_elevation_deg: f64,
    pub sun_azimuth_deg: f64,
    pub time: f32,
}

impl Look {
    /// The scene `gdsky render --projection camera` renders for the same flags (camera 1 m up).
    pub fn scene(&self) -> Scene {
        Scene::default()
            .with_sun(self.sun_elevation_deg, self.sun_azimuth_deg)
            .with_position(glam::DVec3::new(0.0, 1.0, 0.0))
            .with_fov(self.fov_deg)
            .with_view(self.yaw_deg, self.pitch_deg)
            .with_time(f64::from(self.time))
    }
}

/// The sky, the optional mesh and the targets they draw into.
pub struct SceneRenderer {
    pub sky: Sky,
    mesh: Option<Mesh>,
    color: wgpu::Texture,
    color_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
    format: wgpu::TextureFormat,
}

impl SceneRenderer {
    /// `format` is the HDR colour target's (Rgba32Float headless, for exact values;
    /// Rgba16Float in the window).
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        converted: &gdsky::Converted,
        textures: &[(String, TextureData)],
        format: wgpu::TextureFormat,
        (width, height): (u32, u32),
        with_mesh: bool,
    ) -> Result<Self, Failure> {
        let target =
            Target { color_format: format, depth: Some((DEPTH_FORMAT, DepthConvention::Reversed)), sample_count: 1 };
        let mut options = SkyOptions::new(target);
        // The cube lights the mesh; without one nothing reads it and it is not made.
        if with_mesh {
            options.radiance = Some(RadianceOptions { size: 128, ..Default::default() });
        }
        let source = SkySource { wgsl: &converted.wgsl, reflection: &converted.reflection };
        let mut sky = Sky::new(device, queue, source, options).map_err(Failure::input)?;
        for (name, data) in textures {
            sky.set_texture(queue, name, data).map_err(Failure::input)?;
        }
        let mesh = match (with_mesh, sky.radiance_texture()) {
            (true, Some(radiance)) => Some(Mesh::new(device, format, radiance)),
            _ => None,
        };
        let (color, color_view, depth_view) = targets(device, format, width, height);
        Ok(Self { sky, mesh, color, color_view, depth_view, format })
    }

    /// Makes the targets again for a new size.
    pub fn resize(&mut self, device: &wgpu::Device, width: u32, height: u32) {
        (self.color, self.color_view, self.depth_view) = targets(device, self.format, width, height);
    }

    /// The HDR colour target (linear radiance).
    pub fn color(&self) -> &wgpu::Texture {
        &self.color
    }

    /// Records one frame of `scene` into `encoder`.
    pub fn render(&mut self, queue: &wgpu::Queue, encoder: &mut wgpu::CommandEncoder, scene: &Scene) -> FrameReport {
        let (width, height) = (self.color.width(), self.color.height());
        self.sky.update(queue, &Frame::from_scene(scene), width, height);
        if let Some(mesh) = &self.mesh {
            mesh.update(queue, scene, width as f32 / height as f32);
        }
        let report = self.sky.prepare(encoder);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("wgpu-sky scene"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &self.color_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.depth_view,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(0.0), store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            ..Default::default()
        });
        if let Some(mesh) = &self.mesh {
            mesh.draw(&mut pass);
        }
        self.sky.draw(&mut pass);
        report
    }
}

fn targets(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    width: u32,
    height: u32,
) -> (wgpu::Texture, wgpu::TextureView, wgpu::TextureView) {
    let texture = |label, format, usage| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let usage =
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC;
    let color = texture("wgpu-sky colour", format, usage);
    let depth = texture("wgpu-sky depth", DEPTH_FORMAT, wgpu::TextureUsages::RENDER_ATTACHMENT);
    let color_view = color.create_view(&Default::default());
    let depth_view = depth.create_view(&Default::default());
    (color, color_view, depth_view)
}

/// A cube 3.5 m in front of the camera's start, turning with TIME, lit by the sun (LIGHT0) and
/// by the sky's radiance cube (a blurred mip as ambient light, a sharper one as reflection).
struct Mesh {
    pipeline: wgpu::RenderPipeline,
    vertices: wgpu::Buffer,
    uniforms: wgpu::Buffer,
    group: wgpu::BindGroup,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct MeshUniforms {
    view_projection: [[f32; 4]; 4],
    model: [[f32; 4]; 4],
    /// xyz: toward the sun; w: 1 when LIGHT0 is on.
    sun: [f32; 4],
    /// LIGHT0_COLOR × LIGHT0_ENERGY.
    sun_color: [f32; 4],
    camera: [f32; 4],
}

const MESH_WGSL: &str = r#"
struct Uniforms { view_projection: mat4x4<f32>, model: mat4x4<f32>, sun: vec4<f32>, sun_color: vec4<f32>, camera: vec4<f32> }
@group(0) @binding(0) var<uniform> u: Uniforms;
@group(0) @binding(1) var radiance: texture_cube<f32>;
@group(0) @binding(2) var radiance_sampler: sampler;

struct Varyings { @builtin(position) clip: vec4<f32>, @location(0) normal: vec3<f32>, @location(1) world: vec3<f32> }

@vertex fn vs_main(@location(0) position: vec3<f32>, @location(1) normal: vec3<f32>) -> Varyings {
    let world = u.model * vec4(position, 1.0);
    return Varyings(u.view_projection * world, (u.model * vec4(normal, 0.0)).xyz, world.xyz);
}

@fragment fn fs_main(v: Varyings) -> @location(0) vec4<f32> {
    let n = normalize(v.normal);
    let to_eye = normalize(u.camera.xyz - v.world);
    let levels = f32(textureNumLevels(radiance));
    // The cube's mips are box-filtered: a 4×4 level stands in for irradiance, a 32×32 one for
    // a rough reflection. Enough for a demo; a renderer would prefilter (GGX) instead.
    let ambient = textureSampleLevel(radiance, radiance_sampler, n, levels - 3.0).rgb;
    let reflected = textureSampleLevel(radiance, radiance_sampler, reflect(-to_eye, n), levels - 6.0).rgb;
    let direct = u.sun_color.rgb * max(dot(n, u.sun.xyz), 0.0) * u.sun.w;
    let fresnel = 0.04 + 0.96 * pow(1.0 - max(dot(n, to_eye), 0.0), 5.0);
    let albedo = vec3(0.6, 0.55, 0.5);
    return vec4(albedo * (direct + ambient) + fresnel * reflected, 1.0);
}
"#;

impl Mesh {
    fn new(device: &wgpu::Device, format: wgpu::TextureFormat, radiance: &wgpu::Texture) -> Self {
        use wgpu::util::DeviceExt;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("mesh"),
            source: wgpu::ShaderSource::Wgsl(MESH_WGSL.into()),
        });
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("cube vertices"),
            contents: bytemuck::cast_slice(&cube_vertices()),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("mesh uniforms"),
            size: std::mem::size_of::<MeshUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("mesh"),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: 24,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
                })],
            },
            primitive: wgpu::PrimitiveState { cull_mode: Some(wgpu::Face::Back), ..Default::default() },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Greater),
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState::default(),
            }),
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let cube_view = radiance.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::Cube),
            ..Default::default()
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("mesh"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&cube_view) },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::Sampler(&sampler) },
            ],
        });
        Self { pipeline, vertices, uniforms, group }
    }

    fn update(&self, queue: &wgpu::Queue, scene: &Scene, aspect: f32) {
        let c = |v: glam::DVec3| Vec3::new(v.x as f32, v.y as f32, v.z as f32);
        let basis = scene.camera.basis();
        let camera_to_world = Mat3::from_cols(c(basis.x_axis), c(basis.y_axis), c(basis.z_axis));
        let position = c(scene.camera.position);
        let view = Mat4::from_mat3(camera_to_world.transpose()) * Mat4::from_translation(-position);
        let fov_y = (scene.camera.fov_deg as f32).to_radians();
        let projection = glam::camera::rh::proj::directx::perspective_infinite_reverse(fov_y, aspect, 0.05);
        let turn = 0.4 * scene.time as f32;
        let model = Mat4::from_translation(Vec3::new(0.0, 1.0, -3.5))
            * Mat4::from_rotation_y(0.6 + turn)
            * Mat4::from_rotation_x(0.5);
        let sun = scene.sun();
        let toward = c(sun.direction());
        let energy = sun.energy;
        let uniforms = MeshUniforms {
            view_projection: (projection * view).to_cols_array_2d(),
            model: model.to_cols_array_2d(),
            sun: [toward.x, toward.y, toward.z, if sun.enabled { 1.0 } else { 0.0 }],
            sun_color: [sun.color[0] * energy, sun.color[1] * energy, sun.color[2] * energy, 0.0],
            camera: [position.x, position.y, position.z, 1.0],
        };
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
    }

    fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.group, &[]);
        pass.set_vertex_buffer(0, self.vertices.slice(..));
        pass.draw(0..36, 0..1);
    }
}

/// A unit cube's 36 vertices (position, normal), counter-clockwise seen from outside.
fn cube_vertices() -> Vec<[f32; 6]> {
    let mut vertices = Vec::with_capacity(36);
    for axis in 0..3 {
        for sign in [1.0f32, -1.0] {
            let mut n = [0.0f32; 3];
            n[axis] = sign;
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let corner = |a: f32, b: f32| {
                let mut p = [0.0f32; 3];
                p[axis] = 0.5 * sign;
                p[u] = 0.5 * a * sign;
                p[v] = 0.5 * b;
                [p[0], p[1], p[2], n[0], n[1], n[2]]
            };
            let quad = [corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)];
            vertices.extend([quad[0], quad[1], quad[2], quad[0], quad[2], quad[3]]);
        }
    }
    vertices
}

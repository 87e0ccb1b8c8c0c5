//! The radiance cube map: the sky rendered into the six layers of a cube texture by the
//! shader's own cubemap pass, with a mip chain, when the update policy says so; and the
//! background drawn from it.
//!
//! Orientation: face k of the cube is rendered so that its texel (row r, column c) holds the
//! sky in the direction cube sampling assigns that texel (the Vulkan and WebGPU convention,
//! which Godot's radiance map follows): `textureSample(cube, dir)` returns the sky along
//! `dir`. The wrapper's `fs_cubemap` does this ([`skycore::cube_face_basis`]).
//!
//! Updates follow Godot's and Unity HDRP's modes: [`UpdatePolicy::OnChange`] renders when an
//! input the shader reads changed (the built-ins the reflection lists: TIME, POSITION, the
//! lights; the material; the bound textures), [`UpdatePolicy::OnDemand`] when
//! [`crate::Sky::request_radiance`] asks, [`UpdatePolicy::EveryFrame`] always; the
//! [`ProcessMode`] renders the due faces all in one frame or one per frame (Godot's
//! incremental mode). Each face's mips are made right after it (a 2×2 box filter per level).

use crate::sky::{SkyError, Target, texture_group_layout};
use skycore::DepthConvention;

/// When the radiance is rendered again.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum UpdatePolicy {
    /// When an input the shader reads changed since the cube was rendered (Godot's default
    /// for skies that do not read TIME).
    #[default]
    OnChange,
    /// Only when asked ([`crate::Sky::request_radiance`]).
    OnDemand,
    /// Every frame.
    EveryFrame,
}

/// How the due faces are spread over frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ProcessMode {
    /// All due faces in one frame (Godot's real-time mode).
    #[default]
    RealTime,
    /// One face per frame (Godot's incremental mode): cheaper frames, six frames to catch up.
    Incremental,
}

/// The radiance cube's set-up.
#[derive(Clone, Debug)]
pub struct RadianceOptions {
    /// Side of each face in texels (Godot's `radiance_size`, 256 by default).
    pub size: u32,
    /// Texel format (renderable and filterable: `Rgba16Float` by default).
    pub format: wgpu::TextureFormat,
    /// Mip levels, the full chain down to 1×1 by default.
    pub mip_levels: Option<u32>,
    /// When to render it again.
    pub update: UpdatePolicy,
    /// All due faces at once, or one per frame.
    pub process: ProcessMode,
    /// Render into this cube texture (six layers, `RENDER_ATTACHMENT | TEXTURE_BINDING`) of the
    /// caller's instead of one the runtime makes; its size, format and mip count are used.
    pub texture: Option<wgpu::Texture>,
}

impl Default for RadianceOptions {
    fn default() -> Self {
        Self {
            size: 256,
            format: wgpu::TextureFormat::Rgba16Float,
            mip_levels: None,
            update: UpdatePolicy::OnChange,
            process: ProcessMode::RealTime,
            texture: None,
        }
    }
}

/// The runtime's helper shaders: the background sampled from the radiance along each pixel's
/// EYEDIR (the wrapper's camera ray, from the same built-ins), the bilinear upsampling of a
/// reduced-resolution sky, and one mip level from the one above (a 2×2 box).
pub(crate) const HELPERS_WGSL: &str = r#"
struct SkyLight { direction: vec3<f32>, energy: f32, color: vec3<f32>, size: f32, enabled: u32 }
struct SkyBuiltins {
    camera_basis: mat3x3<f32>, position: vec3<f32>, time: f32, screen_size: vec2<f32>,
    tan_half_fov: f32, render_pass: u32, luminance_multiplier: f32, cube_face: u32,
    lights: array<SkyLight, 4>,
}
@group(0) @binding(0) var<uniform> sky: SkyBuiltins;
@group(1) @binding(0) var cube: texture_cube<f32>;
@group(1) @binding(1) var cube_sampler: sampler;

override FAR_PLANE: f32 = 1.0;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, FAR_PLANE, 1.0);
}

@fragment
fn fs_radiance(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let uv = frag.xy / sky.screen_size;
    let t = sky.tan_half_fov;
    let aspect = sky.screen_size.x / sky.screen_size.y;
    let ray = vec3<f32>((2.0 * uv.x - 1.0) * t * aspect, (1.0 - 2.0 * uv.y) * t, -1.0);
    let eyedir = normalize(sky.camera_basis * ray);
    return vec4<f32>(textureSampleLevel(cube, cube_sampler, eyedir, 0.0).rgb, 0.0);
}
"#;

/// The upsampling and mip shaders (a 2D texture at group 1).
pub(crate) const FLAT_WGSL: &str = r#"
struct SkyBuiltins { camera_basis: mat3x3<f32>, position: vec3<f32>, time: f32, screen_size: vec2<f32> }
@group(0) @binding(0) var<uniform> sky: SkyBuiltins;
@group(1) @binding(0) var image: texture_2d<f32>;
@group(1) @binding(1) var image_sampler: sampler;

override FAR_PLANE: f32 = 1.0;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, FAR_PLANE, 1.0);
}

@fragment
fn fs_upsample(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    return vec4<f32>(textureSampleLevel(image, image_sampler, frag.xy / sky.screen_size, 0.0).rgb, 0.0);
}

@fragment
fn fs_mip(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let p = vec2<i32>(frag.xy) * 2;
    let size = vec2<i32>(textureDimensions(image)) - 1;
    var sum = vec4<f32>(0.0);
    for (var k = 0; k < 4; k++) {
        sum += textureLoad(image, min(p + vec2<i32>(k & 1, k >> 1), size), 0);
    }
    return sum * 0.25;
}
"#;

/// A fullscreen-triangle pipeline of a helper shader into one colour target.
#[allow(clippy::too_many_arguments)]
pub(crate) fn helper_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    builtins_layout: &wgpu::BindGroupLayout,
    texture_layout: &wgpu::BindGroupLayout,
    entry: &str,
    format: wgpu::TextureFormat,
    depth: Option<wgpu::DepthStencilState>,
    samples: u32,
    convention: DepthConvention,
) -> wgpu::RenderPipeline {
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(entry),
        bind_group_layouts: &[Some(builtins_layout), Some(texture_layout)],
        immediate_size: 0,
    });
    let constants = [("FAR_PLANE", f64::from(convention.far_plane()))];
    let options = wgpu::PipelineCompilationOptions { constants: &constants, ..Default::default() };
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(entry),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_main"),
            compilation_options: options.clone(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: depth,
        multisample: wgpu::MultisampleState { count: samples, ..Default::default() },
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(entry),
            compilation_options: options,
            targets: &[Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL })],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// The cube, its views and the state of its updates.
pub(crate) struct Radiance {
    texture: wgpu::Texture,
    cube_view: wgpu::TextureView,
    /// Render views: `targets[level][face]`.
    targets: Vec<Vec<wgpu::TextureView>>,
    /// Sources of each level ≥ 1: `mips[level - 1][face]` reads level − 1 of that face.
    mips: Vec<Vec<wgpu::BindGroup>>,
    cube_pipeline: wgpu::RenderPipeline,
    mip_pipeline: wgpu::RenderPipeline,
    background: wgpu::RenderPipeline,
    background_group: wgpu::BindGroup,
    update: UpdatePolicy,
    process: ProcessMode,
    /// Faces still to render, one bit each.
    due: u8,
    /// Whether the inputs changed since the faces were last all rendered.
    outdated: bool,
    /// Where the next round of faces starts.
    next_face: u32,
}

impl Radiance {
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        device: &wgpu::Device,
        options: &RadianceOptions,
        cube_pipeline: wgpu::RenderPipeline,
        helpers: &wgpu::ShaderModule,
        builtins_layout: &wgpu::BindGroupLayout,
        target: &Target,
        depth: Option<wgpu::DepthStencilState>,
        convention: DepthConvention,
    ) -> Result<Self, SkyError> {
        let texture = match &options.texture {
            Some(texture) => {
                if texture.depth_or_array_layers() != 6 || texture.width() != texture.height() {
                    return Err(SkyError::Unsupported(format!(
                        "a radiance texture of {}×{}×{}: a cube map is six square layers",
                        texture.width(),
                        texture.height(),
                        texture.depth_or_array_layers()
                    )));
                }
                texture.clone()
            }
            None => {
                let size = options.size.max(1);
                let full_chain = 32 - size.leading_zeros();
                device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("sky radiance"),
                    size: wgpu::Extent3d { width: size, height: size, depth_or_array_layers: 6 },
                    mip_level_count: options.mip_levels.unwrap_or(full_chain).clamp(1, full_chain),
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: options.format,
                    // COPY_SRC: a renderer may copy the cube into its own resources (an engine's
                    // environment map, a baked probe).
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                        | wgpu::TextureUsages::TEXTURE_BINDING
                        | wgpu::TextureUsages::COPY_SRC,
                    view_formats: &[],
                })
            }
        };
        let layer = |level: u32, face: u32| {
            texture.create_view(&wgpu::TextureViewDescriptor {
                label: Some("sky radiance face"),
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_mip_level: level,
                mip_level_count: Some(1),
                base_array_layer: face,
                array_layer_count: Some(1),
                ..Default::default()
            })
        };
        let levels = texture.mip_level_count();
        let targets: Vec<Vec<wgpu::TextureView>> =
            (0..levels).map(|level| (0..6).map(|face| layer(level, face)).collect()).collect();
        let flat_layout = texture_group_layout(device, wgpu::TextureViewDimension::D2);
        let nearest = device.create_sampler(&wgpu::SamplerDescriptor { label: Some("sky mip"), ..Default::default() });
        let mips = targets
            .iter()
            .take(levels as usize - 1)
            .map(|faces| {
                faces
                    .iter()
                    .map(|view| {
                        device.create_bind_group(&wgpu::BindGroupDescriptor {
                            label: Some("sky radiance mip"),
                            layout: &flat_layout,
                            entries: &[
                                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(view) },
                                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&nearest) },
                            ],
                        })
                    })
                    .collect()
            })
            .collect();
        let flat = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("sky flat helpers"),
            source: wgpu::ShaderSource::Wgsl(FLAT_WGSL.into()),
        });
        let format = texture.format();
        let mip_pipeline = helper_pipeline(
            device,
            &flat,
            builtins_layout,
            &flat_layout,
            "fs_mip",
            format,
            None,
            1,
            DepthConvention::Standard,
        );
        let cube_view = texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some("sky radiance cube"),
            dimension: Some(wgpu::TextureViewDimension::Cube),
            ..Default::default()
        });
        let cube_layout = texture_group_layout(device, wgpu::TextureViewDimension::Cube);
        let linear = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("sky radiance"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        let background_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("sky background"),
            layout: &cube_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&cube_view) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&linear) },
            ],
        });
        let background = helper_pipeline(
            device,
            helpers,
            builtins_layout,
            &cube_layout,
            "fs_radiance",
            target.color_format,
            depth,
            target.sample_count,
            convention,
        );
        Ok(Self {
            texture,
            cube_view,
            targets,
            mips,
            cube_pipeline,
            mip_pipeline,
            background,
            background_group,
            update: options.update,
            process: options.process,
            due: 0,
            outdated: true,
            next_face: 0,
        })
    }

    pub(crate) fn texture(&self) -> &wgpu::Texture {
        &self.texture
    }

    pub(crate) fn cube_view(&self) -> wgpu::TextureView {
        self.cube_view.clone()
    }

    pub(crate) fn size(&self) -> u32 {
        self.texture.width()
    }

    pub(crate) fn request(&mut self) {
        self.due = 0b11_1111;
    }

    /// Takes this frame's news: whether an input the shader reads changed.
    pub(crate) fn note_inputs(&mut self, changed: bool) {
        if changed {
            self.outdated = true;
        }
        let render = match self.update {
            UpdatePolicy::OnChange => changed,
            UpdatePolicy::OnDemand => false,
            UpdatePolicy::EveryFrame => self.due == 0,
        };
        if render {
            self.due = 0b11_1111;
        }
    }

    /// Whether the cube holds the sky of the current inputs.
    pub(crate) fn is_current(&self) -> bool {
        !self.outdated
    }

    /// Renders the faces due this frame (and their mips); returns how many.
    pub(crate) fn render_due(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        face_groups: &[wgpu::BindGroup],
        other_groups: &[Option<&wgpu::BindGroup>],
    ) -> u32 {
        // Round robin from the face after the last one rendered, so that under inputs that
        // change every frame the incremental mode still goes through all six faces.
        let faces: Vec<u32> = (0..6).map(|k| (self.next_face + k) % 6).filter(|f| self.due & (1 << f) != 0).collect();
        let faces = match self.process {
            ProcessMode::RealTime => faces,
            ProcessMode::Incremental => faces.into_iter().take(1).collect(),
        };
        if let Some(last) = faces.last() {
            self.next_face = (last + 1) % 6;
        }
        for &face in &faces {
            self.pass(encoder, &self.cube_pipeline, &self.targets[0][face as usize], |pass| {
                pass.set_bind_group(0, &face_groups[face as usize], &[]);
                for (i, group) in other_groups.iter().enumerate() {
                    if let Some(group) = group {
                        pass.set_bind_group(i as u32 + 1, *group, &[]);
                    }
                }
            });
            for level in 1..self.targets.len() {
                self.pass(encoder, &self.mip_pipeline, &self.targets[level][face as usize], |pass| {
                    pass.set_bind_group(0, &face_groups[face as usize], &[]);
                    pass.set_bind_group(1, &self.mips[level - 1][face as usize], &[]);
                });
            }
            self.due &= !(1 << face);
        }
        if self.due == 0 && !faces.is_empty() {
            self.outdated = false;
        }
        faces.len() as u32
    }

    fn pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::RenderPipeline,
        view: &wgpu::TextureView,
        bind: impl FnOnce(&mut wgpu::RenderPass<'_>),
    ) {
        let mut pass = crate::sky::begin_offscreen_pass(encoder, view, "sky radiance");
        pass.set_pipeline(pipeline);
        bind(&mut pass);
        pass.draw(0..3, 0..1);
    }

    /// The visible sky sampled from the cube along each pixel's EYEDIR.
    pub(crate) fn draw_background(&self, pass: &mut wgpu::RenderPass<'_>, builtins: &wgpu::BindGroup) {
        pass.set_pipeline(&self.background);
        pass.set_bind_group(0, builtins, &[]);
        pass.set_bind_group(1, &self.background_group, &[]);
        pass.draw(0..3, 0..1);
    }
}

//! The render-world plugin: a converted Godot sky drawn by `skydraw` in Bevy's `Core3d`
//! schedule, behind the opaque geometry, on Bevy's own device, queue, colour target and depth
//! buffer.

use bevy::asset::RenderAssetUsages;
use bevy::core_pipeline::core_3d::{main_opaque_pass_3d, main_transparent_pass_3d};
use bevy::core_pipeline::{Core3d, Core3dSystems};
use bevy::image::Image;
use bevy::platform::collections::HashMap;
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::extract_component::{ExtractComponent, ExtractComponentPlugin};
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::{
    Extent3d, RenderPassDescriptor, StoreOp, TextureDimension, TextureFormat, TextureUsages, TextureViewDescriptor,
    TextureViewDimension,
};
use bevy::render::renderer::{RenderContext, RenderDevice, RenderQueue, ViewQuery};
use bevy::render::texture::GpuImage;
use bevy::render::view::{ExtractedView, Msaa, ViewDepthStencilTexture, ViewTarget};
use bevy::render::{Extract, ExtractSchedule, Render, RenderApp, RenderSystems};
use skycore::DepthConvention;
use skycore::reflection::Reflection;
// skydraw's Frame takes glam 0.34 (re-exported); Bevy 0.20 is on glam 0.33: values cross as arrays.
use skydraw::glam;
use skydraw::{Frame, RadianceOptions, Sky, SkyLight, SkyOptions, SkySource, Target, View};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// Bevy's 3D depth format (`bevy::core_pipeline::core_3d::CORE_3D_DEPTH_FORMAT`); Bevy's depth is
/// reversed Z (near 1, far 0), so the sky is converted for [`DepthConvention::Reversed`].
const DEPTH: (TextureFormat, DepthConvention) =
    (bevy::core_pipeline::core_3d::CORE_3D_DEPTH_FORMAT, DepthConvention::Reversed);

/// Put on a `Camera3d`: the converted sky is drawn behind its opaque geometry.
#[derive(Component, Clone, Default, ExtractComponent)]
#[extract_app(RenderApp)]
pub struct GodotSky {
    /// A cube `Image` made by [`radiance_image`]: skydraw's radiance cube (rendered when the
    /// sky's inputs change) is copied into it in Bevy's cube-map orientation, for
    /// `GeneratedEnvironmentMapLight` to filter.
    pub radiance: Option<Handle<Image>>,
}

/// Put on the `DirectionalLight` that is the sky's `LIGHT0`. Up to four become `LIGHT0` …
/// `LIGHT3` in the order Bevy's query yields them (not necessarily spawn order: mark one light
/// for a determined `LIGHT0`). The light shines along its transform's forward (−Z), so the
/// direction toward it, Godot's `LIGHTn_DIRECTION`, is the transform's back (+Z).
#[derive(Component, Clone, Copy, Debug)]
pub struct SkySun {
    /// `LIGHTn_ENERGY` (Godot's `light_energy`; Bevy's illuminance is another unit).
    pub energy: f32,
    /// Angular diameter in degrees (Godot's `light_angular_distance`), `LIGHTn_SIZE` in radians.
    pub angular_diameter_deg: f32,
}

impl Default for SkySun {
    fn default() -> Self {
        Self { energy: 1.0, angular_diameter_deg: 0.5 }
    }
}

/// A cube image of six `size`×`size` Rgba16Float layers that the plugin writes
/// (`RENDER_ATTACHMENT`) and Bevy can sample and filter (`TEXTURE_BINDING`, a cube view).
/// `size` must be a power of two for `GeneratedEnvironmentMapLight`.
pub fn radiance_image(size: u32) -> Image {
    let mut image = Image::new_uninit(
        Extent3d { width: size, height: size, depth_or_array_layers: 6 },
        TextureDimension::D2,
        TextureFormat::Rgba16Float,
        RenderAssetUsages::all(),
    );
    image.texture_descriptor.usage =
        TextureUsages::TEXTURE_BINDING | TextureUsages::RENDER_ATTACHMENT | TextureUsages::COPY_SRC;
    image.texture_view_descriptor =
        Some(TextureViewDescriptor { dimension: Some(TextureViewDimension::Cube), ..default() });
    image
}

/// The converted shader and the material values it is drawn with.
#[derive(Clone)]
pub struct SkyShader {
    /// The WGSL module (converted for reversed Z).
    pub wgsl: String,
    /// Its reflection.
    pub reflection: Reflection,
    /// Material uniforms set on every `Sky` made (name, value).
    pub uniforms: Vec<(String, skycore::UniformValue)>,
}

impl SkyShader {
    /// The example's sky ([`crate::SKY_SHADER`]) converted for Bevy's reversed-Z depth, at its
    /// defaults.
    pub fn freeman_fast() -> Result<Self, gdsky::ConvertError> {
        let converted = crate::convert_sky(DepthConvention::Reversed)?;
        Ok(Self { wgsl: converted.wgsl, reflection: converted.reflection, uniforms: Vec::new() })
    }
}

/// Counts the frames in which the sky was drawn, for whoever waits for it (the headless
/// render): shared between the worlds.
#[derive(Resource, Clone, Default)]
pub struct SkyDrawCount(pub Arc<AtomicU64>);

impl SkyDrawCount {
    /// Frames drawn so far.
    pub fn get(&self) -> u64 {
        self.0.load(Ordering::Relaxed)
    }
}

/// Draws `shader` for every camera that carries [`GodotSky`].
pub struct GodotSkyPlugin {
    /// The converted sky.
    pub shader: SkyShader,
}

impl Plugin for GodotSkyPlugin {
    fn build(&self, app: &mut App) {
        let count = SkyDrawCount::default();
        app.insert_resource(count.clone()).add_plugins(ExtractComponentPlugin::<GodotSky>::default());
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app
            .insert_resource(ShaderResource(Arc::new(self.shader.clone())))
            .insert_resource(count)
            .init_resource::<Skies>()
            .init_resource::<ExtractedSkyFrame>()
            .add_systems(ExtractSchedule, extract_sky_frame)
            .add_systems(Render, forget_gone_views.in_set(RenderSystems::Cleanup))
            .add_systems(
                Core3d,
                draw_sky.after(main_opaque_pass_3d).before(main_transparent_pass_3d).in_set(Core3dSystems::MainPass),
            );
    }
}

#[derive(Resource)]
struct ShaderResource(Arc<SkyShader>);

/// One `Sky` per camera (render-world view entity).
#[derive(Resource, Default)]
struct Skies(HashMap<Entity, ViewSky>);

/// A camera's sky and the target it was made for; `None` after skydraw refused it.
struct ViewSky {
    target: Target,
    sky: Option<(Sky, Option<EnvironmentCopy>)>,
}

/// What the sky reads besides the camera: time and lights, from the main world.
#[derive(Resource, Default, Clone, Copy)]
struct ExtractedSkyFrame {
    time: f32,
    lights: [SkyLight; 4],
}

/// Drops the skies of cameras that are gone or no longer carry [`GodotSky`].
fn forget_gone_views(mut skies: ResMut<Skies>, views: Query<(), With<GodotSky>>) {
    skies.0.retain(|entity, _| views.contains(*entity));
}

fn extract_sky_frame(
    mut frame: ResMut<ExtractedSkyFrame>,
    time: Extract<Res<Time>>,
    suns: Extract<Query<(&DirectionalLight, &GlobalTransform, &SkySun)>>,
) {
    let mut lights = [SkyLight::default(); 4];
    for (slot, (light, transform, sun)) in lights.iter_mut().zip(suns.iter()) {
        let toward = transform.back();
        let color = light.color.to_linear();
        *slot = SkyLight::toward(
            toward.to_array(),
            sun.energy,
            [color.red, color.green, color.blue],
            sun.angular_diameter_deg.to_radians(),
        );
    }
    *frame = ExtractedSkyFrame { time: time.elapsed_secs(), lights };
}

/// Bevy's glam (0.33) to skydraw's (0.34), by value.
fn mat4(m: Mat4) -> glam::Mat4 {
    glam::Mat4::from_cols_array(&m.to_cols_array())
}

#[allow(clippy::too_many_arguments)]
fn draw_sky(
    view: ViewQuery<(&ExtractedCamera, &ExtractedView, &ViewTarget, &ViewDepthStencilTexture, &Msaa, &GodotSky)>,
    shader: Res<ShaderResource>,
    frame: Res<ExtractedSkyFrame>,
    count: Res<SkyDrawCount>,
    mut skies: ResMut<Skies>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    images: Res<RenderAssets<GpuImage>>,
    mut ctx: RenderContext,
) {
    let entity = view.entity();
    let (camera, extracted, target, depth, msaa, godot_sky) = view.into_inner();
    let Some(size) = camera.physical_viewport_size else {
        return;
    };
    if camera.viewport.as_ref().is_some_and(|v| v.physical_position != UVec2::ZERO) {
        // skydraw's camera entry maps framebuffer coordinates (`@builtin(position)`) over
        // `screen_size`: a viewport that does not start at the corner would shift the sky.
        warn_once!("bevy-sky: a camera viewport with an offset is not supported; the sky is not drawn");
        return;
    }
    let wanted =
        Target { color_format: target.main_texture_format(), depth: Some(DEPTH), sample_count: msaa.samples() };
    let radiance = match &godot_sky.radiance {
        Some(handle) => match images.get(handle) {
            Some(image) => Some(image),
            // Its GPU texture is not made yet: wait a frame rather than make a Sky without it.
            None => return,
        },
        None => None,
    };
    let stale = skies.0.get(&entity).is_none_or(|made| made.target != wanted);
    if stale {
        // Made the first time, and again when the view's format or MSAA changes; a refusal is
        // logged once and not tried again for the same target.
        let sky = make_sky(&device, &queue, &shader.0, wanted, radiance);
        skies.0.insert(entity, ViewSky { target: wanted, sky });
    }
    let Some((sky, environment)) = skies.0.get_mut(&entity).and_then(|made| made.sky.as_mut()) else {
        return;
    };

    // The camera as Bevy has it this frame: world_from_view · view_from_clip (or the explicit
    // clip_from_world when the view has one), from which skydraw recovers the rays.
    let inverse_view_projection = match extracted.clip_from_world {
        Some(clip_from_world) => clip_from_world.inverse(),
        None => extracted.world_from_view.to_matrix() * extracted.clip_from_view.inverse(),
    };
    let sky_frame = Frame {
        view: View::InverseViewProjection(mat4(inverse_view_projection)),
        position: glam::Vec3::from_array(extracted.world_from_view.translation().to_array()),
        time: frame.time,
        lights: frame.lights,
    };
    sky.update(&queue, &sky_frame, size.x, size.y);
    let encoder = ctx.command_encoder();
    let report = sky.prepare(encoder);
    if let Some(environment) = environment
        && (report.radiance_faces > 0 || !environment.done)
        && report.radiance_current
    {
        environment.record(encoder);
    }
    {
        let color = [Some(target.get_color_attachment())];
        let mut pass = encoder.begin_render_pass(&RenderPassDescriptor {
            label: Some("godot_sky"),
            color_attachments: &color,
            depth_stencil_attachment: Some(depth.get_attachment(StoreOp::Store)),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        sky.draw(&mut pass);
    }
    count.0.fetch_add(1, Ordering::Relaxed);
}

/// A `Sky` for `target` on Bevy's device, with a radiance cube of `radiance`'s size and the
/// copy into it when given; `None` (logged) when skydraw refuses.
fn make_sky(
    device: &RenderDevice,
    queue: &RenderQueue,
    shader: &SkyShader,
    target: Target,
    radiance: Option<&GpuImage>,
) -> Option<(Sky, Option<EnvironmentCopy>)> {
    let mut options = SkyOptions::new(target);
    // One level: Bevy's filter makes its own mip chain from level 0.
    options.radiance = radiance.map(|image| RadianceOptions {
        size: image.texture_descriptor.size.width,
        format: TextureFormat::Rgba16Float,
        mip_levels: Some(1),
        ..RadianceOptions::default()
    });
    let source = SkySource { wgsl: &shader.wgsl, reflection: &shader.reflection };
    let mut sky = match Sky::new(device.wgpu_device(), queue, source, options) {
        Ok(sky) => sky,
        Err(e) => {
            error!("bevy-sky: skydraw refuses the sky: {e}");
            return None;
        }
    };
    for (name, value) in &shader.uniforms {
        if let Err(e) = sky.set_uniform(name, value) {
            error!("bevy-sky: uniform {name}: {e}");
            return None;
        }
    }
    let environment = match (radiance, sky.radiance_texture()) {
        (Some(image), Some(cube)) => Some(EnvironmentCopy::new(device.wgpu_device(), cube, &image.texture)),
        _ => None,
    };
    Some((sky, environment))
}

/// Copies skydraw's radiance cube into Bevy's cube image, mirrored in Z.
///
/// skydraw's cube is in WebGPU's cube-sampling orientation: `textureSample(cube, d)` is the sky
/// along the world direction `d`. Bevy's environment maps are "left-handed": Bevy samples them
/// at `(d.x, d.y, −d.z)` (bevy_pbr's `environment_map.wesl`, "Cube maps are left-handed so we
/// negate the z coordinate"), and `GeneratedEnvironmentMapLight` filters them in that
/// orientation. A mirror is no rotation (`GeneratedEnvironmentMapLight::rotation` cannot undo
/// it), so each texel of Bevy's cube at cube direction `c` is written with skydraw's sky along
/// `(c.x, c.y, −c.z)`: one fullscreen triangle per face, sampling texel centres (nearest), so
/// the values are copied exactly.
struct EnvironmentCopy {
    pipeline: wgpu::RenderPipeline,
    group: wgpu::BindGroup,
    faces: Vec<wgpu::TextureView>,
    /// Whether a copy was recorded since the Sky was made.
    done: bool,
}

const ENVIRONMENT_COPY_WGSL: &str = r#"
@group(0) @binding(0) var sky_cube: texture_cube<f32>;
@group(0) @binding(1) var sky_sampler: sampler;

struct Varyings {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) face: u32,
}

@vertex
fn vs_main(@builtin(vertex_index) i: u32, @builtin(instance_index) face: u32) -> Varyings {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return Varyings(vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0), face);
}

@fragment
fn fs_main(in: Varyings) -> @location(0) vec4<f32> {
    // Texel (column, row) of face `face` to its cube direction (WebGPU's face table: s to the
    // right, t down).
    let st = in.position.xy / vec2<f32>(textureDimensions(sky_cube)) * 2.0 - 1.0;
    let s = st.x;
    let t = st.y;
    var c: vec3<f32>;
    switch in.face {
        case 0u: { c = vec3<f32>(1.0, -t, -s); }
        case 1u: { c = vec3<f32>(-1.0, -t, s); }
        case 2u: { c = vec3<f32>(s, 1.0, t); }
        case 3u: { c = vec3<f32>(s, -1.0, -t); }
        case 4u: { c = vec3<f32>(s, -t, 1.0); }
        default: { c = vec3<f32>(-s, -t, -1.0); }
    }
    return vec4<f32>(textureSampleLevel(sky_cube, sky_sampler, vec3<f32>(c.x, c.y, -c.z), 0.0).rgb, 1.0);
}
"#;

impl EnvironmentCopy {
    fn new(device: &wgpu::Device, source: &wgpu::Texture, destination: &wgpu::Texture) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("bevy-sky environment copy"),
            source: wgpu::ShaderSource::Wgsl(ENVIRONMENT_COPY_WGSL.into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("bevy-sky environment copy"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::Cube,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("bevy-sky environment copy"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("bevy-sky environment copy"),
            layout: Some(&pipeline_layout),
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
                    format: destination.format(),
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let cube = source.create_view(&wgpu::TextureViewDescriptor {
            label: Some("bevy-sky skydraw radiance"),
            dimension: Some(wgpu::TextureViewDimension::Cube),
            ..Default::default()
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("bevy-sky environment copy"),
            ..Default::default()
        });
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("bevy-sky environment copy"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&cube) },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&sampler) },
            ],
        });
        let faces = (0..6)
            .map(|face| {
                destination.create_view(&wgpu::TextureViewDescriptor {
                    label: Some("bevy-sky environment face"),
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_mip_level: 0,
                    mip_level_count: Some(1),
                    base_array_layer: face,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        Self { pipeline, group, faces, done: false }
    }

    fn record(&mut self, encoder: &mut wgpu::CommandEncoder) {
        for (face, view) in self.faces.iter().enumerate() {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("bevy-sky environment copy"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view,
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
            pass.set_bind_group(0, &self.group, &[]);
            let face = face as u32;
            pass.draw(0..3, face..face + 1);
        }
        self.done = true;
    }
}

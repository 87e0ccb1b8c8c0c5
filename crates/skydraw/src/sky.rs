//! [`Sky`]: a converted sky shader on the caller's device, drawn into the caller's pass.
//!
//! Everything a frame needs is created once, in [`Sky::new`] (pipelines, uniform buffers, bind
//! groups, stand-in textures, the radiance cube and its views) or when the target's size
//! changes (the sub-pass targets); a frame only writes uniform buffers and records passes.
//! What a frame records:
//!
//! 1. [`Sky::update`] writes the built-ins of every pass the frame may run and the material
//!    when it changed, and compares what the shader reads (its built-ins as the reflection
//!    lists them, the material, the bound textures) with what the radiance was rendered from.
//! 2. [`Sky::prepare`] records, into the caller's encoder and before their pass: the radiance
//!    faces the update policy asks for (each face's mips after it), Godot's quarter- and
//!    half-resolution sub-passes when the shader declares them, and the sky at a reduced
//!    resolution when asked for one.
//! 3. [`Sky::draw`] records one fullscreen triangle into the caller's pass at the far plane, so
//!    the depth test skips every pixel their geometry covers: the shader itself, the reduced
//!    image upsampled, or (the cached background) the up-to-date radiance cube sampled along
//!    each pixel's EYEDIR.

use crate::bindings::{self, Binding, BindingKind};
use crate::builtins::{RenderPass, SkyBuiltins, sub_pass_size};
use crate::frame::Frame;
use crate::material::{Material, MaterialError};
use crate::radiance::{Radiance, RadianceOptions};
use skycore::reflection::Reflection;
use skycore::{DepthConvention, SkyResolution, TextureData, TextureError, UniformValue};
use std::collections::HashMap;
use std::fmt;

/// The format of the sub-pass and reduced-resolution targets, as Godot's half and quarter
/// passes use (RGBA16F).
pub const OFFSCREEN_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// A converted shader as the runtime takes it: its WGSL and its reflection (what
/// `gdsky::convert` returns, or the build script's `.wgsl` and `.json`).
#[derive(Clone, Copy, Debug)]
pub struct SkySource<'a> {
    /// The WGSL module.
    pub wgsl: &'a str,
    /// Its reflection.
    pub reflection: &'a Reflection,
}

/// The caller's colour target, and their depth buffer if the sky should be hidden behind their
/// geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Target {
    /// The colour attachment's format.
    pub color_format: wgpu::TextureFormat,
    /// The depth attachment's format and convention; `None` draws without a depth test.
    pub depth: Option<(wgpu::TextureFormat, DepthConvention)>,
    /// MSAA samples of the attachments (1 without MSAA).
    pub sample_count: u32,
}

impl Target {
    /// A colour target without depth or MSAA.
    pub fn color(format: wgpu::TextureFormat) -> Self {
        Self { color_format: format, depth: None, sample_count: 1 }
    }
}

/// How the visible sky is drawn when nothing it reads changed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Background {
    /// The shader runs for every pixel, every frame.
    #[default]
    PerPixel,
    /// While the radiance cube is up to date (rendered from the inputs the shader reads now),
    /// each pixel samples it along its EYEDIR instead of running the shader; when an input
    /// changed, the shader runs per pixel until the cube catches up. Needs
    /// [`SkyOptions::radiance`]; the cube's resolution limits the detail.
    FromRadiance,
}

/// How the runtime is set up.
#[derive(Clone, Debug)]
pub struct SkyOptions {
    /// Where [`Sky::draw`] draws.
    pub target: Target,
    /// The fraction of the target the sky is shaded at; below `Full` it is upsampled
    /// (bilinear) in [`Sky::draw`].
    pub resolution: SkyResolution,
    /// The radiance cube map, its update policy and process mode; `None`: RADIANCE reads
    /// black.
    pub radiance: Option<RadianceOptions>,
    /// How the visible sky is drawn.
    pub background: Background,
}

impl SkyOptions {
    /// Full resolution into `target`, no radiance, per-pixel background.
    pub fn new(target: Target) -> Self {
        Self { target, resolution: SkyResolution::Full, radiance: None, background: Background::PerPixel }
    }
}

/// Why the runtime refused.
#[derive(Debug)]
#[non_exhaustive]
pub enum SkyError {
    /// The module declares a resource nothing can stand in for.
    Bindings(bindings::BindingError),
    /// The module puts the sky on the far plane of one depth convention, the target uses the
    /// other: convert with the target's (`--reversed-z`, `Options::depth`).
    DepthConvention {
        /// The module's.
        module: DepthConvention,
        /// The target's.
        target: DepthConvention,
    },
    /// What the runtime does not do (yet), with why.
    Unsupported(String),
    /// A material value.
    Material(MaterialError),
    /// A texture.
    Texture(TextureError),
    /// wgpu refused (validation, out of memory), with its message.
    Wgpu(String),
}

impl fmt::Display for SkyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SkyError::Bindings(e) => write!(f, "{e}"),
            SkyError::DepthConvention { module, target } => write!(
                f,
                "the module draws the sky on the far plane of {} but the target's depth is {}: convert it for {}",
                module.name(),
                target.name(),
                target.name()
            ),
            SkyError::Unsupported(what) => write!(f, "not supported by the runtime: {what}"),
            SkyError::Material(e) => write!(f, "{e}"),
            SkyError::Texture(e) => write!(f, "{e}"),
            SkyError::Wgpu(message) => write!(f, "wgpu: {message}"),
        }
    }
}

impl std::error::Error for SkyError {}

impl From<MaterialError> for SkyError {
    fn from(e: MaterialError) -> Self {
        SkyError::Material(e)
    }
}

impl From<TextureError> for SkyError {
    fn from(e: TextureError) -> Self {
        SkyError::Texture(e)
    }
}

/// What one frame recorded, from [`Sky::prepare`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameReport {
    /// Radiance faces rendered this frame (0 to 6).
    pub radiance_faces: u32,
    /// Whether the radiance cube holds the sky of this frame's inputs.
    pub radiance_current: bool,
    /// Godot's sub-passes rendered (quarter, half).
    pub sub_passes: u32,
    /// How [`Sky::draw`] draws the visible sky this frame.
    pub drawn: Drawn,
}

/// How [`Sky::draw`] draws the visible sky.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Drawn {
    /// The shader, per pixel.
    #[default]
    Shaded,
    /// The shader at a reduced resolution, upsampled.
    Upsampled,
    /// Sampled from the radiance cube.
    FromRadiance,
}

/// Which uniform buffer (and group 0 bind group) a pass reads its built-ins from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Slot {
    /// The visible sky at the target's size.
    Full,
    /// The sky at its shading size (the reduced resolution), before upsampling.
    Shading,
    Half,
    Quarter,
    Face(u8),
}

const SLOTS: [Slot; 10] = [
    Slot::Full,
    Slot::Shading,
    Slot::Half,
    Slot::Quarter,
    Slot::Face(0),
    Slot::Face(1),
    Slot::Face(2),
    Slot::Face(3),
    Slot::Face(4),
    Slot::Face(5),
];

/// Which textures group 2 binds: Godot's rules per pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Family {
    /// The visible sky: the radiance, and the sub-passes this frame rendered.
    Full,
    /// The half-resolution pass: the quarter-resolution image; its own is white.
    Half,
    /// The quarter-resolution pass: both sub-pass textures white.
    Quarter,
    /// The cubemap pass: RADIANCE and the sub-passes black.
    Cube,
}

/// The targets whose size follows the target's, made again when it changes.
struct SizedTargets {
    width: u32,
    height: u32,
    shading: Option<(wgpu::TextureView, wgpu::BindGroup)>,
    half: Option<wgpu::TextureView>,
    quarter: Option<wgpu::TextureView>,
    sky_groups: HashMap<Family, wgpu::BindGroup>,
}

/// What the shader reads, as of one frame: compared to decide whether the radiance is current.
#[derive(Clone, Debug, PartialEq)]
struct Inputs {
    time: Option<u32>,
    position: Option<[u32; 3]>,
    lights: Option<Vec<u32>>,
    material: u64,
    textures: u64,
}

/// A converted sky shader on the caller's device.
pub struct Sky {
    device: wgpu::Device,
    options: SkyOptions,
    bindings: Vec<Binding>,
    reads: (bool, bool, bool),
    sub_passes: (bool, bool),
    layouts: Vec<wgpu::BindGroupLayout>,
    main: wgpu::RenderPipeline,
    offscreen: Option<wgpu::RenderPipeline>,
    upsample: Option<wgpu::RenderPipeline>,
    upsample_layout: wgpu::BindGroupLayout,
    builtins: Vec<wgpu::Buffer>,
    /// What each built-ins buffer holds, so an unchanged one is not written again.
    builtins_written: Vec<Option<SkyBuiltins>>,
    builtin_groups: Vec<wgpu::BindGroup>,
    material: Material,
    material_buffer: Option<wgpu::Buffer>,
    material_written: Option<u64>,
    material_group: Option<wgpu::BindGroup>,
    texture_slots: Vec<(String, u32, u32)>,
    texture_filters: HashMap<String, (String, bool)>,
    provided: HashMap<(u32, u32), wgpu::TextureView>,
    stand_ins: HashMap<(u32, u32, u8), wgpu::TextureView>,
    samplers: HashMap<(u32, u32), wgpu::Sampler>,
    clamp_sampler: wgpu::Sampler,
    textures_version: u64,
    radiance: Option<Radiance>,
    sized: Option<SizedTargets>,
    frame: Option<(SkyBuiltins, Inputs)>,
    drawn: Drawn,
}

impl Sky {
    /// Compiles `source` on `device` for `options.target` and creates everything its frames
    /// use. The material starts at the shader's defaults, textures at their hints' stand-ins.
    ///
    /// Errors: a depth convention other than the module's, a resource nothing stands in for,
    /// global uniforms (Godot's project settings, which the runtime does not have), wgpu
    /// refusing the module or a pipeline.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        source: SkySource<'_>,
        options: SkyOptions,
    ) -> Result<Sky, SkyError> {
        let reflection = source.reflection;
        let bindings = bindings::discover(source.wgsl).map_err(SkyError::Bindings)?;
        if bindings.iter().any(|b| b.group == bindings::GLOBAL_UNIFORM_GROUP) {
            return Err(SkyError::Unsupported(
                "global uniforms (group 3): they come from Godot's project settings; bake them with --set".into(),
            ));
        }
        let module_depth = match reflection.depth.as_ref().map(|d| d.convention.as_str()) {
            Some("reversed_z") => DepthConvention::Reversed,
            _ => DepthConvention::Standard,
        };
        if let Some((_, convention)) = options.target.depth
            && convention != module_depth
        {
            return Err(SkyError::DepthConvention { module: module_depth, target: convention });
        }
        let entry = |projection: &str| {
            reflection.entry_points.fragment.get(projection).cloned().ok_or_else(|| {
                SkyError::Unsupported(format!("the reflection names no `{projection}` fragment entry point"))
            })
        };
        let (camera_entry, cube_entry) = (entry("camera")?, entry("cubemap")?);
        let scope = Scope::push(device);

        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("sky"),
            source: wgpu::ShaderSource::Wgsl(source.wgsl.into()),
        });
        let groups = bindings.iter().map(|b| b.group + 1).max().unwrap_or(1);
        let layouts: Vec<wgpu::BindGroupLayout> = (0..groups)
            .map(|group| {
                let entries: Vec<_> =
                    bindings.iter().filter(|b| b.group == group).map(bindings::layout_entry).collect();
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("sky group"),
                    entries: &entries,
                })
            })
            .collect();
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("sky"),
            bind_group_layouts: &layouts.iter().map(Some).collect::<Vec<_>>(),
            immediate_size: 0,
        });
        let target = options.target;
        let compare = match module_depth {
            DepthConvention::Standard => wgpu::CompareFunction::LessEqual,
            DepthConvention::Reversed => wgpu::CompareFunction::GreaterEqual,
        };
        let depth_state = target.depth.map(|(format, _)| wgpu::DepthStencilState {
            format,
            depth_write_enabled: Some(false),
            depth_compare: Some(compare),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        });
        let pipeline = |entry: &str, format, depth: Option<wgpu::DepthStencilState>, samples| {
            sky_pipeline(device, &pipeline_layout, &module, entry, format, depth, samples)
        };
        let reduced = options.resolution != SkyResolution::Full;
        let main = pipeline(&camera_entry, target.color_format, depth_state.clone(), target.sample_count);
        let sub_passes =
            (reflection.passes.iter().any(|p| p == "half"), reflection.passes.iter().any(|p| p == "quarter"));
        let offscreen =
            (reduced || sub_passes.0 || sub_passes.1).then(|| pipeline(&camera_entry, OFFSCREEN_FORMAT, None, 1));

        let helpers = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("sky helpers"),
            source: wgpu::ShaderSource::Wgsl(crate::radiance::HELPERS_WGSL.into()),
        });
        let upsample_layout = texture_group_layout(device, wgpu::TextureViewDimension::D2);
        let upsample = reduced.then(|| {
            let flat = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("sky flat helpers"),
                source: wgpu::ShaderSource::Wgsl(crate::radiance::FLAT_WGSL.into()),
            });
            crate::radiance::helper_pipeline(
                device,
                &flat,
                &layouts[0],
                &upsample_layout,
                "fs_upsample",
                target.color_format,
                depth_state.clone(),
                target.sample_count,
                module_depth,
            )
        });

        let builtins: Vec<wgpu::Buffer> = SLOTS
            .iter()
            .map(|_| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("SkyBuiltins"),
                    size: SkyBuiltins::SIZE as u64,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            })
            .collect();
        for buffer in &builtins {
            queue.write_buffer(buffer, 0, bytemuck::bytes_of(&SkyBuiltins::default()));
        }
        let builtin_groups = builtins
            .iter()
            .map(|buffer| {
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("sky built-ins"),
                    layout: &layouts[0],
                    entries: &[wgpu::BindGroupEntry { binding: 0, resource: buffer.as_entire_binding() }],
                })
            })
            .collect();

        let material = Material::with_defaults(reflection);
        let material_buffer = bindings
            .iter()
            .find(|b| b.group == bindings::MATERIAL_GROUP && b.binding == 0)
            .and_then(|b| match b.kind {
                BindingKind::Uniform { size } => Some(size),
                _ => None,
            })
            .map(|size| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("sky material"),
                    size: u64::from(size).max(material.bytes.len() as u64).div_ceil(16) * 16,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            });
        let samplers = reflection
            .bindings
            .samplers
            .iter()
            .map(|s| ((s.group, s.binding), crate::textures::sampler(device, &s.filter, s.repeat)))
            .collect();
        let texture_filters = reflection
            .bindings
            .samplers
            .iter()
            .map(|s| {
                let wants = reflection
                    .bindings
                    .textures
                    .iter()
                    .find(|t| t.name == s.texture)
                    .is_some_and(|t| t.hints.iter().any(|h| h.starts_with("filter_") && h.contains("mipmap")));
                (s.texture.clone(), (s.filter.clone(), wants))
            })
            .collect();
        let clamp_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("sky texture sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        let radiance = match &options.radiance {
            Some(radiance_options) => {
                let cube = pipeline(&cube_entry, radiance_options.format, None, 1);
                Some(Radiance::new(
                    device,
                    radiance_options,
                    cube,
                    &helpers,
                    &layouts[0],
                    &target,
                    depth_state,
                    module_depth,
                )?)
            }
            None if options.background == Background::FromRadiance => {
                return Err(SkyError::Unsupported("a background from the radiance without a radiance cube".into()));
            }
            None => None,
        };
        let mut sky = Sky {
            device: device.clone(),
            bindings,
            reads: (reflection.update.on_time, reflection.update.on_position, reflection.update.on_light),
            sub_passes,
            layouts,
            main,
            offscreen,
            upsample,
            upsample_layout,
            builtins_written: vec![None; builtins.len()],
            builtins,
            builtin_groups,
            material,
            material_buffer,
            material_written: None,
            material_group: None,
            texture_slots: reflection.bindings.textures.iter().map(|t| (t.name.clone(), t.group, t.binding)).collect(),
            texture_filters,
            provided: HashMap::new(),
            stand_ins: HashMap::new(),
            samplers,
            clamp_sampler,
            textures_version: 0,
            radiance,
            sized: None,
            frame: None,
            drawn: Drawn::Shaded,
            options,
        };
        sky.make_stand_ins(queue, reflection);
        sky.material_group = sky.material_group();
        scope.pop()?;
        Ok(sky)
    }

    /// Sets material uniform `name` (checked against the reflection: it must be a material
    /// uniform, and the value of its type) for the frames after the next [`Sky::update`].
    pub fn set_uniform(&mut self, name: &str, value: &UniformValue) -> Result<(), SkyError> {
        Ok(self.material.set(name, value)?)
    }

    /// Replaces the whole material block: the bytes of the build script's generated struct
    /// (`bytemuck::bytes_of(&material)`), which must be the block's size.
    pub fn set_material(&mut self, bytes: &[u8]) -> Result<(), SkyError> {
        Ok(self.material.replace(bytes)?)
    }

    /// Uploads `data` for the material texture `name` (the sampler uniform's name, `name_i`
    /// for element i of an array), with Godot's mip chain where its filter hint asks for one.
    /// Textures are made here, not per frame; the material's bind group is made again.
    ///
    /// Errors: an unknown name, a texture whose shape or format does not fit the binding.
    pub fn set_texture(&mut self, queue: &wgpu::Queue, name: &str, data: &TextureData) -> Result<(), SkyError> {
        let Some(key) = crate::textures::check_texture(&self.bindings, &self.texture_slots, name, data)? else {
            return Ok(());
        };
        let mipmaps = self
            .texture_filters
            .get(name)
            .is_some_and(|(filter, wants)| *wants || (data.mipmapped() && filter.contains("mipmap")));
        let scope = Scope::push(&self.device);
        let view = crate::textures::upload(&self.device, queue, name, data, mipmaps);
        scope.pop()?;
        self.provided.insert(key, view);
        self.textures_changed();
        Ok(())
    }

    /// Binds a texture view the caller made for the material texture `name` (its dimension and
    /// sample type must be the binding's: wgpu validates them when the bind group is made).
    pub fn set_texture_view(&mut self, name: &str, view: wgpu::TextureView) -> Result<(), SkyError> {
        let Some((_, group, binding)) = self.texture_slots.iter().find(|(slot, ..)| slot == name) else {
            return Err(SkyError::Texture(TextureError::UnknownName {
                name: name.to_string(),
                known: self.texture_slots.iter().map(|(slot, ..)| slot.clone()).collect(),
            }));
        };
        let key = (*group, *binding);
        self.provided.insert(key, view);
        let scope = Scope::push(&self.device);
        self.textures_changed();
        scope.pop()
    }

    fn textures_changed(&mut self) {
        self.textures_version += 1;
        self.material_group = self.material_group();
    }

    /// Asks the radiance to be rendered again under [`crate::UpdatePolicy::OnDemand`] (each
    /// face once; one per frame in the incremental process mode).
    pub fn request_radiance(&mut self) {
        if let Some(radiance) = &mut self.radiance {
            radiance.request();
        }
    }

    /// The radiance cube (six layers +X, −X, +Y, −Y, +Z, −Z with their mips), for the caller's
    /// image-based lighting: `textureSample(cube, dir)` gives the sky in direction `dir`.
    pub fn radiance_texture(&self) -> Option<&wgpu::Texture> {
        self.radiance.as_ref().map(Radiance::texture)
    }

    /// Writes this frame's built-ins (the visible pass at `width`×`height`, the sub-passes, the
    /// radiance faces) and the material if it changed, and notes what changed since the
    /// radiance was rendered. The sub-pass targets are made again only when the size changes.
    pub fn update(&mut self, queue: &wgpu::Queue, frame: &Frame, width: u32, height: u32) {
        let (width, height) = (width.max(1), height.max(1));
        if self.sized.as_ref().is_none_or(|s| (s.width, s.height) != (width, height)) {
            self.resize(queue, width, height);
        }
        let full = frame.builtins(width, height);
        let (sw, sh) = self.shading_size(width, height);
        for ((slot, buffer), written) in SLOTS.iter().zip(&self.builtins).zip(&mut self.builtins_written) {
            let builtins = match *slot {
                Slot::Full => full,
                Slot::Shading => full.for_pass(RenderPass::Full, sw, sh),
                Slot::Half => {
                    let (w, h) = sub_pass_size(RenderPass::Half, sw, sh);
                    full.for_pass(RenderPass::Half, w, h)
                }
                Slot::Quarter => {
                    let (w, h) = sub_pass_size(RenderPass::Quarter, sw, sh);
                    full.for_pass(RenderPass::Quarter, w, h)
                }
                Slot::Face(face) => {
                    let size = self.radiance.as_ref().map_or(1, Radiance::size);
                    SkyBuiltins { cube_face: u32::from(face), ..full.for_pass(RenderPass::Cubemap, size, size) }
                }
            };
            // wgpu stages every write in memory of its own: skip the ones that change nothing.
            if *written != Some(builtins) {
                queue.write_buffer(buffer, 0, bytemuck::bytes_of(&builtins));
                *written = Some(builtins);
            }
        }
        if let Some(buffer) = &self.material_buffer
            && self.material_written != Some(self.material.version)
        {
            queue.write_buffer(buffer, 0, &self.material.bytes);
            self.material_written = Some(self.material.version);
        }
        let (time, position, lights) = self.reads;
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<u32>>();
        let inputs = Inputs {
            time: time.then(|| frame.time.to_bits()),
            position: position.then(|| frame.position.to_array().map(f32::to_bits)),
            lights: lights.then(|| bits(bytemuck::cast_slice(&frame.lights))),
            material: self.material.version,
            textures: self.textures_version,
        };
        if let Some(radiance) = &mut self.radiance {
            let changed = self.frame.as_ref().is_none_or(|(_, previous)| *previous != inputs);
            radiance.note_inputs(changed);
        }
        self.frame = Some((full, inputs));
    }

    /// Records what this frame needs before the caller's pass: the radiance faces the policy
    /// asks for (with their mips), Godot's sub-passes, the sky at a reduced resolution. Call
    /// after [`Sky::update`] and before beginning the pass [`Sky::draw`] draws into.
    pub fn prepare(&mut self, encoder: &mut wgpu::CommandEncoder) -> FrameReport {
        let mut report = FrameReport::default();
        if self.frame.is_none() {
            return report;
        }
        let others: Vec<Option<wgpu::BindGroup>> =
            (1..self.layouts.len() as u32).map(|group| self.group(group, Family::Cube).cloned()).collect();
        if let Some(radiance) = &mut self.radiance {
            let others: Vec<Option<&wgpu::BindGroup>> = others.iter().map(Option::as_ref).collect();
            report.radiance_faces = radiance.render_due(encoder, &self.builtin_groups[4..10], &others);
            report.radiance_current = radiance.is_current();
        }
        if let (Some(offscreen), Some(sized)) = (&self.offscreen, &self.sized) {
            let passes = [
                (self.sub_passes.1, Slot::Quarter, Family::Quarter, sized.quarter.as_ref()),
                (self.sub_passes.0, Slot::Half, Family::Half, sized.half.as_ref()),
            ];
            for (wanted, slot, family, view) in passes {
                if let (true, Some(view)) = (wanted, view) {
                    self.offscreen_pass(encoder, offscreen, slot, family, view);
                    report.sub_passes += 1;
                }
            }
            if let Some((view, _)) = &sized.shading {
                self.offscreen_pass(encoder, offscreen, Slot::Shading, Family::Full, view);
            }
        }
        let from_radiance = self.options.background == Background::FromRadiance
            && self.radiance.as_ref().is_some_and(Radiance::is_current);
        self.drawn = if from_radiance {
            Drawn::FromRadiance
        } else if self.upsample.is_some() {
            Drawn::Upsampled
        } else {
            Drawn::Shaded
        };
        report.drawn = self.drawn;
        report
    }

    /// Records the visible sky into the caller's pass (begun on the target given to
    /// [`Sky::new`], with its depth attachment if it has one): one fullscreen triangle at the
    /// far plane, depth-tested, writing no depth.
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        match self.drawn {
            Drawn::FromRadiance => {
                if let Some(radiance) = &self.radiance {
                    radiance.draw_background(pass, &self.builtin_groups[0]);
                }
            }
            Drawn::Upsampled => {
                if let (Some(pipeline), Some((_, group))) =
                    (&self.upsample, self.sized.as_ref().and_then(|s| s.shading.as_ref()))
                {
                    pass.set_pipeline(pipeline);
                    pass.set_bind_group(0, &self.builtin_groups[0], &[]);
                    pass.set_bind_group(1, group, &[]);
                    pass.draw(0..3, 0..1);
                }
            }
            Drawn::Shaded => {
                pass.set_pipeline(&self.main);
                self.set_groups(pass, Slot::Full, Family::Full);
                pass.draw(0..3, 0..1);
            }
        }
    }

    /// The size the sky is shaded at for a `width`×`height` target.
    fn shading_size(&self, width: u32, height: u32) -> (u32, u32) {
        let divisor = match self.options.resolution {
            SkyResolution::Full => 1,
            SkyResolution::Half => 2,
            SkyResolution::Quarter => 4,
        };
        ((width / divisor).max(1), (height / divisor).max(1))
    }

    fn set_groups(&self, pass: &mut wgpu::RenderPass<'_>, slot: Slot, family: Family) {
        let index = SLOTS.iter().position(|s| *s == slot).unwrap_or(0);
        pass.set_bind_group(0, &self.builtin_groups[index], &[]);
        for group in 1..self.layouts.len() as u32 {
            if let Some(bind_group) = self.group(group, family) {
                pass.set_bind_group(group, bind_group, &[]);
            }
        }
    }

    /// The bind group of `group` (1 or 2) for a pass family.
    fn group(&self, group: u32, family: Family) -> Option<&wgpu::BindGroup> {
        match group {
            bindings::MATERIAL_GROUP => self.material_group.as_ref(),
            bindings::SKY_TEXTURE_GROUP => self.sized.as_ref().and_then(|s| s.sky_groups.get(&family)),
            _ => None,
        }
    }

    fn offscreen_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &wgpu::RenderPipeline,
        slot: Slot,
        family: Family,
        view: &wgpu::TextureView,
    ) {
        let mut pass = begin_offscreen_pass(encoder, view, "sky sub-pass");
        pass.set_pipeline(pipeline);
        self.set_groups(&mut pass, slot, family);
        pass.draw(0..3, 0..1);
    }

    /// Makes the size-dependent targets and the group 2 bind groups that read them.
    fn resize(&mut self, queue: &wgpu::Queue, width: u32, height: u32) {
        let device = &self.device;
        let (sw, sh) = self.shading_size(width, height);
        let target = |label: &str, (w, h): (u32, u32)| {
            device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: OFFSCREEN_FORMAT,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                })
                .create_view(&wgpu::TextureViewDescriptor::default())
        };
        let half = self.sub_passes.0.then(|| target("sky half", sub_pass_size(RenderPass::Half, sw, sh)));
        let quarter = self.sub_passes.1.then(|| target("sky quarter", sub_pass_size(RenderPass::Quarter, sw, sh)));
        let shading = self.upsample.is_some().then(|| {
            let view = target("sky shading", (sw, sh));
            let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("sky upsample"),
                layout: &self.upsample_layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&view) },
                    wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&self.clamp_sampler) },
                ],
            });
            (view, group)
        });
        let mut sized = SizedTargets { width, height, shading, half, quarter, sky_groups: HashMap::new() };
        if self.layouts.len() as u32 > bindings::SKY_TEXTURE_GROUP {
            for family in [Family::Full, Family::Half, Family::Quarter, Family::Cube] {
                let group = self.sky_group(queue, family, &sized);
                sized.sky_groups.insert(family, group);
            }
        }
        self.sized = Some(sized);
    }

    /// Group 2 for a pass family: RADIANCE, HALF_RES_COLOR and QUARTER_RES_COLOR by Godot's
    /// rules (black in the cubemap pass; white for a sub-pass not rendered, or while that same
    /// sub-pass renders).
    fn sky_group(&mut self, queue: &wgpu::Queue, family: Family, sized: &SizedTargets) -> wgpu::BindGroup {
        let mut entries_views: Vec<(u32, wgpu::TextureView)> = Vec::new();
        let mut entries_samplers: Vec<u32> = Vec::new();
        let declared: Vec<Binding> =
            self.bindings.iter().filter(|b| b.group == bindings::SKY_TEXTURE_GROUP).cloned().collect();
        for b in &declared {
            match b.kind {
                BindingKind::Texture { dimension, sample_type } => {
                    let rendered = match b.binding {
                        bindings::HALF_RES_BINDING if family == Family::Full => sized.half.clone(),
                        bindings::QUARTER_RES_BINDING if matches!(family, Family::Full | Family::Half) => {
                            sized.quarter.clone()
                        }
                        0 if family != Family::Cube => self.radiance.as_ref().map(Radiance::cube_view),
                        _ => None,
                    };
                    let view = rendered.unwrap_or_else(|| {
                        let black = family == Family::Cube || b.binding == 0;
                        let texel = if black { [0.0, 0.0, 0.0, 1.0] } else { [1.0; 4] };
                        self.stand_in(queue, b.group, b.binding, dimension, sample_type, texel)
                    });
                    entries_views.push((b.binding, view));
                }
                _ => entries_samplers.push(b.binding),
            }
        }
        let mut entries: Vec<wgpu::BindGroupEntry<'_>> = entries_views
            .iter()
            .map(|(binding, view)| wgpu::BindGroupEntry {
                binding: *binding,
                resource: wgpu::BindingResource::TextureView(view),
            })
            .collect();
        entries.extend(entries_samplers.iter().map(|binding| wgpu::BindGroupEntry {
            binding: *binding,
            resource: wgpu::BindingResource::Sampler(&self.clamp_sampler),
        }));
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("sky textures"),
            layout: &self.layouts[bindings::SKY_TEXTURE_GROUP as usize],
            entries: &entries,
        })
    }

    /// A 1×1 texture of one texel for a binding, made once per texel kind.
    fn stand_in(
        &mut self,
        queue: &wgpu::Queue,
        group: u32,
        binding: u32,
        dimension: wgpu::TextureViewDimension,
        sample_type: wgpu::TextureSampleType,
        texel: [f32; 4],
    ) -> wgpu::TextureView {
        let kind = u8::from(texel == [1.0; 4]);
        self.stand_ins
            .entry((group, binding, kind))
            .or_insert_with(|| bindings::constant_texture(&self.device, queue, dimension, sample_type, texel))
            .clone()
    }

    /// The material textures' stand-ins (their hints' default texels), made once.
    fn make_stand_ins(&mut self, queue: &wgpu::Queue, reflection: &Reflection) {
        let declared: Vec<Binding> =
            self.bindings.iter().filter(|b| b.group == bindings::MATERIAL_GROUP).cloned().collect();
        for b in declared {
            if let BindingKind::Texture { dimension, sample_type } = b.kind {
                let entry = reflection.bindings.textures.iter().find(|t| (t.group, t.binding) == (b.group, b.binding));
                let texel = match entry.and_then(|t| t.default.as_deref()) {
                    Some("black") => [0.0, 0.0, 0.0, 1.0],
                    Some("transparent") => [0.0; 4],
                    _ if entry.is_some_and(|t| t.hints.iter().any(|h| h == "hint_normal")) => [0.5, 0.5, 1.0, 1.0],
                    _ => [1.0; 4],
                };
                let view = bindings::constant_texture(&self.device, queue, dimension, sample_type, texel);
                self.stand_ins.insert((b.group, b.binding, 2), view);
            }
        }
    }

    /// Group 1: the material block, the textures given (stand-ins for the others), the
    /// samplers the hints ask for.
    fn material_group(&self) -> Option<wgpu::BindGroup> {
        let layout = self.layouts.get(bindings::MATERIAL_GROUP as usize)?;
        let declared: Vec<&Binding> = self.bindings.iter().filter(|b| b.group == bindings::MATERIAL_GROUP).collect();
        let entries: Vec<wgpu::BindGroupEntry<'_>> = declared
            .iter()
            .filter_map(|b| {
                let resource = match b.kind {
                    BindingKind::Uniform { .. } => self.material_buffer.as_ref()?.as_entire_binding(),
                    BindingKind::Texture { .. } => wgpu::BindingResource::TextureView(
                        self.provided
                            .get(&(b.group, b.binding))
                            .or_else(|| self.stand_ins.get(&(b.group, b.binding, 2)))?,
                    ),
                    BindingKind::Sampler => wgpu::BindingResource::Sampler(
                        self.samplers.get(&(b.group, b.binding)).unwrap_or(&self.clamp_sampler),
                    ),
                };
                Some(wgpu::BindGroupEntry { binding: b.binding, resource })
            })
            .collect();
        Some(self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("sky material"),
            layout,
            entries: &entries,
        }))
    }
}

/// A pass into one of the runtime's own targets (a sub-pass, a radiance face or mip), cleared
/// to black first, without depth.
pub(crate) fn begin_offscreen_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    view: &wgpu::TextureView,
    label: &str,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations { load: wgpu::LoadOp::Clear(wgpu::Color::BLACK), store: wgpu::StoreOp::Store },
        })],
        depth_stencil_attachment: None,
        timestamp_writes: None,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// A render pipeline of the sky module: the fullscreen triangle of `vs_main` and one fragment
/// entry, into one colour target without blending.
fn sky_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    entry: &str,
    format: wgpu::TextureFormat,
    depth: Option<wgpu::DepthStencilState>,
    samples: u32,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(entry),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_main"),
            compilation_options: wgpu::PipelineCompilationOptions::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: depth,
        multisample: wgpu::MultisampleState { count: samples, ..Default::default() },
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(entry),
            compilation_options: wgpu::PipelineCompilationOptions::default(),
            targets: &[Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL })],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// A group of one texture (filterable float, of `dimension`) and a filtering sampler.
pub(crate) fn texture_group_layout(
    device: &wgpu::Device,
    dimension: wgpu::TextureViewDimension,
) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("sky texture"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: true },
                    view_dimension: dimension,
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
    })
}

/// wgpu error scopes around object creation, so that a refusal is an error value.
pub(crate) struct Scope {
    scopes: [wgpu::ErrorScopeGuard; 2],
}

impl Scope {
    pub(crate) fn push(device: &wgpu::Device) -> Self {
        let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
        Self { scopes: [validation, oom] }
    }

    pub(crate) fn pop(self) -> Result<(), SkyError> {
        let mut first = None;
        for scope in self.scopes {
            if let Some(error) = pollster::block_on(scope.pop()) {
                first.get_or_insert(SkyError::Wgpu(error.to_string()));
            }
        }
        first.map_or(Ok(()), Err)
    }
}

//! Offscreen renders of a converted sky shader, read back as f32 RGBA.
//!
//! A [`SkyShader`] holds what does not change between renders (the compiled module, the bind
//! group layouts, one pipeline per entry point and target format), so a test matrix or a
//! benchmark pays for shader compilation once. Each [`SkyShader::render`] records Godot's pass
//! order into one command buffer: the quarter-resolution sub-pass, then the half-resolution
//! one, then the full pass that can read both, then the copy to a read-back buffer.

use crate::bindings::{self, Binding, BindingError, BindingKind};
use crate::gpu::Gpu;
use crate::skip::{OCCLUDED, Occluder, RenderOptions, SkyResolution, UPSAMPLE_WGSL, UpsampleFilter};
use skycore::Projection;
use skydraw::{RenderPass, SkyBuiltins, sub_pass_size};
use std::collections::HashMap;
use std::fmt;
use std::sync::{Mutex, mpsc};
use std::time::{Duration, Instant};

/// Bytes per pixel of the Rgba32Float target.
const BYTES_PER_PIXEL: u32 = 16;

/// The format of the full-pass target: f32, so the comparison sees every bit the shader wrote.
const FULL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// The format of the half/quarter sub-pass targets. Godot renders them as RGBA16F; it is also
/// the widest float format that can be sampled with linear filtering without optional features.
const SUB_PASS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// How long a render waits for the GPU before it gives up. lavapipe renders a 256×128 Freeman
/// sky in well under a second; the bound only keeps a hung driver from hanging a test run.
const GPU_TIMEOUT: Duration = Duration::from_secs(300);

/// The result of a `map_async` whose submission the device has finished. Usually there already:
/// the poll that waited ran the callback. When threads share the device, another thread's poll
/// may have taken the callback and run it a moment later, so this polls and waits for it, up to
/// [`GPU_TIMEOUT`]; `None` if it never comes.
fn mapped<T>(device: &wgpu::Device, receiver: &mpsc::Receiver<T>) -> Option<T> {
    let deadline = Instant::now() + GPU_TIMEOUT;
    loop {
        match receiver.try_recv() {
            Ok(value) => return Some(value),
            Err(mpsc::TryRecvError::Disconnected) => return None,
            Err(mpsc::TryRecvError::Empty) if Instant::now() > deadline => return None,
            Err(mpsc::TryRecvError::Empty) => {
                let _ = device.poll(wgpu::PollType::Poll);
                std::thread::sleep(Duration::from_millis(1));
            }
        }
    }
}

/// Why a render failed.
#[derive(Clone, Debug, PartialEq)]
pub enum RenderError {
    /// The target size is zero or above the device's `max_texture_dimension_2d`.
    InvalidSize {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// The device's limit.
        max: u32,
    },
    /// The shader declares a resource the harness cannot provide, or its WGSL does not parse.
    Binding(BindingError),
    /// The material bytes are shorter than the shader's material block.
    Material {
        /// The block's size as naga lays it out.
        needed: u32,
        /// Bytes given.
        given: usize,
    },
    /// wgpu rejected something: the WGSL (a shader-module error carries naga's message), the
    /// pipeline (an entry point missing), or ran out of memory.
    Wgpu {
        /// The kind of error wgpu reported (validation, out of memory, internal).
        kind: &'static str,
        /// wgpu's message, with its chain of causes.
        message: String,
    },
    /// The GPU did not finish the submission (timeout).
    Poll(String),
    /// Mapping the read-back buffer failed.
    Map(String),
    /// The occluder's size is not the render's.
    OccluderSize {
        /// The mask's width and height.
        mask: (u32, u32),
        /// The render's.
        render: (u32, u32),
    },
}

impl fmt::Display for RenderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RenderError::InvalidSize { width, height, max } => {
                write!(f, "cannot render {width}×{height}: each side must be between 1 and {max}")
            }
            RenderError::Binding(e) => e.fmt(f),
            RenderError::Material { needed, given } => {
                write!(f, "the shader's material block is {needed} bytes but {given} bytes were given")
            }
            RenderError::Wgpu { kind, message } => write!(f, "wgpu {kind} error: {message}"),
            RenderError::Poll(m) => write!(f, "waiting for the GPU failed: {m}"),
            RenderError::Map(m) => write!(f, "reading the image back failed: {m}"),
            RenderError::OccluderSize { mask, render } => {
                write!(f, "the occluder is {}×{} but the render is {}×{}", mask.0, mask.1, render.0, render.1)
            }
        }
    }
}

impl std::error::Error for RenderError {}

impl From<BindingError> for RenderError {
    fn from(e: BindingError) -> Self {
        RenderError::Binding(e)
    }
}

/// Which of Godot's sub-passes a shader asked for with its render modes (`use_half_res_pass`,
/// `use_quarter_res_pass`; the reflection JSON lists them under `passes`).
///
/// A sub-pass is drawn only when the shader asked for it *and* reads its result
/// (HALF_RES_COLOR / QUARTER_RES_COLOR): its output is visible nowhere else. A shader that reads
/// the texture without the render mode gets Godot's stand-in, a white texel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SubPasses {
    /// `render_mode use_half_res_pass`.
    pub half: bool,
    /// `render_mode use_quarter_res_pass`.
    pub quarter: bool,
}

impl SubPasses {
    /// Reads the render modes of a checked shader (none when it did not check).
    pub fn of(front: &gdshader::FrontendOutput) -> SubPasses {
        let modes = front.shader.as_ref().map(|s| s.render_modes.as_slice()).unwrap_or_default();
        SubPasses {
            half: modes.iter().any(|m| m == "use_half_res_pass"),
            quarter: modes.iter().any(|m| m == "use_quarter_res_pass"),
        }
    }
}

/// One render's pixels and how long the GPU took.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// `[r, g, b, a]` per pixel, row 0 at the top, left to right.
    pub pixels: Vec<[f32; 4]>,
    /// Wall time from submitting the command buffer (all passes and the copy) until the device
    /// reported it done: the render time as the host sees it, without setup.
    pub gpu_wait: Duration,
    /// The passes' own time on the device, from GPU timestamp queries (summed over the
    /// sub-passes and the full pass; the copy excluded), when the device has them
    /// ([`Gpu::has_timestamps`]).
    pub gpu_time: Option<Duration>,
}

/// A sky pipeline's key: entry point, target format, depth test.
type PipelineKey = (&'static str, wgpu::TextureFormat, Option<wgpu::CompareFunction>);

/// A converted sky shader compiled for one device, ready to render any number of times.
pub struct SkyShader {
    module: wgpu::ShaderModule,
    bindings: Vec<Binding>,
    group_layouts: Vec<wgpu::BindGroupLayout>,
    pipeline_layout: wgpu::PipelineLayout,
    pipelines: Mutex<HashMap<PipelineKey, wgpu::RenderPipeline>>,
    sub_passes: SubPasses,
    repeat_sampler: wgpu::Sampler,
    clamp_sampler: wgpu::Sampler,
    /// The upsampling sampler of a panorama: linear, wrapping around horizontally (u repeat),
    /// clamped vertically (v clamp to edge).
    panorama_sampler: wgpu::Sampler,
    texture_defaults: Vec<((u32, u32), [f32; 4])>,
    /// The material textures as the reflection describes them
    /// ([`SkyShader::with_material_textures`]): how a uniform's name maps to its bindings.
    material_textures: Vec<gdsky_naga::reflect::TextureBinding>,
    /// Textures the host gave ([`SkyShader::set_texture`]), by (group, binding).
    provided: HashMap<(u32, u32), wgpu::TextureView>,
    /// Samplers built from the uniforms' filter and repeat hints, by the sampler's (group,
    /// binding); a material sampler not listed repeats and filters linearly.
    material_samplers: HashMap<(u32, u32), wgpu::Sampler>,
    /// Values of the module's overrides (`gdsky convert --override`), by `@id` as text; an
    /// override not listed keeps its default.
    constants: Vec<(String, f64)>,
    /// Where `vs_main` puts the sky (the far plane of standard or reversed Z), read from the
    /// module ([`gdsky_naga::depth_convention`]); standard Z when it cannot be read.
    depth: skycore::DepthConvention,
    /// The upsampling pipeline of a reduced sky resolution, per (with depth test, filter), on
    /// first use.
    upsample: Mutex<HashMap<(bool, UpsampleFilter), wgpu::RenderPipeline>>,
}

/// The depth format of the occluder: 16-bit unorm holds 0, ½ and 1 exactly and, unlike
/// Depth32Float, can be written from the host (`write_texture`).
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth16Unorm;

/// Where a render pass draws: the colour target, its clear value and, with an occluder, the
/// depth buffer and the test that hides the sky behind it.
struct Target<'a> {
    view: &'a wgpu::TextureView,
    format: wgpu::TextureFormat,
    /// The clear value; `None`: every pixel is drawn, the old contents are not needed (the
    /// upsampling pass without an occluder: its fullscreen triangle writes every pixel).
    clear: Option<wgpu::Color>,
    depth: Option<(&'a wgpu::TextureView, wgpu::CompareFunction)>,
}

impl SkyShader {
    /// Compiles `wgsl` on `gpu` and builds the bind group layouts from the resources it
    /// declares (see [`bindings::discover`]).
    pub fn new(gpu: &Gpu, wgsl: &str, sub_passes: SubPasses) -> Result<SkyShader, RenderError> {
        Self::with_source(gpu, wgsl, wgpu::ShaderSource::Wgsl(wgsl.into()), sub_passes)
    }

    /// Like [`SkyShader::new`], compiling the SPIR-V `spirv` (what `gdsky convert` writes as
    /// `.spv`; its overrides are specialization constants) instead of `wgsl`, which must be the
    /// same shader's WGSL: its resources give the bind group layouts.
    pub fn from_spirv(gpu: &Gpu, wgsl: &str, spirv: &[u32], sub_passes: SubPasses) -> Result<SkyShader, RenderError> {
        Self::with_source(gpu, wgsl, wgpu::ShaderSource::SpirV(spirv.into()), sub_passes)
    }

    /// Like [`SkyShader::from_spirv`], but hands `spirv` to the driver as is, bypassing wgpu's
    /// re-reading of SPIR-V through naga, which would drop decorations naga's IR cannot hold
    /// (`NoContraction`: the f64 evaluation's exact arithmetic, see
    /// `gdsky_naga::exact_arithmetic`). `entry_points` names the module's entry points.
    ///
    /// Its `Binding` decorations are renumbered as wgpu's Vulkan back end numbers a layout's
    /// entries (their rank in the group; see the `passthrough` module), since no one else
    /// rewrites them on this path.
    ///
    /// The binary must be valid SPIR-V whose interface matches `wgsl`'s: gdsky's f64 modules
    /// are naga-validated and re-read before they get here (`gdsky_naga::to_spirv`), and only
    /// gain decorations afterwards; `spirv-val` checks them in the tests. Errors: the device
    /// has no passthrough shaders ([`Gpu::has_passthrough`]).
    pub fn from_spirv_exact(
        gpu: &Gpu,
        wgsl: &str,
        spirv: &[u32],
        entry_points: &[String],
        sub_passes: SubPasses,
    ) -> Result<SkyShader, RenderError> {
        if !gpu.has_passthrough() {
            return Err(RenderError::Wgpu {
                kind: "missing feature",
                message: "the device cannot take SPIR-V as is (wgpu Features::PASSTHROUGH_SHADERS), which exact \
                          f64 arithmetic needs"
                    .into(),
            });
        }
        let entry_points: Vec<_> = entry_points
            .iter()
            .map(|name| wgpu::PassthroughShaderEntryPoint { name: name.clone().into(), workgroup_size: (0, 0, 0) })
            .collect();
        let layout = bindings::discover(wgsl)?;
        let spirv = crate::passthrough::vulkan_bindings(spirv, &layout)
            .map_err(|message| RenderError::Wgpu { kind: "passthrough", message })?;
        Self::with_module(gpu, wgsl, sub_passes, || {
            // SAFETY: the binary is a naga-validated module written by naga's SPIR-V back end and
            // re-read by its front end (`gdsky_naga::to_spirv`), with `NoContraction` decorations
            // added, which change no interface; its resources are `wgsl`'s, from which the
            // layouts are built.
            unsafe {
                gpu.device.create_shader_module_passthrough(wgpu::ShaderModuleDescriptorPassthrough {
                    label: Some("sky (exact)"),
                    spirv: Some(spirv.as_slice().into()),
                    entry_points: entry_points.into(),
                    ..Default::default()
                })
            }
        })
    }

    fn with_source(
        gpu: &Gpu,
        wgsl: &str,
        source: wgpu::ShaderSource<'_>,
        sub_passes: SubPasses,
    ) -> Result<SkyShader, RenderError> {
        Self::with_module(gpu, wgsl, sub_passes, || {
            gpu.device.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some("sky"), source })
        })
    }

    fn with_module(
        gpu: &Gpu,
        wgsl: &str,
        sub_passes: SubPasses,
        create: impl FnOnce() -> wgpu::ShaderModule,
    ) -> Result<SkyShader, RenderError> {
        let bindings = bindings::discover(wgsl)?;
        // `discover` parsed it already, so this parse succeeds.
        let depth =
            naga::front::wgsl::parse_str(wgsl).ok().and_then(|m| gdsky_naga::depth_convention(&m)).unwrap_or_default();
        let device = &gpu.device;
        scoped(gpu, || {
            let module = create();
            let groups = bindings.iter().map(|b| b.group + 1).max().unwrap_or(1);
            let group_layouts: Vec<_> = (0..groups)
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
                bind_group_layouts: &group_layouts.iter().map(Some).collect::<Vec<_>>(),
                immediate_size: 0,
            });
            let sampler = |mode: wgpu::AddressMode, mode_v: wgpu::AddressMode| {
                device.create_sampler(&wgpu::SamplerDescriptor {
                    label: Some("sky sampler"),
                    address_mode_u: mode,
                    address_mode_v: mode_v,
                    address_mode_w: mode_v,
                    mag_filter: wgpu::FilterMode::Linear,
                    min_filter: wgpu::FilterMode::Linear,
                    mipmap_filter: wgpu::MipmapFilterMode::Linear,
                    ..Default::default()
                })
            };
            SkyShader {
                module,
                bindings,
                group_layouts,
                pipeline_layout,
                pipelines: Mutex::new(HashMap::new()),
                sub_passes,
                repeat_sampler: sampler(wgpu::AddressMode::Repeat, wgpu::AddressMode::Repeat),
                clamp_sampler: sampler(wgpu::AddressMode::ClampToEdge, wgpu::AddressMode::ClampToEdge),
                panorama_sampler: sampler(wgpu::AddressMode::Repeat, wgpu::AddressMode::ClampToEdge),
                texture_defaults: Vec::new(),
                material_textures: Vec::new(),
                provided: HashMap::new(),
                material_samplers: HashMap::new(),
                constants: Vec::new(),
                depth,
                upsample: Mutex::new(HashMap::new()),
            }
        })
    }

    /// The texels to bind for material textures the scene does not provide, by (group,
    /// binding), as [`crate::texture_defaults`] reads them from the shader's hints; textures not
    /// listed are white.
    #[must_use]
    pub fn with_texture_defaults(mut self, defaults: Vec<((u32, u32), [f32; 4])>) -> Self {
        self.texture_defaults = defaults;
        self
    }

    /// The shader's material textures as the reflection describes them
    /// ([`gdsky_naga::reflect::texture_bindings`]): what [`SkyShader::set_texture`] maps a
    /// uniform's name through, and the filter and repeat hints each material sampler is built
    /// from (`filter_nearest*` → nearest, other filters → linear; `repeat_disable` → clamp to
    /// edge, else repeat; anisotropy not applied). Without it, material samplers repeat and
    /// filter linearly, and no texture can be given by name.
    #[must_use]
    pub fn with_material_textures(mut self, gpu: &Gpu, textures: Vec<gdsky_naga::reflect::TextureBinding>) -> Self {
        self.material_samplers = textures
            .iter()
            .filter(|t| self.declares(t.group, t.binding + 1))
            .map(|t| ((t.group, t.binding + 1), crate::textures::sampler(&gpu.device, &t.filter, t.repeat)))
            .collect();
        self.material_textures = textures;
        self
    }

    /// Binds `data` to the material texture `name` (the sampler uniform's name; element i of a
    /// sampler array is `name_i`) for every later render, in place of its stand-in. The name is
    /// looked up in the reflection given to [`SkyShader::with_material_textures`]; a texture the
    /// module does not declare (a uniform the shader never reads is pruned) is accepted and
    /// unused.
    ///
    /// A uniform whose filter hint asks for mipmaps (`filter_*_mipmap*`, [`TextureBinding::wants_mipmaps`](gdsky_naga::reflect::TextureBinding::wants_mipmaps))
    /// gets the full mip chain, Godot's box filter (textures/mipmap.rs), and so does a texture
    /// marked [`crate::TextureData::with_mipmaps`] under any mipmap filter (the default
    /// `linear_mipmap` included); others one level.
    ///
    /// Errors: those of [`crate::check_texture`] (an unknown name, a 32-bit float texture for a
    /// texture the shader samples with filtering, a 2D image for a cube or 3D binding or the
    /// like, an array or integer binding), and wgpu refusing the texture.
    pub fn set_texture(&mut self, gpu: &Gpu, name: &str, data: &crate::TextureData) -> Result<(), crate::TextureError> {
        let Some(key) = crate::textures::check_texture(&self.bindings, &self.material_textures, name, data)? else {
            return Ok(());
        };
        // A hint asks for mipmaps; a texture whose source has its own (a NoiseTexture2D) uses them
        // under any mipmap filter, Godot's default one included.
        let slot = self.material_textures.iter().find(|t| t.name == name);
        let mipmaps = slot.is_some_and(|t| t.wants_mipmaps() || (data.mipmapped() && t.filter.contains("mipmap")));
        let view = scoped(gpu, || crate::textures::upload(&gpu.device, &gpu.queue, name, data, mipmaps))
            .map_err(|e| crate::TextureError::Wgpu(e.to_string()))?;
        self.provided.insert(key, view);
        Ok(())
    }

    /// Values for the module's overrides (WGSL `override`, `gdsky convert --override`), keyed by
    /// `@id` as text (`"0"`) or by name for an override without an id, given to every pipeline
    /// (wgpu's `PipelineCompilationOptions::constants`); an override not listed keeps its
    /// default.
    #[must_use]
    pub fn with_constants(mut self, constants: Vec<(String, f64)>) -> Self {
        self.set_constants(constants);
        self
    }

    /// Like [`SkyShader::with_constants`], in place: when the values differ from the current
    /// ones, the cached pipelines are dropped (their constants are fixed at creation), so the
    /// next render builds its pipelines again, which costs a driver compile of the module.
    pub fn set_constants(&mut self, constants: Vec<(String, f64)>) {
        if constants != self.constants {
            self.constants = constants;
            self.pipelines.get_mut().unwrap_or_else(|poisoned| poisoned.into_inner()).clear();
        }
    }

    /// The resources the shader declares.
    pub fn bindings(&self) -> &[Binding] {
        &self.bindings
    }

    /// Whether the shader declares `group`/`binding`.
    fn declares(&self, group: u32, binding: u32) -> bool {
        self.bindings.iter().any(|b| b.group == group && b.binding == binding)
    }

    /// Where the module puts the sky: the far plane of standard Z (depth 1) or reversed Z (0).
    pub fn depth_convention(&self) -> skycore::DepthConvention {
        self.depth
    }

    /// The depth test that hides the sky behind anything nearer than the far plane.
    fn depth_compare(&self) -> wgpu::CompareFunction {
        if self.depth == skycore::DepthConvention::Reversed {
            wgpu::CompareFunction::GreaterEqual
        } else {
            wgpu::CompareFunction::LessEqual
        }
    }

    /// The pipeline for an entry point and target format (and depth test), built on first use.
    fn pipeline(
        &self,
        gpu: &Gpu,
        entry: &'static str,
        format: wgpu::TextureFormat,
        depth: Option<wgpu::CompareFunction>,
    ) -> wgpu::RenderPipeline {
        let mut cache = self.pipelines.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        let constants: Vec<(&str, f64)> = self.constants.iter().map(|(k, v)| (k.as_str(), *v)).collect();
        let options = || wgpu::PipelineCompilationOptions { constants: &constants, ..Default::default() };
        cache
            .entry((entry, format, depth))
            .or_insert_with(|| {
                let what =
                    move || format!("building the render pipeline of `{entry}` (the driver compiling the shader)");
                crate::watchdog::watched(what, || {
                    gpu.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                        label: Some(entry),
                        layout: Some(&self.pipeline_layout),
                        vertex: wgpu::VertexState {
                            module: &self.module,
                            entry_point: Some("vs_main"),
                            compilation_options: options(),
                            buffers: &[],
                        },
                        primitive: wgpu::PrimitiveState {
                            topology: wgpu::PrimitiveTopology::TriangleList,
                            cull_mode: None,
                            ..Default::default()
                        },
                        depth_stencil: depth.map(depth_state),
                        multisample: wgpu::MultisampleState::default(),
                        fragment: Some(wgpu::FragmentState {
                            module: &self.module,
                            entry_point: Some(entry),
                            compilation_options: options(),
                            targets: &[Some(wgpu::ColorTargetState {
                                format,
                                blend: None,
                                write_mask: wgpu::ColorWrites::ALL,
                            })],
                        }),
                        multiview_mask: None,
                        cache: None,
                    })
                })
            })
            .clone()
    }

    /// Renders into a `width`×`height` Rgba32Float target and reads it back.
    ///
    /// `builtins` is used as given for the full pass (set `screen_size` to the target size, as
    /// [`SkyBuiltins::from_scene`] does); the sub-passes get the same built-ins with their own
    /// size and pass. `material` fills the material block (group 1 binding 0), zero-padded to
    /// the block's size and refused when shorter. Stand-ins, documented in the crate essay:
    /// material textures their hint's default texel ([`SkyShader::with_texture_defaults`];
    /// white without one), RADIANCE a black cube, a sub-pass texture that is not rendered a
    /// white texel (as Godot binds), global uniforms zero.
    pub fn render(
        &self,
        gpu: &Gpu,
        projection: Projection,
        width: u32,
        height: u32,
        builtins: &SkyBuiltins,
        material: &[u8],
    ) -> Result<Rendered, RenderError> {
        self.render_with(gpu, projection, width, height, builtins, material, &RenderOptions::default())
    }

    /// [`SkyShader::render`], skipping what `options` says the scene does not need.
    ///
    /// * An occluder (its size must be `width`×`height`) goes into a depth buffer before the
    ///   full pass (depth ½ where covered, the far plane elsewhere); the full pass tests against
    ///   it, so a covered fragment is rejected before it is shaded, and the pixel keeps
    ///   [`OCCLUDED`]. Godot's sub-passes are not occluded (Godot renders them whole).
    /// * A reduced resolution renders every pass (the sub-passes scaled with it) at
    ///   [`SkyResolution::shaded_size`], then upsamples to the target with `options.filter`
    ///   (wrapping around horizontally in the panorama), all in the same command buffer; with an
    ///   occluder, the reduced pass skips only texels no visible pixel reads
    ///   ([`Occluder::reduced`]) and the upsampling pass is depth-tested too.
    #[allow(clippy::too_many_arguments)]
    pub fn render_with(
        &self,
        gpu: &Gpu,
        projection: Projection,
        width: u32,
        height: u32,
        builtins: &SkyBuiltins,
        material: &[u8],
        options: &RenderOptions<'_>,
    ) -> Result<Rendered, RenderError> {
        let device = &gpu.device;
        let max = device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(RenderError::InvalidSize { width, height, max });
        }
        if let Some(o) = options.occluder
            && (o.width, o.height) != (width, height)
        {
            return Err(RenderError::OccluderSize { mask: (o.width, o.height), render: (width, height) });
        }
        for b in &self.bindings {
            if let (bindings::MATERIAL_GROUP, 0, BindingKind::Uniform { size }) = (b.group, b.binding, b.kind)
                && material.len() < size as usize
            {
                return Err(RenderError::Material { needed: size, given: material.len() });
            }
        }
        // A cube face is Godot's cubemap pass: the face index and the pass travel in the
        // built-ins, and no screen-space sub-pass exists (see `record`).
        let face_builtins;
        let builtins = match projection {
            Projection::CubeFace(face) => {
                face_builtins = SkyBuiltins {
                    cube_face: u32::from(face.min(5)),
                    render_pass: RenderPass::Cubemap.code(),
                    ..*builtins
                };
                &face_builtins
            }
            _ => builtins,
        };
        let (readback, submission, padded_row, timestamps) =
            scoped(gpu, || self.record(gpu, projection, width, height, builtins, material, options))?;
        let submitted = Instant::now();
        let (sender, receiver) = mpsc::channel();
        readback.map_async(wgpu::MapMode::Read, .., move |result| {
            // The receiver outlives the poll below; a send error cannot happen.
            let _ = sender.send(result);
        });
        let (stamp_sender, stamp_receiver) = mpsc::channel();
        if let Some((buffer, _)) = &timestamps {
            buffer.map_async(wgpu::MapMode::Read, .., move |result| {
                let _ = stamp_sender.send(result);
            });
        }
        let what = move || format!("rendering {width}x{height} (the device running the shader)");
        crate::watchdog::watched(what, || {
            device.poll(wgpu::PollType::Wait { submission_index: Some(submission), timeout: Some(GPU_TIMEOUT) })
        })
        .map_err(|e| RenderError::Poll(e.to_string()))?;
        let gpu_wait = submitted.elapsed();
        match mapped(device, &receiver) {
            Some(Ok(())) => {}
            Some(Err(e)) => return Err(RenderError::Map(e.to_string())),
            None => {
                return Err(RenderError::Map("the map callback did not run after the device went idle".into()));
            }
        }
        let pixels = {
            let view = readback.get_mapped_range(..).map_err(|e| RenderError::Map(e.to_string()))?;
            let row_bytes = (width * BYTES_PER_PIXEL) as usize;
            let mut pixels = Vec::with_capacity(width as usize * height as usize);
            for row in view.chunks_exact(padded_row as usize) {
                for px in row[..row_bytes].chunks_exact(BYTES_PER_PIXEL as usize) {
                    let mut rgba = [0.0f32; 4];
                    for (c, bytes) in rgba.iter_mut().zip(px.chunks_exact(4)) {
                        *c = f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
                    }
                    pixels.push(rgba);
                }
            }
            pixels
        };
        readback.unmap();
        let stamps = timestamps.as_ref().and_then(|_| mapped(device, &stamp_receiver));
        let gpu_time = match (&timestamps, stamps) {
            (Some((buffer, passes)), Some(Ok(()))) => {
                let view = buffer.get_mapped_range(..).map_err(|e| RenderError::Map(e.to_string()))?;
                let ticks: Vec<u64> = view
                    .chunks_exact(8)
                    .map(|b| u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
                    .collect();
                drop(view);
                buffer.unmap();
                // Begin and end of each pass; ticks × the queue's period (ns per tick).
                let total: u64 = (0..*passes).map(|p| ticks[2 * p + 1].saturating_sub(ticks[2 * p])).sum();
                Some(Duration::from_secs_f64(total as f64 * f64::from(gpu.queue.get_timestamp_period()) * 1e-9))
            }
            _ => None,
        };
        Ok(Rendered { pixels, gpu_wait, gpu_time })
    }

    /// Records the sub-passes, the full pass and the copy, and submits them; returns the
    /// read-back buffer, the submission, the padded row size and, with timestamp queries, their
    /// read-back buffer and the number of passes timed. Errors surface through the caller's
    /// error scopes.
    #[allow(clippy::too_many_arguments)]
    fn record(
        &self,
        gpu: &Gpu,
        projection: Projection,
        width: u32,
        height: u32,
        builtins: &SkyBuiltins,
        material: &[u8],
        options: &RenderOptions<'_>,
    ) -> (wgpu::Buffer, wgpu::SubmissionIndex, u32, Option<(wgpu::Buffer, usize)>) {
        let device = &gpu.device;
        let entry = projection.entry_point();
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("sky") });
        // Two timestamps per pass (at most quarter, half, full, upsampling).
        const MAX_PASSES: u32 = 4;
        // The size the sky is shaded at, and its built-ins (a reduced resolution is a smaller
        // screen for every pass).
        let (target_width, target_height) = (width, height);
        let (width, height) = options.resolution.shaded_size(width, height);
        let reduced = options.resolution != SkyResolution::Full;
        let scaled_builtins;
        let builtins = if reduced && builtins.render_pass != RenderPass::Cubemap.code() {
            scaled_builtins = SkyBuiltins { screen_size: [width as f32, height as f32], ..*builtins };
            &scaled_builtins
        } else {
            builtins
        };
        let wrap_x = matches!(projection, Projection::Panorama);
        let occluder = options.occluder.map(|o| {
            if reduced {
                std::borrow::Cow::Owned(o.reduced(width, height, options.filter, wrap_x))
            } else {
                std::borrow::Cow::Borrowed(o)
            }
        });
        let depth_view = occluder.as_deref().map(|o| self.depth_buffer(gpu, o));
        let queries = gpu.has_timestamps().then(|| {
            device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("sky pass times"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * MAX_PASSES,
            })
        });
        let mut passes = 0u32;
        let material_buffer = self
            .bindings
            .iter()
            .find(|b| b.group == bindings::MATERIAL_GROUP && b.binding == 0)
            .map(|_| uniform_buffer(gpu, "Material", material));

        // Godot's order: quarter, then half, then the background; each later pass reads the
        // earlier ones, and a pass reading its own (or a later) texture sees the white stand-in.
        let mut half_view = None;
        let mut quarter_view = None;
        for (pass, wanted, binding) in [
            (RenderPass::Quarter, self.sub_passes.quarter, bindings::QUARTER_RES_BINDING),
            (RenderPass::Half, self.sub_passes.half, bindings::HALF_RES_BINDING),
        ] {
            // Godot's cubemap pass reads half/quarter *cubemaps* (radiance mips 1 and 2), which
            // the harness does not render: they are the black stand-in Godot binds when missing.
            let cube = matches!(projection, Projection::CubeFace(_));
            if cube || !wanted || !self.declares(bindings::SKY_TEXTURE_GROUP, binding) {
                continue;
            }
            let (w, h) = sub_pass_size(pass, width, height);
            let target = render_target(gpu, w, h, SUB_PASS_FORMAT, wgpu::TextureUsages::TEXTURE_BINDING);
            let view = target.create_view(&wgpu::TextureViewDescriptor::default());
            let sub = SkyBuiltins { screen_size: [w as f32, h as f32], render_pass: pass.code(), ..*builtins };
            let groups =
                self.bind_groups(gpu, &sub, material_buffer.as_ref(), half_view.as_ref(), quarter_view.as_ref());
            let target =
                Target { view: &view, format: SUB_PASS_FORMAT, clear: Some(wgpu::Color::TRANSPARENT), depth: None };
            self.draw(gpu, &mut encoder, &target, entry, &groups, queries.as_ref().map(|q| (q, passes)));
            passes += 1;
            match pass {
                RenderPass::Quarter => quarter_view = Some(view),
                _ => half_view = Some(view),
            }
        }

        let usage = if reduced { wgpu::TextureUsages::TEXTURE_BINDING } else { wgpu::TextureUsages::COPY_SRC };
        // A reduced image is read by the upsampling pass: half floats for bilinear (sampled
        // with hardware filtering), f32 for Catmull–Rom (see `UpsampleFilter::reduced_format`).
        let sky_format = if reduced { options.filter.reduced_format() } else { FULL_FORMAT };
        let target = render_target(gpu, width, height, sky_format, usage);
        let view = target.create_view(&wgpu::TextureViewDescriptor::default());
        let groups =
            self.bind_groups(gpu, builtins, material_buffer.as_ref(), half_view.as_ref(), quarter_view.as_ref());
        let compare = self.depth_compare();
        let sky_target = Target {
            view: &view,
            format: sky_format,
            clear: Some(occluded_color()),
            depth: depth_view.as_ref().map(|d| (d, compare)),
        };
        self.draw(gpu, &mut encoder, &sky_target, entry, &groups, queries.as_ref().map(|q| (q, passes)));
        passes += 1;
        let target = if reduced {
            let full = render_target(gpu, target_width, target_height, FULL_FORMAT, wgpu::TextureUsages::COPY_SRC);
            let full_view = full.create_view(&wgpu::TextureViewDescriptor::default());
            let full_depth = options.occluder.map(|o| self.depth_buffer(gpu, o));
            let up = Target {
                view: &full_view,
                format: FULL_FORMAT,
                // Without an occluder nothing is left uncovered: no clear of the full-size
                // target (llvmpipe would memset 8 MB at 1024×512).
                clear: options.occluder.is_some().then(occluded_color),
                depth: full_depth.as_ref().map(|d| (d, compare)),
            };
            let params = UpsampleParams {
                src: [width, height],
                dst: [target_width, target_height],
                filter: options.filter,
                wrap_x,
            };
            self.upsample(gpu, &mut encoder, &view, &up, &params, queries.as_ref().map(|q| (q, passes)));
            passes += 1;
            full
        } else {
            target
        };
        let (width, height) = (target_width, target_height);
        let timestamps = queries.map(|set| {
            let bytes = u64::from(2 * passes) * 8;
            let resolved = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("pass times"),
                size: bytes,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let read = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("pass times readback"),
                size: bytes,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            encoder.resolve_query_set(&set, 0..2 * passes, &resolved, 0);
            encoder.copy_buffer_to_buffer(&resolved, 0, &read, 0, bytes);
            (read, passes as usize)
        });
        let padded_row =
            (width * BYTES_PER_PIXEL).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: u64::from(padded_row) * u64::from(height),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        encoder.copy_texture_to_buffer(
            target.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded_row),
                    rows_per_image: Some(height),
                },
            },
            wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        );
        let submission = gpu.queue.submit([encoder.finish()]);
        (readback, submission, padded_row, timestamps)
    }

    /// One bind group per declared group, filled with the scene's resources or stand-ins.
    fn bind_groups(
        &self,
        gpu: &Gpu,
        builtins: &SkyBuiltins,
        material: Option<&wgpu::Buffer>,
        half: Option<&wgpu::TextureView>,
        quarter: Option<&wgpu::TextureView>,
    ) -> Vec<wgpu::BindGroup> {
        let builtins_buffer = uniform_buffer(gpu, "SkyBuiltins", &builtins.to_bytes());
        let resources: Vec<(&Binding, Resource)> = self
            .bindings
            .iter()
            .map(|b| {
                let sky = b.group == bindings::SKY_TEXTURE_GROUP;
                let sub_pass = match b.binding {
                    bindings::HALF_RES_BINDING if sky => half,
                    bindings::QUARTER_RES_BINDING if sky => quarter,
                    _ => None,
                };
                let resource = match (b.group, b.binding, b.kind) {
                    (bindings::BUILTINS_GROUP, 0, _) => Resource::Buffer(builtins_buffer.clone()),
                    (bindings::MATERIAL_GROUP, 0, BindingKind::Uniform { size }) => Resource::Buffer(
                        material.cloned().unwrap_or_else(|| uniform_buffer(gpu, &b.name, &vec![0; size as usize])),
                    ),
                    // Global uniforms (group 3) come from Godot's project settings, which the
                    // harness does not have: zero.
                    (_, _, BindingKind::Uniform { size }) => {
                        Resource::Buffer(uniform_buffer(gpu, &b.name, &vec![0; size as usize]))
                    }
                    (_, _, BindingKind::Sampler) if sky => Resource::Sampler(self.clamp_sampler.clone()),
                    (_, _, BindingKind::Sampler) => Resource::Sampler(
                        self.material_samplers.get(&(b.group, b.binding)).unwrap_or(&self.repeat_sampler).clone(),
                    ),
                    (_, binding, BindingKind::Texture { dimension, sample_type }) => match sub_pass {
                        Some(view) => Resource::View(view.clone()),
                        None if self.provided.contains_key(&(b.group, binding)) => {
                            Resource::View(self.provided[&(b.group, binding)].clone())
                        }
                        // RADIANCE is black (no radiance map is rendered), and so are the
                        // sub-pass textures in the cubemap pass (Godot's cubemap-family
                        // default); a sub-pass texture not rendered is white; a material
                        // texture gets its hint's default (white without one), as in Godot.
                        None => {
                            let cube = builtins.render_pass == RenderPass::Cubemap.code();
                            let black = sky && (binding == 0 || cube);
                            let hinted = self.texture_defaults.iter().find(|(key, _)| *key == (b.group, binding));
                            let value = match hinted {
                                _ if black => [0.0, 0.0, 0.0, 1.0],
                                Some((_, texel)) => *texel,
                                None => [1.0; 4],
                            };
                            Resource::View(bindings::constant_texture(
                                &gpu.device,
                                &gpu.queue,
                                dimension,
                                sample_type,
                                value,
                            ))
                        }
                    },
                };
                (b, resource)
            })
            .collect();
        self.group_layouts
            .iter()
            .enumerate()
            .map(|(group, layout)| {
                let entries: Vec<_> = resources
                    .iter()
                    .filter(|(b, _)| b.group == group as u32)
                    .map(|(b, resource)| {
                        let resource = match resource {
                            Resource::Buffer(buffer) => buffer.as_entire_binding(),
                            Resource::View(view) => wgpu::BindingResource::TextureView(view),
                            Resource::Sampler(sampler) => wgpu::BindingResource::Sampler(sampler),
                        };
                        wgpu::BindGroupEntry { binding: b.binding, resource }
                    })
                    .collect();
                gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("sky group"),
                    layout,
                    entries: &entries,
                })
            })
            .collect()
    }

    /// Draws the fullscreen triangle into `view`; with `timestamps` = (set, pass index), writes
    /// the pass's begin and end times at 2·index and 2·index + 1.
    #[allow(clippy::too_many_arguments)]
    fn draw(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        target: &Target<'_>,
        entry: &'static str,
        groups: &[wgpu::BindGroup],
        timestamps: Option<(&wgpu::QuerySet, u32)>,
    ) {
        let pipeline = self.pipeline(gpu, entry, target.format, target.depth.map(|d| d.1));
        let mut pass = begin_pass(encoder, target, timestamps);
        pass.set_pipeline(&pipeline);
        for (i, group) in groups.iter().enumerate() {
            pass.set_bind_group(i as u32, group, &[]);
        }
        pass.draw(0..3, 0..1);
    }
}

impl SkyShader {
    /// A depth buffer holding the occluder: depth ½ where covered (nearer than the far plane in
    /// either convention), the far plane elsewhere. Written from the host: the geometry a real
    /// renderer would have drawn first.
    fn depth_buffer(&self, gpu: &Gpu, occluder: &Occluder) -> wgpu::TextureView {
        let far = if self.depth == skycore::DepthConvention::Reversed { 0 } else { u16::MAX };
        let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("occluder depth"),
            size: wgpu::Extent3d { width: occluder.width, height: occluder.height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::DepthOnly,
            },
            &occluder.depth_texels(far, 1 << 15),
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(occluder.width * 2), rows_per_image: None },
            wgpu::Extent3d { width: occluder.width, height: occluder.height, depth_or_array_layers: 1 },
        );
        texture.create_view(&wgpu::TextureViewDescriptor::default())
    }

    /// Upsamples the reduced sky `src` into `target`.
    fn upsample(
        &self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        src: &wgpu::TextureView,
        target: &Target<'_>,
        params: &UpsampleParams,
        timestamps: Option<(&wgpu::QuerySet, u32)>,
    ) {
        let device = &gpu.device;
        let pipeline = {
            let mut cache = self.upsample.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
            cache
                .entry((target.depth.is_some(), params.filter))
                .or_insert_with(|| {
                    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                        label: Some("sky upsample"),
                        source: wgpu::ShaderSource::Wgsl(UPSAMPLE_WGSL.into()),
                    });
                    // Explicit: bilinear samples an Rgba16Float image through a filtering
                    // sampler; Catmull–Rom loads from Rgba32Float, which is not filterable
                    // without an optional feature (its entry point does not use the sampler).
                    let bilinear = params.filter == UpsampleFilter::Bilinear;
                    let entries = [
                        wgpu::BindGroupLayoutEntry {
                            binding: 0,
                            visibility: wgpu::ShaderStages::FRAGMENT,
                            ty: wgpu::BindingType::Texture {
                                sample_type: wgpu::TextureSampleType::Float { filterable: bilinear },
                                view_dimension: wgpu::TextureViewDimension::D2,
                                multisampled: false,
                            },
                            count: None,
                        },
                        wgpu::BindGroupLayoutEntry {
                            binding: 1,
                            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                            ty: wgpu::BindingType::Buffer {
                                ty: wgpu::BufferBindingType::Uniform,
                                has_dynamic_offset: false,
                                min_binding_size: None,
                            },
                            count: None,
                        },
                        wgpu::BindGroupLayoutEntry {
                            binding: 2,
                            visibility: wgpu::ShaderStages::FRAGMENT,
                            ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                            count: None,
                        },
                    ];
                    // Catmull–Rom reads no sampler: no binding 2.
                    let group = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                        label: Some("sky upsample"),
                        entries: &entries[..if bilinear { 3 } else { 2 }],
                    });
                    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                        label: Some("sky upsample"),
                        bind_group_layouts: &[Some(&group)],
                        immediate_size: 0,
                    });
                    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                        label: Some("sky upsample"),
                        layout: Some(&layout),
                        vertex: wgpu::VertexState {
                            module: &module,
                            entry_point: Some("vs_main"),
                            compilation_options: Default::default(),
                            buffers: &[],
                        },
                        primitive: wgpu::PrimitiveState::default(),
                        depth_stencil: target.depth.map(|d| depth_state(d.1)),
                        multisample: wgpu::MultisampleState::default(),
                        fragment: Some(wgpu::FragmentState {
                            module: &module,
                            entry_point: Some(if bilinear { "fs_bilinear" } else { "fs_catmull_rom" }),
                            compilation_options: Default::default(),
                            targets: &[Some(wgpu::ColorTargetState {
                                format: target.format,
                                blend: None,
                                write_mask: wgpu::ColorWrites::ALL,
                            })],
                        }),
                        multiview_mask: None,
                        cache: None,
                    })
                })
                .clone()
        };
        let mut bytes = Vec::with_capacity(32);
        for v in [params.src[0], params.src[1], params.dst[0], params.dst[1]] {
            bytes.extend_from_slice(&(v as f32).to_le_bytes());
        }
        bytes.extend_from_slice(&u32::from(params.wrap_x).to_le_bytes());
        bytes.extend_from_slice(&self.depth.far_plane().to_le_bytes());
        bytes.extend_from_slice(&[0; 8]);
        let buffer = uniform_buffer(gpu, "upsample params", &bytes);
        let sampler = if params.wrap_x { &self.panorama_sampler } else { &self.clamp_sampler };
        let entries = [
            wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(src) },
            wgpu::BindGroupEntry { binding: 1, resource: buffer.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::Sampler(sampler) },
        ];
        let bound = if params.filter == UpsampleFilter::Bilinear { 3 } else { 2 };
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("sky upsample"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &entries[..bound],
        });
        let mut pass = begin_pass(encoder, target, timestamps);
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.draw(0..3, 0..1);
    }
}

/// What the upsampling pass needs to know.
struct UpsampleParams {
    src: [u32; 2],
    dst: [u32; 2],
    filter: UpsampleFilter,
    wrap_x: bool,
}

/// [`OCCLUDED`] as a clear colour.
fn occluded_color() -> wgpu::Color {
    let [r, g, b, a] = OCCLUDED.map(f64::from);
    wgpu::Color { r, g, b, a }
}

/// The depth state of a sky pass: test against the occluder, never write.
fn depth_state(compare: wgpu::CompareFunction) -> wgpu::DepthStencilState {
    wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(false),
        depth_compare: Some(compare),
        stencil: wgpu::StencilState::default(),
        bias: wgpu::DepthBiasState::default(),
    }
}

/// Begins a render pass into `target` (clearing it; loading the depth buffer the occluder was
/// written into); with `timestamps` = (set, pass index), writes the pass's begin and end times
/// at 2·index and 2·index + 1.
fn begin_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    target: &Target<'_>,
    timestamps: Option<(&wgpu::QuerySet, u32)>,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("sky"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: target.view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: match target.clear {
                    Some(color) => wgpu::LoadOp::Clear(color),
                    // SAFETY: only for a pass whose draw writes every pixel before any is read
                    // (no blending, nothing reads the target within the pass).
                    None => wgpu::LoadOp::DontCare(unsafe { wgpu::LoadOpDontCare::enabled() }),
                },
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: target.depth.map(|(view, _)| wgpu::RenderPassDepthStencilAttachment {
            view,
            depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Discard }),
            stencil_ops: None,
        }),
        timestamp_writes: timestamps.map(|(query_set, index)| wgpu::RenderPassTimestampWrites {
            query_set,
            beginning_of_pass_write_index: Some(2 * index),
            end_of_pass_write_index: Some(2 * index + 1),
        }),
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// Compiles and renders once: [`SkyShader::new`] without sub-passes, then
/// [`SkyShader::render`]. For many renders of one shader, keep the [`SkyShader`].
pub fn render(
    gpu: &Gpu,
    wgsl: &str,
    projection: Projection,
    width: u32,
    height: u32,
    builtins: &SkyBuiltins,
    material: &[u8],
) -> Result<Vec<[f32; 4]>, RenderError> {
    let shader = SkyShader::new(gpu, wgsl, SubPasses::default())?;
    Ok(shader.render(gpu, projection, width, height, builtins, material)?.pixels)
}

/// What one binding is bound to in one render.
enum Resource {
    Buffer(wgpu::Buffer),
    View(wgpu::TextureView),
    Sampler(wgpu::Sampler),
}

/// A uniform buffer holding `bytes`, zero-padded to a multiple of 16 bytes.
fn uniform_buffer(gpu: &Gpu, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    let size = (bytes.len() as u64).div_ceil(16).max(1) * 16;
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut padded = bytes.to_vec();
    padded.resize(size as usize, 0);
    gpu.queue.write_buffer(&buffer, 0, &padded);
    buffer
}

/// A render target of the given size and format.
fn render_target(
    gpu: &Gpu,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    extra: wgpu::TextureUsages,
) -> wgpu::Texture {
    gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("sky target"),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | extra,
        view_formats: &[],
    })
}

/// Runs `f` inside wgpu error scopes and returns its value, or the first error wgpu reported
/// (validation first: an invalid shader makes every later object invalid too, and the scope
/// keeps the first).
fn scoped<T>(gpu: &Gpu, f: impl FnOnce() -> T) -> Result<T, RenderError> {
    let device = &gpu.device;
    let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let internal = device.push_error_scope(wgpu::ErrorFilter::Internal);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let value = f();
    let scopes = [("validation", validation.pop()), ("internal", internal.pop()), ("out-of-memory", oom.pop())];
    let mut first = None;
    for (kind, scope) in scopes {
        if let Some(error) = pollster::block_on(scope) {
            first.get_or_insert(RenderError::Wgpu { kind, message: error_chain(&error) });
        }
    }
    match first {
        Some(error) => Err(error),
        None => Ok(value),
    }
}

/// A wgpu error's message followed by its causes, one per line.
fn error_chain(error: &wgpu::Error) -> String {
    let mut text = error.to_string();
    let mut source = std::error::Error::source(error);
    while let Some(s) = source {
        let line = s.to_string();
        if !text.contains(&line) {
            text.push_str("\n  caused by: ");
            text.push_str(&line);
        }
        source = s.source();
    }
    text
}

//! Offscreen renders of a converted sky shader, read back as f32 RGBA.
//!
//! A [`SkyShader`] holds what does not change between renders (the compiled module, the bind
//! group layouts, one pipeline per entry point and target format), so a test matrix or a
//! benchmark pays for shader compilation once. Each [`SkyShader::render`] records Godot's pass
//! order into one command buffer: the quarter-resolution sub-pass, then the half-resolution
//! one, then the full pass that can read both, then the copy to a read-back buffer.

use crate::bindings::{self, Binding, BindingError, BindingKind};
use crate::builtins::{RenderPass, SkyBuiltins};
use crate::gpu::Gpu;
use skyref::Projection;
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
        }
    }
}

impl std::error::Error for RenderError {}

impl From<BindingError> for RenderError {
    fn from(e: BindingError) -> Self {
        RenderError::Binding(e)
    }
}

/// The fragment entry point of the converted shader for a projection.
pub fn fragment_entry(projection: Projection) -> &'static str {
    match projection {
        Projection::Panorama => "fs_panorama",
        Projection::Camera => "fs_camera",
        Projection::CubeFace(_) => "fs_cubemap",
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

/// The size of a sub-pass target for a screen: Godot divides by 2 or 4 and keeps each side
/// at least 4 pixels.
pub fn sub_pass_size(pass: RenderPass, width: u32, height: u32) -> (u32, u32) {
    let divisor = match pass {
        RenderPass::Half => 2,
        RenderPass::Quarter => 4,
        _ => 1,
    };
    ((width / divisor).max(4), (height / divisor).max(4))
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

/// A converted sky shader compiled for one device, ready to render any number of times.
pub struct SkyShader {
    module: wgpu::ShaderModule,
    bindings: Vec<Binding>,
    group_layouts: Vec<wgpu::BindGroupLayout>,
    pipeline_layout: wgpu::PipelineLayout,
    pipelines: Mutex<HashMap<(&'static str, wgpu::TextureFormat), wgpu::RenderPipeline>>,
    sub_passes: SubPasses,
    repeat_sampler: wgpu::Sampler,
    clamp_sampler: wgpu::Sampler,
    texture_defaults: Vec<((u32, u32), [f32; 4])>,
}

impl SkyShader {
    /// Compiles `wgsl` on `gpu` and builds the bind group layouts from the resources it
    /// declares (see [`bindings::discover`]).
    pub fn new(gpu: &Gpu, wgsl: &str, sub_passes: SubPasses) -> Result<SkyShader, RenderError> {
        let bindings = bindings::discover(wgsl)?;
        let device = &gpu.device;
        scoped(gpu, || {
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("sky"),
                source: wgpu::ShaderSource::Wgsl(wgsl.into()),
            });
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
            let sampler = |mode: wgpu::AddressMode| {
                device.create_sampler(&wgpu::SamplerDescriptor {
                    label: Some("sky sampler"),
                    address_mode_u: mode,
                    address_mode_v: mode,
                    address_mode_w: mode,
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
                repeat_sampler: sampler(wgpu::AddressMode::Repeat),
                clamp_sampler: sampler(wgpu::AddressMode::ClampToEdge),
                texture_defaults: Vec::new(),
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

    /// The resources the shader declares.
    pub fn bindings(&self) -> &[Binding] {
        &self.bindings
    }

    /// Whether the shader declares `group`/`binding`.
    fn declares(&self, group: u32, binding: u32) -> bool {
        self.bindings.iter().any(|b| b.group == group && b.binding == binding)
    }

    /// The pipeline for an entry point and target format, built on first use.
    fn pipeline(&self, gpu: &Gpu, entry: &'static str, format: wgpu::TextureFormat) -> wgpu::RenderPipeline {
        let mut cache = self.pipelines.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        cache
            .entry((entry, format))
            .or_insert_with(|| {
                gpu.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(entry),
                    layout: Some(&self.pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &self.module,
                        entry_point: Some("vs_main"),
                        compilation_options: Default::default(),
                        buffers: &[],
                    },
                    primitive: wgpu::PrimitiveState {
                        topology: wgpu::PrimitiveTopology::TriangleList,
                        cull_mode: None,
                        ..Default::default()
                    },
                    depth_stencil: None,
                    multisample: wgpu::MultisampleState::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &self.module,
                        entry_point: Some(entry),
                        compilation_options: Default::default(),
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
        let device = &gpu.device;
        let max = device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(RenderError::InvalidSize { width, height, max });
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
                face_builtins =
                    SkyBuiltins { cube_face: u32::from(face.min(5)), render_pass: RenderPass::Cubemap, ..*builtins };
                &face_builtins
            }
            _ => builtins,
        };
        let (readback, submission, padded_row, timestamps) =
            scoped(gpu, || self.record(gpu, projection, width, height, builtins, material))?;
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
        device
            .poll(wgpu::PollType::Wait { submission_index: Some(submission), timeout: Some(GPU_TIMEOUT) })
            .map_err(|e| RenderError::Poll(e.to_string()))?;
        let gpu_wait = submitted.elapsed();
        match receiver.try_recv() {
            Ok(Ok(())) => {}
            Ok(Err(e)) => return Err(RenderError::Map(e.to_string())),
            Err(_) => {
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
        let gpu_time = match (&timestamps, stamp_receiver.try_recv()) {
            (Some((buffer, passes)), Ok(Ok(()))) => {
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
    fn record(
        &self,
        gpu: &Gpu,
        projection: Projection,
        width: u32,
        height: u32,
        builtins: &SkyBuiltins,
        material: &[u8],
    ) -> (wgpu::Buffer, wgpu::SubmissionIndex, u32, Option<(wgpu::Buffer, usize)>) {
        let device = &gpu.device;
        let entry = fragment_entry(projection);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("sky") });
        // Two timestamps per pass (at most quarter, half, full).
        const MAX_PASSES: u32 = 3;
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
            let sub = SkyBuiltins { screen_size: [w as f32, h as f32], render_pass: pass, ..*builtins };
            let groups =
                self.bind_groups(gpu, &sub, material_buffer.as_ref(), half_view.as_ref(), quarter_view.as_ref());
            self.draw(gpu, &mut encoder, &view, entry, SUB_PASS_FORMAT, &groups, queries.as_ref().map(|q| (q, passes)));
            passes += 1;
            match pass {
                RenderPass::Quarter => quarter_view = Some(view),
                _ => half_view = Some(view),
            }
        }

        let target = render_target(gpu, width, height, FULL_FORMAT, wgpu::TextureUsages::COPY_SRC);
        let view = target.create_view(&wgpu::TextureViewDescriptor::default());
        let groups =
            self.bind_groups(gpu, builtins, material_buffer.as_ref(), half_view.as_ref(), quarter_view.as_ref());
        self.draw(gpu, &mut encoder, &view, entry, FULL_FORMAT, &groups, queries.as_ref().map(|q| (q, passes)));
        passes += 1;
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
                    (_, _, BindingKind::Sampler) => Resource::Sampler(self.repeat_sampler.clone()),
                    (_, binding, BindingKind::Texture { dimension, sample_type }) => match sub_pass {
                        Some(view) => Resource::View(view.clone()),
                        // RADIANCE is black (no radiance map is rendered), and so are the
                        // sub-pass textures in the cubemap pass (Godot's cubemap-family
                        // default); a sub-pass texture not rendered is white; a material
                        // texture gets its hint's default (white without one), as in Godot.
                        None => {
                            let cube = builtins.render_pass == RenderPass::Cubemap;
                            let black = sky && (binding == 0 || cube);
                            let hinted = self.texture_defaults.iter().find(|(key, _)| *key == (b.group, binding));
                            let value = match hinted {
                                _ if black => [0.0, 0.0, 0.0, 1.0],
                                Some((_, texel)) => *texel,
                                None => [1.0; 4],
                            };
                            Resource::View(bindings::constant_texture(gpu, dimension, sample_type, value))
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
        view: &wgpu::TextureView,
        entry: &'static str,
        format: wgpu::TextureFormat,
        groups: &[wgpu::BindGroup],
        timestamps: Option<(&wgpu::QuerySet, u32)>,
    ) {
        let pipeline = self.pipeline(gpu, entry, format);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("sky"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: timestamps.map(|(query_set, index)| wgpu::RenderPassTimestampWrites {
                query_set,
                beginning_of_pass_write_index: Some(2 * index),
                end_of_pass_write_index: Some(2 * index + 1),
            }),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&pipeline);
        for (i, group) in groups.iter().enumerate() {
            pass.set_bind_group(i as u32, group, &[]);
        }
        pass.draw(0..3, 0..1);
    }
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

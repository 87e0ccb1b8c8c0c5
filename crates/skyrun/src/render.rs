//! One offscreen render of a converted sky shader, read back as f32 RGBA.

use crate::builtins::SkyBuiltins;
use crate::gpu::Gpu;
use skyref::Projection;
use std::fmt;
use std::sync::mpsc;
use std::time::Duration;

/// Bytes per pixel of the Rgba32Float target.
const BYTES_PER_PIXEL: u32 = 16;

/// How long [`render`] waits for the GPU before it gives up. lavapipe renders a 64×32 Freeman
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
    /// wgpu rejected something: the WGSL (a shader-module error carries naga's message), the
    /// pipeline (an entry point missing, or a binding the explicit layouts do not provide:
    /// textures, group 2 or 3), a bind group (material too small for the block), or ran out of
    /// memory.
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
            RenderError::Wgpu { kind, message } => write!(f, "wgpu {kind} error: {message}"),
            RenderError::Poll(m) => write!(f, "waiting for the GPU failed: {m}"),
            RenderError::Map(m) => write!(f, "reading the image back failed: {m}"),
        }
    }
}

impl std::error::Error for RenderError {}

/// The fragment entry point of the converted shader for a projection.
pub fn fragment_entry(projection: Projection) -> &'static str {
    match projection {
        Projection::Panorama => "fs_panorama",
        Projection::Camera => "fs_camera",
    }
}

/// Renders the converted shader `wgsl` into a `width`×`height` Rgba32Float target and reads it
/// back: one `[r, g, b, a]` per pixel, row 0 at the top, left to right.
///
/// The pipeline is `vs_main` (a fullscreen triangle, 3 vertices, no vertex buffers) and the
/// projection's fragment entry, no blending, no culling. Bind group layouts are explicit:
/// group 0 binding 0 is the 288-byte `SkyBuiltins` uniform (filled from `builtins`; its
/// `screen_size` is used as given, so set it to the target size, as
/// [`SkyBuiltins::from_scene`] does); group 1 binding 0 is a uniform buffer holding `material`
/// when `material` is not empty (zero-padded to a multiple of 16 bytes). Shaders that bind
/// textures (material samplers, the sky's own textures in group 2) or global uniforms
/// (group 3) are outside this harness: pipeline creation fails with [`RenderError::Wgpu`].
///
/// Every wgpu error on the way is caught in error scopes and returned, never panicked on.
pub fn render(
    gpu: &Gpu,
    wgsl: &str,
    projection: Projection,
    width: u32,
    height: u32,
    builtins: &SkyBuiltins,
    material: &[u8],
) -> Result<Vec<[f32; 4]>, RenderError> {
    let device = &gpu.device;
    let max = device.limits().max_texture_dimension_2d;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(RenderError::InvalidSize { width, height, max });
    }

    let oom = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let internal = device.push_error_scope(wgpu::ErrorFilter::Internal);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let recorded = record(gpu, wgsl, projection, width, height, builtins, material);
    // Pop in reverse order of pushing; report the first error found, validation first (an
    // invalid shader makes every later object invalid too, but the scope keeps the first).
    let scopes = [("validation", validation.pop()), ("internal", internal.pop()), ("out-of-memory", oom.pop())];
    let mut first = None;
    for (kind, scope) in scopes {
        if let Some(error) = pollster::block_on(scope) {
            first.get_or_insert(RenderError::Wgpu { kind, message: error_chain(&error) });
        }
    }
    if let Some(error) = first {
        return Err(error);
    }
    let (readback, submission, padded_row) = recorded;

    let (sender, receiver) = mpsc::channel();
    readback.map_async(wgpu::MapMode::Read, .., move |result| {
        // The receiver outlives the poll below; a send error cannot happen.
        let _ = sender.send(result);
    });
    device
        .poll(wgpu::PollType::Wait { submission_index: Some(submission), timeout: Some(GPU_TIMEOUT) })
        .map_err(|e| RenderError::Poll(e.to_string()))?;
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
                let c = |i: usize| f32::from_le_bytes(px[4 * i..4 * i + 4].try_into().unwrap());
                pixels.push([c(0), c(1), c(2), c(3)]);
            }
        }
        pixels
    };
    readback.unmap();
    Ok(pixels)
}

/// Creates every object and submits the render and the copy; returns the read-back buffer,
/// the submission and the padded row size. Errors surface through the caller's error scopes.
fn record(
    gpu: &Gpu,
    wgsl: &str,
    projection: Projection,
    width: u32,
    height: u32,
    builtins: &SkyBuiltins,
    material: &[u8],
) -> (wgpu::Buffer, wgpu::SubmissionIndex, u32) {
    let device = &gpu.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("sky"),
        source: wgpu::ShaderSource::Wgsl(wgsl.into()),
    });

    let uniform_entry = |min: Option<u64>| wgpu::BindGroupLayoutEntry {
        binding: 0,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: min.and_then(wgpu::BufferSize::new),
        },
        count: None,
    };
    let builtins_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("SkyBuiltins"),
        entries: &[uniform_entry(Some(SkyBuiltins::SIZE as u64))],
    });
    let material_layout = (!material.is_empty()).then(|| {
        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("Material"),
            entries: &[uniform_entry(None)],
        })
    });
    let mut layouts = vec![Some(&builtins_layout)];
    if let Some(layout) = &material_layout {
        layouts.push(Some(layout));
    }
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("sky"),
        bind_group_layouts: &layouts,
        immediate_size: 0,
    });
    let format = wgpu::TextureFormat::Rgba32Float;
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(fragment_entry(projection)),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module: &module,
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
            module: &module,
            entry_point: Some(fragment_entry(projection)),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL })],
        }),
        multiview_mask: None,
        cache: None,
    });

    let uniform_buffer = |label: &str, bytes: &[u8]| {
        // Uniform blocks are multiples of 16 bytes; a short tail is zero-padded.
        let size = (bytes.len() as u64).div_ceil(16).max(1) * 16;
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut padded = bytes.to_vec();
        padded.resize(size as usize, 0);
        gpu.queue.write_buffer(&buffer, 0, &padded);
        buffer
    };
    let builtins_buffer = uniform_buffer("SkyBuiltins", &builtins.to_bytes());
    let builtins_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("SkyBuiltins"),
        layout: &builtins_layout,
        entries: &[wgpu::BindGroupEntry { binding: 0, resource: builtins_buffer.as_entire_binding() }],
    });
    let material_group = material_layout.as_ref().map(|layout| {
        let buffer = uniform_buffer("Material", material);
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("Material"),
            layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: buffer.as_entire_binding() }],
        })
    });

    let target = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("target"),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let view = target.create_view(&wgpu::TextureViewDescriptor::default());
    let padded_row =
        (width * BYTES_PER_PIXEL).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: u64::from(padded_row) * u64::from(height),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });

    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("sky") });
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("sky"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &builtins_group, &[]);
        if let Some(group) = &material_group {
            pass.set_bind_group(1, group, &[]);
        }
        pass.draw(0..3, 0..1);
    }
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture: &target,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
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
    (readback, submission, padded_row)
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

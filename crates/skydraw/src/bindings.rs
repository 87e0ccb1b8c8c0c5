//! What a shader binds, read from its WGSL, and what stands in for what nobody gives.
//!
//! The runtime (and the test harness built on it) does not trust a hand-written list of
//! bindings: it parses the WGSL with naga and reads every resource the module declares (group,
//! binding, kind, size). That way the same code draws gdsky's converted modules, whatever subset
//! of the sky textures they declare, and hand-written WGSL with the same interface. The layouts
//! built from them are explicit, so a binding that cannot be provided is an error with its
//! name, not a silently different pipeline.

use std::fmt;

/// The group of the wrapper's `SkyBuiltins` uniform.
pub const BUILTINS_GROUP: u32 = 0;
/// The group of the material (uniform block at binding 0, then textures and samplers).
pub const MATERIAL_GROUP: u32 = 1;
/// The group of the sky's own textures: RADIANCE (0/1), HALF_RES_COLOR (2/3),
/// QUARTER_RES_COLOR (4/5).
pub const SKY_TEXTURE_GROUP: u32 = 2;
/// The group of Godot's global shader uniforms.
pub const GLOBAL_UNIFORM_GROUP: u32 = 3;
/// Binding of the half-resolution sub-pass texture in [`SKY_TEXTURE_GROUP`].
pub const HALF_RES_BINDING: u32 = 2;
/// Binding of the quarter-resolution sub-pass texture in [`SKY_TEXTURE_GROUP`].
pub const QUARTER_RES_BINDING: u32 = 4;

/// One resource the shader declares.
#[derive(Clone, Debug, PartialEq)]
pub struct Binding {
    /// The variable's name in the WGSL.
    pub name: String,
    /// `@group`.
    pub group: u32,
    /// `@binding`.
    pub binding: u32,
    /// What it is.
    pub kind: BindingKind,
}

/// The kinds of resource a converted sky shader can declare.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BindingKind {
    /// A uniform buffer of this many bytes.
    Uniform {
        /// Size of the block as naga lays it out.
        size: u32,
    },
    /// A sampled texture.
    Texture {
        /// 2D, 2D array, 3D or cube.
        dimension: wgpu::TextureViewDimension,
        /// Float, signed or unsigned integer. A float texture is filterable when the module
        /// samples it (`textureSample*`, `textureGather`, naga's `ImageSample`) and not
        /// filterable when it only loads texels from it (`textureLoad`, Godot's `texelFetch`),
        /// so that a 32-bit float texture, which core WebGPU cannot filter, can be bound to it.
        sample_type: wgpu::TextureSampleType,
    },
    /// A filtering sampler.
    Sampler,
}

/// Why a shader's resources cannot be bound.
#[derive(Clone, Debug, PartialEq)]
pub enum BindingError {
    /// The WGSL does not parse (naga's message).
    Parse(String),
    /// A resource nothing stands in for (storage buffers, storage or depth textures,
    /// binding arrays, comparison samplers, an unexpected group).
    Unsupported {
        /// The variable's name.
        name: String,
        /// What it is and why it cannot be bound.
        what: String,
    },
}

impl fmt::Display for BindingError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BindingError::Parse(m) => write!(f, "the WGSL does not parse: {m}"),
            BindingError::Unsupported { name, what } => {
                write!(f, "cannot bind `{name}`: {what}")
            }
        }
    }
}

impl std::error::Error for BindingError {}

/// Every resource a WGSL module declares, sorted by group and binding.
///
/// A float texture is declared filterable only when the module samples it (see
/// [`BindingKind::Texture`] and [`sampled_images`]).
pub fn discover(wgsl: &str) -> Result<Vec<Binding>, BindingError> {
    let module = naga::front::wgsl::parse_str(wgsl).map_err(|e| BindingError::Parse(e.emit_to_string(wgsl)))?;
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).map_err(|e| BindingError::Parse(e.to_string()))?;
    let sampled = sampled_images(&module);
    let mut found = Vec::new();
    for (handle, var) in module.global_variables.iter() {
        let Some(rb) = &var.binding else { continue };
        let name = var.name.clone().unwrap_or_else(|| format!("group{}_binding{}", rb.group, rb.binding));
        found.push(describe(&module, &layouter, &sampled, handle, var, rb, name)?);
    }
    found.sort_by_key(|b| (b.group, b.binding));
    Ok(found)
}

/// The image globals of `module` that some function samples (naga `ImageSample`, which covers
/// WGSL's `textureSample*` and `textureGather*`), following images passed to functions as
/// arguments through every call. When the analysis cannot tell (an image expression that is
/// neither a global nor an argument; none occurs in the modules gdsky emits, which have no
/// binding arrays), every image counts as sampled: the filterable layout the harness used for
/// all float textures before it told the two apart.
pub fn sampled_images(module: &naga::Module) -> std::collections::HashSet<naga::Handle<naga::GlobalVariable>> {
    use naga::{Expression, Handle};
    use std::collections::HashSet;

    /// Where an image expression comes from.
    #[derive(Clone, Copy, PartialEq, Eq, Hash)]
    enum Source {
        Global(Handle<naga::GlobalVariable>),
        Argument(u32),
        Unknown,
    }
    fn source(f: &naga::Function, e: Handle<Expression>) -> Source {
        match f.expressions[e] {
            Expression::GlobalVariable(g) => Source::Global(g),
            Expression::FunctionArgument(i) => Source::Argument(i),
            _ => Source::Unknown,
        }
    }
    /// Every call in a block, nested blocks included: (callee, its arguments).
    fn calls(block: &naga::Block, out: &mut Vec<(Handle<naga::Function>, Vec<Handle<Expression>>)>) {
        for statement in block.iter() {
            match statement {
                naga::Statement::Block(b) => calls(b, out),
                naga::Statement::If { accept, reject, .. } => {
                    calls(accept, out);
                    calls(reject, out);
                }
                naga::Statement::Switch { cases, .. } => cases.iter().for_each(|c| calls(&c.body, out)),
                naga::Statement::Loop { body, continuing, .. } => {
                    calls(body, out);
                    calls(continuing, out);
                }
                naga::Statement::Call { function, arguments, .. } => out.push((*function, arguments.clone())),
                _ => {}
            }
        }
    }

    // Per function: the images it samples directly, and its calls.
    struct Summary {
        function: Option<Handle<naga::Function>>,
        direct: HashSet<Source>,
        calls: Vec<(Handle<naga::Function>, Vec<Source>)>,
    }
    let summarize = |handle: Option<Handle<naga::Function>>, f: &naga::Function| {
        let direct = f
            .expressions
            .iter()
            .filter_map(|(_, e)| match e {
                Expression::ImageSample { image, .. } => Some(source(f, *image)),
                _ => None,
            })
            .collect();
        let mut found = Vec::new();
        calls(&f.body, &mut found);
        let calls =
            found.into_iter().map(|(callee, args)| (callee, args.iter().map(|a| source(f, *a)).collect())).collect();
        Summary { function: handle, direct, calls }
    };
    let summaries: Vec<Summary> = module
        .functions
        .iter()
        .map(|(h, f)| summarize(Some(h), f))
        .chain(module.entry_points.iter().map(|ep| summarize(None, &ep.function)))
        .collect();
    // Which arguments of which function are sampled, to a fixed point: an argument passed on to
    // a callee's sampled argument is sampled too.
    let mut sampled_args: HashSet<(Handle<naga::Function>, u32)> = HashSet::new();
    loop {
        let before = sampled_args.len();
        for s in &summaries {
            let Some(me) = s.function else { continue };
            for source in &s.direct {
                if let Source::Argument(i) = source {
                    sampled_args.insert((me, *i));
                }
            }
            for (callee, args) in &s.calls {
                for (j, arg) in args.iter().enumerate() {
                    if let Source::Argument(i) = arg
                        && sampled_args.contains(&(*callee, j as u32))
                    {
                        sampled_args.insert((me, *i));
                    }
                }
            }
        }
        if sampled_args.len() == before {
            break;
        }
    }
    let mut sampled = HashSet::new();
    let mut unknown = false;
    for s in &summaries {
        for source in &s.direct {
            match source {
                Source::Global(g) => {
                    sampled.insert(*g);
                }
                Source::Unknown => unknown = true,
                Source::Argument(_) => {}
            }
        }
        for (callee, args) in &s.calls {
            for (j, arg) in args.iter().enumerate() {
                if sampled_args.contains(&(*callee, j as u32)) {
                    match arg {
                        Source::Global(g) => {
                            sampled.insert(*g);
                        }
                        Source::Unknown => unknown = true,
                        Source::Argument(_) => {}
                    }
                }
            }
        }
    }
    if unknown {
        sampled.extend(
            module
                .global_variables
                .iter()
                .filter(|(_, v)| matches!(module.types[v.ty].inner, naga::TypeInner::Image { .. }))
                .map(|(h, _)| h),
        );
    }
    sampled
}

/// What one resource global is.
fn describe(
    module: &naga::Module,
    layouter: &naga::proc::Layouter,
    sampled: &std::collections::HashSet<naga::Handle<naga::GlobalVariable>>,
    handle: naga::Handle<naga::GlobalVariable>,
    var: &naga::GlobalVariable,
    rb: &naga::ResourceBinding,
    name: String,
) -> Result<Binding, BindingError> {
    let unsupported = |what: &str| BindingError::Unsupported { name: name.clone(), what: what.to_string() };
    if rb.group > GLOBAL_UNIFORM_GROUP {
        return Err(unsupported(&format!("group {} is outside the sky interface (groups 0–3)", rb.group)));
    }
    let kind = match (&var.space, &module.types[var.ty].inner) {
        (naga::AddressSpace::Uniform, _) => BindingKind::Uniform { size: layouter[var.ty].size },
        (naga::AddressSpace::Handle, naga::TypeInner::Sampler { comparison: false }) => BindingKind::Sampler,
        (naga::AddressSpace::Handle, naga::TypeInner::Image { dim, arrayed, class }) => {
            let naga::ImageClass::Sampled { kind, multi: false } = class else {
                return Err(unsupported("only single-sampled, sampled textures have a stand-in"));
            };
            let sample_type = match kind {
                naga::ScalarKind::Float => wgpu::TextureSampleType::Float { filterable: sampled.contains(&handle) },
                naga::ScalarKind::Sint => wgpu::TextureSampleType::Sint,
                naga::ScalarKind::Uint => wgpu::TextureSampleType::Uint,
                _ => return Err(unsupported("a texture of bool samples")),
            };
            let dimension = match (dim, arrayed) {
                (naga::ImageDimension::D2, false) => wgpu::TextureViewDimension::D2,
                (naga::ImageDimension::D2, true) => wgpu::TextureViewDimension::D2Array,
                (naga::ImageDimension::D3, false) => wgpu::TextureViewDimension::D3,
                (naga::ImageDimension::Cube, false) => wgpu::TextureViewDimension::Cube,
                _ => return Err(unsupported("only 2D, 2D-array, 3D and cube textures have a stand-in")),
            };
            BindingKind::Texture { dimension, sample_type }
        }
        _ => return Err(unsupported("storage buffers, comparison samplers and binding arrays have no stand-in")),
    };
    Ok(Binding { name, group: rb.group, binding: rb.binding, kind })
}

/// The layout entry for one binding.
pub fn layout_entry(binding: &Binding) -> wgpu::BindGroupLayoutEntry {
    let ty = match binding.kind {
        BindingKind::Uniform { size } => wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: wgpu::BufferSize::new(u64::from(size)),
        },
        BindingKind::Texture { dimension, sample_type } => {
            wgpu::BindingType::Texture { sample_type, view_dimension: dimension, multisampled: false }
        }
        BindingKind::Sampler => wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
    };
    wgpu::BindGroupLayoutEntry {
        binding: binding.binding,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty,
        count: None,
    }
}

/// A 1×1 texture (six layers for a cube) filled with one texel, standing in for a texture the
/// scene does not provide. `value` is RGBA in the texture's sample type.
pub fn constant_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    dimension: wgpu::TextureViewDimension,
    sample_type: wgpu::TextureSampleType,
    value: [f32; 4],
) -> wgpu::TextureView {
    let (format, texel): (wgpu::TextureFormat, Vec<u8>) = match sample_type {
        wgpu::TextureSampleType::Sint => {
            (wgpu::TextureFormat::Rgba32Sint, value.iter().flat_map(|v| (*v as i32).to_le_bytes()).collect())
        }
        wgpu::TextureSampleType::Uint => {
            (wgpu::TextureFormat::Rgba32Uint, value.iter().flat_map(|v| (*v as u32).to_le_bytes()).collect())
        }
        // Rgba16Float is filterable without optional features (Rgba32Float is not).
        _ => (wgpu::TextureFormat::Rgba16Float, value.iter().flat_map(|v| f16_bits(*v).to_le_bytes()).collect()),
    };
    let (dim, layers) = match dimension {
        wgpu::TextureViewDimension::D3 => (wgpu::TextureDimension::D3, 1),
        wgpu::TextureViewDimension::Cube => (wgpu::TextureDimension::D2, 6),
        _ => (wgpu::TextureDimension::D2, 1),
    };
    let size = wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: layers };
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("stand-in texture"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: dim,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let data: Vec<u8> = (0..layers).flat_map(|_| texel.iter().copied()).collect();
    queue.write_texture(
        texture.as_image_copy(),
        &data,
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(texel.len() as u32), rows_per_image: Some(1) },
        size,
    );
    texture.create_view(&wgpu::TextureViewDescriptor { dimension: Some(dimension), ..Default::default() })
}

/// IEEE binary16 bits of `v` for the stand-in texels (0, 1 and similar exact values; rounding
/// toward zero is enough for them).
fn f16_bits(v: f32) -> u16 {
    let bits = v.to_bits();
    let sign = ((bits >> 16) & 0x8000) as u16;
    let exp = ((bits >> 23) & 0xff) as i32 - 127 + 15;
    if v == 0.0 || exp <= 0 {
        sign
    } else if exp >= 31 {
        sign | 0x7c00
    } else {
        sign | ((exp as u16) << 10) | ((bits >> 13) & 0x3ff) as u16
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn f16_bits_of_exact_values() {
        assert_eq!(f16_bits(0.0), 0x0000);
        assert_eq!(f16_bits(1.0), 0x3c00);
        assert_eq!(f16_bits(-2.0), 0xc000);
        assert_eq!(f16_bits(0.5), 0x3800);
    }

    #[test]
    fn discovers_the_sky_interface() {
        let wgsl = r#"
            struct B { a: vec4<f32>, b: f32 }
            @group(0) @binding(0) var<uniform> builtins: B;
            @group(1) @binding(2) var tex: texture_2d<f32>;
            @group(1) @binding(3) var samp: sampler;
            @group(2) @binding(0) var radiance: texture_cube<f32>;
            @fragment fn main() -> @location(0) vec4<f32> {
                return builtins.a + textureSample(tex, samp, vec2(0.0)) + textureSample(radiance, samp, vec3(1.0));
            }
        "#;
        let found = discover(wgsl).expect("parses");
        let summary: Vec<_> = found.iter().map(|b| (b.name.as_str(), b.group, b.binding, b.kind)).collect();
        let float = wgpu::TextureSampleType::Float { filterable: true };
        assert_eq!(
            summary,
            vec![
                ("builtins", 0, 0, BindingKind::Uniform { size: 32 }),
                ("tex", 1, 2, BindingKind::Texture { dimension: wgpu::TextureViewDimension::D2, sample_type: float }),
                ("samp", 1, 3, BindingKind::Sampler),
                (
                    "radiance",
                    2,
                    0,
                    BindingKind::Texture { dimension: wgpu::TextureViewDimension::Cube, sample_type: float }
                ),
            ]
        );
    }

    #[test]
    fn only_sampled_float_textures_are_filterable() {
        // `table` is only loaded; `clouds` is sampled two calls deep through arguments; `size`
        // is only measured; `direct` is sampled in the entry point itself.
        let wgsl = r#"
            @group(1) @binding(1) var table: texture_2d<f32>;
            @group(1) @binding(3) var clouds: texture_2d<f32>;
            @group(1) @binding(4) var clouds_sampler: sampler;
            @group(1) @binding(5) var size: texture_2d<f32>;
            @group(1) @binding(7) var direct: texture_2d<f32>;
            fn inner(t: texture_2d<f32>, s: sampler) -> vec4<f32> { return textureSample(t, s, vec2(0.5)); }
            fn outer(t: texture_2d<f32>, s: sampler) -> vec4<f32> { return inner(t, s); }
            fn load(t: texture_2d<f32>) -> vec4<f32> { return textureLoad(t, vec2(0, 0), 0); }
            @fragment fn main() -> @location(0) vec4<f32> {
                let d = vec2<f32>(textureDimensions(size));
                return load(table) + outer(clouds, clouds_sampler) + vec4(d, 0.0, 0.0)
                    + textureSample(direct, clouds_sampler, vec2(0.5));
            }
        "#;
        let found = discover(wgsl).expect("parses");
        let filterable = |name: &str| match found.iter().find(|b| b.name == name).map(|b| b.kind) {
            Some(BindingKind::Texture { sample_type: wgpu::TextureSampleType::Float { filterable }, .. }) => filterable,
            other => panic!("{name}: {other:?}"),
        };
        assert!(!filterable("table"));
        assert!(filterable("clouds"));
        assert!(!filterable("size"));
        assert!(filterable("direct"));
    }

    #[test]
    fn storage_buffers_are_refused_by_name() {
        let wgsl = "@group(1) @binding(1) var<storage, read> data: array<f32>;
                    @fragment fn main() -> @location(0) vec4<f32> { return vec4(data[0]); }";
        match discover(wgsl) {
            Err(BindingError::Unsupported { name, .. }) => assert_eq!(name, "data"),
            other => panic!("expected Unsupported, got {other:?}"),
        }
    }
}

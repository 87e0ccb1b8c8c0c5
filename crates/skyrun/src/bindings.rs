//! What a shader binds, read from its WGSL, and what the harness binds in its place.
//!
//! The harness does not trust a hand-written list of bindings: it parses the WGSL with naga and
//! reads every resource the module declares (group, binding, kind, size). That way the same
//! code renders gdsky's converted modules, whatever subset of the sky textures they declare, and
//! hand-written WGSL with the same interface (the bench's port). The layouts it builds are
//! explicit, so a binding the harness cannot provide is an error with its name, not a silently
//! different pipeline.

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
        /// Float (filterable), signed or unsigned integer.
        sample_type: wgpu::TextureSampleType,
    },
    /// A filtering sampler.
    Sampler,
}

/// Why the harness cannot bind a shader's resources.
#[derive(Clone, Debug, PartialEq)]
pub enum BindingError {
    /// The WGSL does not parse (naga's message).
    Parse(String),
    /// A resource the harness has no stand-in for (storage buffers, storage or depth textures,
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
                write!(f, "the harness cannot bind `{name}`: {what}")
            }
        }
    }
}

impl std::error::Error for BindingError {}

/// Every resource a WGSL module declares, sorted by group and binding.
pub fn discover(wgsl: &str) -> Result<Vec<Binding>, BindingError> {
    let module = naga::front::wgsl::parse_str(wgsl).map_err(|e| BindingError::Parse(e.emit_to_string(wgsl)))?;
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).map_err(|e| BindingError::Parse(e.to_string()))?;
    let mut found = Vec::new();
    for (_, var) in module.global_variables.iter() {
        let Some(rb) = &var.binding else { continue };
        let name = var.name.clone().unwrap_or_else(|| format!("group{}_binding{}", rb.group, rb.binding));
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
                    naga::ScalarKind::Float => wgpu::TextureSampleType::Float { filterable: true },
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
        found.push(Binding { name, group: rb.group, binding: rb.binding, kind });
    }
    found.sort_by_key(|b| (b.group, b.binding));
    Ok(found)
}

/// The layout entry for one binding.
pub(crate) fn layout_entry(binding: &Binding) -> wgpu::BindGroupLayoutEntry {
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
pub(crate) fn constant_texture(
    gpu: &crate::Gpu,
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
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
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
    gpu.queue.write_texture(
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
    fn storage_buffers_are_refused_by_name() {
        let wgsl = "@group(1) @binding(1) var<storage, read> data: array<f32>;
                    @fragment fn main() -> @location(0) vec4<f32> { return vec4(data[0]); }";
        match discover(wgsl) {
            Err(BindingError::Unsupported { name, .. }) => assert_eq!(name, "data"),
            other => panic!("expected Unsupported, got {other:?}"),
        }
    }
}

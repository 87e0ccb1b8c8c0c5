//! Material textures on the device: the wgpu format of each texel format, the sampler Godot's
//! hints ask for, the upload of a [`TextureData`] (with Godot's mip chain where asked), and the
//! check that a texture fits the binding a uniform's name leads to.

use skycore::{TexelFormat, TextureData, TextureError, TextureShape};

/// The wgpu format of a texel format.
pub fn wgpu_format(format: TexelFormat) -> wgpu::TextureFormat {
    match format {
        TexelFormat::Rgba32Float => wgpu::TextureFormat::Rgba32Float,
        TexelFormat::Rgba16Float => wgpu::TextureFormat::Rgba16Float,
        TexelFormat::Rgba8Unorm => wgpu::TextureFormat::Rgba8Unorm,
        TexelFormat::Rgba8UnormSrgb => wgpu::TextureFormat::Rgba8UnormSrgb,
    }
}

/// Checks that `data` can be given to the material texture `name` of a module with `bindings`
/// ([`crate::bindings::discover`]) and texture `slots` (name, group, binding: the reflection's
/// `bindings.textures`), without a device: what [`crate::Sky::set_texture`] checks, for a host
/// that wants to refuse a texture before it opens the GPU. Returns the texture's (group,
/// binding), or `None` when the module does not declare it (the shader never reads the uniform,
/// and the binding was pruned).
///
/// Errors: a name that is not a material texture (the message lists the shader's);
/// [`TexelFormat::Rgba32Float`] for a texture the shader samples with filtering (a texture it
/// reads only with `texelFetch` is declared non-filterable, see [`crate::bindings::discover`]);
/// a texture whose [`TextureShape`] is not the binding's (a 2D image for a `samplerCube`);
/// a binding that is no float 2D, cube or 3D texture (arrays and integer textures cannot be
/// given yet).
pub fn check_texture(
    bindings: &[crate::bindings::Binding],
    slots: &[(String, u32, u32)],
    name: &str,
    data: &TextureData,
) -> Result<Option<(u32, u32)>, TextureError> {
    let Some((_, group, binding)) = slots.iter().find(|(slot, ..)| slot == name) else {
        return Err(TextureError::UnknownName {
            name: name.to_string(),
            known: slots.iter().map(|(slot, ..)| slot.clone()).collect(),
        });
    };
    let key = (*group, *binding);
    let Some(binding) = bindings.iter().find(|b| (b.group, b.binding) == key) else {
        return Ok(None);
    };
    let unsupported = |what: &str| TextureError::Unsupported { name: name.to_string(), what: what.to_string() };
    let crate::bindings::BindingKind::Texture { dimension, sample_type } = binding.kind else {
        return Err(unsupported("its binding is not a texture"));
    };
    let expected = match dimension {
        wgpu::TextureViewDimension::D2 => TextureShape::D2,
        wgpu::TextureViewDimension::Cube => TextureShape::Cube,
        wgpu::TextureViewDimension::D3 => TextureShape::D3,
        _ => {
            return Err(unsupported(&format!(
                "a {dimension:?} texture; only 2D, cube and 3D textures (sampler2D, samplerCube, sampler3D) can be \
                 given so far"
            )));
        }
    };
    if data.shape() != expected {
        return Err(TextureError::WrongShape { name: name.to_string(), expected, given: data.shape() });
    }
    let wgpu::TextureSampleType::Float { filterable } = sample_type else {
        return Err(unsupported(
            "an integer texture (isampler2D, usampler2D); only float textures can be given so far",
        ));
    };
    if filterable && !data.format().filterable() {
        return Err(TextureError::NotFilterable { name: name.to_string() });
    }
    Ok(Some(key))
}

/// The sampler Godot's hints ask for (the reflection's `filter` and `repeat`): `nearest*`
/// filters take the nearest texel, the others interpolate; `*_mipmap*` filters blend the two
/// nearest mip levels, nearest texel or not, as Godot does with its project setting
/// `rendering/textures/default_filters/use_nearest_mipmap_filter` at its default (false);
/// the other filters read one level (the texture has only one: mipmaps are generated only
/// for a `*_mipmap*` hint, a `*_mipmap*` filter); anisotropy is not applied; `repeat` wraps in
/// u, v and w, otherwise clamps to the edge.
pub fn sampler(device: &wgpu::Device, filter: &str, repeat: bool) -> wgpu::Sampler {
    let nearest = filter.starts_with("nearest");
    let texel = if nearest { wgpu::FilterMode::Nearest } else { wgpu::FilterMode::Linear };
    let mip = if filter.contains("mipmap") { wgpu::MipmapFilterMode::Linear } else { wgpu::MipmapFilterMode::Nearest };
    let address = if repeat { wgpu::AddressMode::Repeat } else { wgpu::AddressMode::ClampToEdge };
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("material sampler"),
        address_mode_u: address,
        address_mode_v: address,
        address_mode_w: address,
        mag_filter: texel,
        min_filter: texel,
        mipmap_filter: mip,
        ..Default::default()
    })
}

/// Creates the GPU texture of `data` (a 2D texture, a six-layer 2D texture viewed as a cube, or
/// a 3D texture) with its mip chain when `mipmaps` ([`TextureData::mip_levels`]), and returns the view a
/// material binding takes. Validation errors surface through the caller's error scope.
pub fn upload(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    label: &str,
    data: &TextureData,
    mipmaps: bool,
) -> wgpu::TextureView {
    let levels = if mipmaps { data.mip_levels() } else { Vec::new() };
    let (dimension, view) = match data.shape() {
        TextureShape::D2 => (wgpu::TextureDimension::D2, wgpu::TextureViewDimension::D2),
        TextureShape::Cube => (wgpu::TextureDimension::D2, wgpu::TextureViewDimension::Cube),
        TextureShape::D3 => (wgpu::TextureDimension::D3, wgpu::TextureViewDimension::D3),
    };
    let size = wgpu::Extent3d { width: data.width(), height: data.height(), depth_or_array_layers: data.layers() };
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size,
        mip_level_count: 1 + levels.len() as u32,
        sample_count: 1,
        dimension,
        format: wgpu_format(data.format()),
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let bpt = data.format().bytes_per_texel();
    for (mip_level, level) in std::iter::once(data).chain(&levels).enumerate() {
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: mip_level as u32,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            level.bytes(),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(level.width() * bpt),
                rows_per_image: Some(level.height()),
            },
            wgpu::Extent3d { width: level.width(), height: level.height(), depth_or_array_layers: level.layers() },
        );
    }
    texture.create_view(&wgpu::TextureViewDescriptor { dimension: Some(view), ..Default::default() })
}

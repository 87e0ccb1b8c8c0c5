//! Material textures: the texels a host gives a shader's sampler uniforms (`uniform sampler2D
//! noise;`) in place of the 1×1 stand-ins.
//!
//! A texture is given by the uniform's name ([`crate::SkyShader::set_texture`]). The name is
//! mapped to the module's bindings through the reflection
//! ([`gdsky_naga::reflect::texture_bindings`]: group, binding, `source_color`, the sampler's
//! filter and repeat hints), never by guessing at WGSL global names, which an emitter may
//! rename. [`read_texture`] reads the files `gdsky render --texture NAME=PATH` names: OpenEXR
//! as 32-bit floats, PNG as 8-bit unorm (sRGB-decoded by the GPU when the uniform has
//! `source_color`).

use crate::imageio::{Image, decode_exr};
use std::fmt;
use std::io::Cursor;
use std::path::{Path, PathBuf};

/// Largest width or height of a material texture: wgpu's default `max_texture_dimension_2d`,
/// which [`crate::Gpu::new`] opens the device with.
pub const MAX_TEXTURE_SIDE: u32 = 8192;

/// Largest texture file [`read_texture`] reads: an uncompressed RGBA f32 OpenEXR of
/// [`MAX_TEXTURE_SIDE`]² (1 GiB) plus 64 MiB for headers and other channels. A larger file is
/// refused unread.
pub const MAX_TEXTURE_FILE_BYTES: u64 = (MAX_TEXTURE_SIDE as u64) * (MAX_TEXTURE_SIDE as u64) * 16 + (64 << 20);

/// The texel formats a material texture can have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TexelFormat {
    /// Four f32 per texel: exact data (look-up tables). Core WebGPU cannot filter it, so it
    /// binds only to a texture the shader reads with `texelFetch`, never samples.
    Rgba32Float,
    /// Four IEEE binary16 per texel; filterable.
    Rgba16Float,
    /// Four bytes per texel, read as byte / 255.
    Rgba8Unorm,
    /// Four bytes per texel, RGB sRGB-encoded: the GPU decodes them to linear when the shader
    /// reads them (alpha is linear), as Godot does for a `source_color` texture.
    Rgba8UnormSrgb,
}

impl TexelFormat {
    /// Bytes of one texel.
    pub fn bytes_per_texel(self) -> u32 {
        match self {
            TexelFormat::Rgba32Float => 16,
            TexelFormat::Rgba16Float => 8,
            TexelFormat::Rgba8Unorm | TexelFormat::Rgba8UnormSrgb => 4,
        }
    }

    /// Whether core WebGPU can sample it with a filtering sampler.
    pub fn filterable(self) -> bool {
        self != TexelFormat::Rgba32Float
    }

    /// The wgpu format.
    pub(crate) fn wgpu(self) -> wgpu::TextureFormat {
        match self {
            TexelFormat::Rgba32Float => wgpu::TextureFormat::Rgba32Float,
            TexelFormat::Rgba16Float => wgpu::TextureFormat::Rgba16Float,
            TexelFormat::Rgba8Unorm => wgpu::TextureFormat::Rgba8Unorm,
            TexelFormat::Rgba8UnormSrgb => wgpu::TextureFormat::Rgba8UnormSrgb,
        }
    }
}

/// A 2D texture's texels: `width × height` texels of `format`, row 0 first (the top of the
/// image file), little-endian.
#[derive(Clone, PartialEq)]
pub struct TextureData {
    width: u32,
    height: u32,
    format: TexelFormat,
    bytes: Vec<u8>,
}

impl fmt::Debug for TextureData {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "TextureData({}×{} {:?}, {} bytes)", self.width, self.height, self.format, self.bytes.len())
    }
}

impl TextureData {
    /// Wraps texel bytes, checking the size: each side 1 to [`MAX_TEXTURE_SIDE`], exactly
    /// `width × height × format.bytes_per_texel()` bytes.
    pub fn new(width: u32, height: u32, format: TexelFormat, bytes: Vec<u8>) -> Result<Self, TextureError> {
        if !(1..=MAX_TEXTURE_SIDE).contains(&width) || !(1..=MAX_TEXTURE_SIDE).contains(&height) {
            return Err(TextureError::Size { path: None, width, height });
        }
        let needed = u64::from(width) * u64::from(height) * u64::from(format.bytes_per_texel());
        if bytes.len() as u64 != needed {
            return Err(TextureError::Data { width, height, format, given: bytes.len() });
        }
        Ok(TextureData { width, height, format, bytes })
    }

    /// An f32 RGBA image as an [`TexelFormat::Rgba32Float`] texture, bit for bit.
    pub fn from_image(image: &Image) -> Result<Self, TextureError> {
        let bytes = image.pixels.iter().flat_map(|p| p.iter().flat_map(|c| c.to_le_bytes())).collect();
        Self::new(image.width, image.height, TexelFormat::Rgba32Float, bytes)
    }

    /// Width in texels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in texels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The texel format.
    pub fn format(&self) -> TexelFormat {
        self.format
    }

    /// The texel bytes, row 0 first.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }
}

/// Why a material texture could not be read or bound. Every message names the file or the
/// uniform.
#[derive(Debug)]
#[non_exhaustive]
pub enum TextureError {
    /// The file cannot be read: missing, not a regular file, over [`MAX_TEXTURE_FILE_BYTES`],
    /// permissions (the environment, not the input).
    Read {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file is not an OpenEXR or PNG image that decodes.
    Decode {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A side is 0 or over [`MAX_TEXTURE_SIDE`].
    Size {
        /// The file, when the texels came from one.
        path: Option<PathBuf>,
        /// Width in texels.
        width: u32,
        /// Height in texels.
        height: u32,
    },
    /// The bytes are not `width × height` texels of `format`.
    Data {
        /// Width in texels.
        width: u32,
        /// Height in texels.
        height: u32,
        /// The format.
        format: TexelFormat,
        /// Bytes given.
        given: usize,
    },
    /// The shader has no sampler uniform of that name.
    UnknownName {
        /// The name given.
        name: String,
        /// The shader's material textures (a sampler array's elements as `name_0`, …).
        known: Vec<String>,
    },
    /// A 32-bit float texture for a texture the shader samples (with filtering).
    NotFilterable {
        /// The uniform.
        name: String,
    },
    /// A texture the harness cannot take yet (3D, cube, array, integer).
    Unsupported {
        /// The uniform.
        name: String,
        /// What it is.
        what: String,
    },
    /// wgpu refused the texture.
    Wgpu(String),
}

impl TextureError {
    /// Whether the file could not be read (the environment: exit 2) rather than being wrong
    /// (the input: exit 1).
    pub fn is_read(&self) -> bool {
        matches!(self, TextureError::Read { .. })
    }
}

impl fmt::Display for TextureError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TextureError::Read { path, source } => write!(f, "cannot read texture {}: {source}", path.display()),
            TextureError::Decode { path, message } => write!(f, "texture {}: {message}", path.display()),
            TextureError::Size { path, width, height } => {
                if let Some(path) = path {
                    write!(f, "texture {}: ", path.display())?;
                }
                write!(f, "{width}×{height} texels; each side must be between 1 and {MAX_TEXTURE_SIDE}")
            }
            TextureError::Data { width, height, format, given } => write!(
                f,
                "a {width}×{height} {format:?} texture needs {} bytes, but {given} were given",
                u64::from(*width) * u64::from(*height) * u64::from(format.bytes_per_texel())
            ),
            TextureError::UnknownName { name, known } if known.is_empty() => {
                write!(f, "the shader has no sampler uniform `{name}` (it has no sampler uniforms)")
            }
            TextureError::UnknownName { name, known } => {
                write!(f, "the shader has no sampler uniform `{name}`; its sampler uniforms are: {}", known.join(", "))
            }
            TextureError::NotFilterable { name } => write!(
                f,
                "`{name}` is sampled with filtering (texture(), textureLod(), …), which a 32-bit float texture \
                 cannot be without an optional GPU feature: read it with texelFetch() in the shader, or give an \
                 8-bit (PNG) or 16-bit float texture"
            ),
            TextureError::Unsupported { name, what } => write!(f, "`{name}`: {what}"),
            TextureError::Wgpu(m) => write!(f, "creating the texture failed: {m}"),
        }
    }
}

impl std::error::Error for TextureError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            TextureError::Read { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// Reads a texture file, recognised by its first bytes:
///
/// * OpenEXR → [`TexelFormat::Rgba32Float`], every float as stored (half channels widened to
///   f32; alpha 1 when absent; [`crate::read_exr`]'s rules). `srgb` does not apply: the data
///   is already linear, as Godot treats float images.
/// * PNG → [`TexelFormat::Rgba8UnormSrgb`] when `srgb` (the uniform has `source_color`), else
///   [`TexelFormat::Rgba8Unorm`]. Grey is replicated to RGB, palettes and low bit depths are
///   expanded, 16-bit channels reduced to their high byte (as Godot imports them), alpha 255
///   when absent.
///
/// The file is read with [`crate::safe_io::read_limited`] (a regular file of at most
/// [`MAX_TEXTURE_FILE_BYTES`]); each side at most [`MAX_TEXTURE_SIDE`], checked from the header
/// before the texels are decoded.
pub fn read_texture(path: &Path, srgb: bool) -> Result<TextureData, TextureError> {
    let bytes = crate::safe_io::read_limited(path, MAX_TEXTURE_FILE_BYTES)
        .map_err(|source| TextureError::Read { path: path.to_owned(), source })?;
    let decode = |message: String| TextureError::Decode { path: path.to_owned(), message };
    let size = |width: u32, height: u32| TextureError::Size { path: Some(path.to_owned()), width, height };
    let fits = |side: u32| (1..=MAX_TEXTURE_SIDE).contains(&side);
    if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        // The header first: an oversized image is refused before its pixels are allocated.
        let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(&bytes), false)
            .map_err(|e| decode(format!("not a readable OpenEXR file: {e}")))?;
        if let Some(header) = meta.headers.first() {
            let (w, h) = (header.layer_size.width(), header.layer_size.height());
            let (w, h) = (u32::try_from(w).unwrap_or(u32::MAX), u32::try_from(h).unwrap_or(u32::MAX));
            if !fits(w) || !fits(h) {
                return Err(size(w, h));
            }
        }
        let image = decode_exr(path, &bytes).map_err(|e| decode(e.to_string()))?;
        return TextureData::from_image(&image).map_err(|_| size(image.width, image.height));
    }
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        let limit = MAX_TEXTURE_SIDE as usize * MAX_TEXTURE_SIDE as usize * 8;
        let mut decoder = png::Decoder::new_with_limits(Cursor::new(bytes), png::Limits { bytes: limit });
        decoder.set_transformations(png::Transformations::normalize_to_color8());
        let mut reader = decoder.read_info().map_err(|e| decode(format!("not a readable PNG: {e}")))?;
        let (w, h) = (reader.info().width, reader.info().height);
        if !fits(w) || !fits(h) {
            return Err(size(w, h));
        }
        let buffer_size = reader.output_buffer_size().ok_or_else(|| decode("the image is too large".into()))?;
        let mut buf = vec![0u8; buffer_size];
        let info = reader.next_frame(&mut buf).map_err(|e| decode(format!("not a readable PNG: {e}")))?;
        let channels = info.color_type.samples();
        let mut rgba = Vec::with_capacity(w as usize * h as usize * 4);
        for row in buf.chunks(info.line_size).take(h as usize) {
            for px in row.chunks_exact(channels).take(w as usize) {
                rgba.extend_from_slice(&match *px {
                    [l] => [l, l, l, 255],
                    [l, a] => [l, l, l, a],
                    [r, g, b] => [r, g, b, 255],
                    [r, g, b, a] => [r, g, b, a],
                    _ => return Err(decode(format!("{channels} channels per pixel"))),
                });
            }
        }
        let format = if srgb { TexelFormat::Rgba8UnormSrgb } else { TexelFormat::Rgba8Unorm };
        return TextureData::new(w, h, format, rgba).map_err(|e| decode(e.to_string()));
    }
    Err(decode("neither an OpenEXR nor a PNG file (its first bytes are neither signature)".into()))
}

/// Checks that a texture of `format` can be given to the material texture `name` of a module
/// with `bindings` ([`crate::bindings::discover`]) and `textures` (the reflection's,
/// [`gdsky_naga::reflect::texture_bindings`]), without a device: what
/// [`crate::SkyShader::set_texture`] checks, for a host that wants to refuse a texture before it
/// opens the GPU. Returns the texture's (group, binding), or `None` when the module does not
/// declare it (the shader never reads the uniform, and the binding was pruned).
///
/// Errors: a name that is not a material texture (the message lists the shader's);
/// [`TexelFormat::Rgba32Float`] for a texture the shader samples with filtering (a texture it
/// reads only with `texelFetch` is declared non-filterable, see [`crate::bindings::discover`]);
/// a binding that is not a float 2D texture (3D, cube, array and integer textures cannot be
/// given yet).
pub fn check_texture(
    bindings: &[crate::bindings::Binding],
    textures: &[gdsky_naga::reflect::TextureBinding],
    name: &str,
    format: TexelFormat,
) -> Result<Option<(u32, u32)>, TextureError> {
    let Some(slot) = textures.iter().find(|t| t.name == name) else {
        return Err(TextureError::UnknownName {
            name: name.to_string(),
            known: textures.iter().map(|t| t.name.clone()).collect(),
        });
    };
    let key = (slot.group, slot.binding);
    let Some(binding) = bindings.iter().find(|b| (b.group, b.binding) == key) else {
        return Ok(None);
    };
    let unsupported = |what: &str| TextureError::Unsupported { name: name.to_string(), what: what.to_string() };
    let crate::bindings::BindingKind::Texture { dimension, sample_type } = binding.kind else {
        return Err(unsupported("its binding is not a texture"));
    };
    if dimension != wgpu::TextureViewDimension::D2 {
        return Err(unsupported(&format!("a {dimension:?} texture; only 2D textures (sampler2D) can be given so far")));
    }
    let wgpu::TextureSampleType::Float { filterable } = sample_type else {
        return Err(unsupported(
            "an integer texture (isampler2D, usampler2D); only float textures can be given so far",
        ));
    };
    if filterable && !format.filterable() {
        return Err(TextureError::NotFilterable { name: name.to_string() });
    }
    Ok(Some(key))
}

/// The sampler Godot's hints ask for (the reflection's `filter` and `repeat`): `nearest*`
/// filters take the nearest texel, the others interpolate; `*_mipmap` picks the mipmap filter
/// (material textures have one level, so it changes nothing); anisotropy is not applied;
/// `repeat` wraps in u, v and w, otherwise clamps to the edge.
pub(crate) fn sampler(device: &wgpu::Device, filter: &str, repeat: bool) -> wgpu::Sampler {
    let nearest = filter.starts_with("nearest");
    let texel = if nearest { wgpu::FilterMode::Nearest } else { wgpu::FilterMode::Linear };
    let mip = if filter.starts_with("nearest_mipmap") || filter == "nearest" {
        wgpu::MipmapFilterMode::Nearest
    } else {
        wgpu::MipmapFilterMode::Linear
    };
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_byte_counts_are_checked() {
        assert!(TextureData::new(2, 1, TexelFormat::Rgba8Unorm, vec![0; 8]).is_ok());
        let err = TextureData::new(2, 1, TexelFormat::Rgba32Float, vec![0; 8]).unwrap_err().to_string();
        assert!(err.contains("needs 32 bytes, but 8 were given"), "{err}");
        assert!(TextureData::new(0, 1, TexelFormat::Rgba8Unorm, vec![]).is_err());
        assert!(TextureData::new(MAX_TEXTURE_SIDE + 1, 1, TexelFormat::Rgba8Unorm, vec![0; 32772]).is_err());
    }

    #[test]
    fn files_are_recognised_by_content() {
        let dir = tempfile::tempdir().expect("temp dir");
        let exr = dir.path().join("t.exr");
        let image = Image::new(2, 1, vec![[1e-7, 3.5, -2.0, 0.25], [12345.678, 0.0, 1.0, 1.0]]).expect("image");
        crate::write_exr(&exr, &image).expect("writes");
        let t = read_texture(&exr, true).expect("reads");
        assert_eq!((t.width(), t.height(), t.format()), (2, 1, TexelFormat::Rgba32Float));
        assert_eq!(&t.bytes()[..4], &1e-7f32.to_le_bytes());

        let png = dir.path().join("grey.png");
        let mut bytes = Vec::new();
        let mut encoder = png::Encoder::new(&mut bytes, 1, 1);
        encoder.set_color(png::ColorType::GrayscaleAlpha);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.write_header().and_then(|mut w| w.write_image_data(&[128, 7])).expect("encodes");
        std::fs::write(&png, &bytes).expect("writes");
        let t = read_texture(&png, true).expect("reads");
        assert_eq!((t.format(), t.bytes()), (TexelFormat::Rgba8UnormSrgb, &[128, 128, 128, 7][..]));
        assert_eq!(read_texture(&png, false).expect("reads").format(), TexelFormat::Rgba8Unorm);

        let text = dir.path().join("t.txt");
        std::fs::write(&text, "hello").expect("writes");
        let err = read_texture(&text, false).unwrap_err();
        assert!(!err.is_read() && err.to_string().contains("neither an OpenEXR nor a PNG"), "{err}");
        let err = read_texture(&dir.path().join("missing.exr"), false).unwrap_err();
        assert!(err.is_read() && err.to_string().contains("missing.exr"), "{err}");
    }
}

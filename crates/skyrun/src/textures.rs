//! Material textures: the texels a host gives a shader's sampler uniforms (`uniform sampler2D
//! noise;`) in place of the 1×1 stand-ins.
//!
//! A texture is given by the uniform's name ([`crate::SkyShader::set_texture`]). The name is
//! mapped to the module's bindings through the reflection
//! ([`gdsky_naga::reflect::texture_bindings`]: group, binding, `source_color`, the sampler's
//! filter and repeat hints), never by guessing at WGSL global names, which an emitter may
//! rename. [`read_texture`] reads the files `gdsky render --texture NAME=PATH` names: OpenEXR
//! as 32-bit floats, PNG as 8-bit unorm (sRGB-decoded by the GPU when the uniform has
//! `source_color`); [`read_cube`] and [`read_volume`] assemble cube maps and 3D textures from
//! several files or one image (textures/layout.rs), and a sampler whose filter hint asks for
//! mipmaps gets a full chain (textures/mipmap.rs, Godot's box filter).

mod layout;

pub use layout::{GODOT_VOLUME_GRID, MAX_ASSEMBLED_BYTES, read_cube, read_volume};

use crate::imageio::{Image, decode_exr};
pub use skycore::{MAX_TEXTURE_SIDE, MAX_VOLUME_SIDE, TexelFormat, TextureData, TextureError, TextureShape};
pub(crate) use skydraw::textures::{sampler, upload};

/// [`skydraw::textures::check_texture`] with the texture slots of a lowered module's
/// reflection ([`gdsky_naga::reflect::texture_bindings`]).
pub fn check_texture(
    bindings: &[crate::bindings::Binding],
    textures: &[gdsky_naga::reflect::TextureBinding],
    name: &str,
    data: &TextureData,
) -> Result<Option<(u32, u32)>, TextureError> {
    let slots: Vec<(String, u32, u32)> = textures.iter().map(|t| (t.name.clone(), t.group, t.binding)).collect();
    skydraw::textures::check_texture(bindings, &slots, name, data)
}
use std::io::Cursor;
use std::path::Path;

/// Largest texture file [`read_texture`] reads: an uncompressed RGBA f32 OpenEXR of
/// [`MAX_TEXTURE_SIDE`]² (1 GiB) plus 64 MiB for headers and other channels. A larger file is
/// refused unread.
pub const MAX_TEXTURE_FILE_BYTES: u64 = (MAX_TEXTURE_SIDE as u64) * (MAX_TEXTURE_SIDE as u64) * 16 + (64 << 20);

/// An f32 RGBA image as a [`TexelFormat::Rgba32Float`] texture, bit for bit.
pub fn texture_from_image(image: &Image) -> Result<TextureData, TextureError> {
    let bytes = image.pixels.iter().flat_map(|p| p.iter().flat_map(|c| c.to_le_bytes())).collect();
    TextureData::new(image.width, image.height, TexelFormat::Rgba32Float, bytes)
}

/// The texel bytes a texture file will decode to, from its header alone (the first MiB of the
/// file): PNG 4 bytes a texel, OpenEXR 8 (half RGBA) or 16 (float). `None` when the header does
/// not tell (not a regular file, not PNG or OpenEXR, a header past the first MiB): the full read
/// then refuses what it must. Used to refuse a stack of cube faces or volume slices before any
/// of them is decoded.
pub fn decoded_bytes(path: &Path) -> Option<u64> {
    use std::io::Read;
    if !std::fs::metadata(path).ok()?.is_file() {
        return None;
    }
    let mut head = Vec::new();
    std::fs::File::open(path).ok()?.take(1 << 20).read_to_end(&mut head).ok()?;
    if head.starts_with(b"\x89PNG\r\n\x1a\n") && head.len() >= 24 && &head[12..16] == b"IHDR" {
        let side = |at: usize| u64::from(u32::from_be_bytes([head[at], head[at + 1], head[at + 2], head[at + 3]]));
        return Some(side(16) * side(20) * 4);
    }
    if head.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(&head), false).ok()?;
        let header = meta.headers.first()?;
        let half = ["R", "G", "B", "A"].iter().all(|name| {
            header
                .channels
                .list
                .iter()
                .find(|c| c.name.eq(name))
                .is_none_or(|c| c.sample_type == exr::meta::attribute::SampleType::F16)
        });
        let texels = header.layer_size.width() as u64 * header.layer_size.height() as u64;
        return Some(texels * if half { 8 } else { 16 });
    }
    None
}

/// Reads a texture file, recognised by its first bytes:
///
/// * OpenEXR → [`TexelFormat::Rgba32Float`], every float as stored (alpha 1 when absent;
///   [`crate::read_exr`]'s rules); an image whose R, G, B (and A) channels are all half floats
///   → [`TexelFormat::Rgba16Float`], bit for bit, as Godot's loader makes such a file an RGBAH
///   image: filterable, so a sampled texture (an HDR cube map) can take it. `srgb` does not
///   apply: the data is already linear, as Godot treats float images.
/// * PNG → [`TexelFormat::Rgba8UnormSrgb`] when `srgb` (the uniform has `source_color`), else
///   [`TexelFormat::Rgba8Unorm`]. Grey is replicated to RGB, palettes and low bit depths are
///   expanded, 16-bit channels reduced to their high byte (as Godot imports them), alpha 255
///   when absent.
///
/// The file is read with [`skycore::io::read_limited`] (a regular file of at most
/// [`MAX_TEXTURE_FILE_BYTES`]); each side at most [`MAX_TEXTURE_SIDE`], checked from the header
/// before the texels are decoded.
pub fn read_texture(path: &Path, srgb: bool) -> Result<TextureData, TextureError> {
    let bytes = skycore::io::read_limited(path, MAX_TEXTURE_FILE_BYTES)
        .map_err(|source| TextureError::Read { path: path.to_owned(), source })?;
    let decode = |message: String| TextureError::Decode { path: path.to_owned(), message };
    let size = |width: u32, height: u32| TextureError::Size { path: Some(path.to_owned()), width, height };
    let fits = |side: u32| (1..=MAX_TEXTURE_SIDE).contains(&side);
    if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        // The header first: an oversized image is refused before its pixels are allocated.
        let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(&bytes), false)
            .map_err(|e| decode(format!("not a readable OpenEXR file: {e}")))?;
        let half = meta.headers.first().is_some_and(|header| {
            let list = &header.channels.list;
            ["R", "G", "B", "A"].iter().all(|name| {
                list.iter()
                    .find(|c| c.name.eq(name))
                    .is_none_or(|c| c.sample_type == exr::meta::attribute::SampleType::F16)
            })
        });
        if let Some(header) = meta.headers.first() {
            let (w, h) = (header.layer_size.width(), header.layer_size.height());
            let (w, h) = (u32::try_from(w).unwrap_or(u32::MAX), u32::try_from(h).unwrap_or(u32::MAX));
            if !fits(w) || !fits(h) {
                return Err(size(w, h));
            }
        }
        let image = decode_exr(path, &bytes).map_err(|e| decode(e.to_string()))?;
        if half {
            // Every value came from a half, so narrowing it back is exact.
            let bytes = image
                .pixels
                .iter()
                .flat_map(|p| p.iter().flat_map(|c| skycore::f32_to_f16(*c).to_le_bytes()))
                .collect();
            return TextureData::new(image.width, image.height, TexelFormat::Rgba16Float, bytes)
                .map_err(|_| size(image.width, image.height));
        }
        return texture_from_image(&image).map_err(|_| size(image.width, image.height));
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

        // All-half channels stay half, bit for bit.
        let half_path = dir.path().join("half.exr");
        let halves = [0.1f32, 2.5, -3.0, 60000.0];
        exr::prelude::write_rgba_file(&half_path, 2, 1, |x, _| {
            let v = |i: usize| exr::prelude::f16::from_f32(halves[(i + x) % 4]);
            (v(0), v(1), v(2), v(3))
        })
        .expect("writes a half EXR");
        let t = read_texture(&half_path, false).expect("reads");
        assert_eq!((t.width(), t.format()), (2, TexelFormat::Rgba16Float));
        let expected: Vec<u8> = (0..2)
            .flat_map(|x| (0..4).map(move |i| exr::prelude::f16::from_f32(halves[(i + x) % 4]).to_bits()))
            .flat_map(u16::to_le_bytes)
            .collect();
        assert_eq!(t.bytes(), &expected[..]);

        let text = dir.path().join("t.txt");
        std::fs::write(&text, "hello").expect("writes");
        let err = read_texture(&text, false).unwrap_err();
        assert!(!err.is_read() && err.to_string().contains("neither an OpenEXR nor a PNG"), "{err}");
        let err = read_texture(&dir.path().join("missing.exr"), false).unwrap_err();
        assert!(err.is_read() && err.to_string().contains("missing.exr"), "{err}");
    }
}

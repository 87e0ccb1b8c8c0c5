//! Image files: OpenEXR for exact f32 data, PNG previews and error heatmaps for people.
//!
//! Every writer encodes the whole file in memory first and then replaces the target in one
//! rename (see `skycore::io`), so a failed or interrupted write never leaves a truncated
//! file, or a file half old and half new, where a reference image used to be; the target must be
//! a regular file, absent, or a symbolic link to one.

use std::fmt;
use std::io::{self, Cursor};
use std::path::{Path, PathBuf};

use exr::meta::attribute::{AttributeValue, Text};
use exr::prelude::{
    Encoding, MetaData, ReadChannels, ReadLayers, ReadSpecificChannel, SampleType, SpecificChannels, Vec2,
    WritableImage,
};

/// An RGBA f32 image: `pixels[y * width + x]`, row 0 at the top, each row left to right (the
/// layout [`crate::render`] returns).
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height` pixels, row 0 at the top.
    pub pixels: Vec<[f32; 4]>,
}

impl Image {
    /// Wraps pixels, checking that there are exactly `width × height` of them and that the
    /// image is at least 1×1 (neither OpenEXR nor PNG can store an empty image).
    pub fn new(width: u32, height: u32, pixels: Vec<[f32; 4]>) -> Result<Self, ImageError> {
        let image = Self { width, height, pixels };
        image.check()?;
        Ok(image)
    }

    /// Same-sized views (`width × height` each, row 0 at the top) joined left to right: the
    /// six faces of a cubemap as one 6×1 strip, in the order given.
    pub fn side_by_side(views: Vec<Vec<[f32; 4]>>, width: u32, height: u32) -> Result<Self, ImageError> {
        let n = views.len();
        let (w, h) = (width as usize, height as usize);
        let mut pixels = vec![[0.0; 4]; n * w * h];
        for (i, view) in views.iter().enumerate() {
            if view.len() != w * h {
                return Err(ImageError::BadSize { width, height, pixels: view.len() });
            }
            for (y, row) in view.chunks_exact(w).enumerate() {
                let at = y * n * w + i * w;
                pixels[at..at + w].copy_from_slice(row);
            }
        }
        Image::new(width * n as u32, height, pixels)
    }

    /// The fields are public, so every writer checks again rather than trusting [`Image::new`].
    fn check(&self) -> Result<(), ImageError> {
        let expected = u64::from(self.width) * u64::from(self.height);
        if expected == 0 || expected != self.pixels.len() as u64 {
            return Err(ImageError::BadSize { width: self.width, height: self.height, pixels: self.pixels.len() });
        }
        Ok(())
    }
}

/// What went wrong reading or writing an image; every message names the file or the sizes
/// involved. `path` is always the file concerned.
#[derive(Debug)]
#[non_exhaustive]
#[allow(missing_docs)] // the fields are described in each variant's documentation
pub enum ImageError {
    /// The file system refused (missing directory, permissions, disk full…) while doing
    /// `action` (e.g. `"read"`); `source` is the operating system's error.
    Io { path: PathBuf, action: &'static str, source: io::Error },
    /// The exr crate could not `action` (`"decode"` or `"encode"`) the data.
    Exr { path: PathBuf, action: &'static str, source: exr::error::Error },
    /// An OpenEXR file this reader cannot use; `reason` says what is missing (a channel,
    /// pixels) or unsupported (integer samples, deep data…).
    Unreadable { path: PathBuf, reason: String },
    /// The PNG encoder failed.
    Png { path: PathBuf, source: png::EncodingError },
    /// An image of `width × height` with `pixels` pixels instead, or an empty image.
    BadSize { width: u32, height: u32, pixels: usize },
    /// Two images that `what` needs to match in size (width, height) do not.
    SizeMismatch { what: &'static str, first: (u32, u32), other: (u32, u32) },
    /// A parameter out of range (exposure, white point, an empty image list…).
    InvalidArgument(String),
}

impl fmt::Display for ImageError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Io { path, action, source } => write!(f, "could not {action} {}: {source}", path.display()),
            Self::Exr { path, action, source } => {
                write!(f, "could not {action} OpenEXR file {}: {source}", path.display())
            }
            Self::Unreadable { path, reason } => {
                write!(f, "cannot read OpenEXR file {}: {reason}", path.display())
            }
            Self::Png { path, source } => write!(f, "could not encode PNG {}: {source}", path.display()),
            Self::BadSize { width, height, pixels } => write!(
                f,
                "an image of {width}×{height} needs {} pixels (and at least 1), but {pixels} were given",
                u64::from(*width) * u64::from(*height)
            ),
            Self::SizeMismatch { what, first, other } => {
                write!(f, "{what}: {}×{} vs {}×{}", first.0, first.1, other.0, other.1)
            }
            Self::InvalidArgument(message) => f.write_str(message),
        }
    }
}

impl std::error::Error for ImageError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Io { source, .. } => Some(source),
            Self::Exr { source, .. } => Some(source),
            Self::Png { source, .. } => Some(source),
            _ => None,
        }
    }
}

fn io_error(path: &Path, action: &'static str, source: io::Error) -> ImageError {
    ImageError::Io { path: path.to_owned(), action, source }
}

/// Writes an encoded image with the one safe writer, [`skycore::io::write_atomically`]
/// (through symbolic links, never over a directory, device, FIFO or socket).
fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), ImageError> {
    skycore::io::write_atomically(path, bytes).map_err(|e| io_error(path, "write", e))
}

/// Writes `image` as OpenEXR: one layer, channels R, G, B, A as 32-bit floats, scanlines
/// stored top to bottom. OpenEXR's y axis points down (the data window's minimum y is the top
/// row), so row 0 of `image` is the top of the picture in every EXR viewer.
///
/// The file is replaced atomically: encoded in memory, written to a temporary file in the
/// same directory and renamed over `path`.
pub fn write_exr(path: &Path, image: &Image) -> Result<(), ImageError> {
    write_exr_annotated(path, image, &[])
}

/// [`write_exr`] with `notes` as text attributes of the file's header (`name → text`, what a
/// golden image records: the adapter that drew it, gdsky's version, its views); read them back
/// with [`read_exr_notes`]. OpenEXR's text attributes hold Latin-1: other characters are
/// written as `?`.
pub fn write_exr_annotated(path: &Path, image: &Image, notes: &[(&str, &str)]) -> Result<(), ImageError> {
    image.check()?;
    let width = image.width as usize;
    let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
        let [r, g, b, a] = image.pixels[y * width + x];
        (r, g, b, a)
    });
    // ZIP (16 scanlines per block) rather than uncompressed: lossless, so the floats come back
    // bit for bit; OpenEXR's own default, so every reader has it; and a 512×256 Freeman
    // panorama takes 0.99 MB instead of 2.1 MB. B44 and DWA are lossy, PIZ less widespread.
    let mut exr_image =
        exr::prelude::Image::from_encoded_channels((width, image.height as usize), Encoding::SMALL_LOSSLESS, channels);
    for (name, text) in notes {
        let latin1 = |t: &str| t.chars().map(|c| if u32::from(c) < 256 { c } else { '?' }).collect::<String>();
        // Names and texts are Latin-1 after the replacement, so `new_or_none` never refuses.
        if let (Some(name), Some(text)) = (Text::new_or_none(latin1(name)), Text::new_or_none(latin1(text))) {
            exr_image.attributes.other.insert(name, AttributeValue::Text(text));
        }
    }
    let mut bytes = Cursor::new(Vec::new());
    let encode_error = |source| ImageError::Exr { path: path.to_owned(), action: "encode", source };
    exr_image.write().to_buffered(&mut bytes).map_err(encode_error)?;
    write_atomically(path, bytes.get_ref())
}

/// Largest width or height of one rendered view, in pixels: the `max_texture_dimension_2d` of
/// wgpu's default limits, which [`crate::Gpu::new`] opens the device with (lavapipe offers
/// 16384, but the render target is created under the requested limits). `gdsky`'s `--size`,
/// `render`, `reference`, cubemap faces, `bench` and `oracle` all use it through
/// [`check_render_size`].
pub const MAX_RENDER_SIDE: u32 = 8192;

/// Most pixels of one rendered view, counting the width rounded up to a multiple of 16: the
/// read-back buffer holds 16 bytes a pixel in rows padded to 256 bytes, and must fit wgpu's
/// default `max_buffer_size`, 256 MiB. 2²⁴ = 16,777,216 pixels: 4096 × 4096, 8192 × 2048.
pub const MAX_RENDER_PIXELS: u64 = 1 << 24;

/// Checks a view size against what the renderer can do ([`MAX_RENDER_SIDE`],
/// [`MAX_RENDER_PIXELS`]); the message names the limit that is exceeded.
pub fn check_render_size(width: u32, height: u32) -> Result<(), String> {
    if !(1..=MAX_RENDER_SIDE).contains(&width) || !(1..=MAX_RENDER_SIDE).contains(&height) {
        return Err(format!("{width}x{height}: each side must be between 1 and {MAX_RENDER_SIDE} pixels"));
    }
    let padded = u64::from(width.next_multiple_of(16)) * u64::from(height);
    if padded > MAX_RENDER_PIXELS {
        return Err(format!(
            "{width}x{height}: at most {MAX_RENDER_PIXELS} pixels (4096x4096, 8192x2048; the width counted rounded \
             up to a multiple of 16), the device's 256 MiB read-back limit"
        ));
    }
    Ok(())
}

/// Largest image [`read_exr`] accepts: 16384 × 8192 pixels (2 GiB as f32 RGBA), room for the
/// largest image gdsky writes (a cubemap strip of six [`MAX_RENDER_PIXELS`] faces). A header can
/// claim any size; checking before allocating keeps a corrupt file from exhausting memory.
pub const MAX_READ_PIXELS: usize = 1 << 27;
const _: () = assert!(6 * MAX_RENDER_PIXELS <= MAX_READ_PIXELS as u64);

/// Largest EXR file [`read_exr`] reads: an uncompressed RGBA f32 image of [`MAX_READ_PIXELS`]
/// (2 GiB) plus 64 MiB for headers, offset tables and other channels (2112 MiB in all). A larger
/// file is refused unread.
pub const MAX_EXR_BYTES: u64 = MAX_READ_PIXELS as u64 * 16 + (64 << 20);

/// Pixel storage while the exr crate decodes, with a record of which pixels arrived.
struct Pixels {
    width: usize,
    data: Vec<[f32; 4]>,
    written: Vec<bool>,
    count: usize,
}

/// Reads the first layer of an OpenEXR file: channels R, G and B are required, A is optional
/// (1 when absent); half and float samples are converted to f32. Row 0 is the top of the data
/// window. Scanline and tiled files with any standard compression are read; the largest level
/// of a mip map.
///
/// Anything else is an error naming the file and what is missing: deep data, integer or
/// subsampled colour channels, no R/G/B (the message lists the channels that are there),
/// images over 2²⁷ pixels. Truncated or corrupt files are errors too, never panics (a panic
/// inside the exr crate is caught and returned as an error). The file is read with
/// [`skycore::io::read_limited`]: a regular file (a FIFO, a device, a socket or a directory is
/// refused before it is opened) of at most [`MAX_EXR_BYTES`].
pub fn read_exr(path: &Path) -> Result<Image, ImageError> {
    let bytes = skycore::io::read_limited(path, MAX_EXR_BYTES).map_err(|e| io_error(path, "read", e))?;
    decode_exr(path, &bytes)
}

/// The text attributes of an OpenEXR file's header that are not OpenEXR's own (what
/// [`write_exr_annotated`] wrote), sorted by name; only the header is decoded. Read like
/// [`read_exr`] (bounded, a regular file).
pub fn read_exr_notes(path: &Path) -> Result<Vec<(String, String)>, ImageError> {
    let bytes = skycore::io::read_limited(path, MAX_EXR_BYTES).map_err(|e| io_error(path, "read", e))?;
    let exr_error = |source| ImageError::Exr { path: path.to_owned(), action: "decode", source };
    let meta = std::panic::catch_unwind(|| MetaData::read_from_buffered(Cursor::new(&bytes[..]), false))
        .map_err(|_| ImageError::Unreadable {
            path: path.to_owned(),
            reason: "the OpenEXR decoder panicked on its header; the file is probably corrupt".into(),
        })?
        .map_err(exr_error)?;
    let mut notes: Vec<(String, String)> = meta
        .headers
        .iter()
        .flat_map(|h| h.shared_attributes.other.iter().chain(h.own_attributes.other.iter()))
        .filter_map(|(name, value)| match value {
            AttributeValue::Text(text) => Some((name.to_string(), text.to_string())),
            _ => None,
        })
        .collect();
    notes.sort();
    notes.dedup();
    Ok(notes)
}

/// [`read_exr`] on bytes already in memory; `path` is only for messages.
pub(crate) fn decode_exr(path: &Path, bytes: &[u8]) -> Result<Image, ImageError> {
    // The exr crate is not panic-free on corrupt data: fuzzing 1.74.2 makes its B44 decoder
    // overflow (`attempt to subtract with overflow`) on a few percent of mutated files. Such a
    // panic becomes an error here; the panic hook still prints its message to stderr.
    std::panic::catch_unwind(|| decode_exr_unguarded(path, bytes)).unwrap_or_else(|_| {
        Err(ImageError::Unreadable {
            path: path.to_owned(),
            reason: "the OpenEXR decoder panicked on its data; the file is probably corrupt".into(),
        })
    })
}

fn decode_exr_unguarded(path: &Path, bytes: &[u8]) -> Result<Image, ImageError> {
    let exr_error = |source| ImageError::Exr { path: path.to_owned(), action: "decode", source };
    let unreadable = |reason: String| ImageError::Unreadable { path: path.to_owned(), reason };

    // Check the header first, so that the messages say what is missing in our terms.
    let meta = MetaData::read_from_buffered(Cursor::new(bytes), false).map_err(exr_error)?;
    let header = meta.headers.first().ok_or_else(|| unreadable("the file has no layer".into()))?;
    if header.deep {
        return Err(unreadable("its first layer holds deep data; only flat images are read".into()));
    }
    let (width, height) = (header.layer_size.width(), header.layer_size.height());
    let too_large = width.checked_mul(height).is_none_or(|n| n > MAX_READ_PIXELS);
    if too_large || u32::try_from(width).is_err() || u32::try_from(height).is_err() {
        return Err(unreadable(format!(
            "its first layer is {width}×{height} pixels, more than the {MAX_READ_PIXELS} this reader accepts"
        )));
    }
    let list = &header.channels.list;
    for name in ["R", "G", "B", "A"] {
        match list.iter().find(|c| c.name.eq(name)) {
            None if name == "A" => {}
            None => {
                let present: Vec<String> = list.iter().map(|c| c.name.to_string()).collect();
                return Err(unreadable(format!(
                    "its first layer has no \"{name}\" channel (it has: {}); an RGB or RGBA image is needed",
                    present.join(", ")
                )));
            }
            Some(c) if c.sample_type == SampleType::U32 => {
                return Err(unreadable(format!(
                    "channel \"{name}\" holds 32-bit unsigned integers; only half and float channels are read"
                )));
            }
            Some(c) if c.sampling != Vec2(1, 1) => {
                return Err(unreadable(format!(
                    "channel \"{name}\" is subsampled ({}×{}); only full-resolution channels are read",
                    c.sampling.x(),
                    c.sampling.y()
                )));
            }
            Some(_) => {}
        }
    }

    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .specific_channels()
        .required("R")
        .required("G")
        .required("B")
        .optional("A", 1.0_f32)
        .collect_pixels(
            // All zero, so the allocations come from calloc and cost nothing until written: a
            // corrupt header claiming a large image fails on its missing blocks, not on memory.
            |size: Vec2<usize>, _| Pixels {
                width: size.width(),
                data: vec![[0.0; 4]; size.area()],
                written: vec![false; size.area()],
                count: 0,
            },
            |pixels: &mut Pixels, at: Vec2<usize>, (r, g, b, a): (f32, f32, f32, f32)| {
                // `get_mut`: a position outside the layer is dropped rather than a panic.
                let i = at.y() * pixels.width + at.x();
                if let (Some(p), Some(written)) = (pixels.data.get_mut(i), pixels.written.get_mut(i)) {
                    *p = [r, g, b, a];
                    pixels.count += usize::from(!std::mem::replace(written, true));
                }
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(exr_error)?;
    let layer = image.layer_data;
    let (width, height) = (layer.size.width(), layer.size.height());
    let pixels = layer.channel_data.pixels;
    // The exr crate's relaxed mode (the pedantic one also rejects harmless attribute quirks of
    // other writers) skips blocks its offset table does not reach; an image with holes is
    // worse than an error for a reference, so every pixel must have arrived.
    if pixels.count != pixels.data.len() {
        return Err(unreadable(format!(
            "only {} of its {} pixels are present (the file is truncated or corrupt)",
            pixels.count,
            pixels.data.len()
        )));
    }
    // The layer is the first header's (it has R, G and B), whose size was checked to fit u32.
    Image::new(width as u32, height as u32, pixels.data)
}

/// Default exposure for [`write_png_preview`]. In skyref's Freeman sky (default parameters,
/// sun elevations 2° to 60°) the zenith is 0.1–0.9 per channel, the sky near the horizon up
/// to ≈ 3, the 99th percentile of all channels below 3.3 and the sun disk up to ≈ 60. With
/// [`DEFAULT_WHITE`], 0.5 maps 0.05 → 47/255, 0.35 → 111, 1 → 167, 2.5 → 219, 10 → 254: the
/// zenith's blue sits in the mid tones, the horizon glow keeps its gradient instead of
/// clipping, and only the sun saturates to white. (An exposure of 1 would put a horizon of
/// 2.5 at 245 and flatten its gradient.)
pub const DEFAULT_EXPOSURE: f32 = 0.5;

/// Default white point for [`write_png_preview`]: no white balance (Bruneton's demo default
/// without `do_white_balance`), so the preview shows the colours the shader computes, e.g. a
/// blue zenith and a reddish low sun, rather than correcting them away.
pub const DEFAULT_WHITE: [f32; 3] = [1.0, 1.0, 1.0];

/// NaN in a preview or heatmap (no sky colour is pure magenta).
const MAGENTA: [u8; 3] = [255, 0, 255];
/// ±∞ in a preview: distinct from NaN, and from the saturated white that the formula's
/// limit (1 − e^−∞ = 1) would give, so an overflow is not mistaken for the sun.
const CYAN: [u8; 3] = [0, 255, 255];
/// The gap between side-by-side previews: neutral, visible against both sky and night.
const GAP: [u8; 3] = [128, 128, 128];
/// Gap between side-by-side previews, in pixels.
const GAP_PIXELS: u32 = 2;

fn check_tonemap(exposure: f32, white: [f32; 3]) -> Result<(), ImageError> {
    let ok = |v: f32| v.is_finite() && v > 0.0;
    if !ok(exposure) || !white.into_iter().all(ok) {
        return Err(ImageError::InvalidArgument(format!(
            "exposure ({exposure}) and white point ({white:?}) must be finite and positive"
        )));
    }
    Ok(())
}

/// Bruneton's demo tone map per channel, in f32 as on the GPU: negative radiance is shown as
/// 0 (the preview is for looking; the EXR and the heatmap keep the evidence).
pub(crate) fn tonemap(pixel: [f32; 4], exposure: f32, white: [f32; 3]) -> [u8; 3] {
    let rgb = [pixel[0], pixel[1], pixel[2]];
    if rgb.iter().any(|c| c.is_nan()) {
        return MAGENTA;
    }
    if rgb.iter().any(|c| c.is_infinite()) {
        return CYAN;
    }
    std::array::from_fn(|i| {
        let v = (1.0 - (-rgb[i].max(0.0) / white[i] * exposure).exp()).powf(1.0 / 2.2);
        (v.clamp(0.0, 1.0) * 255.0).round() as u8
    })
}

/// Encodes 8-bit RGB into PNG bytes. No colour chunks: untagged images are displayed as sRGB,
/// and the 1/2.2 power is close enough to sRGB for a preview.
fn encode_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<Vec<u8>, ImageError> {
    let png_error = |source| ImageError::Png { path: path.to_owned(), source };
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(png_error)?;
    writer.write_image_data(rgb).map_err(png_error)?;
    writer.finish().map_err(png_error)?;
    Ok(out)
}

/// Writes an 8-bit RGB PNG preview of `image` (alpha ignored, the PNG is opaque), tone mapped
/// as in Bruneton's demo: `pow(1 − exp(−L / white · exposure), 1/2.2)` per channel, scaled to
/// 0–255 and rounded. Negative values show as 0, a pixel with a NaN channel as magenta
/// (255, 0, 255), one with an infinite channel (and no NaN) as cyan (0, 255, 255).
/// [`DEFAULT_EXPOSURE`] and [`DEFAULT_WHITE`] suit the Freeman sky. Replaced atomically.
pub fn write_png_preview(path: &Path, image: &Image, exposure: f32, white: [f32; 3]) -> Result<(), ImageError> {
    write_side_by_side_png(path, &[image], exposure, white)
}

/// Writes `image`'s [`write_png_preview`] with `overlay` over it: a pixel whose entry is
/// `Some(colour)` is drawn in that colour, the others are the preview at a third of its
/// brightness, so the marked pixels stand out against the sky they belong to
/// (`gdsky render --trace-nonfinite` marks where each NaN or infinity first appeared).
/// `overlay` has one entry per pixel, row 0 at the top. Replaced atomically.
pub fn write_overlay_png(path: &Path, image: &Image, overlay: &[Option<[u8; 3]>]) -> Result<(), ImageError> {
    image.check()?;
    if overlay.len() != image.pixels.len() {
        return Err(ImageError::BadSize { width: image.width, height: image.height, pixels: overlay.len() });
    }
    let mut rgb = Vec::with_capacity(image.pixels.len() * 3);
    for (pixel, mark) in image.pixels.iter().zip(overlay) {
        let c = mark.unwrap_or_else(|| tonemap(*pixel, DEFAULT_EXPOSURE, DEFAULT_WHITE).map(|v| v / 3));
        rgb.extend_from_slice(&c);
    }
    write_atomically(path, &encode_png(path, image.width, image.height, &rgb)?)
}

/// Writes the [`write_png_preview`] previews of `images` next to each other, left to right,
/// separated by 2-pixel grey (128) gaps, e.g. "gdsky vs reference" for the docs. All images
/// must have the same height; at least one is needed. Replaced atomically.
pub fn write_side_by_side_png(
    path: &Path,
    images: &[&Image],
    exposure: f32,
    white: [f32; 3],
) -> Result<(), ImageError> {
    check_tonemap(exposure, white)?;
    let Some(first) = images.first() else {
        return Err(ImageError::InvalidArgument("a side-by-side PNG needs at least one image".into()));
    };
    let mut total_width = 0_u64;
    for image in images {
        image.check()?;
        if image.height != first.height {
            return Err(ImageError::SizeMismatch {
                what: "side-by-side images need the same height",
                first: (first.width, first.height),
                other: (image.width, image.height),
            });
        }
        total_width += u64::from(image.width) + u64::from(GAP_PIXELS);
    }
    let total_width = total_width - u64::from(GAP_PIXELS);
    let Ok(total_width) = u32::try_from(total_width) else {
        return Err(ImageError::InvalidArgument(format!("a side-by-side PNG {total_width} pixels wide is too wide")));
    };

    let (row_len, height) = (total_width as usize * 3, first.height as usize);
    let mut rgb: Vec<u8> = GAP.repeat(total_width as usize * height);
    let mut x0 = 0;
    for image in images {
        let width = image.width as usize;
        for (y, row) in image.pixels.chunks_exact(width).enumerate() {
            let out = &mut rgb[y * row_len + x0 * 3..][..width * 3];
            for (dst, &pixel) in out.chunks_exact_mut(3).zip(row) {
                dst.copy_from_slice(&tonemap(pixel, exposure, white));
            }
        }
        x0 += width + GAP_PIXELS as usize;
    }
    write_atomically(path, &encode_png(path, total_width, first.height, &rgb)?)
}

/// Viridis (matplotlib), 9 evenly spaced stops from 0 to 1; perceptually uniform and
/// readable in grey and by colour-blind viewers, and it contains no magenta.
const VIRIDIS: [[u8; 3]; 9] = [
    [0x44, 0x01, 0x54],
    [0x47, 0x2c, 0x7a],
    [0x3b, 0x51, 0x8b],
    [0x2c, 0x71, 0x8e],
    [0x21, 0x90, 0x8d],
    [0x27, 0xad, 0x81],
    [0x5c, 0xc8, 0x63],
    [0xaa, 0xdc, 0x32],
    [0xfd, 0xe7, 0x25],
];

fn viridis(t: f64) -> [u8; 3] {
    let t = if t >= 0.0 { t.min(1.0) } else { 0.0 }; // also maps NaN to 0
    let scaled = t * (VIRIDIS.len() - 1) as f64;
    let i = (scaled as usize).min(VIRIDIS.len() - 2);
    let frac = scaled - i as f64;
    std::array::from_fn(|c| {
        let (lo, hi) = (f64::from(VIRIDIS[i][c]), f64::from(VIRIDIS[i + 1][c]));
        (lo + (hi - lo) * frac).round() as u8
    })
}

/// Relative error of one pixel as in [`crate::compare`]: the largest over RGB of
/// |a − b| / max(|b|, floor), in f64; `None` when either pixel has a NaN or ±∞ channel.
/// A zero denominator (floor ≤ 0 and b = 0) gives 0 for equal values and ∞ otherwise.
fn pixel_rel(a: [f32; 4], b: [f32; 4], floor: f32) -> Option<f64> {
    let mut worst = 0.0_f64;
    for c in 0..3 {
        if !a[c].is_finite() || !b[c].is_finite() {
            return None;
        }
        let diff = (f64::from(a[c]) - f64::from(b[c])).abs();
        let denominator = f64::from(b[c]).abs().max(f64::from(floor));
        let rel = if diff == 0.0 {
            0.0
        } else if denominator > 0.0 {
            diff / denominator
        } else {
            f64::INFINITY
        };
        worst = worst.max(rel);
    }
    Some(worst)
}

/// Writes a heatmap PNG of the relative error of `a` against the reference `b`: per pixel the
/// largest over RGB of |a − b| / max(|b|, floor) (the definition [`crate::compare`] uses).
///
/// Scale: viridis on log₁₀ of the error, from 1e-7 (dark purple, also exact equality) through
/// 1e-3.5 (teal) to 1 and above (yellow), i.e. `t = (log10(rel) + 7) / 7` clamped to [0, 1].
/// A pixel with NaN or ±∞ in any RGB channel of either image is magenta. The images must have
/// the same size. Replaced atomically.
pub fn write_heatmap_png(path: &Path, a: &Image, b: &Image, floor: f32) -> Result<(), ImageError> {
    a.check()?;
    b.check()?;
    if (a.width, a.height) != (b.width, b.height) {
        return Err(ImageError::SizeMismatch {
            what: "a heatmap needs two images of the same size",
            first: (a.width, a.height),
            other: (b.width, b.height),
        });
    }
    let rgb: Vec<u8> = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .flat_map(|(&pa, &pb)| match pixel_rel(pa, pb, floor) {
            None => MAGENTA,
            Some(rel) => viridis((rel.log10() + 7.0) / 7.0),
        })
        .collect();
    write_atomically(path, &encode_png(path, a.width, a.height, &rgb)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use exr::prelude::f16;
    use std::fs;

    #[test]
    fn views_side_by_side_keep_their_rows() {
        let view = |v: f32| vec![[v, 0.0, 0.0, 1.0], [v, 1.0, 0.0, 1.0], [v, 0.0, 1.0, 1.0], [v, 1.0, 1.0, 1.0]];
        let strip = Image::side_by_side(vec![view(0.0), view(1.0), view(2.0)], 2, 2).expect("same sizes");
        assert_eq!((strip.width, strip.height), (6, 2));
        let red: Vec<f32> = strip.pixels.iter().map(|p| p[0]).collect();
        assert_eq!(red, [0.0, 0.0, 1.0, 1.0, 2.0, 2.0, 0.0, 0.0, 1.0, 1.0, 2.0, 2.0]);
        assert_eq!(strip.pixels[7], [0.0, 1.0, 1.0, 1.0], "row 1 of the first view");
        assert!(Image::side_by_side(vec![view(0.0), vec![[0.0; 4]; 3]], 2, 2).is_err(), "a short view");
    }

    /// The names in `dir`, sorted.
    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<_> = fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        names.sort();
        names.into_iter().map(|n| n.to_string_lossy().into_owned()).collect()
    }

    /// Awkward values (subnormal, huge, negative, −0, NaN, ±∞); (0, 0) and the last pixel marked.
    fn test_image(width: u32, height: u32) -> Image {
        let specials = [1e-40, 1e-30, 3.0e38, -2.5, -0.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 0.1];
        let mut pixels: Vec<[f32; 4]> = (0..width * height)
            .map(|i| [specials[i as usize % 9], i as f32 * 0.37, -(i as f32) - 0.5, 1.0 / (i as f32 + 3.0)])
            .collect();
        *pixels.last_mut().unwrap() = [-5.0, -6.0, -7.0, -8.0];
        pixels[0] = [1.0, 2.0, 3.0, 4.0]; // after the last: a 1×1 image keeps the top-left mark
        Image::new(width, height, pixels).unwrap()
    }

    fn bits(image: &Image) -> Vec<[u32; 4]> {
        image.pixels.iter().map(|p| p.map(f32::to_bits)).collect()
    }

    /// Decodes an 8-bit RGB PNG: (width, height, pixels row 0 first).
    fn decode_png(path: &Path) -> (u32, u32, Vec<[u8; 3]>) {
        let mut reader = png::Decoder::new(io::BufReader::new(fs::File::open(path).unwrap())).read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.color_type, info.bit_depth), (png::ColorType::Rgb, png::BitDepth::Eight));
        let rgb = buf[..info.buffer_size()].chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        (info.width, info.height, rgb)
    }

    #[test]
    fn render_size_limits_are_the_devices() {
        let limits = wgpu::Limits::default();
        assert_eq!(MAX_RENDER_SIDE, limits.max_texture_dimension_2d);
        assert_eq!(MAX_RENDER_PIXELS * 16, limits.max_buffer_size);
        for (w, h) in [(1, 1), (8192, 2048), (4096, 4096), (8191, 2048), (256, 128)] {
            assert!(check_render_size(w, h).is_ok(), "{w}x{h}");
        }
        for (w, h) in [(0, 4), (4, 0), (8193, 1), (1, 8193), (8192, 2049), (4097, 4095), (8192, 8192)] {
            assert!(check_render_size(w, h).is_err(), "{w}x{h}");
        }
    }

    #[test]
    fn new_checks_length() {
        assert!(Image::new(3, 2, vec![[0.0; 4]; 6]).is_ok());
        let err = Image::new(3, 2, vec![[0.0; 4]; 5]).unwrap_err();
        assert!(matches!(err, ImageError::BadSize { width: 3, height: 2, pixels: 5 }), "{err}");
        assert!(err.to_string().contains("needs 6 pixels"), "{err}");
        assert!(Image::new(0, 0, vec![]).is_err());
    }

    #[test]
    fn exr_round_trip_is_bit_exact_with_row_0_on_top() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("sky.exr");
        for (width, height) in [(130, 40), (7, 3), (3, 7), (1, 1)] {
            let image = test_image(width, height);
            write_exr(&path, &image).unwrap(); // also replaces the previous, larger file
            assert_eq!(bits(&read_exr(&path).unwrap()), bits(&image), "{width}×{height}");
            // Row order checked with the exr crate's own reader rather than ours: OpenEXR's
            // position (0, 0) is the top-left of the data window and must hold our (0, 0).
            let exr = exr::prelude::read_first_rgba_layer_from_file(
                &path,
                |size, _| vec![[0.0_f32; 4]; size.area()],
                move |px: &mut Vec<[f32; 4]>, at: Vec2<usize>, (r, g, b, a): (f32, f32, f32, f32)| {
                    px[at.y() * width as usize + at.x()] = [r, g, b, a];
                },
            )
            .unwrap();
            let px = &exr.layer_data.channel_data.pixels;
            assert_eq!(px[0], [1.0, 2.0, 3.0, 4.0]);
            assert_eq!(*px.last().unwrap(), if width > 1 { [-5.0, -6.0, -7.0, -8.0] } else { px[0] });
        }
        assert_eq!(entries(dir.path()), ["sky.exr"], "no temporary files left");
    }

    #[test]
    fn f16_rgb_exr_is_converted_and_alpha_defaults_to_1() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("half.exr");
        let values = [0.5, 1024.0, -3.0, 6.1035156e-5, 65504.0, 0.0];
        let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
            let v = values[y * 3 + x];
            (f16::from_f32(v), f16::from_f32(-v), f16::from_f32(v * 0.25))
        });
        exr::prelude::Image::from_channels((3, 2), channels).write().to_file(&path).unwrap();
        let image = read_exr(&path).unwrap();
        assert_eq!((image.width, image.height), (3, 2));
        let expected: Vec<[f32; 4]> = values.iter().map(|&v| [v, -v, v * 0.25, 1.0]).collect();
        assert_eq!(image.pixels, expected);

        let channels = SpecificChannels::build().with_channel("Y").with_pixel_fn(|_| (0.5_f32,));
        exr::prelude::Image::from_channels((4, 4), channels).write().to_file(&path).unwrap();
        let err = read_exr(&path).unwrap_err().to_string();
        assert!(err.contains("half.exr") && err.contains("no \"R\" channel (it has: Y)"), "{err}");
    }

    #[test]
    fn garbage_exr_input_errors_without_panicking() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.exr");
        write_exr(&path, &test_image(37, 45)).unwrap();
        let valid = fs::read(&path).unwrap();
        let read_file = |bytes: &[u8]| {
            fs::write(&path, bytes).unwrap();
            read_exr(&path)
        };
        assert!(read_file(&[]).is_err(), "empty file");
        assert!(read_file(&valid[..valid.len() / 2]).is_err(), "first half");
        assert!(read_file(b"not an exr at all").unwrap_err().to_string().contains("bad.exr"));
        assert!(read_exr(&dir.path().join("missing.exr")).unwrap_err().to_string().contains("missing.exr"));

        // The many variants in memory (rewriting a file thousands of times is slow).
        let read = |bytes: &[u8]| decode_exr(&path, bytes);
        for len in (0..1024).chain((1024..valid.len()).step_by(13)) {
            assert!(read(&valid[..len]).is_err(), "truncated at {len} of {} bytes", valid.len());
        }
        let mut state = 0x9e37_79b9_7f4a_7c15_u64; // xorshift: deterministic noise
        let mut random = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state as usize
        };
        for n in [1, 8, 100, 4096] {
            let noise: Vec<u8> = (0..n).map(|_| random() as u8).collect();
            assert!(read(&noise).is_err(), "{n} random bytes");
            assert!(read(&[&valid[..8], &noise[..]].concat()).is_err(), "magic + {n} random bytes");
        }
        // Corrupted copies may decode or not, but must not panic. A B44 file (half floats)
        // exercises the exr crate's B44 decoder, which panics on some corruptions.
        let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
            (f16::from_f32(x as f32), f16::ONE, f16::from_f32(y as f32))
        });
        let encoding = Encoding { compression: exr::prelude::Compression::B44, ..Encoding::SMALL_LOSSLESS };
        exr::prelude::Image::from_encoded_channels((37, 45), encoding, channels).write().to_file(&path).unwrap();
        let b44 = fs::read(&path).unwrap();
        assert!(read(&b44).is_ok());
        for i in 0..1000 {
            let mut bytes = if i % 4 == 3 { b44.clone() } else { valid.clone() };
            // Half of them in the header and offset table, where a wrong byte does most harm.
            let at = random() % if i % 2 == 0 { 700 } else { bytes.len() };
            bytes[at] ^= (random() as u8) | 1;
            if i % 3 == 0 {
                let next = (at + 1) % bytes.len();
                bytes[next] = random() as u8;
            }
            let _ = read(&bytes);
        }

        // A block never read: the last offset-table entry pointing at the block before. The exr
        // crate's relaxed reader accepts that; the pixel count must not (rows 32–44 missing).
        let mut bytes = valid.clone();
        let u64_at = |b: &[u8], at: usize| u64::from_le_bytes(b[at..at + 8].try_into().unwrap()) as usize;
        let chunks = MetaData::read_from_buffered(Cursor::new(&bytes), false).unwrap().headers[0].chunk_count;
        assert_eq!(chunks, 3, "45 rows in blocks of 16");
        // The table sits right before the first block, at which its first entry points.
        let table = (0..bytes.len() - 8).find(|&at| u64_at(&bytes, at) == at + 8 * chunks).unwrap();
        let before_last = u64_at(&bytes, table + 8);
        bytes[table + 16..][..8].copy_from_slice(&(before_last as u64).to_le_bytes());
        let err = read(&bytes).unwrap_err();
        assert!(err.to_string().contains("only 1184 of its 1665 pixels are present"), "{err}");
    }

    #[test]
    fn failed_writes_leave_no_files() {
        // Directory missing: the temporary file cannot even be created.
        let dir = tempfile::tempdir().unwrap();
        let image = test_image(4, 3);
        let err = write_exr(&dir.path().join("no-such-dir/sky.exr"), &image).unwrap_err();
        assert!(matches!(err, ImageError::Io { .. }), "{err}");
        assert!(err.to_string().contains("no-such-dir does not exist"), "{err}");
        assert!(write_png_preview(&dir.path().join("no-such-dir/sky.png"), &image, 1.0, DEFAULT_WHITE).is_err());
        assert!(write_heatmap_png(&dir.path().join("no-such-dir/sky.png"), &image, &image, 1e-4).is_err());
        assert_eq!(entries(dir.path()), Vec::<String>::new(), "no stray temporary files");

        // Target is a non-empty directory: refused before anything is written.
        let target = dir.path().join("sky.exr");
        fs::create_dir(&target).unwrap();
        fs::write(target.join("keep"), b"x").unwrap();
        assert!(write_exr(&target, &image).is_err());
        assert!(write_png_preview(&target, &image, 1.0, DEFAULT_WHITE).is_err());
        assert_eq!(entries(dir.path()), ["sky.exr"]);
        assert!(target.join("keep").exists());
    }

    #[test]
    fn overlay_marks_pixels_over_a_dimmed_preview() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("overlay.png");
        let image = Image::new(2, 1, vec![[4.0, 4.0, 4.0, 7.0], [4.0, 4.0, 4.0, 0.0]]).unwrap();
        write_overlay_png(&path, &image, &[Some([1, 2, 3]), None]).unwrap();
        let (width, height, png) = decode_png(&path);
        assert_eq!((width, height), (2, 1));
        let full = tonemap(image.pixels[1], DEFAULT_EXPOSURE, DEFAULT_WHITE);
        assert_eq!(png, [[1, 2, 3], full.map(|v| v / 3)]);
        assert!(full[0] > 30, "the preview is bright enough for the dimming to show: {full:?}");
        // One entry per pixel, or nothing is written.
        let other = dir.path().join("short.png");
        assert!(matches!(write_overlay_png(&other, &image, &[None]), Err(ImageError::BadSize { .. })));
        assert!(!other.exists());
    }

    #[test]
    fn png_preview_has_the_tonemapped_values() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("preview.png");
        let mut pixels = vec![[0.0, 0.0, 0.0, 0.0]; 6];
        pixels[5] = [1.0, 0.25, 4.0, 0.0]; // (2, 1); alpha 0 must not matter
        pixels[1] = [f32::NAN, 1.0, 1.0, 1.0];
        pixels[2] = [1.0, f32::NEG_INFINITY, 1.0, 1.0];
        pixels[3] = [-3.0, 2.0, 1e30, 1.0];
        write_png_preview(&path, &Image::new(3, 2, pixels).unwrap(), 0.5, [1.0, 1.0, 1.0]).unwrap();
        let (width, height, png) = decode_png(&path);
        assert_eq!((width, height), (3, 2));

        // By hand, in f64: round(255 · (1 − e^(−L / white · exposure))^(1/2.2)).
        let expected = |l: f64, exposure: f64, white: f64| {
            ((1.0 - (-l / white * exposure).exp()).powf(1.0 / 2.2) * 255.0).round() as u8
        };
        // 1 → 0.65444 → 166.88, 0.25 → 0.37783 → 96.35, 4 → 0.93604 → 238.69.
        assert_eq!(png[5], [167, 96, 239]);
        assert_eq!(png[5], [expected(1.0, 0.5, 1.0), expected(0.25, 0.5, 1.0), expected(4.0, 0.5, 1.0)]);
        assert_eq!(png[..4], [[0, 0, 0], MAGENTA, CYAN, [0, expected(2.0, 0.5, 1.0), 255]]);

        // Exposure and white point enter as L / white · exposure: 2 / 2 · 1 → 207.01.
        let image = Image::new(1, 1, vec![[2.0, 2.0, 2.0, 1.0]]).unwrap();
        write_png_preview(&path, &image, 1.0, [2.0, 1.0, 4.0]).unwrap();
        let rgb = decode_png(&path).2[0];
        assert_eq!(rgb, [207, expected(2.0, 1.0, 1.0), expected(2.0, 1.0, 4.0)]);
        assert!(matches!(write_png_preview(&path, &image, 0.0, DEFAULT_WHITE), Err(ImageError::InvalidArgument(_))));
        assert!(write_png_preview(&path, &image, 1.0, [1.0, f32::NAN, 1.0]).is_err());
        assert_eq!(entries(dir.path()), ["preview.png"]);
    }

    #[test]
    fn heatmap_colours_follow_the_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("heat.png");
        let reference = Image::new(4, 1, vec![[1.0, 2.0, 3.0, 1.0]; 4]).unwrap();
        let mut test = reference.clone();
        test.pixels[1][1] = 2.0 * (1.0 + 1e-4); // rel 1e-4: t = 3/7
        test.pixels[2][2] = 30.0; // rel 9: clamped to t = 1
        test.pixels[3][0] = f32::NAN;
        write_heatmap_png(&path, &test, &reference, 1e-4).unwrap();
        let (width, height, png) = decode_png(&path);
        assert_eq!((width, height), (4, 1));
        assert_eq!([png[0], png[2], png[3]], [VIRIDIS[0], VIRIDIS[8], MAGENTA]);
        let luma = |c: [u8; 3]| 0.3 * f64::from(c[0]) + 0.59 * f64::from(c[1]) + 0.11 * f64::from(c[2]);
        assert!(luma(png[0]) < luma(png[1]) && luma(png[1]) < luma(png[2]), "{png:?}");

        // Relative to the reference b, with the floor for small values.
        assert_eq!(pixel_rel([1.5, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], 1e-4), Some(0.5));
        assert_eq!(pixel_rel([1e-5, 0.0, 0.0, 0.0], [0.0; 4], 1e-4), Some(0.1));
        let small = Image::new(2, 2, vec![[0.0; 4]; 4]).unwrap();
        let err = write_heatmap_png(&path, &test, &small, 1e-4).unwrap_err();
        assert!(err.to_string().contains("4×1 vs 2×2"), "{err}");
    }

    #[test]
    fn side_by_side_places_previews_with_a_gap() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("side.png");
        let dark = Image::new(2, 2, vec![[0.0, 0.0, 0.0, 1.0]; 4]).unwrap();
        let bright = Image::new(3, 2, vec![[1e3, 1e3, 1e3, 1.0]; 6]).unwrap();
        write_side_by_side_png(&path, &[&dark, &bright], DEFAULT_EXPOSURE, DEFAULT_WHITE).unwrap();
        let (width, height, png) = decode_png(&path);
        assert_eq!((width, height), (2 + 2 + 3, 2));
        let (black, white) = ([0, 0, 0], [255, 255, 255]);
        for row in png.chunks_exact(7) {
            assert_eq!(row, [black, black, GAP, GAP, white, white, white]);
        }
        let short = Image::new(2, 1, vec![[0.0; 4]; 2]).unwrap();
        let err = write_side_by_side_png(&path, &[&dark, &short], 1.0, DEFAULT_WHITE).unwrap_err();
        assert!(matches!(err, ImageError::SizeMismatch { .. }), "{err}");
        assert!(write_side_by_side_png(&path, &[], 1.0, DEFAULT_WHITE).is_err());
    }
}

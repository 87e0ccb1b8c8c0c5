//! What a scene does not need shaded (issue #11): sky pixels hidden behind geometry, and
//! resolution the sky does not need.
//!
//! * [`Occluder`]: a coverage mask at the render's size (from a PNG, white = covered). The
//!   renderer uploads it into a depth buffer (depth 0.5 where covered, the far plane elsewhere)
//!   before the sky's full pass, whose vertex entry puts the sky on the far plane, so covered
//!   fragments fail the depth test before the fragment shader runs. Covered pixels keep the
//!   clear value [`OCCLUDED`] = (0, 0, 0, 1): opaque black, told apart from the sky, whose
//!   full-pass alpha is 0 as in Godot.
//! * [`SkyResolution`]: the whole pipeline (Godot's own sub-passes scaled with it) at W/2×H/2
//!   or W/4×H/4, then upsampled on the GPU ([`UpsampleFilter`]).

pub use skycore::SkyResolution;
use std::fmt;
use std::path::{Path, PathBuf};

/// The value a covered pixel holds: opaque black (the sky's full pass writes alpha 0).
pub const OCCLUDED: [f32; 4] = [0.0, 0.0, 0.0, 1.0];

/// The largest mask file read (a 16-megapixel RGBA16 PNG compresses to well under this).
pub const MAX_MASK_BYTES: u64 = 256 << 20;

/// How a reduced-resolution sky is upsampled to the target.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum UpsampleFilter {
    /// Bilinear between the 2×2 nearest shaded texels.
    #[default]
    Bilinear,
    /// Catmull–Rom bicubic over 4×4 texels, clamped to the 2×2 neighbours' range (no ringing
    /// around the sun disk, no negative radiance).
    CatmullRom,
}

impl UpsampleFilter {
    /// Texels either side of the sample point the filter reads (1 for 2×2, 2 for 4×4).
    pub fn reach(self) -> i64 {
        match self {
            UpsampleFilter::Bilinear => 1,
            UpsampleFilter::CatmullRom => 2,
        }
    }

    /// The format the reduced image is rendered into for this filter: Rgba16Float for
    /// bilinear (sampled through a linear sampler, which Rgba32Float does not allow without an
    /// optional feature; it rounds each value to 11 significant bits, a relative error
    /// ≤ 4.9e-4), Rgba32Float for Catmull–Rom (read texel by texel, every bit kept).
    pub(crate) fn reduced_format(self) -> wgpu::TextureFormat {
        match self {
            UpsampleFilter::Bilinear => wgpu::TextureFormat::Rgba16Float,
            UpsampleFilter::CatmullRom => wgpu::TextureFormat::Rgba32Float,
        }
    }

    /// Every filter's name, as [`UpsampleFilter::name`] gives it.
    pub const NAMES: [&'static str; 2] = ["bilinear", "catmull-rom"];

    /// `bilinear`, `catmull-rom`.
    pub fn name(self) -> &'static str {
        match self {
            UpsampleFilter::Bilinear => "bilinear",
            UpsampleFilter::CatmullRom => "catmull-rom",
        }
    }
}

impl std::str::FromStr for UpsampleFilter {
    type Err = String;

    /// `bilinear` or `catmull-rom`.
    fn from_str(name: &str) -> Result<Self, String> {
        [UpsampleFilter::Bilinear, UpsampleFilter::CatmullRom]
            .into_iter()
            .find(|f| f.name() == name)
            .ok_or_else(|| format!("`{name}` is no upsampling filter; expected one of: {}", Self::NAMES.join(", ")))
    }
}

/// What a render may skip. The default skips nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct RenderOptions<'a> {
    /// Pixels hidden behind geometry: not shaded, left at [`OCCLUDED`]. Its size must be the
    /// render's.
    pub occluder: Option<&'a Occluder>,
    /// The resolution the sky is shaded at.
    pub resolution: SkyResolution,
    /// How a reduced resolution is upsampled.
    pub filter: UpsampleFilter,
}

/// A coverage mask: which pixels of a render are hidden behind geometry.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Occluder {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row 0 at the top; true = covered.
    pub covered: Vec<bool>,
}

/// Why a mask could not be used.
#[derive(Debug)]
pub enum MaskError {
    /// The file could not be read (missing, not a regular file, over [`MAX_MASK_BYTES`]).
    Read(PathBuf, std::io::Error),
    /// The file is not a PNG that decodes.
    Decode(PathBuf, String),
    /// The PNG's header claims more pixels a side than the largest render (width, height).
    TooLarge(PathBuf, u32, u32),
}

impl MaskError {
    /// Whether the file was unreadable (the environment) rather than wrong (the input).
    pub fn is_read(&self) -> bool {
        matches!(self, MaskError::Read(..))
    }
}

impl fmt::Display for MaskError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MaskError::Read(p, e) => write!(f, "cannot read the occluder mask {}: {e}", p.display()),
            MaskError::Decode(p, e) => write!(f, "the occluder mask {} is not a readable PNG: {e}", p.display()),
            MaskError::TooLarge(p, w, h) => write!(
                f,
                "the occluder mask {} is {w}x{h}: at most {} pixels a side (the largest render), refused before decoding",
                p.display(),
                crate::MAX_RENDER_SIDE
            ),
        }
    }
}

impl std::error::Error for MaskError {}

impl Occluder {
    /// Nothing covered.
    pub fn none(width: u32, height: u32) -> Occluder {
        Occluder { width, height, covered: vec![false; width as usize * height as usize] }
    }

    /// The leftmost `fraction` of every row covered (rounded to whole columns): a coverage that
    /// leaves each row's mix of pixels the same, so the time saved follows the fraction.
    pub fn left_columns(width: u32, height: u32, fraction: f64) -> Occluder {
        let cut = (f64::from(width) * fraction.clamp(0.0, 1.0)).round() as u32;
        let covered = (0..height).flat_map(|_| (0..width).map(move |x| x < cut)).collect();
        Occluder { width, height, covered }
    }

    /// The fraction of pixels covered.
    pub fn coverage(&self) -> f64 {
        self.covered.iter().filter(|&&c| c).count() as f64 / self.covered.len().max(1) as f64
    }

    /// Reads a PNG mask (any colour type and bit depth) through the bounded reader
    /// ([`skycore::io::read_limited`], at most [`MAX_MASK_BYTES`]) and scales it to
    /// `width`×`height` with nearest-neighbour sampling (pixel centres). A pixel is covered when
    /// its grey level (the mean of R, G, B) is at least half of white and, with an alpha
    /// channel, its alpha is at least half.
    pub fn from_png(path: &Path, width: u32, height: u32) -> Result<Occluder, MaskError> {
        let bytes = skycore::io::read_limited(path, MAX_MASK_BYTES).map_err(|e| MaskError::Read(path.into(), e))?;
        let decode = |e: &dyn fmt::Display| MaskError::Decode(path.into(), e.to_string());
        let mut decoder = png::Decoder::new_with_limits(
            std::io::Cursor::new(bytes),
            png::Limits { bytes: crate::MAX_READ_PIXELS * 4 },
        );
        decoder.set_transformations(png::Transformations::normalize_to_color8());
        let mut reader = decoder.read_info().map_err(|e| decode(&e))?;
        // From the header, before the pixels are allocated: a mask is sampled at the render's
        // size, so one larger than the largest render is refused (a 510 KB PNG can claim
        // 65535², 4 GiB decoded).
        let (mw, mh) = (reader.info().width, reader.info().height);
        if mw > crate::MAX_RENDER_SIDE || mh > crate::MAX_RENDER_SIDE {
            return Err(MaskError::TooLarge(path.into(), mw, mh));
        }
        let size = reader.output_buffer_size().ok_or_else(|| decode(&"the image is too large"))?;
        let mut buf = vec![0u8; size];
        let info = reader.next_frame(&mut buf).map_err(|e| decode(&e))?;
        let (mw, mh) = (info.width, info.height);
        let channels = info.color_type.samples();
        let row = info.line_size;
        let covered_at = |x: u32, y: u32| -> bool {
            let at = y as usize * row + x as usize * channels;
            let px = &buf[at..at + channels];
            let (grey, alpha) = match channels {
                1 => (u32::from(px[0]), 255),
                2 => (u32::from(px[0]), px[1]),
                3 => ((u32::from(px[0]) + u32::from(px[1]) + u32::from(px[2])) / 3, 255),
                _ => ((u32::from(px[0]) + u32::from(px[1]) + u32::from(px[2])) / 3, px[3]),
            };
            grey >= 128 && alpha >= 128
        };
        let mut covered = Vec::with_capacity(width as usize * height as usize);
        for y in 0..height {
            let my = ((u64::from(y) * 2 + 1) * u64::from(mh) / (2 * u64::from(height))) as u32;
            for x in 0..width {
                let mx = ((u64::from(x) * 2 + 1) * u64::from(mw) / (2 * u64::from(width))) as u32;
                covered.push(covered_at(mx.min(mw - 1), my.min(mh - 1)));
            }
        }
        Ok(Occluder { width, height, covered })
    }

    /// The mask of the reduced-resolution render that feeds this one through `filter`: a
    /// shaded texel is skipped only when no visible target pixel reads it, so the upsampled
    /// visible pixels never see an unshaded texel. `wrap_x`: the filter wraps around
    /// horizontally (the panorama), else it clamps at the edges.
    pub fn reduced(&self, width: u32, height: u32, filter: UpsampleFilter, wrap_x: bool) -> Occluder {
        let mut needed = vec![false; width as usize * height as usize];
        let scale_x = f64::from(width) / f64::from(self.width);
        let scale_y = f64::from(height) / f64::from(self.height);
        let reach = filter.reach();
        let (w, h) = (i64::from(width), i64::from(height));
        for y in 0..self.height {
            let py = ((f64::from(y) + 0.5) * scale_y - 0.5).floor() as i64;
            for x in 0..self.width {
                if self.covered[(y * self.width + x) as usize] {
                    continue;
                }
                let px = ((f64::from(x) + 0.5) * scale_x - 0.5).floor() as i64;
                for ty in py + 1 - reach..=py + reach {
                    let ty = ty.clamp(0, h - 1);
                    for tx in px + 1 - reach..=px + reach {
                        let tx = if wrap_x { tx.rem_euclid(w) } else { tx.clamp(0, w - 1) };
                        needed[(ty * w + tx) as usize] = true;
                    }
                }
            }
        }
        Occluder { width, height, covered: needed.into_iter().map(|n| !n).collect() }
    }

    /// The mask as a Depth16Unorm image: `covered_depth` where covered, `far` elsewhere.
    pub(crate) fn depth_texels(&self, far: u16, covered_depth: u16) -> Vec<u8> {
        self.covered.iter().flat_map(|&c| if c { covered_depth } else { far }.to_le_bytes()).collect()
    }
}

/// The upsampling pass: a fullscreen triangle on the far plane (so the occluder's depth test
/// applies to it too).
///
/// * `fs_bilinear` reads the reduced image (Rgba16Float: filterable without optional features)
///   with one hardware-filtered `textureSampleLevel` per pixel. The sampler does the panorama's
///   wrap-around (address mode u = repeat, v = clamp; clamp both for other projections), so the
///   shader has no edge logic at all. On llvmpipe this is ~10× cheaper than four `textureLoad`s
///   with their clamps and a manual `mix`.
/// * `fs_catmull_rom` keeps the manual path: 16 `textureLoad`s from an Rgba32Float image (no
///   sampler reads it, so it needs no filterable format) and the 2×2 neighbours' clamp.
pub(crate) const UPSAMPLE_WGSL: &str = r#"
struct Params {
    src_size: vec2<f32>,
    dst_size: vec2<f32>,
    wrap_x: u32,
    far: f32,
    pad: vec2<f32>,
}
@group(0) @binding(0) var src: texture_2d<f32>;
@group(0) @binding(1) var<uniform> params: Params;
@group(0) @binding(2) var linear: sampler;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let x = f32((i << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(i & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, params.far, 1.0);
}

@fragment
fn fs_bilinear(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    // The sampler's texel position is uv · src_size − ½: the same point the manual filter used.
    return textureSampleLevel(src, linear, frag.xy / params.dst_size, 0.0);
}

fn texel(p: vec2<i32>) -> vec4<f32> {
    let size = vec2<i32>(params.src_size);
    // Offsets reach at most 2 texels past an edge: wrap with selects, not `%` (an integer
    // division, which llvmpipe scalarizes lane by lane: it made this pass cost 3× a cheap sky).
    var x = p.x;
    if params.wrap_x != 0u {
        x = select(x, x + size.x, x < 0);
        x = select(x, x - size.x, x >= size.x);
    }
    return textureLoad(src, vec2<i32>(clamp(x, 0, size.x - 1), clamp(p.y, 0, size.y - 1)), 0);
}

fn catmull_rom(t: f32) -> vec4<f32> {
    let t2 = t * t;
    let t3 = t2 * t;
    return vec4<f32>(
        -0.5 * t3 + t2 - 0.5 * t,
        1.5 * t3 - 2.5 * t2 + 1.0,
        -1.5 * t3 + 2.0 * t2 + 0.5 * t,
        0.5 * t3 - 0.5 * t2,
    );
}

@fragment
fn fs_catmull_rom(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    let p = frag.xy * params.src_size / params.dst_size - 0.5;
    let base = floor(p);
    let f = p - base;
    let i = vec2<i32>(base);
    let a = texel(i);
    let b = texel(i + vec2<i32>(1, 0));
    let c = texel(i + vec2<i32>(0, 1));
    let d = texel(i + vec2<i32>(1, 1));
    let wx = catmull_rom(f.x);
    let wy = catmull_rom(f.y);
    var sum = vec4<f32>(0.0);
    for (var row = 0; row < 4; row++) {
        var across = vec4<f32>(0.0);
        for (var col = 0; col < 4; col++) {
            across += wx[col] * texel(i + vec2<i32>(col - 1, row - 1));
        }
        sum += wy[row] * across;
    }
    return clamp(sum, min(min(a, b), min(c, d)), max(max(a, b), max(c, d)));
}
"#;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn upsample_shader_validates() {
        let module = naga::front::wgsl::parse_str(UPSAMPLE_WGSL)
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string(UPSAMPLE_WGSL)));
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::empty())
            .validate(&module)
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string(UPSAMPLE_WGSL)));
    }

    #[test]
    fn reduced_mask_keeps_every_texel_a_visible_pixel_reads() {
        // Left half covered at 16×4; at 8×2 bilinear, the texel column next to the edge stays.
        let full = Occluder::left_columns(16, 4, 0.5);
        assert_eq!(full.coverage(), 0.5);
        let half = full.reduced(8, 2, UpsampleFilter::Bilinear, false);
        let row: Vec<bool> = half.covered[..8].to_vec();
        assert_eq!(row, [true, true, true, false, false, false, false, false]);
        let cubic = full.reduced(8, 2, UpsampleFilter::CatmullRom, false);
        assert_eq!(&cubic.covered[..8], [true, true, false, false, false, false, false, false]);
        // Wrapping: the right edge's pixels read column 0.
        let wrapped = full.reduced(8, 2, UpsampleFilter::Bilinear, true);
        assert!(!wrapped.covered[0]);
        assert_eq!(SkyResolution::Quarter.shaded_size(1023, 5), (256, 2));
    }
}

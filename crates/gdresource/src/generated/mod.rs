//! # Godot's noise textures, generated as Godot generates them
//!
//! A material saved by Godot often carries a `NoiseTexture2D` (or `NoiseTexture3D`) instead of
//! an image file: a recipe, not texels. Godot 4.6 bakes it on the CPU when the resource loads
//! (modules/noise): for each texel (x, y) of a `width` × `height` image it asks its
//! `FastNoiseLite` resource for `get_noise_2d(x, y)`, or `get_noise_3d(x, y, 0)` when
//! `in_3d_space`, at integer coordinates. That wrapper adds `offset` to the coordinates, warps
//! them with a second FastNoiseLite instance when `domain_warp_enabled` (its own type,
//! amplitude, frequency and fractal settings, the same seed), and samples the first instance
//! (noise type, seed, frequency, fractal and cellular settings). Everything is f32 (`real_t` in
//! Godot's single-precision builds; FastNoiseLite's templates take the caller's type).
//!
//! The values become 8-bit luminance codes (an L8 image):
//! * `normalize` (the default): the minimum and maximum over the whole image map to 0 and 255,
//!   `⌊(v − min) / (max − min) · 255⌋` in f32 (0 everywhere when max = min);
//! * otherwise `⌊clamp(v · 127.5 + 127.5, 0, 255)⌋`;
//! * `invert` replaces a code c by 255 − c.
//!
//! `seamless` generates a larger image (a skirt of `seamless_blend_skirt` of each side, at least
//! one texel) and rearranges and blends it into a tileable one (src/noise/seamless.rs, all
//! integer work on the codes). A `color_ramp` then maps each code c to the gradient's colour at
//! the luminance of (c/255, c/255, c/255) (Godot's `Color::get_luminance`, f32) into an RGBA8
//! image, each channel truncated from `value · 255`. `as_normal_map` turns the image's red
//! channel (as f32 in 0…1) into an RGBA8 normal map: the normal of the height field from its
//! right and lower neighbours (wrapping), scaled by `bump_strength`, stored as
//! `⌊127.5 + n · 127.5⌋`.
//!
//! ## What is matched
//!
//! Every step above, in Godot's order of operations and types, with the `fastnoise-lite` crate
//! (the official Rust port of FastNoiseLite, 1.1.1) for the noise. Godot ships FastNoiseLite
//! 1.1.0 (thirdparty/misc/FastNoiseLite.h), which rounds one step of the 3D OpenSimplex2 domain
//! warp differently; that warp is computed here as 1.1.0 does (src/noise/warp3d.rs says why it
//! matters). Godot's seamless path normalizes over two slices even for a 2D texture, which
//! changes the codes in 3D space; that is matched too. `tests/godot/noise_oracle.rs` compares the
//! result texel for texel with the images real Godot 4.6 generates (through crates/skyoracle):
//! every one of its 88 configurations is identical, byte for byte (docs/noise.md).
//!
//! Bound as Godot binds them: with `generate_mipmaps` (on by default in Godot) a NoiseTexture2D
//! gets the mip levels [`NoiseImage::mipmaps`] makes as Godot does, sampled under any mipmap
//! filter (`TextureData::with_mipmaps`); a NoiseTexture3D ([`NoiseTexture3D::image`]) is bound
//! to a `sampler3D` (one level). A material's generated textures are read raw, also for a
//! `source_color` sampler, as Godot 4.6's Compatibility renderer reads them (docs/corpus.md).
//!
//! ## How a shader sees it
//!
//! [`NoiseTexture2D::generate`] gives an [`skycore::TexelFormat::Rgba8Unorm`] texture: an L8
//! code v becomes (v, v, v, 255), as Godot's renderers swizzle an L8 texture to (l, l, l, 1);
//! an RGBA8 image is taken as is. Whether the shader decodes sRGB (`source_color`) is the
//! binding's business, not the texture's.

mod gradient;
mod gradient_texture;
mod seamless;
mod warp3d;

pub use gradient::Gradient;
pub use gradient_texture::{
    Curve, CurvePoint, CurveTexture, CurveXyzTexture, GradientTexture1D, GradientTexture2D, RampFormat, RampImage,
    RampTexture,
};

use fastnoise_lite as fnl;
use gradient::Ramp;
use std::fmt;
use warp3d::Warp3d;

/// The largest side accepted for a noise texture: Godot's inspector suggests up to 2048 (and
/// allows more), and a texture over 4096² is more than a CPU bake should be asked for.
pub const MAX_SIDE: i64 = 4096;

/// Godot's `Image::MAX_PIXELS`, which `NoiseTexture3D` checks width × height × depth against.
const MAX_PIXELS_3D: usize = 1 << 28;

/// gdsky's budget for one generated noise texture: 2²⁵ texels (33,554,432: a 4096² image, a
/// 256×256×512 volume), checked before any noise is computed. Godot accepts 2²⁸ for a volume,
/// but a 2048×2048×64 one took gdsky 131 s and 3.2 GB to generate; sky shaders sample volumes
/// of 64³ to 256³.
pub const MAX_GENERATED_TEXELS: usize = 1 << 25;

/// Godot's `FastNoiseLite` resource: its properties by their Godot names, enum-valued ones as
/// Godot's enum numbers.
#[derive(Clone, Debug, PartialEq)]
pub struct FastNoiseLite {
    /// 0 simplex, 1 simplex smooth, 2 cellular, 3 perlin, 4 value cubic, 5 value.
    pub noise_type: i64,
    /// Godot stores it in a C++ `int`: a value outside the i32 range wraps as Godot's cast does.
    pub seed: i64,
    /// Sampling frequency (coordinates are multiplied by it).
    pub frequency: f64,
    /// Added to the texel coordinates before warping and sampling.
    pub offset: [f64; 3],
    /// 0 none, 1 FBM, 2 ridged, 3 ping-pong.
    pub fractal_type: i64,
    /// Octaves, 1 … 10 (Godot's inspector range).
    pub fractal_octaves: i64,
    /// Frequency multiplier between octaves.
    pub fractal_lacunarity: f64,
    /// Amplitude multiplier between octaves.
    pub fractal_gain: f64,
    /// How much an octave's weight depends on the previous octave's value.
    pub fractal_weighted_strength: f64,
    /// Strength of the ping-pong fractal.
    pub fractal_ping_pong_strength: f64,
    /// 0 Euclidean, 1 Euclidean squared, 2 Manhattan, 3 hybrid.
    pub cellular_distance_function: i64,
    /// How far a cell's point may move from its grid position.
    pub cellular_jitter: f64,
    /// 0 cell value, 1 distance, 2 distance2, 3 distance2 add, 4 sub, 5 mul, 6 div.
    pub cellular_return_type: i64,
    /// Whether a second FastNoiseLite warps the coordinates first.
    pub domain_warp_enabled: bool,
    /// 0 simplex, 1 simplex reduced, 2 basic grid.
    pub domain_warp_type: i64,
    /// Largest displacement of the warp.
    pub domain_warp_amplitude: f64,
    /// The warp's frequency.
    pub domain_warp_frequency: f64,
    /// 0 none, 1 progressive, 2 independent.
    pub domain_warp_fractal_type: i64,
    /// The warp's octaves, 1 … 10.
    pub domain_warp_fractal_octaves: i64,
    /// The warp's lacunarity.
    pub domain_warp_fractal_lacunarity: f64,
    /// The warp's gain.
    pub domain_warp_fractal_gain: f64,
}

impl Default for FastNoiseLite {
    /// Godot 4.6's defaults (modules/noise/fastnoise_lite.h): simplex smooth, seed 0, frequency
    /// 0.01, FBM with 5 octaves, Euclidean distance returning the distance, jitter 1, no warp
    /// (simplex, amplitude 30, frequency 0.05, progressive, 5 octaves, lacunarity 6, gain 0.5).
    fn default() -> Self {
        Self {
            noise_type: 1,
            seed: 0,
            frequency: 0.01,
            offset: [0.0; 3],
            fractal_type: 1,
            fractal_octaves: 5,
            fractal_lacunarity: 2.0,
            fractal_gain: 0.5,
            fractal_weighted_strength: 0.0,
            fractal_ping_pong_strength: 2.0,
            cellular_distance_function: 0,
            cellular_jitter: 1.0,
            cellular_return_type: 1,
            domain_warp_enabled: false,
            domain_warp_type: 0,
            domain_warp_amplitude: 30.0,
            domain_warp_frequency: 0.05,
            domain_warp_fractal_type: 1,
            domain_warp_fractal_octaves: 5,
            domain_warp_fractal_lacunarity: 6.0,
            domain_warp_fractal_gain: 0.5,
        }
    }
}

/// Godot's `NoiseTexture2D` resource: its properties by their Godot names.
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseTexture2D {
    /// Width in texels, 1 … [`MAX_SIDE`].
    pub width: i64,
    /// Height in texels, 1 … [`MAX_SIDE`].
    pub height: i64,
    /// Codes c become 255 − c.
    pub invert: bool,
    /// Sample `get_noise_3d(x, y, 0)` instead of `get_noise_2d(x, y)`.
    pub in_3d_space: bool,
    /// Godot adds mip levels ([`NoiseImage::mipmaps`]); gdsky binds them too.
    pub generate_mipmaps: bool,
    /// Make the image tile.
    pub seamless: bool,
    /// The blended overlap, as a fraction of each side, 0 … 1.
    pub seamless_blend_skirt: f64,
    /// Turn the image into a normal map.
    pub as_normal_map: bool,
    /// Height scale of the normal map.
    pub bump_strength: f64,
    /// Stretch the values to the full 0 … 255 range.
    pub normalize: bool,
    /// Map luminance through this gradient into RGBA.
    pub color_ramp: Option<Gradient>,
    /// The noise; without one Godot generates nothing.
    pub noise: Option<FastNoiseLite>,
}

impl Default for NoiseTexture2D {
    /// Godot 4.6's defaults (modules/noise/noise_texture_2d.h): 512 × 512, mipmaps, skirt 0.1,
    /// bump strength 8, normalized, no colour ramp and no noise.
    fn default() -> Self {
        Self {
            width: 512,
            height: 512,
            invert: false,
            in_3d_space: false,
            generate_mipmaps: true,
            seamless: false,
            seamless_blend_skirt: 0.1,
            as_normal_map: false,
            bump_strength: 8.0,
            normalize: true,
            color_ramp: None,
            noise: None,
        }
    }
}

/// Godot's `NoiseTexture3D` resource (bound to a `sampler3D` with one level).
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseTexture3D {
    /// Width in texels, 1 … [`MAX_SIDE`].
    pub width: i64,
    /// Height in texels, 1 … [`MAX_SIDE`].
    pub height: i64,
    /// Depth in slices, 1 … [`MAX_SIDE`].
    pub depth: i64,
    /// Codes c become 255 − c.
    pub invert: bool,
    /// Make the volume tile in all three directions.
    pub seamless: bool,
    /// The blended overlap, as a fraction of each side, 0 … 1.
    pub seamless_blend_skirt: f64,
    /// Stretch the values to the full 0 … 255 range (over the whole volume).
    pub normalize: bool,
    /// Map luminance through this gradient into RGBA.
    pub color_ramp: Option<Gradient>,
    /// The noise; without one Godot generates nothing.
    pub noise: Option<FastNoiseLite>,
}

impl Default for NoiseTexture3D {
    /// Godot 4.6's defaults (modules/noise/noise_texture_3d.h): 64³, skirt 0.1, normalized.
    fn default() -> Self {
        Self {
            width: 64,
            height: 64,
            depth: 64,
            invert: false,
            seamless: false,
            seamless_blend_skirt: 0.1,
            normalize: true,
            color_ramp: None,
            noise: None,
        }
    }
}

/// The pixel format of a generated image, as Godot's `Image` has it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoiseFormat {
    /// One luminance byte per texel (`Image.FORMAT_L8`).
    L8,
    /// Four bytes per texel (`Image.FORMAT_RGBA8`): with a colour ramp or as a normal map.
    Rgba8,
}

impl NoiseFormat {
    /// Bytes per texel.
    pub fn bytes_per_texel(self) -> usize {
        match self {
            Self::L8 => 1,
            Self::Rgba8 => 4,
        }
    }
}

/// A generated image in Godot's own format (level 0), row 0 first.
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseImage {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// L8 or RGBA8.
    pub format: NoiseFormat,
    /// `width × height × format.bytes_per_texel()` bytes.
    pub data: Vec<u8>,
}

impl NoiseImage {
    /// The texels as RGBA8: an L8 code v as (v, v, v, 255), what a shader samples.
    pub fn to_rgba8(&self) -> Vec<u8> {
        match self.format {
            NoiseFormat::L8 => self.data.iter().flat_map(|&v| [v, v, v, 255]).collect(),
            NoiseFormat::Rgba8 => self.data.clone(),
        }
    }
}

impl NoiseImage {
    /// The mip levels Godot's `Image::generate_mipmaps` adds below this image (level 1 first,
    /// down to 1 × 1; none for a 1 × 1 image): each texel of a level is
    /// `(a + b + c + d + 2) >> 2` of the 2 × 2 texels above it, per byte; an odd side drops its
    /// last row or column, and a side of 1 repeats its texel. skyrun cannot bind levels yet,
    /// so [`NoiseTexture2D::generate`] does not use them.
    pub fn mipmaps(&self) -> Vec<NoiseImage> {
        let channels = self.format.bytes_per_texel();
        let mut levels: Vec<NoiseImage> = Vec::new();
        let (mut w, mut h) = (self.width as usize, self.height as usize);
        while w > 1 || h > 1 {
            let src = levels.last().map_or(&self.data, |l| &l.data);
            let (dw, dh) = ((w / 2).max(1), (h / 2).max(1));
            let right = if w == 1 { 0 } else { channels };
            let down = if h == 1 { 0 } else { w * channels };
            let mut data = Vec::with_capacity(dw * dh * channels);
            for i in 0..dh {
                let up = i * 2 * down;
                for j in 0..dw {
                    let at = up + j * 2 * right;
                    for c in 0..channels {
                        let sum = [at, at + right, at + down, at + down + right]
                            .iter()
                            .map(|&k| u32::from(src[k + c]))
                            .sum::<u32>();
                        data.push(((sum + 2) >> 2) as u8);
                    }
                }
            }
            levels.push(NoiseImage { width: dw as u32, height: dh as u32, format: self.format, data });
            (w, h) = (dw, dh);
        }
        levels
    }
}

/// Why a noise texture could not be generated.
#[derive(Debug)]
pub enum NoiseError {
    /// `noise` is not set: Godot then generates no image at all.
    NoNoise,
    /// A property is outside what Godot (or gdsky) accepts.
    OutOfRange {
        /// The property's Godot name (`width`, `noise.fractal_octaves`, `color_ramp`).
        property: &'static str,
        /// What is wrong, with the value.
        message: String,
    },
    /// The generated texels did not make a texture (should not happen after the checks).
    Texture(skycore::TextureError),
}

impl fmt::Display for NoiseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::NoNoise => write!(f, "the noise texture has no `noise` resource, so Godot generates no image"),
            Self::OutOfRange { property, message } => write!(f, "noise texture property `{property}`: {message}"),
            Self::Texture(e) => write!(f, "the generated noise texture: {e}"),
        }
    }
}

impl std::error::Error for NoiseError {}

fn out_of_range(property: &'static str, message: String) -> NoiseError {
    NoiseError::OutOfRange { property, message }
}

fn side(property: &'static str, value: i64) -> Result<usize, NoiseError> {
    if (1..=MAX_SIDE).contains(&value) {
        Ok(value as usize)
    } else {
        Err(out_of_range(property, format!("{value} is outside 1 … {MAX_SIDE}")))
    }
}

fn finite(property: &'static str, value: f64) -> Result<f32, NoiseError> {
    if value.is_finite() {
        Ok(value as f32)
    } else {
        Err(out_of_range(property, format!("{value} is not a finite number")))
    }
}

fn choice<T: Copy>(property: &'static str, value: i64, options: &[T]) -> Result<T, NoiseError> {
    usize::try_from(value).ok().and_then(|i| options.get(i).copied()).ok_or_else(|| {
        out_of_range(property, format!("{value} is not one of Godot's values 0 … {}", options.len() - 1))
    })
}

fn octaves(property: &'static str, value: i64) -> Result<i32, NoiseError> {
    if (1..=10).contains(&value) {
        Ok(value as i32)
    } else {
        Err(out_of_range(property, format!("{value} is outside Godot's range 1 … 10")))
    }
}

fn skirt(value: f64) -> Result<f32, NoiseError> {
    // Godot's setter refuses values outside 0 … 1 (ERR_FAIL_COND) and keeps the old one.
    if (0.0..=1.0).contains(&value) {
        Ok(value as f32)
    } else {
        Err(out_of_range("seamless_blend_skirt", format!("{value} is outside 0 … 1")))
    }
}

/// The two FastNoiseLite instances of Godot's wrapper and its offset.
struct Sampler {
    noise: fnl::FastNoiseLite,
    warp: Option<fnl::FastNoiseLite>,
    /// The 3D warp of the OpenSimplex2 types, in Godot's FastNoiseLite 1.1.0 arithmetic
    /// ([`warp3d`]); `None` for the basic grid, whose 3D warp the crate computes as Godot does.
    warp_3d: Option<Warp3d>,
    offset: [f32; 3],
}

impl Sampler {
    /// Validates the properties and configures the instances as Godot's `FastNoiseLite`
    /// constructor and setters do (modules/noise/fastnoise_lite.cpp).
    fn new(p: &FastNoiseLite) -> Result<Self, NoiseError> {
        use fnl::{CellularDistanceFunction as D, CellularReturnType as R, DomainWarpType as W, FractalType as F};
        let noise_types = [
            fnl::NoiseType::OpenSimplex2,
            fnl::NoiseType::OpenSimplex2S,
            fnl::NoiseType::Cellular,
            fnl::NoiseType::Perlin,
            fnl::NoiseType::ValueCubic,
            fnl::NoiseType::Value,
        ];
        let mut noise = fnl::FastNoiseLite::new();
        noise.set_noise_type(Some(choice("noise.noise_type", p.noise_type, &noise_types)?));
        // Godot's `int seed` takes the low 32 bits of the 64-bit Variant.
        noise.set_seed(Some(p.seed as i32));
        noise.set_frequency(Some(finite("noise.frequency", p.frequency)?));
        noise.set_fractal_type(Some(choice(
            "noise.fractal_type",
            p.fractal_type,
            &[F::None, F::FBm, F::Ridged, F::PingPong],
        )?));
        noise.set_fractal_octaves(Some(octaves("noise.fractal_octaves", p.fractal_octaves)?));
        noise.set_fractal_lacunarity(Some(finite("noise.fractal_lacunarity", p.fractal_lacunarity)?));
        noise.set_fractal_gain(Some(finite("noise.fractal_gain", p.fractal_gain)?));
        noise.set_fractal_weighted_strength(Some(finite(
            "noise.fractal_weighted_strength",
            p.fractal_weighted_strength,
        )?));
        noise.set_fractal_ping_pong_strength(Some(finite(
            "noise.fractal_ping_pong_strength",
            p.fractal_ping_pong_strength,
        )?));
        noise.set_cellular_distance_function(Some(choice(
            "noise.cellular_distance_function",
            p.cellular_distance_function,
            &[D::Euclidean, D::EuclideanSq, D::Manhattan, D::Hybrid],
        )?));
        noise.set_cellular_return_type(Some(choice(
            "noise.cellular_return_type",
            p.cellular_return_type,
            &[
                R::CellValue,
                R::Distance,
                R::Distance2,
                R::Distance2Add,
                R::Distance2Sub,
                R::Distance2Mul,
                R::Distance2Div,
            ],
        )?));
        noise.set_cellular_jitter(Some(finite("noise.cellular_jitter", p.cellular_jitter)?));

        // Godot configures its warp instance whether or not warping is on; checking its
        // properties either way keeps a bad value from passing silently until it is enabled.
        let mut warp = fnl::FastNoiseLite::new();
        warp.set_domain_warp_type(Some(choice(
            "noise.domain_warp_type",
            p.domain_warp_type,
            &[W::OpenSimplex2, W::OpenSimplex2Reduced, W::BasicGrid],
        )?));
        warp.set_seed(Some(p.seed as i32));
        warp.set_domain_warp_amp(Some(finite("noise.domain_warp_amplitude", p.domain_warp_amplitude)?));
        warp.set_frequency(Some(finite("noise.domain_warp_frequency", p.domain_warp_frequency)?));
        warp.set_fractal_type(Some(choice(
            "noise.domain_warp_fractal_type",
            p.domain_warp_fractal_type,
            &[F::None, F::DomainWarpProgressive, F::DomainWarpIndependent],
        )?));
        warp.set_fractal_octaves(Some(octaves("noise.domain_warp_fractal_octaves", p.domain_warp_fractal_octaves)?));
        warp.set_fractal_lacunarity(Some(finite(
            "noise.domain_warp_fractal_lacunarity",
            p.domain_warp_fractal_lacunarity,
        )?));
        warp.set_fractal_gain(Some(finite("noise.domain_warp_fractal_gain", p.domain_warp_fractal_gain)?));

        let mut offset = [0.0f32; 3];
        for (o, v) in offset.iter_mut().zip(p.offset) {
            *o = finite("noise.offset", v)?;
        }
        let warp_3d = (p.domain_warp_enabled && warp.domain_warp_type != W::BasicGrid).then(|| Warp3d {
            seed: warp.seed,
            amplitude: warp.domain_warp_amp,
            frequency: warp.frequency,
            reduced: warp.domain_warp_type == W::OpenSimplex2Reduced,
            fractal: match warp.fractal_type {
                F::DomainWarpProgressive => warp3d::Fractal::Progressive,
                F::DomainWarpIndependent => warp3d::Fractal::Independent,
                _ => warp3d::Fractal::None,
            },
            octaves: warp.octaves,
            lacunarity: warp.lacunarity,
            gain: warp.gain,
        });
        Ok(Self { noise, warp: p.domain_warp_enabled.then_some(warp), warp_3d, offset })
    }

    /// `FastNoiseLite::get_noise_2d`.
    fn noise_2d(&self, x: f32, y: f32) -> f32 {
        let (mut x, mut y) = (x + self.offset[0], y + self.offset[1]);
        if let Some(warp) = &self.warp {
            (x, y) = warp.domain_warp_2d(x, y);
        }
        self.noise.get_noise_2d(x, y)
    }

    /// `FastNoiseLite::get_noise_3d`.
    fn noise_3d(&self, x: f32, y: f32, z: f32) -> f32 {
        let (mut x, mut y, mut z) = (x + self.offset[0], y + self.offset[1], z + self.offset[2]);
        if let Some(warp) = &self.warp_3d {
            [x, y, z] = warp.warp([x, y, z]);
        } else if let Some(warp) = &self.warp {
            (x, y, z) = warp.domain_warp_3d(x, y, z);
        }
        self.noise.get_noise_3d(x, y, z)
    }
}

/// `Noise::_get_image_internal`: `depth` slices of `width × height` L8 codes.
fn codes(
    sampler: &Sampler,
    (width, height, depth): (usize, usize, usize),
    invert: bool,
    in_3d_space: bool,
    normalize: bool,
) -> Vec<Vec<u8>> {
    let value = |x: usize, y: usize, d: usize| {
        if in_3d_space { sampler.noise_3d(x as f32, y as f32, d as f32) } else { sampler.noise_2d(x as f32, y as f32) }
    };
    let code = |c: u8| if invert { 255 - c } else { c };
    let slice_values = |d: usize| (0..height).flat_map(move |y| (0..width).map(move |x| value(x, y, d)));
    if normalize {
        let values: Vec<Vec<f32>> = (0..depth).map(|d| slice_values(d).collect()).collect();
        let (mut min, mut max) = (f32::MAX, -f32::MAX);
        for &v in values.iter().flatten() {
            // Godot's comparisons, in its order: a NaN never moves either bound.
            if v > max {
                max = v;
            }
            if v < min {
                min = v;
            }
        }
        values
            .iter()
            .map(|slice| {
                slice
                    .iter()
                    .map(|&v| {
                        let c = if max == min { 0 } else { ((v - min) / (max - min) * 255.0).clamp(0.0, 255.0) as u8 };
                        code(c)
                    })
                    .collect()
            })
            .collect()
    } else {
        (0..depth)
            .map(|d| slice_values(d).map(|v| code((v * 127.5 + 127.5).clamp(0.0, 255.0) as u8)).collect())
            .collect()
    }
}

/// `NoiseTexture2D::_modulate_with_gradient`: each code through the ramp into RGBA8.
fn modulate(codes: &[u8], ramp: &Ramp) -> Vec<u8> {
    codes
        .iter()
        .flat_map(|&c| {
            // `get_pixel` of L8 (c / 255.0, as f32) and `Color::get_luminance`, in f32.
            let l = (f64::from(c) / 255.0) as f32;
            let luminance = 0.2126f32 * l + 0.7152f32 * l + 0.0722f32 * l;
            // `set_pixel` of RGBA8: `uint8_t(CLAMP(v * 255.0, 0, 255))`, in f64, truncated.
            ramp.color_at(luminance).map(|v| (f64::from(v) * 255.0).clamp(0.0, 255.0) as u8)
        })
        .collect()
}

/// `Image::bump_map_to_normal_map` on the image's red channel.
fn normal_map(image: &NoiseImage, strength: f32) -> Vec<u8> {
    let (w, h) = (image.width as usize, image.height as usize);
    let step = image.format.bytes_per_texel();
    // `convert(FORMAT_RF)`: the red channel through `get_pixel` (byte / 255.0, as f32).
    let height_at = |x: usize, y: usize| (f64::from(image.data[(y * w + x) * step]) / 255.0) as f32;
    let mut out = Vec::with_capacity(w * h * 4);
    for ty in 0..h {
        let py = (ty + 1) % h;
        for tx in 0..w {
            let px = (tx + 1) % w;
            let here = height_at(tx, ty);
            let up_z = (here - height_at(tx, py)) * strength;
            let across_z = (height_at(px, ty) - here) * strength;
            // across × up with across = (1, 0, across_z), up = (0, 1, up_z): exactly
            // (−across_z, −up_z, 1) in Godot's `Vector3::cross`.
            let n = [-across_z, -up_z, 1.0f32];
            let length_squared = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
            let n = if length_squared == 0.0 {
                [0.0; 3]
            } else {
                let length = length_squared.sqrt();
                n.map(|c| c / length)
            };
            // `127.5 + n * 127.5` in f64, stored into a byte by truncation.
            out.extend(n.map(|c| (127.5 + f64::from(c) * 127.5) as u8));
            out.push(255);
        }
    }
    out
}

impl NoiseTexture2D {
    /// The image Godot generates (level 0), in Godot's format: L8, or RGBA8 with a colour ramp
    /// or as a normal map.
    pub fn image(&self) -> Result<NoiseImage, NoiseError> {
        let (width, height) = (side("width", self.width)?, side("height", self.height)?);
        let blend_skirt = skirt(self.seamless_blend_skirt)?;
        let bump = finite("bump_strength", self.bump_strength)?;
        let ramp = self
            .color_ramp
            .as_ref()
            .map(Ramp::new)
            .transpose()
            .map_err(|message| out_of_range("color_ramp", message))?;
        let sampler = Sampler::new(self.noise.as_ref().ok_or(NoiseError::NoNoise)?)?;

        let data = if self.seamless {
            let (sw, sh) = (seamless::skirt(width, blend_skirt), seamless::skirt(height, blend_skirt));
            // Godot's seamless path generates depth + max(1, depth · skirt) = 2 slices even for
            // a 2D texture, and normalizes over both. In 3D space the second slice (z = 1)
            // moves the minimum and maximum; in 2D space it repeats the first, so it is skipped.
            let depth = if self.in_3d_space { 2 } else { 1 };
            let src = codes(&sampler, (width + sw, height + sh, depth), self.invert, self.in_3d_space, self.normalize);
            seamless::slice(&src[0], width, height, blend_skirt)
        } else {
            codes(&sampler, (width, height, 1), self.invert, self.in_3d_space, self.normalize).remove(0)
        };
        let mut image = NoiseImage { width: width as u32, height: height as u32, format: NoiseFormat::L8, data };
        if let Some(ramp) = &ramp {
            image = NoiseImage { format: NoiseFormat::Rgba8, data: modulate(&image.data, ramp), ..image };
        }
        if self.as_normal_map {
            image = NoiseImage { format: NoiseFormat::Rgba8, data: normal_map(&image, bump), ..image };
        }
        Ok(image)
    }

    /// The texture a shader samples: [`Self::image`] as RGBA8 unorm (L8 codes v as
    /// (v, v, v, 255)), level 0 only.
    pub fn generate(&self) -> Result<skycore::TextureData, NoiseError> {
        let image = self.image()?;
        skycore::TextureData::new(image.width, image.height, skycore::TexelFormat::Rgba8Unorm, image.to_rgba8())
            .map_err(NoiseError::Texture)
    }
}

impl NoiseTexture3D {
    /// The slices Godot generates (`NoiseTexture3D::_generate_texture`), front to back, each in
    /// Godot's format (L8, or RGBA8 with a colour ramp).
    pub fn image(&self) -> Result<Vec<NoiseImage>, NoiseError> {
        let (width, height, depth) =
            (side("width", self.width)?, side("height", self.height)?, side("depth", self.depth)?);
        // Godot's 3D setter refuses a skirt under 0.05 (the 2D one allows 0).
        if !(0.05..=1.0).contains(&self.seamless_blend_skirt) {
            let message = format!("{} is outside 0.05 … 1", self.seamless_blend_skirt);
            return Err(out_of_range("seamless_blend_skirt", message));
        }
        let blend_skirt = self.seamless_blend_skirt as f32;
        if width * height * depth > MAX_PIXELS_3D {
            let message = format!("{width}×{height}×{depth} texels is over Godot's limit of {MAX_PIXELS_3D}");
            return Err(out_of_range("depth", message));
        }
        // Before any noise is computed: what the GPU cannot hold, and gdsky's work budget.
        let largest = skycore::MAX_VOLUME_SIDE as usize;
        if width.max(height).max(depth) > largest {
            let message = format!("{width}×{height}×{depth}: a 3D texture's sides are at most {largest} on the GPU");
            return Err(out_of_range("width", message));
        }
        if width * height * depth > MAX_GENERATED_TEXELS {
            let message = format!(
                "{width}×{height}×{depth} texels is over gdsky's budget of {MAX_GENERATED_TEXELS} generated texels \
                 (checked before generating; Godot's own limit is {MAX_PIXELS_3D})"
            );
            return Err(out_of_range("depth", message));
        }
        let ramp = self
            .color_ramp
            .as_ref()
            .map(Ramp::new)
            .transpose()
            .map_err(|message| out_of_range("color_ramp", message))?;
        let sampler = Sampler::new(self.noise.as_ref().ok_or(NoiseError::NoNoise)?)?;

        // Godot's 3D images always sample get_noise_3d(x, y, slice).
        let slices = if self.seamless {
            let skirts = [width, height, depth].map(|s| seamless::skirt(s, blend_skirt));
            let src = codes(
                &sampler,
                (width + skirts[0], height + skirts[1], depth + skirts[2]),
                self.invert,
                true,
                self.normalize,
            );
            let flat: Vec<Vec<u8>> = src.iter().map(|s| seamless::slice(s, width, height, blend_skirt)).collect();
            seamless::depth(flat, depth, blend_skirt)
        } else {
            codes(&sampler, (width, height, depth), self.invert, true, self.normalize)
        };
        Ok(slices
            .into_iter()
            .map(|data| {
                let image = NoiseImage { width: width as u32, height: height as u32, format: NoiseFormat::L8, data };
                match &ramp {
                    Some(ramp) => NoiseImage { format: NoiseFormat::Rgba8, data: modulate(&image.data, ramp), ..image },
                    None => image,
                }
            })
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture(width: i64, height: i64) -> NoiseTexture2D {
        NoiseTexture2D { width, height, noise: Some(FastNoiseLite::default()), ..NoiseTexture2D::default() }
    }

    #[test]
    fn normalized_images_span_the_codes() {
        let image = texture(32, 16).image().expect("generates");
        assert_eq!((image.width, image.height, image.format), (32, 16, NoiseFormat::L8));
        assert_eq!(image.data.iter().min(), Some(&0));
        assert_eq!(image.data.iter().max(), Some(&255));
        let inverted = NoiseTexture2D { invert: true, ..texture(32, 16) }.image().expect("generates");
        assert!(image.data.iter().zip(&inverted.data).all(|(a, b)| a + b == 255));
    }

    #[test]
    fn the_texture_is_rgba8_of_the_codes() {
        let t = texture(8, 4);
        let data = t.generate().expect("generates");
        let image = t.image().expect("generates");
        assert_eq!(data.format(), skycore::TexelFormat::Rgba8Unorm);
        assert_eq!(data.bytes()[..4], [image.data[0], image.data[0], image.data[0], 255]);
        let ramp = NoiseTexture2D { color_ramp: Some(Gradient::default()), ..t.clone() }.image().expect("generates");
        assert_eq!(ramp.format, NoiseFormat::Rgba8);
        let normal = NoiseTexture2D { as_normal_map: true, ..t }.image().expect("generates");
        assert_eq!((normal.format, normal.data.len()), (NoiseFormat::Rgba8, 8 * 4 * 4));
    }

    #[test]
    fn seamless_images_wrap_smoothly() {
        let t = NoiseTexture2D { seamless: true, ..texture(64, 64) };
        let image = t.image().expect("generates");
        // Across the wrap, neighbours differ no more than neighbours inside do.
        let at = |x: usize, y: usize| i32::from(image.data[y * 64 + x]);
        let wrap = (0..64).map(|y| (at(63, y) - at(0, y)).abs()).max();
        let inside = (0..64).map(|y| (at(31, y) - at(32, y)).abs()).max();
        assert!(wrap <= inside.map(|v| v + 8), "wrap {wrap:?}, inside {inside:?}");
    }

    #[test]
    fn out_of_range_values_are_refused_by_name() {
        let refused = |t: NoiseTexture2D, what: &str| {
            let e = t.image().expect_err(what).to_string();
            assert!(e.contains(what), "{e:?} does not name {what:?}");
        };
        refused(texture(0, 4), "`width`");
        refused(texture(4, MAX_SIDE + 1), "`height`");
        refused(NoiseTexture2D { seamless_blend_skirt: 1.5, ..texture(4, 4) }, "`seamless_blend_skirt`");
        refused(NoiseTexture2D { bump_strength: f64::NAN, ..texture(4, 4) }, "`bump_strength`");
        refused(NoiseTexture2D { noise: None, ..texture(4, 4) }, "no `noise`");
        let noise = |n: FastNoiseLite| NoiseTexture2D { noise: Some(n), ..texture(4, 4) };
        refused(noise(FastNoiseLite { noise_type: 6, ..FastNoiseLite::default() }), "`noise.noise_type`");
        refused(noise(FastNoiseLite { fractal_octaves: 0, ..FastNoiseLite::default() }), "`noise.fractal_octaves`");
        refused(noise(FastNoiseLite { domain_warp_type: -1, ..FastNoiseLite::default() }), "`noise.domain_warp_type`");
        refused(
            noise(FastNoiseLite { offset: [0.0, f64::INFINITY, 0.0], ..FastNoiseLite::default() }),
            "`noise.offset`",
        );
        let ramp = Gradient { interpolation_mode: 7, ..Gradient::default() };
        refused(NoiseTexture2D { color_ramp: Some(ramp), ..texture(4, 4) }, "`color_ramp`");
    }

    /// Sizes the GPU cannot hold, or past gdsky's work budget, are refused before any noise is
    /// computed (a 2048×2048×64 volume took 131 s; a 4096-sided one was refused only after 91 s).
    #[test]
    fn volumes_past_the_budget_are_refused_before_generating() {
        let volume = |width, height, depth| NoiseTexture3D {
            width,
            height,
            depth,
            noise: Some(FastNoiseLite::default()),
            ..NoiseTexture3D::default()
        };
        let too_wide = volume(4096, 4, 4).image().expect_err("wider than the GPU holds").to_string();
        assert!(too_wide.contains("at most 2048"), "{too_wide}");
        let too_much = volume(2048, 2048, 64).image().expect_err("over the budget").to_string();
        assert!(too_much.contains("budget") && too_much.contains("2048×2048×64"), "{too_much}");
        assert!(volume(8, 8, 8).image().is_ok());
    }

    #[test]
    fn mipmaps_halve_down_to_one_texel() {
        let image =
            NoiseImage { width: 5, height: 3, format: NoiseFormat::L8, data: (0..15).map(|v| v * 10).collect() };
        let levels = image.mipmaps();
        let sizes: Vec<(u32, u32)> = levels.iter().map(|l| (l.width, l.height)).collect();
        assert_eq!(sizes, [(2, 1), (1, 1)]);
        // (0 + 10 + 50 + 60 + 2) >> 2 = 30, (20 + 30 + 70 + 80 + 2) >> 2 = 50; the fifth column
        // and the third row are dropped.
        assert_eq!(levels[0].data, [30, 50]);
        assert_eq!(levels[1].data, [40]);
        let single = NoiseImage { width: 1, height: 1, format: NoiseFormat::Rgba8, data: vec![1, 2, 3, 4] };
        assert!(single.mipmaps().is_empty());
    }

    #[test]
    fn volumes_have_their_slices() {
        let t = NoiseTexture3D {
            width: 8,
            height: 4,
            depth: 3,
            noise: Some(FastNoiseLite::default()),
            ..NoiseTexture3D::default()
        };
        let slices = t.image().expect("generates");
        assert_eq!(slices.len(), 3);
        assert!(slices.iter().all(|s| s.data.len() == 32));
        let seamless = NoiseTexture3D { seamless: true, ..t }.image().expect("generates");
        assert_eq!(seamless.len(), 3);
    }
}

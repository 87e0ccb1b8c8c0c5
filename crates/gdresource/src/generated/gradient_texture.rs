//! Godot 4.6's other generated textures: `GradientTexture1D`, `GradientTexture2D` (a
//! [`Gradient`] laid out along a line, a circle, a square or an angle) and `CurveTexture` (a
//! [`Curve`] baked into a table and sampled across the texture), as
//! scene/resources/gradient_texture.cpp, curve_texture.cpp and curve.cpp build them.
//!
//! Everything is computed in f32 in Godot's order of operations (Godot's `Vector2`, `Color` and
//! `real_t` hold floats in the builds the editor and the Web export use), so that the bytes
//! match: RGBA8 through `Color::get_r8` (round, clamp), or the floats as stored with `use_hdr`
//! (`FORMAT_RGBAF`); a `CurveTexture` is `FORMAT_RGBF` (value in r, g, b) or `FORMAT_RF`.

use super::gradient::Ramp;
use super::{Gradient, NoiseError};

/// Godot's `Image` format of a generated gradient or curve texture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RampFormat {
    /// `FORMAT_RGBA8`: a gradient texture without `use_hdr`.
    Rgba8,
    /// `FORMAT_RGBAF`: a gradient texture with `use_hdr`, four f32 per texel.
    Rgbaf,
    /// `FORMAT_RGBF`: a `CurveTexture` in RGB mode, the value three times.
    Rgbf,
    /// `FORMAT_RF`: a `CurveTexture` in red mode, one f32 per texel.
    Rf,
}

impl RampFormat {
    /// Bytes per texel.
    pub fn bytes_per_texel(self) -> usize {
        match self {
            Self::Rgba8 => 4,
            Self::Rgbaf => 16,
            Self::Rgbf => 12,
            Self::Rf => 4,
        }
    }

    /// Godot's name of the format (`Image.FORMAT_*` without the prefix).
    pub fn godot_name(self) -> &'static str {
        match self {
            Self::Rgba8 => "RGBA8",
            Self::Rgbaf => "RGBAF",
            Self::Rgbf => "RGBF",
            Self::Rf => "RF",
        }
    }
}

/// A generated gradient or curve image in Godot's format, row 0 first (floats little-endian).
#[derive(Clone, Debug, PartialEq)]
pub struct RampImage {
    /// Width in texels.
    pub width: u32,
    /// Height in texels (1 for `GradientTexture1D` and `CurveTexture`).
    pub height: u32,
    /// Godot's format.
    pub format: RampFormat,
    /// `width × height × format.bytes_per_texel()` bytes.
    pub data: Vec<u8>,
}

impl RampImage {
    /// The texture a shader samples. RGBA8 stays RGBA8 (read as byte / 255, as Godot uploads
    /// it). The float formats become RGBA16F: Godot uploads f32, but a 32-bit float texture
    /// cannot be filtered in core WebGPU, and a sky samples these with `texture()`; half
    /// precision (relative error ≤ 2⁻¹¹) is the price. What a shader sees of the missing
    /// channels is what GL gives: `RF` → (r, 0, 0, 1), `RGBF` → (r, g, b, 1).
    pub fn to_texture(&self) -> Result<skycore::TextureData, NoiseError> {
        let floats = |bytes: &[u8]| -> Vec<f32> {
            bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect()
        };
        let (format, data) = match self.format {
            RampFormat::Rgba8 => (skycore::TexelFormat::Rgba8Unorm, self.data.clone()),
            other => {
                let v = floats(&self.data);
                let rgba: Vec<f32> = match other {
                    RampFormat::Rgbaf => v,
                    RampFormat::Rgbf => v.chunks_exact(3).flat_map(|c| [c[0], c[1], c[2], 1.0]).collect(),
                    _ => v.iter().flat_map(|&r| [r, 0.0, 0.0, 1.0]).collect(),
                };
                let bytes = rgba.iter().flat_map(|&f| f16_bits(f).to_le_bytes()).collect();
                (skycore::TexelFormat::Rgba16Float, bytes)
            }
        };
        skycore::TextureData::new(self.width, self.height, format, data).map_err(NoiseError::Texture)
    }
}

/// IEEE binary16 bits of `v`, rounded to nearest even (overflow to infinity, NaN kept).
fn f16_bits(v: f32) -> u16 {
    let bits = v.to_bits();
    let sign = ((bits >> 16) & 0x8000) as u16;
    let exp = ((bits >> 23) & 0xff) as i32;
    let man = bits & 0x7f_ffff;
    if exp == 0xff {
        return sign | 0x7c00 | if man != 0 { 0x200 } else { 0 };
    }
    let e = exp - 127 + 15;
    if e >= 0x1f {
        return sign | 0x7c00;
    }
    // The significand with its implicit bit, and how far it shifts down to binary16's 10 bits
    // (further for subnormal results).
    let full = man | 0x80_0000;
    let shift = if e <= 0 { 14 - e } else { 13 } as u32;
    if shift > 24 {
        return sign;
    }
    let kept = full >> shift;
    let rest = full & ((1 << shift) - 1);
    let half = 1 << (shift - 1);
    let rounded = kept + u32::from(rest > half || (rest == half && kept & 1 == 1));
    // Normal: the exponent field plus the 10 fraction bits (a carry out of the fraction bumps
    // the exponent, as it should); subnormal: the shifted significand alone.
    let value = if e <= 0 { rounded } else { ((e as u32) << 10) + (rounded - 0x400) };
    sign | value as u16
}

fn out_of_range(property: &'static str, message: String) -> NoiseError {
    NoiseError::OutOfRange { property, message }
}

/// A side within Godot's setter range.
fn side(property: &'static str, value: i64, max: i64) -> Result<usize, NoiseError> {
    if (1..=max).contains(&value) {
        Ok(value as usize)
    } else {
        Err(out_of_range(property, format!("{value} is outside 1 … {max}")))
    }
}

/// The gradient, checked; Godot generates nothing without one.
fn ramp(gradient: Option<&Gradient>) -> Result<Ramp, NoiseError> {
    let g = gradient.ok_or_else(|| out_of_range("gradient", "is not set: Godot generates no image".into()))?;
    Ramp::new(g).map_err(|m| out_of_range("gradient", m))
}

/// `Color::get_r8`: `int32_t(CLAMP(Math::round(v * 255.0f), 0.0f, 255.0f))`.
fn to_u8(v: f32) -> u8 {
    // CLAMP keeps a NaN (as `f32::clamp` does), and the cast then gives 0, as wasm's
    // saturating conversion does.
    (v * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Texels from colours: RGBA8 or, with `hdr`, RGBAF.
fn pack(colors: impl Iterator<Item = [f32; 4]>, hdr: bool) -> Vec<u8> {
    if hdr {
        colors.flat_map(|c| c.into_iter().flat_map(f32::to_le_bytes)).collect()
    } else {
        colors.flat_map(|c| c.map(to_u8)).collect()
    }
}

/// Godot's `GradientTexture1D`: the gradient sampled at `i / (width − 1)`.
#[derive(Clone, Debug, PartialEq)]
pub struct GradientTexture1D {
    /// `gradient`; `None` makes no image (an error here).
    pub gradient: Option<Gradient>,
    /// `width` (1 … 16384, default 256).
    pub width: i64,
    /// `use_hdr`: RGBAF instead of RGBA8 (colours not clamped).
    pub use_hdr: bool,
}

impl Default for GradientTexture1D {
    /// A new Godot `GradientTexture1D` (the editor gives it a new default `Gradient`).
    fn default() -> Self {
        Self { gradient: Some(Gradient::default()), width: 256, use_hdr: false }
    }
}

impl GradientTexture1D {
    /// The image Godot generates (`GradientTexture1D::_update`).
    pub fn image(&self) -> Result<RampImage, NoiseError> {
        let width = side("width", self.width, 16384)?;
        let ramp = ramp(self.gradient.as_ref())?;
        // `float(i) / (width - 1)`: a width of 1 divides 0 by 0, as Godot does.
        let den = (width - 1) as f32;
        let data = pack((0..width).map(|i| ramp.color_at(i as f32 / den)), self.use_hdr);
        let format = if self.use_hdr { RampFormat::Rgbaf } else { RampFormat::Rgba8 };
        Ok(RampImage { width: width as u32, height: 1, format, data })
    }
}

/// Godot's `GradientTexture2D`: the gradient laid out over a rectangle.
#[derive(Clone, Debug, PartialEq)]
pub struct GradientTexture2D {
    /// `gradient`; `None` makes no image (an error here).
    pub gradient: Option<Gradient>,
    /// `width` (1 … 16384, default 64).
    pub width: i64,
    /// `height` (1 … 16384, default 64).
    pub height: i64,
    /// `use_hdr`: RGBAF instead of RGBA8.
    pub use_hdr: bool,
    /// `fill`: 0 linear, 1 radial, 2 square. A 3 (conic, in Godot after 4.6) gives what 4.6
    /// makes of it: offset 0 everywhere, the gradient's start colour.
    pub fill: i64,
    /// `fill_from`, in UV (0 … 1 across the texture), default (0, 0).
    pub fill_from: [f64; 2],
    /// `fill_to`, default (1, 0).
    pub fill_to: [f64; 2],
    /// `repeat`: 0 none (clamped), 1 repeat, 2 mirror.
    pub repeat: i64,
}

impl Default for GradientTexture2D {
    /// A new Godot `GradientTexture2D` (with the editor's default `Gradient`).
    fn default() -> Self {
        Self {
            gradient: Some(Gradient::default()),
            width: 64,
            height: 64,
            use_hdr: false,
            fill: 0,
            fill_from: [0.0, 0.0],
            fill_to: [1.0, 0.0],
            repeat: 0,
        }
    }
}

type V2 = [f32; 2];

fn sub(a: V2, b: V2) -> V2 {
    [a[0] - b[0], a[1] - b[1]]
}

fn dot(a: V2, b: V2) -> f32 {
    a[0] * b[0] + a[1] * b[1]
}

fn length(a: V2) -> f32 {
    (a[0] * a[0] + a[1] * a[1]).sqrt()
}

impl GradientTexture2D {
    /// `_get_gradient_offset_at`: where texel (x, y) falls on the gradient.
    fn offset_at(&self, x: usize, y: usize, from: V2, to: V2, fill: i64, repeat: i64) -> f32 {
        if from == to {
            return 0.0;
        }
        let (w, h) = (self.width as usize, self.height as usize);
        let mut pos = [0.0f32; 2];
        if w > 1 {
            pos[0] = x as f32 / (w - 1) as f32;
        }
        if h > 1 {
            pos[1] = y as f32 / (h - 1) as f32;
        }
        let span = sub(to, from);
        let mut ofs = match fill {
            0 => {
                // Geometry2D::get_closest_point_to_segment_uncapped.
                let p = sub(pos, from);
                let l2 = dot(span, span);
                let closest = if l2 < 1e-20 {
                    from
                } else {
                    let d = dot(span, p) / l2;
                    [from[0] + span[0] * d, from[1] + span[1] * d]
                };
                let along = sub(closest, from);
                let o = length(along) / length(span);
                if dot(along, span) < 0.0 { -o } else { o }
            }
            1 => length(sub(pos, from)) / length(span),
            2 => {
                let d = sub(pos, from);
                d[0].abs().max(d[1].abs()) / span[0].abs().max(span[1].abs())
            }
            // Godot 4.6 has no other fill (the conic fill came later): no branch sets the
            // offset, which stays 0.
            _ => 0.0,
        };
        match repeat {
            0 => {
                // CLAMP(ofs, 0.0, 1.0); a NaN stays NaN, as with CLAMP's comparisons.
                ofs = ofs.clamp(0.0, 1.0);
            }
            1 => {
                ofs %= 1.0;
                if ofs < 0.0 {
                    ofs += 1.0;
                }
            }
            _ => {
                ofs = ofs.abs() % 2.0;
                if ofs > 1.0 {
                    ofs = 2.0 - ofs;
                }
            }
        }
        ofs
    }

    /// The image Godot generates (`GradientTexture2D::_update`).
    pub fn image(&self) -> Result<RampImage, NoiseError> {
        let (w, h) = (side("width", self.width, 16384)?, side("height", self.height, 16384)?);
        let fill = match self.fill {
            f @ 0..=3 => f,
            f => {
                return Err(out_of_range(
                    "fill",
                    format!("{f} is not 0 (linear), 1 (radial), 2 (square) or 3 (conic, newer than Godot 4.6)"),
                ));
            }
        };
        let repeat = match self.repeat {
            r @ 0..=2 => r,
            r => return Err(out_of_range("repeat", format!("{r} is not 0 (none), 1 (repeat) or 2 (mirror)"))),
        };
        let v2 = |name: &'static str, v: [f64; 2]| -> Result<V2, NoiseError> {
            if v.iter().all(|c| c.is_finite()) {
                Ok(v.map(|c| c as f32))
            } else {
                Err(out_of_range(name, "has a non-finite component".into()))
            }
        };
        let (from, to) = (v2("fill_from", self.fill_from)?, v2("fill_to", self.fill_to)?);
        let g = self.gradient.as_ref();
        let ramp = ramp(g)?;
        let format = if self.use_hdr { RampFormat::Rgbaf } else { RampFormat::Rgba8 };
        let points = g.map_or(0, |g| g.offsets.len());
        let data = if points <= 1 {
            // No interpolation: the one colour as given (unsorted is the same), or black.
            let c = g.and_then(|g| g.colors.first()).map_or([0.0, 0.0, 0.0, 1.0], |c| c.map(|v| v as f32));
            pack(std::iter::repeat_n(c, w * h), self.use_hdr)
        } else {
            let texels = (0..h).flat_map(|y| (0..w).map(move |x| (x, y)));
            pack(texels.map(|(x, y)| ramp.color_at(self.offset_at(x, y, from, to, fill, repeat))), self.use_hdr)
        };
        Ok(RampImage { width: w as u32, height: h as u32, format, data })
    }
}

/// One point of a Godot `Curve` (an entry of its `_data`).
#[derive(Clone, Debug, PartialEq)]
pub struct CurvePoint {
    /// (offset, value).
    pub position: [f64; 2],
    /// The slope arriving at the point.
    pub left_tangent: f64,
    /// The slope leaving the point.
    pub right_tangent: f64,
    /// 0 free, 1 linear: how the editor keeps the left tangent (a saved curve already holds
    /// the tangent it computed, and loading does not recompute it).
    pub left_mode: i64,
    /// 0 free, 1 linear (as `left_mode`).
    pub right_mode: i64,
}

/// Godot's `Curve`: points joined by cubic Béziers, baked into a table.
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    /// The points, in the order `_data` gives them (Godot keeps them sorted by offset).
    pub points: Vec<CurvePoint>,
    /// `min_value` (does not change sampling, only the editor's range).
    pub min_value: f64,
    /// `max_value`.
    pub max_value: f64,
    /// `min_domain`: the offset the baked table starts at.
    pub min_domain: f64,
    /// `max_domain`: where it ends.
    pub max_domain: f64,
    /// `bake_resolution` (1 … 1000, default 100): entries in the baked table.
    pub bake_resolution: i64,
}

impl Default for Curve {
    /// A new Godot `Curve`: no points, range and domain 0 … 1, 100 baked entries.
    fn default() -> Self {
        Self {
            points: Vec::new(),
            min_value: 0.0,
            max_value: 1.0,
            min_domain: 0.0,
            max_domain: 1.0,
            bake_resolution: 100,
        }
    }
}

/// A curve in the f32 Godot samples with: (x, y, left tangent, right tangent) per point.
struct Baked {
    points: Vec<[f32; 4]>,
    min_domain: f32,
    range: f32,
    table: Vec<f32>,
}

impl Baked {
    fn new(c: &Curve) -> Result<Self, NoiseError> {
        if !(1..=1000).contains(&c.bake_resolution) {
            return Err(out_of_range("curve.bake_resolution", format!("{} is outside 1 … 1000", c.bake_resolution)));
        }
        let finite = c
            .points
            .iter()
            .all(|p| p.position.iter().chain([&p.left_tangent, &p.right_tangent]).all(|v| v.is_finite()))
            && [c.min_domain, c.max_domain].iter().all(|v| v.is_finite());
        if !finite {
            return Err(out_of_range("curve", "has a non-finite point, tangent or domain".into()));
        }
        let points: Vec<[f32; 4]> = c
            .points
            .iter()
            .map(|p| [p.position[0] as f32, p.position[1] as f32, p.left_tangent as f32, p.right_tangent as f32])
            .collect();
        let (min_domain, max_domain) = (c.min_domain as f32, c.max_domain as f32);
        let mut baked = Self { points, min_domain, range: max_domain - min_domain, table: Vec::new() };
        baked.bake(c.bake_resolution as usize);
        Ok(baked)
    }

    /// `Curve::get_index`: a lower-bound search over the points' offsets.
    fn index(&self, offset: f32) -> usize {
        let (mut lo, mut hi) = (0usize, self.points.len() - 1);
        while hi - lo > 1 {
            let m = (lo + hi) / 2;
            let (a, b) = (self.points[m][0], self.points[m + 1][0]);
            if a < offset && b < offset {
                lo = m;
            } else if a > offset {
                hi = m;
            } else {
                return m;
            }
        }
        if offset > self.points[hi][0] { hi } else { lo }
    }

    /// `Curve::sample`.
    fn sample(&self, offset: f32) -> f32 {
        match self.points.len() {
            0 => return 0.0,
            1 => return self.points[0][1],
            _ => {}
        }
        let i = self.index(offset);
        if i == self.points.len() - 1 {
            return self.points[i][1];
        }
        let local = offset - self.points[i][0];
        if i == 0 && local <= 0.0 {
            return self.points[0][1];
        }
        let (a, b) = (self.points[i], self.points[i + 1]);
        let mut d = b[0] - a[0];
        // Math::is_zero_approx: |d| < CMP_EPSILON (1e-5).
        if d.abs() < 0.00001 {
            return b[1];
        }
        let t = local / d;
        // `d /= 3.0` divides by a double.
        d = (f64::from(d) / 3.0) as f32;
        let (yac, ybc) = (a[1] + d * a[3], b[1] - d * b[2]);
        // Math::bezier_interpolate (f32), term by term.
        let omt = 1.0 - t;
        let (omt2, t2) = (omt * omt, t * t);
        let (omt3, t3) = (omt2 * omt, t2 * t);
        a[1] * omt3 + yac * omt2 * t * 3.0 + ybc * omt * t2 * 3.0 + b[1] * t3
    }

    /// `Curve::_bake`.
    fn bake(&mut self, resolution: usize) {
        let mut table = vec![0.0f32; resolution];
        for (i, entry) in table.iter_mut().enumerate().take(resolution.saturating_sub(1)).skip(1) {
            let x = self.range * i as f32 / (resolution - 1) as f32 + self.min_domain;
            *entry = self.sample(x);
        }
        if let (Some(first), Some(last)) = (self.points.first(), self.points.last()) {
            table[0] = first[1];
            table[resolution - 1] = last[1];
        }
        self.table = table;
    }

    /// `Curve::sample_baked`.
    fn sample_baked(&self, offset: f32) -> f32 {
        let n = self.table.len();
        if n == 1 {
            return self.table[0];
        }
        let mut fi = (offset - self.min_domain) / self.range * (n - 1) as f32;
        let mut i = fi.floor() as i64;
        if i < 0 {
            i = 0;
            fi = 0.0;
        } else if i >= n as i64 {
            i = n as i64 - 1;
            fi = 0.0;
        }
        let i = i as usize;
        if i + 1 < n {
            let t = fi - i as f32;
            // Math::lerp: from + (to - from) * weight.
            self.table[i] + (self.table[i + 1] - self.table[i]) * t
        } else {
            self.table[n - 1]
        }
    }
}

impl Curve {
    /// `Curve::sample_baked` at `offset`, as Godot computes it (f32).
    pub fn sample_baked(&self, offset: f32) -> Result<f32, NoiseError> {
        Ok(Baked::new(self)?.sample_baked(offset))
    }
}

/// Godot's `CurveTexture`: a curve baked and sampled at `i / width`.
#[derive(Clone, Debug, PartialEq)]
pub struct CurveTexture {
    /// `curve`; `None` gives zeros, as in Godot.
    pub curve: Option<Curve>,
    /// `width` (32 … 4096, default 256; Godot's setter ignores other values, so they are
    /// refused here rather than silently replaced).
    pub width: i64,
    /// `texture_mode`: 0 RGB (`FORMAT_RGBF`), 1 red (`FORMAT_RF`).
    pub texture_mode: i64,
}

impl Default for CurveTexture {
    /// A new Godot `CurveTexture` (no curve: the editor adds one when edited).
    fn default() -> Self {
        Self { curve: None, width: 256, texture_mode: 0 }
    }
}

impl CurveTexture {
    /// The image Godot generates (`CurveTexture::_update`).
    pub fn image(&self) -> Result<RampImage, NoiseError> {
        let width = curve_width(self.width)?;
        let format = match self.texture_mode {
            0 => RampFormat::Rgbf,
            1 => RampFormat::Rf,
            m => return Err(out_of_range("texture_mode", format!("{m} is not 0 (RGB) or 1 (red)"))),
        };
        let baked = self.curve.as_ref().map(Baked::new).transpose()?;
        let values = (0..width).map(|i| baked.as_ref().map_or(0.0, |b| b.sample_baked(i as f32 / width as f32)));
        let repeat = if format == RampFormat::Rgbf { 3 } else { 1 };
        let data = values.flat_map(|v| std::iter::repeat_n(v.to_le_bytes(), repeat).flatten()).collect();
        Ok(RampImage { width: width as u32, height: 1, format, data })
    }
}

/// Godot's `CurveXYZTexture`: three curves baked into r, g and b.
#[derive(Clone, Debug, PartialEq)]
pub struct CurveXyzTexture {
    /// `curve_x`, `curve_y`, `curve_z`; a missing one gives zeros in its channel.
    pub curves: [Option<Curve>; 3],
    /// `width` (32 … 4096, default 256).
    pub width: i64,
}

impl Default for CurveXyzTexture {
    /// A new Godot `CurveXYZTexture`.
    fn default() -> Self {
        Self { curves: [None, None, None], width: 256 }
    }
}

impl CurveXyzTexture {
    /// The image Godot generates (`CurveXYZTexture::_update`): `FORMAT_RGBF`, channel c of
    /// texel i the c-th curve's `sample_baked(i / width)`.
    pub fn image(&self) -> Result<RampImage, NoiseError> {
        let width = curve_width(self.width)?;
        let baked: Vec<Option<Baked>> =
            self.curves.iter().map(|c| c.as_ref().map(Baked::new).transpose()).collect::<Result<_, _>>()?;
        let data = (0..width)
            .flat_map(|i| {
                let t = i as f32 / width as f32;
                baked.iter().map(move |b| b.as_ref().map_or(0.0, |b| b.sample_baked(t)))
            })
            .flat_map(f32::to_le_bytes)
            .collect();
        Ok(RampImage { width: width as u32, height: 1, format: RampFormat::Rgbf, data })
    }
}

/// A curve texture's width, in Godot's setter range.
fn curve_width(width: i64) -> Result<usize, NoiseError> {
    if (32..=4096).contains(&width) {
        Ok(width as usize)
    } else {
        Err(out_of_range(
            "width",
            format!("{width} is outside 32 … 4096 (Godot ignores it and keeps the previous width)"),
        ))
    }
}

/// One of the textures this module generates, as a material gives it.
#[derive(Clone, Debug, PartialEq)]
pub enum RampTexture {
    /// A `GradientTexture1D`.
    Gradient1D(GradientTexture1D),
    /// A `GradientTexture2D`.
    Gradient2D(GradientTexture2D),
    /// A `CurveTexture`.
    Curve(CurveTexture),
    /// A `CurveXYZTexture`.
    CurveXyz(CurveXyzTexture),
}

impl RampTexture {
    /// Godot's class name.
    pub fn class(&self) -> &'static str {
        match self {
            Self::Gradient1D(_) => "GradientTexture1D",
            Self::Gradient2D(_) => "GradientTexture2D",
            Self::Curve(_) => "CurveTexture",
            Self::CurveXyz(_) => "CurveXYZTexture",
        }
    }

    /// The image Godot generates.
    pub fn image(&self) -> Result<RampImage, NoiseError> {
        match self {
            Self::Gradient1D(t) => t.image(),
            Self::Gradient2D(t) => t.image(),
            Self::Curve(t) => t.image(),
            Self::CurveXyz(t) => t.image(),
        }
    }

    /// The texture a shader samples ([`RampImage::to_texture`]).
    pub fn generate(&self) -> Result<skycore::TextureData, NoiseError> {
        self.image()?.to_texture()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn floats(image: &RampImage) -> Vec<f32> {
        image.data.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect()
    }

    #[test]
    fn half_floats_round_to_nearest() {
        assert_eq!(f16_bits(1.0), 0x3c00);
        assert_eq!(f16_bits(-2.0), 0xc000);
        assert_eq!(f16_bits(0.5 + 1.0 / 4096.0), 0x3800, "a tie rounds to even");
        assert_eq!(f16_bits(65504.0), 0x7bff);
        assert_eq!(f16_bits(1e6), 0x7c00);
        assert_eq!(f16_bits(2f32.powi(-24)), 1, "the smallest subnormal");
        assert_eq!(f16_bits(0.0), 0);
    }

    #[test]
    fn gradient_1d_runs_from_the_first_colour_to_the_last() {
        let image = GradientTexture1D { width: 5, ..Default::default() }.image().unwrap();
        let reds: Vec<u8> = image.data.chunks_exact(4).map(|c| c[0]).collect();
        // 0, 0.25, 0.5, 0.75, 1 of black → white: get_r8 rounds 63.75 and 191.25.
        assert_eq!(reds, [0, 64, 128, 191, 255]);
    }

    #[test]
    fn radial_and_square_fills_grow_from_fill_from() {
        let t =
            GradientTexture2D { width: 3, height: 3, fill_from: [0.5, 0.5], fill_to: [1.0, 0.5], ..Default::default() };
        for fill in [1, 2] {
            let image = GradientTexture2D { fill, ..t.clone() }.image().unwrap();
            assert_eq!(image.data[4 * 4], 0, "the centre is the start");
            assert_eq!(image.data[0], 255, "a corner is past the end (clamped)");
        }
        let mirror = GradientTexture2D { fill_to: [0.75, 0.5], repeat: 2, ..t.clone() }.image().unwrap();
        assert_eq!(mirror.data[3 * 4], 0, "(0, 0.5) is 2 lengths away: mirrored back to 0");
    }

    #[test]
    fn a_curve_texture_bakes_the_bezier() {
        let point = |x: f64, y: f64| CurvePoint {
            position: [x, y],
            left_tangent: 0.0,
            right_tangent: 0.0,
            left_mode: 0,
            right_mode: 0,
        };
        let curve = Curve { points: vec![point(0.0, 0.0), point(1.0, 1.0)], ..Default::default() };
        let t = CurveTexture { curve: Some(curve.clone()), width: 32, texture_mode: 1 };
        let v = floats(&t.image().unwrap());
        assert_eq!(v[0], 0.0);
        assert!((v[16] - 0.5).abs() < 1e-3, "smoothstep-like through the middle: {}", v[16]);
        let rgb = floats(&CurveTexture { texture_mode: 0, ..t }.image().unwrap());
        assert_eq!((rgb[48], rgb[49], rgb[50]), (v[16], v[16], v[16]));
        assert!(CurveTexture { width: 16, ..Default::default() }.image().is_err());
    }
}

//! Godot's `Gradient` as `NoiseTexture2D.color_ramp` samples it (scene/resources/gradient.h,
//! `get_color_at_offset`): a binary search over the points sorted by offset, then constant,
//! linear or cubic interpolation in sRGB, linear sRGB or OKLab. All in f32, in Godot's order of
//! operations, since Godot's `Color` and `Gradient::Point` hold floats.

/// Godot's `Gradient` resource, as a `.tres` gives it.
#[derive(Clone, Debug, PartialEq)]
pub struct Gradient {
    /// `offsets` (a `PackedFloat32Array`): where each colour sits, usually 0 … 1. Godot sorts
    /// the points by offset before sampling.
    pub offsets: Vec<f64>,
    /// `colors` (a `PackedColorArray`): RGBA per point, as stored (sRGB values, not converted).
    pub colors: Vec<[f64; 4]>,
    /// `interpolation_mode`: 0 linear, 1 constant, 2 cubic.
    pub interpolation_mode: i64,
    /// `interpolation_color_space`: 0 sRGB, 1 linear sRGB, 2 OKLab.
    pub interpolation_color_space: i64,
}

impl Default for Gradient {
    /// Godot 4.6's new `Gradient`: black at 0, white at 1, linear, in sRGB.
    fn default() -> Self {
        Self {
            offsets: vec![0.0, 1.0],
            colors: vec![[0.0, 0.0, 0.0, 1.0], [1.0, 1.0, 1.0, 1.0]],
            interpolation_mode: 0,
            interpolation_color_space: 0,
        }
    }
}

/// Godot's `Gradient::InterpolationMode`.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Mode {
    Linear,
    Constant,
    Cubic,
}

/// Godot's `Gradient::ColorSpace`.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Space {
    Srgb,
    LinearSrgb,
    Oklab,
}

/// A validated gradient, in the f32 Godot samples with.
#[derive(Clone, Debug)]
pub(crate) struct Ramp {
    /// (offset, colour), sorted by offset.
    points: Vec<(f32, [f32; 4])>,
    mode: Mode,
    space: Space,
}

impl Ramp {
    /// Checks the gradient: as many colours as offsets, finite values, known enum numbers.
    pub(crate) fn new(g: &Gradient) -> Result<Self, String> {
        if g.offsets.len() != g.colors.len() {
            return Err(format!("color_ramp has {} offsets but {} colors", g.offsets.len(), g.colors.len()));
        }
        if g.offsets.iter().chain(g.colors.iter().flatten()).any(|v| !v.is_finite()) {
            return Err("color_ramp has a non-finite offset or colour".into());
        }
        let mode = match g.interpolation_mode {
            0 => Mode::Linear,
            1 => Mode::Constant,
            2 => Mode::Cubic,
            n => return Err(format!("color_ramp interpolation_mode {n} is not 0 (linear), 1 (constant) or 2 (cubic)")),
        };
        let space = match g.interpolation_color_space {
            0 => Space::Srgb,
            1 => Space::LinearSrgb,
            2 => Space::Oklab,
            n => {
                return Err(format!(
                    "color_ramp interpolation_color_space {n} is not 0 (sRGB), 1 (linear sRGB) or 2 (OKLab)"
                ));
            }
        };
        let mut points: Vec<(f32, [f32; 4])> =
            g.offsets.iter().zip(&g.colors).map(|(o, c)| (*o as f32, c.map(|v| v as f32))).collect();
        // Godot sorts with `operator<` on offsets; points at equal offsets keep an order Godot's
        // unstable sort does not promise, so a stable sort is as good a choice as any.
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        Ok(Self { points, mode, space })
    }

    /// `Gradient::get_color_at_offset`.
    pub(crate) fn color_at(&self, offset: f32) -> [f32; 4] {
        let points = &self.points;
        if points.is_empty() {
            return [0.0, 0.0, 0.0, 1.0];
        }
        // Godot's binary search, kept as is: which neighbour it lands on decides ties.
        let (mut low, mut high, mut middle) = (0i64, points.len() as i64 - 1, 0i64);
        while low <= high {
            middle = (low + high) / 2;
            let point = points[middle as usize];
            if point.0 > offset {
                high = middle - 1;
            } else if point.0 < offset {
                low = middle + 1;
            } else {
                return point.1;
            }
        }
        if points[middle as usize].0 > offset {
            middle -= 1;
        }
        let (first, second) = (middle, middle + 1);
        if second >= points.len() as i64 {
            return points[points.len() - 1].1;
        }
        if first < 0 {
            return points[0].1;
        }
        let (p1, p2) = (points[first as usize], points[second as usize]);
        let weight = (offset - p1.0) / (p2.0 - p1.0);
        match self.mode {
            Mode::Constant => p1.1,
            Mode::Linear => {
                let (c1, c2) = (self.transform_color_space(p1.1), self.transform_color_space(p2.1));
                self.inv_transform_color_space(std::array::from_fn(|i| c1[i] + (c2[i] - c1[i]) * weight))
            }
            Mode::Cubic => {
                let p0 = points[(first - 1).max(0) as usize].1;
                let p3 = points[(second + 1).min(points.len() as i64 - 1) as usize].1;
                let [c0, c1, c2, c3] = [p0, p1.1, p2.1, p3].map(|c| self.transform_color_space(c));
                self.inv_transform_color_space(std::array::from_fn(|i| {
                    cubic_interpolate(c1[i], c2[i], c0[i], c3[i], weight)
                }))
            }
        }
    }

    /// `Gradient::transform_color_space`.
    fn transform_color_space(&self, c: [f32; 4]) -> [f32; 4] {
        match self.space {
            Space::Srgb => c,
            Space::LinearSrgb => srgb_to_linear(c),
            Space::Oklab => {
                let l = srgb_to_linear(c);
                let lab = linear_srgb_to_oklab([l[0], l[1], l[2]]);
                [lab[0], lab[1], lab[2], l[3]]
            }
        }
    }

    /// `Gradient::inv_transform_color_space`.
    fn inv_transform_color_space(&self, c: [f32; 4]) -> [f32; 4] {
        match self.space {
            Space::Srgb => c,
            Space::LinearSrgb => linear_to_srgb(c),
            Space::Oklab => {
                let rgb = oklab_to_linear_srgb([c[0], c[1], c[2]]);
                linear_to_srgb([rgb[0], rgb[1], rgb[2], c[3]])
            }
        }
    }
}

/// `Math::cubic_interpolate` (f32): Catmull–Rom through `pre`, `from`, `to`, `post`.
fn cubic_interpolate(from: f32, to: f32, pre: f32, post: f32, w: f32) -> f32 {
    0.5 * ((from * 2.0)
        + (-pre + to) * w
        + (2.0 * pre - 5.0 * from + 4.0 * to - post) * (w * w)
        + (-pre + 3.0 * from - 3.0 * to + post) * (w * w * w))
}

/// `Color::srgb_to_linear` (core/math/color.h; alpha unchanged). Godot 4.6 computes the
/// base in f64 and rounds it to f32 before the f32 `pow` (measured against Godot: the f32
/// form of later sources is one ulp off in most RGBAF texels).
fn srgb_to_linear(c: [f32; 4]) -> [f32; 4] {
    let f = |v: f32| {
        if v < 0.04045 {
            v * (1.0 / 12.92)
        } else {
            (((f64::from(v) + 0.055) * (1.0 / (1.0 + 0.055))) as f32).powf(2.4)
        }
    };
    [f(c[0]), f(c[1]), f(c[2]), c[3]]
}

/// `Color::linear_to_srgb` (alpha unchanged): the f32 `pow`, then the scale and offset in f64,
/// rounded to f32, as Godot 4.6 writes it.
fn linear_to_srgb(c: [f32; 4]) -> [f32; 4] {
    let f = |v: f32| {
        if v < 0.0031308 { 12.92 * v } else { ((1.0 + 0.055) * f64::from(v.powf(1.0 / 2.4)) - 0.055) as f32 }
    };
    [f(c[0]), f(c[1]), f(c[2]), c[3]]
}

/// `cbrtf` as Godot's Web export (emscripten's musl, from FreeBSD) computes it: a bit-trick
/// first guess and two Halley steps in f64, rounded once to f32. Rust's `f32::cbrt` calls the
/// host's libm, whose last bit differs at some inputs (measured: one RGBA8 code in one texel of
/// a 256-wide cubic OKLab gradient).
fn cbrtf(x: f32) -> f32 {
    const B1: u32 = 709_958_130; // (127 − 127/3 − 0.03306235651) · 2²³
    const B2: u32 = 642_849_266; // (127 − 127/3 − 24/3 − 0.03306235651) · 2²³
    let bits = x.to_bits();
    let mut hx = bits & 0x7fff_ffff;
    if hx >= 0x7f80_0000 {
        return x + x;
    }
    let guess_bits = if hx < 0x0080_0000 {
        if hx == 0 {
            return x;
        }
        // Subnormal: scale by 2²⁴ to read an exponent.
        hx = (x * 16_777_216.0).to_bits() & 0x7fff_ffff;
        hx / 3 + B2
    } else {
        hx / 3 + B1
    };
    let mut t = f64::from(f32::from_bits((bits & 0x8000_0000) | guess_bits));
    let xd = f64::from(x);
    for _ in 0..2 {
        let r = t * t * t;
        t = t * (xd + xd + r) / (xd + r + r);
    }
    t as f32
}

/// Björn Ottosson's linear sRGB → OKLab, as thirdparty/misc/ok_color.h computes it in f32.
// The literals are ok_color.h's, written as it writes them so that they round to the same f32.
#[allow(clippy::excessive_precision)]
fn linear_srgb_to_oklab(c: [f32; 3]) -> [f32; 3] {
    let l = 0.4122214708 * c[0] + 0.5363325363 * c[1] + 0.0514459929 * c[2];
    let m = 0.2119034982 * c[0] + 0.6806995451 * c[1] + 0.1073969566 * c[2];
    let s = 0.0883024619 * c[0] + 0.2817188376 * c[1] + 0.6299787005 * c[2];
    let (l, m, s) = (cbrtf(l), cbrtf(m), cbrtf(s));
    [
        0.2104542553 * l + 0.7936177850 * m - 0.0040720468 * s,
        1.9779984951 * l - 2.4285922050 * m + 0.4505937099 * s,
        0.0259040371 * l + 0.7827717662 * m - 0.8086757660 * s,
    ]
}

/// OKLab → linear sRGB (ok_color.h, f32).
#[allow(clippy::excessive_precision)]
fn oklab_to_linear_srgb(c: [f32; 3]) -> [f32; 3] {
    let l = c[0] + 0.3963377774 * c[1] + 0.2158037573 * c[2];
    let m = c[0] - 0.1055613458 * c[1] - 0.0638541728 * c[2];
    let s = c[0] - 0.0894841775 * c[1] - 1.2914855480 * c[2];
    let (l, m, s) = (l * l * l, m * m * m, s * s * s);
    [
        4.0767416621 * l - 3.3077115913 * m + 0.2309699292 * s,
        -1.2684380046 * l + 2.6097574011 * m - 0.3413193965 * s,
        -0.0041960863 * l - 0.7034186147 * m + 1.7076147010 * s,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(mode: i64, space: i64) -> Ramp {
        let g = Gradient {
            offsets: vec![1.0, 0.0, 0.5],
            colors: vec![[1.0, 1.0, 1.0, 1.0], [0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 1.0]],
            interpolation_mode: mode,
            interpolation_color_space: space,
        };
        Ramp::new(&g).expect("a valid gradient")
    }

    #[test]
    fn points_are_sorted_and_ends_are_held() {
        let r = ramp(0, 0);
        assert_eq!(r.color_at(-1.0), [0.0, 0.0, 0.0, 1.0]);
        assert_eq!(r.color_at(2.0), [1.0, 1.0, 1.0, 1.0]);
        assert_eq!(r.color_at(0.5), [1.0, 0.0, 0.0, 1.0]);
        assert_eq!(r.color_at(0.25), [0.5, 0.0, 0.0, 1.0]);
        assert_eq!(ramp(1, 0).color_at(0.75), [1.0, 0.0, 0.0, 1.0]);
    }

    #[test]
    fn colour_spaces_change_the_middle() {
        // Black to white at 0.5: sRGB 0.5; linear 0.5 shown in sRGB; OKLab L 0.5, linear 0.125.
        for (space, expected) in [(0, 0.5), (1, 0.735_356_6), (2, 0.388_572_9)] {
            let g = Gradient { interpolation_color_space: space, ..Gradient::default() };
            let c = Ramp::new(&g).expect("valid").color_at(0.5);
            assert!(c[..3].iter().all(|v| (v - expected).abs() < 1e-4), "space {space}: {c:?}");
            assert_eq!(c[3], 1.0);
        }
    }

    #[test]
    fn cbrtf_is_within_an_ulp_of_the_exact_root() {
        for x in [27.0f32, 0.001, 1e-40, -8.0, 0.3, 123.456, 7e30] {
            let exact = f64::from(x).cbrt();
            let got = cbrtf(x);
            assert!((f64::from(got) - exact).abs() <= f64::from(got.abs()) * 1.2e-7, "{x}: {got} vs {exact}");
        }
        assert_eq!(cbrtf(27.0), 3.0);
        assert_eq!(cbrtf(0.0), 0.0);
    }

    #[test]
    fn bad_gradients_are_refused() {
        let mut g = Gradient::default();
        g.colors.pop();
        assert!(Ramp::new(&g).unwrap_err().contains("2 offsets but 1 colors"));
        let g = Gradient { interpolation_mode: 3, ..Gradient::default() };
        assert!(Ramp::new(&g).unwrap_err().contains("interpolation_mode 3"));
        let g = Gradient { interpolation_color_space: -1, ..Gradient::default() };
        assert!(Ramp::new(&g).unwrap_err().contains("interpolation_color_space -1"));
        let g = Gradient { offsets: vec![0.0, f64::NAN], ..Gradient::default() };
        assert!(Ramp::new(&g).unwrap_err().contains("non-finite"));
    }
}

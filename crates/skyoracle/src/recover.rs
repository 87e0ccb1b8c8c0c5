//! From 8-bit frames back to linear radiance.
//!
//! The Compatibility renderer's sky pass ends with (drivers/gles3/shaders/sky.glsl and
//! tonemap_inc.glsl, linear tonemapper, exposure 1):
//!
//! ```text
//! y    = energy · COLOR                     (Environment.background_energy_multiplier)
//! out  = L2S(S2L(y))                        S2L(c) = c·(c·(0.305306011·c + 0.682171111) + 0.012522878)
//!                                           L2S(x) = max(1.055·x^0.41666667 − 0.055, 0)
//! code = round(255 · clamp(out, 0, 1))      the RGBA8 store
//! ```
//!
//! The store is monotonic in y, so each code q stands for an interval of y, [t(q), t(q+1)), where
//! t(q) is the least y stored as q or above. [`Transfer`] holds those 255 thresholds, measured on
//! the running Godot by [`crate::Oracle::start`] ([`Transfer::model`] computes them from the
//! formula instead; on SwiftShader the two differ by up to 0.12 of a code, see the crate
//! documentation). A frame taken at energy e then says COLOR ∈ [t(q)/e, t(q+1)/e), and
//! [`recover`] intersects those intervals over all brackets, per channel: the answer is the middle of
//! what is left, and the interval itself is kept so that callers can see how sure it is.

/// The 8-bit store of Godot's sky pass as 255 thresholds on y = energy · COLOR.
#[derive(Clone, Debug, PartialEq)]
pub struct Transfer {
    /// `thresholds[q]` (q = 1 ..= 255): the least y stored as code q or above. Index 0 is 0.
    thresholds: [f32; 256],
}

/// Godot's `srgb_to_linear` of tonemap_inc.glsl (an approximation, exact only at 0 and 1).
pub fn s2l(c: f64) -> f64 {
    c * (c * (c * 0.305306011 + 0.682171111) + 0.012522878)
}

/// Godot's `linear_to_srgb` of tonemap_inc.glsl.
pub fn l2s(x: f64) -> f64 {
    if x <= 0.0 { 0.0 } else { (1.055 * x.powf(0.416666667) - 0.055).max(0.0) }
}

/// The code the formula predicts for y = energy · COLOR (before any GPU rounding).
pub fn model_code(y: f64) -> u8 {
    (255.0 * l2s(s2l(y)).clamp(0.0, 1.0)).round() as u8
}

/// The y at which the formula's unrounded output, 255 · L2S(S2L(y)), equals `raw` (0 for raw ≤ 0).
pub fn model_y(raw: f64) -> f64 {
    if raw <= 0.0 {
        return 0.0;
    }
    let x = ((raw / 255.0 + 0.055) / 1.055).powf(2.4);
    // S2L is increasing for c ≥ 0; bisection is plenty for a 256-entry table.
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    while s2l(hi) < x {
        hi *= 2.0;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if s2l(mid) < x { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

impl Transfer {
    /// Thresholds from measured values: `thresholds[q - 1]` is t(q) for q = 1 ..= 255. They must
    /// increase.
    pub fn from_thresholds(thresholds: &[f32; 255]) -> Option<Self> {
        if thresholds.windows(2).any(|w| w[0] >= w[1])
            || thresholds[0] <= 0.0
            || thresholds[0].is_nan()
            || !thresholds[254].is_finite()
        {
            return None;
        }
        let mut t = [0.0; 256];
        t[1..].copy_from_slice(thresholds);
        Some(Self { thresholds: t })
    }

    /// The thresholds the formula gives (rounding half up at 255 · L2S(S2L(y)) = q − ½).
    pub fn model() -> Self {
        let mut t = [0.0; 256];
        for (q, slot) in t.iter_mut().enumerate().skip(1) {
            *slot = model_y(q as f64 - 0.5) as f32;
        }
        Self { thresholds: t }
    }

    /// t(q), the least y stored as q or above (0 for q = 0).
    pub fn threshold(&self, q: u8) -> f32 {
        self.thresholds[usize::from(q)]
    }

    /// The code this transfer stores y as.
    pub fn code(&self, y: f32) -> u8 {
        // Thresholds increase, so the count of those ≤ y is the code; NaN and y ≤ 0 give 0.
        (self.thresholds[1..].partition_point(|&t| t <= y)) as u8
    }

    /// The interval of y that code q stands for: [t(q), t(q+1)), with t(0) = 0 (negative COLOR is
    /// stored as 0 too) and t(256) = ∞.
    pub fn interval(&self, q: u8) -> (f64, f64) {
        let lo = f64::from(self.thresholds[usize::from(q)]);
        let hi = if q == 255 { f64::INFINITY } else { f64::from(self.thresholds[usize::from(q) + 1]) };
        (lo, hi)
    }
}

/// Linear radiance recovered from bracketed frames.
#[derive(Clone, Debug, PartialEq)]
pub struct Recovered {
    /// Per pixel, row 0 at the top: the recovered COLOR (middle of the interval), alpha 1.
    pub pixels: Vec<[f32; 4]>,
    /// Per pixel and channel: the greatest lower bound every bracket allows.
    pub lower: Vec<[f32; 3]>,
    /// Per pixel and channel: the least upper bound (∞ when every bracket was saturated).
    pub upper: Vec<[f32; 3]>,
    /// Per pixel and channel: how many brackets stored a code strictly between 0 and 255.
    pub valid: Vec<[u8; 3]>,
    /// Channels whose brackets contradict each other (empty intersection), which the transfer
    /// cannot explain: a frame that missed its energy, or a GPU that is not deterministic. Their
    /// value comes from the single best bracket.
    pub inconsistent: usize,
}

/// Inverts `frames` (RGBA8, row 0 at the top, one per energy) through `transfer`.
///
/// Per channel: a channel that every bracket stored as 0 is 0 (its upper bound says how dark it
/// may be); one saturated in every bracket is its lower bound; otherwise the middle of the
/// intersected interval.
pub fn recover(transfer: &Transfer, width: u32, height: u32, energies: &[f32], frames: &[Vec<u8>]) -> Recovered {
    let n = width as usize * height as usize;
    let mut out = Recovered {
        pixels: vec![[0.0, 0.0, 0.0, 1.0]; n],
        lower: vec![[0.0; 3]; n],
        upper: vec![[0.0; 3]; n],
        valid: vec![[0; 3]; n],
        inconsistent: 0,
    };
    for i in 0..n {
        for c in 0..3 {
            let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
            let mut valid = 0u8;
            let mut all_black = true;
            // The bracket with the highest unsaturated code has the narrowest interval on its own.
            let mut best: Option<(u8, f64)> = None;
            for (frame, &energy) in frames.iter().zip(energies) {
                let q = frame[4 * i + c];
                let (a, b) = transfer.interval(q);
                let e = f64::from(energy);
                let (a, b) = (a / e, b / e);
                lo = lo.max(a);
                hi = hi.min(b);
                all_black &= q == 0;
                if q > 0 && q < 255 {
                    valid = valid.saturating_add(1);
                    if best.is_none_or(|(bq, _)| q > bq) {
                        best = Some((q, 0.5 * (a + b)));
                    }
                }
            }
            let value = if lo > hi {
                out.inconsistent += 1;
                best.map_or(lo, |(_, mid)| mid)
            } else if all_black {
                0.0
            } else if hi.is_infinite() {
                lo
            } else {
                0.5 * (lo + hi)
            };
            out.pixels[i][c] = value as f32;
            out.lower[i][c] = lo as f32;
            out.upper[i][c] = hi as f32;
            out.valid[i][c] = valid;
        }
    }
    out
}

/// Samples per threshold per calibration pass (the calibration image's height).
pub(crate) const CALIBRATION_SAMPLES: u32 = 256;

/// The bisection that measures [`Transfer`] on the running Godot: for every code q, a window of
/// f32 bit patterns [lo, hi] with code(lo) < q ≤ code(hi), narrowed 255-fold per pass by rendering
/// 256 evenly spaced patterns inside it (exact values: the shader builds them with
/// `uintBitsToFloat`, so no GPU arithmetic stands between the number and the store).
pub(crate) struct Calibrator {
    /// Per q − 1: (lo, hi) bit patterns of non-negative f32 values (ordered like the values).
    windows: Vec<(u32, u32)>,
    /// Samples that decreased along a column (the store is not monotonic there).
    pub non_monotonic: usize,
    /// Pixels whose green or blue differed from red (the channels do not share the transfer).
    pub channel_mismatches: usize,
}

impl Calibrator {
    /// Windows from the formula, a code wide on either side of its threshold.
    pub fn new() -> Self {
        let windows = (1..=255u32)
            .map(|q| {
                // Below raw 0.05 everything is stored as 0 (y < 0.026); starting there rather than at
                // y = 0 saves the dark codes two passes.
                let lo = model_y((f64::from(q) - 1.5).max(0.05)) as f32;
                let hi = model_y(f64::from(q) + 0.5) as f32;
                (lo.to_bits(), hi.to_bits())
            })
            .collect();
        Self { windows, non_monotonic: 0, channel_mismatches: 0 }
    }

    /// True when every window is down to adjacent f32 values.
    pub fn done(&self) -> bool {
        self.windows.iter().all(|&(lo, hi)| hi - lo <= 1)
    }

    fn step(lo: u32, hi: u32) -> u32 {
        (hi - lo).div_ceil(CALIBRATION_SAMPLES - 1).max(1)
    }

    /// The calibration shader: column c (0 ..= 254) tests q = c + 1, FRAGCOORD row j the j-th
    /// sample of the window. The windows travel as uniforms ([`Self::uniforms`]), so that Godot
    /// compiles the shader once, not once per pass.
    pub fn shader() -> String {
        format!(
            "shader_type sky;\n\
             uniform uint LO[255];\n\
             uniform uint STEP[255];\n\
             uniform uint HI[255];\n\
             void sky() {{\n\
             \tint c = clamp(int(FRAGCOORD.x), 0, 254);\n\
             \tuint j = uint(clamp(int(FRAGCOORD.y), 0, {}));\n\
             \tCOLOR = vec3(uintBitsToFloat(min(LO[c] + j * STEP[c], HI[c])));\n\
             }}\n",
            CALIBRATION_SAMPLES - 1
        )
    }

    /// The windows of the next pass, as the uniforms of [`Self::shader`]. The bit patterns of
    /// non-negative finite f32 values are below 2³¹, so they fit Godot's int arrays.
    pub fn uniforms(&self) -> Vec<(String, Parameter)> {
        let list = |f: &dyn Fn(u32, u32) -> u32| {
            Parameter::Value(UniformValue::IntArray(self.windows.iter().map(|&(lo, hi)| f(lo, hi) as i32).collect()))
        };
        vec![
            ("LO".to_string(), list(&|lo, _| lo)),
            ("STEP".to_string(), list(&|lo, hi| Self::step(lo, hi))),
            ("HI".to_string(), list(&|_, hi| hi)),
        ]
    }

    /// Narrows every window from one pass's frame (255 × 64 RGBA8, row 0 at the top).
    /// `fragcoord_y_down` says whether FRAGCOORD.y grows toward the bottom of the image.
    pub fn update(&mut self, frame: &[u8], fragcoord_y_down: bool) {
        let width = 255usize;
        let rows = CALIBRATION_SAMPLES as usize;
        for (c, window) in self.windows.iter_mut().enumerate() {
            let (lo, hi) = *window;
            if hi - lo <= 1 {
                continue;
            }
            let q = c as u8 + 1;
            let step = Self::step(lo, hi);
            let sample = |j: usize| (lo + j as u32 * step).min(hi);
            let code = |j: usize| {
                let row = if fragcoord_y_down { j } else { rows - 1 - j };
                &frame[4 * (row * width + c)..4 * (row * width + c) + 3]
            };
            let mut previous = 0u8;
            let mut first_at_or_above = None;
            for j in 0..rows {
                let rgb = code(j);
                if rgb[1] != rgb[0] || rgb[2] != rgb[0] {
                    self.channel_mismatches += 1;
                }
                if rgb[0] < previous {
                    self.non_monotonic += 1;
                }
                previous = rgb[0];
                if first_at_or_above.is_none() && rgb[0] >= q {
                    first_at_or_above = Some(j);
                }
            }
            *window = match first_at_or_above {
                // The threshold lies above the window: look in the next octave up.
                None => (hi, (f32::from_bits(hi) * 2.0).to_bits()),
                // The window's low end is already at or above q: look in the octave below.
                Some(0) => ((f32::from_bits(lo) * 0.5).to_bits(), lo),
                Some(j) => (sample(j - 1), sample(j)),
            };
        }
    }

    /// The measured thresholds, once [`Self::done`].
    pub fn thresholds(&self) -> [f32; 255] {
        let mut t = [0.0; 255];
        for (slot, &(_, hi)) in t.iter_mut().zip(&self.windows) {
            *slot = f32::from_bits(hi);
        }
        t
    }
}

use crate::Parameter;
use skycore::UniformValue;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn model_round_trips() {
        let t = Transfer::model();
        for q in 1..=255u8 {
            let y = t.threshold(q);
            assert_eq!(model_code(f64::from(y) * 1.000001), q, "q {q}");
            assert_eq!(t.code(y), q);
            assert_eq!(t.code(y * 0.9999), q - 1);
        }
        // The example of the issue: 0.5 at energy 1 is stored as 128.
        assert_eq!(model_code(0.5), 128);
        assert_eq!(t.code(0.5), 128);
    }

    /// Frames synthesized through the model recover every value to within the model's own
    /// interval width, and constant black and saturated pixels come out as documented.
    #[test]
    fn recovers_synthetic_frames() {
        let t = Transfer::model();
        let energies: Vec<f32> = (-12..=14).map(|k| 2f32.powi(k)).collect();
        let truth = [1e-5f32, 3e-4, 0.01, 0.5, 1.0, 7.5, 100.0, 3000.0, 0.0, 1e6];
        let frames: Vec<Vec<u8>> = energies
            .iter()
            .map(|&e| truth.iter().flat_map(|&v| [t.code(v * e), t.code(v * e), t.code(v * e), 255]).collect())
            .collect();
        let r = recover(&t, truth.len() as u32, 1, &energies, &frames);
        assert_eq!(r.inconsistent, 0);
        for (i, &v) in truth.iter().enumerate().take(8) {
            let got = r.pixels[i][0];
            assert!((got - v).abs() <= 0.005 * v, "{v}: {got}");
            assert!(r.lower[i][0] <= v && v < r.upper[i][0]);
            assert!(r.valid[i][0] > 0);
        }
        assert_eq!(r.pixels[8][0], 0.0);
        assert_eq!(r.valid[8][0], 0);
        assert!(r.upper[9][0].is_infinite() && r.pixels[9][0] == r.lower[9][0]);
    }

    #[test]
    fn calibrator_converges_on_the_model() {
        let t = Transfer::model();
        let mut cal = Calibrator::new();
        for _ in 0..10 {
            if cal.done() {
                break;
            }
            // Render the pass on the CPU, FRAGCOORD.y growing upward as in GL.
            let rows = CALIBRATION_SAMPLES as usize;
            let mut frame = vec![0u8; 255 * rows * 4];
            for (c, &(lo, hi)) in cal.windows.iter().enumerate() {
                let step = Calibrator::step(lo, hi);
                for j in 0..rows {
                    let y = f32::from_bits((lo + j as u32 * step).min(hi));
                    let row = rows - 1 - j;
                    let q = t.code(y);
                    frame[4 * (row * 255 + c)..4 * (row * 255 + c) + 4].copy_from_slice(&[q, q, q, 255]);
                }
            }
            cal.update(&frame, false);
        }
        assert!(cal.done());
        let measured = Transfer::from_thresholds(&cal.thresholds()).expect("increasing");
        assert_eq!(measured, t);
        assert_eq!((cal.non_monotonic, cal.channel_mismatches), (0, 0));
    }
}

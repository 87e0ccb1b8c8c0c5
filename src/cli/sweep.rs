//! What `bench` and `stress` share: loading a Freeman-compatible shader, filling its material
//! from skyref's parameters, error statistics of an f32 image against an f64 truth, the
//! preview's tone map, and PNG plots drawn with plotters without system fonts.

use super::scene::{LoadedShader, load_shader};
use skyref::FreemanParams;
use std::collections::BTreeSet;
use std::path::Path;
use std::process::ExitCode;

/// Floor of the relative error, as in `gdsky compare` and the pixel tests: a channel's error is
/// |a − b| / max(|b|, floor), so the black night sky is not divided by zero.
pub const FLOOR: f64 = 1e-4;

/// The uniform names of the Freeman sky, in declaration order.
pub fn freeman_names() -> Vec<&'static str> {
    let mut params = FreemanParams::default();
    params.uniforms_mut().iter().map(|(name, _)| *name).collect()
}

/// Loads FILE (the bundled Freeman sky without one) and checks that it is Freeman-compatible:
/// exactly the Freeman sky's uniforms, with the same types (and optionally freeman_lut's
/// `transmittance_table`, which the commands bake from these uniforms). skyref models the Freeman sky's
/// integral, so it is the truth only for such a shader. Exit 1 when it is not (or is invalid),
/// 2 when it cannot be read.
pub fn load_freeman(file: Option<&Path>) -> Result<LoadedShader, ExitCode> {
    let loaded = load_shader(file)?;
    let shader = loaded.front.shader.as_ref().ok_or(ExitCode::from(1))?;
    let name = file.map(|f| f.display().to_string()).unwrap_or_else(|| super::scene::BUNDLED_NAME.to_string());
    // freeman_lut's table is an input of the same model, baked from these uniforms
    // (LoadedShader::bake_tables), not a uniform skyref lacks.
    let have: BTreeSet<&str> =
        shader.uniforms.iter().map(|u| u.name.as_str()).filter(|n| *n != super::scene::TRANSMITTANCE_TABLE).collect();
    let want: BTreeSet<&str> = freeman_names().into_iter().collect();
    if have != want {
        let missing: Vec<_> = want.difference(&have).copied().collect();
        let extra: Vec<_> = have.difference(&want).copied().collect();
        eprintln!(
            "error: {name} is not Freeman-compatible: skyref, the truth, models the Freeman sky's 22 uniforms \
             (missing: {}; not in the Freeman sky: {})",
            list_or_none(&missing),
            list_or_none(&extra)
        );
        return Err(ExitCode::from(1));
    }
    material(&loaded, &FreemanParams::default()).map_err(|err| {
        eprintln!("error: {name} is not Freeman-compatible: {err}");
        ExitCode::from(1)
    })?;
    // The uniforms' defaults come from skyref on both sides; say so when FILE's own differ.
    let own = skyrun::material_with_defaults(shader, &loaded.lowered, &[]).unwrap_or_default();
    if material(&loaded, &FreemanParams::default()).ok().as_deref() != Some(own.as_slice()) {
        eprintln!(
            "note: {name}'s uniform defaults differ from the Freeman sky's; both the shader and skyref use the \
             Freeman sky's (skyref's) values"
        );
    }
    Ok(loaded)
}

fn list_or_none(names: &[&str]) -> String {
    if names.is_empty() { "none".into() } else { names.join(", ") }
}

/// The material block of a Freeman-compatible shader from skyref's parameters, so that the
/// GPU and skyref start from the same (f32-rounded) values.
pub fn material(loaded: &LoadedShader, params: &FreemanParams) -> Result<Vec<u8>, skyrun::MaterialError> {
    skyrun::material_bytes(&loaded.lowered, &skyrun::freeman_values(params))
}

/// The preview's tone map per channel, in f64: `(1 − exp(−0.5 L))^(1/2.2)`, negative L as 0.
pub fn tonemap(l: f64) -> f64 {
    (1.0 - (-0.5 * l.max(0.0)).exp()).powf(1.0 / 2.2)
}

/// Error statistics of an f32 image (the one under test) against an f64 truth, over RGB.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorStats {
    /// Largest relative error over the channels where both images are finite.
    pub max: f64,
    /// 99.9th percentile (nearest rank).
    pub p999: f64,
    /// 99th percentile (nearest rank).
    pub p99: f64,
    /// Mean relative error.
    pub mean: f64,
    /// Mean absolute error after the preview's tone map (each channel in [0, 1]).
    pub mean_tonemapped: f64,
    /// Channels that are NaN in the image under test.
    pub nan: usize,
    /// Channels that are ±∞ in the image under test.
    pub inf: usize,
    /// Channels where the truth itself is NaN or ±∞ (whatever the image under test; left out
    /// of the statistics).
    pub truth_nonfinite: usize,
    /// The worst channel: pixel index and channel (0 R, 1 G, 2 B); `None` when nothing finite
    /// was compared.
    pub worst: Option<(usize, usize)>,
    /// Channels compared.
    pub channels: usize,
}

/// Compares `test` with `truth` channel by channel (RGB): |a − b| / max(|b|, [`FLOOR`]).
/// A channel counts in `nan`/`inf` when the image under test is non-finite there (whatever the
/// truth), in `truth_nonfinite` when the truth is; neither enters the error statistics.
pub fn error_stats(test: &[[f32; 4]], truth: &[[f64; 4]]) -> ErrorStats {
    let mut s = ErrorStats::default();
    let mut rels = Vec::with_capacity(test.len() * 3);
    let mut tonemapped = 0.0;
    for (i, (a, b)) in test.iter().zip(truth).enumerate() {
        for c in 0..3 {
            let (x, y) = (f64::from(a[c]), b[c]);
            s.truth_nonfinite += usize::from(!y.is_finite());
            if x.is_nan() {
                s.nan += 1;
            } else if x.is_infinite() {
                s.inf += 1;
            } else if y.is_finite() {
                let rel = (x - y).abs() / y.abs().max(FLOOR);
                if s.worst.is_none() || rel > s.max {
                    s.max = rel;
                    s.worst = Some((i, c));
                }
                rels.push(rel);
                tonemapped += (tonemap(x) - tonemap(y)).abs();
            }
        }
    }
    s.channels = rels.len();
    if rels.is_empty() {
        return s;
    }
    s.mean = rels.iter().sum::<f64>() / rels.len() as f64;
    s.mean_tonemapped = tonemapped / rels.len() as f64;
    rels.sort_by(f64::total_cmp);
    let rank = |q: f64| rels[((q * rels.len() as f64).ceil() as usize).clamp(1, rels.len()) - 1];
    s.p999 = rank(0.999);
    s.p99 = rank(0.99);
    s
}

/// Widens an f32 image to f64.
pub fn widen(image: &[[f32; 4]]) -> Vec<[f64; 4]> {
    image.iter().map(|p| p.map(f64::from)).collect()
}

/// Rounds an f64 image to f32 (for EXRs and heatmaps).
pub fn narrow(image: &[[f64; 4]]) -> Vec<[f32; 4]> {
    image.iter().map(|p| p.map(|c| c as f32)).collect()
}

/// Registers the font plotters draws every label with (once per process). plotters is built
/// with `ab_glyph` and no font-kit, so it never asks fontconfig: a bare machine without fonts
/// draws the same labels. The font is Ubuntu Light (Ubuntu Font Licence), shipped as bytes in
/// `epaint_default_fonts`.
pub fn register_fonts() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        use plotters::style::{FontStyle, register_font};
        for family in ["sans-serif", "serif", "monospace"] {
            for style in [FontStyle::Normal, FontStyle::Bold] {
                // The bytes are a valid TrueType font (a constant of the crate); a failure
                // would only mean labels are missing, which drawing reports as an error.
                let _ = register_font(family, style, epaint_default_fonts::UBUNTU_LIGHT);
            }
        }
    });
}

/// Encodes an 8-bit RGB buffer (what plotters' bitmap backend drew) as PNG and writes it
/// atomically.
pub fn write_rgb_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), String> {
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(|e| format!("cannot encode {}: {e}", path.display()))?;
        writer.write_image_data(rgb).map_err(|e| format!("cannot encode {}: {e}", path.display()))?;
        writer.finish().map_err(|e| format!("cannot encode {}: {e}", path.display()))?;
    }
    super::write_file(path, &bytes)
}

/// A progress bar on stderr in the style of `gdsky demo` (indicatif hides it when stderr is
/// not a terminal).
pub fn progress_bar(len: u64) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} [{bar:30}] {pos}/{len} {elapsed_precise} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar
}

/// Formats a relative error compactly (`1.23e-4`), `—` for nothing measured.
pub fn sci(value: f64, measured: bool) -> String {
    if measured { format!("{value:.2e}") } else { "—".into() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_stats_counts_non_finite_apart() {
        let test = [[1.1, f32::NAN, f32::INFINITY, 0.0], [1.0, 1.0, 1.0, 0.0]];
        let truth = [[1.0, 1.0, 1.0, 0.0], [1.0, f64::NAN, 1.0, 0.0]];
        let s = error_stats(&test, &truth);
        assert_eq!((s.nan, s.inf, s.truth_nonfinite, s.channels), (1, 1, 1, 3));
        let both = error_stats(&[[f32::NAN; 4]], &[[f64::NAN; 4]]);
        assert_eq!((both.nan, both.truth_nonfinite, both.channels), (3, 3, 0));
        assert!((s.max - 0.1).abs() < 1e-6);
        assert_eq!(s.worst, Some((0, 0)));
        assert!((s.mean - 0.1 / 3.0).abs() < 1e-6);
    }

    #[test]
    fn tonemap_matches_the_preview() {
        assert_eq!(tonemap(0.0), 0.0);
        assert_eq!(tonemap(-3.0), 0.0);
        assert!((tonemap(2.0) - (1.0 - (-1.0f64).exp()).powf(1.0 / 2.2)).abs() < 1e-12);
    }

    #[test]
    fn freeman_has_22_uniforms() {
        assert_eq!(freeman_names().len(), 22);
    }
}

//! What `bench` and `stress` share: loading a Freeman-compatible shader, filling its material
//! from skyref's parameters, error statistics of an f32 image against an f64 truth, the
//! preview's tone map, and PNG plots drawn with plotters without system fonts.

use super::scene::{LoadedShader, load_shader};
use skyref::FreemanParams;
use std::collections::BTreeSet;
use std::path::Path;
use std::process::ExitCode;

pub use gdsky::measure::stats::{ErrorStats, FLOOR, error_stats, narrow, widen};

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
    let loaded = load_shader(file, &gdsky::measure::any::measuring_options())?;
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
    fn freeman_has_22_uniforms() {
        assert_eq!(freeman_names().len(), 22);
    }
}

//! Plots drawn in memory with plotters, without system fonts, and written as PNG.

use crate::engine::Error;
use std::path::Path;

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
pub fn write_rgb_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), Error> {
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer =
            encoder.write_header().map_err(|e| Error::environment(format!("cannot encode {}: {e}", path.display())))?;
        writer
            .write_image_data(rgb)
            .map_err(|e| Error::environment(format!("cannot encode {}: {e}", path.display())))?;
        writer.finish().map_err(|e| Error::environment(format!("cannot encode {}: {e}", path.display())))?;
    }
    crate::engine::write_file(path, &bytes)
}

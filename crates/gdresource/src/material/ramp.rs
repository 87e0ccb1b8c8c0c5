//! A `GradientTexture1D`, `GradientTexture2D` or `CurveTexture` section (with its `Gradient` or
//! `Curve`) mapped onto [`crate::generated::RampTexture`], property by property with Godot's names,
//! every value checked for its kind where it is written (the helpers of [`super::noise`]).

use super::noise::{boolean, float, gradient, int, numbers, wrong};
use crate::codes;
use crate::generated::{
    Curve, CurvePoint, CurveTexture, CurveXyzTexture, GradientTexture1D, GradientTexture2D, RampTexture,
};
use crate::text::{Entry, Section, ValueKind};
use gdshader::diag::{Diagnostic, FileId};

/// A `Vector2` property.
fn vector2(file: FileId, e: &Entry) -> Result<[f64; 2], Diagnostic> {
    match numbers(&e.value, &["Vector2", "Vector2i"]) {
        Some(v) if v.len() == 2 => Ok([v[0], v[1]]),
        _ => Err(wrong(file, e, "a Vector2")),
    }
}

/// The texture of class `class` (in `file`), its `gradient` or curves (`curve`, or a
/// `CurveXYZTexture`'s `curve_x`, `curve_y`, `curve_z`) already followed to their sections. A gradient texture without a gradient gets Godot's new default one only when the
/// editor made it; a file without one makes no image in Godot, which the generation refuses.
pub fn ramp_texture(
    file: FileId,
    class: &str,
    texture: &Section,
    gradient_section: Option<&Section>,
    curve_sections: &[Option<Section>; 3],
) -> Result<RampTexture, Diagnostic> {
    let curve_section = curve_sections[0].as_ref();
    let g = gradient_section.map(|s| gradient(file, s)).transpose()?;
    Ok(match class {
        "GradientTexture1D" => {
            let mut t = GradientTexture1D { gradient: g, ..Default::default() };
            for e in &texture.properties {
                match e.name.as_str() {
                    "width" => t.width = int(file, e)?,
                    "use_hdr" => t.use_hdr = boolean(file, e)?,
                    _ => {}
                }
            }
            RampTexture::Gradient1D(t)
        }
        "GradientTexture2D" => {
            let mut t = GradientTexture2D { gradient: g, ..Default::default() };
            for e in &texture.properties {
                match e.name.as_str() {
                    "width" => t.width = int(file, e)?,
                    "height" => t.height = int(file, e)?,
                    "use_hdr" => t.use_hdr = boolean(file, e)?,
                    "fill" => t.fill = int(file, e)?,
                    "fill_from" => t.fill_from = vector2(file, e)?,
                    "fill_to" => t.fill_to = vector2(file, e)?,
                    "repeat" => t.repeat = int(file, e)?,
                    _ => {}
                }
            }
            RampTexture::Gradient2D(t)
        }
        "CurveXYZTexture" => {
            let mut curves = [None, None, None];
            for (c, s) in curves.iter_mut().zip(curve_sections) {
                *c = s.as_ref().map(|s| curve(file, s)).transpose()?;
            }
            let mut t = CurveXyzTexture { curves, ..Default::default() };
            for e in &texture.properties {
                if e.name == "width" {
                    t.width = int(file, e)?;
                }
            }
            RampTexture::CurveXyz(t)
        }
        _ => {
            let mut t =
                CurveTexture { curve: curve_section.map(|s| curve(file, s)).transpose()?, ..Default::default() };
            for e in &texture.properties {
                match e.name.as_str() {
                    "width" => t.width = int(file, e)?,
                    "texture_mode" => t.texture_mode = int(file, e)?,
                    _ => {}
                }
            }
            RampTexture::Curve(t)
        }
    })
}

/// A `Curve` section: `_data` (position, left and right tangent, left and right mode per point,
/// stored as they are, as Godot's `set_data` does), `_limits` or the older `min_value` /
/// `max_value`, and `bake_resolution`.
pub fn curve(file: FileId, section: &Section) -> Result<Curve, Diagnostic> {
    let mut c = Curve::default();
    for e in &section.properties {
        match e.name.as_str() {
            "min_value" => c.min_value = float(file, e)?,
            "max_value" => c.max_value = float(file, e)?,
            "min_domain" => c.min_domain = float(file, e)?,
            "max_domain" => c.max_domain = float(file, e)?,
            "bake_resolution" => c.bake_resolution = int(file, e)?,
            "_limits" => {
                let v = match &e.value.kind {
                    ValueKind::Array(items) => items.iter().map(|i| i.number()).collect::<Option<Vec<f64>>>(),
                    _ => None,
                };
                match v.as_deref() {
                    Some(&[min_value, max_value, min_domain, max_domain]) => {
                        (c.min_value, c.max_value, c.min_domain, c.max_domain) =
                            (min_value, max_value, min_domain, max_domain)
                    }
                    _ => {
                        return Err(wrong(
                            file,
                            e,
                            "an array of 4 numbers [min_value, max_value, min_domain, max_domain]",
                        ));
                    }
                }
            }
            "_data" => {
                let ValueKind::Array(items) = &e.value.kind else {
                    return Err(wrong(file, e, "an array"));
                };
                if items.len() % 5 != 0 {
                    return Err(wrong(file, e, "an array of 5 values per point"));
                }
                let mut points = Vec::with_capacity(items.len() / 5);
                for p in items.chunks_exact(5) {
                    let position = match numbers(&p[0], &["Vector2", "Vector2i"]) {
                        Some(v) if v.len() == 2 => [v[0], v[1]],
                        _ => return Err(point_error(file, &p[0], "a Vector2 position")),
                    };
                    let tangent = |v: &super::Value| v.number().ok_or_else(|| point_error(file, v, "a number"));
                    let mode = |v: &super::Value| match v.kind {
                        ValueKind::Int(m @ 0..=1) => Ok(m),
                        _ => Err(point_error(file, v, "a tangent mode, 0 (free) or 1 (linear)")),
                    };
                    points.push(CurvePoint {
                        position,
                        left_tangent: tangent(&p[1])?,
                        right_tangent: tangent(&p[2])?,
                        left_mode: mode(&p[3])?,
                        right_mode: mode(&p[4])?,
                    });
                }
                c.points = points;
            }
            _ => {}
        }
    }
    Ok(c)
}

fn point_error(file: FileId, value: &super::Value, expected: &str) -> Diagnostic {
    let m = format!("a curve point's value must be {expected}, not {}", value.describe());
    Diagnostic::error(codes::BAD_NOISE, m.clone()).with_primary(file, value.span.clone(), m)
}

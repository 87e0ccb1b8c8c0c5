//! A `NoiseTexture2D` or `NoiseTexture3D` section (with its `FastNoiseLite` and `Gradient`)
//! mapped onto [`crate::generated::NoiseTexture2D`] or [`crate::generated::NoiseTexture3D`]: property by property, Godot's names, every value checked
//! for its kind where it is written. Properties gdsky does not use (`resource_name`, …) are
//! skipped, as Godot's editor-only ones are.

use crate::codes;
use crate::generated::{FastNoiseLite, Gradient, NoiseTexture2D, NoiseTexture3D};
use crate::text::{Entry, Section, Value, ValueKind};
use gdshader::diag::{Diagnostic, FileId};

/// A property's value of the wrong kind, located.
pub(super) fn wrong(file: FileId, entry: &Entry, expected: &str) -> Diagnostic {
    let m = format!("`{}` must be {expected}, not {}", entry.name, entry.value.describe());
    Diagnostic::error(codes::BAD_NOISE, m.clone()).with_primary(file, entry.value.span.clone(), m)
}

pub(super) fn int(file: FileId, e: &Entry) -> Result<i64, Diagnostic> {
    match e.value.kind {
        ValueKind::Int(i) => Ok(i),
        _ => Err(wrong(file, e, "an int")),
    }
}

pub(super) fn float(file: FileId, e: &Entry) -> Result<f64, Diagnostic> {
    e.value.number().ok_or_else(|| wrong(file, e, "a number"))
}

pub(super) fn boolean(file: FileId, e: &Entry) -> Result<bool, Diagnostic> {
    match e.value.kind {
        ValueKind::Bool(b) => Ok(b),
        _ => Err(wrong(file, e, "true or false")),
    }
}

/// The numbers of a constructor named one of `names`.
pub(super) fn numbers(value: &Value, names: &[&str]) -> Option<Vec<f64>> {
    match &value.kind {
        ValueKind::Constructor { name, args } if names.contains(&name.as_str()) => {
            args.iter().map(Value::number).collect()
        }
        _ => None,
    }
}

/// The `NoiseTexture2D` of `texture` (in `file`), its `noise` and `color_ramp` already
/// followed to their sections.
pub fn noise_texture(
    file: FileId,
    texture: &Section,
    noise: Option<&Section>,
    color_ramp: Option<&Section>,
) -> Result<NoiseTexture2D, Diagnostic> {
    let mut t = NoiseTexture2D::default();
    for e in &texture.properties {
        match e.name.as_str() {
            "width" => t.width = int(file, e)?,
            "height" => t.height = int(file, e)?,
            "invert" => t.invert = boolean(file, e)?,
            "in_3d_space" => t.in_3d_space = boolean(file, e)?,
            "generate_mipmaps" => t.generate_mipmaps = boolean(file, e)?,
            "seamless" => t.seamless = boolean(file, e)?,
            "seamless_blend_skirt" => t.seamless_blend_skirt = float(file, e)?,
            "as_normal_map" => t.as_normal_map = boolean(file, e)?,
            "bump_strength" => t.bump_strength = float(file, e)?,
            "normalize" => t.normalize = boolean(file, e)?,
            _ => {}
        }
    }
    t.noise = noise.map(|s| fast_noise_lite(file, s)).transpose()?;
    t.color_ramp = color_ramp.map(|s| gradient(file, s)).transpose()?;
    Ok(t)
}

/// The `NoiseTexture3D` of `texture` (in `file`), its `noise` and `color_ramp` already
/// followed to their sections.
pub fn noise_texture_3d(
    file: FileId,
    texture: &Section,
    noise: Option<&Section>,
    color_ramp: Option<&Section>,
) -> Result<NoiseTexture3D, Diagnostic> {
    let mut t = NoiseTexture3D::default();
    for e in &texture.properties {
        match e.name.as_str() {
            "width" => t.width = int(file, e)?,
            "height" => t.height = int(file, e)?,
            "depth" => t.depth = int(file, e)?,
            "invert" => t.invert = boolean(file, e)?,
            "seamless" => t.seamless = boolean(file, e)?,
            "seamless_blend_skirt" => t.seamless_blend_skirt = float(file, e)?,
            "normalize" => t.normalize = boolean(file, e)?,
            _ => {}
        }
    }
    t.noise = noise.map(|s| fast_noise_lite(file, s)).transpose()?;
    t.color_ramp = color_ramp.map(|s| gradient(file, s)).transpose()?;
    Ok(t)
}

fn fast_noise_lite(file: FileId, section: &Section) -> Result<FastNoiseLite, Diagnostic> {
    let mut n = FastNoiseLite::default();
    for e in &section.properties {
        match e.name.as_str() {
            "noise_type" => n.noise_type = int(file, e)?,
            "seed" => n.seed = int(file, e)?,
            "frequency" => n.frequency = float(file, e)?,
            "offset" => {
                let v = numbers(&e.value, &["Vector3", "Vector3i"]).ok_or_else(|| wrong(file, e, "a Vector3"))?;
                n.offset = [v[0], v[1], v[2]];
            }
            "fractal_type" => n.fractal_type = int(file, e)?,
            "fractal_octaves" => n.fractal_octaves = int(file, e)?,
            "fractal_lacunarity" => n.fractal_lacunarity = float(file, e)?,
            "fractal_gain" => n.fractal_gain = float(file, e)?,
            "fractal_weighted_strength" => n.fractal_weighted_strength = float(file, e)?,
            "fractal_ping_pong_strength" => n.fractal_ping_pong_strength = float(file, e)?,
            "cellular_distance_function" => n.cellular_distance_function = int(file, e)?,
            "cellular_jitter" => n.cellular_jitter = float(file, e)?,
            "cellular_return_type" => n.cellular_return_type = int(file, e)?,
            "domain_warp_enabled" => n.domain_warp_enabled = boolean(file, e)?,
            "domain_warp_type" => n.domain_warp_type = int(file, e)?,
            "domain_warp_amplitude" => n.domain_warp_amplitude = float(file, e)?,
            "domain_warp_frequency" => n.domain_warp_frequency = float(file, e)?,
            "domain_warp_fractal_type" => n.domain_warp_fractal_type = int(file, e)?,
            "domain_warp_fractal_octaves" => n.domain_warp_fractal_octaves = int(file, e)?,
            "domain_warp_fractal_lacunarity" => n.domain_warp_fractal_lacunarity = float(file, e)?,
            "domain_warp_fractal_gain" => n.domain_warp_fractal_gain = float(file, e)?,
            _ => {}
        }
    }
    Ok(n)
}

pub(super) fn gradient(file: FileId, section: &Section) -> Result<Gradient, Diagnostic> {
    let mut g = Gradient::default();
    for e in &section.properties {
        match e.name.as_str() {
            "offsets" => {
                g.offsets = numbers(&e.value, &["PackedFloat32Array", "PackedFloat64Array", "PoolRealArray"])
                    .ok_or_else(|| wrong(file, e, "a PackedFloat32Array"))?;
            }
            "colors" => {
                let v = numbers(&e.value, &["PackedColorArray", "PoolColorArray"])
                    .ok_or_else(|| wrong(file, e, "a PackedColorArray"))?;
                g.colors = v.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
            }
            "interpolation_mode" => g.interpolation_mode = int(file, e)?,
            "interpolation_color_space" => g.interpolation_color_space = int(file, e)?,
            _ => {}
        }
    }
    if g.offsets.len() != g.colors.len() {
        let span = section
            .property("colors")
            .or(section.property("offsets"))
            .map_or(section.span.clone(), |e| e.value.span.clone());
        let m = format!(
            "the gradient has {} offsets and {} colors: each point needs both",
            g.offsets.len(),
            g.colors.len()
        );
        return Err(Diagnostic::error(codes::BAD_NOISE, m.clone()).with_primary(file, span, m));
    }
    Ok(g)
}

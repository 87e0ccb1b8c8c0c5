//! The material uniform block (bind group 1, binding 0) as bytes.
//!
//! Offsets are not computed here: they come from the lowering ([`gdsky_naga::Lowered::uniforms`],
//! the same numbers the reflection JSON holds), so the bytes follow whatever layout naga gave
//! the block. Each value is checked against the uniform's shader type before it is written.

use crate::builtins::{put_f32s, put_i32, put_u32};
use gdshader::check::types::{Scalar, Type};
use gdsky_naga::{Lowered, MATERIAL_GROUP};
use std::fmt;

/// A value for one non-array, non-sampler uniform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum UniformValue {
    /// `float`
    Float(f32),
    /// `int`
    Int(i32),
    /// `uint`
    UInt(u32),
    /// `bool` (travels as a `u32`, 0 or 1)
    Bool(bool),
    /// `vec2`
    Vec2([f32; 2]),
    /// `vec3`
    Vec3([f32; 3]),
    /// `vec4`
    Vec4([f32; 4]),
}

impl UniformValue {
    /// The shader type this value fits.
    fn shader_type(&self) -> Type {
        match self {
            UniformValue::Float(_) => Type::FLOAT,
            UniformValue::Int(_) => Type::INT,
            UniformValue::UInt(_) => Type::UINT,
            UniformValue::Bool(_) => Type::BOOL,
            UniformValue::Vec2(_) => Type::Vector(Scalar::Float, 2),
            UniformValue::Vec3(_) => Type::Vector(Scalar::Float, 3),
            UniformValue::Vec4(_) => Type::Vector(Scalar::Float, 4),
        }
    }

    /// Writes the value at `offset`.
    fn write(&self, bytes: &mut [u8], offset: usize) {
        match *self {
            UniformValue::Float(v) => put_f32s(bytes, offset, &[v]),
            UniformValue::Int(v) => put_i32(bytes, offset, v),
            UniformValue::UInt(v) => put_u32(bytes, offset, v),
            UniformValue::Bool(v) => put_u32(bytes, offset, u32::from(v)),
            UniformValue::Vec2(v) => put_f32s(bytes, offset, &v),
            UniformValue::Vec3(v) => put_f32s(bytes, offset, &v),
            UniformValue::Vec4(v) => put_f32s(bytes, offset, &v),
        }
    }
}

/// Why [`material_bytes`] could not place a value.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialError {
    /// The lowered shader has no uniform of that name in its material block (a typo, a
    /// uniform baked into a constant, or a `global uniform`, which lives in group 3).
    NoSuchUniform(String),
    /// The value's type is not the uniform's.
    TypeMismatch {
        /// The uniform.
        name: String,
        /// The uniform's type in the shader.
        expected: String,
        /// The type of the value given.
        given: String,
    },
}

impl fmt::Display for MaterialError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MaterialError::NoSuchUniform(name) => {
                write!(f, "the material block has no uniform `{name}`")
            }
            MaterialError::TypeMismatch { name, expected, given } => {
                write!(f, "uniform `{name}` is `{expected}` in the shader, but a `{given}` value was given")
            }
        }
    }
}

impl std::error::Error for MaterialError {}

/// The material block of `lowered` (`lowered.material_size` bytes) with each `(name, value)`
/// written at the uniform's offset. Uniforms not listed stay zero (the shader's defaults are
/// not applied). Empty when the shader has no material block.
pub fn material_bytes(lowered: &Lowered, values: &[(&str, UniformValue)]) -> Result<Vec<u8>, MaterialError> {
    let mut bytes = vec![0u8; lowered.material_size as usize];
    for (name, value) in values {
        let slot = lowered
            .uniforms
            .get(*name)
            .filter(|slot| slot.group == MATERIAL_GROUP)
            .ok_or_else(|| MaterialError::NoSuchUniform((*name).to_owned()))?;
        let given = value.shader_type();
        if slot.ty != given {
            return Err(MaterialError::TypeMismatch {
                name: (*name).to_owned(),
                expected: slot.ty.display(&[]).to_string(),
                given: given.display(&[]).to_string(),
            });
        }
        value.write(&mut bytes, slot.offset as usize);
    }
    Ok(bytes)
}

/// The 22 uniforms of `fixtures/freeman_sky.gdshader` from skyref's parameters, with the
/// shader's names and types, rounded to f32 as a host fills the buffer.
pub fn freeman_values(params: &skyref::FreemanParams) -> Vec<(&'static str, UniformValue)> {
    use UniformValue::{Float, Int, Vec3};
    let f = |v: f64| Float(v as f32);
    let v3 = |v: glam::DVec3| Vec3([v.x as f32, v.y as f32, v.z as f32]);
    let p = params;
    vec![
        ("sun_intensity", f(p.sun_intensity)),
        ("sun_wavelengths", v3(p.sun_wavelengths)),
        ("rayleigh_scale_height", f(p.rayleigh_scale_height)),
        ("rayleigh_multi_scattering", f(p.rayleigh_multi_scattering)),
        ("mie_scale_height", f(p.mie_scale_height)),
        ("mie_scattering", f(p.mie_scattering)),
        ("mie_albedo", f(p.mie_albedo)),
        ("mie_g_forward", f(p.mie_g_forward)),
        ("mie_g_backward", f(p.mie_g_backward)),
        ("mie_weight", f(p.mie_weight)),
        ("mie_multi_scattering", f(p.mie_multi_scattering)),
        ("multiscattering_mie_g_forward", f(p.multiscattering_mie_g_forward)),
        ("multiscattering_mie_g_backward", f(p.multiscattering_mie_g_backward)),
        ("multiscattering_mie_weight", f(p.multiscattering_mie_weight)),
        ("ozone_center", f(p.ozone_center)),
        ("ozone_width", f(p.ozone_width)),
        ("planet_radius", f(p.planet_radius)),
        ("atmosphere_height", f(p.atmosphere_height)),
        ("base_altitude", f(p.base_altitude)),
        ("ground_color", v3(p.ground_color)),
        ("view_samples", Int(p.view_samples)),
        ("sun_samples", Int(p.sun_samples)),
    ]
}

/// The material block of a lowered Freeman sky filled from `params`. Uniforms baked into
/// constants (`gdsky_naga::lower_with`) are not in the block and are skipped.
///
/// # Panics
///
/// If `lowered` is not the Freeman sky: a uniform of the same name with another type.
pub fn freeman_material(lowered: &Lowered, params: &skyref::FreemanParams) -> Vec<u8> {
    let values: Vec<_> =
        freeman_values(params).into_iter().filter(|(name, _)| lowered.uniforms.contains_key(*name)).collect();
    material_bytes(lowered, &values).unwrap_or_else(|e| panic!("the lowered shader is not the Freeman sky: {e}"))
}

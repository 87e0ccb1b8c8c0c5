//! The material uniform block (bind group 1, binding 0) as bytes.
//!
//! Offsets are not computed here: they come from the lowering ([`gdsky_naga::Lowered::uniforms`],
//! the same numbers the reflection JSON holds), so the bytes follow whatever layout naga gave
//! the block. Each value is checked against the uniform's shader type before it is written.

use gdshader::check::types::{Scalar, Type};
use gdsky_naga::{Lowered, MATERIAL_GROUP};
use std::fmt;

pub use skycore::UniformValue;

/// The shader type a value fits: its scalar or vector type, or for an array, the element's
/// scalar type and the count.
fn shader_type(value: &UniformValue) -> Type {
    match value {
        UniformValue::Float(_) => Type::FLOAT,
        UniformValue::Int(_) => Type::INT,
        UniformValue::UInt(_) => Type::UINT,
        UniformValue::Bool(_) => Type::BOOL,
        UniformValue::Vec2(_) => Type::Vector(Scalar::Float, 2),
        UniformValue::Vec3(_) => Type::Vector(Scalar::Float, 3),
        UniformValue::Vec4(_) => Type::Vector(Scalar::Float, 4),
        UniformValue::IVec2(_) => Type::Vector(Scalar::Int, 2),
        UniformValue::IVec3(_) => Type::Vector(Scalar::Int, 3),
        UniformValue::IVec4(_) => Type::Vector(Scalar::Int, 4),
        UniformValue::FloatArray(v) => Type::Array(Box::new(Type::FLOAT), v.len() as u32),
        UniformValue::IntArray(v) => Type::Array(Box::new(Type::INT), v.len() as u32),
    }
}

/// Whether a value of type `given` fits a uniform of type `slot`: the same type, or an int
/// array for a uint array (the elements travel as their bit patterns).
fn fits(slot: &Type, given: &Type) -> bool {
    match (slot, given) {
        (Type::Array(s, n), Type::Array(g, m)) => n == m && (s == g || (**s == Type::UINT && **g == Type::INT)),
        _ => slot == given,
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
    /// An override's text does not parse as the uniform's type.
    BadValue {
        /// The uniform.
        name: String,
        /// What is wrong with the text.
        message: String,
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
            MaterialError::BadValue { name, message } => write!(f, "uniform `{name}`: {message}"),
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
        let given = shader_type(value);
        if !fits(&slot.ty, &given) {
            return Err(MaterialError::TypeMismatch {
                name: (*name).to_owned(),
                expected: slot.ty.display(&[]).to_string(),
                given: given.display(&[]).to_string(),
            });
        }
        value.write_into(&mut bytes, slot.offset as usize, slot.stride.unwrap_or(0) as usize);
    }
    Ok(bytes)
}

/// The 22 uniforms of `fixtures/freeman_sky.gdshader` from skyref's parameters, with the
/// shader's names and types, rounded to f32 as a host fills the buffer.
pub fn freeman_values(params: &skyref::FreemanParams) -> Vec<(&'static str, UniformValue)> {
    let mut params = *params;
    params
        .uniforms_mut()
        .into_iter()
        .map(|(name, value)| {
            let value = match value {
                skyref::UniformMut::Float(v) => UniformValue::Float(*v as f32),
                skyref::UniformMut::Vec3(v) => UniformValue::Vec3([v.x as f32, v.y as f32, v.z as f32]),
                skyref::UniformMut::Int(v) => UniformValue::Int(*v),
            };
            (name, value)
        })
        .collect()
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

/// The material block of any checked, lowered shader: every uniform at its shader default
/// (zero where the shader gives none, as Godot does), then each `(name, text)` override parsed
/// like `gdsky convert --set` (`1.5`, `24`, `true`, `0.1,0.2,0.3`).
///
/// Scalars, vectors, matrices (columns 16 bytes apart) and arrays (at the lowering's stride) are
/// written; bools travel as `u32`. Overrides of unknown, baked, global or sampler uniforms are
/// errors.
pub fn material_with_defaults(
    shader: &gdshader::CheckedShader,
    lowered: &Lowered,
    overrides: &[(String, String)],
) -> Result<Vec<u8>, MaterialError> {
    let mut bytes = vec![0u8; lowered.material_size as usize];
    let in_block = |name: &str| lowered.uniforms.get(name).filter(|slot| slot.group == MATERIAL_GROUP);
    for u in &shader.uniforms {
        if let (Some(slot), Some(default)) = (in_block(&u.name), &u.default) {
            write_const(&mut bytes, slot.offset as usize, &slot.ty, default, slot.stride.unwrap_or(16) as usize);
        }
    }
    for (name, text) in overrides {
        let slot = in_block(name).ok_or_else(|| MaterialError::NoSuchUniform(name.clone()))?;
        let value = gdshader::values::parse_value(&slot.ty, text)
            .map_err(|message| MaterialError::BadValue { name: name.clone(), message })?;
        write_const(&mut bytes, slot.offset as usize, &slot.ty, &value, slot.stride.unwrap_or(16) as usize);
    }
    Ok(bytes)
}

/// Writes a constant of type `ty` at `offset` with the uniform address space's layout.
fn write_const(
    bytes: &mut [u8],
    offset: usize,
    ty: &Type,
    value: &gdshader::check::consteval::ConstValue,
    stride: usize,
) {
    use gdshader::check::consteval::ConstValue;
    let scalar = |bytes: &mut [u8], at: usize, s: Scalar, v: &ConstValue| {
        if at + 4 > bytes.len() {
            return;
        }
        match v.convert(s) {
            Some(ConstValue::Float(f)) => UniformValue::Float(f as f32).write_into(bytes, at, 0),
            Some(ConstValue::Int(i)) => UniformValue::Int(i as i32).write_into(bytes, at, 0),
            Some(ConstValue::UInt(u)) => UniformValue::UInt(u as u32).write_into(bytes, at, 0),
            Some(ConstValue::Bool(b)) => UniformValue::Bool(b).write_into(bytes, at, 0),
            _ => {}
        }
    };
    match (ty, value) {
        (Type::Scalar(s), v) => scalar(bytes, offset, *s, v),
        (Type::Vector(s, _), ConstValue::Composite(items)) => {
            for (i, item) in items.iter().enumerate() {
                scalar(bytes, offset + 4 * i, *s, item);
            }
        }
        (Type::Matrix(n), ConstValue::Composite(items)) => {
            let n = usize::from(*n);
            for (i, item) in items.iter().enumerate() {
                scalar(bytes, offset + (i / n) * 16 + (i % n) * 4, Scalar::Float, item);
            }
        }
        (Type::Array(element, _), ConstValue::Composite(items)) => {
            for (i, item) in items.iter().enumerate() {
                write_const(bytes, offset + i * stride, element, item, stride);
            }
        }
        _ => {}
    }
}

/// The texel Godot binds for a material sampler the scene gives no texture, from the uniform's
/// hint: `hint_default_black` (0, 0, 0, 1), `hint_default_transparent` (0, 0, 0, 0),
/// `hint_normal` (0.5, 0.5, 1, 1), otherwise (`hint_default_white` or no hint) white. Keyed by
/// the texture's (group, binding); a sampler array gives each element its uniform's default.
pub fn texture_defaults(shader: &gdshader::CheckedShader, lowered: &Lowered) -> Vec<((u32, u32), [f32; 4])> {
    let mut defaults: Vec<((u32, u32), [f32; 4])> = lowered
        .textures
        .iter()
        .filter(|(_, slot)| slot.group == MATERIAL_GROUP)
        .map(|(name, slot)| {
            // Sampler arrays are lowered as `name_0`, `name_1`, …
            let uniform = shader.uniforms.iter().find(|u| {
                u.name == *name
                    || name
                        .strip_prefix(u.name.as_str())
                        .and_then(|rest| rest.strip_prefix('_'))
                        .is_some_and(|index| index.parse::<u32>().is_ok() && matches!(u.ty, Type::Array(..)))
            });
            let has = |hint: &str| uniform.is_some_and(|u| u.hints.iter().any(|h| h.name == hint));
            let texel = if has("hint_default_black") {
                [0.0, 0.0, 0.0, 1.0]
            } else if has("hint_default_transparent") {
                [0.0; 4]
            } else if has("hint_normal") {
                [0.5, 0.5, 1.0, 1.0]
            } else {
                [1.0; 4]
            };
            ((slot.group, slot.binding), texel)
        })
        .collect();
    defaults.sort_by_key(|(key, _)| *key);
    defaults
}

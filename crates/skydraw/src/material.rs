//! The material block (group 1, binding 0) on the host: its bytes, starting at the shader's
//! defaults, changed by uniform name through the reflection or replaced whole by the build
//! script's generated struct.

use serde_json::Value;
use skycore::UniformValue;
use skycore::reflection::{Reflection, UniformEntry};

/// Why a material value was refused.
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialError {
    /// No material uniform of that name (baked uniforms and overrides are not in the block).
    UnknownUniform {
        /// The name asked for.
        name: String,
        /// The shader's material uniforms.
        known: Vec<String>,
    },
    /// The value's type is not the uniform's.
    WrongType {
        /// The uniform.
        name: String,
        /// Its type in the shader.
        expected: String,
        /// The value's.
        given: &'static str,
    },
    /// [`crate::Sky::set_material`] got a block of the wrong size.
    WrongSize {
        /// The block's size in bytes.
        expected: usize,
        /// The bytes given.
        given: usize,
    },
}

impl std::fmt::Display for MaterialError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MaterialError::UnknownUniform { name, known } => {
                write!(f, "the shader has no material uniform `{name}` (it has: {})", known.join(", "))
            }
            MaterialError::WrongType { name, expected, given } => {
                write!(f, "`{name}` is a `{expected}`, not a `{given}`")
            }
            MaterialError::WrongSize { expected, given } => {
                write!(f, "the material block is {expected} bytes, {given} were given")
            }
        }
    }
}

impl std::error::Error for MaterialError {}

/// The material block's bytes and the uniforms that live in it.
#[derive(Clone, Debug)]
pub(crate) struct Material {
    pub(crate) bytes: Vec<u8>,
    entries: Vec<UniformEntry>,
    /// Bumped by every change, so that the radiance knows when the material changed.
    pub(crate) version: u64,
}

impl Material {
    /// The block of `reflection` filled with the uniforms' defaults (zero where a uniform has
    /// none, as Godot's are).
    pub(crate) fn with_defaults(reflection: &Reflection) -> Self {
        let size = reflection.bindings.material.size as usize;
        let entries: Vec<UniformEntry> = reflection
            .uniforms
            .iter()
            .filter(|u| u.block.as_deref() == Some("material") && u.offset.is_some())
            .cloned()
            .collect();
        let mut bytes = vec![0; size];
        for entry in &entries {
            if let (Some(offset), Some(default)) = (entry.offset, &entry.default) {
                write_default(&mut bytes, offset as usize, &entry.type_name, entry.array_stride, default);
            }
        }
        Self { bytes, entries, version: 0 }
    }

    pub(crate) fn set(&mut self, name: &str, value: &UniformValue) -> Result<(), MaterialError> {
        let Some(entry) = self.entries.iter().find(|e| e.name == name) else {
            return Err(MaterialError::UnknownUniform {
                name: name.to_string(),
                known: self.entries.iter().map(|e| e.name.clone()).collect(),
            });
        };
        if !value.fits(&entry.type_name) {
            return Err(MaterialError::WrongType {
                name: name.to_string(),
                expected: entry.type_name.clone(),
                given: value.type_name(),
            });
        }
        let offset = entry.offset.unwrap_or(0) as usize;
        value.write_into(&mut self.bytes, offset, entry.array_stride.unwrap_or(0) as usize);
        self.version += 1;
        Ok(())
    }

    pub(crate) fn replace(&mut self, bytes: &[u8]) -> Result<(), MaterialError> {
        if bytes.len() != self.bytes.len() {
            return Err(MaterialError::WrongSize { expected: self.bytes.len(), given: bytes.len() });
        }
        if bytes != self.bytes {
            self.bytes.copy_from_slice(bytes);
            self.version += 1;
        }
        Ok(())
    }
}

/// Writes a uniform's JSON default (a number, a bool, or nested lists of them) at `offset`:
/// vector components 4 bytes apart, matrix columns 16 bytes apart, array elements
/// `array_stride` apart.
fn write_default(bytes: &mut [u8], offset: usize, type_name: &str, array_stride: Option<u32>, default: &Value) {
    let (element, count) = match type_name.split_once('[') {
        Some((element, rest)) => (element, rest.trim_end_matches(']').parse::<usize>().unwrap_or(0)),
        None => (type_name, 0),
    };
    if count > 0 {
        let stride = array_stride.unwrap_or(0) as usize;
        if let Value::Array(items) = default {
            for (i, item) in items.iter().enumerate().take(count) {
                write_default(bytes, offset + i * stride, element, None, item);
            }
        }
        return;
    }
    let mut scalars = Vec::new();
    flatten(default, &mut scalars);
    let columns = element.strip_prefix("mat").and_then(|n| n.parse::<usize>().ok());
    for (i, scalar) in scalars.iter().enumerate() {
        let at = match columns {
            Some(n) => offset + (i / n) * 16 + (i % n) * 4,
            None => offset + 4 * i,
        };
        let value = if element.starts_with("int") || element.starts_with("ivec") {
            UniformValue::Int(scalar.as_i64().unwrap_or(0) as i32)
        } else if element.starts_with("uint") || element.starts_with("uvec") {
            UniformValue::UInt(scalar.as_u64().unwrap_or(0) as u32)
        } else if element.starts_with("bool") || element.starts_with("bvec") {
            UniformValue::Bool(scalar.as_bool().unwrap_or(false))
        } else {
            UniformValue::Float(scalar.as_f64().unwrap_or(0.0) as f32)
        };
        value.write_into(bytes, at, 0);
    }
}

/// The scalars of a JSON value, lists flattened in order.
fn flatten<'a>(value: &'a Value, out: &mut Vec<&'a Value>) {
    match value {
        Value::Array(items) => items.iter().for_each(|item| flatten(item, out)),
        scalar => out.push(scalar),
    }
}

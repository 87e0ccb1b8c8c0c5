//! A value for one uniform of a sky shader, as a host holds it before it reaches the GPU.

use std::fmt;

/// A value for one non-sampler uniform: what `--set NAME=VALUE`, a scene file's `[uniforms]`, a
/// Godot material's `shader_parameter/*` and a runtime's material update all come down to.
///
/// Where it goes depends on who takes it: the GPU side writes it into the material block at the
/// offset the reflection gives (checking it against the uniform's type); the Godot oracle sends
/// it to `ShaderMaterial.set_shader_parameter`. Its text ([`fmt::Display`]) is the `--set`
/// syntax: `1.5`, `24`, `true`, `0.1,0.2,0.3`.
#[derive(Clone, Debug, PartialEq)]
pub enum UniformValue {
    /// `float`.
    Float(f32),
    /// `int`.
    Int(i32),
    /// `uint`.
    UInt(u32),
    /// `bool` (travels as a `u32`, 0 or 1).
    Bool(bool),
    /// `vec2`.
    Vec2([f32; 2]),
    /// `vec3`.
    Vec3([f32; 3]),
    /// `vec4`.
    Vec4([f32; 4]),
    /// `ivec2`.
    IVec2([i32; 2]),
    /// `ivec3`.
    IVec3([i32; 3]),
    /// `ivec4`.
    IVec4([i32; 4]),
    /// A `float` array (`uniform float x[N]`).
    FloatArray(Vec<f32>),
    /// An `int` or `uint` array (a `uint` element above 2³¹ − 1 as its two's-complement bit
    /// pattern, as Godot's `PackedInt32Array` carries both).
    IntArray(Vec<i32>),
}

impl UniformValue {
    /// Whether the value fits a uniform of the Godot type `type_name` as the reflection writes
    /// it (`float`, `ivec3`, `float[4]`): the same type, or an int array for a `uint` array
    /// (the elements travel as their bit patterns).
    pub fn fits(&self, type_name: &str) -> bool {
        match self {
            UniformValue::FloatArray(v) => type_name == format!("float[{}]", v.len()),
            UniformValue::IntArray(v) => {
                type_name == format!("int[{}]", v.len()) || type_name == format!("uint[{}]", v.len())
            }
            other => type_name == other.type_name(),
        }
    }

    /// Writes the value into a uniform block's `bytes` at `offset`, in the host's byte order
    /// (little-endian on every wgpu platform): a `bool` as a `u32` 0 or 1, vectors as
    /// consecutive components, array elements `stride` bytes apart. Components past the end of
    /// `bytes` are not written.
    pub fn write_into(&self, bytes: &mut [u8], offset: usize, stride: usize) {
        let mut put = |at: usize, word: [u8; 4]| {
            if let Some(slot) = bytes.get_mut(at..at + 4) {
                slot.copy_from_slice(&word);
            }
        };
        match self {
            UniformValue::Float(v) => put(offset, v.to_ne_bytes()),
            UniformValue::Int(v) => put(offset, v.to_ne_bytes()),
            UniformValue::UInt(v) => put(offset, v.to_ne_bytes()),
            UniformValue::Bool(v) => put(offset, u32::from(*v).to_ne_bytes()),
            UniformValue::Vec2(v) => v.iter().enumerate().for_each(|(i, c)| put(offset + 4 * i, c.to_ne_bytes())),
            UniformValue::Vec3(v) => v.iter().enumerate().for_each(|(i, c)| put(offset + 4 * i, c.to_ne_bytes())),
            UniformValue::Vec4(v) => v.iter().enumerate().for_each(|(i, c)| put(offset + 4 * i, c.to_ne_bytes())),
            UniformValue::IVec2(v) => v.iter().enumerate().for_each(|(i, c)| put(offset + 4 * i, c.to_ne_bytes())),
            UniformValue::IVec3(v) => v.iter().enumerate().for_each(|(i, c)| put(offset + 4 * i, c.to_ne_bytes())),
            UniformValue::IVec4(v) => v.iter().enumerate().for_each(|(i, c)| put(offset + 4 * i, c.to_ne_bytes())),
            UniformValue::FloatArray(v) => {
                v.iter().enumerate().for_each(|(i, c)| put(offset + stride * i, c.to_ne_bytes()))
            }
            UniformValue::IntArray(v) => {
                v.iter().enumerate().for_each(|(i, c)| put(offset + stride * i, c.to_ne_bytes()))
            }
        }
    }

    /// The Godot shading language type this value is written for (`float`, `ivec3`, `float[]`).
    pub fn type_name(&self) -> &'static str {
        match self {
            UniformValue::Float(_) => "float",
            UniformValue::Int(_) => "int",
            UniformValue::UInt(_) => "uint",
            UniformValue::Bool(_) => "bool",
            UniformValue::Vec2(_) => "vec2",
            UniformValue::Vec3(_) => "vec3",
            UniformValue::Vec4(_) => "vec4",
            UniformValue::IVec2(_) => "ivec2",
            UniformValue::IVec3(_) => "ivec3",
            UniformValue::IVec4(_) => "ivec4",
            UniformValue::FloatArray(_) => "float[]",
            UniformValue::IntArray(_) => "int[]",
        }
    }
}

impl fmt::Display for UniformValue {
    /// The `--set` syntax: numbers as Rust prints them exactly (`0.1`, `24`), components
    /// separated by commas, `true`/`false`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fn join<T: fmt::Debug>(f: &mut fmt::Formatter<'_>, values: &[T]) -> fmt::Result {
            for (i, v) in values.iter().enumerate() {
                if i > 0 {
                    f.write_str(",")?;
                }
                write!(f, "{v:?}")?;
            }
            Ok(())
        }
        match self {
            UniformValue::Float(v) => write!(f, "{v:?}"),
            UniformValue::Int(v) => write!(f, "{v}"),
            UniformValue::UInt(v) => write!(f, "{v}"),
            UniformValue::Bool(v) => write!(f, "{v}"),
            UniformValue::Vec2(v) => join(f, v),
            UniformValue::Vec3(v) => join(f, v),
            UniformValue::Vec4(v) => join(f, v),
            UniformValue::IVec2(v) => join(f, v),
            UniformValue::IVec3(v) => join(f, v),
            UniformValue::IVec4(v) => join(f, v),
            UniformValue::FloatArray(v) => join(f, v),
            UniformValue::IntArray(v) => join(f, v),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_the_set_syntax() {
        assert_eq!(UniformValue::Float(1.5).to_string(), "1.5");
        assert_eq!(UniformValue::Float(2.0).to_string(), "2.0");
        assert_eq!(UniformValue::Int(-3).to_string(), "-3");
        assert_eq!(UniformValue::Bool(true).to_string(), "true");
        assert_eq!(UniformValue::Vec3([0.1, 0.2, 0.3]).to_string(), "0.1,0.2,0.3");
        assert_eq!(UniformValue::IVec2([1, 2]).to_string(), "1,2");
    }
}

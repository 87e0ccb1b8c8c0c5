//! The types of the Godot shading language.

use std::fmt;

/// Scalar kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Scalar {
    /// `bool`
    Bool,
    /// `int` (32-bit signed)
    Int,
    /// `uint`
    UInt,
    /// `float` (32-bit)
    Float,
}

/// Sampler types (uniforms and RADIANCE only).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SamplerKind {
    /// `sampler2D` and its `i`/`u` forms.
    Tex2D,
    /// `sampler2DArray` and its `i`/`u` forms.
    Tex2DArray,
    /// `sampler3D` and its `i`/`u` forms.
    Tex3D,
    /// `samplerCube`
    Cube,
    /// `samplerCubeArray`
    CubeArray,
}

/// Identifies a struct declared in the shader (index in declaration order).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct StructId(pub u32);

/// A type.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Type {
    /// `void` (function returns only)
    Void,
    /// `bool`, `int`, `uint`, `float`
    Scalar(Scalar),
    /// `vecN`, `ivecN`, `uvecN`, `bvecN` (N = 2..4)
    Vector(Scalar, u8),
    /// `matN` (N = 2..4, float, column-major)
    Matrix(u8),
    /// A sampler; the scalar is what it returns (`Float` for `sampler2D`, `Int` for `isampler2D`).
    Sampler(SamplerKind, Scalar),
    /// A struct.
    Struct(StructId),
    /// `T[N]`
    Array(Box<Type>, u32),
}

impl Type {
    /// `float`
    pub const FLOAT: Type = Type::Scalar(Scalar::Float);
    /// `int`
    pub const INT: Type = Type::Scalar(Scalar::Int);
    /// `uint`
    pub const UINT: Type = Type::Scalar(Scalar::UInt);
    /// `bool`
    pub const BOOL: Type = Type::Scalar(Scalar::Bool);

    /// A built-in (non-struct) type from its name.
    pub fn from_name(name: &str) -> Option<Type> {
        use Scalar::*;
        let vec = |s, n| Some(Type::Vector(s, n));
        match name {
            "void" => Some(Type::Void),
            "bool" => Some(Type::BOOL),
            "int" => Some(Type::INT),
            "uint" => Some(Type::UINT),
            "float" => Some(Type::FLOAT),
            "vec2" => vec(Float, 2),
            "vec3" => vec(Float, 3),
            "vec4" => vec(Float, 4),
            "ivec2" => vec(Int, 2),
            "ivec3" => vec(Int, 3),
            "ivec4" => vec(Int, 4),
            "uvec2" => vec(UInt, 2),
            "uvec3" => vec(UInt, 3),
            "uvec4" => vec(UInt, 4),
            "bvec2" => vec(Bool, 2),
            "bvec3" => vec(Bool, 3),
            "bvec4" => vec(Bool, 4),
            "mat2" => Some(Type::Matrix(2)),
            "mat3" => Some(Type::Matrix(3)),
            "mat4" => Some(Type::Matrix(4)),
            "sampler2D" => Some(Type::Sampler(SamplerKind::Tex2D, Float)),
            "isampler2D" => Some(Type::Sampler(SamplerKind::Tex2D, Int)),
            "usampler2D" => Some(Type::Sampler(SamplerKind::Tex2D, UInt)),
            "sampler2DArray" => Some(Type::Sampler(SamplerKind::Tex2DArray, Float)),
            "isampler2DArray" => Some(Type::Sampler(SamplerKind::Tex2DArray, Int)),
            "usampler2DArray" => Some(Type::Sampler(SamplerKind::Tex2DArray, UInt)),
            "sampler3D" => Some(Type::Sampler(SamplerKind::Tex3D, Float)),
            "isampler3D" => Some(Type::Sampler(SamplerKind::Tex3D, Int)),
            "usampler3D" => Some(Type::Sampler(SamplerKind::Tex3D, UInt)),
            "samplerCube" => Some(Type::Sampler(SamplerKind::Cube, Float)),
            "samplerCubeArray" => Some(Type::Sampler(SamplerKind::CubeArray, Float)),
            _ => None,
        }
    }

    /// The scalar kind of a scalar or vector (float for matrices).
    pub fn scalar(&self) -> Option<Scalar> {
        match self {
            Type::Scalar(s) | Type::Vector(s, _) => Some(*s),
            Type::Matrix(_) => Some(Scalar::Float),
            _ => None,
        }
    }

    /// Number of components of a scalar (1) or vector (N).
    pub fn components(&self) -> Option<u8> {
        match self {
            Type::Scalar(_) => Some(1),
            Type::Vector(_, n) => Some(*n),
            Type::Matrix(n) => Some(n * n),
            _ => None,
        }
    }

    /// A scalar (N = 1) or vector of `scalar`.
    pub fn vector_of(scalar: Scalar, n: u8) -> Type {
        if n == 1 { Type::Scalar(scalar) } else { Type::Vector(scalar, n) }
    }

    /// True for int, uint and float scalars, vectors and matrices.
    pub fn is_numeric(&self) -> bool {
        matches!(self.scalar(), Some(Scalar::Int | Scalar::UInt | Scalar::Float))
    }

    /// True for int and uint scalars and vectors.
    pub fn is_integer(&self) -> bool {
        matches!(self, Type::Scalar(Scalar::Int | Scalar::UInt) | Type::Vector(Scalar::Int | Scalar::UInt, _))
    }

    /// True for samplers and types containing one (they cannot be copied around).
    pub fn is_opaque(&self) -> bool {
        match self {
            Type::Sampler(..) => true,
            Type::Array(t, _) => t.is_opaque(),
            _ => false,
        }
    }

    /// The type's name as Godot writes it, with struct names from `structs`.
    pub fn display<'a>(&'a self, structs: &'a [String]) -> TypeDisplay<'a> {
        TypeDisplay { ty: self, structs }
    }
}

/// Formats a [`Type`] with struct names.
pub struct TypeDisplay<'a> {
    ty: &'a Type,
    structs: &'a [String],
}

impl fmt::Display for TypeDisplay<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let prefix = |s: Scalar| match s {
            Scalar::Bool => "b",
            Scalar::Int => "i",
            Scalar::UInt => "u",
            Scalar::Float => "",
        };
        match self.ty {
            Type::Void => f.write_str("void"),
            Type::Scalar(Scalar::Bool) => f.write_str("bool"),
            Type::Scalar(Scalar::Int) => f.write_str("int"),
            Type::Scalar(Scalar::UInt) => f.write_str("uint"),
            Type::Scalar(Scalar::Float) => f.write_str("float"),
            Type::Vector(s, n) => write!(f, "{}vec{n}", prefix(*s)),
            Type::Matrix(n) => write!(f, "mat{n}"),
            Type::Sampler(kind, s) => {
                let base = match kind {
                    SamplerKind::Tex2D => "sampler2D",
                    SamplerKind::Tex2DArray => "sampler2DArray",
                    SamplerKind::Tex3D => "sampler3D",
                    SamplerKind::Cube => "samplerCube",
                    SamplerKind::CubeArray => "samplerCubeArray",
                };
                write!(f, "{}{base}", prefix(*s))
            }
            Type::Struct(id) => f.write_str(self.structs.get(id.0 as usize).map_or("struct", String::as_str)),
            Type::Array(t, n) => write!(f, "{}[{n}]", t.display(self.structs)),
        }
    }
}

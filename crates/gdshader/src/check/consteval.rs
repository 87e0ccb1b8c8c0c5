//! Compile-time values: what `const` initializers, array sizes, `case` labels, hint arguments
//! and uniform defaults evaluate to.
//!
//! Floats are folded in double precision and rounded to single precision once, when the value
//! becomes a literal of the shader, as GLSL compilers fold Godot's constant expressions; IEEE
//! throughout (`1.0 / 0.0` is +inf, `0.0 / 0.0` NaN, a value past f32's range rounds to an
//! infinity). Ints wrap (two's complement), and where GLSL leaves the result undefined,
//! naga's run-time code decides: `x / 0 = x`, `x % 0 = 0`, `INT_MIN / -1 = INT_MIN`,
//! `INT_MIN % -1 = 0`, a shift amount keeps its low 5 bits, and a float converts to an int by
//! clamping to the range (NaN to 0). Whether Godot accepts an integer division by a constant zero
//! is the checker's business (`codes::DIVISION_BY_ZERO`); the value is defined either way.

use super::types::{Scalar, Type};
use crate::parse::ast::{BinaryOp, UnaryOp};
use std::fmt;

/// A constant's value: a scalar, or the components of a vector, matrix (column-major) or array.
#[derive(Clone, Debug, PartialEq)]
pub enum ConstValue {
    /// `bool`
    Bool(bool),
    /// `int`
    Int(i64),
    /// `uint`
    UInt(u64),
    /// `float`, kept in double precision as Godot keeps it.
    Float(f64),
    /// Vector, matrix or array components in order.
    Composite(Vec<ConstValue>),
}

impl ConstValue {
    /// As an integer, for array sizes, indices and case labels.
    pub fn as_int(&self) -> Option<i64> {
        match *self {
            ConstValue::Int(v) => Some(v),
            ConstValue::UInt(v) => Some(v as i64),
            _ => None,
        }
    }

    /// As a number, for hint arguments.
    pub fn as_f64(&self) -> Option<f64> {
        match *self {
            ConstValue::Int(v) => Some(v as f64),
            ConstValue::UInt(v) => Some(v as f64),
            ConstValue::Float(v) => Some(v),
            _ => None,
        }
    }

    /// Every scalar component, flattened.
    pub fn scalars(&self) -> Vec<ConstValue> {
        match self {
            ConstValue::Composite(c) => c.iter().flat_map(ConstValue::scalars).collect(),
            s => vec![s.clone()],
        }
    }

    /// Converts a scalar to `to`, as a constructor does.
    pub fn convert(&self, to: Scalar) -> Option<ConstValue> {
        let f = match *self {
            ConstValue::Bool(b) => f64::from(u8::from(b)),
            ConstValue::Int(v) => v as f64,
            ConstValue::UInt(v) => v as f64,
            ConstValue::Float(v) => v,
            ConstValue::Composite(_) => return None,
        };
        Some(match to {
            Scalar::Bool => ConstValue::Bool(f != 0.0),
            Scalar::Float => ConstValue::Float(f),
            Scalar::Int => ConstValue::Int(match *self {
                ConstValue::UInt(v) => v as u32 as i32 as i64,
                ConstValue::Int(v) => v,
                _ => float_to_i32(f as f32) as i64,
            }),
            Scalar::UInt => ConstValue::UInt(match *self {
                ConstValue::Int(v) => v as i32 as u32 as u64,
                ConstValue::UInt(v) => v,
                _ => float_to_u32(f as f32) as u64,
            }),
        })
    }
}

/// A float converted to `int` as the translated shader does at run time (naga clamps to the
/// range of ints representable in f32 before converting; NaN gives 0).
pub fn float_to_i32(f: f32) -> i32 {
    f.clamp(-2_147_483_648.0, 2_147_483_520.0) as i32
}

/// A float converted to `uint` (clamped to 0 ..= 4294967040, the largest f32 below 2³²).
pub fn float_to_u32(f: f32) -> u32 {
    f.clamp(0.0, 4_294_967_040.0) as u32
}

/// Writes a value the way the shader would: `1.5`, `vec3(0.68, 0.55, 0.48)`.
pub struct ValueDisplay<'a> {
    /// The value.
    pub value: &'a ConstValue,
    /// Its type.
    pub ty: &'a Type,
    /// Struct names, for struct-typed values.
    pub structs: &'a [String],
}

impl fmt::Display for ValueDisplay<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.value, self.ty) {
            (ConstValue::Composite(items), ty) => {
                write!(f, "{}(", ty.display(self.structs))?;
                let elem = match ty {
                    Type::Array(t, _) => (**t).clone(),
                    Type::Vector(s, _) => Type::Scalar(*s),
                    _ => Type::FLOAT,
                };
                for (i, item) in items.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{}", ValueDisplay { value: item, ty: &elem, structs: self.structs })?;
                }
                f.write_str(")")
            }
            (ConstValue::Bool(b), _) => write!(f, "{b}"),
            (ConstValue::Int(v), _) => write!(f, "{v}"),
            (ConstValue::UInt(v), _) => write!(f, "{v}u"),
            (ConstValue::Float(v), _) => {
                if v.is_finite() && v.fract() == 0.0 && v.abs() < 1e15 {
                    write!(f, "{v:.1}")
                } else {
                    write!(f, "{v}")
                }
            }
        }
    }
}

/// Applies a unary operator to a constant.
pub fn unary(op: UnaryOp, v: &ConstValue) -> Option<ConstValue> {
    if let ConstValue::Composite(items) = v {
        return items.iter().map(|i| unary(op, i)).collect::<Option<Vec<_>>>().map(ConstValue::Composite);
    }
    Some(match (op, v) {
        (UnaryOp::Plus, v) => v.clone(),
        (UnaryOp::Neg, ConstValue::Int(x)) => ConstValue::Int(wrap_i32(x.wrapping_neg())),
        (UnaryOp::Neg, ConstValue::UInt(x)) => ConstValue::UInt((x.wrapping_neg()) & 0xFFFF_FFFF),
        (UnaryOp::Neg, ConstValue::Float(x)) => ConstValue::Float(-x),
        (UnaryOp::Not, ConstValue::Bool(b)) => ConstValue::Bool(!b),
        (UnaryOp::BitNot, ConstValue::Int(x)) => ConstValue::Int(wrap_i32(!x)),
        (UnaryOp::BitNot, ConstValue::UInt(x)) => ConstValue::UInt(!x & 0xFFFF_FFFF),
        _ => return None,
    })
}

fn wrap_i32(v: i64) -> i64 {
    v as i32 as i64
}

/// Applies a binary operator to constants (component-wise for vectors, with scalar broadcast).
/// Matrix products are not folded (`None`); the value is then simply unknown.
pub fn binary(op: BinaryOp, a: &ConstValue, b: &ConstValue, a_ty: &Type, b_ty: &Type) -> Option<ConstValue> {
    use BinaryOp::*;
    if matches!(a_ty, Type::Matrix(_)) || matches!(b_ty, Type::Matrix(_)) {
        return None;
    }
    if matches!(op, Eq | NotEq) {
        let equal = a == b;
        return Some(ConstValue::Bool(if op == Eq { equal } else { !equal }));
    }
    match (a, b) {
        (ConstValue::Composite(x), ConstValue::Composite(y)) => x
            .iter()
            .zip(y)
            .map(|(x, y)| binary(op, x, y, &Type::FLOAT, &Type::FLOAT))
            .collect::<Option<Vec<_>>>()
            .map(ConstValue::Composite),
        (ConstValue::Composite(x), s) => x
            .iter()
            .map(|x| binary(op, x, s, &Type::FLOAT, &Type::FLOAT))
            .collect::<Option<Vec<_>>>()
            .map(ConstValue::Composite),
        (s, ConstValue::Composite(y)) => y
            .iter()
            .map(|y| binary(op, s, y, &Type::FLOAT, &Type::FLOAT))
            .collect::<Option<Vec<_>>>()
            .map(ConstValue::Composite),
        (ConstValue::Float(x), ConstValue::Float(y)) => float_op(op, *x, *y),
        (ConstValue::Int(x), ConstValue::Int(y)) => int_op(op, *x, *y),
        (ConstValue::UInt(x), ConstValue::UInt(y)) => uint_op(op, *x, *y),
        (ConstValue::Int(x), ConstValue::UInt(y)) if matches!(op, Shl | Shr) => int_op(op, *x, *y as i64),
        (ConstValue::UInt(x), ConstValue::Int(y)) if matches!(op, Shl | Shr) => uint_op(op, *x, *y as u64),
        (ConstValue::Bool(x), ConstValue::Bool(y)) => Some(ConstValue::Bool(match op {
            LogicalAnd => *x && *y,
            LogicalOr => *x || *y,
            _ => return None,
        })),
        _ => None,
    }
}

fn float_op(op: BinaryOp, x: f64, y: f64) -> Option<ConstValue> {
    use BinaryOp::*;
    let f = ConstValue::Float;
    Some(match op {
        Add => f(x + y),
        Sub => f(x - y),
        Mul => f(x * y),
        Div => f(x / y),
        Less => ConstValue::Bool(x < y),
        Greater => ConstValue::Bool(x > y),
        LessEq => ConstValue::Bool(x <= y),
        GreaterEq => ConstValue::Bool(x >= y),
        _ => return None,
    })
}

fn int_op(op: BinaryOp, x: i64, y: i64) -> Option<ConstValue> {
    use BinaryOp::*;
    let (x32, y32) = (x as i32, y as i32);
    let int = |v: i32| Some(ConstValue::Int(v as i64));
    match op {
        Add => int(x32.wrapping_add(y32)),
        Sub => int(x32.wrapping_sub(y32)),
        Mul => int(x32.wrapping_mul(y32)),
        // naga's run-time code divides by 1 instead of 0 and of -1 under INT_MIN.
        Div if y32 == 0 => int(x32),
        Div => int(x32.wrapping_div(y32)),
        Rem if y32 == 0 => int(0),
        Rem => int(x32.wrapping_rem(y32)),
        // `wrapping_shl` keeps the low 5 bits of the amount.
        Shl => int(x32.wrapping_shl(y as u32)),
        Shr => int(x32.wrapping_shr(y as u32)),
        BitAnd => int(x32 & y32),
        BitOr => int(x32 | y32),
        BitXor => int(x32 ^ y32),
        Less => Some(ConstValue::Bool(x32 < y32)),
        Greater => Some(ConstValue::Bool(x32 > y32)),
        LessEq => Some(ConstValue::Bool(x32 <= y32)),
        GreaterEq => Some(ConstValue::Bool(x32 >= y32)),
        _ => None,
    }
}

fn uint_op(op: BinaryOp, x: u64, y: u64) -> Option<ConstValue> {
    use BinaryOp::*;
    let (x32, y32) = (x as u32, y as u32);
    let uint = |v: u32| Some(ConstValue::UInt(v as u64));
    match op {
        Add => uint(x32.wrapping_add(y32)),
        Sub => uint(x32.wrapping_sub(y32)),
        Mul => uint(x32.wrapping_mul(y32)),
        Div if y32 == 0 => uint(x32),
        Div => uint(x32 / y32),
        Rem if y32 == 0 => uint(0),
        Rem => uint(x32 % y32),
        Shl => uint(x32.wrapping_shl(y32)),
        Shr => uint(x32.wrapping_shr(y32)),
        BitAnd => uint(x32 & y32),
        BitOr => uint(x32 | y32),
        BitXor => uint(x32 ^ y32),
        Less => Some(ConstValue::Bool(x32 < y32)),
        Greater => Some(ConstValue::Bool(x32 > y32)),
        LessEq => Some(ConstValue::Bool(x32 <= y32)),
        GreaterEq => Some(ConstValue::Bool(x32 >= y32)),
        _ => None,
    }
}

//! What Godot's parser folds into a constant node, and the only conversions it applies to one.
//!
//! Godot converts values implicitly in exactly one situation: a *constant node* of a scalar type
//! given where another scalar type is expected — an argument of a built-in function or
//! constructor, an argument of a user function that is not overloaded, a uniform's default. A
//! constant node is what `ShaderLanguage::_reduce_expression` leaves behind
//! (servers/rendering/shader_language.cpp): a literal, `-` applied to a constant node, or a
//! scalar, vector or matrix constructor whose arguments all reduce (a unary `+` is dropped by the
//! parser). Nothing else is folded there: not `1.0 + 1.0`, not a swizzle, not a `const`'s name.
//! The conversions are `ShaderLanguage::convert_constant`'s: int → float, uint → float,
//! int → uint when not negative, uint → int when at most 2³¹ − 1; never to or from bool.
//!
//! Measured against Godot 4.6 (tests/godot/godot_frontend.rs): `sin(int(1))` and `vec2(1.0, int(2))`
//! are accepted, `uvec2(-1)` and `bvec2(1, 0)` are not; `uniform float f = 1;` is accepted,
//! `uniform float f = 1.0 + 1.0;` and `uniform int i = int(1.5);` are not.

use super::consteval::ConstValue;
use super::types::{Scalar, Type};
use crate::parse::ast::{Expr, ExprKind, UnaryOp};

/// A constant node: its type and its scalar components in order (a matrix column by column).
#[derive(Clone, Debug, PartialEq)]
pub struct Reduced {
    /// Type of the constant.
    pub ty: Type,
    /// Scalar components.
    pub values: Vec<ConstValue>,
}

/// The constant node Godot's parser reduces `e` to, if it does.
pub fn reduce(e: &Expr) -> Option<Reduced> {
    match &e.kind {
        ExprKind::IntLit(v) => scalar(Scalar::Int, ConstValue::Int(i64::from(*v as i32))),
        ExprKind::UIntLit(v) => scalar(Scalar::UInt, ConstValue::UInt(u64::from(*v))),
        ExprKind::FloatLit(v) => scalar(Scalar::Float, ConstValue::Float(*v)),
        ExprKind::BoolLit(b) => scalar(Scalar::Bool, ConstValue::Bool(*b)),
        ExprKind::Unary { op: UnaryOp::Plus, operand } => reduce(operand),
        ExprKind::Unary { op: UnaryOp::Neg, operand } => {
            let r = reduce(operand)?;
            let values = r.values.iter().map(negate).collect::<Option<_>>()?;
            Some(Reduced { ty: r.ty, values })
        }
        ExprKind::Call { callee, args } => {
            let ty = Type::from_name(&callee.name)?;
            let (base, count) = match ty {
                Type::Scalar(s) => (s, 1),
                Type::Vector(s, n) => (s, usize::from(n)),
                Type::Matrix(n) => (Scalar::Float, usize::from(n) * usize::from(n)),
                _ => return None,
            };
            let mut values = Vec::new();
            for arg in args {
                let r = reduce(arg)?;
                match r.ty {
                    _ if r.ty.scalar() == Some(base) => values.extend(r.values),
                    Type::Scalar(from) => values.push(convert(&r.values[0], from, base)?),
                    _ => return None,
                }
            }
            match values.len() {
                1 => {
                    let v = values.pop()?;
                    values = match ty {
                        // One value makes a matrix's diagonal.
                        Type::Matrix(n) => {
                            let n = usize::from(n);
                            (0..n * n)
                                .map(|i| if i % (n + 1) == 0 { v.clone() } else { ConstValue::Float(0.0) })
                                .collect()
                        }
                        _ => vec![v; count],
                    };
                }
                // Godot prints "Failed to reduce expression, values and cardinality mismatch."
                // and keeps the constructor (`mat3(mat4(1.0))`).
                n if n != count => return None,
                _ => {}
            }
            Some(Reduced { ty, values })
        }
        _ => None,
    }
}

fn scalar(s: Scalar, v: ConstValue) -> Option<Reduced> {
    Some(Reduced { ty: Type::Scalar(s), values: vec![v] })
}

fn negate(v: &ConstValue) -> Option<ConstValue> {
    Some(match *v {
        ConstValue::Bool(b) => ConstValue::Bool(!b),
        ConstValue::Int(i) => ConstValue::Int(i64::from((i as i32).wrapping_neg())),
        // Godot wraps, as GLSL does.
        ConstValue::UInt(u) => ConstValue::UInt(u64::from(0u32.wrapping_sub(u as u32))),
        ConstValue::Float(f) => ConstValue::Float(-f),
        ConstValue::Composite(_) => return None,
    })
}

/// `convert_constant` for one scalar: `None` where Godot refuses.
pub fn convert(v: &ConstValue, from: Scalar, to: Scalar) -> Option<ConstValue> {
    match (from, to, v) {
        _ if from == to => Some(v.clone()),
        (Scalar::Int | Scalar::UInt, Scalar::Float, _) => v.convert(Scalar::Float),
        (Scalar::Int, Scalar::UInt, ConstValue::Int(i)) if *i >= 0 => Some(ConstValue::UInt(*i as u64)),
        (Scalar::UInt, Scalar::Int, ConstValue::UInt(u)) if *u <= 0x7FFF_FFFF => Some(ConstValue::Int(*u as i64)),
        _ => None,
    }
}

/// True when `e` is a scalar constant node that Godot converts to the scalar type `to` (a
/// different one) where `to` is expected.
pub fn converts_to(e: &Expr, to: &Type) -> bool {
    let (Some(r), Type::Scalar(to)) = (reduce(e), to) else {
        return false;
    };
    match r.ty {
        Type::Scalar(from) => from != *to && convert(&r.values[0], from, *to).is_some(),
        _ => false,
    }
}

//! Uniform values as text: the `--set NAME=VALUE` syntax that the command line, scene files,
//! Godot materials and build scripts all give values in (`1.5`, `24`, `true`, `0.1,0.2,0.3`),
//! read into the checker's constants for a uniform's type, and written back.

use crate::CheckedShader;
use crate::check::consteval::ConstValue;
use crate::check::types::{Scalar, Type};
use skycore::UniformValue;
use std::collections::HashMap;

/// A value in `--set` syntax, as [`parse_value`] reads it back (`1.5`, `24`, `true`,
/// `0.1,0.2,0.3`).
pub fn value_text(v: &ConstValue) -> String {
    match v {
        ConstValue::Bool(b) => b.to_string(),
        ConstValue::Int(i) => i.to_string(),
        ConstValue::UInt(u) => u.to_string(),
        ConstValue::Float(f) => format!("{f:?}"),
        ConstValue::Composite(items) => items.iter().map(value_text).collect::<Vec<_>>().join(","),
    }
}

/// Every scalar and vector uniform of `shader` that has a default, at its default, in `--set`
/// syntax: what baking a shader "at its defaults" bakes.
pub fn defaults_as_set(shader: &CheckedShader) -> HashMap<String, String> {
    shader
        .uniforms
        .iter()
        .filter(|u| matches!(u.ty, Type::Scalar(_) | Type::Vector(..)))
        .filter_map(|u| Some((u.name.clone(), value_text(u.default.as_ref()?))))
        .collect()
}

/// Parses a `--set` value for a uniform of type `ty`: `1.5`, `24`, `true`, or comma-separated
/// components for vectors (`0.1,0.2,0.3`).
///
/// Every value must fit its type, as the GPU will hold it: a float is finite and rounds to a
/// finite f32, i.e. at most `f32::MAX` = 3.4028235e38 in magnitude (`nan`, `inf`, `1e39` are
/// refused; a value too small for f32 rounds to 0 or a subnormal, as a literal does), an int is within i32 (−2147483648 to 2147483647), a
/// uint within u32 (0 to 4294967295, an optional `u` suffix). The message says which rule the
/// text broke; `gdsky convert` reports it as `E603`, `render` as a usage error.
pub fn parse_value(ty: &Type, text: &str) -> Result<ConstValue, String> {
    let scalar = |s: Scalar, t: &str| -> Result<ConstValue, String> {
        let t = t.trim();
        match s {
            Scalar::Float => {
                let v = t.parse::<f64>().map_err(|_| format!("`{t}` is not a number"))?;
                if !v.is_finite() {
                    Err(format!("`{t}` is not a finite number (a float uniform cannot be NaN or infinite)"))
                } else if (v as f32).is_infinite() {
                    Err(format!("`{t}` overflows a float (largest magnitude {:e})", f32::MAX))
                } else {
                    Ok(ConstValue::Float(v))
                }
            }
            Scalar::Int => match t.parse::<i32>() {
                Ok(v) => Ok(ConstValue::Int(i64::from(v))),
                Err(_) if is_integer(t) => {
                    Err(format!("`{t}` is out of range for an int ({} to {})", i32::MIN, i32::MAX))
                }
                Err(_) => Err(format!("`{t}` is not an int")),
            },
            Scalar::UInt => {
                let digits = t.strip_suffix('u').unwrap_or(t);
                match digits.parse::<u32>() {
                    Ok(v) => Ok(ConstValue::UInt(u64::from(v))),
                    Err(_) if is_integer(digits) => {
                        Err(format!("`{t}` is out of range for a uint (0 to {})", u32::MAX))
                    }
                    Err(_) => Err(format!("`{t}` is not a uint")),
                }
            }
            Scalar::Bool => match t {
                "true" => Ok(ConstValue::Bool(true)),
                "false" => Ok(ConstValue::Bool(false)),
                _ => Err(format!("`{t}` is not `true` or `false`")),
            },
        }
    };
    match ty {
        Type::Scalar(s) => scalar(*s, text),
        Type::Vector(s, n) => {
            let parts: Vec<&str> = text.split(',').collect();
            if parts.len() != usize::from(*n) {
                return Err(format!("expected {n} comma-separated components, got {}", parts.len()));
            }
            parts.iter().map(|p| scalar(*s, p)).collect::<Result<Vec<_>, _>>().map(ConstValue::Composite)
        }
        _ => Err("only scalar and vector uniforms can be set".into()),
    }
}

/// An optionally signed run of decimal digits: an integer too large for its type, rather than
/// something that is not an integer at all.
fn is_integer(t: &str) -> bool {
    let digits = t.strip_prefix(['-', '+']).unwrap_or(t);
    !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit())
}

/// A checked constant as a [`UniformValue`] for a uniform of type `ty`: scalars, and float and
/// int vectors (what a host, or Godot's `set_shader_parameter`, takes); `None` for other types or
/// a value that does not fit.
pub fn uniform_value(ty: &Type, value: &ConstValue) -> Option<UniformValue> {
    let float = |v: &ConstValue| match v.convert(Scalar::Float) {
        Some(ConstValue::Float(f)) => Some(f as f32),
        _ => None,
    };
    let int = |v: &ConstValue| match v.convert(Scalar::Int) {
        Some(ConstValue::Int(i)) => i32::try_from(i).ok(),
        _ => None,
    };
    let items = |v: &ConstValue| match v {
        ConstValue::Composite(items) => Some(items.clone()),
        _ => None,
    };
    Some(match ty {
        Type::Scalar(Scalar::Float) => UniformValue::Float(float(value)?),
        Type::Scalar(Scalar::Int) => UniformValue::Int(int(value)?),
        Type::Scalar(Scalar::UInt) => match value.convert(Scalar::UInt) {
            Some(ConstValue::UInt(u)) => UniformValue::UInt(u32::try_from(u).ok()?),
            _ => return None,
        },
        Type::Scalar(Scalar::Bool) => match value.convert(Scalar::Bool) {
            Some(ConstValue::Bool(b)) => UniformValue::Bool(b),
            _ => return None,
        },
        Type::Vector(Scalar::Float, n) => {
            let v = items(value)?.iter().map(float).collect::<Option<Vec<f32>>>()?;
            match (n, v.as_slice()) {
                (2, &[x, y]) => UniformValue::Vec2([x, y]),
                (3, &[x, y, z]) => UniformValue::Vec3([x, y, z]),
                (4, &[x, y, z, w]) => UniformValue::Vec4([x, y, z, w]),
                _ => return None,
            }
        }
        Type::Vector(Scalar::Int, n) => {
            let v = items(value)?.iter().map(int).collect::<Option<Vec<i32>>>()?;
            match (n, v.as_slice()) {
                (2, &[x, y]) => UniformValue::IVec2([x, y]),
                (3, &[x, y, z]) => UniformValue::IVec3([x, y, z]),
                (4, &[x, y, z, w]) => UniformValue::IVec4([x, y, z, w]),
                _ => return None,
            }
        }
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_value_refuses_non_finite_and_overflowing_numbers() {
        let float = Type::Scalar(Scalar::Float);
        assert!(matches!(parse_value(&float, " 1.5 "), Ok(ConstValue::Float(v)) if v == 1.5));
        assert!(matches!(parse_value(&float, "3.4028235e38"), Ok(ConstValue::Float(_))));
        assert!(matches!(parse_value(&float, "-3.4028235e38"), Ok(ConstValue::Float(_))));
        assert!(matches!(parse_value(&float, "1e-50"), Ok(ConstValue::Float(_))));
        for bad in ["nan", "NaN", "inf", "-inf", "infinity", "1e400"] {
            let err = parse_value(&float, bad).unwrap_err();
            assert!(err.contains("not a finite number"), "{bad}: {err}");
        }
        for bad in ["1e39", "-3.5e38"] {
            let err = parse_value(&float, bad).unwrap_err();
            assert!(err.contains("overflows a float"), "{bad}: {err}");
        }
        let int = Type::Scalar(Scalar::Int);
        assert!(matches!(parse_value(&int, "-2147483648"), Ok(ConstValue::Int(-2147483648))));
        for bad in ["2147483648", "-2147483649", "99999999999999999999999"] {
            let err = parse_value(&int, bad).unwrap_err();
            assert!(err.contains("out of range for an int"), "{bad}: {err}");
        }
        assert!(parse_value(&int, "1.5").unwrap_err().contains("not an int"));
        let uint = Type::Scalar(Scalar::UInt);
        assert!(matches!(parse_value(&uint, "4294967295u"), Ok(ConstValue::UInt(4294967295))));
        for bad in ["4294967296", "-1", "5000000000u"] {
            let err = parse_value(&uint, bad).unwrap_err();
            assert!(err.contains("out of range for a uint"), "{bad}: {err}");
        }
        let vec3 = Type::Vector(Scalar::Float, 3);
        assert!(parse_value(&vec3, "0.1,0.2,0.3").is_ok());
        assert!(parse_value(&vec3, "0.1,nan,0.3").unwrap_err().contains("`nan` is not a finite number"));
        let ivec2 = Type::Vector(Scalar::Int, 2);
        assert!(parse_value(&ivec2, "1,3000000000").unwrap_err().contains("out of range"));
    }
}

//! Uniform hints: which hint fits which uniform, and what its arguments must be.

use super::builtins::{HINTS, HintTarget};
use super::consteval::{ConstValue, ValueDisplay};
use super::types::{Scalar, Type};
use super::{Checker, HintInfo};
use crate::diag::codes;
use crate::parse::ast::{self, HintArg};

impl Checker {
    pub(super) fn hints(&mut self, u: &ast::Uniform, ty: &Type, default: Option<&ConstValue>) -> Vec<HintInfo> {
        let mut out = Vec::new();
        let mut filter_seen: Option<&str> = None;
        let mut repeat_seen: Option<&str> = None;
        let elem = match ty {
            Type::Array(t, _) => t.as_ref(),
            t => t,
        };
        let tname = self.type_name(ty);
        for hint in &u.hints {
            let name = hint.name.name.as_str();
            let Some(&(_, target)) = HINTS.iter().find(|(n, _)| *n == name) else {
                self.error(codes::BAD_HINT, format!("unknown hint `{name}`"), hint.name.span, "not a uniform hint");
                continue;
            };
            let fits = match target {
                HintTarget::IntOrFloat => matches!(elem, Type::Scalar(Scalar::Int | Scalar::Float)),
                HintTarget::Int => matches!(elem, Type::Scalar(Scalar::Int)),
                HintTarget::ColorOrSampler => {
                    matches!(elem, Type::Vector(Scalar::Float, 3 | 4) | Type::Sampler(..))
                }
                HintTarget::Color => {
                    matches!(elem, Type::Vector(Scalar::Float, 3 | 4) | Type::Sampler(..))
                }
                HintTarget::Sampler => matches!(elem, Type::Sampler(..)),
                HintTarget::ScreenTexture => matches!(ty, Type::Sampler(..)),
                HintTarget::NotInSky => {
                    self.error(
                        codes::BAD_HINT,
                        format!("hint `{name}` is not available in sky shaders"),
                        hint.name.span,
                        "",
                    );
                    continue;
                }
            };
            if !fits {
                let wants = match target {
                    HintTarget::IntOrFloat => "an `int` or `float` uniform",
                    HintTarget::Int => "an `int` uniform",
                    HintTarget::ColorOrSampler | HintTarget::Color => "a `vec3`, `vec4` or sampler uniform",
                    _ => "a sampler uniform",
                };
                self.error(
                    codes::BAD_HINT,
                    format!("hint `{name}` cannot be used on a uniform of type `{tname}`"),
                    hint.name.span,
                    format!("needs {wants}"),
                );
                continue;
            }
            if name.starts_with("filter_") {
                if let Some(prev) = filter_seen {
                    self.error(
                        codes::BAD_HINT,
                        format!("filter hint `{name}` conflicts with `{prev}`"),
                        hint.name.span,
                        "second filter hint",
                    );
                    continue;
                }
                filter_seen = Some(name);
            }
            if name.starts_with("repeat_") {
                if let Some(prev) = repeat_seen {
                    self.error(
                        codes::BAD_HINT,
                        format!("repeat hint `{name}` conflicts with `{prev}`"),
                        hint.name.span,
                        "second repeat hint",
                    );
                    continue;
                }
                repeat_seen = Some(name);
            }
            if name == "color_conversion_disabled" && !out.iter().any(|h: &HintInfo| h.name == "source_color") {
                self.error(
                    codes::BAD_HINT,
                    "Hint 'color_conversion_disabled' should be preceded by 'source_color'.",
                    hint.name.span,
                    "",
                );
                continue;
            }
            if out.iter().any(|h: &HintInfo| h.name == name) {
                self.error(codes::BAD_HINT, format!("hint `{name}` is given twice"), hint.name.span, "repeated");
                continue;
            }
            let args = match name {
                "hint_range" => self.hint_range(hint, default, *elem == Type::INT),
                "hint_enum" => self.hint_enum(hint),
                _ => {
                    if !hint.args.is_empty() {
                        self.error(codes::BAD_HINT, format!("hint `{name}` takes no arguments"), hint.span, "");
                    }
                    Some(Vec::new())
                }
            };
            if target == HintTarget::ScreenTexture {
                self.diags.push(
                    crate::parse::SpannedDiagnostic::warning(
                        codes::SCREEN_TEXTURE_IN_SKY,
                        format!("`{}` has no screen texture to read in a sky shader", u.name.name),
                        hint.name.span,
                        "not available in sky shaders",
                    )
                    .note("Godot 4.6 accepts the declaration, but reading the uniform is an error"),
                );
            }
            if let Some(args) = args {
                out.push(HintInfo { name: name.to_string(), args });
            }
        }
        out
    }

    /// `hint_range(min, max[, step])`: numeric constants, min < max, step > 0, default inside.
    fn hint_range(&mut self, hint: &ast::Hint, default: Option<&ConstValue>, u_is_int: bool) -> Option<Vec<String>> {
        if !(2..=3).contains(&hint.args.len()) {
            self.error(
                codes::BAD_HINT,
                format!("`hint_range` takes 2 or 3 arguments (min, max[, step]), not {}", hint.args.len()),
                hint.span,
                "",
            );
            return None;
        }
        let mut values = Vec::new();
        for arg in &hint.args {
            let HintArg::Expr(e) = arg else {
                if let HintArg::Str(_, span) = arg {
                    self.error(codes::BAD_HINT, "`hint_range` arguments must be numbers", *span, "a string");
                }
                return None;
            };
            let info = self.expr(e)?;
            match info.value.as_ref().and_then(ConstValue::as_f64).filter(|_| info.constant && info.ty.is_numeric()) {
                Some(v) => values.push(v),
                None => {
                    self.error(
                        codes::BAD_HINT,
                        "`hint_range` arguments must be constant numbers",
                        e.span,
                        "not a constant number",
                    );
                    return None;
                }
            }
        }
        // Godot checks none of the following; they are warnings because the editor slider
        // they produce is unusable or the default is clamped as soon as it is touched.
        let (min, max) = (values[0], values[1]);
        if min >= max {
            self.warn(format!("`hint_range` minimum {min} is not below its maximum {max}"), hint.span);
        }
        if let Some(&step) = values.get(2)
            && step <= 0.0
        {
            self.warn(format!("`hint_range` step {step} is not greater than zero"), hint.span);
        }
        if let Some(d) = default.and_then(ConstValue::as_f64)
            && !(min.min(max)..=max.max(min)).contains(&d)
        {
            self.warn(format!("default value {d} is outside the hint range [{min}, {max}]"), hint.span);
        }
        // Written the way the uniform's type reads them: `0.0` for a float, `0` for an int.
        let ty = if u_is_int { Type::INT } else { Type::FLOAT };
        Some(
            values
                .iter()
                .map(|&v| {
                    let value = if u_is_int { ConstValue::Int(v as i64) } else { ConstValue::Float(v) };
                    ValueDisplay { value: &value, ty: &ty, structs: &[] }.to_string()
                })
                .collect(),
        )
    }

    fn warn(&mut self, message: String, span: crate::parse::ast::Span) {
        self.diags.push(
            crate::parse::SpannedDiagnostic::warning(codes::SUSPICIOUS_HINT, message, span, "")
                .note("Godot accepts this, but the inspector slider will not behave as intended"),
        );
    }

    fn hint_enum(&mut self, hint: &ast::Hint) -> Option<Vec<String>> {
        if hint.args.is_empty() {
            self.error(codes::BAD_HINT, "`hint_enum` needs at least one name", hint.span, "");
            return None;
        }
        let mut names = Vec::new();
        for arg in &hint.args {
            match arg {
                HintArg::Str(s, _) => names.push(s.clone()),
                HintArg::Expr(e) => {
                    self.error(
                        codes::BAD_HINT,
                        "`hint_enum` arguments must be strings, like `hint_enum(\"Low\", \"High\")`",
                        e.span,
                        "not a string",
                    );
                    return None;
                }
            }
        }
        Some(names)
    }
}

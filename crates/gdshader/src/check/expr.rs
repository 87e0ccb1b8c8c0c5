//! Expressions: name resolution, typing with Godot's casting rules, constant folding,
//! assignability, calls and constructors.

use super::builtins::{self, BuiltinScope};
use super::consteval::{self, ConstValue};
use super::reduce::converts_to;
use super::types::{Scalar, Type};
use super::{Checker, Global};
use crate::diag::codes;
use crate::parse::ast::{self, BinaryOp, Expr, ExprKind, UnaryOp};

/// What the checker knows about an expression.
#[derive(Clone, Debug)]
pub(super) struct ExprInfo {
    pub ty: Type,
    /// A compile-time constant (its value may still be unknown, e.g. `sin(1.0)`).
    pub constant: bool,
    pub value: Option<ConstValue>,
}

impl ExprInfo {
    fn runtime(ty: Type) -> Self {
        Self { ty, constant: false, value: None }
    }

    fn constant(ty: Type, value: Option<ConstValue>) -> Self {
        Self { ty, constant: true, value }
    }
}

/// An int or uint literal, possibly signed (for messages; what Godot converts is decided by
/// [`converts_to`]).
fn is_int_literal(e: &Expr) -> bool {
    match &e.kind {
        ExprKind::IntLit(_) | ExprKind::UIntLit(_) => true,
        ExprKind::Unary { op: UnaryOp::Neg | UnaryOp::Plus, operand } => {
            matches!(operand.kind, ExprKind::IntLit(_) | ExprKind::UIntLit(_))
        }
        _ => false,
    }
}

const SWIZZLE_SETS: [&str; 3] = ["xyzw", "rgba", "stpq"];

/// Whether Godot's `_eval_scalar` (servers/rendering/shader_language.cpp) refuses `_ / divisor`
/// or `_ % divisor` with a result of type `ty`: an int or int-vector division or remainder by a
/// zero component, a `uint` division by zero (Godot checks `uint` scalars only: a `uvec`
/// division falls into its float branch), a `uint` or `uvec` remainder by zero.
fn godot_divides_by_zero(op: BinaryOp, ty: &Type, divisor: &ConstValue) -> bool {
    let zero = divisor.scalars().iter().any(|v| matches!(v, ConstValue::Int(0) | ConstValue::UInt(0)));
    zero && match (op, ty) {
        (BinaryOp::Div | BinaryOp::Rem, t) if t.scalar() == Some(Scalar::Int) => true,
        (BinaryOp::Div, Type::Scalar(Scalar::UInt)) => true,
        (BinaryOp::Rem, t) => t.scalar() == Some(Scalar::UInt),
        _ => false,
    }
}

impl Checker {
    /// Checks an expression and records its type.
    pub(super) fn expr(&mut self, e: &Expr) -> Option<ExprInfo> {
        let info = self.expr_kind(e);
        if let (Some(slot), Some(i)) = (self.expr_types.get_mut(e.id.0 as usize), &info) {
            *slot = Some(i.ty.clone());
        }
        info
    }

    fn set_type(&mut self, e: &Expr, ty: &Type) {
        if let Some(slot) = self.expr_types.get_mut(e.id.0 as usize) {
            *slot = Some(ty.clone());
        }
    }

    /// Records the type a constant argument is converted to, when it is a literal: on the
    /// argument and, through a unary `-` or `+`, on the literal it applies to (so `-3` given to a
    /// float is a float `3` negated). A converted constructor (`int(2)` in `vec2(1.0, int(2))`)
    /// keeps its own type: the conversion is then explicit in the lowering.
    pub(super) fn set_converted(&mut self, e: &Expr, ty: &Type) {
        match &e.kind {
            ExprKind::IntLit(_) | ExprKind::UIntLit(_) => self.set_type(e, ty),
            ExprKind::Unary { op: UnaryOp::Neg | UnaryOp::Plus, operand } if is_int_literal(e) => {
                self.set_type(e, ty);
                self.set_converted(operand, ty);
            }
            // A constant constructor (`int(2)`): the lowering converts its value to `ty`.
            ExprKind::Call { .. } => self.set_type(e, ty),
            _ => {}
        }
    }

    /// Checks `init` as the initial value of something of type `ty` (a declaration, a default,
    /// a `return`): `{…}` lists are allowed here, and the types must match exactly.
    pub(super) fn initializer(&mut self, init: &Expr, ty: &Type) -> Option<ExprInfo> {
        if let ExprKind::InitList(items) = &init.kind {
            let Type::Array(elem, len) = ty else {
                let t = self.type_name(ty);
                self.error(
                    codes::BAD_ARRAY,
                    format!("a `{{…}}` list can only initialize an array, not `{t}`"),
                    init.span,
                    "",
                );
                return None;
            };
            if items.len() != *len as usize {
                self.error(
                    codes::BAD_ARRAY,
                    format!("the array has {len} elements but the list gives {}", items.len()),
                    init.span,
                    "",
                );
                return None;
            }
            let mut constant = true;
            let mut values = Some(Vec::new());
            let mut ok = true;
            for item in items {
                match self.initializer(item, elem) {
                    Some(i) => {
                        constant &= i.constant;
                        match (i.value, values.as_mut()) {
                            (Some(v), Some(vs)) => vs.push(v),
                            _ => values = None,
                        }
                    }
                    None => ok = false,
                }
            }
            self.set_type(init, ty);
            return ok.then(|| ExprInfo { ty: ty.clone(), constant, value: values.map(ConstValue::Composite) });
        }
        let info = self.expr(init)?;
        if info.ty != *ty {
            self.mismatch(init, &info.ty, ty, "type mismatch: expected `{to}`, found `{from}`");
            return None;
        }
        Some(info)
    }

    /// Reports a type mismatch, with a note on Godot's int→float rule where it applies.
    fn mismatch(&mut self, e: &Expr, from: &Type, to: &Type, template: &str) {
        let (f, t) = (self.type_name(from), self.type_name(to));
        let message = template.replace("{from}", &f).replace("{to}", &t);
        let d = self.error(codes::TYPE_MISMATCH, message, e.span, format!("this is `{f}`"));
        if from.scalar() == Some(Scalar::Int) && to.scalar() == Some(Scalar::Float) {
            d.diagnostic.notes.push(if is_int_literal(e) {
                "Godot does not convert int to float implicitly: write a float literal such as `2.0`".into()
            } else {
                format!("Godot does not convert int to float implicitly: convert with `{t}(...)`")
            });
        }
    }

    fn expr_kind(&mut self, e: &Expr) -> Option<ExprInfo> {
        match &e.kind {
            ExprKind::IntLit(v) => Some(ExprInfo::constant(Type::INT, Some(ConstValue::Int(*v as i32 as i64)))),
            ExprKind::UIntLit(v) => Some(ExprInfo::constant(Type::UINT, Some(ConstValue::UInt(u64::from(*v))))),
            ExprKind::FloatLit(v) => Some(ExprInfo::constant(Type::FLOAT, Some(ConstValue::Float(*v)))),
            ExprKind::BoolLit(b) => Some(ExprInfo::constant(Type::BOOL, Some(ConstValue::Bool(*b)))),
            ExprKind::Error => None,
            ExprKind::Ident(id) => self.ident(id),
            ExprKind::Call { callee, args } => self.call(e, callee, args),
            ExprKind::ArrayCtor { elem, size, args } => self.array_ctor(e, elem, size.as_deref(), args),
            ExprKind::InitList(_) => {
                self.error(
                    codes::BAD_ARRAY,
                    "a `{…}` list is only allowed as the initializer of an array or in `return`",
                    e.span,
                    "",
                );
                None
            }
            ExprKind::Member { base, name } => self.member(base, name),
            ExprKind::MethodCall { base, name, args } => self.method(base, name, args),
            ExprKind::Index { base, index } => self.index(base, index),
            ExprKind::Unary { op, operand } => self.unary(e, *op, operand),
            ExprKind::IncDec { op, target } => {
                let info = self.expr(target)?;
                // Godot: int, uint and float scalars and vectors; not matrices ("Invalid base type
                // for increment/decrement operator.").
                if !info.ty.is_numeric() || matches!(info.ty, Type::Matrix(_)) {
                    let t = self.type_name(&info.ty);
                    let sym = if op.increment { "++" } else { "--" };
                    self.error(
                        codes::TYPE_MISMATCH,
                        format!("`{sym}` needs an int, uint or float scalar or vector, not `{t}`"),
                        target.span,
                        "",
                    );
                    return None;
                }
                self.assignable(target)?;
                Some(ExprInfo::runtime(info.ty))
            }
            ExprKind::Binary { op, lhs, rhs } => self.binary(e, *op, lhs, rhs),
            ExprKind::Assign { op, target, value } => self.assign(*op, target, value),
            ExprKind::Ternary { cond, then, otherwise } => {
                let c = self.expr(cond);
                let a = self.expr(then);
                let b = self.expr(otherwise);
                if let Some(c) = &c
                    && c.ty != Type::BOOL
                {
                    let t = self.type_name(&c.ty);
                    self.error(
                        codes::TYPE_MISMATCH,
                        format!("the condition of `?:` must be `bool`, not `{t}`"),
                        cond.span,
                        "",
                    );
                }
                let (c, a, b) = (c?, a?, b?);
                if a.ty != b.ty {
                    let (x, y) = (self.type_name(&a.ty), self.type_name(&b.ty));
                    self.error(
                        codes::TYPE_MISMATCH,
                        format!("the branches of `?:` have different types, `{x}` and `{y}`"),
                        then.span.to(otherwise.span),
                        "",
                    )
                    .diagnostic
                    .notes
                    .push("both branches must have the same type".into());
                    return None;
                }
                let constant = c.constant && a.constant && b.constant;
                let value = match c.value {
                    Some(ConstValue::Bool(true)) => a.value,
                    Some(ConstValue::Bool(false)) => b.value,
                    _ => None,
                };
                Some(ExprInfo { ty: a.ty, constant, value: value.filter(|_| constant) })
            }
        }
    }

    fn ident(&mut self, id: &ast::Ident) -> Option<ExprInfo> {
        if let Some(local) = self.scopes.iter().rev().find_map(|s| s.get(&id.name)) {
            return Some(ExprInfo { ty: local.ty.clone()?, constant: local.is_const, value: local.value.clone() });
        }
        if let Some(g) = self.globals.get(&id.name) {
            return match g {
                Global::Const { ty, value } => Some(ExprInfo::constant(ty.clone(), value.clone())),
                Global::Uniform { ty, screen_texture } => {
                    if *screen_texture {
                        let ty = ty.clone();
                        self.error(
                            codes::SCREEN_TEXTURE_READ,
                            format!("`{}` is a screen texture, which sky shaders cannot read", id.name),
                            id.span,
                            "read here",
                        )
                        .diagnostic
                        .notes
                        .push(
                            "Godot 4.6 compiles a read of a `hint_screen_texture` uniform into its `color_buffer`, \
                             which sky shaders do not declare, so the shader fails to compile \
                             (\"'color_buffer' : undeclared identifier\"); Godot 4.7 refuses the hint in sky shaders"
                                .into(),
                        );
                        return Some(ExprInfo::runtime(ty));
                    }
                    Some(ExprInfo::runtime(ty.clone()))
                }
                Global::Struct => {
                    self.error(
                        codes::TYPE_MISMATCH,
                        format!("`{}` is a struct type, not a value", id.name),
                        id.span,
                        "",
                    )
                    .diagnostic
                    .notes
                    .push(format!("construct one with `{}(...)`", id.name));
                    None
                }
            };
        }
        if let Some(b) = builtins::builtin_var(&id.name) {
            let in_sky = self.current.as_ref().is_some_and(|c| c.is_sky);
            if b.scope == BuiltinScope::SkyOnly && !in_sky {
                let where_ = match &self.current {
                    Some(c) => format!("in `{}()`", c.name),
                    None => "outside a function".to_string(),
                };
                self.error(
                    codes::BUILTIN_SCOPE,
                    format!("`{}` exists only inside `sky()`, not {where_}", b.name),
                    id.span,
                    "not available here",
                )
                .diagnostic
                .notes
                .push("pass the value to the function as a parameter instead".into());
                return None;
            }
            self.builtins_used.insert(b.name);
            let ty = Type::from_name(b.ty)?;
            return Some(match builtins::builtin_constant(b.name) {
                Some(v) => ExprInfo::constant(ty, Some(ConstValue::Float(v))),
                None => ExprInfo::runtime(ty),
            });
        }
        if self.global_spans.contains_key(&id.name) {
            // Declared, but its declaration had an error that was already reported.
            return None;
        }
        if self.functions.contains_key(&id.name) || builtins::builtin_function(&id.name).is_some() {
            self.error(codes::TYPE_MISMATCH, format!("`{}` is a function; call it with `(...)`", id.name), id.span, "");
            return None;
        }
        let d =
            self.error(codes::UNDECLARED, format!("unknown identifier `{}`", id.name), id.span, "not declared here");
        if let Some(b) = builtins::BUILTIN_VARS.iter().find(|b| b.name.eq_ignore_ascii_case(&id.name)) {
            d.diagnostic.notes.push(format!("the built-in is spelled `{}`", b.name));
        }
        None
    }

    /// Checks that `target` (already typed) can be written.
    fn assignable(&mut self, target: &Expr) -> Option<()> {
        match &target.kind {
            ExprKind::Ident(id) => {
                if let Some(local) = self.scopes.iter().rev().find_map(|s| s.get(&id.name)) {
                    if local.is_const {
                        self.error(
                            codes::NOT_ASSIGNABLE,
                            "Constants cannot be modified.",
                            target.span,
                            format!("`{}` is constant", id.name),
                        );
                        return None;
                    }
                    return Some(());
                }
                match self.globals.get(&id.name) {
                    Some(Global::Const { .. }) => {
                        self.error(
                            codes::NOT_ASSIGNABLE,
                            "Constants cannot be modified.",
                            target.span,
                            format!("`{}` is constant", id.name),
                        );
                        return None;
                    }
                    Some(Global::Uniform { .. }) => {
                        self.error(
                            codes::NOT_ASSIGNABLE,
                            format!("uniform `{}` is read-only in the shader", id.name),
                            target.span,
                            "",
                        )
                        .diagnostic
                        .notes
                        .push("copy it into a local variable to change it".into());
                        return None;
                    }
                    _ => {}
                }
                if let Some(b) = builtins::builtin_var(&id.name)
                    && !b.writable
                {
                    self.error(codes::NOT_ASSIGNABLE, format!("built-in `{}` is read-only", b.name), target.span, "")
                        .diagnostic
                        .notes
                        .push("a sky shader writes only COLOR, ALPHA and FOG".into());
                    return None;
                }
                Some(())
            }
            ExprKind::Member { base, name } => {
                let base_ty = self.expr_types.get(base.id.0 as usize).cloned().flatten();
                if matches!(base_ty, Some(Type::Vector(..))) {
                    let mut seen = [false; 4];
                    for c in name.name.chars() {
                        let i = SWIZZLE_SETS.iter().find_map(|s| s.find(c)).unwrap_or(0);
                        if std::mem::replace(&mut seen[i], true) {
                            self.error(
                                codes::NOT_ASSIGNABLE,
                                format!("cannot assign to swizzle `.{}`: it repeats a component", name.name),
                                name.span,
                                "",
                            );
                            return None;
                        }
                    }
                }
                self.assignable(base)
            }
            ExprKind::Index { base, .. } => self.assignable(base),
            _ => {
                self.error(
                    codes::NOT_ASSIGNABLE,
                    "this expression cannot be assigned to",
                    target.span,
                    "not a variable",
                );
                None
            }
        }
    }

    fn assign(&mut self, op: Option<BinaryOp>, target: &Expr, value: &Expr) -> Option<ExprInfo> {
        let t = self.expr(target);
        let v = self.expr(value);
        let (t, v) = (t?, v?);
        self.assignable(target)?;
        let result = match op {
            None => v.ty.clone(),
            // No result type falls through to the mismatch report below.
            Some(op) => self.binary_type(op, &t.ty, &v.ty, true).unwrap_or(Type::Void),
        };
        if result != t.ty {
            match op {
                None => self.mismatch(value, &v.ty, &t.ty, "cannot assign `{from}` to `{to}`"),
                Some(op) => {
                    let (a, b) = (self.type_name(&t.ty), self.type_name(&v.ty));
                    self.error(
                        codes::TYPE_MISMATCH,
                        format!("invalid operands `{a}` and `{b}` for `{}=`", op.symbol()),
                        target.span.to(value.span),
                        "",
                    );
                }
            }
            return None;
        }
        Some(ExprInfo::runtime(t.ty))
    }

    fn unary(&mut self, e: &Expr, op: UnaryOp, operand: &Expr) -> Option<ExprInfo> {
        let info = self.expr(operand)?;
        let ok = match op {
            // Godot negates int, uint and float scalars and vectors, not matrices.
            UnaryOp::Neg => info.ty.is_numeric() && !matches!(info.ty, Type::Matrix(_)),
            // Godot's parser drops a unary `+` whatever follows it.
            UnaryOp::Plus => true,
            UnaryOp::Not => info.ty == Type::BOOL,
            UnaryOp::BitNot => info.ty.is_integer(),
        };
        if !ok {
            let t = self.type_name(&info.ty);
            let sym = match op {
                UnaryOp::Neg => "-",
                UnaryOp::Plus => "+",
                UnaryOp::Not => "!",
                UnaryOp::BitNot => "~",
            };
            self.error(codes::TYPE_MISMATCH, format!("invalid operand `{t}` for unary `{sym}`"), e.span, "");
            return None;
        }
        let value = info.value.as_ref().and_then(|v| consteval::unary(op, v));
        Some(ExprInfo { ty: info.ty, constant: info.constant, value })
    }

    /// The result type of `a op b` (of `a op= b` when `compound`), as Godot's
    /// `_validate_operator` decides it: GLSL ES 3.0 without implicit conversions, with Godot's
    /// own restrictions (`%` and shifts take a scalar on the right only; `&`, `|`, `^` mix a
    /// vector and a scalar only in `&=`, `|=`, `^=`).
    fn binary_type(&self, op: BinaryOp, a: &Type, b: &Type, compound: bool) -> Option<Type> {
        use BinaryOp::*;
        let same_scalar = a.scalar().is_some() && a.scalar() == b.scalar();
        match op {
            Add | Sub | Mul | Div => {
                if !a.is_numeric() || !b.is_numeric() || !same_scalar {
                    return None;
                }
                match (a, b) {
                    _ if a == b => Some(a.clone()),
                    (Type::Scalar(_), Type::Vector(..) | Type::Matrix(_)) => Some(b.clone()),
                    (Type::Vector(..) | Type::Matrix(_), Type::Scalar(_)) => Some(a.clone()),
                    (Type::Matrix(n), Type::Vector(_, m)) | (Type::Vector(_, m), Type::Matrix(n))
                        if op == Mul && n == m =>
                    {
                        Some(Type::Vector(Scalar::Float, *n))
                    }
                    _ => None,
                }
            }
            // Godot's table lists `ivecN & int`, but for `&`, `|`, `^` it first swaps the operands
            // so that the scalar comes first, and then finds no entry: only the compound forms
            // accept a vector and a scalar.
            BitAnd | BitOr | BitXor if !compound => (a == b && a.is_integer()).then(|| a.clone()),
            BitAnd | BitOr | BitXor | Rem | Shl | Shr => {
                if !a.is_integer() || !b.is_integer() || !same_scalar {
                    return None;
                }
                match (a, b) {
                    _ if a == b => Some(a.clone()),
                    (Type::Vector(..), Type::Scalar(_)) => Some(a.clone()),
                    _ => None,
                }
            }
            Less | Greater | LessEq | GreaterEq => {
                (a == b && matches!(a, Type::Scalar(Scalar::Int | Scalar::UInt | Scalar::Float))).then_some(Type::BOOL)
            }
            // Godot compares no arrays.
            Eq | NotEq => {
                (a == b && !a.is_opaque() && *a != Type::Void && !matches!(a, Type::Array(..))).then_some(Type::BOOL)
            }
            LogicalAnd | LogicalOr => (*a == Type::BOOL && *b == Type::BOOL).then_some(Type::BOOL),
        }
    }

    fn binary(&mut self, e: &Expr, op: BinaryOp, lhs: &Expr, rhs: &Expr) -> Option<ExprInfo> {
        let a = self.expr(lhs);
        let b = self.expr(rhs);
        let (a, b) = (a?, b?);
        let Some(ty) = self.binary_type(op, &a.ty, &b.ty, false) else {
            let (x, y) = (self.type_name(&a.ty), self.type_name(&b.ty));
            let d = self.error(
                codes::TYPE_MISMATCH,
                format!("invalid operands `{x}` and `{y}` for `{}`", op.symbol()),
                e.span,
                "",
            );
            if a.ty.scalar() != b.ty.scalar() && a.ty.is_numeric() && b.ty.is_numeric() {
                let literal = if is_int_literal(lhs) || is_int_literal(rhs) {
                    " (write int literals as floats, e.g. `2.0`)"
                } else {
                    ""
                };
                d.diagnostic.notes.push(format!(
                    "Godot does not mix int and float in arithmetic; convert one side explicitly{literal}"
                ));
            }
            return None;
        };
        let constant = a.constant && b.constant;
        let value = match (&a.value, &b.value) {
            (Some(x), Some(y)) if constant => {
                if self.op_eval && godot_divides_by_zero(op, &ty, y) {
                    let what = if op == BinaryOp::Div { "Division" } else { "Modulo" };
                    self.error(
                        codes::DIVISION_BY_ZERO,
                        format!("{what} by zero error."),
                        e.span,
                        "the divisor is zero",
                    )
                    .diagnostic
                    .notes
                    .push(
                        "Godot evaluates constant integer operands here and refuses a zero divisor (only the \
                             initializer of a non-`const` local variable is left to run time)"
                            .into(),
                    );
                    return None;
                }
                consteval::binary(op, x, y, &a.ty, &b.ty)
            }
            _ => None,
        };
        Some(ExprInfo { ty, constant, value })
    }

    fn member(&mut self, base: &Expr, name: &ast::Ident) -> Option<ExprInfo> {
        let info = self.expr(base)?;
        match &info.ty {
            Type::Vector(scalar, n) => {
                let s = name.name.as_str();
                let Some(set) = SWIZZLE_SETS.iter().find(|set| s.chars().next().is_some_and(|c| set.contains(c)))
                else {
                    self.error(codes::BAD_MEMBER, format!("invalid swizzle `.{s}`"), name.span, "")
                        .diagnostic
                        .notes
                        .push("swizzles use the letters xyzw, rgba or stpq".into());
                    return None;
                };
                if let Some(other) = s.chars().find(|c| !set.contains(*c)) {
                    if SWIZZLE_SETS.iter().any(|set| set.contains(other)) {
                        self.error(
                            codes::BAD_MEMBER,
                            format!("Cannot combine symbols from different sets in expression '.{s}'."),
                            name.span,
                            "",
                        )
                        .diagnostic
                        .notes
                        .push(format!("use letters from one set only: {}", SWIZZLE_SETS.join(", ")));
                    } else {
                        self.error(
                            codes::BAD_MEMBER,
                            format!("invalid swizzle `.{s}`: `{other}` is not a component name"),
                            name.span,
                            "",
                        );
                    }
                    return None;
                }
                if s.len() > 4 {
                    self.error(codes::BAD_MEMBER, format!("swizzle `.{s}` has more than 4 components"), name.span, "");
                    return None;
                }
                let indices: Vec<usize> = s.chars().filter_map(|c| set.find(c)).collect();
                if let Some(&bad) = indices.iter().find(|&&i| i >= *n as usize) {
                    let t = self.type_name(&info.ty);
                    let c = set.as_bytes()[bad] as char;
                    self.error(
                        codes::BAD_MEMBER,
                        format!("`{t}` has no component `{c}`"),
                        name.span,
                        format!("`{t}` has {n} components"),
                    );
                    return None;
                }
                let ty = Type::vector_of(*scalar, indices.len() as u8);
                let value = match &info.value {
                    Some(ConstValue::Composite(c)) => {
                        let picked: Option<Vec<ConstValue>> = indices.iter().map(|&i| c.get(i).cloned()).collect();
                        picked.map(|p| if p.len() == 1 { p[0].clone() } else { ConstValue::Composite(p) })
                    }
                    _ => None,
                };
                Some(ExprInfo { ty, constant: info.constant, value })
            }
            Type::Struct(id) => {
                let member = self
                    .structs
                    .get(id.0 as usize)
                    .and_then(|s| s.members.iter().find(|(m, _)| *m == name.name))
                    .map(|(_, t)| t.clone());
                match member {
                    Some(ty) => Some(ExprInfo { ty, constant: info.constant, value: None }),
                    None => {
                        let t = self.type_name(&info.ty);
                        self.error(
                            codes::BAD_MEMBER,
                            format!("struct `{t}` has no member `{}`", name.name),
                            name.span,
                            "",
                        );
                        None
                    }
                }
            }
            Type::Array(..) if name.name == "length" => {
                self.error(codes::BAD_MEMBER, "the array length is a method: write `.length()`", name.span, "");
                None
            }
            other => {
                let t = self.type_name(other);
                self.error(codes::BAD_MEMBER, format!("`{t}` has no member `{}`", name.name), name.span, "");
                None
            }
        }
    }

    fn method(&mut self, base: &Expr, name: &ast::Ident, args: &[Expr]) -> Option<ExprInfo> {
        let info = self.expr(base)?;
        match (&info.ty, name.name.as_str()) {
            (Type::Array(_, n), "length") if args.is_empty() => {
                Some(ExprInfo::constant(Type::INT, Some(ConstValue::Int(i64::from(*n)))))
            }
            (Type::Array(..), "length") => {
                self.error(codes::NO_MATCHING_OVERLOAD, "`.length()` takes no arguments", name.span, "");
                None
            }
            (ty, m) => {
                let t = self.type_name(ty);
                self.error(codes::BAD_MEMBER, format!("`{t}` has no method `{m}`"), name.span, "")
                    .diagnostic
                    .notes
                    .push("the only method is `.length()` on arrays".into());
                None
            }
        }
    }

    fn index(&mut self, base: &Expr, index: &Expr) -> Option<ExprInfo> {
        let b = self.expr(base);
        let i = self.expr(index);
        let (b, i) = (b?, i?);
        if !matches!(i.ty, Type::Scalar(Scalar::Int | Scalar::UInt)) {
            let t = self.type_name(&i.ty);
            self.error(codes::BAD_INDEX, format!("an index must be `int` or `uint`, not `{t}`"), index.span, "");
            return None;
        }
        let (elem, len) = match &b.ty {
            Type::Vector(s, n) => (Type::Scalar(*s), u32::from(*n)),
            Type::Matrix(n) => (Type::Vector(Scalar::Float, *n), u32::from(*n)),
            Type::Array(t, n) => ((**t).clone(), *n),
            other => {
                let t = self.type_name(other);
                self.error(codes::BAD_INDEX, format!("values of type `{t}` cannot be indexed"), base.span, "");
                return None;
            }
        };
        let at = i.value.as_ref().and_then(ConstValue::as_int).filter(|_| i.constant);
        if let Some(k) = at
            && (k < 0 || k >= i64::from(len))
        {
            let t = self.type_name(&b.ty);
            self.error(
                codes::BAD_INDEX,
                format!("index {k} is out of bounds for `{t}`"),
                index.span,
                format!("valid indices are 0 to {}", len - 1),
            );
            return None;
        }
        let value = match (&b.value, at) {
            (Some(ConstValue::Composite(c)), Some(k)) if matches!(b.ty, Type::Vector(..) | Type::Array(..)) => {
                c.get(k as usize).cloned()
            }
            _ => None,
        };
        Some(ExprInfo { ty: elem, constant: b.constant && i.constant, value })
    }

    fn call(&mut self, e: &Expr, callee: &ast::Ident, args: &[Expr]) -> Option<ExprInfo> {
        if let Some(ty) = Type::from_name(&callee.name) {
            return self.constructor(e, callee, ty, args);
        }
        if let Some(id) = self.struct_ids.get(&callee.name).copied() {
            return self.struct_ctor(e, id, args);
        }
        if let Some(ctx) = &self.current
            && ctx.name == callee.name
            && self.functions.contains_key(&callee.name)
        {
            for a in args {
                self.expr(a);
            }
            self.error(
                codes::RECURSION,
                "Recursion is not allowed.",
                callee.span,
                format!("`{}` calls itself", callee.name),
            )
            .diagnostic
            .notes
            .push("GPU shaders cannot recurse; rewrite it as a loop".into());
            return None;
        }
        let infos: Vec<Option<ExprInfo>> = args.iter().map(|a| self.expr(a)).collect();
        let infos: Vec<ExprInfo> = infos.into_iter().collect::<Option<_>>()?;
        if let Some(local) = self.scopes.iter().rev().find_map(|s| s.get(&callee.name)).map(|l| l.span) {
            let label = if self.functions.contains_key(&callee.name) {
                "this variable hides the function"
            } else {
                "declared here as a variable"
            };
            self.error(
                codes::NOT_CALLABLE,
                format!("`{}` is a local variable here, not a function", callee.name),
                callee.span,
                "",
            )
            .secondary
            .push((local, label.into()));
            return None;
        }
        if let Some(overloads) = self.functions.get(&callee.name).cloned() {
            // Godot converts scalar constants for a user function too, but only when it has a
            // single definition (with overloads the constant's own type picks one).
            let convert = overloads.len() == 1;
            let found = overloads.iter().find(|f| {
                f.params.len() == infos.len()
                    && f.params
                        .iter()
                        .zip(&infos)
                        .zip(args)
                        .all(|((p, a), arg)| p.0 == a.ty || (convert && converts_to(arg, &p.0)))
            });
            let Some(f) = found else {
                let wanted: Vec<String> = overloads
                    .iter()
                    .map(|f| {
                        format!(
                            "{}({})",
                            callee.name,
                            f.params.iter().map(|p| self.type_name(&p.0)).collect::<Vec<_>>().join(", ")
                        )
                    })
                    .collect();
                let given = self.arg_list(&infos);
                let d = self.error(
                    codes::NO_MATCHING_OVERLOAD,
                    format!("no function `{}` takes ({given})", callee.name),
                    e.span,
                    "",
                );
                d.diagnostic.notes.push(format!("expected {}", wanted.join(" or ")));
                if args.iter().any(is_int_literal) && !convert {
                    d.diagnostic
                        .notes
                        .push("int literals are not converted in calls of an overloaded user function".into());
                }
                return None;
            };
            for ((p, q), (a, info)) in f.params.iter().zip(args.iter().zip(&infos)) {
                if *p != info.ty {
                    self.set_converted(a, p);
                }
                if matches!(q, ast::ParamQualifier::Out | ast::ParamQualifier::InOut) {
                    self.assignable(a)?;
                }
            }
            return Some(ExprInfo::runtime(f.ret.clone()));
        }
        if let Some(sigs) = builtins::builtin_function(&callee.name) {
            return self.builtin_call(e, callee, sigs, args, &infos);
        }
        if self.scopes.iter().any(|s| s.contains_key(&callee.name))
            || self.globals.contains_key(&callee.name)
            || builtins::builtin_var(&callee.name).is_some()
        {
            self.error(codes::NOT_CALLABLE, format!("`{}` is not a function", callee.name), callee.span, "");
        } else {
            self.error(
                codes::UNDECLARED,
                format!("unknown function `{}`", callee.name),
                callee.span,
                "not declared here",
            )
            .diagnostic
            .notes
            .push("functions must be defined above their first use".into());
        }
        None
    }

    fn arg_list(&self, infos: &[ExprInfo]) -> String {
        infos.iter().map(|i| self.type_name(&i.ty)).collect::<Vec<_>>().join(", ")
    }

    /// Built-in call: an exact overload first, then one reached by converting int literals.
    fn builtin_call(
        &mut self,
        e: &Expr,
        callee: &ast::Ident,
        sigs: &[builtins::Signature],
        args: &[Expr],
        infos: &[ExprInfo],
    ) -> Option<ExprInfo> {
        // Godot tries overloads in table order and accepts the first one that fits after
        // converting int literals, so `abs(-3)` is `abs(float)`: float overloads come first.
        let fits = |s: &&builtins::Signature| {
            s.params.len() == infos.len()
                && s.params
                    .iter()
                    .zip(infos)
                    .zip(args)
                    .all(|((p, a), arg)| p.0 == a.ty || (!p.1 && converts_to(arg, &p.0)))
        };
        let Some(sig) = sigs.iter().find(fits) else {
            let given = self.arg_list(infos);
            let mut shown: Vec<String> = Vec::new();
            for s in sigs {
                let text = format!(
                    "{}({})",
                    callee.name,
                    s.params
                        .iter()
                        .map(|p| format!("{}{}", if p.1 { "out " } else { "" }, self.type_name(&p.0)))
                        .collect::<Vec<_>>()
                        .join(", ")
                );
                if !shown.contains(&text) {
                    shown.push(text);
                }
            }
            let more = shown.len().saturating_sub(6);
            shown.truncate(6);
            let d = self.error(
                codes::NO_MATCHING_OVERLOAD,
                format!("no overload of built-in `{}` takes ({given})", callee.name),
                e.span,
                "",
            );
            d.diagnostic.notes.push(format!(
                "overloads include {}{}",
                shown.join(", "),
                if more > 0 { format!(" and {more} more") } else { String::new() }
            ));
            return None;
        };
        for ((p, a), arg) in sig.params.iter().zip(infos).zip(args) {
            if p.0 != a.ty {
                // A constant converted to the parameter type: record the converted type.
                self.set_converted(arg, &p.0);
            }
            if p.1 {
                self.assignable(arg)?;
            }
        }
        let constant = infos.iter().all(|i| i.constant) && sig.params.iter().all(|p| !p.1 && !p.0.is_opaque());
        Some(ExprInfo { ty: sig.ret.clone(), constant, value: None })
    }

    /// `T(args)` for scalars, vectors and matrices.
    fn constructor(&mut self, e: &Expr, callee: &ast::Ident, ty: Type, args: &[Expr]) -> Option<ExprInfo> {
        let infos: Vec<Option<ExprInfo>> = args.iter().map(|a| self.expr(a)).collect();
        let infos: Vec<ExprInfo> = infos.into_iter().collect::<Option<_>>()?;
        let constant = infos.iter().all(|i| i.constant);
        let target = ty.scalar();
        let fail = |c: &mut Checker, why: String| {
            let given = c.arg_list(&infos);
            c.error(
                codes::NO_MATCHING_OVERLOAD,
                format!("cannot construct `{}` from ({given})", callee.name),
                e.span,
                "",
            )
            .diagnostic
            .notes
            .push(why);
            None
        };
        let Some(target) = target else {
            return fail(self, format!("`{}` has no constructor", callee.name));
        };
        if args.is_empty() {
            return fail(self, "a constructor needs at least one argument".into());
        }
        // Scalar constants Godot converts become the target's scalar type; other arguments keep
        // theirs.
        let arg_scalar = |info: &ExprInfo, arg: &Expr| {
            if converts_to(arg, &Type::Scalar(target)) { Some(target) } else { info.ty.scalar() }
        };
        let single = infos.len() == 1;
        match &ty {
            Type::Scalar(_) => {
                if !single || !matches!(infos[0].ty, Type::Scalar(_)) {
                    return fail(self, format!("`{}(...)` takes one scalar", callee.name));
                }
            }
            Type::Vector(_, n) => {
                let whole_vector = single && matches!(infos[0].ty, Type::Vector(_, m) if m == *n);
                if !whole_vector {
                    let mut count = 0u32;
                    for (info, arg) in infos.iter().zip(args) {
                        if !matches!(info.ty, Type::Scalar(_) | Type::Vector(..))
                            || arg_scalar(info, arg) != Some(target)
                        {
                            let t = self.type_name(&info.ty);
                            return fail(
                                self,
                                format!(
                                    "components must be `{}` scalars or vectors, and `{t}` is not (convert it first)",
                                    Type::Scalar(target).display(&[])
                                ),
                            );
                        }
                        count += u32::from(info.ty.components().unwrap_or(0));
                    }
                    if !(single && count == 1) && count != u32::from(*n) {
                        return fail(
                            self,
                            format!(
                                "`{}` needs {n} components (or one scalar), and the arguments give {count}",
                                callee.name
                            ),
                        );
                    }
                }
            }
            Type::Matrix(n) => {
                // Godot's constructor table: one float (the diagonal), one matrix, or N columns.
                let column = Type::Vector(Scalar::Float, *n);
                let ok = single
                    && (matches!(infos[0].ty, Type::Matrix(_) | Type::Scalar(Scalar::Float))
                        || converts_to(&args[0], &Type::FLOAT))
                    || infos.len() == usize::from(*n) && infos.iter().all(|i| i.ty == column);
                if !ok {
                    return fail(
                        self,
                        format!(
                            "`{}` takes one float (the diagonal), one matrix, or {n} `vec{n}` columns",
                            callee.name
                        ),
                    );
                }
            }
            _ => return fail(self, format!("`{}` has no constructor", callee.name)),
        }
        for (info, arg) in infos.iter().zip(args) {
            if matches!(info.ty, Type::Scalar(s) if s != target)
                && !matches!(ty, Type::Scalar(_))
                && converts_to(arg, &Type::Scalar(target))
            {
                self.set_converted(arg, &Type::Scalar(target));
            }
        }
        let value = constant.then(|| construct_value(&ty, &infos)).flatten();
        Some(ExprInfo { ty, constant, value })
    }

    fn struct_ctor(&mut self, e: &Expr, id: super::types::StructId, args: &[Expr]) -> Option<ExprInfo> {
        let info = self.structs.get(id.0 as usize)?.clone();
        // A `{…}` list may initialize an array member.
        let infos: Vec<Option<ExprInfo>> = args
            .iter()
            .enumerate()
            .map(|(i, a)| match (&a.kind, info.members.get(i)) {
                (ExprKind::InitList(_), Some((_, t))) => self.initializer(a, t),
                _ => self.expr(a),
            })
            .collect();
        let infos: Vec<ExprInfo> = infos.into_iter().collect::<Option<_>>()?;
        // Godot converts nothing here: `S(1)` for a float member is "Invalid assignment of 'int'
        // to 'float'".
        let fits = info.members.len() == infos.len() && info.members.iter().zip(&infos).all(|((_, t), a)| *t == a.ty);
        if !fits {
            let given = self.arg_list(&infos);
            let wanted = info.members.iter().map(|(_, t)| self.type_name(t)).collect::<Vec<_>>().join(", ");
            self.error(
                codes::NO_MATCHING_OVERLOAD,
                format!("cannot construct struct `{}` from ({given})", info.name),
                e.span,
                "",
            )
            .diagnostic
            .notes
            .push(format!("expected ({wanted}), one value per member in order"));
            return None;
        }
        let constant = infos.iter().all(|i| i.constant);
        Some(ExprInfo { ty: Type::Struct(id), constant, value: None })
    }

    /// `T[N](args)` / `T[](args)`.
    fn array_ctor(&mut self, e: &Expr, elem: &ast::Ident, size: Option<&Expr>, args: &[Expr]) -> Option<ExprInfo> {
        let elem_ty =
            match Type::from_name(&elem.name).or_else(|| self.struct_ids.get(&elem.name).map(|id| Type::Struct(*id))) {
                Some(t) if t != Type::Void && !t.is_opaque() => t,
                _ => {
                    self.error(
                        codes::UNKNOWN_TYPE,
                        format!("`{}` is not a type that arrays can hold", elem.name),
                        elem.span,
                        "",
                    );
                    return None;
                }
            };
        let len = match size {
            Some(s) => self.array_len(s)?,
            None => args.len() as u32,
        };
        if args.len() != len as usize {
            self.error(
                codes::BAD_ARRAY,
                format!("the array has {len} elements but the constructor gives {}", args.len()),
                e.span,
                "",
            );
            return None;
        }
        let mut constant = true;
        let mut values = Some(Vec::new());
        let mut ok = true;
        // Godot converts nothing here: `float[2](1, 2)` is "Invalid assignment of 'int' to 'float'".
        for arg in args {
            match self.expr(arg) {
                Some(i) if i.ty == elem_ty => {
                    constant &= i.constant;
                    match (i.value, values.as_mut()) {
                        (Some(v), Some(vs)) => vs.push(v),
                        _ => values = None,
                    }
                }
                Some(i) => {
                    self.mismatch(arg, &i.ty, &elem_ty, "array element is `{from}` but the array holds `{to}`");
                    ok = false;
                }
                None => ok = false,
            }
        }
        let ty = Type::Array(Box::new(elem_ty), len);
        ok.then(|| ExprInfo { ty, constant, value: values.filter(|_| constant).map(ConstValue::Composite) })
    }
}

/// The value of a scalar or vector constructor with constant arguments.
fn construct_value(ty: &Type, infos: &[ExprInfo]) -> Option<ConstValue> {
    let target = ty.scalar()?;
    let mut comps = Vec::new();
    for i in infos {
        comps.extend(i.value.as_ref()?.scalars());
    }
    let comps: Vec<ConstValue> = comps.iter().map(|c| c.convert(target)).collect::<Option<_>>()?;
    match ty {
        Type::Scalar(_) => comps.into_iter().next(),
        Type::Vector(_, n) if comps.len() == 1 => Some(ConstValue::Composite(vec![comps[0].clone(); *n as usize])),
        Type::Vector(..) => Some(ConstValue::Composite(comps)),
        _ => None,
    }
}

//! Expressions of one function: values, places (what assignments write), calls.

use super::builder::FnBuilder;
use super::{GlobalConst, Lowerer, literal, scalar, span, vector_size};
use gdshader::check::types::{Scalar as GdScalar, Type as GdType};
use gdshader::parse::ast::{self, BinaryOp, Expr, ExprKind, ParamQualifier, UnaryOp};
use naga::{
    BinaryOperator as Bo, Expression as E, Handle, Literal, RelationalFunction, ScalarKind, Statement,
    SwizzleComponent, UnaryOperator,
};
use std::collections::HashMap;

type H = Handle<E>;

/// A lowered expression: a value, or a pointer to where the value lives.
#[derive(Clone, Copy)]
pub(crate) enum Val {
    Value(H),
    Pointer(H),
}

/// What an assignment writes to.
enum Place {
    /// A pointer to the whole target.
    Pointer(H),
    /// Components `pattern` of the vector behind `pointer`.
    Swizzle { pointer: H, vector: GdType, pattern: Vec<u8> },
}

/// A name in scope inside a function.
#[derive(Clone)]
enum LocalSlot {
    /// A function-space variable.
    Variable(H),
    /// An `out`/`inout` parameter: argument `index` is a pointer.
    OutParam(u32),
    /// An `in` parameter the body never assigns: read straight from the argument.
    Argument(u32),
    /// A sampler parameter: texture argument `index`, its sampler at `index + 1`.
    Sampler(u32, gdshader::check::types::SamplerKind, GdScalar),
    /// A local the function never assigns after its initializer: the initializer's value (a
    /// WGSL `let`), so no variable, store or load is emitted for it.
    Let(H),
}

/// Lowers the body of one function.
pub(crate) struct FnCtx<'l, 'a> {
    pub lw: &'l mut Lowerer<'a>,
    ret: GdType,
    scopes: Vec<HashMap<String, LocalSlot>>,
    /// Names the body writes anywhere (see [`assigned_names`]); a declared local not among them
    /// is a `let`.
    assigned: std::collections::HashSet<String>,
}

const COMPONENTS: [SwizzleComponent; 4] =
    [SwizzleComponent::X, SwizzleComponent::Y, SwizzleComponent::Z, SwizzleComponent::W];

fn swizzle_index(c: char) -> u8 {
    ["xyzw", "rgba", "stpq"].iter().find_map(|set| set.find(c)).unwrap_or(0) as u8
}

/// True when evaluating `e` can change state: assignments, `++`/`--`, and calls of user
/// functions with `out` parameters. Such operands keep `&&`, `||` and `?:` lazy.
pub(super) fn has_side_effects(lw: &Lowerer, e: &Expr) -> bool {
    let any = |es: &[Expr]| es.iter().any(|x| has_side_effects(lw, x));
    match &e.kind {
        ExprKind::Assign { .. } | ExprKind::IncDec { .. } => true,
        ExprKind::Call { callee, args } => {
            lw.functions.get(&callee.name).is_some_and(|fs| {
                fs.iter()
                    .any(|f| f.params.iter().any(|(_, q)| matches!(q, ParamQualifier::Out | ParamQualifier::InOut)))
            }) || any(args)
        }
        ExprKind::ArrayCtor { args, .. } | ExprKind::InitList(args) => any(args),
        ExprKind::Member { base, .. } => has_side_effects(lw, base),
        ExprKind::MethodCall { base, args, .. } => has_side_effects(lw, base) || any(args),
        ExprKind::Index { base, index } => has_side_effects(lw, base) || has_side_effects(lw, index),
        ExprKind::Unary { operand, .. } => has_side_effects(lw, operand),
        ExprKind::Binary { lhs, rhs, .. } => has_side_effects(lw, lhs) || has_side_effects(lw, rhs),
        ExprKind::Ternary { cond, then, otherwise } => [cond, then, otherwise].iter().any(|x| has_side_effects(lw, x)),
        _ => false,
    }
}

impl<'l, 'a> FnCtx<'l, 'a> {
    pub fn new(lw: &'l mut Lowerer<'a>, ret: GdType) -> Self {
        FnCtx { lw, ret, scopes: vec![HashMap::new()], assigned: Default::default() }
    }

    pub fn return_type(&self) -> &GdType {
        &self.ret
    }

    pub fn push_scope(&mut self) {
        self.scopes.push(HashMap::new());
    }

    pub fn pop_scope(&mut self) {
        self.scopes.pop();
    }

    /// Parameters the body assigns become locals (Godot's parameters are assignable); the others
    /// are read from the argument; `out`/`inout` ones are pointers.
    pub fn params(&mut self, b: &mut FnBuilder, f: &ast::Function, params: &[(GdType, ParamQualifier)]) {
        let mut assigned = std::collections::HashSet::new();
        let functions = &self.lw.functions;
        let is_out = |callee: &str, i: usize| {
            matches!((callee, i), ("modf" | "frexp" | "ldexp", 1))
                || functions.get(callee).is_some_and(|fs| {
                    fs.iter().any(|f| {
                        f.params.get(i).is_some_and(|p| matches!(p.1, ParamQualifier::Out | ParamQualifier::InOut))
                    })
                })
        };
        assigned_names(&f.body.stmts, &is_out, &mut assigned);
        self.assigned = assigned.iter().map(|s| s.to_string()).collect();
        let mut next_arg = 0u32;
        for (p, (ty, q)) in f.params.iter().zip(params) {
            let sp = span(p.name.span);
            let i = next_arg;
            next_arg += if matches!(ty, GdType::Sampler(..)) { 2 } else { 1 };
            if let GdType::Sampler(kind, scalar) = ty {
                self.declare(&p.name.name, LocalSlot::Sampler(i, *kind, *scalar));
                continue;
            }
            if matches!(q, ParamQualifier::Out | ParamQualifier::InOut) {
                self.declare(&p.name.name, LocalSlot::OutParam(i));
                continue;
            }
            if !assigned.contains(p.name.name.as_str()) {
                self.declare(&p.name.name, LocalSlot::Argument(i));
                continue;
            }
            let Some(th) = self.lw.ty(ty, p.ty.span) else {
                continue;
            };
            let arg = b.expr(E::FunctionArgument(i), sp);
            let local = b.local(Some(&p.name.name), th, sp);
            b.stmt(Statement::Store { pointer: local, value: arg }, sp);
            self.declare(&p.name.name, LocalSlot::Variable(local));
        }
    }

    fn declare(&mut self, name: &str, slot: LocalSlot) {
        if let Some(scope) = self.scopes.last_mut() {
            scope.insert(name.to_string(), slot);
        }
    }

    /// Declares a local variable of type `ty` named `name`, returning its pointer.
    pub fn declare_variable(&mut self, b: &mut FnBuilder, name: &ast::Ident, ty: &GdType) -> Option<H> {
        let th = self.lw.ty(ty, name.span)?;
        let ptr = b.local(Some(&name.name), th, span(name.span));
        self.declare(&name.name, LocalSlot::Variable(ptr));
        Some(ptr)
    }

    /// Declares `name` as the value `v` when the body never writes it and it is a scalar, a
    /// vector or a matrix (arrays and structs stay variables: they are indexed through a
    /// pointer). Returns false when `name` must be a variable.
    pub fn declare_let(&mut self, b: &mut FnBuilder, name: &ast::Ident, ty: &GdType, v: H) -> bool {
        if self.assigned.contains(&name.name)
            || !matches!(ty, GdType::Scalar(_) | GdType::Vector(..) | GdType::Matrix(_))
        {
            return false;
        }
        if b.known(v).is_none()
            && !b.function.expressions[v].needs_pre_emit()
            && !b.function.named_expressions.contains_key(&v)
        {
            b.function.named_expressions.insert(v, name.name.clone());
        }
        self.declare(&name.name, LocalSlot::Let(v));
        true
    }

    /// A sampler expression (a sampler uniform, an element of a sampler array by a literal index,
    /// or a sampler parameter) as its texture and sampler expressions, with its kind.
    pub fn sampler(
        &mut self,
        b: &mut FnBuilder,
        e: &Expr,
    ) -> Option<(H, H, gdshader::check::types::SamplerKind, GdScalar)> {
        let sp = span(e.span);
        let name = match &e.kind {
            ExprKind::Ident(id) => {
                if let Some(LocalSlot::Sampler(i, kind, scalar)) =
                    self.scopes.iter().rev().find_map(|s| s.get(&id.name)).cloned()
                {
                    let image = b.expr(E::FunctionArgument(i), sp);
                    let sampler = b.expr(E::FunctionArgument(i + 1), sp);
                    return Some((image, sampler, kind, scalar));
                }
                id.name.clone()
            }
            // An element of a sampler array, by a literal index: its own binding.
            ExprKind::Index { base, index } => match (&base.kind, &index.kind) {
                (ExprKind::Ident(id), ExprKind::IntLit(i)) => format!("{}_{i}", id.name),
                _ => return None,
            },
            _ => return None,
        };
        let slot = self.lw.textures.get(&name).cloned()?;
        let image = b.expr(E::GlobalVariable(slot.image), sp);
        let sampler = b.expr(E::GlobalVariable(slot.sampler), sp);
        Some((image, sampler, slot.kind, slot.scalar))
    }

    /// The naga type of a shader type.
    pub fn naga_type(&mut self, ty: &GdType, at: ast::Span) -> Option<Handle<naga::Type>> {
        self.lw.ty(ty, at)
    }

    pub fn type_of(&self, e: &Expr) -> Option<GdType> {
        self.lw.shader.expr_types.get(e.id.0 as usize).cloned().flatten()
    }

    pub fn unsupported<T>(&mut self, e: &Expr, what: &str) -> Option<T> {
        self.lw.error(e.span, format!("gdsky cannot translate {what} yet"));
        None
    }

    /// The value of `e`.
    pub fn value(&mut self, b: &mut FnBuilder, e: &Expr) -> Option<H> {
        let v = self.lower(b, e)?;
        Some(self.load(b, v, e.span))
    }

    fn load(&mut self, b: &mut FnBuilder, v: Val, at: ast::Span) -> H {
        match v {
            Val::Value(h) => h,
            Val::Pointer(p) => b.expr(E::Load { pointer: p }, span(at)),
        }
    }

    /// `e` as the initial value of something of type `ty` (`{…}` lists need the type).
    pub fn initial_value(&mut self, b: &mut FnBuilder, e: &Expr, ty: &GdType) -> Option<H> {
        match &e.kind {
            ExprKind::InitList(items) => {
                let GdType::Array(elem, _) = ty else {
                    return self.unsupported(e, "this initializer list");
                };
                let th = self.lw.ty(ty, e.span)?;
                let mut components = Vec::new();
                for item in items {
                    components.push(self.initial_value(b, item, elem)?);
                }
                Some(b.expr(E::Compose { ty: th, components }, span(e.span)))
            }
            _ => self.value(b, e),
        }
    }

    fn literal(&mut self, b: &mut FnBuilder, e: &Expr, v: gdshader::check::consteval::ConstValue) -> Option<Val> {
        let ty = self.type_of(e)?;
        let GdType::Scalar(s) = ty else {
            return self.unsupported(e, "a literal of this type");
        };
        let lit = literal(s, &v)?;
        Some(Val::Value(b.expr(E::Literal(lit), span(e.span))))
    }

    /// Lowers `e` to a value or a pointer.
    pub fn lower(&mut self, b: &mut FnBuilder, e: &Expr) -> Option<Val> {
        use gdshader::check::consteval::ConstValue as C;
        let sp = span(e.span);
        match &e.kind {
            ExprKind::IntLit(v) => self.literal(b, e, C::Int(i64::from(*v as i32))),
            ExprKind::UIntLit(v) => self.literal(b, e, C::UInt(u64::from(*v))),
            ExprKind::FloatLit(v) => self.literal(b, e, C::Float(*v)),
            ExprKind::BoolLit(v) => Some(Val::Value(b.expr(E::Literal(Literal::Bool(*v)), sp))),
            ExprKind::Ident(id) => self.ident(b, e, id),
            ExprKind::Call { callee, args } => self.call(b, e, callee, args),
            ExprKind::ArrayCtor { args, .. } | ExprKind::InitList(args) => {
                let ty = self.type_of(e)?;
                let th = self.lw.ty(&ty, e.span)?;
                let components = args.iter().map(|a| self.value(b, a)).collect::<Option<Vec<_>>>()?;
                Some(Val::Value(b.expr(E::Compose { ty: th, components }, sp)))
            }
            ExprKind::Member { base, name } => self.member(b, e, base, name),
            ExprKind::MethodCall { base, .. } => {
                let Some(GdType::Array(_, n)) = self.type_of(base) else {
                    return self.unsupported(e, "this method call");
                };
                Some(Val::Value(b.expr(E::Literal(Literal::I32(n as i32)), sp)))
            }
            ExprKind::Index { base, index } => self.index(b, e, base, index),
            ExprKind::Unary { op, operand } => {
                let v = self.value(b, operand)?;
                let op = match op {
                    UnaryOp::Plus => return Some(Val::Value(v)),
                    UnaryOp::Neg => UnaryOperator::Negate,
                    UnaryOp::Not => UnaryOperator::LogicalNot,
                    UnaryOp::BitNot => UnaryOperator::BitwiseNot,
                };
                Some(Val::Value(b.expr(E::Unary { op, expr: v }, sp)))
            }
            ExprKind::IncDec { op, target } => {
                let ty = self.type_of(target)?;
                let place = self.place(b, target)?;
                let old = self.read_place(b, &place, target.span);
                let one = self.one(b, &ty, e)?;
                let new = b.expr(
                    E::Binary { op: if op.increment { Bo::Add } else { Bo::Subtract }, left: old, right: one },
                    sp,
                );
                self.write_place(b, &place, new, e.span);
                Some(Val::Value(if op.prefix { new } else { old }))
            }
            ExprKind::Binary { op, lhs, rhs } => self.binary(b, e, *op, lhs, rhs),
            ExprKind::Assign { op, target, value } => {
                let target_ty = self.type_of(target)?;
                let value_ty = self.type_of(value)?;
                let v = self.value(b, value)?;
                let place = self.place(b, target)?;
                let new = match op {
                    None => v,
                    Some(op) => {
                        let old = self.read_place(b, &place, target.span);
                        self.arith(b, e, *op, old, &target_ty, v, &value_ty)?
                    }
                };
                self.write_place(b, &place, new, e.span);
                Some(Val::Value(new))
            }
            ExprKind::Ternary { cond, then, otherwise } => {
                let ty = self.type_of(e)?;
                if has_side_effects(self.lw, then) || has_side_effects(self.lw, otherwise) {
                    let th = self.lw.ty(&ty, e.span)?;
                    let c = self.value(b, cond)?;
                    let tmp = b.local(None, th, sp);
                    b.open();
                    let t = self.value(b, then)?;
                    b.stmt(Statement::Store { pointer: tmp, value: t }, sp);
                    let accept = b.close();
                    b.open();
                    let o = self.value(b, otherwise)?;
                    b.stmt(Statement::Store { pointer: tmp, value: o }, sp);
                    let reject = b.close();
                    b.stmt(Statement::If { condition: c, accept, reject }, sp);
                    Some(Val::Pointer(tmp))
                } else {
                    let c = self.value(b, cond)?;
                    let t = self.value(b, then)?;
                    let o = self.value(b, otherwise)?;
                    if matches!(ty, GdType::Array(..) | GdType::Struct(_) | GdType::Matrix(_)) {
                        // naga's Select takes scalars and vectors only.
                        let th = self.lw.ty(&ty, e.span)?;
                        let tmp = b.local(None, th, sp);
                        b.open();
                        b.stmt(Statement::Store { pointer: tmp, value: t }, sp);
                        let accept = b.close();
                        b.open();
                        b.stmt(Statement::Store { pointer: tmp, value: o }, sp);
                        let reject = b.close();
                        b.stmt(Statement::If { condition: c, accept, reject }, sp);
                        return Some(Val::Pointer(tmp));
                    }
                    Some(Val::Value(b.expr(E::Select { condition: c, accept: t, reject: o }, sp)))
                }
            }
            ExprKind::Error => None,
        }
    }

    /// `1` of a scalar or vector type, for `++` and `--`.
    fn one(&mut self, b: &mut FnBuilder, ty: &GdType, e: &Expr) -> Option<H> {
        let sp = span(e.span);
        let (s, n) = match ty {
            GdType::Scalar(s) => (*s, 1),
            GdType::Vector(s, n) => (*s, *n),
            _ => return self.unsupported(e, "`++`/`--` on a matrix"),
        };
        let lit = b.expr(E::Literal(literal(s, &gdshader::check::consteval::ConstValue::Int(1))?), sp);
        Some(if n == 1 { lit } else { b.expr(E::Splat { size: vector_size(n), value: lit }, sp) })
    }

    fn ident(&mut self, b: &mut FnBuilder, e: &Expr, id: &ast::Ident) -> Option<Val> {
        let sp = span(id.span);
        if let Some(slot) = self.scopes.iter().rev().find_map(|s| s.get(&id.name)).cloned() {
            return Some(match slot {
                LocalSlot::Variable(ptr) => Val::Pointer(ptr),
                LocalSlot::OutParam(i) => Val::Pointer(b.expr(E::FunctionArgument(i), sp)),
                LocalSlot::Argument(i) => Val::Value(b.expr(E::FunctionArgument(i), sp)),
                LocalSlot::Let(h) => Val::Value(h),
                LocalSlot::Sampler(..) => {
                    return self.unsupported(
                        e,
                        "a sampler used other than as the first argument of a texture function or a call",
                    );
                }
            });
        }
        if let Some(c) = self.lw.constants.get(&id.name).cloned() {
            return match c {
                GlobalConst::Module(h, v) => Some(Val::Value(b.constant(h, v, sp))),
                GlobalConst::Value(ty, value) => {
                    let v = self.lw.const_value(&ty, &value)?;
                    Some(Val::Value(b.value(&v, sp)))
                }
                GlobalConst::Inline(init) => self.lower(b, &init),
            };
        }
        if self.lw.textures.contains_key(&id.name) {
            return self.unsupported(e, "a sampler used other than as the first argument of a texture function");
        }
        if let Some(slot) = self.lw.uniforms.get(&id.name).cloned() {
            let g = b.expr(E::GlobalVariable(slot.block), sp);
            let ptr = b.expr(E::AccessIndex { base: g, index: slot.member }, sp);
            let loaded = b.expr(E::Load { pointer: ptr }, sp);
            return self.lw.uniform_value(b, loaded, &slot.ty, sp).map(Val::Value);
        }
        let ty = self.type_of(e)?;
        super::wrapper::read_builtin(self.lw, b, &id.name, &ty, id.span)
            .or_else(|| self.unsupported(e, &format!("`{}`", id.name)))
    }

    fn member(&mut self, b: &mut FnBuilder, e: &Expr, base: &Expr, name: &ast::Ident) -> Option<Val> {
        let sp = span(e.span);
        let base_ty = self.type_of(base)?;
        let base_v = self.lower(b, base)?;
        match base_ty {
            GdType::Vector(_, _) => {
                let pattern: Vec<u8> = name.name.chars().map(swizzle_index).collect();
                if pattern.len() == 1 {
                    return Some(match base_v {
                        Val::Pointer(p) => {
                            Val::Pointer(b.expr(E::AccessIndex { base: p, index: u32::from(pattern[0]) }, sp))
                        }
                        Val::Value(v) => {
                            Val::Value(b.expr(E::AccessIndex { base: v, index: u32::from(pattern[0]) }, sp))
                        }
                    });
                }
                let vector = self.load(b, base_v, base.span);
                let mut comps = [SwizzleComponent::X; 4];
                for (i, &c) in pattern.iter().enumerate() {
                    comps[i] = COMPONENTS[usize::from(c)];
                }
                Some(Val::Value(
                    b.expr(E::Swizzle { size: vector_size(pattern.len() as u8), vector, pattern: comps }, sp),
                ))
            }
            GdType::Struct(id) => {
                let index =
                    self.lw.shader.structs.get(id.0 as usize)?.members.iter().position(|(m, _)| *m == name.name)?
                        as u32;
                Some(match base_v {
                    Val::Pointer(p) => Val::Pointer(b.expr(E::AccessIndex { base: p, index }, sp)),
                    Val::Value(v) => Val::Value(b.expr(E::AccessIndex { base: v, index }, sp)),
                })
            }
            _ => self.unsupported(e, "this member access"),
        }
    }

    fn index(&mut self, b: &mut FnBuilder, e: &Expr, base: &Expr, index: &Expr) -> Option<Val> {
        let sp = span(e.span);
        let base_v = self.lower(b, base)?;
        let constant = match index.kind {
            ExprKind::IntLit(k) | ExprKind::UIntLit(k) => Some(k),
            _ => None,
        };
        let pointer = match base_v {
            Val::Pointer(p) => p,
            Val::Value(v) => {
                if let Some(k) = constant {
                    return Some(Val::Value(b.expr(E::AccessIndex { base: v, index: k }, sp)));
                }
                // A dynamic index needs a place: spill the value to a temporary.
                let ty = self.type_of(base)?;
                let th = self.lw.ty(&ty, base.span)?;
                let tmp = b.local(None, th, sp);
                b.stmt(Statement::Store { pointer: tmp, value: v }, sp);
                tmp
            }
        };
        Some(Val::Pointer(match constant {
            Some(k) => b.expr(E::AccessIndex { base: pointer, index: k }, sp),
            None => {
                let i = self.value(b, index)?;
                b.expr(E::Access { base: pointer, index: i }, sp)
            }
        }))
    }

    fn place(&mut self, b: &mut FnBuilder, target: &Expr) -> Option<Place> {
        if let ExprKind::Member { base, name } = &target.kind
            && let Some(GdType::Vector(..)) = self.type_of(base)
            && name.name.len() > 1
        {
            let vector = self.type_of(base)?;
            let Val::Pointer(pointer) = self.lower(b, base)? else {
                return self.unsupported(target, "this assignment");
            };
            return Some(Place::Swizzle { pointer, vector, pattern: name.name.chars().map(swizzle_index).collect() });
        }
        match self.lower(b, target)? {
            Val::Pointer(p) => Some(Place::Pointer(p)),
            Val::Value(_) => self.unsupported(target, "an assignment to this expression"),
        }
    }

    fn read_place(&mut self, b: &mut FnBuilder, place: &Place, at: ast::Span) -> H {
        let sp = span(at);
        match place {
            Place::Pointer(p) => b.expr(E::Load { pointer: *p }, sp),
            Place::Swizzle { pointer, pattern, .. } => {
                let v = b.expr(E::Load { pointer: *pointer }, sp);
                let mut comps = [SwizzleComponent::X; 4];
                for (i, &c) in pattern.iter().enumerate() {
                    comps[i] = COMPONENTS[usize::from(c)];
                }
                b.expr(E::Swizzle { size: vector_size(pattern.len() as u8), vector: v, pattern: comps }, sp)
            }
        }
    }

    fn write_place(&mut self, b: &mut FnBuilder, place: &Place, value: H, at: ast::Span) {
        let sp = span(at);
        match place {
            Place::Pointer(p) => b.stmt(Statement::Store { pointer: *p, value }, sp),
            Place::Swizzle { pointer, vector, pattern } => {
                let GdType::Vector(_, n) = vector else { return };
                let Some(th) = self.lw.ty(vector, at) else {
                    return;
                };
                let old = b.expr(E::Load { pointer: *pointer }, sp);
                let components = (0..*n)
                    .map(|i| match pattern.iter().position(|&c| c == i) {
                        Some(j) => b.expr(E::AccessIndex { base: value, index: j as u32 }, sp),
                        None => b.expr(E::AccessIndex { base: old, index: u32::from(i) }, sp),
                    })
                    .collect();
                let new = b.expr(E::Compose { ty: th, components }, sp);
                b.stmt(Statement::Store { pointer: *pointer, value: new }, sp);
            }
        }
    }

    fn binary(&mut self, b: &mut FnBuilder, e: &Expr, op: BinaryOp, lhs: &Expr, rhs: &Expr) -> Option<Val> {
        let sp = span(e.span);
        if matches!(op, BinaryOp::LogicalAnd | BinaryOp::LogicalOr) && has_side_effects(self.lw, rhs) {
            // Short-circuit explicitly: the right side must not run when the left decides.
            let bool_ty = self.lw.ty(&GdType::BOOL, e.span)?;
            let l = self.value(b, lhs)?;
            let tmp = b.local(None, bool_ty, sp);
            b.stmt(Statement::Store { pointer: tmp, value: l }, sp);
            b.open();
            let r = self.value(b, rhs)?;
            b.stmt(Statement::Store { pointer: tmp, value: r }, sp);
            let run_rhs = b.close();
            let (accept, reject) =
                if op == BinaryOp::LogicalAnd { (run_rhs, naga::Block::new()) } else { (naga::Block::new(), run_rhs) };
            b.stmt(Statement::If { condition: l, accept, reject }, sp);
            return Some(Val::Pointer(tmp));
        }
        let lt = self.type_of(lhs)?;
        let rt = self.type_of(rhs)?;
        let l = self.value(b, lhs)?;
        let r = self.value(b, rhs)?;
        let h = match op {
            BinaryOp::Eq | BinaryOp::NotEq => {
                let bop = if op == BinaryOp::Eq { Bo::Equal } else { Bo::NotEqual };
                match lt {
                    GdType::Scalar(_) => b.expr(E::Binary { op: bop, left: l, right: r }, sp),
                    GdType::Vector(..) => {
                        let per = b.expr(E::Binary { op: bop, left: l, right: r }, sp);
                        let fun = if op == BinaryOp::Eq { RelationalFunction::All } else { RelationalFunction::Any };
                        b.expr(E::Relational { fun, argument: per }, sp)
                    }
                    _ => {
                        return self.unsupported(e, "comparing matrices, structs or arrays with `==`");
                    }
                }
            }
            BinaryOp::Less => b.expr(E::Binary { op: Bo::Less, left: l, right: r }, sp),
            BinaryOp::Greater => b.expr(E::Binary { op: Bo::Greater, left: l, right: r }, sp),
            BinaryOp::LessEq => b.expr(E::Binary { op: Bo::LessEqual, left: l, right: r }, sp),
            BinaryOp::GreaterEq => b.expr(E::Binary { op: Bo::GreaterEqual, left: l, right: r }, sp),
            BinaryOp::LogicalAnd => b.expr(E::Binary { op: Bo::LogicalAnd, left: l, right: r }, sp),
            BinaryOp::LogicalOr => b.expr(E::Binary { op: Bo::LogicalOr, left: l, right: r }, sp),
            _ => return self.arith(b, e, op, l, &lt, r, &rt).map(Val::Value),
        };
        Some(Val::Value(h))
    }

    /// Arithmetic, bitwise and shift operators, with GLSL's scalar–vector mixing made explicit.
    #[allow(clippy::too_many_arguments)]
    fn arith(&mut self, b: &mut FnBuilder, e: &Expr, op: BinaryOp, l: H, lt: &GdType, r: H, rt: &GdType) -> Option<H> {
        let sp = span(e.span);
        let splat_to = |b: &mut FnBuilder, h: H, to: &GdType| match to {
            GdType::Vector(_, n) => b.expr(E::Splat { size: vector_size(*n), value: h }, sp),
            _ => h,
        };
        let (mut l, mut r) = (l, r);
        let bop = match op {
            BinaryOp::Mul => {
                if matches!(
                    (lt, rt),
                    (GdType::Matrix(_), GdType::Scalar(_))
                        | (GdType::Scalar(_), GdType::Matrix(_))
                        | (GdType::Vector(..), GdType::Scalar(_))
                        | (GdType::Scalar(_), GdType::Vector(..))
                ) {
                    // naga multiplies vectors and matrices by scalars directly.
                }
                Bo::Multiply
            }
            BinaryOp::Add | BinaryOp::Sub | BinaryOp::Div | BinaryOp::Rem => {
                if matches!(lt, GdType::Matrix(_)) != matches!(rt, GdType::Matrix(_)) {
                    return self.unsupported(e, "adding or dividing a matrix and a scalar");
                }
                match (lt, rt) {
                    (GdType::Vector(..), GdType::Scalar(_)) => r = splat_to(b, r, lt),
                    (GdType::Scalar(_), GdType::Vector(..)) => l = splat_to(b, l, rt),
                    _ => {}
                }
                match op {
                    BinaryOp::Add => Bo::Add,
                    BinaryOp::Sub => Bo::Subtract,
                    BinaryOp::Div => Bo::Divide,
                    _ => Bo::Modulo,
                }
            }
            BinaryOp::BitAnd | BinaryOp::BitOr | BinaryOp::BitXor => {
                // Godot allows `ivec2 &= int` (compound forms); naga wants equal shapes.
                match (lt, rt) {
                    (GdType::Vector(..), GdType::Scalar(_)) => r = splat_to(b, r, lt),
                    (GdType::Scalar(_), GdType::Vector(..)) => l = splat_to(b, l, rt),
                    _ => {}
                }
                match op {
                    BinaryOp::BitAnd => Bo::And,
                    BinaryOp::BitOr => Bo::InclusiveOr,
                    _ => Bo::ExclusiveOr,
                }
            }
            BinaryOp::Shl | BinaryOp::Shr => {
                // naga wants an unsigned shift amount of the left side's shape.
                if rt.scalar() == Some(GdScalar::Int) {
                    r = b.expr(E::As { expr: r, kind: ScalarKind::Uint, convert: Some(4) }, sp);
                }
                if b.known(r).is_none() {
                    // GLSL leaves a shift by 32 or more (or by a negative amount) undefined, and
                    // so does SPIR-V: keep the amount's low 5 bits, as a constant amount is
                    // folded (the builder masks those).
                    let mask = b.expr(E::Literal(Literal::U32(31)), sp);
                    let mask = match rt {
                        GdType::Vector(_, n) => b.expr(E::Splat { size: vector_size(*n), value: mask }, sp),
                        _ => mask,
                    };
                    r = b.expr(E::Binary { op: Bo::And, left: r, right: mask }, sp);
                }
                if let (GdType::Vector(..), GdType::Scalar(_)) = (lt, rt) {
                    r = splat_to(b, r, lt);
                }
                if op == BinaryOp::Shl { Bo::ShiftLeft } else { Bo::ShiftRight }
            }
            _ => return self.unsupported(e, "this operator"),
        };
        Some(b.expr(E::Binary { op: bop, left: l, right: r }, sp))
    }

    fn call(&mut self, b: &mut FnBuilder, e: &Expr, callee: &ast::Ident, args: &[Expr]) -> Option<Val> {
        if let Some(ty) = GdType::from_name(&callee.name) {
            let v = self.constructor(b, e, &ty, args)?;
            // A constant constructor passed where Godot converts it (`g(int(2))` for
            // `g(float)`) carries the converted type in the checker's table.
            return Some(Val::Value(match (self.type_of(e), ty.scalar()) {
                (Some(recorded), Some(_)) if recorded != ty => match recorded.scalar() {
                    Some(to) => self.convert(b, v, &ty, to, e.span),
                    None => v,
                },
                _ => v,
            }));
        }
        if self.lw.shader.structs.iter().any(|s| s.name == callee.name) {
            let ty = self.type_of(e)?;
            let th = self.lw.ty(&ty, e.span)?;
            let components = args.iter().map(|a| self.value(b, a)).collect::<Option<Vec<_>>>()?;
            return Some(Val::Value(b.expr(E::Compose { ty: th, components }, span(e.span))));
        }
        let arg_types: Vec<GdType> = args.iter().map(|a| self.type_of(a)).collect::<Option<_>>()?;
        let user = self
            .lw
            .functions
            .get(&callee.name)
            .and_then(|fs| fs.iter().find(|f| f.params.iter().map(|p| &p.0).eq(arg_types.iter())).cloned());
        if let Some(f) = user {
            return self.user_call(b, e, &f, args);
        }
        super::calls::builtin(self, b, e, callee, args, &arg_types).map(Val::Value)
    }

    fn user_call(&mut self, b: &mut FnBuilder, e: &Expr, f: &super::UserFn, args: &[Expr]) -> Option<Val> {
        let sp = span(e.span);
        let mut arguments = Vec::new();
        // `out`/`inout` arguments go through temporaries: copy in, call, copy out (GLSL's rule).
        let mut copy_out = Vec::new();
        for ((ty, q), a) in f.params.iter().zip(args) {
            match q {
                ParamQualifier::Out | ParamQualifier::InOut => {
                    let th = self.lw.ty(ty, a.span)?;
                    let place = self.place(b, a)?;
                    let tmp = b.local(None, th, span(a.span));
                    if *q == ParamQualifier::InOut {
                        let current = self.read_place(b, &place, a.span);
                        b.stmt(Statement::Store { pointer: tmp, value: current }, span(a.span));
                    }
                    arguments.push(tmp);
                    copy_out.push((place, tmp, a.span));
                }
                _ if matches!(ty, GdType::Sampler(..)) => {
                    let Some((image, sampler, ..)) = self.sampler(b, a) else {
                        return self.unsupported(a, "passing this sampler (a dynamically indexed sampler array)");
                    };
                    arguments.push(image);
                    arguments.push(sampler);
                }
                _ => arguments.push(self.value(b, a)?),
            }
        }
        let result = (f.ret != GdType::Void).then(|| b.expr(E::CallResult(f.handle), sp));
        b.stmt(Statement::Call { function: f.handle, arguments, result }, sp);
        for (place, tmp, at) in copy_out {
            let v = b.expr(E::Load { pointer: tmp }, span(at));
            self.write_place(b, &place, v, at);
        }
        // A void call used as a statement has no value; give it a harmless one.
        Some(Val::Value(match result {
            Some(r) => r,
            None => b.expr(E::Literal(Literal::Bool(false)), sp),
        }))
    }

    /// Scalar, vector and matrix constructors, with Godot's conversions.
    fn constructor(&mut self, b: &mut FnBuilder, e: &Expr, ty: &GdType, args: &[Expr]) -> Option<H> {
        let sp = span(e.span);
        let th = self.lw.ty(ty, e.span)?;
        let target = ty.scalar()?;
        let mut values = Vec::new();
        for a in args {
            let at = self.type_of(a)?;
            let v = self.value(b, a)?;
            values.push((self.convert(b, v, &at, target, a.span), at));
        }
        Some(match ty {
            GdType::Scalar(_) => values.first()?.0,
            GdType::Vector(_, n) if values.len() == 1 && matches!(values[0].1, GdType::Scalar(_)) => {
                b.expr(E::Splat { size: vector_size(*n), value: values[0].0 }, sp)
            }
            GdType::Vector(..) => {
                if values.len() == 1 && values[0].1.components() == ty.components() {
                    return Some(values[0].0);
                }
                b.expr(E::Compose { ty: th, components: values.into_iter().map(|v| v.0).collect() }, sp)
            }
            GdType::Matrix(n) => match values.as_slice() {
                [(v, GdType::Scalar(_))] => {
                    // The diagonal.
                    let zero = b.expr(E::Literal(Literal::F32(0.0)), sp);
                    let col_ty = self.lw.ty(&GdType::Vector(GdScalar::Float, *n), e.span)?;
                    let columns = (0..*n)
                        .map(|c| {
                            let comps = (0..*n).map(|r| if r == c { *v } else { zero }).collect();
                            b.expr(E::Compose { ty: col_ty, components: comps }, sp)
                        })
                        .collect();
                    b.expr(E::Compose { ty: th, components: columns }, sp)
                }
                [(v, GdType::Matrix(m))] if m == n => *v,
                [(v, GdType::Matrix(m))] => {
                    // GLSL: keep the overlapping block, fill the rest from the identity.
                    let (m, n) = (*m, *n);
                    let col_ty = self.lw.ty(&GdType::Vector(GdScalar::Float, n), e.span)?;
                    let (zero, one) =
                        (b.expr(E::Literal(Literal::F32(0.0)), sp), b.expr(E::Literal(Literal::F32(1.0)), sp));
                    let columns = (0..n)
                        .map(|c| {
                            let src = (c < m).then(|| b.expr(E::AccessIndex { base: *v, index: u32::from(c) }, sp));
                            let comps = (0..n)
                                .map(|r| match src {
                                    Some(col) if r < m => b.expr(E::AccessIndex { base: col, index: u32::from(r) }, sp),
                                    _ if r == c => one,
                                    _ => zero,
                                })
                                .collect();
                            b.expr(E::Compose { ty: col_ty, components: comps }, sp)
                        })
                        .collect();
                    b.expr(E::Compose { ty: th, components: columns }, sp)
                }
                _ => b.expr(E::Compose { ty: th, components: values.into_iter().map(|v| v.0).collect() }, sp),
            },
            _ => return self.unsupported(e, "this constructor"),
        })
    }

    /// Converts a scalar or vector value to another scalar kind, as a constructor does.
    pub fn convert(&mut self, b: &mut FnBuilder, v: H, from: &GdType, to: GdScalar, at: ast::Span) -> H {
        let sp = span(at);
        let Some(from_s) = from.scalar() else {
            return v;
        };
        if from_s == to {
            return v;
        }
        let shape = |n: Option<u8>, b: &mut FnBuilder, h: H| match n {
            Some(n) if n > 1 => b.expr(E::Splat { size: vector_size(n), value: h }, sp),
            _ => h,
        };
        let n = match from {
            GdType::Vector(_, n) => Some(*n),
            _ => None,
        };
        match (from_s, to) {
            (_, GdScalar::Bool) => {
                let zero = b.expr(
                    E::Literal(
                        literal(from_s, &gdshader::check::consteval::ConstValue::Int(0)).unwrap_or(Literal::I32(0)),
                    ),
                    sp,
                );
                let zero = shape(n, b, zero);
                b.expr(E::Binary { op: Bo::NotEqual, left: v, right: zero }, sp)
            }
            (GdScalar::Bool, _) => {
                let one = b.expr(
                    E::Literal(literal(to, &gdshader::check::consteval::ConstValue::Int(1)).unwrap_or(Literal::I32(1))),
                    sp,
                );
                let zero = b.expr(
                    E::Literal(literal(to, &gdshader::check::consteval::ConstValue::Int(0)).unwrap_or(Literal::I32(0))),
                    sp,
                );
                let (one, zero) = (shape(n, b, one), shape(n, b, zero));
                b.expr(E::Select { condition: v, accept: one, reject: zero }, sp)
            }
            _ => b.expr(E::As { expr: v, kind: scalar(to).kind, convert: Some(4) }, sp),
        }
    }
}

/// Names written anywhere in `stmts`: assignment and `++`/`--` targets, and `out` arguments.
/// Over-approximate on purpose (shadowing is ignored): a name listed here only costs a copy.
fn assigned_names<'s>(
    stmts: &'s [ast::Stmt],
    is_out: &dyn Fn(&str, usize) -> bool,
    out: &mut std::collections::HashSet<&'s str>,
) {
    use ast::StmtKind;
    let mut exprs: Vec<&Expr> = Vec::new();
    let mut stack: Vec<&ast::Stmt> = stmts.iter().collect();
    while let Some(s) = stack.pop() {
        match &s.kind {
            StmtKind::Block(b) => stack.extend(&b.stmts),
            StmtKind::VarDecl(d) => exprs.extend(d.declarators.iter().filter_map(|d| d.init.as_ref())),
            StmtKind::Expr(e) | StmtKind::Return(Some(e)) => exprs.push(e),
            StmtKind::If { branches, otherwise } => {
                for (c, b) in branches {
                    exprs.push(c);
                    stack.push(b);
                }
                stack.extend(otherwise.as_deref());
            }
            StmtKind::For { init, cond, step, body } => {
                stack.extend(init.as_deref());
                exprs.extend(cond);
                exprs.extend(step);
                stack.push(body);
            }
            StmtKind::While { cond, body } | StmtKind::DoWhile { body, cond } => {
                exprs.push(cond);
                stack.push(body);
            }
            StmtKind::Switch { selector, cases } => {
                exprs.push(selector);
                for c in cases {
                    stack.extend(&c.body);
                }
            }
            _ => {}
        }
    }
    let root = |mut e: &'s Expr| loop {
        match &e.kind {
            ExprKind::Member { base, .. } | ExprKind::Index { base, .. } => e = base,
            ExprKind::Ident(id) => return Some(id.name.as_str()),
            _ => return None,
        }
    };
    while let Some(e) = exprs.pop() {
        match &e.kind {
            ExprKind::Assign { target, value, .. } => {
                out.extend(root(target));
                exprs.push(target);
                exprs.push(value);
            }
            ExprKind::IncDec { target, .. } => {
                out.extend(root(target));
                exprs.push(target);
            }
            ExprKind::Call { callee, args } => {
                out.extend(
                    args.iter().enumerate().filter(|(i, _)| is_out(&callee.name, *i)).filter_map(|(_, a)| root(a)),
                );
                exprs.extend(args);
            }
            ExprKind::ArrayCtor { args, .. } | ExprKind::InitList(args) => exprs.extend(args),
            ExprKind::Member { base, .. } => exprs.push(base),
            ExprKind::MethodCall { base, args, .. } => {
                exprs.push(base);
                exprs.extend(args);
            }
            ExprKind::Index { base, index } => {
                exprs.push(base);
                exprs.push(index);
            }
            ExprKind::Unary { operand, .. } => exprs.push(operand),
            ExprKind::Binary { lhs, rhs, .. } => {
                exprs.push(lhs);
                exprs.push(rhs);
            }
            ExprKind::Ternary { cond, then, otherwise } => exprs.extend([&**cond, &**then, &**otherwise]),
            _ => {}
        }
    }
}

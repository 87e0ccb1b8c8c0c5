//! Builds one naga function body, keeping `Emit` ranges right, and keeping every constant
//! expression one naga accepts.
//!
//! naga wants every expression that is not "pre-emitted" (literals, constants, arguments,
//! variable pointers, call results) to be covered by exactly one `Statement::Emit` in a block
//! that dominates its uses. The builder keeps a running emit range, closes it before a
//! pre-emitted expression or a statement, and so no caller has to think about it.
//!
//! The same way, every expression goes through [`fold::evaluate`] (when the builder has the
//! module's [`TypeTable`]): a constant that naga's evaluator or validator would refuse is
//! written as its value instead, as literals, and a value that is not finite (which no naga
//! literal may hold) as a run-time value: the load of a local variable holding its bits,
//! bitcast to `f32`. No caller has to think about that either.

use super::fold::{self, Fold, TypeTable, Value};
use naga::{Block, Expression, Function, Handle, Literal, LocalVariable, Span, Statement, Type};
use std::collections::HashMap;

/// A function under construction.
pub(crate) struct FnBuilder {
    pub function: Function,
    blocks: Vec<Block>,
    emit_start: Option<usize>,
    /// Types for folding; without them the builder writes expressions as given.
    types: Option<TypeTable>,
    /// The value of each constant expression built so far, by handle index.
    known: Vec<Option<Value>>,
    /// The handles (by index) that are run-time copies of constants: naga sees a run-time value,
    /// the folder still knows it (an infinity, a NaN), so what is computed from it is folded too.
    runtime_copies: std::collections::HashSet<usize>,
    /// Local variables holding the bits of run-time copies of constants, by literal.
    runtime_vars: HashMap<(u8, u32), Handle<LocalVariable>>,
    /// Run-time values known never to be NaN, by handle index: the compare-and-select form of
    /// a maxNum `max`/`min` with an operand that is not NaN (`calls.rs`, `max_num`).
    not_nan: std::collections::HashSet<usize>,
}

impl FnBuilder {
    pub fn new(name: &str) -> Self {
        FnBuilder {
            function: Function { name: Some(name.into()), ..Default::default() },
            blocks: vec![Block::new()],
            emit_start: None,
            types: None,
            known: Vec::new(),
            runtime_copies: std::collections::HashSet::new(),
            runtime_vars: HashMap::new(),
            not_nan: std::collections::HashSet::new(),
        }
    }

    /// A builder that folds constants (see the module's essay).
    pub fn with_types(name: &str, types: TypeTable) -> Self {
        FnBuilder { types: Some(types), ..Self::new(name) }
    }

    /// The value of `h` when it is a constant naga evaluates.
    pub fn known(&self, h: Handle<Expression>) -> Option<&Value> {
        if self.runtime_copies.contains(&h.index()) {
            return None;
        }
        self.known.get(h.index()).and_then(Option::as_ref)
    }

    /// Whether `h` is never NaN: a finite constant, a value marked by [`Self::mark_not_nan`], or
    /// a splat of either.
    pub fn is_not_nan(&self, h: Handle<Expression>) -> bool {
        self.known(h).is_some_and(Value::is_finite)
            || self.not_nan.contains(&h.index())
            || matches!(self.function.expressions[h], Expression::Splat { value, .. } if self.is_not_nan(value))
    }

    /// Records that the run-time value `h` is never NaN.
    pub fn mark_not_nan(&mut self, h: Handle<Expression>) {
        self.not_nan.insert(h.index());
    }

    fn record(&mut self, h: Handle<Expression>, v: Option<Value>) {
        if self.known.len() <= h.index() {
            self.known.resize(h.index() + 1, None);
        }
        self.known[h.index()] = v;
    }

    /// A module constant of value `v` (its handle's value is known to the folder).
    pub fn constant(&mut self, c: Handle<naga::Constant>, v: Value, span: Span) -> Handle<Expression> {
        let h = self.append(Expression::Constant(c), span);
        self.record(h, Some(v));
        h
    }

    /// Appends an expression, emitting it unless naga says it is pre-emitted; a constant naga
    /// would refuse is written as its value.
    pub fn expr(&mut self, expr: Expression, span: Span) -> Handle<Expression> {
        let Some(types) = self.types else {
            return self.append(expr, span);
        };
        let outcome = {
            let known = &self.known;
            fold::evaluate(&expr, &|h: Handle<Expression>| known.get(h.index()).cloned().flatten(), &types)
        };
        // An expression computed from a run-time copy of a constant is a constant too (GLSL's
        // compilers fold it); naga would leave it to run time, where a driver need not keep an
        // infinity or a NaN: it is written as its value.
        let from_copy = fold::operands(&expr).iter().any(|h| self.runtime_copies.contains(&h.index()));
        match outcome {
            Fold::Runtime => self.append(expr, span),
            Fold::Keep(v) | Fold::Replace(v) if from_copy => self.value(&v, span),
            Fold::Opaque(_) if from_copy => self.append(expr, span),
            Fold::Keep(v) => {
                let h = self.append(expr, span);
                self.record(h, Some(v));
                h
            }
            Fold::Replace(v) => self.value(&v, span),
            Fold::Opaque(i) => {
                let mut expr = expr;
                if let Some(&h) = fold::operands(&expr).get(i)
                    && let Some(v) = self.known(h).cloned()
                {
                    let r = self.runtime_value(&v, &types, &|_| false, span);
                    fold::replace_operand(&mut expr, i, r);
                }
                self.append(expr, span)
            }
            Fold::FixRight { value, runtime } => {
                let mut expr = expr;
                // A zero divisor must not be a constant (naga's validator); the other lanes may.
                let zero = |l: &Literal| matches!(l, Literal::I32(0) | Literal::U32(0));
                let r =
                    if runtime { self.runtime_value(&value, &types, &zero, span) } else { self.value(&value, span) };
                fold::replace_operand(&mut expr, 1, r);
                self.append(expr, span)
            }
        }
    }

    /// A value as expressions: literals (a constant naga accepts) where finite, a run-time
    /// value where not.
    pub fn value(&mut self, v: &Value, span: Span) -> Handle<Expression> {
        let Some(types) = self.types else {
            return self.append(Expression::Literal(Literal::Bool(false)), span);
        };
        if !v.is_finite() {
            let h = self.runtime_value(v, &types, &|_| false, span);
            self.record(h, Some(v.clone()));
            self.runtime_copies.insert(h.index());
            return h;
        }
        let h = match v {
            Value::Scalar(l) => self.append(Expression::Literal(*l), span),
            Value::Vector(lanes) => {
                let components = lanes.iter().map(|l| self.append(Expression::Literal(*l), span)).collect();
                let ty = types.vector(&lanes[0], lanes.len());
                self.append(Expression::Compose { ty, components }, span)
            }
            Value::Matrix(columns) => {
                let components = columns.iter().map(|c| self.value(&Value::Vector(c.clone()), span)).collect();
                let ty = types.matrix(columns.len());
                self.append(Expression::Compose { ty, components }, span)
            }
            Value::Other(ty, items) => {
                let components = items.iter().map(|item| self.value(item, span)).collect();
                self.append(Expression::Compose { ty: *ty, components }, span)
            }
        };
        self.record(h, Some(v.clone()));
        h
    }

    /// A value naga does not evaluate: its scalars that are not finite, those `force` picks, and
    /// (when that is none of them) the first one are loaded from local variables initialised
    /// with them (a float by its bits, bitcast back, since a naga literal cannot hold an
    /// infinity or a NaN); the others are literals.
    fn runtime_value(
        &mut self,
        v: &Value,
        types: &TypeTable,
        force: &dyn Fn(&Literal) -> bool,
        span: Span,
    ) -> Handle<Expression> {
        let scalars = v.scalars();
        let pick = |l: &Literal| force(l) || matches!(l, Literal::F32(f) if !f.is_finite());
        let first = !scalars.iter().any(pick);
        let mut index = 0usize;
        self.runtime_tree(
            v,
            types,
            &mut |b: &mut Self, l: Literal| {
                let runtime = pick(&l) || (first && index == 0);
                index += 1;
                if runtime { b.runtime_scalar(l, types, span) } else { b.append(Expression::Literal(l), span) }
            },
            span,
        )
    }

    fn runtime_tree(
        &mut self,
        v: &Value,
        types: &TypeTable,
        scalar: &mut dyn FnMut(&mut Self, Literal) -> Handle<Expression>,
        span: Span,
    ) -> Handle<Expression> {
        let (ty, components) = match v {
            Value::Scalar(l) => return scalar(self, *l),
            Value::Vector(lanes) => {
                (types.vector(&lanes[0], lanes.len()), lanes.iter().map(|l| scalar(self, *l)).collect())
            }
            Value::Matrix(columns) => (
                types.matrix(columns.len()),
                columns.iter().map(|c| self.runtime_tree(&Value::Vector(c.clone()), types, scalar, span)).collect(),
            ),
            Value::Other(ty, items) => {
                (*ty, items.iter().map(|item| self.runtime_tree(item, types, scalar, span)).collect())
            }
        };
        self.append(Expression::Compose { ty, components }, span)
    }

    fn runtime_scalar(&mut self, l: Literal, types: &TypeTable, span: Span) -> Handle<Expression> {
        let (key, init, name) = match l {
            Literal::F32(f) => {
                let name = match f {
                    f if f.is_nan() => "nan_bits",
                    f if f == f32::INFINITY => "inf_bits",
                    f if f == f32::NEG_INFINITY => "neg_inf_bits",
                    _ => "f32_bits",
                };
                ((3, f.to_bits()), Literal::U32(f.to_bits()), name)
            }
            Literal::I32(v) => ((1, v as u32), l, "runtime_i32"),
            Literal::U32(v) => ((2, v), l, "runtime_u32"),
            Literal::Bool(v) => ((0, u32::from(v)), l, "runtime_bool"),
            other => ((4, 0), other, "runtime"),
        };
        let var = match self.runtime_vars.get(&key) {
            Some(var) => *var,
            None => {
                let init = self.append(Expression::Literal(init), span);
                let var = self.function.local_variables.append(
                    LocalVariable { name: Some(name.into()), ty: types.scalar(&init_literal(l)), init: Some(init) },
                    span,
                );
                self.runtime_vars.insert(key, var);
                var
            }
        };
        let pointer = self.append(Expression::LocalVariable(var), span);
        let loaded = self.append(Expression::Load { pointer }, span);
        match l {
            Literal::F32(_) => {
                self.append(Expression::As { expr: loaded, kind: naga::ScalarKind::Float, convert: None }, span)
            }
            _ => loaded,
        }
    }

    /// Appends an expression as given.
    fn append(&mut self, expr: Expression, span: Span) -> Handle<Expression> {
        let pre_emitted = expr.needs_pre_emit() || matches!(expr, Expression::CallResult(_));
        if pre_emitted {
            self.flush();
        } else if self.emit_start.is_none() {
            self.emit_start = Some(self.function.expressions.len());
        }
        self.function.expressions.append(expr, span)
    }

    fn flush(&mut self) {
        if let Some(start) = self.emit_start.take()
            && start != self.function.expressions.len()
        {
            let range = self.function.expressions.range_from(start);
            let mut span = Span::default();
            for h in range.clone() {
                span.subsume(self.function.expressions.get_span(h));
            }
            self.current().push(Statement::Emit(range), span);
        }
    }

    fn current(&mut self) -> &mut Block {
        if self.blocks.is_empty() {
            self.blocks.push(Block::new());
        }
        let last = self.blocks.len() - 1;
        &mut self.blocks[last]
    }

    /// Appends a statement to the current block.
    pub fn stmt(&mut self, stmt: Statement, span: Span) {
        self.flush();
        self.current().push(stmt, span);
    }

    /// Starts a nested block.
    pub fn open(&mut self) {
        self.flush();
        self.blocks.push(Block::new());
    }

    /// Ends the nested block started by the matching [`open`](Self::open).
    pub fn close(&mut self) -> Block {
        self.flush();
        if self.blocks.len() > 1 { self.blocks.pop().unwrap_or_default() } else { Block::new() }
    }

    /// The first `size` components of `vector` (`.xy`, `.xyz`).
    pub fn head(&mut self, vector: Handle<Expression>, size: u8, span: Span) -> Handle<Expression> {
        use naga::SwizzleComponent::{W, X, Y, Z};
        let size = match size {
            2 => naga::VectorSize::Bi,
            3 => naga::VectorSize::Tri,
            _ => naga::VectorSize::Quad,
        };
        self.expr(Expression::Swizzle { size, vector, pattern: [X, Y, Z, W] }, span)
    }

    /// A new local variable (zero-initialised), returning its pointer expression.
    pub fn local(&mut self, name: Option<&str>, ty: Handle<Type>, span: Span) -> Handle<Expression> {
        let lv =
            self.function.local_variables.append(LocalVariable { name: name.map(Into::into), ty, init: None }, span);
        self.expr(Expression::LocalVariable(lv), span)
    }

    /// The finished function.
    pub fn finish(mut self) -> Function {
        self.flush();
        while self.blocks.len() > 1 {
            let inner = self.blocks.pop().unwrap_or_default();
            self.current().push(Statement::Block(inner), Span::default());
        }
        self.function.body = self.blocks.pop().unwrap_or_default();
        if let Some(result) = &self.function.result {
            // GLSL leaves the result of falling off the end of a non-void function undefined;
            // naga's WGSL front end would end such a body with `return;`, which is invalid. End
            // it with the zero of the result type wherever naga would.
            let zero = self.function.expressions.append(Expression::ZeroValue(result.ty), Span::default());
            ensure_returns(&mut self.function.body, zero);
        }
        self.function
    }
}

/// The literal a run-time scalar's variable is initialised with (a float by its bits).
fn init_literal(l: Literal) -> Literal {
    match l {
        Literal::F32(f) => Literal::U32(f.to_bits()),
        other => other,
    }
}

/// Appends `return zero;` wherever `naga::proc::ensure_block_returns` would append `return;`.
fn ensure_returns(block: &mut Block, zero: Handle<Expression>) {
    match block.last_mut() {
        Some(Statement::Block(b)) => ensure_returns(b, zero),
        Some(Statement::If { accept, reject, .. }) => {
            ensure_returns(accept, zero);
            ensure_returns(reject, zero);
        }
        Some(Statement::Switch { cases, .. }) => {
            for case in cases.iter_mut().filter(|c| !c.fall_through) {
                ensure_returns(&mut case.body, zero);
            }
        }
        Some(Statement::Break | Statement::Continue | Statement::Return { .. } | Statement::Kill) => {}
        _ => block.push(Statement::Return { value: Some(zero) }, Span::default()),
    }
}

//! The values of constant expressions, with the translated shader's semantics, and what naga's
//! constant evaluator would make of them.
//!
//! naga's WGSL front end evaluates every function-body expression built only from literals,
//! constants and the operations it can evaluate, and rejects the shader where WGSL is stricter
//! than GLSL (an overflowing shift, an integer division by zero, a float that is not finite, a
//! built-in outside its domain, `clamp` with `low > high`); naga's validator rejects a non-finite
//! float literal anywhere, and an integer division or a shift by a constant that is zero or too
//! large even when the other operand is a run-time value. [`evaluate`] mirrors naga's evaluator
//! operation by operation: for each expression the lowering builds it says whether the
//! expression is a run-time value, a constant naga evaluates to the same value without complaint
//! (kept as written), or a constant naga would reject, together with the value the translated
//! shader gives it at run time (the builder then writes that value instead). The semantics are
//! the ones gdsky's run-time code has through naga's back ends, so a folded constant and the same
//! computation at run time agree; see the lowering essay for the list.

use naga::{
    BinaryOperator as Bo, Expression as E, Handle, Literal, MathFunction as Mf, RelationalFunction, ScalarKind,
    SwizzleComponent, Type, UnaryOperator,
};

type H = Handle<E>;

/// The types the builder needs to write a value back as expressions.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TypeTable {
    /// `bool`, `i32`, `u32`, `f32`.
    pub scalars: [Handle<Type>; 4],
    /// Vectors of 2, 3, 4 of each scalar, in the order of [`TypeTable::scalars`].
    pub vectors: [[Handle<Type>; 3]; 4],
    /// `mat2x2<f32>`, `mat3x3<f32>`, `mat4x4<f32>`.
    pub matrices: [Handle<Type>; 3],
}

fn kind_index(l: &Literal) -> usize {
    match l {
        Literal::Bool(_) => 0,
        Literal::I32(_) => 1,
        Literal::U32(_) => 2,
        _ => 3,
    }
}

impl TypeTable {
    pub fn scalar(&self, l: &Literal) -> Handle<Type> {
        self.scalars[kind_index(l)]
    }

    pub fn vector(&self, first: &Literal, size: usize) -> Handle<Type> {
        self.vectors[kind_index(first)][size.clamp(2, 4) - 2]
    }

    pub fn matrix(&self, columns: usize) -> Handle<Type> {
        self.matrices[columns.clamp(2, 4) - 2]
    }

    fn vector_size_of(&self, ty: Handle<Type>) -> Option<usize> {
        self.vectors.iter().find_map(|row| row.iter().position(|&h| h == ty).map(|i| i + 2))
    }

    fn is_matrix(&self, ty: Handle<Type>) -> bool {
        self.matrices.contains(&ty)
    }
}

/// A constant value (a value that is not finite is a run-time value in the module, see
/// `FnBuilder`).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Value {
    Scalar(Literal),
    Vector(Vec<Literal>),
    /// Columns, each a vector.
    Matrix(Vec<Vec<Literal>>),
    /// An array or a struct, of the given type.
    Other(Handle<Type>, Vec<Value>),
}

impl Value {
    /// Every scalar, in order.
    pub fn scalars(&self) -> Vec<Literal> {
        match self {
            Value::Scalar(l) => vec![*l],
            Value::Vector(v) => v.clone(),
            Value::Matrix(c) => c.concat(),
            Value::Other(_, items) => items.iter().flat_map(Value::scalars).collect(),
        }
    }

    pub fn is_finite(&self) -> bool {
        self.scalars().iter().all(|l| !matches!(l, Literal::F32(f) if !f.is_finite()))
    }

    /// The components of a scalar or vector.
    fn lanes(&self) -> Option<Vec<Literal>> {
        match self {
            Value::Scalar(l) => Some(vec![*l]),
            Value::Vector(v) => Some(v.clone()),
            _ => None,
        }
    }
}

/// What the builder does with an expression.
pub(crate) enum Fold {
    /// A run-time value (or one naga leaves to run time): written as it is.
    Runtime,
    /// A constant naga evaluates to this value without complaint: written as it is.
    Keep(Value),
    /// A constant naga would reject: written as this value (literals, or run-time values where
    /// not finite).
    Replace(Value),
    /// A constant this folder cannot evaluate but naga would: operand `index` (in the order of
    /// [`operands`]) is made a run-time value, so naga leaves the expression to run time.
    Opaque(usize),
    /// A run-time integer division or shift whose right operand is a constant naga's validator
    /// refuses (a zero divisor, a shift by 32 or more): the operand becomes this value, made a
    /// run-time value for a divisor, masked literals for a shift.
    FixRight { value: Value, runtime: bool },
}

/// The operands of an expression the folder evaluates, in order.
pub(crate) fn operands(e: &E) -> Vec<H> {
    match e {
        E::Compose { components, .. } => components.clone(),
        E::Splat { value, .. } => vec![*value],
        E::AccessIndex { base, .. } => vec![*base],
        E::Access { base, index } => vec![*base, *index],
        E::Swizzle { vector, .. } => vec![*vector],
        E::Unary { expr, .. } => vec![*expr],
        E::Binary { left, right, .. } => vec![*left, *right],
        E::Math { arg, arg1, arg2, arg3, .. } => [Some(*arg), *arg1, *arg2, *arg3].into_iter().flatten().collect(),
        E::As { expr, .. } => vec![*expr],
        E::Select { condition, accept, reject } => vec![*condition, *accept, *reject],
        E::Relational { argument, .. } => vec![*argument],
        _ => Vec::new(),
    }
}

/// Replaces operand `index` (in the order of [`operands`]) of `e` by `to`.
pub(crate) fn replace_operand(e: &mut E, index: usize, to: H) {
    let mut i = 0;
    let mut visit = |h: &mut H| {
        if i == index {
            *h = to;
        }
        i += 1;
    };
    match e {
        E::Compose { components, .. } => components.iter_mut().for_each(visit),
        E::Splat { value, .. } => visit(value),
        E::AccessIndex { base, .. } => visit(base),
        E::Access { base, index } => {
            visit(base);
            visit(index);
        }
        E::Swizzle { vector, .. } => visit(vector),
        E::Unary { expr, .. } => visit(expr),
        E::Binary { left, right, .. } => {
            visit(left);
            visit(right);
        }
        E::Math { arg, arg1, arg2, arg3, .. } => {
            visit(arg);
            for a in [arg1, arg2, arg3].into_iter().flatten() {
                visit(a);
            }
        }
        E::As { expr, .. } => visit(expr),
        E::Select { condition, accept, reject } => {
            visit(condition);
            visit(accept);
            visit(reject);
        }
        E::Relational { argument, .. } => visit(argument),
        _ => {}
    }
}

/// What the builder should do with `e`, given the values of the expressions built so far.
pub(crate) fn evaluate(e: &E, known: &dyn Fn(H) -> Option<Value>, types: &TypeTable) -> Fold {
    if let E::Literal(l) = e {
        let v = Value::Scalar(*l);
        return if v.is_finite() { Fold::Keep(v) } else { Fold::Replace(v) };
    }
    let ops = operands(e);
    if ops.is_empty() {
        return Fold::Runtime;
    }
    let values: Vec<Option<Value>> = ops.iter().map(|&h| known(h)).collect();
    if values.iter().any(Option::is_none) {
        return run_time_right(e, &values);
    }
    let values: Vec<Value> = values.into_iter().flatten().collect();
    let outcome = match e {
        E::Compose { ty, .. } => compose(*ty, &values, types).map(Outcome::keep),
        E::Splat { size, .. } => match &values[0] {
            Value::Scalar(l) => Some(Outcome::keep(Value::Vector(vec![*l; *size as usize]))),
            _ => None,
        },
        E::AccessIndex { index, .. } => element(&values[0], *index as usize).map(Outcome::keep),
        E::Access { .. } => {
            let i = match values[1] {
                Value::Scalar(Literal::I32(i)) => usize::try_from(i).ok(),
                Value::Scalar(Literal::U32(i)) => Some(i as usize),
                _ => None,
            };
            i.and_then(|i| element(&values[0], i)).map(Outcome::keep)
        }
        E::Swizzle { size, pattern, .. } => match &values[0] {
            Value::Vector(v) => {
                let pick: Option<Vec<Literal>> =
                    pattern[..*size as usize].iter().map(|c| v.get(component(*c)).copied()).collect();
                pick.map(|p| Outcome::keep(Value::Vector(p)))
            }
            _ => None,
        },
        E::Unary { op, .. } => unary(*op, &values[0]),
        E::Binary { op, .. } => binary(*op, &values[0], &values[1], types),
        E::Math { fun, .. } => match math(*fun, &values, types) {
            MathOutcome::Done(o) => Some(o),
            MathOutcome::NotEvaluated => return Fold::Runtime,
            MathOutcome::Unknown => None,
        },
        E::As { kind, convert: Some(_), .. } => map_lanes(&values[0], |l| cast(l, *kind)).map(Outcome::keep),
        // naga does not evaluate a bitcast: it stays a run-time operation.
        E::As { convert: None, .. } => return Fold::Runtime,
        E::Select { .. } => select(&values[0], &values[1], &values[2]).map(Outcome::keep),
        E::Relational { fun, .. } => relational(*fun, &values[0]).map(Outcome::keep),
        _ => return Fold::Runtime,
    };
    match outcome {
        Some(Outcome { value, naga_accepts: true }) if value.is_finite() => Fold::Keep(value),
        Some(Outcome { value, .. }) => Fold::Replace(value),
        None => Fold::Opaque(0),
    }
}

/// A run-time expression whose constant right operand naga's validator refuses.
fn run_time_right(e: &E, values: &[Option<Value>]) -> Fold {
    let E::Binary { op, .. } = e else {
        return Fold::Runtime;
    };
    let (None, Some(right)) = (&values[0], &values[1]) else {
        return Fold::Runtime;
    };
    let lanes = right.scalars();
    match op {
        Bo::Divide | Bo::Modulo if lanes.iter().any(|l| matches!(l, Literal::I32(0) | Literal::U32(0))) => {
            // naga's run-time code divides by 1 instead (x / 0 = x, x % 0 = 0).
            Fold::FixRight { value: right.clone(), runtime: true }
        }
        Bo::ShiftLeft | Bo::ShiftRight if lanes.iter().any(|l| matches!(l, Literal::U32(s) if *s >= 32)) => {
            let masked = map_lanes(right, |l| match l {
                Literal::U32(s) => Some(Literal::U32(s & 31)),
                other => Some(other),
            });
            match masked {
                Some(value) => Fold::FixRight { value, runtime: false },
                None => Fold::Runtime,
            }
        }
        _ => Fold::Runtime,
    }
}

struct Outcome {
    value: Value,
    /// naga's evaluator computes the same value without an error.
    naga_accepts: bool,
}

impl Outcome {
    fn keep(value: Value) -> Self {
        Outcome { value, naga_accepts: true }
    }
}

fn component(c: SwizzleComponent) -> usize {
    match c {
        SwizzleComponent::X => 0,
        SwizzleComponent::Y => 1,
        SwizzleComponent::Z => 2,
        SwizzleComponent::W => 3,
    }
}

fn compose(ty: Handle<Type>, values: &[Value], types: &TypeTable) -> Option<Value> {
    if let Some(n) = types.vector_size_of(ty) {
        let lanes: Vec<Literal> = values.iter().map(Value::lanes).collect::<Option<Vec<_>>>()?.concat();
        return (lanes.len() == n).then_some(Value::Vector(lanes));
    }
    if types.is_matrix(ty) {
        let columns = values.iter().map(|v| match v {
            Value::Vector(c) => Some(c.clone()),
            _ => None,
        });
        return columns.collect::<Option<Vec<_>>>().map(Value::Matrix);
    }
    Some(Value::Other(ty, values.to_vec()))
}

fn element(v: &Value, i: usize) -> Option<Value> {
    match v {
        Value::Vector(c) => c.get(i).copied().map(Value::Scalar),
        Value::Matrix(c) => c.get(i).cloned().map(Value::Vector),
        Value::Other(_, items) => items.get(i).cloned(),
        Value::Scalar(_) => None,
    }
}

/// Applies `f` to each component of a scalar or vector.
fn map_lanes(v: &Value, f: impl Fn(Literal) -> Option<Literal>) -> Option<Value> {
    match v {
        Value::Scalar(l) => f(*l).map(Value::Scalar),
        Value::Vector(c) => c.iter().map(|l| f(*l)).collect::<Option<Vec<_>>>().map(Value::Vector),
        Value::Matrix(cols) => cols
            .iter()
            .map(|c| c.iter().map(|l| f(*l)).collect::<Option<Vec<_>>>())
            .collect::<Option<Vec<_>>>()
            .map(Value::Matrix),
        Value::Other(..) => None,
    }
}

fn unary(op: UnaryOperator, v: &Value) -> Option<Outcome> {
    let value = map_lanes(v, |l| {
        Some(match (op, l) {
            // naga wraps, as GLSL's ints do.
            (UnaryOperator::Negate, Literal::I32(x)) => Literal::I32(x.wrapping_neg()),
            (UnaryOperator::Negate, Literal::F32(x)) => Literal::F32(-x),
            (UnaryOperator::LogicalNot, Literal::Bool(b)) => Literal::Bool(!b),
            (UnaryOperator::BitwiseNot, Literal::I32(x)) => Literal::I32(!x),
            (UnaryOperator::BitwiseNot, Literal::U32(x)) => Literal::U32(!x),
            _ => return None,
        })
    })?;
    Some(Outcome::keep(value))
}

/// One lane of a binary operation: the run-time value, and whether naga evaluates it the same.
fn binary_lane(op: Bo, a: Literal, b: Literal) -> Option<(Literal, bool)> {
    use Literal as L;
    Some(match (a, b) {
        (L::I32(x), L::I32(y)) => match op {
            Bo::Add => (L::I32(x.wrapping_add(y)), true),
            Bo::Subtract => (L::I32(x.wrapping_sub(y)), true),
            Bo::Multiply => (L::I32(x.wrapping_mul(y)), true),
            // naga's run-time code divides by 1 for a zero divisor and for INT_MIN / -1.
            Bo::Divide if y == 0 || (x == i32::MIN && y == -1) => (L::I32(x), false),
            Bo::Divide => (L::I32(x / y), true),
            Bo::Modulo if y == 0 || (x == i32::MIN && y == -1) => (L::I32(0), false),
            Bo::Modulo => (L::I32(x % y), true),
            Bo::And => (L::I32(x & y), true),
            Bo::InclusiveOr => (L::I32(x | y), true),
            Bo::ExclusiveOr => (L::I32(x ^ y), true),
            _ => (L::Bool(compare(op, x.cmp(&y))?), true),
        },
        (L::U32(x), L::U32(y)) => match op {
            Bo::Add => (L::U32(x.wrapping_add(y)), true),
            Bo::Subtract => (L::U32(x.wrapping_sub(y)), true),
            Bo::Multiply => (L::U32(x.wrapping_mul(y)), true),
            Bo::Divide if y == 0 => (L::U32(x), false),
            Bo::Divide => (L::U32(x / y), true),
            Bo::Modulo if y == 0 => (L::U32(0), false),
            Bo::Modulo => (L::U32(x % y), true),
            Bo::And => (L::U32(x & y), true),
            Bo::InclusiveOr => (L::U32(x | y), true),
            Bo::ExclusiveOr => (L::U32(x ^ y), true),
            // A shift keeps the low 5 bits of its amount; naga refuses an amount of 32 or more
            // and a left shift that loses bits.
            Bo::ShiftLeft => (L::U32(x.wrapping_shl(y)), y < 32 && x.checked_mul(1u32 << y.min(31)).is_some()),
            Bo::ShiftRight => (L::U32(x.wrapping_shr(y)), y < 32),
            _ => (L::Bool(compare(op, x.cmp(&y))?), true),
        },
        (L::I32(x), L::U32(y)) => match op {
            // naga refuses a left shift that changes the sign bit or loses bits.
            Bo::ShiftLeft => (L::I32(x.wrapping_shl(y)), y < 32 && (if x < 0 { !x } else { x }).leading_zeros() > y),
            Bo::ShiftRight => (L::I32(x.wrapping_shr(y)), y < 32),
            _ => return None,
        },
        (L::F32(x), L::F32(y)) => match op {
            Bo::Add => (L::F32(x + y), true),
            Bo::Subtract => (L::F32(x - y), true),
            Bo::Multiply => (L::F32(x * y), true),
            Bo::Divide => (L::F32(x / y), true),
            Bo::Modulo => (L::F32(x % y), true),
            _ => (L::Bool(compare(op, x.partial_cmp(&y)?)?), true),
        },
        (L::Bool(x), L::Bool(y)) => match op {
            Bo::LogicalAnd | Bo::And => (L::Bool(x && y), true),
            Bo::LogicalOr | Bo::InclusiveOr => (L::Bool(x || y), true),
            Bo::Equal => (L::Bool(x == y), true),
            Bo::NotEqual => (L::Bool(x != y), true),
            _ => return None,
        },
        _ => return None,
    })
}

fn compare(op: Bo, o: std::cmp::Ordering) -> Option<bool> {
    use std::cmp::Ordering::*;
    Some(match op {
        Bo::Equal => o == Equal,
        Bo::NotEqual => o != Equal,
        Bo::Less => o == Less,
        Bo::LessEqual => o != Greater,
        Bo::Greater => o == Greater,
        Bo::GreaterEqual => o != Less,
        _ => return None,
    })
}

fn binary(op: Bo, a: &Value, b: &Value, types: &TypeTable) -> Option<Outcome> {
    match (a, b) {
        (Value::Matrix(_), _) | (_, Value::Matrix(_)) => matrix_binary(op, a, b, types),
        _ => {
            let (x, y) = (a.lanes()?, b.lanes()?);
            let n = x.len().max(y.len());
            // Vectors go lane by lane; a scalar operand (naga allows one in `*`) broadcasts.
            if !(x.len() == n || x.len() == 1) || !(y.len() == n || y.len() == 1) {
                return None;
            }
            let mut lanes = Vec::new();
            let mut accepts = true;
            for i in 0..n {
                let (l, ok) = binary_lane(op, x[i.min(x.len() - 1)], y[i.min(y.len() - 1)])?;
                lanes.push(l);
                accepts &= ok;
            }
            let value = if n == 1 && matches!((a, b), (Value::Scalar(_), Value::Scalar(_))) {
                Value::Scalar(lanes[0])
            } else {
                Value::Vector(lanes)
            };
            Some(Outcome { value, naga_accepts: accepts })
        }
    }
}

fn f32s(v: &[Literal]) -> Option<Vec<f32>> {
    v.iter()
        .map(|l| match l {
            Literal::F32(f) => Some(*f),
            _ => None,
        })
        .collect()
}

fn lits(v: impl IntoIterator<Item = f32>) -> Vec<Literal> {
    v.into_iter().map(Literal::F32).collect()
}

/// Matrix arithmetic, as naga evaluates it (column-major; `m * v` sums columns).
fn matrix_binary(op: Bo, a: &Value, b: &Value, _types: &TypeTable) -> Option<Outcome> {
    let mat = |v: &Value| match v {
        Value::Matrix(c) => c.iter().map(|col| f32s(col)).collect::<Option<Vec<_>>>(),
        _ => None,
    };
    let value = match (op, a, b) {
        (Bo::Add | Bo::Subtract, Value::Matrix(_), Value::Matrix(_)) => {
            let (x, y) = (mat(a)?, mat(b)?);
            let sign = if op == Bo::Add { 1.0 } else { -1.0 };
            Value::Matrix(x.iter().zip(&y).map(|(cx, cy)| lits(cx.iter().zip(cy).map(|(p, q)| p + sign * q))).collect())
        }
        (Bo::Multiply, Value::Matrix(_), Value::Scalar(Literal::F32(s)))
        | (Bo::Multiply, Value::Scalar(Literal::F32(s)), Value::Matrix(_)) => {
            let m = if matches!(a, Value::Matrix(_)) { mat(a)? } else { mat(b)? };
            Value::Matrix(m.iter().map(|c| lits(c.iter().map(|x| x * s))).collect())
        }
        (Bo::Multiply, Value::Matrix(_), Value::Vector(v)) => {
            let (m, v) = (mat(a)?, f32s(v)?);
            let rows = m.first()?.len();
            Value::Vector(lits((0..rows).map(|r| m.iter().zip(&v).map(|(col, x)| col[r] * x).sum::<f32>())))
        }
        (Bo::Multiply, Value::Vector(v), Value::Matrix(_)) => {
            let (v, m) = (f32s(v)?, mat(b)?);
            Value::Vector(lits(m.iter().map(|col| col.iter().zip(&v).map(|(c, x)| c * x).sum::<f32>())))
        }
        (Bo::Multiply, Value::Matrix(_), Value::Matrix(_)) => {
            let (x, y) = (mat(a)?, mat(b)?);
            let rows = x.first()?.len();
            Value::Matrix(
                y.iter()
                    .map(|ycol| lits((0..rows).map(|r| x.iter().zip(ycol).map(|(xc, k)| xc[r] * k).sum::<f32>())))
                    .collect(),
            )
        }
        _ => return None,
    };
    Some(Outcome::keep(value))
}

/// naga's conversion of one literal (`As` with a width).
fn cast(l: Literal, kind: ScalarKind) -> Option<Literal> {
    use Literal as L;
    Some(match (kind, l) {
        (ScalarKind::Sint, L::I32(v)) => L::I32(v),
        (ScalarKind::Sint, L::U32(v)) => L::I32(v as i32),
        (ScalarKind::Sint, L::F32(v)) => L::I32(v.clamp(-2_147_483_648.0, 2_147_483_520.0) as i32),
        (ScalarKind::Sint, L::Bool(v)) => L::I32(i32::from(v)),
        (ScalarKind::Uint, L::I32(v)) => L::U32(v as u32),
        (ScalarKind::Uint, L::U32(v)) => L::U32(v),
        (ScalarKind::Uint, L::F32(v)) => L::U32(v.clamp(0.0, 4_294_967_040.0) as u32),
        (ScalarKind::Uint, L::Bool(v)) => L::U32(u32::from(v)),
        (ScalarKind::Float, L::I32(v)) => L::F32(v as f32),
        (ScalarKind::Float, L::U32(v)) => L::F32(v as f32),
        (ScalarKind::Float, L::F32(v)) => L::F32(v),
        (ScalarKind::Float, L::Bool(v)) => L::F32(f32::from(u8::from(v))),
        (ScalarKind::Bool, L::I32(v)) => L::Bool(v != 0),
        (ScalarKind::Bool, L::U32(v)) => L::Bool(v != 0),
        (ScalarKind::Bool, L::F32(v)) => L::Bool(v != 0.0),
        (ScalarKind::Bool, L::Bool(v)) => L::Bool(v),
        _ => return None,
    })
}

fn select(condition: &Value, accept: &Value, reject: &Value) -> Option<Value> {
    match condition {
        Value::Scalar(Literal::Bool(c)) => Some(if *c { accept.clone() } else { reject.clone() }),
        Value::Vector(c) => {
            let (a, r) = (accept.lanes()?, reject.lanes()?);
            let lanes = c
                .iter()
                .enumerate()
                .map(|(i, c)| match c {
                    Literal::Bool(true) => a.get(i).copied(),
                    Literal::Bool(false) => r.get(i).copied(),
                    _ => None,
                })
                .collect::<Option<Vec<_>>>()?;
            Some(Value::Vector(lanes))
        }
        _ => None,
    }
}

fn relational(fun: RelationalFunction, v: &Value) -> Option<Value> {
    let lanes = v.lanes()?;
    let bools = || lanes.iter().map(|l| if let Literal::Bool(b) = l { Some(*b) } else { None });
    Some(match fun {
        RelationalFunction::All => {
            Value::Scalar(Literal::Bool(bools().collect::<Option<Vec<_>>>()?.iter().all(|b| *b)))
        }
        RelationalFunction::Any => {
            Value::Scalar(Literal::Bool(bools().collect::<Option<Vec<_>>>()?.iter().any(|b| *b)))
        }
        RelationalFunction::IsNan | RelationalFunction::IsInf => {
            let test = |f: f32| if fun == RelationalFunction::IsNan { f.is_nan() } else { f.is_infinite() };
            let out: Vec<Literal> =
                lanes.iter().map(|l| Literal::Bool(matches!(l, Literal::F32(f) if test(*f)))).collect();
            if matches!(v, Value::Scalar(_)) { Value::Scalar(out[0]) } else { Value::Vector(out) }
        }
    })
}

enum MathOutcome {
    Done(Outcome),
    /// naga does not evaluate this function: the result is a run-time value.
    NotEvaluated,
    /// naga evaluates it but this folder does not.
    Unknown,
}

/// The built-in functions naga's evaluator computes, with its formulas; the result is what the
/// function gives at run time too, IEEE-754 in single precision outside GLSL's domain
/// (`sqrt(-1)` NaN, `log(0)` -inf, `pow(-1, 0.5)` NaN).
fn math(fun: Mf, args: &[Value], types: &TypeTable) -> MathOutcome {
    use MathOutcome::*;
    let _ = types;
    match fun {
        Mf::Modf
        | Mf::Frexp
        | Mf::Ldexp
        | Mf::Outer
        | Mf::FaceForward
        | Mf::Reflect
        | Mf::Refract
        | Mf::Mix
        | Mf::SmoothStep
        | Mf::Inverse
        | Mf::Transpose
        | Mf::Determinant
        | Mf::QuantizeToF16
        | Mf::ExtractBits
        | Mf::InsertBits
        | Mf::Pack4x8snorm
        | Mf::Pack4x8unorm
        | Mf::Pack2x16snorm
        | Mf::Pack2x16unorm
        | Mf::Pack2x16float
        | Mf::Pack4xI8
        | Mf::Pack4xU8
        | Mf::Pack4xI8Clamp
        | Mf::Pack4xU8Clamp
        | Mf::Unpack4x8snorm
        | Mf::Unpack4x8unorm
        | Mf::Unpack2x16snorm
        | Mf::Unpack2x16unorm
        | Mf::Unpack2x16float
        | Mf::Unpack4xI8
        | Mf::Unpack4xU8 => return NotEvaluated,
        _ => {}
    }
    let geometric = match fun {
        Mf::Dot | Mf::Length | Mf::Distance | Mf::Normalize | Mf::Cross => Some(geometric(fun, args)),
        _ => None,
    };
    if let Some(g) = geometric {
        return g.map_or(Unknown, Done);
    }
    let lanes: Option<Vec<Vec<Literal>>> = args.iter().map(Value::lanes).collect();
    let Some(lanes) = lanes else {
        return Unknown;
    };
    let n = lanes.iter().map(Vec::len).max().unwrap_or(1);
    let mut out = Vec::new();
    let mut accepts = true;
    for i in 0..n {
        let lane: Vec<Literal> = lanes.iter().map(|a| a[i.min(a.len() - 1)]).collect();
        match math_lane(fun, &lane) {
            Some((l, ok)) => {
                out.push(l);
                accepts &= ok;
            }
            None => return Unknown,
        }
    }
    let value = if matches!(args[0], Value::Scalar(_)) { Value::Scalar(out[0]) } else { Value::Vector(out) };
    Done(Outcome { value, naga_accepts: accepts })
}

fn math_lane(fun: Mf, a: &[Literal]) -> Option<(Literal, bool)> {
    use Literal as L;
    let f = |i: usize| match a.get(i) {
        Some(L::F32(x)) => Some(*x),
        _ => None,
    };
    // Integer functions.
    match (fun, a[0]) {
        (Mf::Abs, L::I32(x)) => return Some((L::I32(x.wrapping_abs()), true)),
        (Mf::Abs, L::U32(x)) => return Some((L::U32(x), true)),
        (Mf::Sign, L::I32(x)) => return Some((L::I32(x.signum()), true)),
        (Mf::Min | Mf::Max | Mf::Clamp, L::I32(_) | L::U32(_)) => {
            let int = |l: &Literal| match l {
                L::I32(v) => Some(i64::from(*v)),
                L::U32(v) => Some(i64::from(*v)),
                _ => None,
            };
            let v: Vec<i64> = a.iter().map(int).collect::<Option<_>>()?;
            let (r, ok) = match fun {
                Mf::Min => (v[0].min(*v.get(1)?), true),
                Mf::Max => (v[0].max(*v.get(1)?), true),
                // naga refuses `low > high`; at run time clamp is max then min.
                _ => (v[0].max(*v.get(1)?).min(*v.get(2)?), v[1] <= v[2]),
            };
            let l = if matches!(a[0], L::I32(_)) { L::I32(r as i32) } else { L::U32(r as u32) };
            return Some((l, ok));
        }
        (Mf::CountOneBits, L::I32(x)) => return Some((L::I32(x.count_ones() as i32), true)),
        (Mf::CountOneBits, L::U32(x)) => return Some((L::U32(x.count_ones()), true)),
        (Mf::ReverseBits, L::I32(x)) => return Some((L::I32(x.reverse_bits()), true)),
        (Mf::ReverseBits, L::U32(x)) => return Some((L::U32(x.reverse_bits()), true)),
        (_, L::F32(_)) => {}
        _ => return None,
    }
    let x = f(0)?;
    let finite = |r: f32| (L::F32(r), r.is_finite());
    Some(match fun {
        Mf::Abs => finite(x.abs()),
        Mf::Min => finite(x.min(f(1)?)),
        Mf::Max => finite(x.max(f(1)?)),
        Mf::Clamp => {
            let (lo, hi) = (f(1)?, f(2)?);
            (L::F32(x.max(lo).min(hi)), lo <= hi)
        }
        Mf::Saturate => finite(x.clamp(0.0, 1.0)),
        Mf::Cos => finite(x.cos()),
        Mf::Cosh => finite(x.cosh()),
        Mf::Sin => finite(x.sin()),
        Mf::Sinh => finite(x.sinh()),
        Mf::Tan => finite(x.tan()),
        Mf::Tanh => finite(x.tanh()),
        Mf::Acos => finite(x.acos()),
        Mf::Asin => finite(x.asin()),
        Mf::Atan => finite(x.atan()),
        Mf::Atan2 => finite(x.atan2(f(1)?)),
        Mf::Asinh => finite((f64::from(x)).asinh() as f32),
        Mf::Acosh => finite((f64::from(x)).acosh() as f32),
        Mf::Atanh => finite(x.atanh()),
        Mf::Radians => finite(x.to_radians()),
        Mf::Degrees => finite(x.to_degrees()),
        Mf::Ceil => finite(x.ceil()),
        Mf::Floor => finite(x.floor()),
        Mf::Round => finite(x.round_ties_even()),
        Mf::Fract => finite(x - x.floor()),
        Mf::Trunc => finite(x.trunc()),
        Mf::Exp => finite(x.exp()),
        Mf::Exp2 => finite(x.exp2()),
        Mf::Log => finite(x.ln()),
        Mf::Log2 => finite(x.log2()),
        Mf::Pow => {
            let y = f(1)?;
            let r = x.powf(y);
            // naga refuses these even where the result is finite (`pow(-2, 2)`, `pow(0, 0)`).
            let refused = x < 0.0 || (x == 1.0 && y.is_infinite()) || (x == 0.0 && y == 0.0);
            (L::F32(r), !refused && r.is_finite())
        }
        Mf::Sign => finite(if x == 0.0 { 0.0 } else { x.signum() }),
        Mf::Fma => finite(x.mul_add(f(1)?, f(2)?)),
        Mf::Step => finite(if x <= f(1)? { 1.0 } else { 0.0 }),
        Mf::Sqrt => finite(x.sqrt()),
        Mf::InverseSqrt => finite(1.0 / x.sqrt()),
        _ => return None,
    })
}

fn geometric(fun: Mf, args: &[Value]) -> Option<Outcome> {
    let vec = |v: &Value| match v {
        Value::Vector(c) => f32s(c),
        Value::Scalar(l) => f32s(std::slice::from_ref(l)),
        _ => None,
    };
    let length = |v: &[f32]| v.iter().map(|x| x * x).sum::<f32>().sqrt();
    let scalar = |r: f32| Outcome { value: Value::Scalar(Literal::F32(r)), naga_accepts: r.is_finite() };
    Some(match fun {
        Mf::Dot => {
            let (a, b) = (vec(&args[0])?, vec(args.get(1)?)?);
            scalar(a.iter().zip(&b).map(|(x, y)| x * y).sum())
        }
        Mf::Length => scalar(length(&vec(&args[0])?)),
        Mf::Distance => {
            let (a, b) = (vec(&args[0])?, vec(args.get(1)?)?);
            let d: Vec<f32> = a.iter().zip(&b).map(|(x, y)| x - y).collect();
            scalar(length(&d))
        }
        Mf::Normalize => {
            let a = vec(&args[0])?;
            let len = length(&a);
            let out: Vec<f32> = a.iter().map(|x| x / len).collect();
            let ok = out.iter().all(|x| x.is_finite());
            Outcome { value: Value::Vector(lits(out)), naga_accepts: ok }
        }
        Mf::Cross => {
            let (a, b) = (vec(&args[0])?, vec(args.get(1)?)?);
            if a.len() != 3 || b.len() != 3 {
                return None;
            }
            let c = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
            Outcome { value: Value::Vector(lits(c)), naga_accepts: c.iter().all(|x| x.is_finite()) }
        }
        _ => return None,
    })
}

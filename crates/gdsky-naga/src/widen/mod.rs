//! # Widening: the same shader evaluated in f64
//!
//! [`crate::lower_f64`] lowers a shader as usual (f32, validated), then this pass rewrites the
//! validated module so that every float the shader computes with is an f64, and the module's
//! boundaries stay what the host and the pipeline expect (f32). It is a pass over naga IR
//! rather than a mode of the lowering so the f32 path (and its snapshots) cannot change, and so
//! the rules of the f64 evaluation sit in one place:
//!
//! * **Types.** Every `f32` scalar, vector and matrix type becomes its `f64` form, and arrays
//!   and structs built from them are re-laid out (naga's layouter gives the f64 sizes). Module
//!   constants, private globals (the wrapper's per-pixel built-ins: EYEDIR, COLOR, …), locals,
//!   function arguments and results are all widened.
//! * **Literals** come back at f64 precision: the lowering rounds each float constant of the
//!   shader (a literal, a folded `const`, `PI`, the wrapper's 2π) from the f64 the front end
//!   computed, and [`crate::lower_f64`] records those f64 values by the f32 they rounded to
//!   ([`ExactFloats`]). A literal whose f32 was recorded from one f64 only becomes that f64; any
//!   other (one the lowering's constant folding computed in f32, or an f32 two different
//!   constants round to) is widened exactly as it is.
//! * **Boundaries stay f32 and are converted:** loads from the material and built-ins uniform
//!   blocks (any uniform, storage or handle global; the host layout is unchanged, so
//!   `skyrun::material_bytes` fills an f64 module's block as it fills the f32 one) are widened
//!   after the load; texture samples and loads return f32 and are widened, and their float
//!   coordinates, levels, gradients and depth references are rounded to f32 on the way in;
//!   entry-point arguments (FRAGCOORD, the vertex index) are widened at the top of the entry
//!   point; an entry point's return value is rounded to f32 at the `return`.
//! * **Derivatives** (`dFdx`, `dFdy`, `fwidth`) are taken in f32: the operand is rounded to f32,
//!   differentiated, and the result widened (SPIR-V's derivative instructions are f32-only).
//! * **Bit casts** (`floatBitsToInt` and friends) act on the value rounded to f32, as the f32
//!   shader would; `intBitsToFloat` gives an f32 that is then widened. Packing built-ins
//!   (`packHalf2x16`, …) round their operand to f32; unpacking widens the result.
//! * **Transcendentals.** GLSL.std.450 has no f64 form of exp, exp2, log, log2, pow, sin, cos,
//!   tan, asin, acos, atan, atan2, sinh, cosh, tanh, asinh, acosh, atanh, radians and degrees
//!   (Vulkan drivers reject them). `radians`/`degrees` become a multiplication by π/180 or
//!   180/π in f64; the others become calls to f64 routines written in WGSL
//!   (`f64_math.wgsl`, essay at its top), grafted into the module on first use ([`graft`]),
//!   one call per component of a vector. Their measured errors are in `docs/precision.md`.
//!   sqrt, inversesqrt, fma, floor, abs, min/max, mix, clamp, length, normalize, cross, … have
//!   f64 forms and are kept.
//!
//! The fragment output is f32, so a single f64 evaluation can only be read back rounded. For a
//! reader that wants the f64 value, [`F64Output::Residual`] makes the fragment entries return
//! `f32(c − f64(f32(c)))` instead of `f32(c)`: the nearest f32 and the residual, rendered in two
//! passes and added in f64, carry ~48 significant bits (`skyrun::F64Sky` does this).
//!
//! Not supported (an error naming the construct): overrides (`--override`), atomics, storage
//! writes, image stores, subgroup and ray-query operations; none occur in sky shaders.

pub(crate) mod graft;

pub use graft::F64_MATH_WGSL;

use naga::proc::Layouter;
use naga::valid::{FunctionInfo, ModuleInfo};
use naga::{
    AddressSpace, ArraySize, BinaryOperator, Block, Expression as E, Function, Handle, Literal, MathFunction as Mf,
    Module, Range, SampleLevel, Scalar, ScalarKind, Span, Statement, Type, TypeInner,
};
use std::collections::HashMap;

/// What the fragment entry points of an f64 module return.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum F64Output {
    /// The f64 result rounded to f32: the image the f64 evaluation gives on an f32 target.
    #[default]
    Nearest,
    /// `f32(c − f64(f32(c)))`, what rounding to f32 loses; with the [`Nearest`](Self::Nearest)
    /// image it gives c to ~48 bits.
    Residual,
}

/// The f64 values the lowering rounded float constants from, by the bits of the f32 each became;
/// `None` where two different f64 values rounded to the same f32 (then the f32 is kept).
pub type ExactFloats = HashMap<u32, Option<f64>>;

/// The f64 module of a validated f32 module, or why it cannot be built.
pub(crate) fn widen(
    module: &Module,
    info: &ModuleInfo,
    exact: &ExactFloats,
    output: F64Output,
) -> Result<Module, String> {
    if !module.overrides.is_empty() {
        return Err("overrides (`--override`) are not supported by the f64 evaluation".into());
    }
    let lib = graft::library()?;
    let mut w = Widener {
        old: module,
        new: module.clone(),
        wide: HashMap::new(),
        layouter: Layouter::default(),
        exact,
        routines: HashMap::new(),
        fmap: HashMap::new(),
    };
    // The routines first: naga wants a function defined before it is called.
    w.new.functions = naga::Arena::new();
    let mut grafter = graft::Grafter::new(lib);
    let mut needed = Vec::new();
    for (_, f) in module.functions.iter() {
        routines_used(f, &mut needed);
    }
    for ep in &module.entry_points {
        routines_used(&ep.function, &mut needed);
    }
    for name in needed {
        let h = grafter.routine(&mut w.new, name)?;
        w.routines.insert(name, h);
    }
    // Module scope: constants, their expressions, private globals.
    for (h, _) in module.constants.iter() {
        let ty = w.wide(module.constants[h].ty)?;
        w.new.constants[h].ty = ty;
    }
    for (h, e) in module.global_expressions.iter() {
        let new = match e {
            E::Literal(l) => E::Literal(w.literal(*l)),
            E::ZeroValue(ty) => E::ZeroValue(w.wide(*ty)?),
            E::Compose { ty, components } => E::Compose { ty: w.wide(*ty)?, components: components.clone() },
            E::As { expr, kind: ScalarKind::Float, convert: Some(4) } => {
                E::As { expr: *expr, kind: ScalarKind::Float, convert: Some(8) }
            }
            other => other.clone(),
        };
        w.new.global_expressions[h] = new;
    }
    for (h, g) in module.global_variables.iter() {
        if !boundary_space(g.space) {
            let ty = w.wide(g.ty)?;
            w.new.global_variables[h].ty = ty;
        }
    }
    for (h, f) in module.functions.iter() {
        let nf = FnWiden::run(&mut w, f, &info[h], None)?;
        let nh = w.new.functions.append(nf, module.functions.get_span(h));
        w.fmap.insert(h, nh);
    }
    for (i, ep) in module.entry_points.iter().enumerate() {
        let out = if ep.stage == naga::ShaderStage::Fragment { output } else { F64Output::Nearest };
        let nf = FnWiden::run(&mut w, &ep.function, info.get_entry_point(i), Some(out))?;
        w.new.entry_points[i].function = nf;
    }
    Ok(w.new)
}

/// Address spaces whose memory the host or the pipeline lays out: kept f32.
fn boundary_space(space: AddressSpace) -> bool {
    !matches!(space, AddressSpace::Private | AddressSpace::Function | AddressSpace::WorkGroup)
}

/// The library routine replacing a math function on f64, if any.
fn routine_of(fun: Mf) -> Option<&'static str> {
    Some(match fun {
        Mf::Exp => "gdsky_f64_exp",
        Mf::Exp2 => "gdsky_f64_exp2",
        Mf::Log => "gdsky_f64_log",
        Mf::Log2 => "gdsky_f64_log2",
        Mf::Pow => "gdsky_f64_pow",
        Mf::Sin => "gdsky_f64_sin",
        Mf::Cos => "gdsky_f64_cos",
        Mf::Tan => "gdsky_f64_tan",
        Mf::Asin => "gdsky_f64_asin",
        Mf::Acos => "gdsky_f64_acos",
        Mf::Atan => "gdsky_f64_atan",
        Mf::Atan2 => "gdsky_f64_atan2",
        Mf::Sinh => "gdsky_f64_sinh",
        Mf::Cosh => "gdsky_f64_cosh",
        Mf::Tanh => "gdsky_f64_tanh",
        Mf::Asinh => "gdsky_f64_asinh",
        Mf::Acosh => "gdsky_f64_acosh",
        Mf::Atanh => "gdsky_f64_atanh",
        Mf::Frexp => "gdsky_f64_frexp",
        _ => return None,
    })
}

/// Routines a function's math needs (every float math of an f32 module is f32, so every use
/// of a listed function needs its routine).
fn routines_used(f: &Function, out: &mut Vec<&'static str>) {
    for (_, e) in f.expressions.iter() {
        if let E::Math { fun, .. } = e
            && let Some(name) = routine_of(*fun)
            && !out.contains(&name)
        {
            out.push(name);
        }
    }
}

fn has_f32(types: &naga::UniqueArena<Type>, inner: &TypeInner) -> bool {
    match inner {
        TypeInner::Scalar(s) | TypeInner::Vector { scalar: s, .. } | TypeInner::Matrix { scalar: s, .. } => {
            *s == Scalar::F32
        }
        TypeInner::ValuePointer { scalar, .. } => *scalar == Scalar::F32,
        TypeInner::Array { base, .. } | TypeInner::Pointer { base, .. } => has_f32(types, &types[*base].inner),
        TypeInner::Struct { members, .. } => members.iter().any(|m| has_f32(types, &types[m.ty].inner)),
        _ => false,
    }
}

struct Widener<'a> {
    old: &'a Module,
    new: Module,
    /// f32 type → its f64 form (itself when it holds no f32).
    wide: HashMap<Handle<Type>, Handle<Type>>,
    layouter: Layouter,
    exact: &'a ExactFloats,
    routines: HashMap<&'static str, Handle<naga::Function>>,
    /// Old function handles → new (the routines come first).
    fmap: HashMap<Handle<naga::Function>, Handle<naga::Function>>,
}

impl Widener<'_> {
    fn literal(&self, l: Literal) -> Literal {
        match l {
            Literal::F32(v) => Literal::F64(self.exact.get(&v.to_bits()).copied().flatten().unwrap_or(f64::from(v))),
            other => other,
        }
    }

    fn insert(&mut self, inner: TypeInner) -> Handle<Type> {
        self.new.types.insert(Type { name: None, inner }, Span::UNDEFINED)
    }

    /// Size and alignment of a type of the new module.
    fn layout(&mut self, ty: Handle<Type>) -> Result<(u32, naga::proc::Alignment), String> {
        self.layouter.update(self.new.to_ctx()).map_err(|e| format!("laying out an f64 type: {e}"))?;
        let l = self.layouter[ty];
        Ok((l.size, l.alignment))
    }

    /// The f64 form of a type of the f32 module.
    fn wide(&mut self, ty: Handle<Type>) -> Result<Handle<Type>, String> {
        if let Some(t) = self.wide.get(&ty) {
            return Ok(*t);
        }
        let old = &self.new.types[ty];
        let (name, inner) = (old.name.clone(), old.inner.clone());
        let new = if !has_f32(&self.new.types, &inner) {
            ty
        } else {
            match inner {
                TypeInner::Scalar(_) => self.insert(TypeInner::Scalar(Scalar::F64)),
                TypeInner::Vector { size, .. } => self.insert(TypeInner::Vector { size, scalar: Scalar::F64 }),
                TypeInner::Matrix { columns, rows, .. } => {
                    self.insert(TypeInner::Matrix { columns, rows, scalar: Scalar::F64 })
                }
                TypeInner::ValuePointer { size, space, .. } => {
                    self.insert(TypeInner::ValuePointer { size, scalar: Scalar::F64, space })
                }
                TypeInner::Pointer { base, space } => {
                    let base = self.wide(base)?;
                    self.insert(TypeInner::Pointer { base, space })
                }
                TypeInner::Array { base, size, .. } => {
                    let base = self.wide(base)?;
                    let (bsize, align) = self.layout(base)?;
                    self.insert(TypeInner::Array { base, size, stride: align.round_up(bsize) })
                }
                TypeInner::Struct { members, .. } => {
                    let key = self.old.special_types.predeclared_types.iter().find(|(_, t)| **t == ty).map(|(k, _)| k);
                    match key {
                        Some(naga::PredeclaredType::ModfResult { size, .. }) => {
                            self.new.generate_predeclared_type(naga::PredeclaredType::ModfResult {
                                size: *size,
                                scalar: Scalar::F64,
                            })
                        }
                        Some(other @ naga::PredeclaredType::AtomicCompareExchangeWeakResult(_)) => {
                            return Err(format!("cannot widen naga's predeclared type {other:?}"));
                        }
                        // naga's f64 frexp result has an i64 exponent (SHADER_INT64); the
                        // widened frexp builds a plain struct { fract: f64, exp: i32 } instead.
                        Some(naga::PredeclaredType::FrexpResult { .. }) | None => {
                            let mut out = Vec::with_capacity(members.len());
                            let (mut offset, mut max_align) = (0u32, naga::proc::Alignment::ONE);
                            for m in &members {
                                let mty = self.wide(m.ty)?;
                                let (size, align) = self.layout(mty)?;
                                let at = align.round_up(offset);
                                out.push(naga::StructMember { ty: mty, offset: at, ..m.clone() });
                                offset = at + size;
                                max_align = max_align.max(align);
                            }
                            let span = max_align.round_up(offset);
                            let name = name.map(|n| format!("{n}_f64"));
                            self.new
                                .types
                                .insert(Type { name, inner: TypeInner::Struct { members: out, span } }, Span::UNDEFINED)
                        }
                    }
                }
                other => return Err(format!("cannot widen the type {other:?}")),
            }
        };
        self.wide.insert(ty, new);
        Ok(new)
    }
}

/// Rewrites one function into the new module.
struct FnWiden<'w, 'a> {
    w: &'w mut Widener<'a>,
    old: &'w Function,
    info: &'w FunctionInfo,
    exprs: naga::Arena<E>,
    /// Old expression → the new expression holding its (widened) value.
    map: Vec<Handle<E>>,
    /// Old expression → the new expressions appended while translating it (start, end).
    created: Vec<(usize, usize)>,
    /// New call results and the call statements that produce them.
    calls: HashMap<Handle<E>, Statement>,
    /// Emittable expressions made for pre-emitted ones (entry arguments): emitted first.
    prologue: Vec<Handle<E>>,
    /// `Some(output)` for an entry point.
    entry: Option<F64Output>,
    /// The new arena's handles by index (naga does not make handles from indices).
    handles: Vec<Handle<E>>,
}

impl<'w, 'a> FnWiden<'w, 'a> {
    fn run(
        w: &'w mut Widener<'a>,
        old: &'w Function,
        info: &'w FunctionInfo,
        entry: Option<F64Output>,
    ) -> Result<Function, String> {
        let mut f = FnWiden {
            w,
            old,
            info,
            exprs: naga::Arena::new(),
            map: Vec::with_capacity(old.expressions.len()),
            created: Vec::with_capacity(old.expressions.len()),
            calls: HashMap::new(),
            prologue: Vec::new(),
            entry,
            handles: Vec::new(),
        };
        for (h, e) in old.expressions.iter() {
            let start = f.exprs.len();
            let span = old.expressions.get_span(h);
            let v = f.expression(h, e, span)?;
            f.map.push(v);
            if e.needs_pre_emit() {
                // Conversions of a pre-emitted value are emitted at the top of the function.
                let made: Vec<_> =
                    f.handles[start..].iter().copied().filter(|n| !f.exprs[*n].needs_pre_emit()).collect();
                f.prologue.extend(made);
            }
            f.created.push((start, f.exprs.len()));
        }
        let mut body = Block::new();
        for h in std::mem::take(&mut f.prologue) {
            body.push(Statement::Emit(Range::new_from_bounds(h, h)), Span::UNDEFINED);
        }
        let rest = f.block(&old.body)?;
        body.extend_block(rest);
        let mut locals = old.local_variables.clone();
        for (_, l) in locals.iter_mut() {
            l.ty = f.w.wide(l.ty)?;
            l.init = l.init.map(|i| f.map[i.index()]);
        }
        let mut arguments = old.arguments.clone();
        let mut result = old.result.clone();
        if entry.is_none() {
            for a in &mut arguments {
                a.ty = f.w.wide(a.ty)?;
            }
            if let Some(r) = &mut result {
                r.ty = f.w.wide(r.ty)?;
            }
        }
        let named_expressions = old.named_expressions.iter().map(|(h, n)| (f.map[h.index()], n.clone())).collect();
        Ok(Function {
            name: old.name.clone(),
            arguments,
            result,
            local_variables: locals,
            expressions: f.exprs,
            named_expressions,
            body,
            diagnostic_filter_leaf: old.diagnostic_filter_leaf,
        })
    }

    fn push(&mut self, e: E, span: Span) -> Handle<E> {
        let h = self.exprs.append(e, span);
        self.handles.push(h);
        h
    }

    fn m(&self, h: Handle<E>) -> Handle<E> {
        self.map[h.index()]
    }

    /// The f32-form type of an old expression, as a handle of the new module.
    fn old_ty(&mut self, h: Handle<E>) -> Handle<Type> {
        match &self.info[h].ty {
            naga::proc::TypeResolution::Handle(t) => *t,
            naga::proc::TypeResolution::Value(inner) => {
                let inner = inner.clone();
                self.w.insert(inner)
            }
        }
    }

    /// Converts `e` (new) between an f32-form type and its f64 form: `up` widens, else rounds.
    fn convert(&mut self, e: Handle<E>, ty: Handle<Type>, up: bool, span: Span) -> Result<Handle<E>, String> {
        let inner = self.w.new.types[ty].inner.clone();
        if !has_f32(&self.w.new.types, &inner) {
            return Ok(e);
        }
        let target = if up { self.w.wide(ty)? } else { ty };
        let width = if up { 8 } else { 4 };
        Ok(match inner {
            TypeInner::Scalar(_) | TypeInner::Vector { .. } => {
                self.push(E::As { expr: e, kind: ScalarKind::Float, convert: Some(width) }, span)
            }
            TypeInner::Matrix { columns, .. } => {
                let mut comps = Vec::new();
                for i in 0..columns as u32 {
                    let c = self.push(E::AccessIndex { base: e, index: i }, span);
                    comps.push(self.push(E::As { expr: c, kind: ScalarKind::Float, convert: Some(width) }, span));
                }
                self.push(E::Compose { ty: target, components: comps }, span)
            }
            TypeInner::Struct { members, .. } => {
                let mut comps = Vec::new();
                for (i, m) in members.iter().enumerate() {
                    let c = self.push(E::AccessIndex { base: e, index: i as u32 }, span);
                    comps.push(self.convert(c, m.ty, up, span)?);
                }
                self.push(E::Compose { ty: target, components: comps }, span)
            }
            TypeInner::Array { base, size: ArraySize::Constant(n), .. } => {
                let mut comps = Vec::new();
                for i in 0..n.get() {
                    let c = self.push(E::AccessIndex { base: e, index: i }, span);
                    comps.push(self.convert(c, base, up, span)?);
                }
                self.push(E::Compose { ty: target, components: comps }, span)
            }
            other => return Err(format!("cannot convert a value of type {other:?} between f32 and f64")),
        })
    }

    /// Whether an old pointer expression points into host-laid-out memory.
    fn boundary_pointer(&self, mut h: Handle<E>) -> bool {
        loop {
            match &self.old.expressions[h] {
                E::Access { base, .. } | E::AccessIndex { base, .. } => h = *base,
                E::GlobalVariable(g) => return boundary_space(self.w.old.global_variables[*g].space),
                _ => return false,
            }
        }
    }

    fn is_f32_value(&self, h: Handle<E>) -> bool {
        has_f32(&self.w.old.types, self.info[h].ty.inner_with(&self.w.old.types))
    }

    /// Rounds an old operand's new value to f32 (for an f32-only operation).
    fn down(&mut self, h: Handle<E>, span: Span) -> Result<Handle<E>, String> {
        let ty = self.old_ty(h);
        let v = self.m(h);
        self.convert(v, ty, false, span)
    }

    fn expression(&mut self, h: Handle<E>, e: &E, span: Span) -> Result<Handle<E>, String> {
        let m = |h: &Handle<E>| self.map[h.index()];
        let new = match e {
            E::Literal(l) => E::Literal(self.w.literal(*l)),
            E::Constant(c) => E::Constant(*c),
            E::Override(_) => return Err("overrides are not supported by the f64 evaluation".into()),
            E::ZeroValue(ty) => E::ZeroValue(self.w.wide(*ty)?),
            E::Compose { ty, components } => {
                let components = components.iter().map(m).collect();
                E::Compose { ty: self.w.wide(*ty)?, components }
            }
            E::Access { base, index } => E::Access { base: m(base), index: m(index) },
            E::AccessIndex { base, index } => E::AccessIndex { base: m(base), index: *index },
            E::Splat { size, value } => E::Splat { size: *size, value: m(value) },
            E::Swizzle { size, vector, pattern } => E::Swizzle { size: *size, vector: m(vector), pattern: *pattern },
            E::FunctionArgument(i) => {
                let arg = self.push(E::FunctionArgument(*i), span);
                if self.entry.is_some() {
                    let ty = self.old.arguments[*i as usize].ty;
                    return self.convert(arg, ty, true, span);
                }
                return Ok(arg);
            }
            E::GlobalVariable(g) => E::GlobalVariable(*g),
            E::LocalVariable(l) => E::LocalVariable(*l),
            E::Load { pointer } => {
                let load = self.push(E::Load { pointer: m(pointer) }, span);
                if self.boundary_pointer(*pointer) {
                    let ty = self.old_ty(h);
                    return self.convert(load, ty, true, span);
                }
                return Ok(load);
            }
            E::ImageSample {
                image,
                sampler,
                gather,
                coordinate,
                array_index,
                offset,
                level,
                depth_ref,
                clamp_to_edge,
            } => {
                let coordinate = self.down(*coordinate, span)?;
                let level = match level {
                    SampleLevel::Exact(l) => SampleLevel::Exact(self.down(*l, span)?),
                    SampleLevel::Bias(l) => SampleLevel::Bias(self.down(*l, span)?),
                    SampleLevel::Gradient { x, y } => {
                        SampleLevel::Gradient { x: self.down(*x, span)?, y: self.down(*y, span)? }
                    }
                    other => *other,
                };
                let depth_ref = depth_ref.map(|d| self.down(d, span)).transpose()?;
                let sample = self.push(
                    E::ImageSample {
                        image: self.m(*image),
                        sampler: self.m(*sampler),
                        gather: *gather,
                        coordinate,
                        array_index: array_index.map(|a| self.m(a)),
                        offset: offset.map(|o| self.m(o)),
                        level,
                        depth_ref,
                        clamp_to_edge: *clamp_to_edge,
                    },
                    span,
                );
                let ty = self.old_ty(h);
                return self.convert(sample, ty, true, span);
            }
            E::ImageLoad { image, coordinate, array_index, sample, level } => {
                let load = self.push(
                    E::ImageLoad {
                        image: m(image),
                        coordinate: m(coordinate),
                        array_index: array_index.as_ref().map(m),
                        sample: sample.as_ref().map(m),
                        level: level.as_ref().map(m),
                    },
                    span,
                );
                let ty = self.old_ty(h);
                return self.convert(load, ty, true, span);
            }
            E::ImageQuery { image, query } => {
                let query = match query {
                    naga::ImageQuery::Size { level } => naga::ImageQuery::Size { level: level.as_ref().map(m) },
                    other => *other,
                };
                E::ImageQuery { image: m(image), query }
            }
            E::Unary { op, expr } => E::Unary { op: *op, expr: m(expr) },
            E::Binary { op, left, right } => E::Binary { op: *op, left: m(left), right: m(right) },
            E::Select { condition, accept, reject } => {
                E::Select { condition: m(condition), accept: m(accept), reject: m(reject) }
            }
            E::Derivative { axis, ctrl, expr } => {
                let narrow = self.down(*expr, span)?;
                let d = self.push(E::Derivative { axis: *axis, ctrl: *ctrl, expr: narrow }, span);
                let ty = self.old_ty(h);
                return self.convert(d, ty, true, span);
            }
            E::Relational { fun, argument } => E::Relational { fun: *fun, argument: m(argument) },
            E::Math { fun, arg, arg1, arg2, arg3 } => {
                return self.math(h, *fun, [Some(*arg), *arg1, *arg2, *arg3], span);
            }
            E::As { expr, kind, convert } => return self.cast(h, *expr, *kind, *convert, span),
            E::CallResult(f) => {
                E::CallResult(*self.w.fmap.get(f).ok_or("a call to a function defined after its caller")?)
            }
            E::ArrayLength(a) => E::ArrayLength(m(a)),
            other => return Err(format!("the f64 evaluation does not support the expression {other:?}")),
        };
        Ok(self.push(new, span))
    }

    fn math(&mut self, h: Handle<E>, fun: Mf, args: [Option<Handle<E>>; 4], span: Span) -> Result<Handle<E>, String> {
        let arg = args[0].ok_or("a math function without an argument")?;
        let float_arg = self.is_f32_value(arg);
        if float_arg && fun == Mf::Frexp {
            return self.frexp(h, arg, span);
        }
        if float_arg && let Some(name) = routine_of(fun) {
            let routine = *self.w.routines.get(name).ok_or("a routine the pre-scan missed")?;
            let operands: Vec<Handle<E>> = args.iter().flatten().map(|a| self.m(*a)).collect();
            let ty = self.old_ty(arg);
            return match self.w.new.types[ty].inner {
                TypeInner::Scalar(_) => Ok(self.call(routine, operands, span)),
                TypeInner::Vector { size, .. } => {
                    let mut lanes = Vec::new();
                    for i in 0..size as u32 {
                        let lane_args: Vec<_> =
                            operands.iter().map(|o| self.push(E::AccessIndex { base: *o, index: i }, span)).collect();
                        lanes.push(self.call(routine, lane_args, span));
                    }
                    let vty = self.w.insert(TypeInner::Vector { size, scalar: Scalar::F64 });
                    Ok(self.push(E::Compose { ty: vty, components: lanes }, span))
                }
                ref other => Err(format!("{fun:?} of a {other:?}")),
            };
        }
        let factor = match fun {
            Mf::Radians => Some(std::f64::consts::PI / 180.0),
            Mf::Degrees => Some(180.0 / std::f64::consts::PI),
            _ => None,
        };
        if let Some(k) = factor {
            let k = self.push(E::Literal(Literal::F64(k)), span);
            return Ok(self.push(E::Binary { op: BinaryOperator::Multiply, left: self.m(arg), right: k }, span));
        }
        let packs = matches!(
            fun,
            Mf::Pack4x8snorm
                | Mf::Pack4x8unorm
                | Mf::Pack2x16snorm
                | Mf::Pack2x16unorm
                | Mf::Pack2x16float
                | Mf::QuantizeToF16
        );
        let mut new_args = [None; 4];
        for (slot, a) in new_args.iter_mut().zip(args) {
            *slot = match a {
                Some(a) if packs => Some(self.down(a, span)?),
                Some(a) => Some(self.m(a)),
                None => None,
            };
        }
        if float_arg {
            // Their result type is naga's predeclared struct, registered for f64 here.
            let size = match self.w.old.types[self.old_ty(arg)].inner {
                TypeInner::Vector { size, .. } => Some(size),
                _ => None,
            };
            if fun == Mf::Modf {
                self.w.new.generate_predeclared_type(naga::PredeclaredType::ModfResult { size, scalar: Scalar::F64 });
            }
        }
        let r = self.push(
            E::Math { fun, arg: new_args[0].unwrap_or(arg), arg1: new_args[1], arg2: new_args[2], arg3: new_args[3] },
            span,
        );
        let unpacks = matches!(
            fun,
            Mf::Unpack4x8snorm | Mf::Unpack4x8unorm | Mf::Unpack2x16snorm | Mf::Unpack2x16unorm | Mf::Unpack2x16float
        ) || fun == Mf::QuantizeToF16;
        if unpacks {
            let ty = self.old_ty(h);
            return self.convert(r, ty, true, span);
        }
        Ok(r)
    }

    /// frexp through the library's `gdsky_f64_frexp`, per component, into the widened result
    /// struct `{ fract, exp }`.
    fn frexp(&mut self, h: Handle<E>, arg: Handle<E>, span: Span) -> Result<Handle<E>, String> {
        let routine = *self.w.routines.get("gdsky_f64_frexp").ok_or("a routine the pre-scan missed")?;
        let x = self.m(arg);
        let ty = self.old_ty(arg);
        let size = match self.w.new.types[ty].inner {
            TypeInner::Vector { size, .. } => Some(size),
            _ => None,
        };
        let lanes = size.map_or(1, |s| s as u32);
        let (mut fracts, mut exps) = (Vec::new(), Vec::new());
        for i in 0..lanes {
            let lane = if size.is_some() { self.push(E::AccessIndex { base: x, index: i }, span) } else { x };
            let r = self.call(routine, vec![lane], span);
            fracts.push(self.push(E::AccessIndex { base: r, index: 0 }, span));
            let e = self.push(E::AccessIndex { base: r, index: 1 }, span);
            exps.push(self.push(E::As { expr: e, kind: ScalarKind::Sint, convert: Some(4) }, span));
        }
        let (fract, exp) = match size {
            Some(size) => {
                let fty = self.w.insert(TypeInner::Vector { size, scalar: Scalar::F64 });
                let ity = self.w.insert(TypeInner::Vector { size, scalar: Scalar::I32 });
                (
                    self.push(E::Compose { ty: fty, components: fracts }, span),
                    self.push(E::Compose { ty: ity, components: exps }, span),
                )
            }
            None => (fracts[0], exps[0]),
        };
        let old_struct = self.old_ty(h);
        let ty = self.w.wide(old_struct)?;
        Ok(self.push(E::Compose { ty, components: vec![fract, exp] }, span))
    }

    fn call(&mut self, function: Handle<naga::Function>, arguments: Vec<Handle<E>>, span: Span) -> Handle<E> {
        let result = self.push(E::CallResult(function), span);
        self.calls.insert(result, Statement::Call { function, arguments, result: Some(result) });
        result
    }

    fn cast(
        &mut self,
        h: Handle<E>,
        expr: Handle<E>,
        kind: ScalarKind,
        convert: Option<u8>,
        span: Span,
    ) -> Result<Handle<E>, String> {
        let source_float = self.is_f32_value(expr);
        match (kind, convert) {
            (ScalarKind::Float, Some(_)) => Ok(self.push(E::As { expr: self.m(expr), kind, convert: Some(8) }, span)),
            (ScalarKind::Float, None) => {
                // A float made from bits: the lowering keeps some constants as u32 bits in a
                // local (see `builder::runtime_scalar`); a recorded one comes back as its f64.
                if let Some(v) = self.runtime_constant(expr) {
                    return Ok(self.push(E::Literal(Literal::F64(v)), span));
                }
                let bits = self.push(E::As { expr: self.m(expr), kind, convert: None }, span);
                let ty = self.old_ty(h);
                self.convert(bits, ty, true, span)
            }
            (_, None) if source_float => {
                let narrow = self.down(expr, span)?;
                Ok(self.push(E::As { expr: narrow, kind, convert: None }, span))
            }
            _ => Ok(self.push(E::As { expr: self.m(expr), kind, convert }, span)),
        }
    }

    /// The recorded f64 of a scalar bitcast from a local initialised with u32 bits.
    fn runtime_constant(&self, expr: Handle<E>) -> Option<f64> {
        let E::Load { pointer } = self.old.expressions[expr] else { return None };
        let E::LocalVariable(l) = self.old.expressions[pointer] else { return None };
        let init = self.old.local_variables[l].init?;
        let E::Literal(Literal::U32(bits)) = self.old.expressions[init] else { return None };
        let v = f32::from_bits(bits);
        v.is_finite().then(|| self.w.exact.get(&bits).copied().flatten()).flatten()
    }

    fn block(&mut self, old: &Block) -> Result<Block, String> {
        let mut out = Block::with_capacity(old.len());
        for (s, span) in old.span_iter() {
            self.statement(s, *span, &mut out)?;
        }
        Ok(out)
    }

    /// Emits the new expressions `start..end`: emittable runs as `Emit`, call results by their
    /// calls, pre-emitted ones not at all.
    fn emit(&mut self, start: usize, end: usize, out: &mut Block) {
        let mut run: Option<(usize, usize)> = None;
        let handles = &self.handles;
        let flush = |run: &mut Option<(usize, usize)>, out: &mut Block| {
            if let Some((a, b)) = run.take() {
                out.push(Statement::Emit(Range::new_from_bounds(handles[a], handles[b])), Span::UNDEFINED);
            }
        };
        for (i, &h) in handles.iter().enumerate().take(end).skip(start) {
            if let Some(call) = self.calls.remove(&h) {
                flush(&mut run, out);
                out.push(call, Span::UNDEFINED);
            } else if self.exprs[h].needs_pre_emit() {
                flush(&mut run, out);
            } else {
                run = Some(match run {
                    Some((a, _)) => (a, i),
                    None => (i, i),
                });
            }
        }
        flush(&mut run, out);
    }

    fn statement(&mut self, s: &Statement, span: Span, out: &mut Block) -> Result<(), String> {
        let m = |h: &Handle<E>| self.map[h.index()];
        let new = match s {
            Statement::Emit(range) => {
                let mut handles = range.clone();
                if let Some(first) = handles.next() {
                    let last = handles.last().unwrap_or(first);
                    let (start, end) = (self.created[first.index()].0, self.created[last.index()].1);
                    self.emit(start, end, out);
                }
                return Ok(());
            }
            Statement::Block(b) => Statement::Block(self.block(b)?),
            Statement::If { condition, accept, reject } => {
                let (accept, reject) = (self.block(accept)?, self.block(reject)?);
                Statement::If { condition: self.m(*condition), accept, reject }
            }
            Statement::Switch { selector, cases } => {
                let mut new_cases = Vec::with_capacity(cases.len());
                for c in cases {
                    new_cases.push(naga::SwitchCase {
                        value: c.value,
                        body: self.block(&c.body)?,
                        fall_through: c.fall_through,
                    });
                }
                Statement::Switch { selector: self.m(*selector), cases: new_cases }
            }
            Statement::Loop { body, continuing, break_if } => {
                let (body, continuing) = (self.block(body)?, self.block(continuing)?);
                Statement::Loop { body, continuing, break_if: break_if.map(|h| self.m(h)) }
            }
            Statement::Break => Statement::Break,
            Statement::Continue => Statement::Continue,
            Statement::Kill => Statement::Kill,
            Statement::ControlBarrier(b) => Statement::ControlBarrier(*b),
            Statement::MemoryBarrier(b) => Statement::MemoryBarrier(*b),
            Statement::Return { value } => {
                let value = match (value, self.entry) {
                    (Some(v), Some(output)) => {
                        let start = self.exprs.len();
                        let ty = self.old.result.as_ref().ok_or("an entry point returns a value but has no result")?.ty;
                        let nv = self.output(m(v), ty, output, span)?;
                        let end = self.exprs.len();
                        self.emit(start, end, out);
                        Some(nv)
                    }
                    (v, _) => v.as_ref().map(m),
                };
                Statement::Return { value }
            }
            Statement::Store { pointer, value } => {
                if self.boundary_pointer(*pointer) {
                    return Err("the f64 evaluation does not support stores to storage buffers".into());
                }
                Statement::Store { pointer: m(pointer), value: m(value) }
            }
            Statement::Call { function, arguments, result } => Statement::Call {
                function: *self.w.fmap.get(function).ok_or("a call to a function defined after its caller")?,
                arguments: arguments.iter().map(m).collect(),
                result: result.as_ref().map(m),
            },
            other => return Err(format!("the f64 evaluation does not support the statement {other:?}")),
        };
        out.push(new, span);
        Ok(())
    }

    /// An entry point's return value (new, f64) as its f32 result.
    fn output(&mut self, v: Handle<E>, ty: Handle<Type>, output: F64Output, span: Span) -> Result<Handle<E>, String> {
        let nearest = self.convert(v, ty, false, span)?;
        if output == F64Output::Nearest {
            return Ok(nearest);
        }
        match self.w.new.types[ty].inner {
            TypeInner::Scalar(_) | TypeInner::Vector { .. } => {}
            ref other => return Err(format!("a residual output of type {other:?}")),
        }
        let back = self.convert(nearest, ty, true, span)?;
        let diff = self.push(E::Binary { op: BinaryOperator::Subtract, left: v, right: back }, span);
        self.convert(diff, ty, false, span)
    }
}

//! # Tracing NaN and Inf to the source
//!
//! [`instrument`] rewrites a validated module (the one [`crate::lower`] gives, unchanged:
//! the snapshots and every other caller see the same module) into one that also records, per
//! pixel, the **first** expression in execution order whose value was not finite, as a small
//! integer: the id of a *site* in a table that comes with the module ([`Site`]: file, line,
//! column, source snippet, what the expression computes, the function it is in).
//!
//! **Where the sites come from.** The lowering already gives every naga expression the span of
//! the shader text it came from (validation errors use it), and the span survives the
//! optimizing passes (naga's compaction keeps spans), so no side table is needed: a site's
//! location is the front end's source map applied to the expression's span
//! ([`gdshader::FrontendOutput::locate`]), which goes through `#include`s and gives a macro's
//! invocation for code a macro expanded. Code the sky wrapper adds has no span and is not
//! instrumented: it is not the user's, and a non-finite COLOR is caught where the shader
//! computed it.
//!
//! **Which expressions.** Only those that can make a non-finite value out of finite operands:
//! float `+ − * / %` (overflow, 0/0, x/0), every float math function except those that cannot
//! (`abs`, `min`, `max`, `clamp`, `saturate`, `floor`, `ceil`, `round`, `trunc`, `fract`,
//! `sign`, `sin`, `cos`, `tanh`, `atan`, `atan2`, `step`), derivatives, and bit casts to float
//! (`intBitsToFloat`, and the run-time form the lowering gives a non-finite constant such as
//! `1.0 / 0.0`, reported at that constant). Loads, selects, swizzles, negation and composition
//! only pass a value on, so a non-finite value reaching them was already caught where it was
//! made; leaving them out keeps the module small and changes no answer. A value that enters
//! non-finite (a uniform set to `inf`, a texel) is reported at the first instrumented
//! expression that computes with it and gives a non-finite result. Scalars and vectors are
//! tested; a matrix result (`m * m`) is not (sky shaders rarely make one; its columns are caught
//! when they are used).
//!
//! **The test** is a bit test, `(bitcast<u32>(x) & 0x7f800000) == 0x7f800000` (all exponent
//! bits set: an infinity or a NaN), `any(…)` for a vector. Not naga's `isnan`/`isinf`: WGSL has
//! no such built-ins, so naga's WGSL writer cannot write them, and a driver compiling with fast
//! math may assume they are false; integer operations are kept as written.
//!
//! **The register** is one private `u32` global, zero at the start of each invocation, shared
//! by every function, so a helper called from many places records its site only when nothing
//! earlier did. After each `Emit` statement that computes a site, in handle order (the order
//! naga evaluates an `Emit`'s expressions), the register becomes
//! `select(old, id, old == 0 && nonfinite(x))`: a load, a few comparisons and a store, no
//! branch. The statements go after the `Emit`, before anything that could use the value
//! (a call, a store, a branch), so the first site recorded is the first executed.
//!
//! **The output.** Each fragment entry point returns `vec4(rgb, f32(site))`: the colour as
//! before, the site id as the alpha (exact for ids below 2²⁴). The sub-passes
//! (`render_pass` 1 and 2, which the full pass reads as HALF_RES_COLOR/QUARTER_RES_COLOR) keep
//! their alpha, so the full pass computes what it computes without the trace; a non-finite value
//! made in a sub-pass is reported where the full pass first computes with it. The full pass's
//! alpha is otherwise always 0 (Godot's), so nothing is lost there; a cubemap face's alpha (which
//! Godot keeps) is replaced too, so a host renders the instrumented module only for the ids and
//! takes the colour from the shader's own module. It reads the id from the alpha of an
//! Rgba32Float target (`gdsky render --trace-nonfinite` does).
//!
//! **Limits.** `?:` and `mix`-like selects whose operands have no side effects are lowered as
//! naga `Select`s that evaluate both operands (as a GPU does), so a NaN made in the branch not
//! taken is reported although the shader never uses it. Expressions the lowering folded into
//! constants are not run and are not sites.

mod budget;
mod report;

pub use budget::{BUDGET_LEFT, BUDGET_SPENT, loop_budget};
pub use report::{NonfiniteReport, PLACE_COLOURS, Place};

use crate::Lowered;
use crate::valid::{validation_diagnostic, validator_for};
use gdshader::parse::ast;
use gdshader::{Diagnostic, FrontendOutput};
use naga::{
    AddressSpace, BinaryOperator as Bo, Block, Expression as E, Function, GlobalVariable, Handle, Literal,
    MathFunction as Mf, MemoryDecorations, RelationalFunction, Scalar, ScalarKind, ShaderStage, Span, Statement, Type,
    TypeInner, VectorSize,
};
use std::collections::HashMap;

/// Name of the private global that holds the first site's id (0: none yet).
pub const SITE_REGISTER: &str = "gdsky_nonfinite_site";

/// The exponent bits of an f32: all set in an infinity or a NaN, and only there.
const EXPONENT_BITS: u32 = 0x7f80_0000;

/// One instrumented expression: where it is in the user's source.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Site {
    /// The id the module records (≥ 1; 0 means no site).
    pub id: u32,
    /// The file's display name (the shader, or an included file).
    pub file: String,
    /// 1-based line of the expression's first character.
    pub line: usize,
    /// 1-based column (in characters).
    pub col: usize,
    /// The expression's source text, whitespace runs collapsed to one space (a macro's
    /// invocation when a macro expanded to it).
    pub snippet: String,
    /// What it computes: `division`, `sqrt`, …
    pub kind: String,
    /// The naga function it is in (a user function's name, or an entry point's).
    pub function: String,
}

impl Site {
    /// `file:line:col`.
    pub fn location(&self) -> String {
        format!("{}:{}:{}", self.file, self.line, self.col)
    }
}

/// An instrumented module and its site table.
pub struct Traced {
    /// The module (validated), with the same bindings and material block as the one given.
    pub lowered: Lowered,
    /// The sites, `sites[i].id == i + 1`.
    pub sites: Vec<Site>,
}

impl Traced {
    /// The site an id read back from the alpha channel names (`None` for 0, or a value that is
    /// no site's id).
    pub fn site_of_alpha(&self, alpha: f32) -> Option<&Site> {
        if !(alpha >= 1.0 && alpha.fract() == 0.0) {
            return None;
        }
        self.sites.get(alpha as usize - 1)
    }
}

/// The instrumented form of `lowered` (lowered from `front`); see the module's essay. An error
/// is a module naga rejects (a bug in gdsky), as a diagnostic.
pub fn instrument(front: &FrontendOutput, lowered: &Lowered) -> Result<Traced, Vec<Diagnostic>> {
    let mut module = lowered.module.clone();
    let u32_ty = module.types.insert(Type { name: None, inner: TypeInner::Scalar(Scalar::U32) }, Span::UNDEFINED);
    let zero = module.global_expressions.append(E::Literal(Literal::U32(0)), Span::UNDEFINED);
    let register = module.global_variables.append(
        GlobalVariable {
            name: Some(SITE_REGISTER.into()),
            space: AddressSpace::Private,
            binding: None,
            ty: u32_ty,
            init: Some(zero),
            memory_decorations: MemoryDecorations::empty(),
        },
        Span::UNDEFINED,
    );
    let pass = render_pass(&module);

    let mut raw_sites: Vec<(String, &'static str, Span)> = Vec::new();
    let handles: Vec<_> = module.functions.iter().map(|(h, _)| h).collect();
    for h in handles {
        let candidates = candidates(&module.functions[h], &module.types, &lowered.info[h]);
        let name = module.functions[h].name.clone().unwrap_or_default();
        instrument_function(&mut module.functions[h], register, &candidates, &name, &mut raw_sites);
    }
    for i in 0..module.entry_points.len() {
        let candidates = candidates(&module.entry_points[i].function, &module.types, lowered.info.get_entry_point(i));
        let name = module.entry_points[i].name.clone();
        let ep = &mut module.entry_points[i];
        instrument_function(&mut ep.function, register, &candidates, &name, &mut raw_sites);
        if ep.stage == ShaderStage::Fragment {
            let mut body = std::mem::take(&mut ep.function.body);
            id_in_alpha(&mut ep.function, &mut body, register, pass);
            ep.function.body = body;
        }
    }
    let info = validator_for(&module).validate(&module).map_err(|err| vec![validation_diagnostic(front, &err)])?;
    let sites = raw_sites
        .into_iter()
        .enumerate()
        .map(|(i, (function, kind, span))| site(front, i as u32 + 1, function, kind, span))
        .collect();
    let lowered = Lowered {
        module,
        info,
        uniforms: lowered.uniforms.clone(),
        material_size: lowered.material_size,
        textures: lowered.textures.clone(),
        options: lowered.options.clone(),
    };
    Ok(Traced { lowered, sites })
}

/// A site's entry in the table: its span through the source map.
fn site(front: &FrontendOutput, id: u32, function: String, kind: &'static str, span: Span) -> Site {
    let range = span.to_range().unwrap_or(0..0);
    let (file, range) = front.locate(ast::Span::new(range.start, range.end));
    let (line, col) = front.db.line_col(file, range.start);
    let text = front.db.text(file);
    let snippet = text.get(range).unwrap_or("").split_whitespace().collect::<Vec<_>>().join(" ");
    Site { id, file: front.db.name(file).to_string(), line, col, snippet, kind: kind.to_string(), function }
}

/// The expressions to test, each with what it computes and its vector size (`None`: a scalar).
type Candidates = HashMap<Handle<E>, (&'static str, Option<VectorSize>)>;

/// The expressions of `f` to test, from the validator's types of the module before this pass.
fn candidates(f: &Function, types: &naga::UniqueArena<Type>, info: &naga::valid::FunctionInfo) -> Candidates {
    let mut out = HashMap::new();
    for (h, e) in f.expressions.iter() {
        if !f.expressions.get_span(h).is_defined() {
            continue;
        }
        let size = match *info[h].ty.inner_with(types) {
            TypeInner::Scalar(s) if s.kind == ScalarKind::Float => None,
            TypeInner::Vector { scalar: s, size } if s.kind == ScalarKind::Float => Some(size),
            _ => continue,
        };
        if let Some(kind) = creates_nonfinite(e) {
            out.insert(h, (kind, size));
        }
    }
    out
}

/// What `e` computes, when it can make a non-finite value out of finite operands (the caller
/// has checked that its result is a float).
fn creates_nonfinite(e: &E) -> Option<&'static str> {
    match e {
        E::Binary { op, .. } => match op {
            Bo::Add => Some("addition"),
            Bo::Subtract => Some("subtraction"),
            Bo::Multiply => Some("multiplication"),
            Bo::Divide => Some("division"),
            Bo::Modulo => Some("remainder"),
            _ => None,
        },
        E::Math { fun, .. } => match fun {
            Mf::Abs
            | Mf::Min
            | Mf::Max
            | Mf::Clamp
            | Mf::Saturate
            | Mf::Floor
            | Mf::Ceil
            | Mf::Round
            | Mf::Trunc
            | Mf::Fract
            | Mf::Sign
            | Mf::Sin
            | Mf::Cos
            | Mf::Tanh
            | Mf::Atan
            | Mf::Atan2
            | Mf::Step => None,
            other => Some(math_name(*other)),
        },
        E::Derivative { .. } => Some("derivative"),
        E::As { kind: ScalarKind::Float, convert: None, .. } => Some("bit cast to float"),
        _ => None,
    }
}

/// The GLSL-ish name of a math function, for the report.
fn math_name(fun: Mf) -> &'static str {
    match fun {
        Mf::Exp => "exp",
        Mf::Exp2 => "exp2",
        Mf::Log => "log",
        Mf::Log2 => "log2",
        Mf::Pow => "pow",
        Mf::Sqrt => "sqrt",
        Mf::InverseSqrt => "inversesqrt",
        Mf::Tan => "tan",
        Mf::Asin => "asin",
        Mf::Acos => "acos",
        Mf::Sinh => "sinh",
        Mf::Cosh => "cosh",
        Mf::Asinh => "asinh",
        Mf::Acosh => "acosh",
        Mf::Atanh => "atanh",
        Mf::Radians => "radians",
        Mf::Degrees => "degrees",
        Mf::Dot => "dot",
        Mf::Cross => "cross",
        Mf::Length => "length",
        Mf::Distance => "distance",
        Mf::Normalize => "normalize",
        Mf::FaceForward => "faceforward",
        Mf::Reflect => "reflect",
        Mf::Refract => "refract",
        Mf::Mix => "mix",
        Mf::SmoothStep => "smoothstep",
        Mf::Fma => "fma",
        Mf::Ldexp => "ldexp",
        Mf::Determinant => "determinant",
        Mf::Inverse => "inverse",
        _ => "math function",
    }
}

/// Adds the tests of `candidates` after the `Emit`s that compute them, numbering the sites in
/// the order met (appended to `sites`).
fn instrument_function(
    f: &mut Function,
    register: Handle<GlobalVariable>,
    candidates: &Candidates,
    name: &str,
    sites: &mut Vec<(String, &'static str, Span)>,
) {
    if candidates.is_empty() {
        return;
    }
    let mut body = std::mem::take(&mut f.body);
    let mut cx = Cx { f, register, candidates, name, sites, pointer: None, mask: None };
    cx.block(&mut body);
    cx.f.body = body;
}

struct Cx<'a> {
    f: &'a mut Function,
    register: Handle<GlobalVariable>,
    candidates: &'a Candidates,
    name: &'a str,
    sites: &'a mut Vec<(String, &'static str, Span)>,
    /// The register's pointer expression (made once per function: it needs no `Emit`).
    pointer: Option<Handle<E>>,
    /// The exponent mask literal, once per function.
    mask: Option<Handle<E>>,
}

impl Cx<'_> {
    fn block(&mut self, block: &mut Block) {
        let old = std::mem::take(block);
        for (mut stmt, span) in old.span_into_iter() {
            match &mut stmt {
                Statement::Block(b) => self.block(b),
                Statement::If { accept, reject, .. } => {
                    self.block(accept);
                    self.block(reject);
                }
                Statement::Switch { cases, .. } => {
                    for c in cases {
                        self.block(&mut c.body);
                    }
                }
                Statement::Loop { body, continuing, .. } => {
                    self.block(body);
                    self.block(continuing);
                }
                _ => {}
            }
            let emitted = match &stmt {
                Statement::Emit(range) => range.clone().filter(|h| self.candidates.contains_key(h)).collect(),
                _ => Vec::new(),
            };
            block.push(stmt, span);
            for h in emitted {
                self.test(block, h);
            }
        }
    }

    /// Appends to `block` the statements that record `value`'s site if it is the first
    /// non-finite value.
    fn test(&mut self, block: &mut Block, value: Handle<E>) {
        let sp = Span::UNDEFINED;
        let (kind, size) = self.candidates[&value];
        let span = self.f.expressions.get_span(value);
        self.sites.push((self.name.to_string(), kind, span));
        let id = self.sites.len() as u32;
        let ex = &mut self.f.expressions;
        // Expressions naga evaluates at function entry (literals, globals) are never in an
        // `Emit`; they come first, the emitted ones after, as one range.
        let pointer = *self.pointer.get_or_insert_with(|| ex.append(E::GlobalVariable(self.register), sp));
        let mask = *self.mask.get_or_insert_with(|| ex.append(E::Literal(Literal::U32(EXPONENT_BITS)), sp));
        let zero = ex.append(E::Literal(Literal::U32(0)), sp);
        let id_lit = ex.append(E::Literal(Literal::U32(id)), sp);
        let start = ex.len();
        let bits = ex.append(E::As { expr: value, kind: ScalarKind::Uint, convert: None }, sp);
        let mask = match size {
            Some(size) => ex.append(E::Splat { size, value: mask }, sp),
            None => mask,
        };
        let exponent = ex.append(E::Binary { op: Bo::And, left: bits, right: mask }, sp);
        let all_set = ex.append(E::Binary { op: Bo::Equal, left: exponent, right: mask }, sp);
        let nonfinite = match size {
            Some(_) => ex.append(E::Relational { fun: RelationalFunction::Any, argument: all_set }, sp),
            None => all_set,
        };
        let old = ex.append(E::Load { pointer }, sp);
        let fresh = ex.append(E::Binary { op: Bo::Equal, left: old, right: zero }, sp);
        let hit = ex.append(E::Binary { op: Bo::LogicalAnd, left: fresh, right: nonfinite }, sp);
        let new = ex.append(E::Select { condition: hit, accept: id_lit, reject: old }, sp);
        block.push(Statement::Emit(ex.range_from(start)), sp);
        block.push(Statement::Store { pointer, value: new }, sp);
    }
}

/// The built-ins uniform (group 0, binding 0, `sky_builtins`) and the index of its
/// `render_pass` member: what tells a fragment entry point's sub-passes from its full pass.
pub(crate) fn render_pass(module: &naga::Module) -> Option<(Handle<GlobalVariable>, u32)> {
    let builtins = module.global_variables.iter().find_map(|(h, g)| {
        (g.space == AddressSpace::Uniform
            && g.binding.as_ref().is_some_and(|b| b.group == 0 && b.binding == 0)
            && g.name.as_deref() == Some("sky_builtins"))
        .then_some(h)
    });
    let member = crate::lower::wrapper::BUILTIN_FIELDS.iter().position(|f| *f == "render_pass").map(|i| i as u32);
    builtins.zip(member)
}

/// What [`rewrite_returns`] calls for each `return v`: given the function, the block the
/// return is in, `v` and the result type, it appends what it needs and gives the new value.
pub(crate) type ReturnRewrite<'a> = dyn FnMut(&mut Function, &mut Block, Handle<E>, Handle<Type>) -> Handle<E> + 'a;

/// Replaces the value of each `return v` in `block` (nested blocks included) by what `rewrite`
/// appends to the block just before the return: how the instrumented modules put what they
/// record into a fragment entry point's output.
pub(crate) fn rewrite_returns(f: &mut Function, block: &mut Block, rewrite: &mut ReturnRewrite<'_>) {
    let old = std::mem::take(block);
    for (mut stmt, span) in old.span_into_iter() {
        match &mut stmt {
            Statement::Block(b) => rewrite_returns(f, b, rewrite),
            Statement::If { accept, reject, .. } => {
                rewrite_returns(f, accept, rewrite);
                rewrite_returns(f, reject, rewrite);
            }
            Statement::Switch { cases, .. } => {
                for c in cases {
                    rewrite_returns(f, &mut c.body, rewrite);
                }
            }
            Statement::Loop { body, continuing, .. } => {
                rewrite_returns(f, body, rewrite);
                rewrite_returns(f, continuing, rewrite);
            }
            Statement::Return { value: Some(v) } => {
                if let Some(ty) = f.result.as_ref().map(|r| r.ty) {
                    *v = rewrite(f, block, *v, ty);
                }
            }
            _ => {}
        }
        block.push(stmt, span);
    }
}

/// The expressions that tell the sub-passes from the full pass: the built-ins uniform, its
/// `render_pass` member's index, and the half and quarter pass numbers. Made by [`PassRefs::new`]
/// before an `Emit` range starts (globals and literals are never emitted).
#[derive(Clone, Copy)]
pub(crate) struct PassRefs {
    globals: Handle<E>,
    member: u32,
    half: Handle<E>,
    quarter: Handle<E>,
}

impl PassRefs {
    /// Appends the uniform's and the literals' expressions to `ex`.
    pub(crate) fn new(ex: &mut naga::Arena<E>, (globals, member): (Handle<GlobalVariable>, u32)) -> Self {
        let sp = Span::UNDEFINED;
        PassRefs {
            globals: ex.append(E::GlobalVariable(globals), sp),
            member,
            half: ex.append(E::Literal(Literal::U32(crate::lower::wrapper::PASS_HALF)), sp),
            quarter: ex.append(E::Literal(Literal::U32(crate::lower::wrapper::PASS_QUARTER)), sp),
        }
    }

    /// The `render_pass` member's value (an expression to emit).
    pub(crate) fn render_pass(&self, ex: &mut naga::Arena<E>) -> Handle<E> {
        let field = ex.append(E::AccessIndex { base: self.globals, index: self.member }, Span::UNDEFINED);
        ex.append(E::Load { pointer: field }, Span::UNDEFINED)
    }
}

/// Appends to the expressions `vec4(out.rgb, a)` where `a` is `recorded` in the full pass and
/// `out`'s own alpha in the sub-passes (without `pass`, `recorded` always). Every expression it
/// appends is to be emitted: the caller emits the range.
pub(crate) fn with_alpha(
    ex: &mut naga::Arena<E>,
    out: Handle<E>,
    ty: Handle<Type>,
    recorded: Handle<E>,
    pass: Option<PassRefs>,
) -> Handle<E> {
    let sp = Span::UNDEFINED;
    let alpha = ex.append(E::AccessIndex { base: out, index: 3 }, sp);
    let alpha = match pass {
        Some(p) => {
            let value = p.render_pass(ex);
            let is_half = ex.append(E::Binary { op: Bo::Equal, left: value, right: p.half }, sp);
            let is_quarter = ex.append(E::Binary { op: Bo::Equal, left: value, right: p.quarter }, sp);
            let sub = ex.append(E::Binary { op: Bo::LogicalOr, left: is_half, right: is_quarter }, sp);
            ex.append(E::Select { condition: sub, accept: alpha, reject: recorded }, sp)
        }
        None => recorded,
    };
    let rgb: Vec<_> = (0..3).map(|index| ex.append(E::AccessIndex { base: out, index }, sp)).collect();
    ex.append(E::Compose { ty, components: [rgb, vec![alpha]].concat() }, sp)
}

/// Makes each `return v` of a fragment entry point return `vec4(v.rgb, f32(site))`, except in
/// the sub-passes (`pass`: the built-ins uniform and its `render_pass` member), which keep
/// `v`'s alpha.
fn id_in_alpha(
    f: &mut Function,
    block: &mut Block,
    register: Handle<GlobalVariable>,
    pass: Option<(Handle<GlobalVariable>, u32)>,
) {
    rewrite_returns(f, block, &mut |f, block, out, ty| {
        let sp = Span::UNDEFINED;
        let ex = &mut f.expressions;
        let pointer = ex.append(E::GlobalVariable(register), sp);
        let refs = pass.map(|p| PassRefs::new(ex, p));
        let start = ex.len();
        let site = ex.append(E::Load { pointer }, sp);
        let id = ex.append(E::As { expr: site, kind: ScalarKind::Float, convert: Some(4) }, sp);
        let composed = with_alpha(ex, out, ty, id, refs);
        block.push(Statement::Emit(ex.range_from(start)), sp);
        composed
    });
}

#[cfg(test)]
mod tests;

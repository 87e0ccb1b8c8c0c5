//! Built-in function calls: Godot's (GLSL's) functions as naga math, relational and conversion
//! expressions, with the semantics GLSL gives them where naga's differ.

use super::builder::FnBuilder;
use super::expr::FnCtx;
use super::{span, vector_size};
use gdshader::check::types::{Scalar as GdScalar, Type as GdType};
use gdshader::parse::ast::{self, Expr};
use naga::{
    BinaryOperator as Bo, DerivativeAxis, DerivativeControl, Expression as E, Handle, MathFunction as Mf,
    RelationalFunction, ScalarKind, Statement, UnaryOperator,
};

type H = Handle<E>;

/// Lowers a call of a built-in function (arguments already type-checked by the checker).
pub(super) fn builtin(
    ctx: &mut FnCtx,
    b: &mut FnBuilder,
    e: &Expr,
    callee: &ast::Ident,
    args: &[Expr],
    types: &[GdType],
) -> Option<H> {
    let sp = span(e.span);
    let name = callee.name.as_str();
    if name.starts_with("texture") || name == "texelFetch" {
        return texture_call(ctx, b, e, name, args, types);
    }
    // Functions with an `out` argument take the place, not its value.
    match name {
        "modf" | "frexp" => return out_struct_call(ctx, b, e, name, args),
        "umulExtended" | "imulExtended" => return mul_extended(ctx, b, e, name, args, types),
        "uaddCarry" | "usubBorrow" => {
            // sum = x + y, carry = sum < x; diff = x - y, borrow = x < y (as 0u or 1u).
            let (x, y) = (ctx.value(b, &args[0])?, ctx.value(b, &args[1])?);
            let add = name == "uaddCarry";
            let result = b.expr(E::Binary { op: if add { Bo::Add } else { Bo::Subtract }, left: x, right: y }, sp);
            let flag = if add {
                b.expr(E::Binary { op: Bo::Less, left: result, right: x }, sp)
            } else {
                b.expr(E::Binary { op: Bo::Less, left: x, right: y }, sp)
            };
            let flag = ctx.convert(
                b,
                flag,
                &GdType::vector_of(GdScalar::Bool, types[0].components().unwrap_or(1)),
                GdScalar::UInt,
                e.span,
            );
            let Some(super::expr::Val::Pointer(ptr)) = ctx.lower(b, &args[2]) else {
                return ctx.unsupported(e, &format!("`{name}` with this output argument"));
            };
            b.stmt(Statement::Store { pointer: ptr, value: flag }, sp);
            return Some(result);
        }
        "ldexp" => {
            let x = ctx.value(b, &args[0])?;
            let ex = ctx.value(b, &args[1])?;
            return Some(math(b, Mf::Ldexp, &[x, ex], sp));
        }
        _ => {}
    }
    let v: Vec<H> = args.iter().map(|a| ctx.value(b, a)).collect::<Option<_>>()?;
    let shape = types
        .iter()
        .filter_map(|t| match t {
            GdType::Vector(_, n) => Some(*n),
            _ => None,
        })
        .max();
    // Scalars among vector arguments are splatted: naga wants one type for all of them.
    let splat = |b: &mut FnBuilder, h: H, t: &GdType| match (t, shape) {
        (GdType::Scalar(_), Some(n)) => b.expr(E::Splat { size: vector_size(n), value: h }, sp),
        _ => h,
    };
    let is_float = types.first().and_then(GdType::scalar) == Some(GdScalar::Float);
    // naga's geometric functions take vectors; GLSL's also take floats.
    if matches!(types.first(), Some(GdType::Scalar(_))) {
        match name {
            "length" => return Some(math(b, Mf::Abs, &v, sp)),
            "normalize" => return Some(math(b, Mf::Sign, &v, sp)),
            "distance" => {
                let d = b.expr(E::Binary { op: Bo::Subtract, left: v[0], right: v[1] }, sp);
                return Some(math(b, Mf::Abs, &[d], sp));
            }
            _ => {}
        }
    }
    let unary_math = |fun| -> Option<Mf> { Some(fun) };
    let one = match name {
        "radians" => unary_math(Mf::Radians),
        "degrees" => unary_math(Mf::Degrees),
        "sin" => unary_math(Mf::Sin),
        "cos" => unary_math(Mf::Cos),
        "tan" => unary_math(Mf::Tan),
        "asin" => unary_math(Mf::Asin),
        "acos" => unary_math(Mf::Acos),
        "atan" if args.len() == 1 => unary_math(Mf::Atan),
        "sinh" => unary_math(Mf::Sinh),
        "cosh" => unary_math(Mf::Cosh),
        "tanh" => unary_math(Mf::Tanh),
        "asinh" => unary_math(Mf::Asinh),
        "acosh" => unary_math(Mf::Acosh),
        "atanh" => unary_math(Mf::Atanh),
        "exp" => unary_math(Mf::Exp),
        "log" => unary_math(Mf::Log),
        "exp2" => unary_math(Mf::Exp2),
        "log2" => unary_math(Mf::Log2),
        "sqrt" => unary_math(Mf::Sqrt),
        "inversesqrt" => unary_math(Mf::InverseSqrt),
        "abs" => unary_math(Mf::Abs),
        "sign" => unary_math(Mf::Sign),
        "floor" => unary_math(Mf::Floor),
        "round" | "roundEven" => unary_math(Mf::Round),
        "trunc" => unary_math(Mf::Trunc),
        "ceil" => unary_math(Mf::Ceil),
        "fract" => unary_math(Mf::Fract),
        "length" => unary_math(Mf::Length),
        "normalize" => unary_math(Mf::Normalize),
        "transpose" => unary_math(Mf::Transpose),
        "determinant" => unary_math(Mf::Determinant),
        "bitCount" => unary_math(Mf::CountOneBits),
        "bitfieldReverse" => unary_math(Mf::ReverseBits),
        "findLSB" => unary_math(Mf::FirstTrailingBit),
        "findMSB" => unary_math(Mf::FirstLeadingBit),
        "packHalf2x16" => unary_math(Mf::Pack2x16float),
        "unpackHalf2x16" => unary_math(Mf::Unpack2x16float),
        "packUnorm2x16" => unary_math(Mf::Pack2x16unorm),
        "unpackUnorm2x16" => unary_math(Mf::Unpack2x16unorm),
        "packSnorm2x16" => unary_math(Mf::Pack2x16snorm),
        "unpackSnorm2x16" => unary_math(Mf::Unpack2x16snorm),
        "packUnorm4x8" => unary_math(Mf::Pack4x8unorm),
        "unpackUnorm4x8" => unary_math(Mf::Unpack4x8unorm),
        "packSnorm4x8" => unary_math(Mf::Pack4x8snorm),
        "unpackSnorm4x8" => unary_math(Mf::Unpack4x8snorm),
        _ => None,
    };
    if let Some(fun) = one {
        return Some(math(b, fun, &v, sp));
    }
    let h = match name {
        "atan" => math(b, Mf::Atan2, &v, sp),
        "pow" => math(b, Mf::Pow, &v, sp),
        "distance" => math(b, Mf::Distance, &v, sp),
        "dot" if matches!(types[0], GdType::Scalar(_)) => {
            b.expr(E::Binary { op: Bo::Multiply, left: v[0], right: v[1] }, sp)
        }
        "dot" => math(b, Mf::Dot, &v, sp),
        "cross" => math(b, Mf::Cross, &v, sp),
        "reflect" => math(b, Mf::Reflect, &v, sp),
        "refract" => math(b, Mf::Refract, &v, sp),
        "faceforward" => math(b, Mf::FaceForward, &v, sp),
        "outerProduct" => {
            // WGSL has no outer product: column j is c * r[j].
            let (GdType::Vector(_, n), Some(th)) =
                (&types[0], ctx.naga_type(&GdType::Matrix(types[0].components().unwrap_or(2)), e.span))
            else {
                return None;
            };
            let columns = (0..*n)
                .map(|j| {
                    let rj = b.expr(E::AccessIndex { base: v[1], index: u32::from(j) }, sp);
                    b.expr(E::Binary { op: Bo::Multiply, left: v[0], right: rj }, sp)
                })
                .collect();
            b.expr(E::Compose { ty: th, components: columns }, sp)
        }
        "inverse" => {
            let GdType::Matrix(n) = types[0] else {
                return None;
            };
            let th = ctx.naga_type(&types[0], e.span)?;
            let col_ty = ctx.naga_type(&GdType::Vector(GdScalar::Float, n), e.span)?;
            inverse(b, v[0], n, th, col_ty, sp)
        }
        "matrixCompMult" => {
            let (GdType::Matrix(n), Some(th)) = (&types[0], ctx.naga_type(&types[0], e.span)) else {
                return None;
            };
            let columns = (0..*n)
                .map(|c| {
                    let (l, r) = (
                        b.expr(E::AccessIndex { base: v[0], index: u32::from(c) }, sp),
                        b.expr(E::AccessIndex { base: v[1], index: u32::from(c) }, sp),
                    );
                    b.expr(E::Binary { op: Bo::Multiply, left: l, right: r }, sp)
                })
                .collect();
            b.expr(E::Compose { ty: th, components: columns }, sp)
        }
        "fma" => math(b, Mf::Fma, &v, sp),
        "step" => {
            let (edge, x) = (splat(b, v[0], &types[0]), v[1]);
            math(b, Mf::Step, &[edge, x], sp)
        }
        "smoothstep" => {
            let (lo, hi) = (splat(b, v[0], &types[0]), splat(b, v[1], &types[1]));
            math(b, Mf::SmoothStep, &[lo, hi, v[2]], sp)
        }
        "mix" if types[2].scalar() == Some(GdScalar::Bool) => {
            b.expr(E::Select { condition: v[2], accept: v[1], reject: v[0] }, sp)
        }
        "mix" => math(b, Mf::Mix, &v, sp),
        "mod" => {
            // GLSL's mod is floored: x - y * floor(x / y). naga's Modulo truncates.
            let y = splat(b, v[1], &types[1]);
            let q = b.expr(E::Binary { op: Bo::Divide, left: v[0], right: y }, sp);
            let f = math(b, Mf::Floor, &[q], sp);
            let m = b.expr(E::Binary { op: Bo::Multiply, left: y, right: f }, sp);
            b.expr(E::Binary { op: Bo::Subtract, left: v[0], right: m }, sp)
        }
        "min" | "max" => {
            let (x, y) = (v[0], splat(b, v[1], &types[1]));
            let fun = if name == "min" { Mf::Min } else { Mf::Max };
            if is_float { max_num(b, fun, x, y, shape, sp) } else { math(b, fun, &[x, y], sp) }
        }
        "clamp" => {
            let (x, lo, hi) = (v[0], splat(b, v[1], &types[1]), splat(b, v[2], &types[2]));
            if is_float {
                let m = max_num(b, Mf::Max, x, lo, shape, sp);
                max_num(b, Mf::Min, m, hi, shape, sp)
            } else {
                math(b, Mf::Clamp, &[x, lo, hi], sp)
            }
        }
        "isnan" => float_class(b, v[0], shape, Class::Nan, sp),
        "isinf" => float_class(b, v[0], shape, Class::Inf, sp),
        "any" => b.expr(E::Relational { fun: RelationalFunction::Any, argument: v[0] }, sp),
        "all" => b.expr(E::Relational { fun: RelationalFunction::All, argument: v[0] }, sp),
        "not" => b.expr(E::Unary { op: UnaryOperator::LogicalNot, expr: v[0] }, sp),
        "lessThan" => b.expr(E::Binary { op: Bo::Less, left: v[0], right: v[1] }, sp),
        "lessThanEqual" => b.expr(E::Binary { op: Bo::LessEqual, left: v[0], right: v[1] }, sp),
        "greaterThan" => b.expr(E::Binary { op: Bo::Greater, left: v[0], right: v[1] }, sp),
        "greaterThanEqual" => b.expr(E::Binary { op: Bo::GreaterEqual, left: v[0], right: v[1] }, sp),
        "equal" => b.expr(E::Binary { op: Bo::Equal, left: v[0], right: v[1] }, sp),
        "notEqual" => b.expr(E::Binary { op: Bo::NotEqual, left: v[0], right: v[1] }, sp),
        "floatBitsToInt" => b.expr(E::As { expr: v[0], kind: ScalarKind::Sint, convert: None }, sp),
        "floatBitsToUint" => b.expr(E::As { expr: v[0], kind: ScalarKind::Uint, convert: None }, sp),
        "intBitsToFloat" | "uintBitsToFloat" => {
            b.expr(E::As { expr: v[0], kind: ScalarKind::Float, convert: None }, sp)
        }
        "bitfieldExtract" => {
            let (o, c) = (to_u32(ctx, b, v[1], args[1].span), to_u32(ctx, b, v[2], args[2].span));
            math(b, Mf::ExtractBits, &[v[0], o, c], sp)
        }
        "bitfieldInsert" => {
            let (o, c) = (to_u32(ctx, b, v[2], args[2].span), to_u32(ctx, b, v[3], args[3].span));
            math(b, Mf::InsertBits, &[v[0], v[1], o, c], sp)
        }
        "dFdx" | "dFdy" | "fwidth" | "dFdxCoarse" | "dFdyCoarse" | "fwidthCoarse" | "dFdxFine" | "dFdyFine"
        | "fwidthFine" => {
            let axis = match &name[..2] {
                "dF" if name.as_bytes()[3] == b'x' => DerivativeAxis::X,
                "dF" => DerivativeAxis::Y,
                _ => DerivativeAxis::Width,
            };
            let ctrl = if name.ends_with("Coarse") {
                DerivativeControl::Coarse
            } else if name.ends_with("Fine") {
                DerivativeControl::Fine
            } else {
                DerivativeControl::None
            };
            b.expr(E::Derivative { axis, ctrl, expr: v[0] }, sp)
        }
        _ => return ctx.unsupported(e, &format!("the built-in function `{name}`")),
    };
    Some(h)
}

fn math(b: &mut FnBuilder, fun: Mf, args: &[H], sp: naga::Span) -> H {
    b.expr(
        E::Math {
            fun,
            arg: args[0],
            arg1: args.get(1).copied(),
            arg2: args.get(2).copied(),
            arg3: args.get(3).copied(),
        },
        sp,
    )
}

/// `min`/`max` with IEEE maxNum semantics: a NaN operand yields the other one. GLSL leaves this
/// undefined and SPIR-V's FMax too; Godot's drivers, and gdsky's reference, return the other.
///
/// When one operand is a constant that is not NaN (a literal, a folded constant, a baked
/// uniform), maxNum is one comparison and one select: `max(x, c)` is `x > c ? x : c` (a NaN `x`
/// compares false and yields `c`), `min(x, c)` is `x < c ? x : c`. This is the cheaper NaN-proof
/// form the clean-up of issue #11 asks for (`get_optical_depth_at_point`'s `max(0.0, …)` runs
/// ~240 times per pixel); lavapipe's LLVM reads the pattern as one `maxps`.
///
/// The same holds for any operand known not to be NaN, and the result of that form is itself
/// never NaN (it is `v` only where `v` compared true, else the operand that is not NaN): so
/// `clamp(x, 0.5, u)` for a uniform `u` is two comparisons and two selects, the `min` taking
/// the `max`'s result as its operand that is not NaN, instead of two bit tests around `min`.
fn max_num(b: &mut FnBuilder, fun: Mf, x: H, y: H, n: Option<u8>, sp: naga::Span) -> H {
    let constant = if b.is_not_nan(y) {
        Some((x, y))
    } else if b.is_not_nan(x) {
        Some((y, x))
    } else {
        None
    };
    if let Some((v, c)) = constant {
        let op = if fun == Mf::Max { Bo::Greater } else { Bo::Less };
        let keep = b.expr(E::Binary { op, left: v, right: c }, sp);
        let h = b.expr(E::Select { condition: keep, accept: v, reject: c }, sp);
        b.mark_not_nan(h);
        return h;
    }
    let m = math(b, fun, &[x, y], sp);
    let x_nan = float_class(b, x, n, Class::Nan, sp);
    let m = b.expr(E::Select { condition: x_nan, accept: y, reject: m }, sp);
    let y_nan = float_class(b, y, n, Class::Nan, sp);
    b.expr(E::Select { condition: y_nan, accept: x, reject: m }, sp)
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Class {
    Nan,
    Inf,
}

/// `isnan` / `isinf` from the bits (WGSL has neither, and a compiler that assumes finite math
/// may fold `x != x` away): |bits| > 0x7f800000 is NaN, == 0x7f800000 is infinity.
fn float_class(b: &mut FnBuilder, x: H, n: Option<u8>, class: Class, sp: naga::Span) -> H {
    let bits = b.expr(E::As { expr: x, kind: ScalarKind::Uint, convert: None }, sp);
    let mut mask = b.expr(E::Literal(naga::Literal::U32(0x7fff_ffff)), sp);
    let mut inf = b.expr(E::Literal(naga::Literal::U32(0x7f80_0000)), sp);
    if let Some(n) = n {
        mask = b.expr(E::Splat { size: vector_size(n), value: mask }, sp);
        inf = b.expr(E::Splat { size: vector_size(n), value: inf }, sp);
    }
    let magnitude = b.expr(E::Binary { op: Bo::And, left: bits, right: mask }, sp);
    let op = if class == Class::Nan { Bo::Greater } else { Bo::Equal };
    b.expr(E::Binary { op, left: magnitude, right: inf }, sp)
}

fn to_u32(ctx: &mut FnCtx, b: &mut FnBuilder, v: H, at: ast::Span) -> H {
    ctx.convert(b, v, &GdType::INT, GdScalar::UInt, at)
}

/// `modf(x, out i)` and `frexp(x, out e)`: naga returns a struct of both results.
fn out_struct_call(ctx: &mut FnCtx, b: &mut FnBuilder, e: &Expr, name: &str, args: &[Expr]) -> Option<H> {
    let sp = span(e.span);
    let x = ctx.value(b, &args[0])?;
    let fun = if name == "modf" { Mf::Modf } else { Mf::Frexp };
    // naga types the result with a predeclared struct the module must hold.
    let size = match ctx.type_of(&args[0]) {
        Some(GdType::Vector(_, n)) => Some(vector_size(n)),
        _ => None,
    };
    let scalar = naga::Scalar::F32;
    let predeclared = if name == "modf" {
        naga::PredeclaredType::ModfResult { size, scalar }
    } else {
        naga::PredeclaredType::FrexpResult { size, scalar }
    };
    ctx.lw.module.generate_predeclared_type(predeclared);
    let both = math(b, fun, &[x], sp);
    let first = b.expr(E::AccessIndex { base: both, index: 0 }, sp);
    let second = b.expr(E::AccessIndex { base: both, index: 1 }, sp);
    let Some(super::expr::Val::Pointer(ptr)) = ctx.lower(b, &args[1]) else {
        return ctx.unsupported(e, &format!("`{name}` with this output argument"));
    };
    b.stmt(Statement::Store { pointer: ptr, value: second }, sp);
    Some(first)
}

/// Texture functions on a sampler uniform: `texture`, `textureLod`, `textureGrad`,
/// `textureProj`, `textureProjLod`, `textureGather`, `texelFetch`, `textureSize`,
/// `textureQueryLevels`.
fn texture_call(
    ctx: &mut FnCtx,
    b: &mut FnBuilder,
    e: &Expr,
    name: &str,
    args: &[Expr],
    types: &[GdType],
) -> Option<H> {
    use gdshader::check::types::SamplerKind as K;
    let sp = span(e.span);
    let Some((image, sampler, kind, scalar)) = ctx.sampler(b, &args[0]) else {
        return ctx.unsupported(e, &format!("`{name}` on this sampler (a dynamically indexed sampler array)"));
    };
    let rest: Vec<H> = args[1..].iter().map(|a| ctx.value(b, a)).collect::<Option<_>>()?;
    let arrayed = matches!(kind, K::Tex2DArray | K::CubeArray);
    // GLSL puts an array layer in the last coordinate; naga takes it apart.
    let split = |b: &mut FnBuilder, coord: H, n: u8| -> (H, Option<H>) {
        if !arrayed {
            return (coord, None);
        }
        let xy = b.head(coord, n - 1, sp);
        let layer = b.expr(E::AccessIndex { base: coord, index: u32::from(n - 1) }, sp);
        (xy, Some(layer))
    };
    let coord_width = types.get(1).and_then(GdType::components).unwrap_or(2);
    let sample = |b: &mut FnBuilder, coord: H, level: naga::SampleLevel, gather: Option<naga::SwizzleComponent>| {
        let (coordinate, layer) = split(b, coord, coord_width);
        let array_index = layer.map(|l| {
            let r = math(b, Mf::Round, &[l], sp);
            b.expr(E::As { expr: r, kind: ScalarKind::Sint, convert: Some(4) }, sp)
        });
        b.expr(
            E::ImageSample {
                image,
                sampler,
                gather,
                coordinate,
                array_index,
                offset: None,
                level,
                depth_ref: None,
                clamp_to_edge: false,
            },
            sp,
        )
    };
    let float_only = |ctx: &mut FnCtx| -> Option<()> {
        if scalar == GdScalar::Float {
            Some(())
        } else {
            ctx.unsupported(e, &format!("`{name}` on an integer sampler (WGSL samples only float textures)"))
        }
    };
    let projected = |b: &mut FnBuilder, p: H, width: u8| {
        // textureProj divides the coordinate by its last component.
        let last = b.expr(E::AccessIndex { base: p, index: u32::from(width - 1) }, sp);
        let n = if matches!(kind, K::Tex3D) { 3 } else { 2 };
        let head = b.head(p, n, sp);
        let last = b.expr(E::Splat { size: vector_size(n), value: last }, sp);
        b.expr(E::Binary { op: Bo::Divide, left: head, right: last }, sp)
    };
    let h = match name {
        "texture" => {
            float_only(ctx)?;
            let level = rest.get(1).map_or(naga::SampleLevel::Auto, |bias| naga::SampleLevel::Bias(*bias));
            sample(b, rest[0], level, None)
        }
        "textureLod" => {
            float_only(ctx)?;
            sample(b, rest[0], naga::SampleLevel::Exact(rest[1]), None)
        }
        "textureGrad" => {
            float_only(ctx)?;
            sample(b, rest[0], naga::SampleLevel::Gradient { x: rest[1], y: rest[2] }, None)
        }
        "textureProj" | "textureProjLod" => {
            float_only(ctx)?;
            let coord = projected(b, rest[0], coord_width);
            let level = match (name, rest.get(1)) {
                ("textureProjLod", Some(l)) => naga::SampleLevel::Exact(*l),
                (_, Some(bias)) => naga::SampleLevel::Bias(*bias),
                _ => naga::SampleLevel::Auto,
            };
            b.expr(
                E::ImageSample {
                    image,
                    sampler,
                    gather: None,
                    coordinate: coord,
                    array_index: None,
                    offset: None,
                    level,
                    depth_ref: None,
                    clamp_to_edge: false,
                },
                sp,
            )
        }
        "textureGather" => {
            float_only(ctx)?;
            let component = match args.get(2).map(|a| &a.kind) {
                None => naga::SwizzleComponent::X,
                Some(ast::ExprKind::IntLit(c)) => [
                    naga::SwizzleComponent::X,
                    naga::SwizzleComponent::Y,
                    naga::SwizzleComponent::Z,
                    naga::SwizzleComponent::W,
                ][(*c as usize).min(3)],
                Some(_) => {
                    return ctx.unsupported(e, "`textureGather` with a component that is not a literal");
                }
            };
            sample(b, rest[0], naga::SampleLevel::Zero, Some(component))
        }
        "texelFetch" => {
            let (coordinate, array_index) = split(b, rest[0], coord_width);
            b.expr(E::ImageLoad { image, coordinate, array_index, sample: None, level: Some(rest[1]) }, sp)
        }
        "textureSize" => {
            let size = b.expr(E::ImageQuery { image, query: naga::ImageQuery::Size { level: Some(rest[0]) } }, sp);
            let size = if arrayed {
                let layers = b.expr(E::ImageQuery { image, query: naga::ImageQuery::NumLayers }, sp);
                let ret = ctx.naga_type(&GdType::Vector(GdScalar::UInt, 3), e.span)?;
                let x = b.expr(E::AccessIndex { base: size, index: 0 }, sp);
                let y = b.expr(E::AccessIndex { base: size, index: 1 }, sp);
                b.expr(E::Compose { ty: ret, components: vec![x, y, layers] }, sp)
            } else {
                size
            };
            b.expr(E::As { expr: size, kind: ScalarKind::Sint, convert: Some(4) }, sp)
        }
        "textureQueryLod" => {
            // naga has no LOD query: compute it as GLSL defines it for an isotropic footprint,
            // λ = log2(ρ) with ρ the larger screen-space derivative of the texel coordinate;
            // returns (λ clamped to the mip chain, λ).
            float_only(ctx)?;
            let size = b.expr(E::ImageQuery { image, query: naga::ImageQuery::Size { level: None } }, sp);
            let size = b.expr(E::As { expr: size, kind: ScalarKind::Float, convert: Some(4) }, sp);
            let texel = b.expr(E::Binary { op: Bo::Multiply, left: rest[0], right: size }, sp);
            let dx = b.expr(E::Derivative { axis: DerivativeAxis::X, ctrl: DerivativeControl::None, expr: texel }, sp);
            let dy = b.expr(E::Derivative { axis: DerivativeAxis::Y, ctrl: DerivativeControl::None, expr: texel }, sp);
            let (dxx, dyy) = (math(b, Mf::Dot, &[dx, dx], sp), math(b, Mf::Dot, &[dy, dy], sp));
            let rho2 = math(b, Mf::Max, &[dxx, dyy], sp);
            let l2 = math(b, Mf::Log2, &[rho2], sp);
            let half = b.expr(E::Literal(naga::Literal::F32(0.5)), sp);
            let lambda = b.expr(E::Binary { op: Bo::Multiply, left: l2, right: half }, sp);
            let levels = b.expr(E::ImageQuery { image, query: naga::ImageQuery::NumLevels }, sp);
            let levels = b.expr(E::As { expr: levels, kind: ScalarKind::Float, convert: Some(4) }, sp);
            let one = b.expr(E::Literal(naga::Literal::F32(1.0)), sp);
            let top = b.expr(E::Binary { op: Bo::Subtract, left: levels, right: one }, sp);
            let zero = b.expr(E::Literal(naga::Literal::F32(0.0)), sp);
            let clamped = math(b, Mf::Clamp, &[lambda, zero, top], sp);
            let ret = ctx.naga_type(&GdType::Vector(GdScalar::Float, 2), e.span)?;
            b.expr(E::Compose { ty: ret, components: vec![clamped, lambda] }, sp)
        }
        "textureQueryLevels" => {
            let levels = b.expr(E::ImageQuery { image, query: naga::ImageQuery::NumLevels }, sp);
            b.expr(E::As { expr: levels, kind: ScalarKind::Sint, convert: Some(4) }, sp)
        }
        _ => return ctx.unsupported(e, &format!("the built-in function `{name}`")),
    };
    Some(h)
}

/// `inverse(m)` by the adjugate: WGSL has no matrix inverse. Element (row r, column c) of the
/// inverse is the cofactor C(c, r) over the determinant.
fn inverse(
    b: &mut FnBuilder,
    m: H,
    n: u8,
    mat_ty: Handle<naga::Type>,
    col_ty: Handle<naga::Type>,
    sp: naga::Span,
) -> H {
    let n = usize::from(n);
    let cols: Vec<H> = (0..n).map(|c| b.expr(E::AccessIndex { base: m, index: c as u32 }, sp)).collect();
    // at[r][c]: row r, column c.
    let at: Vec<Vec<H>> = (0..n)
        .map(|r| cols.iter().map(|&col| b.expr(E::AccessIndex { base: col, index: r as u32 }, sp)).collect())
        .collect();
    fn det(b: &mut FnBuilder, at: &[Vec<H>], rows: &[usize], cols: &[usize], sp: naga::Span) -> H {
        if rows.len() == 1 {
            return at[rows[0]][cols[0]];
        }
        let mut sum: Option<H> = None;
        for (i, &c) in cols.iter().enumerate() {
            let rest: Vec<usize> = cols.iter().copied().filter(|&x| x != c).collect();
            let minor = det(b, at, &rows[1..], &rest, sp);
            let term = b.expr(E::Binary { op: Bo::Multiply, left: at[rows[0]][c], right: minor }, sp);
            sum = Some(match sum {
                None => term,
                Some(acc) => b.expr(
                    E::Binary { op: if i % 2 == 0 { Bo::Add } else { Bo::Subtract }, left: acc, right: term },
                    sp,
                ),
            });
        }
        sum.unwrap_or(at[rows[0]][cols[0]])
    }
    let all: Vec<usize> = (0..n).collect();
    let cofactor = |b: &mut FnBuilder, r: usize, c: usize| {
        let rows: Vec<usize> = all.iter().copied().filter(|&x| x != r).collect();
        let cs: Vec<usize> = all.iter().copied().filter(|&x| x != c).collect();
        let d = det(b, &at, &rows, &cs, sp);
        if (r + c).is_multiple_of(2) { d } else { b.expr(E::Unary { op: UnaryOperator::Negate, expr: d }, sp) }
    };
    let first_row: Vec<H> = (0..n).map(|c| cofactor(b, 0, c)).collect();
    let mut d: Option<H> = None;
    for (c, &cf) in first_row.iter().enumerate() {
        let term = b.expr(E::Binary { op: Bo::Multiply, left: at[0][c], right: cf }, sp);
        d = Some(match d {
            None => term,
            Some(acc) => b.expr(E::Binary { op: Bo::Add, left: acc, right: term }, sp),
        });
    }
    let one = b.expr(E::Literal(naga::Literal::F32(1.0)), sp);
    let inv_det = b.expr(E::Binary { op: Bo::Divide, left: one, right: d.unwrap_or(one) }, sp);
    // Column c of the inverse holds rows r: C(c, r) / det.
    let columns = (0..n)
        .map(|c| {
            let comps = (0..n)
                .map(|r| {
                    let cf = if c == 0 { first_row[r] } else { cofactor(b, c, r) };
                    b.expr(E::Binary { op: Bo::Multiply, left: cf, right: inv_det }, sp)
                })
                .collect();
            b.expr(E::Compose { ty: col_ty, components: comps }, sp)
        })
        .collect();
    b.expr(E::Compose { ty: mat_ty, components: columns }, sp)
}

/// `umulExtended(x, y, out msb, out lsb)` / `imulExtended`: the 64-bit product in two halves,
/// from 16-bit partial products (WGSL has no widening multiply).
fn mul_extended(
    ctx: &mut FnCtx,
    b: &mut FnBuilder,
    e: &Expr,
    name: &str,
    args: &[Expr],
    types: &[GdType],
) -> Option<H> {
    let sp = span(e.span);
    let n = match types[0] {
        GdType::Vector(_, n) => Some(n),
        _ => None,
    };
    let lit = |b: &mut FnBuilder, v: u32| {
        let l = b.expr(E::Literal(naga::Literal::U32(v)), sp);
        match n {
            Some(n) => b.expr(E::Splat { size: vector_size(n), value: l }, sp),
            None => l,
        }
    };
    let signed = name == "imulExtended";
    let (x, y) = (ctx.value(b, &args[0])?, ctx.value(b, &args[1])?);
    let as_u = |b: &mut FnBuilder, h: H| {
        if signed { b.expr(E::As { expr: h, kind: ScalarKind::Uint, convert: None }, sp) } else { h }
    };
    let (xu, yu) = (as_u(b, x), as_u(b, y));
    let bin = |b: &mut FnBuilder, op, l, r| b.expr(E::Binary { op, left: l, right: r }, sp);
    let (mask, sixteen) = (lit(b, 0xffff), lit(b, 16));
    let (x0, x1) = (bin(b, Bo::And, xu, mask), bin(b, Bo::ShiftRight, xu, sixteen));
    let (y0, y1) = (bin(b, Bo::And, yu, mask), bin(b, Bo::ShiftRight, yu, sixteen));
    let p00 = bin(b, Bo::Multiply, x0, y0);
    let p01 = bin(b, Bo::Multiply, x0, y1);
    let p10 = bin(b, Bo::Multiply, x1, y0);
    let p11 = bin(b, Bo::Multiply, x1, y1);
    let p00h = bin(b, Bo::ShiftRight, p00, sixteen);
    let (p01l, p10l) = (bin(b, Bo::And, p01, mask), bin(b, Bo::And, p10, mask));
    let mid = bin(b, Bo::Add, p00h, p01l);
    let mid = bin(b, Bo::Add, mid, p10l);
    let (p01h, p10h, midh) = (
        bin(b, Bo::ShiftRight, p01, sixteen),
        bin(b, Bo::ShiftRight, p10, sixteen),
        bin(b, Bo::ShiftRight, mid, sixteen),
    );
    let hi = bin(b, Bo::Add, p11, p01h);
    let hi = bin(b, Bo::Add, hi, p10h);
    let mut hi = bin(b, Bo::Add, hi, midh);
    let lo = bin(b, Bo::Multiply, xu, yu);
    if signed {
        // Two's complement: subtract y when x < 0 and x when y < 0 from the high half.
        let zero_i = b.expr(E::Literal(naga::Literal::I32(0)), sp);
        let zero_i = match n {
            Some(n) => b.expr(E::Splat { size: vector_size(n), value: zero_i }, sp),
            None => zero_i,
        };
        let zero_u = lit(b, 0);
        let x_neg = bin(b, Bo::Less, x, zero_i);
        let y_neg = bin(b, Bo::Less, y, zero_i);
        let sub_y = b.expr(E::Select { condition: x_neg, accept: yu, reject: zero_u }, sp);
        let sub_x = b.expr(E::Select { condition: y_neg, accept: xu, reject: zero_u }, sp);
        hi = bin(b, Bo::Subtract, hi, sub_y);
        hi = bin(b, Bo::Subtract, hi, sub_x);
    }
    let back = |b: &mut FnBuilder, h: H| {
        if signed { b.expr(E::As { expr: h, kind: ScalarKind::Sint, convert: None }, sp) } else { h }
    };
    let (hi, lo) = (back(b, hi), back(b, lo));
    for (arg, value) in [(&args[2], hi), (&args[3], lo)] {
        let Some(super::expr::Val::Pointer(ptr)) = ctx.lower(b, arg) else {
            return ctx.unsupported(e, &format!("`{name}` with this output argument"));
        };
        b.stmt(Statement::Store { pointer: ptr, value }, sp);
    }
    Some(b.expr(E::Literal(naga::Literal::Bool(false)), sp))
}

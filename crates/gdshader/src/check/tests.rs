//! What the checker records about valid code: types (including the int literals Godot converts),
//! constant values, and the uniforms' view.

use crate::parse::ast::{Expr, ExprKind, ItemKind, Stmt, StmtKind};
use crate::{CheckedShader, Loader, check_source};
use std::path::Path;

struct NoIncludes;

impl Loader for NoIncludes {
    fn load(&mut self, path: &Path) -> std::io::Result<Vec<u8>> {
        Err(std::io::Error::new(std::io::ErrorKind::NotFound, path.display().to_string()))
    }
}

fn checked(src: &str) -> (CheckedShader, String) {
    let text = format!("shader_type sky;\n{src}");
    let out = check_source("test.gdshader", text.clone().into_bytes(), None, &mut NoIncludes);
    let rendered = crate::diag::render_human(&out.db, &out.diagnostics, false);
    let shader = out.shader.unwrap_or_else(|| panic!("rejected:\n{rendered}"));
    (shader, text)
}

fn walk_expr<'a>(e: &'a Expr, out: &mut Vec<&'a Expr>) {
    out.push(e);
    match &e.kind {
        ExprKind::Call { args, .. } | ExprKind::InitList(args) | ExprKind::ArrayCtor { args, .. } => {
            args.iter().for_each(|a| walk_expr(a, out))
        }
        ExprKind::Member { base, .. } => walk_expr(base, out),
        ExprKind::MethodCall { base, args, .. } => {
            walk_expr(base, out);
            args.iter().for_each(|a| walk_expr(a, out));
        }
        ExprKind::Index { base, index } => {
            walk_expr(base, out);
            walk_expr(index, out);
        }
        ExprKind::Unary { operand, .. } => walk_expr(operand, out),
        ExprKind::IncDec { target, .. } => walk_expr(target, out),
        ExprKind::Binary { lhs, rhs, .. } => {
            walk_expr(lhs, out);
            walk_expr(rhs, out);
        }
        ExprKind::Assign { target, value, .. } => {
            walk_expr(target, out);
            walk_expr(value, out);
        }
        ExprKind::Ternary { cond, then, otherwise } => {
            [cond, then, otherwise].into_iter().for_each(|x| walk_expr(x, out))
        }
        _ => {}
    }
}

fn walk_stmt<'a>(s: &'a Stmt, out: &mut Vec<&'a Expr>) {
    match &s.kind {
        StmtKind::Block(b) => b.stmts.iter().for_each(|s| walk_stmt(s, out)),
        StmtKind::VarDecl(d) => d.declarators.iter().filter_map(|d| d.init.as_ref()).for_each(|e| walk_expr(e, out)),
        StmtKind::Expr(e) | StmtKind::Return(Some(e)) => walk_expr(e, out),
        _ => {}
    }
}

/// The type the checker gave to the `nth` expression whose text is `needle`.
fn type_of(shader: &CheckedShader, text: &str, needle: &str, nth: usize) -> String {
    let mut exprs = Vec::new();
    for item in &shader.ast.items {
        if let ItemKind::Function(f) = &item.kind {
            f.body.stmts.iter().for_each(|s| walk_stmt(s, &mut exprs));
        }
    }
    let e = exprs
        .into_iter()
        .filter(|e| &text[e.span.range()] == needle)
        .nth(nth)
        .unwrap_or_else(|| panic!("no expression `{needle}`"));
    let names = shader.struct_names();
    shader.expr_types[e.id.0 as usize].as_ref().map_or("<none>".to_string(), |t| t.display(&names).to_string())
}

#[test]
fn int_literals_take_the_type_godot_converts_them_to() {
    let (s, text) = checked(
        "float half_of(float x) { return x * 0.5; }\n\
         void sky() { float x = 2.0; float p = pow(x, 2); vec3 up = vec3(0, 0, 1); float h = half_of(3); COLOR = up * p * h; }",
    );
    assert_eq!(type_of(&s, &text, "2", 0), "float");
    assert_eq!(type_of(&s, &text, "1", 0), "float");
    assert_eq!(type_of(&s, &text, "3", 0), "float");
    assert_eq!(type_of(&s, &text, "pow(x, 2)", 0), "float");
}

#[test]
fn builtin_overloads_are_tried_in_godot_order() {
    // The float overload comes first, so a literal argument picks it; a variable picks its own.
    let (s, text) = checked(
        "void sky() { int i = 3; float a = abs(-3); int b = abs(i); uint u = 2u; uint c = bitCount(u); COLOR = vec3(a); }",
    );
    assert_eq!(type_of(&s, &text, "abs(-3)", 0), "float");
    assert_eq!(type_of(&s, &text, "abs(i)", 0), "int");
    assert_eq!(type_of(&s, &text, "bitCount(u)", 0), "uint");
}

#[test]
fn constants_fold_into_array_sizes_and_lengths() {
    let (s, text) = checked(
        "const int N = 3 * 4 + 1;\nvoid sky() { float a[N]; int n = a.length(); float b[] = {1.0, 2.0}; COLOR = vec3(float(n + b.length())); }",
    );
    assert_eq!(type_of(&s, &text, "a.length()", 0), "int");
    assert_eq!(type_of(&s, &text, "{1.0, 2.0}", 0), "float[2]");
    let (s, text) = checked("void sky() { const int M = (7 << 2) % 5; float c[M + 1]; COLOR = vec3(c[0]); }");
    // (7 << 2) % 5 = 28 % 5 = 3.
    assert_eq!(type_of(&s, &text, "c", 0), "float[4]");
}

#[test]
fn swizzles_increments_and_array_returns_have_their_types() {
    let (s, text) = checked(
        "vec3[2] pair() { return {vec3(1.0), vec3(2.0)}; }\n\
         int bump(int x) { return x + 1; }\n\
         void sky() { vec4 v = vec4(1.0); vec2 a = v.zy; v.g *= 2.0; int seed = 1; int k = bump(seed++); vec3 p[2] = pair(); COLOR = p[1] + vec3(a, float(k)); }",
    );
    assert_eq!(type_of(&s, &text, "v.zy", 0), "vec2");
    assert_eq!(type_of(&s, &text, "seed++", 0), "int");
    assert_eq!(type_of(&s, &text, "{vec3(1.0), vec3(2.0)}", 0), "vec3[2]");
    assert_eq!(type_of(&s, &text, "pair()", 0), "vec3[2]");
    assert_eq!(type_of(&s, &text, "v.g *= 2.0", 0), "float");
}

#[test]
fn builtins_used_are_recorded() {
    let (s, _) = checked("float t() { return TIME; }\nvoid sky() { COLOR = EYEDIR * t() + LIGHT0_DIRECTION; }");
    let used: Vec<&str> = s.builtins_used.iter().copied().collect();
    assert_eq!(used, ["COLOR", "EYEDIR", "LIGHT0_DIRECTION", "TIME"]);
}

/// The codes of the errors the front end reports for `src` (after `shader_type sky;`).
fn error_codes(src: &str) -> Vec<&'static str> {
    let text = format!("shader_type sky;\n{src}");
    let out = check_source("test.gdshader", text.into_bytes(), None, &mut NoIncludes);
    out.diagnostics.iter().filter(|d| d.is_error()).map(|d| d.code).collect()
}

#[test]
fn negated_literals_converted_for_a_call_are_typed_down_to_the_literal() {
    // The lowering emits the literal with the recorded type: `-3` given to abs(float) must be a
    // float 3 negated, not an int.
    let (s, text) = checked("void sky() { float a = abs(-3); vec3 v = vec3(-1, 2, +3); COLOR = v * a; }");
    assert_eq!(type_of(&s, &text, "-3", 0), "float");
    assert_eq!(type_of(&s, &text, "3", 0), "float");
    assert_eq!(type_of(&s, &text, "-1", 0), "float");
    assert_eq!(type_of(&s, &text, "1", 0), "float");
    assert_eq!(type_of(&s, &text, "3", 1), "float");
}

#[test]
fn constants_convert_where_godot_converts_them() {
    // A constructor of constants is a constant node too (Godot: sin(int(1)) is sin(float)).
    let (s, text) = checked("void sky() { float a = sin(int(1)); vec2 v = vec2(1.0, int(2)); COLOR = vec3(v, a); }");
    assert_eq!(type_of(&s, &text, "sin(int(1))", 0), "float");
    // Never to bool, never a negative value to uint, never in a struct or array constructor.
    assert_eq!(error_codes("void sky() { bvec2 b = bvec2(1, 0); }"), ["E301"]);
    assert_eq!(error_codes("void sky() { uvec2 u = uvec2(-1); }"), ["E301"]);
    assert_eq!(error_codes("float f(uint x) { return 1.0; }\nvoid sky() { COLOR = vec3(f(-1)); }"), ["E301"]);
    assert_eq!(error_codes("struct S { float a; };\nvoid sky() { S s = S(1); }"), ["E301"]);
    assert_eq!(error_codes("void sky() { float a[2] = float[2](1, 2); }"), ["E300", "E300"]);
}

#[test]
fn uniform_defaults_follow_godots_reduce_and_convert() {
    let (s, _) = checked(
        "uniform float f : hint_range(0, 10) = 5;\nuniform uint u = 1;\nuniform int i = 1u;\n\
         uniform float n = -(1);\nuniform vec3 c = vec3(1, -2, 3u);\nglobal uniform float g = 1;\n\
         void sky() { COLOR = c; }",
    );
    let defaults: Vec<_> = s.uniforms.iter().map(|u| u.default_text.clone().unwrap_or_default()).collect();
    assert_eq!(defaults, ["5.0", "1u", "1", "-1.0", "vec3(1.0, -2.0, 3.0)", "1.0"]);
    // Only literals, `-` and constructors of them are folded.
    for bad in [
        "uniform float f = 1.0 + 1.0;",
        "const float K = 2.0;\nuniform float f = K;",
        "uniform vec2 v = vec2(1.0).xy;",
        "uniform int i = int(1.5);",
        "uniform bool b = bool(1);",
    ] {
        assert_eq!(error_codes(bad), ["E306"], "{bad}");
    }
    // And converted only between scalars, int to uint only when not negative.
    for bad in [
        "uniform vec3 v = 1;",
        "uniform uint u = -1;",
        "uniform int i = 1.0;",
        "uniform bool b = 1;",
        "uniform int i = 4294967295u;",
    ] {
        assert_eq!(error_codes(bad), ["E300"], "{bad}");
    }
}

#[test]
fn operators_take_the_operands_godot_takes() {
    let ok = "void sky() { int i = 1 << 2; uint u = 1u >> 1u; ivec2 a = ivec2(1) << 2; \
              uvec2 b = uvec2(1u) << uvec2(1u); a &= 3; b |= 1u; a %= 2; ivec2 m = ivec2(1) % 2; \
              bool t = +true; mat2 p = +mat2(1.0); COLOR = vec3(0.0); }";
    checked(ok);
    for bad in [
        "int x = 1 << 2u;",
        "uint x = 1u << 2;",
        "ivec2 x = ivec2(1) << 1u;",
        "ivec3 x = ivec3(1) >> uvec3(2u);",
        "int x = 1; x <<= 2u;",
        "ivec2 x = 2 % ivec2(1);",
        "ivec2 x = ivec2(1) & 3;",
        "mat2 m = -mat2(1.0);",
        "mat2 m = mat2(1.0); m++;",
        "float a[2] = {1.0, 2.0}; bool c = a == a;",
    ] {
        assert_eq!(error_codes(&format!("void sky() {{ {bad} }}")), ["E300"], "{bad}");
    }
}

#[test]
fn names_clash_where_godots_do() {
    // A helper may reuse the name of a built-in that exists only in sky(), and any function may
    // reuse a struct's name for a local.
    checked(
        "void h() { vec3 EYEDIR = vec3(1.0); float ALPHA = EYEDIR.x; }\nstruct S { float a; };\n\
         void sky() { float S = 1.0; COLOR = vec3(S); }",
    );
    // Not in sky(), not a global built-in, and no parameter named like a uniform or a constant.
    assert_eq!(error_codes("void sky() { vec3 EYEDIR = vec3(1.0); }"), ["E201"]);
    assert_eq!(error_codes("void h() { float TIME = 1.0; }"), ["E201"]);
    assert_eq!(error_codes("uniform float u;\nvoid h(float u) { }"), ["E201"]);
    assert_eq!(error_codes("const float K = 1.0;\nvoid h(float K) { }"), ["E201"]);
    assert_eq!(error_codes("void h(float ALPHA) { }"), ["E201"]);
}

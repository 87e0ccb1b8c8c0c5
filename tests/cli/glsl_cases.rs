//! The GLSL-semantics cases (issue #10): one small sky shader per construct where WGSL or naga's
//! constant evaluator is stricter than GLSL, with the values worked out by hand. Rendered and
//! checked by tests/cli/glsl_semantics.rs; compiled by Chromium's WebGPU (Tint) by
//! tests/godot/preview.rs, which includes this file by path.

/// An expected channel.
#[derive(Clone, Copy, Debug)]
pub enum X {
    /// This float, bit for bit (so `-0.0` is not `0.0`).
    F(f32),
    /// +∞.
    Inf,
    /// −∞.
    NegInf,
    /// Any NaN.
    NaN,
}

/// An int's two channels: its high and low 16 bits.
fn int(v: i32) -> [X; 2] {
    [X::F((v >> 16) as f32), X::F((v & 0xFFFF) as f32)]
}

/// A uint's two channels.
fn uint(v: u32) -> [X; 2] {
    [X::F((v >> 16) as f32), X::F((v & 0xFFFF) as f32)]
}

/// What each shader declares before its code: the int and uint encoders.
const ENCODE: &str = "
vec3 enc(int v) { return vec3(float(v >> 16), float(v & 65535), 0.0); }
vec3 encu(uint v) { return vec3(float(v >> 16u), float(v & 65535u), 0.0); }
";

pub struct Case {
    pub name: &'static str,
    /// Global declarations and functions (after `shader_type sky;` and the encoders).
    pub globals: &'static str,
    /// The body of `sky()`.
    pub body: &'static str,
    /// COLOR's three channels.
    pub expect: [X; 3],
}

fn i3(v: i32) -> [X; 3] {
    let [a, b] = int(v);
    [a, b, X::F(0.0)]
}

fn u3(v: u32) -> [X; 3] {
    let [a, b] = uint(v);
    [a, b, X::F(0.0)]
}

pub fn cases() -> Vec<Case> {
    use X::*;
    vec![
        // 1136930381 · 2 = 2273860762 = 2³² − 2021106534: wraps to −2021106534.
        Case {
            name: "int_shift_left_overflow_global_const",
            globals: "const int P = 1136930381;",
            body: "COLOR = enc(P << 1);",
            expect: i3(-2_021_106_534),
        },
        // 1 << 31 is the sign bit: −2147483648.
        Case {
            name: "int_shift_into_sign_bit_local",
            globals: "float f() { int s = 1 << 31; return float(s); }",
            body: "COLOR = vec3(f(), 0.0, 0.0);",
            expect: [F(-2_147_483_648.0), F(0.0), F(0.0)],
        },
        // 2147483647 + 1 wraps to −2147483648.
        Case { name: "int_add_overflow", globals: "", body: "COLOR = enc(2147483647 + 1);", expect: i3(i32::MIN) },
        // INT_MIN / −1 = INT_MIN (naga's run-time code divides by 1 instead).
        Case {
            name: "int_min_div_minus_one_global",
            globals: "const int A = (-2147483647 - 1) / -1;",
            body: "COLOR = enc(A);",
            expect: i3(i32::MIN),
        },
        Case {
            name: "int_min_rem_minus_one_global",
            globals: "const int B = (-2147483647 - 1) % -1;",
            body: "COLOR = enc(B);",
            expect: i3(0),
        },
        Case {
            name: "int_min_div_minus_one_local",
            globals: "",
            body: "int a = (-2147483647 - 1) / -1; COLOR = enc(a);",
            expect: i3(i32::MIN),
        },
        // −INT_MIN wraps to INT_MIN.
        Case { name: "int_min_negated", globals: "", body: "COLOR = enc(-(-2147483647 - 1));", expect: i3(i32::MIN) },
        // Godot accepts these in a non-const local's initializer: 5 / 0 = 5, 5 % 0 = 0.
        Case {
            name: "int_div_rem_by_zero_local_initializer",
            globals: "",
            body: "int z = 5 / 0; int m = 5 % 0; COLOR = vec3(float(z), float(m), 1.0);",
            expect: [F(5.0), F(0.0), F(1.0)],
        },
        // A run-time 7 (TIME is 0) by a constant zero: 7 / 0 = 7, 7 % 0 = 0.
        Case {
            name: "int_div_rem_by_zero_run_time",
            globals: "",
            body: "int x = int(TIME) + 7; int y = x / 0; int r = x % 0; \
                   ivec2 v = ivec2(x) / ivec2(2, 0); COLOR = vec3(float(y), float(r), float(v.x * 10 + v.y));",
            // ivec2(7) / ivec2(2, 0) = (3, 7): 3 · 10 + 7 = 37.
            expect: [F(7.0), F(0.0), F(37.0)],
        },
        // Shift amounts keep their low 5 bits: 3 << 33 = 3 << 1 = 6; −8 >> 33 = −8 >> 1 = −4;
        // 3 << −1 = 3 << 31 = 0x80000000 = −2147483648.
        Case {
            name: "int_shift_by_32_or_more_or_negative",
            globals: "",
            body: "int a = 3 << 33; int b = -8 >> 33; int c = 3 << -1; \
                   COLOR = vec3(float(a), float(b), float(c));",
            expect: [F(6.0), F(-4.0), F(-2_147_483_648.0)],
        },
        // The same at run time: the amount 33 (TIME is 0) is masked to 1.
        Case {
            name: "int_shift_by_33_run_time",
            globals: "",
            body: "int k = int(TIME) + 33; int a = 5 << k; int b = -8 >> k; uint c = 5u << uint(k); \
                   COLOR = vec3(float(a), float(b), float(c));",
            expect: [F(10.0), F(-4.0), F(10.0)],
        },
        // 4000000000 · 2 = 8000000000 − 2³² = 3705032704.
        Case {
            name: "uint_shift_left_overflow",
            globals: "",
            body: "COLOR = encu(4000000000u << 1u);",
            expect: u3(3_705_032_704),
        },
        // +∞: 3.4e38 · 10 overflows f32.
        Case {
            name: "float_overflow_in_function",
            globals: "float f() { float a = 3.4e38 * 10.0; return a; }",
            body: "COLOR = vec3(f(), -f(), 1.0);",
            expect: [Inf, NegInf, F(1.0)],
        },
        Case {
            name: "float_vector_div_by_zero",
            globals: "vec3 f() { vec3 b = vec3(1.0) / 0.0; return b; }",
            body: "COLOR = f();",
            expect: [Inf, Inf, Inf],
        },
        // 1 / −0 = −∞; 0 / 0 = NaN; 1 / 0 = +∞.
        Case {
            name: "float_div_by_signed_zero",
            globals: "float f() { return 1.0 / -0.0; }",
            body: "COLOR = vec3(f(), 0.0 / 0.0, 1.0 / 0.0);",
            expect: [NegInf, NaN, Inf],
        },
        // sqrt(−1) = NaN, log(0) = −∞, pow(−1, 0.5) = NaN.
        Case {
            name: "builtins_outside_their_domain",
            globals: "float a() { return sqrt(-1.0); } float b() { return log(0.0); } float c() { return pow(-1.0, 0.5); }",
            body: "COLOR = vec3(a(), b(), c());",
            expect: [NaN, NegInf, NaN],
        },
        // inversesqrt(0) = +∞, log2(−1) = NaN, acos(2) = NaN.
        Case {
            name: "builtins_outside_their_domain_2",
            globals: "",
            body: "COLOR = vec3(inversesqrt(0.0), log2(-1.0), acos(2.0));",
            expect: [Inf, NaN, NaN],
        },
        // asin(−2) = NaN, acosh(0.5) = NaN, atanh(1) = +∞.
        Case {
            name: "builtins_outside_their_domain_3",
            globals: "",
            body: "COLOR = vec3(asin(-2.0), acosh(0.5), atanh(1.0));",
            expect: [NaN, NaN, Inf],
        },
        // exp(100) overflows: +∞; sinh(100): +∞; 10¹⁰⁰ in degrees: 1e38 · 57.3 overflows: +∞.
        Case {
            name: "builtins_overflowing",
            globals: "",
            body: "COLOR = vec3(exp(100.0), sinh(100.0), degrees(1e38));",
            expect: [Inf, Inf, Inf],
        },
        // naga refuses pow with a negative base or 0⁰ even when C's powf is finite: pow(−2, 2)
        // = 4, pow(0, 0) = 1; and pow(0, −1) = +∞.
        Case {
            name: "pow_refused_by_naga",
            globals: "",
            body: "COLOR = vec3(pow(-2.0, 2.0), pow(0.0, 0.0), pow(0.0, -1.0));",
            expect: [F(4.0), F(1.0), Inf],
        },
        // clamp(5, 3, 1) with low > high: naga refuses it; at run time it is min(max(5, 3), 1) = 1.
        Case {
            name: "int_clamp_low_above_high",
            globals: "",
            body: "COLOR = vec3(float(clamp(5, 3, 1)), float(clamp(0u, 7u, 2u)), 0.0);",
            expect: [F(1.0), F(2.0), F(0.0)],
        },
        // A float past int's range clamps: the largest int an f32 holds below 2³¹ is
        // 2³¹ − 128 = 2147483520; below −2³¹ it is −2147483648; −1.0 to uint is 0.
        Case {
            name: "float_to_int_out_of_range",
            globals: "",
            body: "COLOR = vec3(float(int(3e10) - 2147483000), float(int(-3e10) + 2147483000), float(uint(-1.0)));",
            // 2147483520 − 2147483000 = 520; −2147483648 + 2147483000 = −648.
            expect: [F(520.0), F(-648.0), F(0.0)],
        },
        // A global constant that folds to +∞ (a "no hit" distance), negated, times zero (NaN).
        Case {
            name: "global_const_infinity",
            globals: "const float INF = 1.0 / 0.0;",
            body: "COLOR = vec3(INF, -INF, INF * 0.0);",
            expect: [Inf, NegInf, NaN],
        },
        Case {
            name: "global_const_nan",
            globals: "const float NOPE = 0.0 / 0.0; const vec2 V = vec2(1.0, -1.0) / 0.0;",
            body: "COLOR = vec3(NOPE, V.x, V.y);",
            expect: [NaN, Inf, NegInf],
        },
        // A[2] is −0.0, which a Vulkan driver need not keep at run time; 1 / A[2] = −∞ shows
        // its sign (folded, as GLSL's compilers fold it).
        Case {
            name: "global_const_array_with_infinity",
            globals: "const float A[3] = float[3](1.0 / 0.0, 0.0, -0.0);",
            body: "int i = int(TIME); COLOR = vec3(A[0], A[i + 1], 1.0 / A[2]);",
            expect: [Inf, F(0.0), NegInf],
        },
        // Constant expressions of a non-finite constant fold as IEEE: INF − INF = NaN,
        // 1 / INF = 0, INF > 1 is true, isinf(INF), isnan(INF · 0).
        Case {
            name: "arithmetic_on_infinity",
            globals: "const float INF = 1.0 / 0.0;",
            body: "COLOR = vec3(INF - INF, 1.0 / INF + (INF > 1.0 ? 1.0 : 0.0), \
                   (isinf(INF) ? 2.0 : 0.0) + (isnan(INF * 0.0) ? 4.0 : 0.0));",
            expect: [NaN, F(1.0), F(6.0)],
        },
        // 3.4028235e38 rounds to f32's largest value, 3.4028234663852886e38; 3.4028236e38 is
        // past the midpoint to the next power of two, 3.4028235677973366e38: +∞.
        Case {
            name: "float_literals_near_f32_max",
            globals: "const float M = 3.4028235e38; const float M2 = 3.4028236e38;",
            body: "float m3 = 3.4028236e38; COLOR = vec3(M, M2, m3);",
            expect: [F(f32::MAX), Inf, Inf],
        },
        // Falling off the end of a non-void function returns zero; f(2) = 2, g(3) = 3.
        Case {
            name: "missing_return",
            globals: "float f(float x) { if (x > 0.0) { return x; } }\n\
                      float g(float x) { while (true) { return x; } }",
            body: "COLOR = vec3(f(-1.0), f(2.0), g(3.0));",
            expect: [F(0.0), F(2.0), F(3.0)],
        },
        // Statements after return, break and continue never run.
        Case {
            name: "code_after_terminators",
            globals: "float h() { return 1.0; return 2.0; }\n\
                      float k() { float s = 0.0; for (int i = 0; i < 3; i++) { s += 1.0; continue; s += 100.0; } \
                      while (true) { s += 10.0; break; s += 1000.0; } return s; }",
            body: "COLOR = vec3(h(), k(), 0.0);",
            // k: 3 · 1 + 10 = 13.
            expect: [F(1.0), F(13.0), F(0.0)],
        },
        // A screen texture declared and never read: accepted (W005), no binding.
        Case {
            name: "unread_screen_texture",
            globals: "uniform sampler2D screen : hint_screen_texture;",
            body: "COLOR = vec3(0.25, 0.5, 0.75);",
            expect: [F(0.25), F(0.5), F(0.75)],
        },
    ]
}

/// The case's whole shader.
pub fn source(c: &Case) -> String {
    format!("shader_type sky;\n{ENCODE}\n{}\nvoid sky() {{\n{}\n}}\n", c.globals, c.body)
}

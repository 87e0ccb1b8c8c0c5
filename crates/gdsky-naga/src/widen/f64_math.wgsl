// f64 versions of the GLSL built-ins that SPIR-V's GLSL.std.450 (and so Vulkan) defines for 16-
// and 32-bit floats only: exp, exp2, log, log2, pow, sin, cos, tan, asin, acos, atan, atan2, sinh,
// cosh, tanh, asinh, acosh, atanh. gdsky's f64 evaluation (`gdsky_naga::lower_f64`) grafts the
// ones a shader uses into its module; see `mod.rs` for the design and docs/precision.md for the
// measured error of each.
//
// Only operations with f64 forms in SPIR-V appear here: + − × ÷, fma, sqrt, floor, round, abs,
// ldexp, f32 log2, comparisons and conversions. The polynomials are Taylor series, truncated where
// the next term is below 2^-60 of the result on the reduced interval, so their coefficients
// (1/n!, 2/(2k+1), 1/(2k+1)) are exact rationals rounded once; the constants that need more than
// 53 bits (ln 2, π/2, atan(i/8)) are split into a head and a tail, computed with mpmath.
//
// The algorithms follow fdlibm's (Sun's freely distributable libm, which Rust's f64 methods
// descend from): exp by Cody–Waite reduction by ln 2; log by frexp and the atanh series of
// (m − 1)/(m + 1) in double-double; sin/cos by a Cody–Waite reduction by π/2 (three pieces below
// 1.6e6, seven 24-bit pieces up to 2^53; beyond 2^53 there is no Payne–Hanek); atan by a table
// of atan(i/8).
//
// No `const` declarations at module scope: the grafting copies functions only.

// ---------------------------------------------------------------------------------------------
// Error-free products
// ---------------------------------------------------------------------------------------------

// The rounding error e of p = a·b (p + e = a·b exactly), by Dekker's product of Veltkamp halves:
// + − × only. Not fma(a, b, −p): Vulkan does not promise that f64 fma is fused, and lavapipe's
// is not (measured: fma(a, b, −a·b) = 0). Exact while a·b neither under- nor overflows and
// |a|, |b| < 2^996. Like every error term here, it needs the module's arithmetic evaluated as
// written: gdsky's f64 modules decorate it `NoContraction` (`gdsky_naga::exact_arithmetic`).
fn gdsky_f64_mul_err(a: f64, b: f64, p: f64) -> f64 {
    let ca = 134217729.0lf * a;
    let ah = ca - (ca - a);
    let al = a - ah;
    let cb = 134217729.0lf * b;
    let bh = cb - (cb - b);
    let bl = b - bh;
    return (((ah * bh - p) + ah * bl) + al * bh) + al * bl;
}

// ---------------------------------------------------------------------------------------------
// exp
// ---------------------------------------------------------------------------------------------

// 2^k · y for an integral k in [-1100, 1100], as a product of exact powers of two 2^(±2^j)
// (lavapipe's f64 ldexp overflows for large |k|, measured). Only the last product can round
// (into subnormals); k = 1024 with y < 1 overflows (2^1024 is not a double).
fn gdsky_f64_scale(y: f64, k: f64) -> f64 {
    var r = y;
    var p = select(2.0lf, 0.5lf, k < 0.0lf);
    var n = abs(k);
    for (var j = 0; j < 11; j++) {
        let half = floor(n * 0.5lf);
        if (n - 2.0lf * half == 1.0lf) {
            r = r * p;
        }
        p = p * p;
        n = half;
    }
    return r;
}

// exp(xh + xl) with |xl| far below an ulp of xh, |xh| < 746; no special cases.
fn gdsky_f64_exp_dd(xh: f64, xl: f64) -> f64 {
    let k = round(xh * 1.4426950408889634lf);
    // k·LN2_HI is exact (LN2_HI has 32 significant bits and |k| < 2^11), so hi is too.
    let hi = xh - k * 0.6931471803691238lf;
    let lo = k * 1.9082149292705877e-10lf - xl;
    let r = hi - lo;
    let rl = (hi - r) - lo;
    // exp(r) − 1 − r on |r| ≤ ln2/2 + ε: Taylor to r^15/15! (next term < 2^-60).
    var q = 7.647163731819816e-13lf;
    q = fma(q, r, 1.1470745597729725e-11lf);
    q = fma(q, r, 1.6059043836821613e-10lf);
    q = fma(q, r, 2.08767569878681e-09lf);
    q = fma(q, r, 2.505210838544172e-08lf);
    q = fma(q, r, 2.755731922398589e-07lf);
    q = fma(q, r, 2.7557319223985893e-06lf);
    q = fma(q, r, 2.48015873015873e-05lf);
    q = fma(q, r, 0.0001984126984126984lf);
    q = fma(q, r, 0.001388888888888889lf);
    q = fma(q, r, 0.008333333333333333lf);
    q = fma(q, r, 0.041666666666666664lf);
    q = fma(q, r, 0.16666666666666666lf);
    q = fma(q, r, 0.5lf);
    let p = r * r * q;
    // exp(r + rl) = exp(r)·(1 + rl) to first order; rl·(1 + r) is that correction.
    let y = 1.0lf + (r + (p + rl * (1.0lf + r)));
    return gdsky_f64_scale(y, k);
}

fn gdsky_f64_exp(x: f64) -> f64 {
    if (x > 709.782712893384lf) {
        return x * 1.0e308lf; // +inf
    }
    if (x < -745.1332191019412lf) {
        return 0.0lf;
    }
    // NaN falls through and stays NaN.
    return gdsky_f64_exp_dd(x, 0.0lf);
}

fn gdsky_f64_exp2(x: f64) -> f64 {
    if (x >= 1024.0lf) {
        return x * 1.0e308lf;
    }
    if (x < -1075.0lf) {
        return 0.0lf;
    }
    let k = round(x);
    let r = x - k; // exact
    // r·ln2 as a double-double: the product's rounding error by fma, plus r times ln2's tail.
    let t = r * 0.6931471805599453lf;
    let tl = gdsky_f64_mul_err(r, 0.6931471805599453lf, t) + r * 2.3190468138462996e-17lf;
    return gdsky_f64_scale(gdsky_f64_exp_dd(t, tl), k);
}

// expm1 for sinh/cosh/tanh: Taylor to x^19/19! on |x| < 1, exp(x) − 1 outside (where the
// subtraction costs at most e/(e − 1) ≈ 1.6 ulps).
fn gdsky_f64_expm1(x: f64) -> f64 {
    if (abs(x) < 1.0lf) {
        var q = 8.22063524662433e-18lf;
        q = fma(q, x, 1.5619206968586225e-16lf);
        q = fma(q, x, 2.8114572543455206e-15lf);
        q = fma(q, x, 4.779477332387385e-14lf);
        q = fma(q, x, 7.647163731819816e-13lf);
        q = fma(q, x, 1.1470745597729725e-11lf);
        q = fma(q, x, 1.6059043836821613e-10lf);
        q = fma(q, x, 2.08767569878681e-09lf);
        q = fma(q, x, 2.505210838544172e-08lf);
        q = fma(q, x, 2.755731922398589e-07lf);
        q = fma(q, x, 2.7557319223985893e-06lf);
        q = fma(q, x, 2.48015873015873e-05lf);
        q = fma(q, x, 0.0001984126984126984lf);
        q = fma(q, x, 0.001388888888888889lf);
        q = fma(q, x, 0.008333333333333333lf);
        q = fma(q, x, 0.041666666666666664lf);
        q = fma(q, x, 0.16666666666666666lf);
        q = fma(q, x, 0.5lf);
        return x + x * x * q;
    }
    return gdsky_f64_exp(x) - 1.0lf;
}

// ---------------------------------------------------------------------------------------------
// log
// ---------------------------------------------------------------------------------------------

// frexp without naga's f64 frexp (whose exponent is an i64, which would need SHADER_INT64):
// (m, e) with x = m·2^e, 0.5 ≤ |m| < 1, e as an f64; (x, 0) for 0, ±inf and NaN. The exponent
// comes from an f32 log2 of x brought into [2^-64, 2^64) by exact steps of 2^64, then
// corrected by one where the f32 result crossed a binade.
fn gdsky_f64_frexp(x: f64) -> vec2<f64> {
    let a = abs(x);
    if (a == 0.0lf || !(a <= 1.7976931348623157e308lf)) {
        return vec2<f64>(x, 0.0lf);
    }
    var y = a;
    var e = 0.0lf;
    for (var i = 0; i < 17 && y >= 18446744073709551616.0lf; i++) {
        y = y * 5.421010862427522e-20lf;
        e = e + 64.0lf;
    }
    for (var i = 0; i < 18 && y < 5.421010862427522e-20lf; i++) {
        y = y * 18446744073709551616.0lf;
        e = e - 64.0lf;
    }
    // f32's log2 may miss by one next to a power of two; the two corrections below fix that.
    // (Not frexp: naga's SPIR-V reader, which wgpu runs on SPIR-V, does not register frexp's
    // result type.)
    let fe = i32(floor(log2(f32(y)))) + 1;
    var m = ldexp(y, -fe);
    e = e + f64(fe);
    if (m < 0.5lf) {
        m = m * 2.0lf;
        e = e - 1.0lf;
    }
    if (m >= 1.0lf) {
        m = m * 0.5lf;
        e = e + 1.0lf;
    }
    return vec2<f64>(select(m, -m, x < 0.0lf), e);
}

// log(x) as a double-double (hi, lo) for finite x > 0 (subnormals included).
fn gdsky_f64_log_dd(x: f64) -> vec2<f64> {
    let fr = gdsky_f64_frexp(x);
    var m = fr.x; // [0.5, 1)
    var e = fr.y;
    if (m < 0.7071067811865476lf) {
        m = m * 2.0lf;
        e = e - 1.0lf;
    }
    let f = m - 1.0lf; // exact (Sterbenz), in [-0.29, 0.42)
    // s = f / (2 + f) as a double-double: 2 + f's rounding error, and the quotient's (f − s·u is
    // exact in f − su − e: su is within an ulp of f).
    let u = 2.0lf + f;
    let ul = (2.0lf - u) + f;
    let s = f / u;
    let su = s * u;
    let sl = (((f - su) - gdsky_f64_mul_err(s, u, su)) - s * ul) / u;
    // log(m) = 2·atanh(s) = 2s + s³·(2/3 + 2z/5 + …), z = s² ≤ 0.0295: to z^11 (next < 2^-60 of 2s).
    let z = s * s;
    var q = 0.08695652173913043lf;
    q = fma(q, z, 0.09523809523809523lf);
    q = fma(q, z, 0.10526315789473684lf);
    q = fma(q, z, 0.11764705882352941lf);
    q = fma(q, z, 0.13333333333333333lf);
    q = fma(q, z, 0.15384615384615385lf);
    q = fma(q, z, 0.18181818181818182lf);
    q = fma(q, z, 0.2222222222222222lf);
    q = fma(q, z, 0.2857142857142857lf);
    q = fma(q, z, 0.4lf);
    q = fma(q, z, 0.6666666666666666lf);
    let t = s * z * q;
    // e·LN2_HI is exact (32-bit head, |e| < 1100); add 2s to it exactly (two-sum).
    let h1 = e * 0.6931471803691238lf;
    let s2 = 2.0lf * s;
    let a = h1 + s2;
    let bb = a - h1;
    let err = (h1 - (a - bb)) + (s2 - bb);
    let lo = err + (e * 1.9082149292705877e-10lf + (2.0lf * sl + t));
    let h = a + lo;
    return vec2<f64>(h, lo - (h - a));
}

fn gdsky_f64_log(x: f64) -> f64 {
    if (x == 0.0lf) {
        return -1.0lf / abs(x); // -inf
    }
    if (!(x > 0.0lf)) {
        return sqrt(x); // NaN for x < 0 and for NaN
    }
    if (x > 1.7976931348623157e308lf) {
        return x; // +inf
    }
    return gdsky_f64_log_dd(x).x;
}

fn gdsky_f64_log2(x: f64) -> f64 {
    if (x == 0.0lf) {
        return -1.0lf / abs(x);
    }
    if (!(x > 0.0lf)) {
        return sqrt(x);
    }
    if (x > 1.7976931348623157e308lf) {
        return x;
    }
    let l = gdsky_f64_log_dd(x);
    // (hi + lo)·(1/ln2 + tail) as a double-double, then rounded once.
    let h = l.x * 1.4426950408889634lf;
    let hl = gdsky_f64_mul_err(l.x, 1.4426950408889634lf, h) + (l.x * 2.0355273740931033e-17lf + l.y * 1.4426950408889634lf);
    return h + hl;
}

// log(1 + x): log(u) for u = 1 + x rounded, plus the first-order correction (x − (u − 1))/u.
fn gdsky_f64_log1p(x: f64) -> f64 {
    if (x == -1.0lf) {
        return -1.0lf / (x + 1.0lf); // -inf
    }
    if (!(x > -1.0lf)) {
        return sqrt(x + -1.0lf); // NaN for x < -1 and NaN
    }
    if (x > 1.7976931348623157e308lf) {
        return x;
    }
    let u = 1.0lf + x;
    if (u == 1.0lf) {
        return x;
    }
    let c = (x - (u - 1.0lf)) / u;
    let l = gdsky_f64_log_dd(u);
    return l.x + (l.y + c);
}

// x^y, GLSL's pow: x < 0 gives NaN (GLSL leaves it undefined), pow(0, y < 0) +inf, pow(0, 0) 1;
// otherwise C99's special cases (pow(x, ±0) = 1, pow(1, y) = 1, infinities).
fn gdsky_f64_pow(x: f64, y: f64) -> f64 {
    if (y == 0.0lf || x == 1.0lf) {
        return 1.0lf;
    }
    if (x != x || y != y) {
        return x + y; // NaN
    }
    if (x < 0.0lf) {
        return sqrt(x); // NaN
    }
    let big = 1.7976931348623157e308lf;
    if (x == 0.0lf) {
        if (y > 0.0lf) {
            return 0.0lf;
        }
        return 1.0lf / x; // +inf
    }
    if (abs(y) > big) {
        // y = ±inf: grows when |x| > 1 and y > 0, or |x| < 1 and y < 0.
        if ((x > 1.0lf) == (y > 0.0lf)) {
            return abs(y);
        }
        return 0.0lf;
    }
    if (x > big) {
        if (y > 0.0lf) {
            return x;
        }
        return 0.0lf;
    }
    // exp(y·log x) with y·log x as a double-double: an error δ in y·log x is an error of δ
    // relative in the result, and y·log x reaches 745.
    let l = gdsky_f64_log_dd(x);
    let p = y * l.x;
    let pl = gdsky_f64_mul_err(y, l.x, p) + y * l.y;
    if (p > 709.8lf) {
        return big * 2.0lf * abs(y); // +inf
    }
    if (p < -745.2lf) {
        return 0.0lf;
    }
    return gdsky_f64_exp_dd(p, pl);
}

// ---------------------------------------------------------------------------------------------
// sin, cos, tan
// ---------------------------------------------------------------------------------------------

// x − n·π/2 as a double-double (y0, y1), and n mod 4 in z, for |x| < 2^20·π/2 ≈ 1.6e6: π/2 in
// three 33-bit pieces and a tail; n·piece is exact for |n| < 2^20, and the sums are exact
// two-sums.
fn gdsky_f64_rem_pio2_small(x: f64) -> vec3<f64> {
    let n = round(x * 0.6366197723675814lf);
    let r1 = x - n * 1.5707963267341256lf;
    let w2 = -(n * 6.077100506303966e-11lf);
    let s = r1 + w2;
    let sb = s - r1;
    let e = (r1 - (s - sb)) + (w2 - sb);
    let w3 = -(n * 2.0222662487111665e-21lf);
    let s2 = s + w3;
    let sb2 = s2 - s;
    let e2 = (s - (s2 - sb2)) + (w3 - sb2);
    let tail = (e + e2) - n * 8.4784276603689e-32lf;
    let y0 = s2 + tail;
    let y1 = tail - (y0 - s2);
    let quadrant = n - 4.0lf * floor(n * 0.25lf);
    return vec3<f64>(y0, y1, quadrant);
}

// (s, t) + b with s + b as an exact two-sum and its error gathered in t.
fn gdsky_f64_dd_add(acc: vec2<f64>, b: f64) -> vec2<f64> {
    let s = acc.x + b;
    let bb = s - acc.x;
    return vec2<f64>(s, acc.y + ((acc.x - (s - bb)) + (b - bb)));
}

// The same for |x| < 2^53; beyond, NaN rather than a wrong value (every such double is an even
// integer whose remainder needs the bits of 2/π far below 2^-53, i.e. Payne–Hanek, not done). n is
// x·2/π rounded from a double-double product; π/2 is seven pieces of 24 bits (168 bits, what
// cancels against an n of 53 bits leaves 115) and n is split at 2^24, so each n-part × piece is
// exact; the products are subtracted from x, largest first, into a double-double.
fn gdsky_f64_rem_pio2(x: f64) -> vec3<f64> {
    if (abs(x) < 1.6e6lf) {
        return gdsky_f64_rem_pio2_small(x);
    }
    if (!(abs(x) < 9007199254740992.0lf)) {
        return vec3<f64>(sqrt(-abs(x)), 0.0lf, 0.0lf); // NaN
    }
    let p = x * 0.6366197723675814lf;
    let pe = gdsky_f64_mul_err(x, 0.6366197723675814lf, p) + x * -3.935735335036497e-17lf;
    let n1 = round(p);
    let n = n1 + round((p - n1) + pe);
    let n_hi = 16777216.0lf * floor(n * 5.960464477539063e-08lf);
    let n_lo = n - n_hi;
    var acc = vec2<f64>(x, 0.0lf);
    acc = gdsky_f64_dd_add(acc, -(n_hi * 1.5707963705062866lf));
    acc = gdsky_f64_dd_add(acc, -(n_hi * -4.371138828673793e-08lf));
    acc = gdsky_f64_dd_add(acc, -(n_lo * 1.5707963705062866lf));
    acc = gdsky_f64_dd_add(acc, -(n_hi * -1.7151245100058819e-15lf));
    acc = gdsky_f64_dd_add(acc, -(n_lo * -4.371138828673793e-08lf));
    acc = gdsky_f64_dd_add(acc, -(n_hi * 1.056299898220315e-23lf));
    acc = gdsky_f64_dd_add(acc, -(n_lo * -1.7151245100058819e-15lf));
    acc = gdsky_f64_dd_add(acc, -(n_hi * 8.478427566216846e-32lf));
    acc = gdsky_f64_dd_add(acc, -(n_lo * 1.056299898220315e-23lf));
    acc = gdsky_f64_dd_add(acc, -(n_hi * 9.415205271428978e-40lf));
    acc = gdsky_f64_dd_add(acc, -(n_lo * 8.478427566216846e-32lf));
    acc = gdsky_f64_dd_add(acc, -(n_hi * 1.1687495018667348e-47lf));
    let tail = acc.y - (n_lo * 9.415205271428978e-40lf + n_lo * 1.1687495018667348e-47lf);
    let y0 = acc.x + tail;
    let y1 = tail - (y0 - acc.x);
    let quadrant = n - 4.0lf * floor(n * 0.25lf);
    return vec3<f64>(y0, y1, quadrant);
}

// sin(x + y) on |x| ≤ π/4 + ε, |y| tiny: Taylor to x^21/21!.
fn gdsky_f64_ksin(x: f64, y: f64) -> f64 {
    let z = x * x;
    var q = 1.9572941063391263e-20lf;
    q = fma(q, z, -8.22063524662433e-18lf);
    q = fma(q, z, 2.8114572543455206e-15lf);
    q = fma(q, z, -7.647163731819816e-13lf);
    q = fma(q, z, 1.6059043836821613e-10lf);
    q = fma(q, z, -2.505210838544172e-08lf);
    q = fma(q, z, 2.755731922398589e-06lf);
    q = fma(q, z, -0.0001984126984126984lf);
    q = fma(q, z, 0.008333333333333333lf);
    q = fma(q, z, -0.16666666666666666lf);
    // sin(x) + y·cos(x) ≈ x + (x³·q + y·(1 − z/2)).
    return x + (x * z * q + y * (1.0lf - 0.5lf * z));
}

// cos(x + y) likewise: Taylor to x^20/20!; 1 − z/2 split as fdlibm does, so its rounding error
// is recovered.
fn gdsky_f64_kcos(x: f64, y: f64) -> f64 {
    let z = x * x;
    var q = 4.110317623312165e-19lf;
    q = fma(q, z, -1.5619206968586225e-16lf);
    q = fma(q, z, 4.779477332387385e-14lf);
    q = fma(q, z, -1.1470745597729725e-11lf);
    q = fma(q, z, 2.08767569878681e-09lf);
    q = fma(q, z, -2.755731922398589e-07lf);
    q = fma(q, z, 2.48015873015873e-05lf);
    q = fma(q, z, -0.001388888888888889lf);
    q = fma(q, z, 0.041666666666666664lf);
    let hz = 0.5lf * z;
    let w = 1.0lf - hz;
    return w + (((1.0lf - w) - hz) + (z * z * q - x * y));
}

fn gdsky_f64_sin(x: f64) -> f64 {
    let r = gdsky_f64_rem_pio2(x);
    let s = gdsky_f64_ksin(r.x, r.y);
    let c = gdsky_f64_kcos(r.x, r.y);
    if (r.z == 0.0lf) {
        return s;
    }
    if (r.z == 1.0lf) {
        return c;
    }
    if (r.z == 2.0lf) {
        return -s;
    }
    // Quadrant 3, and NaN for x = NaN or ±inf (every comparison above false, s NaN).
    return select(s, -c, r.z == 3.0lf);
}

fn gdsky_f64_cos(x: f64) -> f64 {
    let r = gdsky_f64_rem_pio2(x);
    let s = gdsky_f64_ksin(r.x, r.y);
    let c = gdsky_f64_kcos(r.x, r.y);
    if (r.z == 0.0lf) {
        return c;
    }
    if (r.z == 1.0lf) {
        return -s;
    }
    if (r.z == 2.0lf) {
        return -c;
    }
    return select(c, s, r.z == 3.0lf);
}

// tan as the quotient of the kernels: about 2 ulps (each kernel ≤ 1, the division ½).
fn gdsky_f64_tan(x: f64) -> f64 {
    let r = gdsky_f64_rem_pio2(x);
    let s = gdsky_f64_ksin(r.x, r.y);
    let c = gdsky_f64_kcos(r.x, r.y);
    if (r.z == 1.0lf || r.z == 3.0lf) {
        return -c / s;
    }
    return s / c;
}

// ---------------------------------------------------------------------------------------------
// atan, atan2, asin, acos
// ---------------------------------------------------------------------------------------------

// atan(a) for a in [0, 1]: a = i/8 + …, atan(a) = atan(i/8) + atan(t), t = (a − i/8)/(1 + a·i/8),
// |t| ≤ 1/16; atan(t) by Taylor to t^19/19.
fn gdsky_f64_atan01(a: f64) -> f64 {
    var hi = array<f64, 9>(
        0.0lf, 0.12435499454676144lf, 0.24497866312686414lf, 0.35877067027057225lf, 0.4636476090008061lf,
        0.5585993153435624lf, 0.6435011087932844lf, 0.7188299996216245lf, 0.7853981633974483lf
    );
    var lo = array<f64, 9>(
        0.0lf, -3.1253241424539383e-18lf, 1.0698755618734451e-17lf, -2.4623815582638635e-17lf,
        2.2698777452961687e-17lf, -5.4556305485916264e-18lf, 1.5834785051444286e-17lf,
        -2.1478388444456983e-17lf, 3.061616997868383e-17lf
    );
    let fi = round(a * 8.0lf);
    let i = clamp(i32(fi), 0, 8);
    let c = fi * 0.125lf;
    let t = (a - c) / (1.0lf + a * c);
    let z = t * t;
    var q = 0.05263157894736842lf;
    q = fma(q, z, -0.058823529411764705lf);
    q = fma(q, z, 0.06666666666666667lf);
    q = fma(q, z, -0.07692307692307693lf);
    q = fma(q, z, 0.09090909090909091lf);
    q = fma(q, z, -0.1111111111111111lf);
    q = fma(q, z, 0.14285714285714285lf);
    q = fma(q, z, -0.2lf);
    q = fma(q, z, 0.3333333333333333lf);
    return hi[i] + (t + (lo[i] - t * z * q));
}

fn gdsky_f64_atan(x: f64) -> f64 {
    let a = abs(x);
    var r: f64;
    if (a <= 1.0lf) {
        r = gdsky_f64_atan01(a);
    } else if (a > 1.0lf) {
        // π/2 − atan(1/a); 1/a's rounding moves the result by < ½ ulp (the result is ≥ π/4).
        r = 1.5707963267948966lf + (6.123233995736766e-17lf - gdsky_f64_atan01(1.0lf / a));
    } else {
        return x; // NaN
    }
    return select(r, -r, x < 0.0lf);
}

// atan2(y, x) with fdlibm's special cases (signed zeros of x by 1/x).
fn gdsky_f64_atan2(y: f64, x: f64) -> f64 {
    if (x != x || y != y) {
        return x + y;
    }
    let pi = 3.141592653589793lf;
    let x_negative = x < 0.0lf || (x == 0.0lf && 1.0lf / x < 0.0lf);
    let big = 1.7976931348623157e308lf;
    if (y == 0.0lf) {
        if (x_negative) {
            return select(pi, -pi, y < 0.0lf || 1.0lf / y < 0.0lf);
        }
        return y;
    }
    if (x == 0.0lf) {
        return select(1.5707963267948966lf, -1.5707963267948966lf, y < 0.0lf);
    }
    var z: f64;
    if (abs(x) > big && abs(y) > big) {
        z = 0.7853981633974483lf;
    } else {
        z = gdsky_f64_atan(abs(y / x));
    }
    if (x_negative) {
        // π − z with π's tail, as fdlibm does.
        z = pi - (z - 1.2246467991473532e-16lf);
    }
    return select(z, -z, y < 0.0lf);
}

// asin(x) = atan(x / sqrt((1 − x)(1 + x))): 1 − x is exact for x ≥ ½, so the argument is good to
// ~1.5 ulps and the result to ~2.
fn gdsky_f64_asin(x: f64) -> f64 {
    let a = abs(x);
    if (a < 1.0e-9lf) {
        return x;
    }
    let c = sqrt((1.0lf - a) * (1.0lf + a));
    let r = gdsky_f64_atan(a / c); // a = 1: atan(+inf) = π/2; a > 1: NaN
    return select(r, -r, x < 0.0lf);
}

// acos(x) = 2·atan(sqrt((1 − x)/(1 + x))).
fn gdsky_f64_acos(x: f64) -> f64 {
    return 2.0lf * gdsky_f64_atan(sqrt((1.0lf - x) / (1.0lf + x)));
}

// ---------------------------------------------------------------------------------------------
// Hyperbolic functions (fdlibm's formulas over expm1 and log1p)
// ---------------------------------------------------------------------------------------------

fn gdsky_f64_sinh(x: f64) -> f64 {
    let a = abs(x);
    var r: f64;
    if (a < 3.725290298461914e-09lf) {
        return x;
    } else if (a < 22.0lf) {
        let t = gdsky_f64_expm1(a);
        if (a < 1.0lf) {
            r = 0.5lf * (2.0lf * t - t * t / (t + 1.0lf));
        } else {
            r = 0.5lf * (t + t / (t + 1.0lf));
        }
    } else if (a < 709.782712893384lf) {
        r = 0.5lf * gdsky_f64_exp(a);
    } else if (a <= 710.4758600739439lf) {
        let w = gdsky_f64_exp(0.5lf * a);
        r = (0.5lf * w) * w;
    } else {
        r = a * 1.0e308lf; // +inf, or NaN
    }
    return select(r, -r, x < 0.0lf);
}

fn gdsky_f64_cosh(x: f64) -> f64 {
    let a = abs(x);
    if (a < 0.34657359027997264lf) {
        let t = gdsky_f64_expm1(a);
        let w = 1.0lf + t;
        return 1.0lf + (t * t) / (w + w);
    }
    if (a < 22.0lf) {
        let t = gdsky_f64_exp(a);
        return 0.5lf * t + 0.5lf / t;
    }
    if (a < 709.782712893384lf) {
        return 0.5lf * gdsky_f64_exp(a);
    }
    if (a <= 710.4758600739439lf) {
        let w = gdsky_f64_exp(0.5lf * a);
        return (0.5lf * w) * w;
    }
    return a * 1.0e308lf;
}

fn gdsky_f64_tanh(x: f64) -> f64 {
    let a = abs(x);
    var z: f64;
    if (a < 2.7755575615628914e-17lf) {
        return x;
    } else if (a < 1.0lf) {
        let t = gdsky_f64_expm1(-2.0lf * a);
        z = -t / (t + 2.0lf);
    } else if (a <= 22.0lf) {
        let t = gdsky_f64_expm1(2.0lf * a);
        z = 1.0lf - 2.0lf / (t + 2.0lf);
    } else if (a > 22.0lf) {
        z = 1.0lf;
    } else {
        return x; // NaN
    }
    return select(z, -z, x < 0.0lf);
}

fn gdsky_f64_asinh(x: f64) -> f64 {
    let a = abs(x);
    var r: f64;
    if (a < 3.725290298461914e-09lf) {
        return x;
    } else if (a > 268435456.0lf) {
        r = gdsky_f64_log(a) + 0.6931471805599453lf;
    } else if (a > 2.0lf) {
        r = gdsky_f64_log(2.0lf * a + 1.0lf / (sqrt(a * a + 1.0lf) + a));
    } else {
        let t = a * a;
        r = gdsky_f64_log1p(a + t / (1.0lf + sqrt(1.0lf + t)));
    }
    return select(r, -r, x < 0.0lf);
}

fn gdsky_f64_acosh(x: f64) -> f64 {
    if (x < 1.0lf) {
        return sqrt(x - 1.0lf); // NaN
    }
    if (x > 268435456.0lf) {
        return gdsky_f64_log(x) + 0.6931471805599453lf;
    }
    if (x > 2.0lf) {
        return gdsky_f64_log(2.0lf * x - 1.0lf / (x + sqrt(x * x - 1.0lf)));
    }
    let t = x - 1.0lf; // exact
    return gdsky_f64_log1p(t + sqrt(2.0lf * t + t * t));
}

fn gdsky_f64_atanh(x: f64) -> f64 {
    let a = abs(x);
    var r: f64;
    if (a < 3.725290298461914e-09lf) {
        return x;
    } else if (a < 0.5lf) {
        let t = a + a;
        r = 0.5lf * gdsky_f64_log1p(t + t * a / (1.0lf - a));
    } else {
        // a = 1: log1p(+inf) = +inf; a > 1: NaN from log1p of a negative < −1.
        r = 0.5lf * gdsky_f64_log1p((a + a) / (1.0lf - a));
    }
    return select(r, -r, x < 0.0lf);
}

//! Godot's tables for sky shaders, as data: built-in variables, render modes, uniform hints and
//! the built-in function overloads. Everything the checker knows about Godot's built-ins is here.
//!
//! Sources: reference/godot-sky.md §1–§3 (shader_types.cpp SKY section, shading_language.rst,
//! shader_functions.rst).

use super::types::{SamplerKind, Scalar, Type};
use std::collections::HashMap;
use std::sync::OnceLock;

/// Where a built-in variable can be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BuiltinScope {
    /// Anywhere: in `sky()`, in helper functions, in initializers of locals.
    Global,
    /// Only inside `sky()`.
    SkyOnly,
}

/// A built-in variable of sky shaders.
#[derive(Clone, Copy, Debug)]
pub struct BuiltinVar {
    /// Name as written in the shader.
    pub name: &'static str,
    /// Type name.
    pub ty: &'static str,
    /// Where it may be used.
    pub scope: BuiltinScope,
    /// True for the outputs COLOR, ALPHA and FOG.
    pub writable: bool,
}

const fn var(name: &'static str, ty: &'static str, scope: BuiltinScope, writable: bool) -> BuiltinVar {
    BuiltinVar { name, ty, scope, writable }
}

use BuiltinScope::{Global, SkyOnly};

/// Every built-in variable of `shader_type sky` (reference §1).
pub const BUILTIN_VARS: &[BuiltinVar] = &[
    var("EYEDIR", "vec3", SkyOnly, false),
    var("SCREEN_UV", "vec2", SkyOnly, false),
    var("SKY_COORDS", "vec2", SkyOnly, false),
    var("FRAGCOORD", "vec4", SkyOnly, false),
    var("HALF_RES_COLOR", "vec4", SkyOnly, false),
    var("QUARTER_RES_COLOR", "vec4", SkyOnly, false),
    var("COLOR", "vec3", SkyOnly, true),
    var("ALPHA", "float", SkyOnly, true),
    var("FOG", "vec4", SkyOnly, true),
    var("POSITION", "vec3", Global, false),
    var("RADIANCE", "samplerCube", Global, false),
    var("AT_CUBEMAP_PASS", "bool", Global, false),
    var("AT_HALF_RES_PASS", "bool", Global, false),
    var("AT_QUARTER_RES_PASS", "bool", Global, false),
    var("TIME", "float", Global, false),
    var("PI", "float", Global, false),
    var("TAU", "float", Global, false),
    var("E", "float", Global, false),
    var("LIGHT0_ENABLED", "bool", Global, false),
    var("LIGHT0_DIRECTION", "vec3", Global, false),
    var("LIGHT0_ENERGY", "float", Global, false),
    var("LIGHT0_COLOR", "vec3", Global, false),
    var("LIGHT0_SIZE", "float", Global, false),
    var("LIGHT1_ENABLED", "bool", Global, false),
    var("LIGHT1_DIRECTION", "vec3", Global, false),
    var("LIGHT1_ENERGY", "float", Global, false),
    var("LIGHT1_COLOR", "vec3", Global, false),
    var("LIGHT1_SIZE", "float", Global, false),
    var("LIGHT2_ENABLED", "bool", Global, false),
    var("LIGHT2_DIRECTION", "vec3", Global, false),
    var("LIGHT2_ENERGY", "float", Global, false),
    var("LIGHT2_COLOR", "vec3", Global, false),
    var("LIGHT2_SIZE", "float", Global, false),
    var("LIGHT3_ENABLED", "bool", Global, false),
    var("LIGHT3_DIRECTION", "vec3", Global, false),
    var("LIGHT3_ENERGY", "float", Global, false),
    var("LIGHT3_COLOR", "vec3", Global, false),
    var("LIGHT3_SIZE", "float", Global, false),
];

/// Values of the built-in constants, which Godot's compiler substitutes as literals.
pub fn builtin_constant(name: &str) -> Option<f64> {
    match name {
        "PI" => Some(std::f64::consts::PI),
        "TAU" => Some(std::f64::consts::TAU),
        "E" => Some(std::f64::consts::E),
        _ => None,
    }
}

/// Looks up a built-in variable.
pub fn builtin_var(name: &str) -> Option<&'static BuiltinVar> {
    BUILTIN_VARS.iter().find(|v| v.name == name)
}

/// The render modes of sky shaders (reference §2; the docs list only the first three).
pub const RENDER_MODES: &[&str] = &["use_half_res_pass", "use_quarter_res_pass", "disable_fog", "use_debanding"];

/// What a uniform hint may be put on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HintTarget {
    /// `hint_range`: int or float scalars.
    IntOrFloat,
    /// `hint_enum`: int scalars.
    Int,
    /// `source_color`: vec3, vec4, or a sampler.
    ColorOrSampler,
    /// `color_conversion_disabled`: vec3 or vec4 (with `source_color`).
    Color,
    /// Texture hints: samplers only.
    Sampler,
    /// Hints Godot knows but rejects in sky shaders.
    NotInSky,
    /// `hint_screen_texture`: a sampler; Godot 4.6 accepts it in a sky shader, which has no
    /// screen texture to read (a warning; reading it is an error).
    ScreenTexture,
}

/// The uniform hints Godot knows (reference §3), with what each may be put on.
pub const HINTS: &[(&str, HintTarget)] = &[
    ("hint_range", HintTarget::IntOrFloat),
    ("hint_enum", HintTarget::Int),
    ("source_color", HintTarget::ColorOrSampler),
    ("color_conversion_disabled", HintTarget::Color),
    ("hint_normal", HintTarget::Sampler),
    ("hint_roughness_r", HintTarget::Sampler),
    ("hint_roughness_g", HintTarget::Sampler),
    ("hint_roughness_b", HintTarget::Sampler),
    ("hint_roughness_a", HintTarget::Sampler),
    ("hint_roughness_normal", HintTarget::Sampler),
    ("hint_roughness_gray", HintTarget::Sampler),
    ("hint_default_white", HintTarget::Sampler),
    ("hint_default_black", HintTarget::Sampler),
    ("hint_default_transparent", HintTarget::Sampler),
    ("hint_anisotropy", HintTarget::Sampler),
    ("filter_nearest", HintTarget::Sampler),
    ("filter_linear", HintTarget::Sampler),
    ("filter_nearest_mipmap", HintTarget::Sampler),
    ("filter_linear_mipmap", HintTarget::Sampler),
    ("filter_nearest_mipmap_anisotropic", HintTarget::Sampler),
    ("filter_linear_mipmap_anisotropic", HintTarget::Sampler),
    ("repeat_enable", HintTarget::Sampler),
    ("repeat_disable", HintTarget::Sampler),
    ("hint_screen_texture", HintTarget::ScreenTexture),
    ("hint_depth_texture", HintTarget::NotInSky),
    ("hint_normal_roughness_texture", HintTarget::NotInSky),
    ("instance_index", HintTarget::NotInSky),
];

/// The built-in function overloads, one per line: `ret name(params)`.
///
/// Generic names stand for a family, all instances of one line using the same width N:
/// `genF`/`genI`/`genU`/`genB` are the scalar (N = 1) or vector (N = 2..4) of float, int, uint,
/// bool; `vecF`/`vecI`/`vecU`/`vecB` the vectors only (N = 2..4); `mat` is `matN`. `gsampler*`
/// and `gvec4` run over the float, int and uint samplers with the matching vec4. `out` marks an
/// output parameter. Lines starting with `#` are comments.
const FUNCTIONS: &str = "
genF radians(genF)
genF degrees(genF)
genF sin(genF)
genF cos(genF)
genF tan(genF)
genF asin(genF)
genF acos(genF)
genF atan(genF)
genF atan(genF, genF)
genF sinh(genF)
genF cosh(genF)
genF tanh(genF)
genF asinh(genF)
genF acosh(genF)
genF atanh(genF)
genF pow(genF, genF)
genF exp(genF)
genF log(genF)
genF exp2(genF)
genF log2(genF)
genF sqrt(genF)
genF inversesqrt(genF)
genF abs(genF)
genI abs(genI)
genF sign(genF)
genI sign(genI)
genF floor(genF)
genF round(genF)
genF roundEven(genF)
genF trunc(genF)
genF ceil(genF)
genF fract(genF)
genF mod(genF, genF)
genF mod(genF, float)
genF modf(genF, out genF)
genF min(genF, genF)
genF min(genF, float)
genI min(genI, genI)
genI min(genI, int)
genU min(genU, genU)
genU min(genU, uint)
genF max(genF, genF)
genF max(genF, float)
genI max(genI, genI)
genI max(genI, int)
genU max(genU, genU)
genU max(genU, uint)
genF clamp(genF, genF, genF)
genF clamp(genF, float, float)
genI clamp(genI, genI, genI)
genI clamp(genI, int, int)
genU clamp(genU, genU, genU)
genU clamp(genU, uint, uint)
genF mix(genF, genF, genF)
genF mix(genF, genF, float)
genF mix(genF, genF, genB)
genF fma(genF, genF, genF)
genF step(genF, genF)
genF step(float, genF)
genF smoothstep(genF, genF, genF)
genF smoothstep(float, float, genF)
genB isnan(genF)
genB isinf(genF)
genI floatBitsToInt(genF)
genU floatBitsToUint(genF)
genF intBitsToFloat(genI)
genF uintBitsToFloat(genU)
float length(genF)
float distance(genF, genF)
float dot(genF, genF)
vec3 cross(vec3, vec3)
genF normalize(genF)
genF reflect(genF, genF)
genF refract(genF, genF, float)
genF faceforward(genF, genF, genF)
mat matrixCompMult(mat, mat)
mat outerProduct(vecF, vecF)
mat transpose(mat)
float determinant(mat)
mat inverse(mat)
vecB lessThan(vecF, vecF)
vecB lessThan(vecI, vecI)
vecB lessThan(vecU, vecU)
vecB greaterThan(vecF, vecF)
vecB greaterThan(vecI, vecI)
vecB greaterThan(vecU, vecU)
vecB lessThanEqual(vecF, vecF)
vecB lessThanEqual(vecI, vecI)
vecB lessThanEqual(vecU, vecU)
vecB greaterThanEqual(vecF, vecF)
vecB greaterThanEqual(vecI, vecI)
vecB greaterThanEqual(vecU, vecU)
vecB equal(vecF, vecF)
vecB equal(vecI, vecI)
vecB equal(vecU, vecU)
vecB equal(vecB, vecB)
vecB notEqual(vecF, vecF)
vecB notEqual(vecI, vecI)
vecB notEqual(vecU, vecU)
vecB notEqual(vecB, vecB)
bool any(vecB)
bool all(vecB)
vecB not(vecB)
ivec2 textureSize(gsampler2D, int)
ivec3 textureSize(gsampler2DArray, int)
ivec3 textureSize(gsampler3D, int)
ivec2 textureSize(samplerCube, int)
ivec3 textureSize(samplerCubeArray, int)
vec2 textureQueryLod(gsampler2D, vec2)
vec2 textureQueryLod(gsampler2DArray, vec2)
vec2 textureQueryLod(gsampler3D, vec3)
vec2 textureQueryLod(samplerCube, vec3)
int textureQueryLevels(gsampler2D)
int textureQueryLevels(gsampler2DArray)
int textureQueryLevels(gsampler3D)
int textureQueryLevels(samplerCube)
gvec4 texture(gsampler2D, vec2)
gvec4 texture(gsampler2D, vec2, float)
gvec4 texture(gsampler2DArray, vec3)
gvec4 texture(gsampler2DArray, vec3, float)
gvec4 texture(gsampler3D, vec3)
gvec4 texture(gsampler3D, vec3, float)
vec4 texture(samplerCube, vec3)
vec4 texture(samplerCube, vec3, float)
vec4 texture(samplerCubeArray, vec4)
vec4 texture(samplerCubeArray, vec4, float)
gvec4 textureProj(gsampler2D, vec3)
gvec4 textureProj(gsampler2D, vec4)
gvec4 textureProj(gsampler2D, vec3, float)
gvec4 textureProj(gsampler2D, vec4, float)
gvec4 textureProj(gsampler3D, vec4)
gvec4 textureProj(gsampler3D, vec4, float)
gvec4 textureLod(gsampler2D, vec2, float)
gvec4 textureLod(gsampler2DArray, vec3, float)
gvec4 textureLod(gsampler3D, vec3, float)
vec4 textureLod(samplerCube, vec3, float)
vec4 textureLod(samplerCubeArray, vec4, float)
gvec4 textureProjLod(gsampler2D, vec3, float)
gvec4 textureProjLod(gsampler2D, vec4, float)
gvec4 textureProjLod(gsampler3D, vec4, float)
gvec4 texelFetch(gsampler2D, ivec2, int)
gvec4 texelFetch(gsampler2DArray, ivec3, int)
gvec4 texelFetch(gsampler3D, ivec3, int)
gvec4 textureGrad(gsampler2D, vec2, vec2, vec2)
gvec4 textureGrad(gsampler2DArray, vec3, vec2, vec2)
gvec4 textureGrad(gsampler3D, vec3, vec3, vec3)
vec4 textureGrad(samplerCube, vec3, vec3, vec3)
vec4 textureGrad(samplerCubeArray, vec4, vec3, vec3)
gvec4 textureGather(gsampler2D, vec2)
gvec4 textureGather(gsampler2D, vec2, int)
gvec4 textureGather(gsampler2DArray, vec3)
gvec4 textureGather(gsampler2DArray, vec3, int)
vec4 textureGather(samplerCube, vec3)
vec4 textureGather(samplerCube, vec3, int)
genF dFdx(genF)
genF dFdy(genF)
genF fwidth(genF)
genF dFdxCoarse(genF)
genF dFdyCoarse(genF)
genF fwidthCoarse(genF)
genF dFdxFine(genF)
genF dFdyFine(genF)
genF fwidthFine(genF)
uint packHalf2x16(vec2)
vec2 unpackHalf2x16(uint)
uint packUnorm2x16(vec2)
vec2 unpackUnorm2x16(uint)
uint packSnorm2x16(vec2)
vec2 unpackSnorm2x16(uint)
uint packUnorm4x8(vec4)
vec4 unpackUnorm4x8(uint)
uint packSnorm4x8(vec4)
vec4 unpackSnorm4x8(uint)
genI bitfieldExtract(genI, int, int)
genU bitfieldExtract(genU, int, int)
genI bitfieldInsert(genI, genI, int, int)
genU bitfieldInsert(genU, genU, int, int)
genI bitfieldReverse(genI)
genU bitfieldReverse(genU)
genI bitCount(genI)
genU bitCount(genU)
genI findLSB(genI)
genU findLSB(genU)
genI findMSB(genI)
genU findMSB(genU)
void imulExtended(genI, genI, out genI, out genI)
void umulExtended(genU, genU, out genU, out genU)
genU uaddCarry(genU, genU, out genU)
genU usubBorrow(genU, genU, out genU)
# Godot's table marks ldexp's exponent as an output, so it must be a variable there too.
genF ldexp(genF, out genI)
genF frexp(genF, out genI)
";

/// One overload of a built-in function.
#[derive(Clone, Debug, PartialEq)]
pub struct Signature {
    /// Return type.
    pub ret: Type,
    /// Parameter types, with `true` for `out` parameters.
    pub params: Vec<(Type, bool)>,
}

/// All overloads of the built-in function `name`, or `None` when it is not one.
pub fn builtin_function(name: &str) -> Option<&'static [Signature]> {
    static TABLE: OnceLock<HashMap<&'static str, Vec<Signature>>> = OnceLock::new();
    TABLE.get_or_init(build_table).get(name).map(Vec::as_slice)
}

fn build_table() -> HashMap<&'static str, Vec<Signature>> {
    let mut table: HashMap<&'static str, Vec<Signature>> = HashMap::new();
    for line in FUNCTIONS.lines().map(str::trim).filter(|l| !l.is_empty() && !l.starts_with('#')) {
        let Some((ret, rest)) = line.split_once(' ') else {
            continue;
        };
        let Some((name, params)) = rest.split_once('(') else {
            continue;
        };
        let params: Vec<&str> =
            params.trim_end_matches(')').split(',').map(str::trim).filter(|p| !p.is_empty()).collect();
        let tokens = || std::iter::once(ret).chain(params.iter().map(|p| p.trim_start_matches("out ")));
        let widths: &[u8] = if tokens().any(|t| t.starts_with("gen")) {
            &[1, 2, 3, 4]
        } else if tokens().any(|t| matches!(t, "vecF" | "vecI" | "vecU" | "vecB" | "mat")) {
            &[2, 3, 4]
        } else {
            &[0]
        };
        let samplers: &[Scalar] = if tokens().any(|t| t.starts_with('g') && !t.starts_with("gen")) {
            &[Scalar::Float, Scalar::Int, Scalar::UInt]
        } else {
            &[Scalar::Float]
        };
        for &n in widths {
            for &g in samplers {
                let resolve = |t: &str| generic_type(t, n, g);
                let (Some(ret), Some(params)) = (
                    resolve(ret),
                    params
                        .iter()
                        .map(|p| match p.strip_prefix("out ") {
                            Some(t) => resolve(t).map(|t| (t, true)),
                            None => resolve(p).map(|t| (t, false)),
                        })
                        .collect::<Option<Vec<_>>>(),
                ) else {
                    continue;
                };
                table.entry(name).or_default().push(Signature { ret, params });
            }
        }
    }
    table
}

fn generic_type(token: &str, n: u8, g: Scalar) -> Option<Type> {
    let family = |s| Some(Type::vector_of(s, n));
    match token {
        "genF" | "vecF" => family(Scalar::Float),
        "genI" | "vecI" => family(Scalar::Int),
        "genU" | "vecU" => family(Scalar::UInt),
        "genB" | "vecB" => family(Scalar::Bool),
        "mat" => Some(Type::Matrix(n)),
        "gvec4" => Some(Type::Vector(g, 4)),
        "gsampler2D" => Some(Type::Sampler(SamplerKind::Tex2D, g)),
        "gsampler2DArray" => Some(Type::Sampler(SamplerKind::Tex2DArray, g)),
        "gsampler3D" => Some(Type::Sampler(SamplerKind::Tex3D, g)),
        other => Type::from_name(other),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_line_of_the_function_table_parses() {
        let lines = FUNCTIONS.lines().filter(|l| !l.trim().is_empty() && !l.starts_with('#')).count();
        let total: usize = build_table().values().map(Vec::len).sum();
        // Each line yields at least one overload; generic lines yield three or four.
        assert!(total >= lines, "{total} overloads from {lines} lines");
        let mix = builtin_function("mix").map(<[Signature]>::len);
        assert_eq!(mix, Some(12));
        let texture = builtin_function("texture").map(<[Signature]>::len);
        assert_eq!(texture, Some(3 * 6 + 4));
        assert!(builtin_function("sky").is_none());
    }

    #[test]
    fn every_builtin_var_type_is_a_type() {
        for v in BUILTIN_VARS {
            assert!(Type::from_name(v.ty).is_some(), "{}", v.name);
        }
    }
}

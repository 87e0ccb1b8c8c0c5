//! Godot's sky wrapper: the built-ins uniform, the per-pixel built-ins, and the entry points.
//!
//! Godot runs `sky()` inside a generated fragment shader that computes EYEDIR for the pass,
//! sets COLOR = 0, ALPHA = 1, FOG = 0, calls `sky()`, applies custom fog, multiplies by the
//! luminance multiplier and forces alpha to 0 outside the sub-passes (reference §1.1–§1.3). This
//! module builds the same thing in naga IR:
//!
//! * group 0, binding 0: [`SkyBuiltins`](crate::reflect) — camera basis, POSITION, TIME, screen
//!   size, the camera's tan(fov/2), the pass, the luminance multiplier, the cube face, and
//!   LIGHT0..3. Its layout is fixed, so a host can fill it without reading reflection.
//! * private globals for the built-ins that exist only inside `sky()` (EYEDIR, SCREEN_UV,
//!   SKY_COORDS, FRAGCOORD, COLOR, ALPHA, FOG), declared only when the shader uses them.
//! * `vs_main` (a fullscreen triangle), and `fs_panorama`, `fs_camera`, `fs_cubemap`, which differ
//!   only in how a pixel becomes EYEDIR.

use super::{FnBuilder, Lowerer, Val, span};
use gdshader::check::types::Type as GdType;
use gdshader::parse::ast;
use naga::{
    AddressSpace, BinaryOperator as Bo, Binding, BuiltIn, EntryPoint, Expression as E, FunctionArgument,
    FunctionResult, GlobalVariable, Handle, Literal, MathFunction as Mf, MemoryDecorations, ResourceBinding,
    ShaderStage, Span, Statement, Type, TypeInner, VectorSize,
};
use skycore::{DepthConvention, Projection};
use std::collections::HashMap;
use std::f64::consts::PI;

/// Fields of the built-ins uniform, in order (member indices).
pub const BUILTIN_FIELDS: [&str; 9] = [
    "camera_basis",
    "position",
    "time",
    "screen_size",
    "tan_half_fov",
    "render_pass",
    "luminance_multiplier",
    "cube_face",
    "lights",
];
/// Fields of one light, in order.
pub const LIGHT_FIELDS: [&str; 5] = ["direction", "energy", "color", "size", "enabled"];

const CAMERA_BASIS: u32 = 0;
const POSITION: u32 = 1;
const TIME: u32 = 2;
const SCREEN_SIZE: u32 = 3;
const TAN_HALF_FOV: u32 = 4;
const PASS: u32 = 5;
const LUMINANCE: u32 = 6;
const CUBE_FACE: u32 = 7;
const LIGHTS: u32 = 8;

/// Values of the `render_pass` field.
pub const PASS_FULL: u32 = 0;
/// Half-resolution sub-pass.
pub const PASS_HALF: u32 = 1;
/// Quarter-resolution sub-pass.
pub const PASS_QUARTER: u32 = 2;
/// A cubemap (radiance) face.
pub const PASS_CUBEMAP: u32 = 3;

/// What the fragment entry points do for a shader with `render_mode use_debanding`.
///
/// Godot 4.x (Forward+/Mobile, `servers/rendering/renderer_rd/shaders/environment/sky.glsl`)
/// compiles the sky pass with `#define USE_DEBANDING` and, as its last step, adds
/// `interleaved_gradient_noise(gl_FragCoord.xy) * luminance_multiplier`, where the noise is
/// `r = fract(52.9829189 · fract(dot(pos, (0.06711056, 0.00583715)))) · 2 − 1` and
/// `vec3(r, −r, r) / 255`: ±1/255 per channel in COLOR's units, a pattern fixed per pixel.
/// It is a compile-time switch in Godot (a define), so it is a lowering option here, not a
/// field of the built-ins block (whose layout hosts fill without reflection). See
/// docs/godot.md, "Debanding".
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Debanding {
    /// No noise: the shader's linear COLOR (for error measurement, where the dither is noise).
    None,
    /// Godot's interleaved-gradient-noise dither, added where Godot adds it: for a shader that
    /// declares `use_debanding` (the default, as in Godot).
    #[default]
    Godot,
}

impl Debanding {
    /// The names `--debanding` takes.
    pub const NAMES: [&'static str; 2] = ["none", "godot"];
}

impl std::str::FromStr for Debanding {
    type Err = String;

    /// `none` or `godot`.
    fn from_str(name: &str) -> Result<Self, String> {
        match name {
            "none" => Ok(Debanding::None),
            "godot" => Ok(Debanding::Godot),
            _ => Err(format!("`{name}` is no debanding; expected one of: none, godot")),
        }
    }
}

/// How the wrapper computes SKY_COORDS from EYEDIR.
///
/// Godot 4.3–4.5 use exact `atan2`/`acos`. Godot 4.6, the newest Godot the oracle runs and so the
/// default,
/// (both renderers' sky.glsl, including the Compatibility renderer the oracle runs) uses
/// polynomial approximations, Eberly's (`acos_approx`: (π/2 − 0.156583·|x|)·√(1 − |x|), mirrored
/// for x < 0; `atan2_approx`: a·(1 + s·(−0.301895 + 0.0872929·s)) with a = min/max of |x|, |y|,
/// s = a², then the octant folds), which move SKY_COORDS by up to 2.9e-3 in v and 2.2e-4 in u
/// (measured through the oracle, docs/godot.md). A texture of independent texels sampled at
/// SKY_COORDS (a hashed star field) lands on other texels; [`SkyCoords::Godot46`] reproduces
/// Godot 4.6's values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SkyCoords {
    /// `atan2(d.x, −d.z) / 2π` wrapped to [0, 1), `acos(d.y) / π`, as Godot 4.3–4.5.
    Exact,
    /// Godot 4.6's `atan2_approx` and `acos_approx`, in its order of operations (the default).
    #[default]
    Godot46,
}

impl SkyCoords {
    /// The names `--sky-coords` takes.
    pub const NAMES: [&'static str; 2] = ["exact", "godot46"];
}

impl std::str::FromStr for SkyCoords {
    type Err = String;

    /// `exact` or `godot46`.
    fn from_str(name: &str) -> Result<Self, String> {
        match name {
            "exact" => Ok(SkyCoords::Exact),
            "godot46" => Ok(SkyCoords::Godot46),
            _ => Err(format!("`{name}` is no SKY_COORDS mode; expected one of: exact, godot46")),
        }
    }
}

/// The per-pixel built-ins, which live in private globals.
const PRIVATES: [(&str, &str); 9] = [
    ("HALF_RES_COLOR", "vec4"),
    ("QUARTER_RES_COLOR", "vec4"),
    ("EYEDIR", "vec3"),
    ("SCREEN_UV", "vec2"),
    ("SKY_COORDS", "vec2"),
    ("FRAGCOORD", "vec4"),
    ("COLOR", "vec3"),
    ("ALPHA", "float"),
    ("FOG", "vec4"),
];

/// The wrapper's globals.
#[derive(Default)]
pub struct Builtins {
    global: Option<Handle<GlobalVariable>>,
    privates: HashMap<&'static str, Handle<GlobalVariable>>,
}

impl Builtins {
    /// Declares the built-ins uniform and the private globals the shader uses.
    pub(crate) fn declare(lw: &mut Lowerer<'_>) {
        let f = GdType::FLOAT;
        let (Some(f32t), Some(u32t), Some(v2), Some(v3), Some(m3)) = (
            lw.ty(&f, ast::Span::default()),
            lw.ty(&GdType::UINT, ast::Span::default()),
            lw.ty(&GdType::Vector(gdshader::check::types::Scalar::Float, 2), ast::Span::default()),
            lw.ty(&GdType::Vector(gdshader::check::types::Scalar::Float, 3), ast::Span::default()),
            lw.ty(&GdType::Matrix(3), ast::Span::default()),
        ) else {
            return;
        };
        let light = lw.struct_type(
            "SkyLight",
            &[
                ("direction".into(), v3),
                ("energy".into(), f32t),
                ("color".into(), v3),
                ("size".into(), f32t),
                ("enabled".into(), u32t),
            ],
            true,
        );
        let lights = lw.uniform_array(light, 4);
        let fields = [m3, v3, f32t, v2, f32t, u32t, f32t, u32t, lights];
        let members: Vec<(String, Handle<Type>)> = BUILTIN_FIELDS.iter().map(|n| n.to_string()).zip(fields).collect();
        let ty = lw.struct_type("SkyBuiltins", &members, true);
        let global = lw.module.global_variables.append(
            GlobalVariable {
                name: Some("sky_builtins".into()),
                space: AddressSpace::Uniform,
                binding: Some(ResourceBinding { group: 0, binding: 0 }),
                ty,
                init: None,
                memory_decorations: MemoryDecorations::empty(),
            },
            Span::UNDEFINED,
        );
        lw.builtins.global = Some(global);
        for (name, ty_name) in PRIVATES {
            if !lw.shader.builtins_used.contains(name) {
                continue;
            }
            let Some(ty) = GdType::from_name(ty_name).and_then(|t| lw.ty(&t, ast::Span::default())) else {
                continue;
            };
            let g = lw.module.global_variables.append(
                GlobalVariable {
                    name: Some(name.into()),
                    space: AddressSpace::Private,
                    binding: None,
                    ty,
                    init: None,
                    memory_decorations: MemoryDecorations::empty(),
                },
                Span::UNDEFINED,
            );
            lw.builtins.privates.insert(name, g);
        }
        // Group 2: the sky's own textures, each with a sampler, declared only when used.
        for (builtin, name, kind, binding) in SKY_TEXTURES {
            if lw.shader.builtins_used.contains(builtin) {
                lw.sky_texture(name, kind, binding);
            }
        }
    }
}

/// The bind group of the sky's own textures (RADIANCE, HALF_RES_COLOR, QUARTER_RES_COLOR).
pub const SKY_TEXTURE_GROUP: u32 = 2;

/// The sky's own textures: the built-in that needs it, the texture's global name, dimension,
/// and texture binding (its sampler is the next binding).
pub const SKY_TEXTURES: [(&str, &str, gdshader::check::types::SamplerKind, u32); 3] = [
    ("RADIANCE", "RADIANCE", gdshader::check::types::SamplerKind::Cube, 0),
    ("HALF_RES_COLOR", "half_res_color", gdshader::check::types::SamplerKind::Tex2D, 2),
    ("QUARTER_RES_COLOR", "quarter_res_color", gdshader::check::types::SamplerKind::Tex2D, 4),
];

fn load_field(b: &mut FnBuilder, global: Handle<GlobalVariable>, path: &[u32], sp: Span) -> Handle<E> {
    let mut h = b.expr(E::GlobalVariable(global), sp);
    for &i in path {
        h = b.expr(E::AccessIndex { base: h, index: i }, sp);
    }
    b.expr(E::Load { pointer: h }, sp)
}

fn eq_u32(b: &mut FnBuilder, v: Handle<E>, k: u32, sp: Span) -> Handle<E> {
    let k = b.expr(E::Literal(Literal::U32(k)), sp);
    b.expr(E::Binary { op: Bo::Equal, left: v, right: k }, sp)
}

/// Reads a built-in variable in a function body (`None` when gdsky cannot supply it).
pub(crate) fn read_builtin(
    lw: &mut Lowerer,
    b: &mut FnBuilder,
    name: &str,
    _ty: &GdType,
    at: ast::Span,
) -> Option<Val> {
    let sp = span(at);
    if let Some(v) = gdshader::check::builtins::builtin_constant(name) {
        return Some(Val::Value(b.expr(E::Literal(crate::lower::f32_literal(v)), sp)));
    }
    if let Some(g) = lw.builtins.privates.get(name) {
        return Some(Val::Pointer(b.expr(E::GlobalVariable(*g), sp)));
    }
    let global = lw.builtins.global?;
    let value = match name {
        "TIME" => load_field(b, global, &[TIME], sp),
        "POSITION" => load_field(b, global, &[POSITION], sp),
        "AT_HALF_RES_PASS" | "AT_QUARTER_RES_PASS" | "AT_CUBEMAP_PASS" => {
            let pass = load_field(b, global, &[PASS], sp);
            let k = match name {
                "AT_HALF_RES_PASS" => PASS_HALF,
                "AT_QUARTER_RES_PASS" => PASS_QUARTER,
                _ => PASS_CUBEMAP,
            };
            eq_u32(b, pass, k, sp)
        }
        _ => {
            let rest = name.strip_prefix("LIGHT")?;
            let (n, field) = rest.split_once('_')?;
            let n: u32 = n.parse().ok()?;
            let index = LIGHT_FIELDS.iter().position(|f| f.eq_ignore_ascii_case(field))? as u32;
            let v = load_field(b, global, &[LIGHTS, n, index], sp);
            if field == "ENABLED" {
                let zero = b.expr(E::Literal(Literal::U32(0)), sp);
                b.expr(E::Binary { op: Bo::NotEqual, left: v, right: zero }, sp)
            } else {
                v
            }
        }
    };
    Some(Val::Value(value))
}

/// Adds the vertex entry point and one fragment entry point per projection.
pub(crate) fn entry_points(lw: &mut Lowerer) {
    let Some(global) = lw.builtins.global else {
        return;
    };
    vertex(lw);
    for p in Projection::ENTRIES {
        fragment(lw, global, p);
    }
}

/// The depth convention of a module's `vs_main` (where it puts the sky: its position's z, with w
/// 1). `None` when the module has no `vs_main` of the wrapper's form (a module not built by
/// gdsky, or WGSL from before the sky moved to the far plane, which drew it at 0).
pub fn depth_convention(module: &naga::Module) -> Option<DepthConvention> {
    let (function, z) = vertex_depth(module)?;
    match function.expressions[z] {
        E::Literal(Literal::F32(v)) => {
            [DepthConvention::Standard, DepthConvention::Reversed].into_iter().find(|c| c.far_plane() == v)
        }
        _ => None,
    }
}

fn vertex_depth(module: &naga::Module) -> Option<(&naga::Function, Handle<E>)> {
    let entry = module.entry_points.iter().find(|e| e.name == "vs_main" && e.stage == ShaderStage::Vertex)?;
    let function = &entry.function;
    let value = function.body.iter().find_map(|s| match s {
        Statement::Return { value: Some(v) } => Some(*v),
        _ => None,
    })?;
    match &function.expressions[value] {
        E::Compose { components, .. } if components.len() == 4 => Some((function, components[2])),
        _ => None,
    }
}

fn vertex(lw: &mut Lowerer) {
    let sp = Span::UNDEFINED;
    let (Some(u32t), Some(v4)) = (
        lw.ty(&GdType::UINT, ast::Span::default()),
        lw.ty(&GdType::Vector(gdshader::check::types::Scalar::Float, 4), ast::Span::default()),
    ) else {
        return;
    };
    let mut b = FnBuilder::new("vs_main");
    b.function.arguments.push(FunctionArgument {
        name: Some("vertex_index".into()),
        ty: u32t,
        binding: Some(Binding::BuiltIn(BuiltIn::VertexIndex)),
    });
    b.function.result =
        Some(FunctionResult { ty: v4, binding: Some(Binding::BuiltIn(BuiltIn::Position { invariant: false })) });
    // The triangle (-1,-1), (3,-1), (-1,3) covers the screen.
    let vi = b.expr(E::FunctionArgument(0), sp);
    let one_u = b.expr(E::Literal(Literal::U32(1)), sp);
    let two_u = b.expr(E::Literal(Literal::U32(2)), sp);
    let shifted = b.expr(E::Binary { op: Bo::ShiftLeft, left: vi, right: one_u }, sp);
    let xu = b.expr(E::Binary { op: Bo::And, left: shifted, right: two_u }, sp);
    let yu = b.expr(E::Binary { op: Bo::And, left: vi, right: two_u }, sp);
    let xf = b.expr(E::As { expr: xu, kind: naga::ScalarKind::Float, convert: Some(4) }, sp);
    let yf = b.expr(E::As { expr: yu, kind: naga::ScalarKind::Float, convert: Some(4) }, sp);
    let two = b.expr(E::Literal(Literal::F32(2.0)), sp);
    let one = b.expr(E::Literal(Literal::F32(1.0)), sp);
    // The sky lies on the far plane (w = 1, so this is the depth), as Godot draws it behind
    // its geometry: a depth test against what was drawn first skips every covered pixel.
    let far = b.expr(E::Literal(Literal::F32(lw.options.depth.far_plane())), sp);
    let x2 = b.expr(E::Binary { op: Bo::Multiply, left: xf, right: two }, sp);
    let y2 = b.expr(E::Binary { op: Bo::Multiply, left: yf, right: two }, sp);
    let x = b.expr(E::Binary { op: Bo::Subtract, left: x2, right: one }, sp);
    let y = b.expr(E::Binary { op: Bo::Subtract, left: y2, right: one }, sp);
    let pos = b.expr(E::Compose { ty: v4, components: vec![x, y, far, one] }, sp);
    b.stmt(Statement::Return { value: Some(pos) }, sp);
    add_entry_point(lw, "vs_main", ShaderStage::Vertex, b);
}

fn fragment(lw: &mut Lowerer, global: Handle<GlobalVariable>, projection: Projection) {
    let sp = Span::UNDEFINED;
    let fl = |lw: &mut Lowerer, n: u8| {
        lw.ty(&GdType::vector_of(gdshader::check::types::Scalar::Float, n), ast::Span::default())
    };
    let (Some(v2t), Some(v3t), Some(v4t)) = (fl(lw, 2), fl(lw, 3), fl(lw, 4)) else {
        return;
    };
    let mut b = FnBuilder::new(projection.entry_point());
    b.function.arguments.push(FunctionArgument {
        name: Some("frag_coord".into()),
        ty: v4t,
        binding: Some(Binding::BuiltIn(BuiltIn::Position { invariant: false })),
    });
    b.function.result = Some(FunctionResult {
        ty: v4t,
        binding: Some(Binding::Location {
            location: 0,
            interpolation: None,
            sampling: None,
            blend_src: None,
            per_primitive: false,
        }),
    });
    let f = |b: &mut FnBuilder, v: f64| b.expr(E::Literal(crate::lower::f32_literal(v)), sp);
    let bin = |b: &mut FnBuilder, op, l, r| b.expr(E::Binary { op, left: l, right: r }, sp);
    let math = |b: &mut FnBuilder, fun, args: &[Handle<E>]| {
        b.expr(E::Math { fun, arg: args[0], arg1: args.get(1).copied(), arg2: args.get(2).copied(), arg3: None }, sp)
    };
    let frag_coord = b.expr(E::FunctionArgument(0), sp);
    let xy = b.head(frag_coord, 2, sp);
    let screen = load_field(&mut b, global, &[SCREEN_SIZE], sp);
    let uv = bin(&mut b, Bo::Divide, xy, screen);
    let u = b.expr(E::AccessIndex { base: uv, index: 0 }, sp);
    let v = b.expr(E::AccessIndex { base: uv, index: 1 }, sp);
    let dir = match projection {
        Projection::Panorama => {
            // The inverse of SKY_COORDS: u = atan2(x, -z) / 2π, v = acos(y) / π.
            let tau = f(&mut b, 2.0 * PI);
            let pi = f(&mut b, PI);
            let phi = bin(&mut b, Bo::Multiply, u, tau);
            let theta = bin(&mut b, Bo::Multiply, v, pi);
            let (st, ct) = (math(&mut b, Mf::Sin, &[theta]), math(&mut b, Mf::Cos, &[theta]));
            let (sphi, cphi) = (math(&mut b, Mf::Sin, &[phi]), math(&mut b, Mf::Cos, &[phi]));
            let x = bin(&mut b, Bo::Multiply, st, sphi);
            let zc = bin(&mut b, Bo::Multiply, st, cphi);
            let z = b.expr(E::Unary { op: naga::UnaryOperator::Negate, expr: zc }, sp);
            b.expr(E::Compose { ty: v3t, components: vec![x, ct, z] }, sp)
        }
        Projection::Camera | Projection::CubeFace(_) => {
            // Godot's camera ray: ((2u − 1)·t·aspect, (1 − 2v)·t, −1), rotated by the basis.
            let (one, two) = (f(&mut b, 1.0), f(&mut b, 2.0));
            let u2 = bin(&mut b, Bo::Multiply, u, two);
            let nx = bin(&mut b, Bo::Subtract, u2, one);
            let v2 = bin(&mut b, Bo::Multiply, v, two);
            let ny = bin(&mut b, Bo::Subtract, one, v2);
            let (basis, t) = if projection == Projection::Camera {
                (load_field(&mut b, global, &[CAMERA_BASIS], sp), load_field(&mut b, global, &[TAN_HALF_FOV], sp))
            } else {
                (cube_basis(lw, &mut b, global, sp), f(&mut b, 1.0))
            };
            let sx = b.expr(E::AccessIndex { base: screen, index: 0 }, sp);
            let sy = b.expr(E::AccessIndex { base: screen, index: 1 }, sp);
            let aspect = bin(&mut b, Bo::Divide, sx, sy);
            let nxt = bin(&mut b, Bo::Multiply, nx, t);
            let x = bin(&mut b, Bo::Multiply, nxt, aspect);
            let y = bin(&mut b, Bo::Multiply, ny, t);
            let minus_one = f(&mut b, -1.0);
            let ray = b.expr(E::Compose { ty: v3t, components: vec![x, y, minus_one] }, sp);
            let world = bin(&mut b, Bo::Multiply, basis, ray);
            math(&mut b, Mf::Normalize, &[world])
        }
    };
    let set = |lw: &Lowerer, b: &mut FnBuilder, name: &str, value: Handle<E>| {
        if let Some(g) = lw.builtins.privates.get(name) {
            let p = b.expr(E::GlobalVariable(*g), sp);
            b.stmt(Statement::Store { pointer: p, value }, sp);
        }
    };
    set(lw, &mut b, "EYEDIR", dir);
    set(lw, &mut b, "SCREEN_UV", uv);
    set(lw, &mut b, "FRAGCOORD", frag_coord);
    if lw.builtins.privates.contains_key("SKY_COORDS") {
        // u = atan2(d.x, −d.z) / 2π wrapped to [0, 1); v = acos(d.y) / π.
        let dx = b.expr(E::AccessIndex { base: dir, index: 0 }, sp);
        let dy = b.expr(E::AccessIndex { base: dir, index: 1 }, sp);
        let dz = b.expr(E::AccessIndex { base: dir, index: 2 }, sp);
        let ndz = b.expr(E::Unary { op: naga::UnaryOperator::Negate, expr: dz }, sp);
        let (su, sv) = match lw.options.sky_coords {
            SkyCoords::Exact => {
                let a = math(&mut b, Mf::Atan2, &[dx, ndz]);
                let tau = f(&mut b, 2.0 * PI);
                let su = bin(&mut b, Bo::Divide, a, tau);
                let su = math(&mut b, Mf::Fract, &[su]);
                let ac = math(&mut b, Mf::Acos, &[dy]);
                let pi = f(&mut b, PI);
                (su, bin(&mut b, Bo::Divide, ac, pi))
            }
            SkyCoords::Godot46 => {
                // panorama_coords = (atan2_approx(x, −z), acos_approx(y)); x += 2π where < 0;
                // then divided by (2π, π).
                let a = atan2_approx(&mut b, dx, ndz);
                let zero = f(&mut b, 0.0);
                let negative = bin(&mut b, Bo::Less, a, zero);
                let tau = f(&mut b, 2.0 * PI);
                let wrapped = bin(&mut b, Bo::Add, a, tau);
                let a = b.expr(E::Select { condition: negative, accept: wrapped, reject: a }, sp);
                let su = bin(&mut b, Bo::Divide, a, tau);
                let ac = acos_approx(&mut b, dy);
                let pi = f(&mut b, PI);
                (su, bin(&mut b, Bo::Divide, ac, pi))
            }
        };
        let coords = b.expr(E::Compose { ty: v2t, components: vec![su, sv] }, sp);
        set(lw, &mut b, "SKY_COORDS", coords);
    }
    let zero3 = f(&mut b, 0.0);
    let zero3 = b.expr(E::Splat { size: VectorSize::Tri, value: zero3 }, sp);
    set(lw, &mut b, "COLOR", zero3);
    let one = f(&mut b, 1.0);
    set(lw, &mut b, "ALPHA", one);
    let zero4 = f(&mut b, 0.0);
    let zero4 = b.expr(E::Splat { size: VectorSize::Quad, value: zero4 }, sp);
    set(lw, &mut b, "FOG", zero4);
    for (name, texture) in [("HALF_RES_COLOR", "half_res_color"), ("QUARTER_RES_COLOR", "quarter_res_color")] {
        // Godot samples the sub-pass at SCREEN_UV, LOD 0, and divides by the luminance
        // multiplier to return to shader units.
        let Some(slot) = lw.textures.get(texture).cloned() else {
            continue;
        };
        let image = b.expr(E::GlobalVariable(slot.image), sp);
        let sampler = b.expr(E::GlobalVariable(slot.sampler), sp);
        let texel = b.expr(
            E::ImageSample {
                image,
                sampler,
                gather: None,
                coordinate: uv,
                array_index: None,
                offset: None,
                level: naga::SampleLevel::Zero,
                depth_ref: None,
                clamp_to_edge: false,
            },
            sp,
        );
        let lum = load_field(&mut b, global, &[LUMINANCE], sp);
        let lum = b.expr(E::Splat { size: VectorSize::Quad, value: lum }, sp);
        let value = bin(&mut b, Bo::Divide, texel, lum);
        set(lw, &mut b, name, value);
    }
    if let Some(sky) = lw.sky_function {
        b.stmt(Statement::Call { function: sky, arguments: Vec::new(), result: None }, sp);
    }
    let read = |lw: &Lowerer, b: &mut FnBuilder, name: &str| {
        lw.builtins.privates.get(name).map(|g| {
            let p = b.expr(E::GlobalVariable(*g), sp);
            b.expr(E::Load { pointer: p }, sp)
        })
    };
    let mut rgb = read(lw, &mut b, "COLOR").unwrap_or(zero3);
    let alpha = read(lw, &mut b, "ALPHA").unwrap_or(one);
    let pass = load_field(&mut b, global, &[PASS], sp);
    let is_cubemap = eq_u32(&mut b, pass, PASS_CUBEMAP, sp);
    if !lw.shader.render_modes.iter().any(|m| m == "disable_fog")
        && let Some(fog) = read(lw, &mut b, "FOG")
    {
        // Godot: if (FOG.a > 0) rgb = mix(rgb, FOG.rgb, FOG.a), never in the cubemap pass.
        let fa = b.expr(E::AccessIndex { base: fog, index: 3 }, sp);
        let frgb = b.head(fog, 3, sp);
        let mixed = math(&mut b, Mf::Mix, &[rgb, frgb, fa]);
        let zero = f(&mut b, 0.0);
        let has_fog = bin(&mut b, Bo::Greater, fa, zero);
        let not_cube = b.expr(E::Unary { op: naga::UnaryOperator::LogicalNot, expr: is_cubemap }, sp);
        let apply = bin(&mut b, Bo::LogicalAnd, has_fog, not_cube);
        rgb = b.expr(E::Select { condition: apply, accept: mixed, reject: rgb }, sp);
    }
    let lum = load_field(&mut b, global, &[LUMINANCE], sp);
    let mut rgb = bin(&mut b, Bo::Multiply, rgb, lum);
    if lw.options.debanding == Debanding::Godot && lw.shader.render_modes.iter().any(|m| m == "use_debanding") {
        // Godot's last step: frag_color.rgb += interleaved_gradient_noise(gl_FragCoord.xy) *
        // luminance_multiplier, with the noise's operations in its order.
        let magic = [f(&mut b, 0.06711056), f(&mut b, 0.00583715)];
        let magic = b.expr(E::Compose { ty: v2t, components: magic.to_vec() }, sp);
        let d = math(&mut b, Mf::Dot, &[xy, magic]);
        let inner = math(&mut b, Mf::Fract, &[d]);
        let z = f(&mut b, 52.9829189);
        let scaled = bin(&mut b, Bo::Multiply, z, inner);
        let outer = math(&mut b, Mf::Fract, &[scaled]);
        let two = f(&mut b, 2.0);
        let doubled = bin(&mut b, Bo::Multiply, outer, two);
        let one_f = f(&mut b, 1.0);
        let r = bin(&mut b, Bo::Subtract, doubled, one_f);
        let minus_r = b.expr(E::Unary { op: naga::UnaryOperator::Negate, expr: r }, sp);
        let noise = b.expr(E::Compose { ty: v3t, components: vec![r, minus_r, r] }, sp);
        let steps = f(&mut b, 255.0);
        let steps = b.expr(E::Splat { size: VectorSize::Tri, value: steps }, sp);
        let noise = bin(&mut b, Bo::Divide, noise, steps);
        let noise = bin(&mut b, Bo::Multiply, noise, lum);
        rgb = bin(&mut b, Bo::Add, rgb, noise);
    }
    // Alpha is kept only where Godot keeps it: the sub-passes and the cubemap.
    let full = eq_u32(&mut b, pass, PASS_FULL, sp);
    let zero = f(&mut b, 0.0);
    let alpha = b.expr(E::Select { condition: full, accept: zero, reject: alpha }, sp);
    let out = b.expr(E::Compose { ty: v4t, components: vec![rgb, alpha] }, sp);
    b.stmt(Statement::Return { value: Some(out) }, sp);
    add_entry_point(lw, projection.entry_point(), ShaderStage::Fragment, b);
}

/// A float literal in the wrapper's functions (no span: the wrapper's code is not the user's).
fn lit(b: &mut FnBuilder, v: f64) -> Handle<E> {
    b.expr(E::Literal(crate::lower::f32_literal(v)), Span::UNDEFINED)
}

/// A binary operation in the wrapper's functions.
fn binop(b: &mut FnBuilder, op: Bo, left: Handle<E>, right: Handle<E>) -> Handle<E> {
    b.expr(E::Binary { op, left, right }, Span::UNDEFINED)
}

/// A math function of one or two arguments in the wrapper's functions.
fn mathf(b: &mut FnBuilder, fun: Mf, args: &[Handle<E>]) -> Handle<E> {
    b.expr(E::Math { fun, arg: args[0], arg1: args.get(1).copied(), arg2: None, arg3: None }, Span::UNDEFINED)
}

/// Godot 4.6's `acos_approx(x)`: `res = (−0.156583·|x| + π/2)·√(1 − |x|)`, `π − res` for x < 0.
fn acos_approx(b: &mut FnBuilder, x: Handle<E>) -> Handle<E> {
    let sp = Span::UNDEFINED;
    let ax = mathf(b, Mf::Abs, &[x]);
    let k = lit(b, -0.156583);
    let half_pi = lit(b, PI / 2.0);
    let lin = binop(b, Bo::Multiply, k, ax);
    let res = binop(b, Bo::Add, lin, half_pi);
    let one = lit(b, 1.0);
    let rest = binop(b, Bo::Subtract, one, ax);
    let root = mathf(b, Mf::Sqrt, &[rest]);
    let res = binop(b, Bo::Multiply, res, root);
    let zero = lit(b, 0.0);
    let non_negative = binop(b, Bo::GreaterEqual, x, zero);
    let pi = lit(b, PI);
    let mirrored = binop(b, Bo::Subtract, pi, res);
    b.expr(E::Select { condition: non_negative, accept: res, reject: mirrored }, sp)
}

/// Godot 4.6's `atan2_approx(y, x)`: `a = min(|x|, |y|) / max(|x|, |y|)`, `s = a²`,
/// `poly = (1 + (−0.301895 + 0.0872929·s)·s)·a`, then `π/2 − poly` where |y| > |x|, `π − r`
/// where x < 0, `−r` where y < 0.
fn atan2_approx(b: &mut FnBuilder, y: Handle<E>, x: Handle<E>) -> Handle<E> {
    let sp = Span::UNDEFINED;
    let (ax, ay) = (mathf(b, Mf::Abs, &[x]), mathf(b, Mf::Abs, &[y]));
    let lo = mathf(b, Mf::Min, &[ax, ay]);
    let hi = mathf(b, Mf::Max, &[ax, ay]);
    let a = binop(b, Bo::Divide, lo, hi);
    let s = binop(b, Bo::Multiply, a, a);
    let c2 = lit(b, 0.0872929);
    let c1 = lit(b, -0.301895);
    let poly = binop(b, Bo::Multiply, c2, s);
    let poly = binop(b, Bo::Add, c1, poly);
    let poly = binop(b, Bo::Multiply, poly, s);
    let one = lit(b, 1.0);
    let poly = binop(b, Bo::Add, one, poly);
    let poly = binop(b, Bo::Multiply, poly, a);
    let half_pi = lit(b, PI / 2.0);
    let steep = binop(b, Bo::Greater, ay, ax);
    let folded = binop(b, Bo::Subtract, half_pi, poly);
    let r = b.expr(E::Select { condition: steep, accept: folded, reject: poly }, sp);
    let zero = lit(b, 0.0);
    let x_negative = binop(b, Bo::Less, x, zero);
    let pi = lit(b, PI);
    let back = binop(b, Bo::Subtract, pi, r);
    let r = b.expr(E::Select { condition: x_negative, accept: back, reject: r }, sp);
    let y_negative = binop(b, Bo::Less, y, zero);
    let neg = b.expr(E::Unary { op: naga::UnaryOperator::Negate, expr: r }, sp);
    b.expr(E::Select { condition: y_negative, accept: neg, reject: r }, sp)
}

/// The basis of the cube face selected by the `cube_face` field, from a constant table.
fn cube_basis(lw: &mut Lowerer, b: &mut FnBuilder, global: Handle<GlobalVariable>, sp: Span) -> Handle<E> {
    let (Some(m3), Some(v3)) = (
        lw.ty(&GdType::Matrix(3), ast::Span::default()),
        lw.ty(&GdType::Vector(gdshader::check::types::Scalar::Float, 3), ast::Span::default()),
    ) else {
        return b.expr(E::Literal(Literal::F32(0.0)), sp);
    };
    let table_ty = lw.module.types.insert(
        Type {
            name: None,
            inner: TypeInner::Array {
                base: m3,
                size: naga::ArraySize::Constant(std::num::NonZeroU32::new(6).unwrap_or(std::num::NonZeroU32::MIN)),
                stride: 48,
            },
        },
        Span::UNDEFINED,
    );
    let ge = &mut lw.module.global_expressions;
    let faces = (0..6)
        .map(|face| {
            let basis = skycore::cube_face_basis(face);
            let cols = [basis.x_axis, basis.y_axis, basis.z_axis]
                .iter()
                .map(|c| {
                    // The axes are exact: 0 and ±1.
                    let comps =
                        c.to_array().iter().map(|&x| ge.append(E::Literal(Literal::F32(x as f32)), sp)).collect();
                    ge.append(E::Compose { ty: v3, components: comps }, sp)
                })
                .collect();
            ge.append(E::Compose { ty: m3, components: cols }, sp)
        })
        .collect();
    let init = ge.append(E::Compose { ty: table_ty, components: faces }, sp);
    let table = lw.module.constants.append(naga::Constant { name: Some("CUBE_FACES".into()), ty: table_ty, init }, sp);
    let face = load_field(b, global, &[CUBE_FACE], sp);
    let c = b.expr(E::Constant(table), sp);
    let tmp = b.local(Some("cube_faces"), table_ty, sp);
    b.stmt(Statement::Store { pointer: tmp, value: c }, sp);
    let p = b.expr(E::Access { base: tmp, index: face }, sp);
    b.expr(E::Load { pointer: p }, sp)
}

/// Adds a finished entry-point function to the module.
fn add_entry_point(lw: &mut Lowerer, name: &str, stage: ShaderStage, b: FnBuilder) {
    lw.module.entry_points.push(EntryPoint {
        name: name.into(),
        stage,
        early_depth_test: None,
        workgroup_size: [0; 3],
        workgroup_size_overrides: None,
        function: b.finish(),
        mesh_info: None,
        task_payload: None,
        incoming_ray_payload: None,
    });
}

//! # gdsky-naga: Godot sky shaders as naga IR
//!
//! Takes the front end's [`CheckedShader`](gdshader::CheckedShader) and builds a
//! [`naga::Module`] directly — arenas, types, constants, globals, functions and entry points —
//! with no GLSL or WGSL text in between, then validates it with naga and writes WGSL and
//! SPIR-V with naga's back ends.
//!
//! * `lower/` walks the checked tree and builds the module (see its essay for the semantics
//!   written out explicitly: floored `mod`, NaN-proof `max`/`min`/`clamp`, lazy `&&`/`?:`,
//!   copy-in/copy-out `out` arguments, `bool` uniforms as `u32`).
//! * `opt/` removes what no entry point needs (unreachable functions, unused constants and
//!   values) before validation; see its essay for what the lowering itself leaves out.
//! * `wrapper.rs` adds Godot's sky wrapper: the built-ins uniform (group 0), per-pixel
//!   built-ins, the fullscreen-triangle vertex entry and one fragment entry per projection.
//! * `trace/` instruments a validated module to record, per pixel, the first expression that
//!   made a NaN or an infinity, with a table of those expressions' places in the source
//!   (`gdsky render --trace-nonfinite`).
//!
//! Every naga expression carries the span of the shader text it came from, so a validation
//! error is reported at the user's file and line ([`lower`] maps it through the source map);
//! code the wrapper injects carries no span and is reported as the wrapper's.

mod emit;
mod lower;
mod opt;
pub mod reflect;
pub mod trace;
mod widen;
pub mod wrapper;

pub use emit::{EmitError, exact_arithmetic, reread_wgsl, to_spirv, to_wgsl};
pub use lower::{GLOBAL_UNIFORM_GROUP, MATERIAL_GROUP, TextureSlot, UniformSlot};
pub use widen::{F64_MATH_WGSL, F64Output};
pub use wrapper::{Debanding, SkyCoords};

use gdshader::parse::ast;
use gdshader::{Diagnostic, FrontendOutput};
use naga::valid::{Capabilities, ModuleInfo, ValidationFlags, Validator};
use std::collections::HashMap;

/// Diagnostic code for a construct the lowering does not support yet.
pub const UNSUPPORTED: &str = "E600";
/// Diagnostic code for a module naga's validator rejects (a bug in gdsky's lowering).
pub const INVALID_MODULE: &str = "E601";
/// Diagnostic code for a back end that could not write the module.
pub const BACKEND: &str = "E602";
/// Diagnostic code for a `--set NAME=VALUE` that names no uniform or does not fit its type, or an
/// `--override NAME` that names no scalar material uniform.
pub const BAD_SET: &str = "E603";
/// Diagnostic code for emitted WGSL or SPIR-V that naga's own front end cannot read back or
/// validate (a bug in gdsky's translation; nothing is written).
pub const REREAD: &str = "E604";

/// Something the lowering could not translate, at a span of the checked shader.
#[derive(Clone, Debug)]
pub struct LowerError {
    span: ast::Span,
    message: String,
}

/// A validated naga module of a sky shader.
pub struct Lowered {
    /// The module.
    pub module: naga::Module,
    /// naga's validation result, which the back ends need.
    pub info: ModuleInfo,
    /// Where each uniform lives in the material block (group [`MATERIAL_GROUP`], binding 0).
    pub uniforms: HashMap<String, UniformSlot>,
    /// Size in bytes of the material block (0 when the shader has no uniforms).
    pub material_size: u32,
    /// Sampler uniforms: a texture and a sampler each in group [`MATERIAL_GROUP`].
    pub textures: HashMap<String, TextureSlot>,
}

/// Lowers and validates a checked shader. Errors come back as diagnostics located in the
/// user's files.
pub fn lower(front: &FrontendOutput) -> Result<Lowered, Vec<Diagnostic>> {
    lower_with(front, &HashMap::new())
}

/// Like [`lower`], with uniforms baked into constants: `baked` maps a uniform's name to the text
/// of its value (`1.5`, `24`, `true`, `0.1,0.2,0.3`), as `gdsky convert --set` takes it.
pub fn lower_with(front: &FrontendOutput, baked: &HashMap<String, String>) -> Result<Lowered, Vec<Diagnostic>> {
    // The lowering recurses over the expression tree, which the front end lets grow to
    // `MAX_EXPR_DEPTH` (a chain of 2,048 operators): it gets the front end's deep stack rather
    // than whatever thread called it (a test thread has 2 MiB).
    on_lowering_thread(|| lower_here(front, baked, Debanding::None, SkyCoords::Exact))?
}

/// Runs `f` on a thread with the lowering's deep stack.
fn on_lowering_thread<T: Send>(f: impl FnOnce() -> T + Send) -> Result<T, Vec<Diagnostic>> {
    std::thread::scope(|scope| {
        std::thread::Builder::new()
            .stack_size(LOWERING_STACK_BYTES)
            .spawn_scoped(scope, f)
            .map_err(|e| vec![Diagnostic::error(UNSUPPORTED, format!("cannot start the lowering's thread: {e}"))])?
            .join()
            .map_err(|_| {
                vec![Diagnostic::error(INVALID_MODULE, "the lowering panicked: a bug in gdsky; please report it")]
            })
    })
}

/// Like [`lower_with`], and the module evaluates the shader in f64: every float of the shader's
/// code and of the sky wrapper is an f64, the uniform blocks, textures and outputs stay f32 and
/// are converted where they are read or written, and the transcendentals GLSL.std.450 has only
/// in f32 are f64 routines grafted into the module. `output` says what the fragment entries
/// return ([`F64Output`]). The material block's layout is the f32 module's (`uniforms`,
/// `material_size` and `textures` are those of [`lower_with`]). See the `widen` essay for
/// the rules and their limits. The module needs naga's `FLOAT64` capability ([`validator_f64`])
/// and a device with `shaderFloat64` (wgpu's `Features::SHADER_F64`); write it as SPIR-V with
/// [`to_spirv`] (WGSL has no f64).
pub fn lower_f64(
    front: &FrontendOutput,
    baked: &HashMap<String, String>,
    output: F64Output,
) -> Result<Lowered, Vec<Diagnostic>> {
    let (lowered, exact) = on_lowering_thread(|| {
        (lower_here(front, baked, Debanding::None, SkyCoords::Exact), lower::take_exact_floats())
    })?;
    let lowered = lowered?;
    let module = widen::widen(&lowered.module, &lowered.info, &exact, output).map_err(|why| {
        vec![Diagnostic::error(UNSUPPORTED, format!("the f64 evaluation cannot widen this shader: {why}"))]
    })?;
    let info = validator_f64().validate(&module).map_err(|err| vec![validation_diagnostic(front, &err)])?;
    Ok(Lowered { module, info, ..lowered })
}

/// Stack of the lowering's thread: like the front end's, enough for its deepest expression in an
/// unoptimised build, with a wide margin (only the pages touched are ever mapped).
const LOWERING_STACK_BYTES: usize = 256 << 20;

fn lower_here(
    front: &FrontendOutput,
    baked: &HashMap<String, String>,
    debanding: Debanding,
    sky_coords: SkyCoords,
) -> Result<Lowered, Vec<Diagnostic>> {
    let Some(shader) = front.shader.as_ref() else {
        return Err(front.diagnostics.clone());
    };
    let mut values = HashMap::new();
    let mut errors = Vec::new();
    for (name, text) in baked {
        let Some(u) = shader.uniforms.iter().find(|u| &u.name == name) else {
            let known: Vec<&str> = shader.uniforms.iter().map(|u| u.name.as_str()).collect();
            errors.push(
                Diagnostic::error(BAD_SET, format!("`--set {name}=…`: the shader has no uniform `{name}`"))
                    .with_note(format!("its uniforms are: {}", known.join(", "))),
            );
            continue;
        };
        match reflect::parse_value(&u.ty, text) {
            Ok(v) => {
                values.insert(name.clone(), v);
            }
            Err(why) => errors.push(
                Diagnostic::error(BAD_SET, format!("`--set {name}={text}`: {why}"))
                    .with_note(format!("`{name}` is a `{}`", u.type_name)),
            ),
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    let mut lw = lower::Lowerer::new(shader, values);
    lw.debanding = debanding;
    lw.sky_coords = sky_coords;
    lw.items();
    if !lw.errors.is_empty() {
        return Err(lw
            .errors
            .iter()
            .map(|e| {
                let (file, range) = front.locate(e.span);
                Diagnostic::error(UNSUPPORTED, e.message.clone()).with_primary(file, range, "")
            })
            .collect());
    }
    let uniforms = lw.uniforms;
    let material_size = lw.material_size;
    let textures = lw.textures;
    let module = lw.module;
    if let Some(span) = emit::too_deep_for_wgsl(&module).and_then(|s| s.to_range()) {
        let (file, range) = front.locate(ast::Span::new(span.start, span.end));
        return Err(vec![
            Diagnostic::error(UNSUPPORTED, "this statement nests blocks deeper than WGSL allows")
                .with_primary(file, range, "")
                .with_note(format!("WGSL (naga's front end) accepts at most {} nested braces", emit::MAX_WGSL_BRACES)),
        ]);
    }
    let module = {
        let mut module = module;
        opt::optimize(&mut module);
        module
    };
    let info = validate(front, &module).map_err(|d| vec![d])?;
    Ok(Lowered { module, info, uniforms, material_size, textures })
}

/// Like [`lower_with`], and each uniform named in `overrides` becomes a WGSL `override` (`@id(k)`
/// for the k-th name, defaulting to the uniform's default; a `bool` as a `u32` 0 or 1) instead of
/// a member of the material block: one module serves many values, given when the pipeline is
/// created (wgpu's `PipelineCompilationOptions::constants`, keyed by the id as text). Only scalar
/// material uniforms can be overrides. [`to_spirv`] writes each as a specialization constant
/// (`OpSpecConstant` decorated `SpecId k`, the same k).
pub fn lower_with_overrides(
    front: &FrontendOutput,
    baked: &HashMap<String, String>,
    overrides: &[String],
) -> Result<Lowered, Vec<Diagnostic>> {
    lower_with_options(front, baked, overrides, Debanding::None)
}

/// Like [`lower_with_overrides`], with Godot's sky debanding emulated when `debanding` is
/// [`Debanding::Godot`] and the shader declares `render_mode use_debanding` (see [`Debanding`]).
/// A shader without `use_debanding` lowers to the same module either way.
pub fn lower_with_options(
    front: &FrontendOutput,
    baked: &HashMap<String, String>,
    overrides: &[String],
    debanding: Debanding,
) -> Result<Lowered, Vec<Diagnostic>> {
    lower_for_godot(front, baked, overrides, debanding, SkyCoords::Exact)
}

/// [`lower_with_options`], with SKY_COORDS computed as `sky_coords` says ([`SkyCoords::Godot46`]:
/// Godot 4.6's approximate trigonometry). A shader that does not read SKY_COORDS lowers to the
/// same module either way.
pub fn lower_for_godot(
    front: &FrontendOutput,
    baked: &HashMap<String, String>,
    overrides: &[String],
    debanding: Debanding,
    sky_coords: SkyCoords,
) -> Result<Lowered, Vec<Diagnostic>> {
    let mut lowered = on_lowering_thread(|| lower_here(front, baked, debanding, sky_coords))??;
    if overrides.is_empty() {
        return Ok(lowered);
    }
    let Some(shader) = front.shader.as_ref() else {
        return Err(front.diagnostics.clone());
    };
    let mut errors = Vec::new();
    for (i, name) in overrides.iter().enumerate() {
        let why = match shader.uniforms.iter().find(|u| &u.name == name) {
            None => Some(format!("the shader has no uniform `{name}`")),
            Some(_) if baked.contains_key(name) => Some("it is baked by `--set` too".to_string()),
            Some(_) if overrides[..i].contains(name) => Some("it is named twice".to_string()),
            Some(u) if u.global || !matches!(u.ty, gdshader::check::types::Type::Scalar(_)) => Some(format!(
                "only scalar material uniforms can be overrides (WGSL overrides are scalars); `{name}` is a{} `{}`",
                if u.global { " global" } else { "" },
                u.type_name
            )),
            Some(_) if !lowered.uniforms.contains_key(name) => {
                Some(format!("`{name}` has no place in the material block"))
            }
            Some(_) => None,
        };
        if let Some(why) = why {
            errors.push(Diagnostic::error(BAD_SET, format!("`--override {name}`: {why}")));
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    opt::overrides::apply(&mut lowered, shader, overrides);
    opt::optimize(&mut lowered.module);
    lowered.info = validate(front, &lowered.module).map_err(|d| vec![d])?;
    Ok(lowered)
}

/// Validates a module lowered from `front` with naga; an error comes back as a diagnostic at
/// the shader's own lines (every expression's span points into the shader).
pub fn validate(front: &FrontendOutput, module: &naga::Module) -> Result<ModuleInfo, Diagnostic> {
    validator().validate(module).map_err(|err| validation_diagnostic(front, &err))
}

/// The validator gdsky uses: everything checked except uniformity of control flow, since GLSL
/// (and so Godot) allows derivatives and implicit-LOD sampling in non-uniform control flow;
/// with naga's default capabilities plus packing halves into 32-bit words (`packHalf2x16`),
/// which every Vulkan device does (wgpu's `DownlevelFlags::SHADER_F16_IN_F32`).
pub fn validator() -> Validator {
    Validator::new(
        ValidationFlags::all() - ValidationFlags::CONTROL_FLOW_UNIFORMITY,
        Capabilities::default() | Capabilities::SHADER_FLOAT16_IN_FLOAT32,
    )
}

/// [`validator`] with naga's `FLOAT64` capability, for the modules of [`lower_f64`].
pub fn validator_f64() -> Validator {
    Validator::new(
        ValidationFlags::all() - ValidationFlags::CONTROL_FLOW_UNIFORMITY,
        Capabilities::default() | Capabilities::SHADER_FLOAT16_IN_FLOAT32 | Capabilities::FLOAT64,
    )
}

/// The validator for `module`: [`validator_f64`] when it has an f64 type, else [`validator`].
pub(crate) fn validator_for(module: &naga::Module) -> Validator {
    let f64 = module.types.iter().any(|(_, t)| {
        matches!(t.inner, naga::TypeInner::Scalar(s) | naga::TypeInner::Vector { scalar: s, .. } if s == naga::Scalar::F64)
    });
    if f64 { validator_f64() } else { validator() }
}

/// A naga validation error as a diagnostic at the shader's own lines.
fn validation_diagnostic(front: &FrontendOutput, err: &naga::WithSpan<naga::valid::ValidationError>) -> Diagnostic {
    let mut chain = Vec::new();
    let mut source: Option<&dyn std::error::Error> = std::error::Error::source(err.as_inner());
    while let Some(s) = source {
        chain.push(s.to_string());
        source = s.source();
    }
    let mut d = Diagnostic::error(INVALID_MODULE, format!("naga rejected the translated shader: {}", err.as_inner()))
        .with_note("this is a bug in gdsky's translation, not in the shader; please report it")
        .with_notes(chain);
    // naga lists spans from the outer context (the function) to the innermost culprit; the
    // innermost is where the user should look.
    let spans: Vec<_> = err.spans().filter_map(|(span, label)| span.to_range().map(|r| (r, label.clone()))).collect();
    let labelled = !spans.is_empty();
    let last = spans.len().saturating_sub(1);
    for (i, (range, label)) in spans.into_iter().enumerate() {
        let (file, range) = front.locate(ast::Span::new(range.start, range.end));
        d.labels.push(gdshader::Label { file, range, message: label, primary: i == last });
    }
    if !labelled {
        d.notes.push("the problem is in code gdsky's sky wrapper adds, which has no place in the shader".into());
    }
    d
}

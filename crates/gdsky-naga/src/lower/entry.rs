//! The lowering's one public entry: [`lower`] with [`LowerOptions`].
//!
//! Every choice that changes the module is an option, taken before the module is built, so each
//! command lowers once and nothing patches a validated module afterwards: uniforms baked into
//! constants, uniforms made pipeline-overridable constants, Godot's debanding, how SKY_COORDS is
//! computed, the depth the sky lies at, and f32 or f64 evaluation. The module is optimised once
//! and validated once (the f64 module, a rewrite of the validated f32 one, once more with f64).

use super::{Lowerer, TextureSlot, UniformSlot};
use crate::valid::{validate, validation_diagnostic, validator_f64};
use crate::widen::{self, F64Output};
use crate::{BAD_SET, INVALID_MODULE, UNSUPPORTED, emit, opt};
use gdshader::parse::ast;
use gdshader::{Diagnostic, FrontendOutput};
use naga::valid::ModuleInfo;
use skycore::DepthConvention;
use std::collections::HashMap;

pub use super::wrapper::{Debanding, SkyCoords};

/// How [`lower`] translates a checked shader. The default is what the newest Godot the oracle
/// runs (4.6) renders: a shader's own `render_mode use_debanding` honoured, SKY_COORDS computed
/// with Godot 4.6's approximations, the sky at the far plane of standard Z, f32 arithmetic, no
/// uniform baked or overridden.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LowerOptions {
    /// Uniforms baked into constants: name → the text of the value (`1.5`, `24`, `true`,
    /// `0.1,0.2,0.3`), as `gdsky convert --set NAME=VALUE` takes it. A baked uniform leaves the
    /// material block; the reflection lists it under `baked`.
    pub baked: HashMap<String, String>,
    /// Scalar material uniforms emitted as pipeline-overridable constants: a WGSL `override`
    /// `@id(k)` and a SPIR-V specialization constant `SpecId k` for the k-th name, defaulting
    /// to the uniform's default (a `bool` as a `u32` 0 or 1), as `gdsky convert --override NAME`
    /// does. One module then serves many values, given when the pipeline is created (wgpu's
    /// `PipelineCompilationOptions::constants`, keyed by the id as text).
    pub overrides: Vec<String>,
    /// Godot's sky debanding, for a shader that declares `render_mode use_debanding` (a shader
    /// without it lowers to the same module either way).
    pub debanding: Debanding,
    /// How SKY_COORDS is computed from EYEDIR (a shader that does not read SKY_COORDS lowers to
    /// the same module either way).
    pub sky_coords: SkyCoords,
    /// Where `vs_main` puts the sky: the far plane of this depth convention.
    pub depth: DepthConvention,
    /// f32, as Godot evaluates, or f64 for a truth without f32 rounding.
    pub precision: Precision,
}

/// The arithmetic a lowered module evaluates in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Precision {
    /// f32, as Godot (and every GPU a sky ships to) evaluates the shader.
    #[default]
    F32,
    /// f64: every float of the shader's code and of the sky wrapper is an f64, the uniform
    /// blocks, textures and outputs stay f32 and are converted where they are read or written,
    /// and the transcendentals GLSL.std.450 has only in f32 are f64 routines grafted into the
    /// module. The fragment entries return what [`F64Output`] says. The material block's layout
    /// is the f32 module's. The module needs naga's `FLOAT64` capability
    /// ([`crate::validator_f64`]) and a device with `shaderFloat64` (wgpu's
    /// `Features::SHADER_F64`); write it as SPIR-V with [`crate::to_spirv`] (WGSL has no f64).
    /// See the `widen` essay for the rules and their limits.
    F64(F64Output),
}

impl LowerOptions {
    /// The default options: what Godot 4.6 renders.
    pub fn new() -> Self {
        Self::default()
    }

    /// Bakes uniform `name` at `value` (the text `--set NAME=VALUE` takes).
    #[must_use]
    pub fn bake(mut self, name: impl Into<String>, value: impl Into<String>) -> Self {
        self.baked.insert(name.into(), value.into());
        self
    }

    /// Emits uniform `name` as the next pipeline-overridable constant.
    #[must_use]
    pub fn override_uniform(mut self, name: impl Into<String>) -> Self {
        self.overrides.push(name.into());
        self
    }

    /// The same options, evaluating in `precision`.
    #[must_use]
    pub fn with_precision(mut self, precision: Precision) -> Self {
        self.precision = precision;
        self
    }
}

/// Something the lowering could not translate, at a span of the checked shader.
#[derive(Clone, Debug)]
pub(crate) struct LowerError {
    pub span: ast::Span,
    pub message: String,
}

/// A validated naga module of a sky shader.
pub struct Lowered {
    /// The module.
    pub module: naga::Module,
    /// naga's validation result, which the back ends need.
    pub info: ModuleInfo,
    /// Where each uniform lives in the material block (group [`crate::MATERIAL_GROUP`], binding
    /// 0); baked and overridden uniforms are not in it.
    pub uniforms: HashMap<String, UniformSlot>,
    /// Size in bytes of the material block (0 when the shader has no uniforms).
    pub material_size: u32,
    /// Sampler uniforms: a texture and a sampler each in group [`crate::MATERIAL_GROUP`].
    pub textures: HashMap<String, TextureSlot>,
    /// The options the module was lowered with.
    pub options: LowerOptions,
}

/// Lowers and validates a checked shader as `options` say. Errors come back as diagnostics
/// located in the user's files: `E603` for a baked value that does not fit its uniform or an
/// override that names no scalar material uniform, `E600` for what gdsky cannot translate,
/// `E601` for a module naga refuses (a gdsky bug).
pub fn lower(front: &FrontendOutput, options: &LowerOptions) -> Result<Lowered, Vec<Diagnostic>> {
    // The lowering recurses over the expression tree, which the front end lets grow to
    // `MAX_EXPR_DEPTH` (a chain of 2,048 operators): it gets the front end's deep stack rather
    // than whatever thread called it (a test thread has 2 MiB).
    let (lowered, exact) = std::thread::scope(|scope| {
        std::thread::Builder::new()
            .stack_size(LOWERING_STACK_BYTES)
            .spawn_scoped(scope, || (lower_here(front, options), super::take_exact_floats()))
            .map_err(|e| vec![Diagnostic::error(UNSUPPORTED, format!("cannot start the lowering's thread: {e}"))])?
            .join()
            .map_err(|_| {
                vec![Diagnostic::error(INVALID_MODULE, "the lowering panicked: a bug in gdsky; please report it")]
            })
    })?;
    let lowered = lowered?;
    let Precision::F64(output) = options.precision else {
        return Ok(lowered);
    };
    let module = widen::widen(&lowered.module, &lowered.info, &exact, output).map_err(|why| {
        vec![Diagnostic::error(UNSUPPORTED, format!("the f64 evaluation cannot widen this shader: {why}"))]
    })?;
    let info = validator_f64().validate(&module).map_err(|err| vec![validation_diagnostic(front, &err)])?;
    Ok(Lowered { module, info, ..lowered })
}

/// Stack of the lowering's thread: like the front end's, enough for its deepest expression in an
/// unoptimised build, with a wide margin (only the pages touched are ever mapped).
const LOWERING_STACK_BYTES: usize = 256 << 20;

/// [`lower`] on the current thread, in f32.
fn lower_here(front: &FrontendOutput, options: &LowerOptions) -> Result<Lowered, Vec<Diagnostic>> {
    let Some(shader) = front.shader.as_ref() else {
        return Err(front.diagnostics.clone());
    };
    let mut values = HashMap::new();
    let mut errors = Vec::new();
    let mut baked: Vec<(&String, &String)> = options.baked.iter().collect();
    baked.sort();
    for (name, text) in baked {
        let Some(u) = shader.uniforms.iter().find(|u| &u.name == name) else {
            let known: Vec<&str> = shader.uniforms.iter().map(|u| u.name.as_str()).collect();
            errors.push(
                Diagnostic::error(BAD_SET, format!("`--set {name}=…`: the shader has no uniform `{name}`"))
                    .with_note(format!("its uniforms are: {}", known.join(", "))),
            );
            continue;
        };
        match gdshader::values::parse_value(&u.ty, text) {
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
    let mut lw = Lowerer::new(shader, values, options);
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
    let (mut module, mut uniforms, material_size, textures) = (lw.module, lw.uniforms, lw.material_size, lw.textures);
    if let Some(span) = emit::too_deep_for_wgsl(&module).and_then(|s| s.to_range()) {
        let (file, range) = front.locate(ast::Span::new(span.start, span.end));
        return Err(vec![
            Diagnostic::error(UNSUPPORTED, "this statement nests blocks deeper than WGSL allows")
                .with_primary(file, range, "")
                .with_note(format!("WGSL (naga's front end) accepts at most {} nested braces", emit::MAX_WGSL_BRACES)),
        ]);
    }
    check_overrides(shader, options, &uniforms)?;
    opt::overrides::apply(&mut module, &mut uniforms, shader, &options.overrides);
    opt::optimize(&mut module);
    let info = validate(front, &module).map_err(|d| vec![d])?;
    Ok(Lowered { module, info, uniforms, material_size, textures, options: options.clone() })
}

/// Refuses an override that is not a scalar material uniform, is baked too, or is named twice.
fn check_overrides(
    shader: &gdshader::CheckedShader,
    options: &LowerOptions,
    uniforms: &HashMap<String, UniformSlot>,
) -> Result<(), Vec<Diagnostic>> {
    let overrides = &options.overrides;
    let mut errors = Vec::new();
    for (i, name) in overrides.iter().enumerate() {
        let why = match shader.uniforms.iter().find(|u| &u.name == name) {
            None => Some(format!("the shader has no uniform `{name}`")),
            Some(_) if options.baked.contains_key(name) => Some("it is baked by `--set` too".to_string()),
            Some(_) if overrides[..i].contains(name) => Some("it is named twice".to_string()),
            Some(u) if u.global || !matches!(u.ty, gdshader::check::types::Type::Scalar(_)) => Some(format!(
                "only scalar material uniforms can be overrides (WGSL overrides are scalars); `{name}` is a{} `{}`",
                if u.global { " global" } else { "" },
                u.type_name
            )),
            Some(_) if !uniforms.contains_key(name) => Some(format!("`{name}` has no place in the material block")),
            Some(_) => None,
        };
        if let Some(why) = why {
            errors.push(Diagnostic::error(BAD_SET, format!("`--override {name}`: {why}")));
        }
    }
    if errors.is_empty() { Ok(()) } else { Err(errors) }
}

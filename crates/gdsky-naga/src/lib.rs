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
//! * `wrapper.rs` adds Godot's sky wrapper: the built-ins uniform (group 0), per-pixel
//!   built-ins, the fullscreen-triangle vertex entry and one fragment entry per projection.
//!
//! Every naga expression carries the span of the shader text it came from, so a validation
//! error is reported at the user's file and line ([`lower`] maps it through the source map);
//! code the wrapper injects carries no span and is reported as the wrapper's.

mod lower;
pub mod reflect;
pub mod wrapper;

pub use lower::{GLOBAL_UNIFORM_GROUP, MATERIAL_GROUP, TextureSlot, UniformSlot};
pub use wrapper::Projection;

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
/// Diagnostic code for a `--set NAME=VALUE` that names no uniform or does not fit its type.
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
    let info = validate(front, &module).map_err(|d| vec![d])?;
    Ok(Lowered { module, info, uniforms, material_size, textures })
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

/// Why an emitted module was refused: a back end failed, or what it wrote does not read back.
///
/// Every text gdsky emits is re-read by naga's own front end and validated before anyone sees
/// it ([`to_wgsl`], [`to_spirv`]): naga's IR validator is more lenient than the WGSL language
/// (its constant evaluator, its return rules), so a module can validate and still print as WGSL
/// that no WGSL compiler accepts. Such a module is a gdsky bug and must never reach a file.
#[derive(Clone, Debug)]
pub struct EmitError {
    /// `"WGSL"` or `"SPIR-V"`.
    pub format: &'static str,
    /// What failed, in naga's words (for a re-read: the emitted line with a caret).
    pub message: String,
    /// The back end wrote the module but naga's front end could not read it back or validate it
    /// (otherwise the back end itself failed).
    pub reread: bool,
    /// The function of the module the failure is in, when it could be found: its span points at
    /// the function in the user's shader (none for the wrapper's entry points).
    span: Option<naga::Span>,
    /// The function's name in the emitted text.
    function: Option<String>,
}

impl std::fmt::Display for EmitError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.format, self.message)
    }
}

impl std::error::Error for EmitError {}

impl EmitError {
    /// The failure as a diagnostic at the user's function (code [`BACKEND`] or [`REREAD`]).
    pub fn diagnostic(&self, front: &FrontendOutput) -> Diagnostic {
        let code = if self.reread { REREAD } else { BACKEND };
        let mut d = Diagnostic::error(code, format!("gdsky emitted {} that does not hold up", self.format))
            .with_note(self.message.clone())
            .with_note(
                "this is a bug in gdsky's translation, not in the shader; nothing was written; please report it",
            );
        match (self.span.and_then(|s| s.to_range()), &self.function) {
            (Some(range), Some(name)) => {
                let (file, range) = front.locate(ast::Span::new(range.start, range.end));
                d.labels.push(gdshader::Label {
                    file,
                    range,
                    message: format!("in this function (`{name}` in the emitted text)"),
                    primary: true,
                });
            }
            (None, Some(name)) => {
                d.notes.push(format!("the problem is in `{name}`, code gdsky's sky wrapper adds"));
            }
            _ => {}
        }
        d
    }
}

/// Writes the module as WGSL, then re-reads that text with naga's WGSL front end and validates
/// the result: only text that round-trips comes back.
pub fn to_wgsl(lowered: &Lowered) -> Result<String, EmitError> {
    let text = naga::back::wgsl::write_string(&lowered.module, &lowered.info, naga::back::wgsl::WriterFlags::empty())
        .map_err(|e| EmitError {
        format: "WGSL",
        message: format!("naga's WGSL writer failed: {e}"),
        reread: false,
        span: None,
        function: None,
    })?;
    reread_wgsl(&lowered.module, &text)?;
    Ok(text)
}

/// Re-reads emitted WGSL with naga's front end and validator; an error names the function of
/// `module` whose text holds the offending line.
pub fn reread_wgsl(module: &naga::Module, text: &str) -> Result<(), EmitError> {
    let fail = |message: String, offset: Option<usize>| {
        let function = offset.and_then(|o| enclosing_wgsl_function(text, o));
        let span = function.as_deref().and_then(|name| function_span(module, name));
        EmitError { format: "WGSL", message, reread: true, span, function }
    };
    let reread = naga::front::wgsl::parse_str(text).map_err(|e| {
        let offset = e.location(text).map(|l| l.offset as usize);
        fail(format!("the emitted WGSL does not re-read: {}", e.emit_to_string_with_path(text, "emitted.wgsl")), offset)
    })?;
    validator().validate(&reread).map_err(|e| {
        let offset = e.spans().next().and_then(|(s, _)| s.to_range()).map(|r| r.start);
        fail(
            format!("the re-read WGSL does not validate: {}", e.emit_to_string_with_path(text, "emitted.wgsl")),
            offset,
        )
    })?;
    Ok(())
}

/// Writes the module as SPIR-V 1.3 for Vulkan, every entry point in one module, then re-reads it
/// with naga's SPIR-V front end and validates the result. The vertex position is written in
/// Vulkan's clip space as wgpu expects (naga's default adjustment).
pub fn to_spirv(lowered: &Lowered) -> Result<Vec<u32>, EmitError> {
    let fail = |message: String, reread| EmitError { format: "SPIR-V", message, reread, span: None, function: None };
    let options = naga::back::spv::Options { lang_version: (1, 3), fake_missing_bindings: true, ..Default::default() };
    let words = naga::back::spv::write_vec(&lowered.module, &lowered.info, &options, None)
        .map_err(|e| fail(format!("naga's SPIR-V writer failed: {e}"), false))?;
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let reread = naga::front::spv::parse_u8_slice(&bytes, &naga::front::spv::Options::default())
        .map_err(|e| fail(format!("the emitted SPIR-V does not re-read with naga's SPIR-V front end: {e}"), true))?;
    validator()
        .validate(&reread)
        .map_err(|e| fail(format!("the re-read SPIR-V does not validate: {}", error_chain(e.as_inner())), true))?;
    Ok(words)
}

/// An error and its sources on one line.
fn error_chain(err: &dyn std::error::Error) -> String {
    let mut text = err.to_string();
    let mut source = err.source();
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}

/// The name of the WGSL function whose text holds byte `offset` of `text`: the last `fn NAME(`
/// at the start of a line that starts at or before it.
fn enclosing_wgsl_function(text: &str, offset: usize) -> Option<String> {
    // `+ 3`: an offset at the `f` of `fn` itself (naga's span of a whole function) counts.
    let mut end = (offset + 3).min(text.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    let before = &text[..end];
    let start = before.rfind("\nfn ").map(|i| i + 4).or_else(|| before.starts_with("fn ").then_some(3))?;
    let rest = &text[start..];
    let name: String = rest.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect();
    (!name.is_empty()).then_some(name)
}

/// The span of the module function (or entry point) that naga's WGSL writer names `name`: the
/// writer keeps a function's own name unless it clashes, when it appends `_N`.
fn function_span(module: &naga::Module, name: &str) -> Option<naga::Span> {
    let base = name.rsplit_once('_').filter(|(_, n)| n.chars().all(|c| c.is_ascii_digit())).map(|(b, _)| b);
    let matches = |f: &Option<String>| f.as_deref() == Some(name) || (base.is_some() && f.as_deref() == base);
    let span =
        module.functions.iter().find(|(_, f)| matches(&f.name)).map(|(h, _)| module.functions.get_span(h)).or_else(
            || module.entry_points.iter().find(|e| matches(&e.function.name)).map(|_| naga::Span::UNDEFINED),
        )?;
    span.is_defined().then_some(span)
}

//! Validation: the one place gdsky asks naga whether a module holds up, and turns a refusal
//! into a diagnostic at the user's own lines.
//!
//! Every module the lowering builds is validated once before anyone sees it ([`validate`]); the
//! instrumenting passes (NaN tracing, the loop-budget canary) and the f64 widening validate what
//! they rewrite with the validator that fits the module ([`validator_for`]). A refusal is always a
//! bug in gdsky's translation, never the shader's fault: the message says so, and points at the
//! innermost span naga names (every expression carries the span of the shader text it came from;
//! code the wrapper injects carries none and is reported as the wrapper's).

use crate::INVALID_MODULE;
use gdshader::parse::ast;
use gdshader::{Diagnostic, FrontendOutput};
use naga::valid::{Capabilities, ModuleInfo, ValidationFlags, Validator};

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

/// [`validator`] with naga's `FLOAT64` capability, for the f64 modules of
/// [`crate::Precision::F64`].
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
pub(crate) fn validation_diagnostic(
    front: &FrontendOutput,
    err: &naga::WithSpan<naga::valid::ValidationError>,
) -> Diagnostic {
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

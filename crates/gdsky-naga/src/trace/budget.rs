//! # Did the device run every loop? (lavapipe's loop budget)
//!
//! lavapipe (Mesa's llvmpipe) gives every shader invocation one budget of 65,535 loop passes,
//! shared by all its loops and by the SIMD lanes it runs in lockstep (gallivm's
//! `LP_MAX_TGSI_LOOP_ITERATIONS`); when it is spent, every loop leaves at its next back edge,
//! silently (docs/lavapipe-loop-limit.md). A sky whose loops need more — a ray march at high
//! sample counts, the sampling truth of `gdsky bench` — renders a wrong image with no error.
//!
//! [`loop_budget`] makes a module that tells, per pixel, whether that happened: each fragment
//! entry point, just before it returns, calls a two-pass loop whose trip count the compiler
//! cannot know (2, or 3 when `render_pass` is `u32::MAX`, which it never is: a constant would
//! let the driver unroll the loop and take it out of the budget), and returns the number of
//! passes it made as the alpha. With budget left that is 2; with the budget spent the loop
//! leaves after its first pass: 1. The full pass's alpha is otherwise always 0 (Godot's), so
//! nothing is lost; the sub-passes keep their alpha, as [`super::instrument`]'s do. On a device
//! without such a limit the alpha is always 2, and the canary costs two loop passes a pixel.
//!
//! Render the canary module with the same uniforms as the shader's own and count pixels with
//! alpha [`BUDGET_SPENT`]; the colour is the shader's.

use crate::Lowered;
use crate::valid::{validation_diagnostic, validator_for};
use crate::widen::graft::Grafter;
use gdshader::{Diagnostic, FrontendOutput};
use naga::{
    BinaryOperator as Bo, Block, Expression as E, Function, Handle, Literal, ScalarKind, ShaderStage, Span, Statement,
};
use std::sync::OnceLock;

/// The alpha of a pixel whose loops the device stopped early.
pub const BUDGET_SPENT: f32 = 1.0;

/// The alpha of a pixel that ran every loop (and so the canary's two passes).
pub const BUDGET_LEFT: f32 = 2.0;

const CANARY_WGSL: &str = "fn gdsky_loop_budget(limit: u32) -> u32 {\n\
    var passes = 0u;\n\
    loop {\n\
        passes = passes + 1u;\n\
        if (passes >= limit) { break; }\n\
    }\n\
    return passes;\n\
}\n";

fn canary_library() -> Result<&'static naga::Module, String> {
    static LIB: OnceLock<Result<naga::Module, String>> = OnceLock::new();
    LIB.get_or_init(|| naga::front::wgsl::parse_str(CANARY_WGSL).map_err(|e| e.emit_to_string(CANARY_WGSL)))
        .as_ref()
        .map_err(Clone::clone)
}

/// The module of `lowered` (validated, unchanged otherwise) whose fragment entry points return
/// the canary's pass count as the alpha of the full pass (see the module essay). Errors: the
/// rewritten module does not validate (a gdsky bug, reported as a diagnostic).
pub fn loop_budget(front: &FrontendOutput, lowered: &Lowered) -> Result<Lowered, Vec<Diagnostic>> {
    let bug = |message: String| vec![Diagnostic::error(crate::INVALID_MODULE, message)];
    let mut module = lowered.module.clone();
    let lib = canary_library().map_err(bug)?;
    let canary = Grafter::new(lib).routine(&mut module, "gdsky_loop_budget").map_err(bug)?;
    let Some(pass) = super::render_pass(&module) else {
        return Err(bug("the module has no built-ins uniform with `render_pass`".into()));
    };
    for ep in module.entry_points.iter_mut().filter(|ep| ep.stage == ShaderStage::Fragment) {
        let mut body = std::mem::take(&mut ep.function.body);
        passes_in_alpha(&mut ep.function, &mut body, canary, pass);
        ep.function.body = body;
    }
    let info = validator_for(&module).validate(&module).map_err(|err| vec![validation_diagnostic(front, &err)])?;
    Ok(Lowered {
        module,
        info,
        uniforms: lowered.uniforms.clone(),
        material_size: lowered.material_size,
        textures: lowered.textures.clone(),
        options: lowered.options.clone(),
    })
}

/// Makes each `return v` of a fragment entry point return `vec4(v.rgb, f32(canary(limit)))`,
/// except in the sub-passes, which keep `v`'s alpha.
fn passes_in_alpha(
    f: &mut Function,
    block: &mut Block,
    canary: Handle<Function>,
    (globals, member): (Handle<naga::GlobalVariable>, u32),
) {
    super::rewrite_returns(f, block, &mut |f, block, out, ty| {
        let sp = Span::UNDEFINED;
        let ex = &mut f.expressions;
        let refs = super::PassRefs::new(ex, (globals, member));
        let never = ex.append(E::Literal(Literal::U32(u32::MAX)), sp);
        let (two, three) = (ex.append(E::Literal(Literal::U32(2)), sp), ex.append(E::Literal(Literal::U32(3)), sp));
        let start = ex.len();
        let value = refs.render_pass(ex);
        let impossible = ex.append(E::Binary { op: Bo::Equal, left: value, right: never }, sp);
        let limit = ex.append(E::Select { condition: impossible, accept: three, reject: two }, sp);
        block.push(Statement::Emit(ex.range_from(start)), sp);
        let passes = ex.append(E::CallResult(canary), sp);
        block.push(Statement::Call { function: canary, arguments: vec![limit], result: Some(passes) }, sp);
        let start = ex.len();
        let count = ex.append(E::As { expr: passes, kind: ScalarKind::Float, convert: Some(4) }, sp);
        let composed = super::with_alpha(ex, out, ty, count, Some(refs));
        block.push(Statement::Emit(ex.range_from(start)), sp);
        composed
    });
}

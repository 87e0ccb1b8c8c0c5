//! # Emitting: WGSL and SPIR-V that read back
//!
//! naga's back ends write the validated module; nothing they write is handed out before naga's
//! own front ends have read it back and naga's validator has accepted the result. The IR
//! validator is more lenient than the languages: WGSL's constant evaluator rejects overflowing
//! or non-finite constant expressions, WGSL requires a non-void function to end in a `return`;
//! the IR has neither rule. So a module can validate and still print as text that no WGSL
//! compiler takes. Re-reading turns every such case into a located gdsky bug (E604) instead of a
//! file on disk.
//!
//! naga 30's SPIR-V front end reads some valid SPIR-V (which naga's own back end writes and
//! `spirv-val` accepts) into IR its validator rejects; [`complete_spirv_reread`] fills exactly
//! those gaps, each named with its cause, so the validator judges the module rather than the
//! front end. A gap found later shows up as E604 on a valid shader and belongs there.
//!
//! naga 30's SPIR-V writer refuses overrides; [`to_spirv`] writes them as specialization
//! constants itself (see `spec_constants`), and the re-read checks each comes back as an
//! override with its id and default.

use crate::valid::{validator, validator_for};
use crate::{BACKEND, Lowered, REREAD};
use gdshader::parse::ast;
use gdshader::{Diagnostic, FrontendOutput};

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
    /// A known limit of what gdsky can write, not a bug: what to do about it (an override that
    /// is no specialization constant, a module too large to re-read).
    limitation: Option<&'static str>,
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
        let title = if self.limitation.is_some() {
            format!("gdsky cannot write this shader as {}", self.format)
        } else {
            format!("gdsky emitted {} that does not hold up", self.format)
        };
        let mut d =
            Diagnostic::error(code, title).with_note(self.message.clone()).with_note(self.limitation.unwrap_or(
                "this is a bug in gdsky's translation, not in the shader; nothing was written; please report it",
            ));
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
    let module = with_shallow_expressions(&lowered.module, &lowered.info);
    let text = naga::back::wgsl::write_string(&module, &lowered.info, naga::back::wgsl::WriterFlags::empty()).map_err(
        |e| EmitError {
            format: "WGSL",
            message: format!("naga's WGSL writer failed: {e}"),
            reread: false,
            span: None,
            function: None,
            limitation: None,
        },
    )?;
    let text = exact_f32_max(text);
    reread_wgsl(&lowered.module, &text)?;
    Ok(text)
}

/// The largest finite f32 as naga's WGSL writer prints it: Rust's shortest round-trip form,
/// 3.4028235e38 written out, which is *above* f32::MAX (3.4028234663852886e38) and rounds down to
/// it. WGSL requires a literal's value to be representable in its type, and Chromium's compiler
/// (Tint) holds to that ("value cannot be represented as 'f32'"; naga rounds). No other f32 is
/// affected: below the largest, the shortest form that reads back as a value never passes the
/// largest finite one.
const F32_MAX_AS_WRITTEN: &str = "340282350000000000000000000000000000000f";
/// f32::MAX exactly, (2 − 2⁻²³)·2¹²⁷: the same value, within the type, for every compiler.
const F32_MAX_EXACT: &str = "340282346638528859811704183484516925440f";

/// [`F32_MAX_AS_WRITTEN`] replaced by [`F32_MAX_EXACT`] (a literal of either sign; the digits can
/// be nothing but a float literal in WGSL text). Found by the Tint run in tests/godot/preview.rs.
fn exact_f32_max(text: String) -> String {
    if text.contains(F32_MAX_AS_WRITTEN) { text.replace(F32_MAX_AS_WRITTEN, F32_MAX_EXACT) } else { text }
}

/// How deep one expression may nest in WGSL text before it is given a name (`let`). naga's WGSL
/// parser stops at 200 levels of recursion, shared between nested statements (at most
/// [`MAX_WGSL_BRACES`]) and the expression being parsed; naga's writer prints an expression used
/// once inline, so a long chain such as `a + a + … + a` would print as one deeply parenthesised
/// expression. 32 leaves room for the deepest statement nesting.
const MAX_INLINE_DEPTH: u32 = 32;

/// How deep braces may nest in WGSL: naga's WGSL front end refuses more than 127 (the minimum
/// the WGSL specification requires implementations to support).
pub const MAX_WGSL_BRACES: usize = 127;

/// A copy of `module` in which every expression that would print nested deeper than
/// [`MAX_INLINE_DEPTH`] has a name, so naga's WGSL writer gives it a `let` of its own. Names do
/// not change the module's meaning or its validation info.
fn with_shallow_expressions<'m>(
    module: &'m naga::Module,
    info: &naga::valid::ModuleInfo,
) -> std::borrow::Cow<'m, naga::Module> {
    let deep =
        |function: &naga::Function, fun_info: &naga::valid::FunctionInfo| -> Vec<naga::Handle<naga::Expression>> {
            // The arena lists operands before their users, so one pass computes every depth.
            let mut depth = vec![1u32; function.expressions.len()];
            let mut named = Vec::new();
            for (h, expression) in function.expressions.iter() {
                let inline = |o: &naga::Handle<naga::Expression>| {
                    // Named or used more than once: printed as a name, depth 1.
                    let printed_by_name = function.named_expressions.contains_key(o) || fun_info[*o].ref_count > 1;
                    if printed_by_name { 1 } else { depth[o.index()] }
                };
                let d = 1 + crate::opt::operands(expression).unwrap_or_default().iter().map(inline).max().unwrap_or(0);
                let value = !matches!(
                    fun_info[h].ty.inner_with(&module.types),
                    naga::TypeInner::Pointer { .. } | naga::TypeInner::ValuePointer { .. }
                );
                if d > MAX_INLINE_DEPTH && value && is_emitted(expression) {
                    named.push(h);
                    depth[h.index()] = 1;
                } else {
                    depth[h.index()] = d;
                }
            }
            named
        };
    let per_function: Vec<_> = module.functions.iter().map(|(h, f)| deep(f, &info[h])).collect();
    let per_entry: Vec<_> =
        module.entry_points.iter().enumerate().map(|(i, e)| deep(&e.function, info.get_entry_point(i))).collect();
    if per_function.iter().chain(&per_entry).all(Vec::is_empty) {
        return std::borrow::Cow::Borrowed(module);
    }
    let mut copy = module.clone();
    let functions =
        copy.functions.iter_mut().map(|(_, f)| f).chain(copy.entry_points.iter_mut().map(|e| &mut e.function));
    for (function, named) in functions.zip(per_function.iter().chain(&per_entry)) {
        for &h in named {
            function.named_expressions.insert(h, format!("part{}", h.index()));
        }
    }
    std::borrow::Cow::Owned(copy)
}

/// Whether naga covers `expression` with an `Emit` statement (only such expressions can be
/// named into a `let`): not the pre-emitted kinds (literals, constants, variables, arguments),
/// nor the results a statement defines (calls, atomics and the like), which print as themselves.
fn is_emitted(expression: &naga::Expression) -> bool {
    use naga::Expression as E;
    !expression.needs_pre_emit()
        && !matches!(
            expression,
            E::CallResult(_)
                | E::AtomicResult { .. }
                | E::WorkGroupUniformLoadResult { .. }
                | E::RayQueryProceedResult
                | E::SubgroupBallotResult
                | E::SubgroupOperationResult { .. }
        )
}

/// The first statement of `module` that opens braces deeper than WGSL allows
/// ([`MAX_WGSL_BRACES`]), with its span: such a shader cannot be written as WGSL.
pub fn too_deep_for_wgsl(module: &naga::Module) -> Option<naga::Span> {
    fn block(b: &naga::Block, depth: usize) -> Option<naga::Span> {
        for (statement, span) in b.span_iter() {
            use naga::Statement as S;
            // `depth` counts the braces this block sits in; a statement's own blocks open more:
            // one for `if`, `loop` and a bare block, two for `continuing` (inside the loop's)
            // and for a `switch` case (inside the switch's).
            let inner: Vec<(&naga::Block, usize)> = match statement {
                S::Block(inner) => vec![(inner, 1)],
                S::If { accept, reject, .. } => vec![(accept, 1), (reject, 1)],
                S::Loop { body, continuing, .. } => vec![(body, 1), (continuing, 2)],
                S::Switch { cases, .. } => cases.iter().map(|c| (&c.body, 2)).collect(),
                _ => Vec::new(),
            };
            for (inner, opens) in inner {
                if depth + opens > MAX_WGSL_BRACES {
                    return Some(*span);
                }
                if let Some(found) = block(inner, depth + opens) {
                    return Some(found);
                }
            }
        }
        None
    }
    let bodies =
        module.functions.iter().map(|(_, f)| &f.body).chain(module.entry_points.iter().map(|e| &e.function.body));
    bodies.into_iter().find_map(|body| block(body, 1))
}

/// Runs one of naga's readers on what gdsky made: a panic inside it (the SPIR-V front end's
/// 16-bit word count once wrapped on a 65,539-word instruction) becomes an error that says what
/// was being done, so the command reports it (E604) and writes nothing, instead of exit 101.
/// The panic hook has already printed naga's own message on stderr.
fn guarded<T>(what: &str, work: impl FnOnce() -> T) -> Result<T, String> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(work))
        .map_err(|_| format!("naga panicked {what}: a bug in naga or in gdsky's output; nothing was written"))
}

/// Re-reads emitted WGSL with naga's front end and validator; an error names the function of
/// `module` whose text holds the offending line.
pub fn reread_wgsl(module: &naga::Module, text: &str) -> Result<(), EmitError> {
    let fail = |message: String, offset: Option<usize>| {
        let function = offset.and_then(|o| enclosing_wgsl_function(text, o));
        let span = function.as_deref().and_then(|name| function_span(module, name));
        EmitError { format: "WGSL", message, reread: true, span, function, limitation: None }
    };
    let reread = guarded("re-reading the emitted WGSL", || naga::front::wgsl::parse_str(text))
        .map_err(|m| fail(m, None))?
        .map_err(|e| {
            let offset = e.location(text).map(|l| l.offset as usize);
            fail(
                format!("the emitted WGSL does not re-read: {}", e.emit_to_string_with_path(text, "emitted.wgsl")),
                offset,
            )
        })?;
    guarded("validating the re-read WGSL", || validator().validate(&reread).map_err(Box::new))
        .map_err(|m| fail(m, None))?
        .map_err(|e| {
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
///
/// Each override of the module (`--override`) becomes a specialization constant: an
/// `OpSpecConstant` decorated `SpecId k` (its `@id`) whose default is the override's. naga 30's
/// writer has no specialization constants, so `spec_constants` writes a copy of the module in
/// which each override is an ordinary constant with a sentinel value found nowhere else, and
/// turns that one constant of the binary into the specialization constant.
pub fn to_spirv(lowered: &Lowered) -> Result<Vec<u32>, EmitError> {
    to_spirv_with(lowered, &SpirvOptions::default())
}

/// What [`to_spirv_with`] writes besides the code. The default is the same bytes from every build
/// of gdsky: naga's writer adds debug names by default only when *it* was compiled with debug
/// assertions, so a debug build script and a release CLI would write different SPIR-V for one
/// shader.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SpirvOptions {
    /// `OpName`/`OpMemberName` for every function, variable and member (naga's `DEBUG` writer
    /// flag): readable disassembly and GPU debuggers, about 12 % more bytes.
    pub debug_names: bool,
}

/// [`to_spirv`] with `options`.
pub fn to_spirv_with(lowered: &Lowered, spirv: &SpirvOptions) -> Result<Vec<u32>, EmitError> {
    let fail = |message: String, reread| EmitError {
        format: "SPIR-V",
        message,
        reread,
        span: None,
        function: None,
        limitation: None,
    };
    use naga::back::spv::WriterFlags;
    let mut flags = WriterFlags::ADJUST_COORDINATE_SPACE | WriterFlags::LABEL_VARYINGS | WriterFlags::CLAMP_FRAG_DEPTH;
    flags.set(WriterFlags::DEBUG, spirv.debug_names);
    let options =
        naga::back::spv::Options { lang_version: (1, 3), fake_missing_bindings: true, flags, ..Default::default() };
    let words = if lowered.module.overrides.is_empty() {
        naga::back::spv::write_vec(&lowered.module, &lowered.info, &options, None)
            .map_err(|e| fail(format!("naga's SPIR-V writer failed: {e}"), false))?
    } else {
        spec_constants(&lowered.module, &options).map_err(|(message, limitation)| EmitError {
            limitation: limitation.then_some(
                "a limit of gdsky's SPIR-V output, not a bug; nothing was written (the override works in WGSL; \
                     without `--override` of this uniform the SPIR-V is written)",
            ),
            ..fail(message, false)
        })?
    };
    let (functions, module_values) = spirv_reread_size(&words);
    let cost = functions.saturating_mul(module_values);
    if cost > MAX_SPIRV_REREAD_EXPRESSIONS {
        return Err(EmitError {
            limitation: Some(
                "a budget of gdsky's, not a bug: nothing was written; fewer functions (inline small helpers) or \
                 fewer distinct literal values bring it under",
            ),
            ..fail(
                format!(
                    "the SPIR-V has {functions} functions and {module_values} module-level constants and variables; \
                     naga's SPIR-V reader, which re-reads every module gdsky writes, gives each function an expression \
                     for each of them: {cost} expressions, over the budget of {MAX_SPIRV_REREAD_EXPRESSIONS} (about \
                     50 bytes each)"
                ),
                false,
            )
        });
    }
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    let mut reread = guarded("re-reading the emitted SPIR-V", || {
        naga::front::spv::parse_u8_slice(&bytes, &naga::front::spv::Options::default())
    })
    .map_err(|m| fail(m, true))?
    .map_err(|e| fail(format!("the emitted SPIR-V does not re-read with naga's SPIR-V front end: {e}"), true))?;
    complete_spirv_reread(&mut reread);
    // naga's SPIR-V reader gives every function an expression for every module-level constant;
    // compaction drops the unused ones, so validating the re-read costs memory in proportion to
    // the module rather than to functions × constants (5,000 small functions: 2.6 GB before).
    naga::compact::compact(&mut reread, naga::compact::KeepUnused::Yes);
    // An f64 module re-reads with f64 types and needs FLOAT64.
    guarded("validating the re-read SPIR-V", || validator_for(&reread).validate(&reread).map_err(Box::new))
        .map_err(|m| fail(m, true))?
        .map_err(|e| fail(format!("the re-read SPIR-V does not validate: {}", error_chain(e.as_inner())), true))?;
    // Every override reads back as the specialization constant of its id, with its default.
    for (_, o) in lowered.module.overrides.iter() {
        let default = o.init.map(|i| &lowered.module.global_expressions[i]);
        let found = reread.overrides.iter().any(|(_, r)| {
            r.id == o.id && r.init.map(|i| &reread.global_expressions[i]) == default && default.is_some()
        });
        if !found {
            return Err(fail(
                format!(
                    "the override `{}` does not read back as a specialization constant with its id and default",
                    o.name.as_deref().unwrap_or("?")
                ),
                true,
            ));
        }
    }
    Ok(words)
}

/// Most expressions naga's SPIR-V reader may build to re-read a module: functions × module-level
/// constants and variables, which it puts in every function's expression arena before reading its
/// body. Measured at about 50 bytes each at the peak of a `convert` (after compaction of the
/// re-read): 4.1 million took 237 MB, 16.3 million 880 MB; the shipped skies need at most a few
/// thousand. 8 million bounds the re-read near 450 MB.
pub const MAX_SPIRV_REREAD_EXPRESSIONS: u64 = 8 << 20;

/// (functions, module-level constants and global variables) of a SPIR-V module, counted from its
/// instructions: what [`MAX_SPIRV_REREAD_EXPRESSIONS`] bounds.
fn spirv_reread_size(words: &[u32]) -> (u64, u64) {
    let (mut functions, mut values, mut in_function, mut at) = (0u64, 0u64, false, 5usize);
    while let Some(&word) = words.get(at) {
        let (count, opcode) = ((word >> 16) as usize, word & 0xffff);
        match opcode {
            op::FUNCTION => {
                functions += 1;
                in_function = true;
            }
            op::FUNCTION_END => in_function = false,
            // OpConstantTrue … OpSpecConstantOp, and OpVariable outside a function.
            41..=52 => values += 1,
            op::VARIABLE if !in_function => values += 1,
            _ => {}
        }
        at += count.max(1);
    }
    (functions, values)
}

/// SPIR-V opcodes [`spec_constants`] and [`spirv_reread_size`] read or write.
mod op {
    pub const TYPE_INT: u32 = 21;
    pub const TYPE_FLOAT: u32 = 22;
    pub const CONSTANT: u32 = 43;
    pub const CONSTANT_COMPOSITE: u32 = 44;
    pub const SPEC_CONSTANT: u32 = 50;
    pub const FUNCTION: u32 = 54;
    pub const FUNCTION_END: u32 = 56;
    pub const VARIABLE: u32 = 59;
    pub const DECORATE: u32 = 71;
    /// `OpDecorate` … `OpGroupMemberDecorate`, `OpDecorateId`, `OpDecorateString`,
    /// `OpMemberDecorateString`: the annotations section of the logical layout.
    pub fn is_annotation(opcode: u32) -> bool {
        matches!(opcode, 71..=75 | 332 | 5632 | 5633)
    }
    /// Type declarations (`OpTypeVoid` … `OpTypeForwardPointer`), which follow the annotations.
    pub fn is_type(opcode: u32) -> bool {
        matches!(opcode, 19..=39)
    }
    /// The `SpecId` decoration.
    pub const SPEC_ID: u32 = 1;
}

/// Writes a module with overrides as SPIR-V with a specialization constant per override (see
/// [`to_spirv`]). Each override must be a 32-bit scalar (gdsky makes `f32`, `i32` and `u32` ones)
/// used only as a value in functions, which is all `--override` produces. The refusals (E602)
/// are cases where the constant cannot be found again in the binary: the writer folded it into
/// a composite constant, or the sentinel is not unique.
///
/// An error says whether it is such a refusal (`true`) or a failure of naga's writer or
/// validator (a bug, `false`).
fn spec_constants(module: &naga::Module, options: &naga::back::spv::Options) -> Result<Vec<u32>, (String, bool)> {
    use naga::{Expression as E, Literal as L};
    let refuse = |name: &str, why: String| {
        (format!("cannot write the override `{name}` as a specialization constant: {why}"), true)
    };
    // Every 32-bit literal of the module, as (is_float, signed, bits).
    let mut used = std::collections::HashSet::new();
    let mut note = |e: &E| match *e {
        E::Literal(L::F32(f)) => {
            used.insert((true, false, f.to_bits()));
        }
        E::Literal(L::I32(i)) => {
            used.insert((false, true, i as u32));
        }
        E::Literal(L::U32(u)) => {
            used.insert((false, false, u));
        }
        _ => {}
    };
    module.global_expressions.iter().for_each(|(_, e)| note(e));
    for f in module.functions.iter().map(|(_, f)| f).chain(module.entry_points.iter().map(|e| &e.function)) {
        f.expressions.iter().for_each(|(_, e)| note(e));
    }
    let mut copy = module.clone();
    // (name, SpecId, (is_float, signed), sentinel bits, default bits, constant handle)
    let mut specs = Vec::new();
    let mut constant_of = std::collections::HashMap::new();
    for (h, o) in module.overrides.iter() {
        let name = o.name.clone().unwrap_or_else(|| format!("override{}", h.index()));
        let Some(id) = o.id else {
            return Err(refuse(&name, "it has no id".into()));
        };
        let default = o.init.map(|i| &module.global_expressions[i]);
        let (kind, default_bits) = match default {
            Some(E::Literal(L::F32(f))) => ((true, false), f.to_bits()),
            Some(E::Literal(L::I32(i))) => ((false, true), *i as u32),
            Some(E::Literal(L::U32(u))) => ((false, false), *u),
            _ => return Err(refuse(&name, "its default is not a 32-bit scalar literal".into())),
        };
        // Sentinels: values no shader or polyfill writes, tried until one is unused.
        let sentinel = (0u32..64)
            .map(|k| if kind.0 { (0x1E5E_C000 + k * 0x1_0003).to_owned() } else { 0x5EC1_D00D ^ (k * 0x0101_0101) })
            .find(|bits| !used.contains(&(kind.0, kind.1, *bits)))
            .ok_or_else(|| refuse(&name, "no sentinel value is free".into()))?;
        used.insert((kind.0, kind.1, sentinel));
        let literal = match kind {
            (true, _) => L::F32(f32::from_bits(sentinel)),
            (false, true) => L::I32(sentinel as i32),
            (false, false) => L::U32(sentinel),
        };
        let init = copy.global_expressions.append(E::Literal(literal), naga::Span::UNDEFINED);
        let c =
            copy.constants.append(naga::Constant { name: Some(name.clone()), ty: o.ty, init }, naga::Span::UNDEFINED);
        constant_of.insert(h, c);
        specs.push((name, u32::from(id), kind, sentinel, default_bits));
    }
    if copy.global_expressions.iter().any(|(_, e)| matches!(e, E::Override(_))) {
        return Err(refuse(&specs[0].0, "an override is used in a module-scope expression".into()));
    }
    copy.overrides = naga::Arena::new();
    let functions =
        copy.functions.iter_mut().map(|(_, f)| f).chain(copy.entry_points.iter_mut().map(|e| &mut e.function));
    for f in functions {
        for (_, e) in f.expressions.iter_mut() {
            if let E::Override(o) = *e {
                *e = E::Constant(constant_of[&o]);
            }
        }
    }
    let info = validator()
        .validate(&copy)
        .map_err(|e| format!("the module with overrides as constants does not validate: {}", error_chain(e.as_inner())))
        .map_err(|m| (m, false))?;
    let mut words = naga::back::spv::write_vec(&copy, &info, options, None)
        .map_err(|e| (format!("naga's SPIR-V writer failed: {e}"), false))?;
    let list = instructions(&words);
    let scalar_type = |words: &[u32], kind: (bool, bool)| -> Vec<u32> {
        list.iter()
            .filter(|&&(at, opcode, len)| match kind {
                (true, _) => opcode == op::TYPE_FLOAT && len >= 3 && words[at + 2] == 32,
                (false, signed) => {
                    opcode == op::TYPE_INT && len == 4 && words[at + 2] == 32 && words[at + 3] == u32::from(signed)
                }
            })
            .map(|&(at, _, _)| words[at + 1])
            .collect()
    };
    let mut decorations = Vec::new();
    for (name, id, kind, sentinel, default_bits) in &specs {
        let types = scalar_type(&words, *kind);
        let found: Vec<usize> = list
            .iter()
            .filter(|&&(at, opcode, len)| {
                opcode == op::CONSTANT && len == 4 && types.contains(&words[at + 1]) && words[at + 3] == *sentinel
            })
            .map(|&(at, _, _)| at)
            .collect();
        let [at] = found[..] else {
            return Err(refuse(
                name,
                format!("naga's writer left {} constants of its sentinel value (one expected)", found.len()),
            ));
        };
        let result = words[at + 2];
        let in_composite = list
            .iter()
            .any(|&(c, opcode, len)| opcode == op::CONSTANT_COMPOSITE && words[c + 3..c + len].contains(&result));
        if in_composite {
            return Err(refuse(name, "naga's writer folded it into a composite constant".into()));
        }
        words[at] = (4 << 16) | op::SPEC_CONSTANT;
        words[at + 3] = *default_bits;
        decorations.extend([(4 << 16) | op::DECORATE, result, op::SPEC_ID, *id]);
    }
    let at =
        annotations_end(&words).ok_or_else(|| ("the written SPIR-V has no type declarations".to_string(), false))?;
    words.splice(at..at, decorations);
    Ok(words)
}

/// The instructions after the five header words of a SPIR-V binary: (start, opcode, length).
/// Stops at a malformed length (the binaries come from naga's writer; its validator and
/// `spirv-val` in the tests judge them).
fn instructions(words: &[u32]) -> Vec<(usize, u32, usize)> {
    let mut at = 5;
    let mut list = Vec::new();
    while at < words.len() {
        let (len, opcode) = ((words[at] >> 16) as usize, words[at] & 0xffff);
        if len == 0 || at + len > words.len() {
            break;
        }
        list.push((at, opcode, len));
        at += len;
    }
    list
}

/// Where a new annotation goes: after the last annotation before the first function, else
/// before the first type declaration (SPIR-V's logical layout puts annotations between the
/// debug instructions and the types).
fn annotations_end(words: &[u32]) -> Option<usize> {
    let list = instructions(words);
    let functions_start = list.iter().find(|i| i.1 == op::FUNCTION).map_or(words.len(), |i| i.0);
    list.iter()
        .rfind(|i| i.0 < functions_start && op::is_annotation(i.1))
        .map(|i| i.0 + i.2)
        .or_else(|| list.iter().find(|i| op::is_type(i.1)).map(|i| i.0))
}

/// Decorates the result of every floating-point arithmetic instruction of a SPIR-V binary
/// `NoContraction`, so that the driver evaluates each operation as written and rounded.
///
/// Why: SPIR-V lets a consumer treat undecorated arithmetic as real-number algebra, and Mesa
/// does (NIR's inexact algebraic rules apply to every ALU instruction not marked exact, and
/// `NoContraction` is what marks it). Measured on lavapipe (Mesa 22.3), undecorated, every
/// error-free transformation folds to zero: the two-sum error `(a − (s − (s − a))) + (b − (s −
/// a))`, `x − ((1 + x) − 1)` and even `fma(a, b, −a·b)`. The f64 routines
/// ([`crate::F64_MATH_WGSL`]) and the f64 evaluation of a user's shader rely on those terms,
/// so the f64 modules carry this decoration (see `skyrun::F64Sky`, which hands the binary to
/// the driver as is). The GLSL.std.450 `Fma` and every other extended instruction are
/// decorated too: Mesa reads the decoration on any ALU result.
pub fn exact_arithmetic(words: &[u32]) -> Vec<u32> {
    // FNegate, FAdd, FSub, FMul, FDiv, FRem, FMod, VectorTimesScalar, MatrixTimesScalar,
    // VectorTimesMatrix, MatrixTimesVector, MatrixTimesMatrix, Dot, ExtInst.
    const ARITHMETIC: [u32; 14] = [127, 129, 131, 133, 136, 140, 141, 142, 143, 144, 145, 146, 148, 12];
    const NO_CONTRACTION: u32 = 42;
    let mut float_types = std::collections::HashSet::new();
    let list = instructions(words);
    let mut decorations = Vec::new();
    for &(at, opcode, len) in &list {
        match opcode {
            op::TYPE_FLOAT if len >= 3 => {
                float_types.insert(words[at + 1]);
            }
            // OpTypeVector and OpTypeMatrix of a float component type are float types too.
            23 | 24 if len >= 4 && float_types.contains(&words[at + 2]) => {
                float_types.insert(words[at + 1]);
            }
            _ if ARITHMETIC.contains(&opcode) && len >= 3 && float_types.contains(&words[at + 1]) => {
                decorations.extend([(3 << 16) | op::DECORATE, words[at + 2], NO_CONTRACTION]);
            }
            _ => {}
        }
    }
    let mut out = words.to_vec();
    if let Some(at) = annotations_end(words) {
        out.splice(at..at, decorations);
    }
    out
}

/// Completes what naga 30's SPIR-V front end leaves out of valid SPIR-V, so that its validator
/// judges the module and not the front end's gaps. Three constructs, all of which naga's own
/// SPIR-V back end writes and `spirv-val` accepts (the conversion tests run it on every module):
/// * The layer count of an arrayed image (`textureSize(array, 0).z`): the back end queries the
///   size with the layers as the last component and extracts it; the front end reads the query
///   as the IR's `Size`, which has no layer component ("TODO: handle arrays and cubes" in
///   `front/spv/image.rs`), so the extract is out of bounds. It is the IR's `NumLayers`.
/// * `OpLogicalAnd`/`OpLogicalOr` on bool vectors (naga's integer-division polyfill uses them)
///   are read as IR `LogicalAnd`/`LogicalOr`, which the IR allows on scalars only. SPIR-V's
///   logical operators evaluate both operands, so the IR's non-short-circuit `And`/`InclusiveOr`
///   on bools say the same thing, for scalars and vectors alike.
/// * `modf`/`frexp` (`ModfStruct`/`FrexpStruct`) are read without registering their result
///   structs as the module's predeclared types, so type resolution fails. gdsky writes them for
///   f32 only; every vector size is registered.
fn complete_spirv_reread(module: &mut naga::Module) {
    use naga::{BinaryOperator as B, Expression as E, MathFunction as M};
    let (mut modf, mut frexp) = (false, false);
    let (types, globals) = (&module.types, &module.global_variables);
    let functions =
        module.functions.iter_mut().map(|(_, f)| f).chain(module.entry_points.iter_mut().map(|e| &mut e.function));
    for function in functions {
        let layer_counts: Vec<_> = function
            .expressions
            .iter()
            .filter_map(|(h, e)| match *e {
                E::AccessIndex { base, index } => match function.expressions[base] {
                    E::ImageQuery { image, query: naga::ImageQuery::Size { .. } } => {
                        let ty = match function.expressions[image] {
                            E::GlobalVariable(g) => globals[g].ty,
                            E::FunctionArgument(i) => function.arguments.get(i as usize)?.ty,
                            _ => return None,
                        };
                        match types[ty].inner {
                            naga::TypeInner::Image { dim, arrayed: true, .. } if index == dimensions(dim) => {
                                Some((h, image))
                            }
                            _ => None,
                        }
                    }
                    _ => None,
                },
                _ => None,
            })
            .collect();
        for (h, image) in layer_counts {
            function.expressions[h] = E::ImageQuery { image, query: naga::ImageQuery::NumLayers };
        }
        for (_, expression) in function.expressions.iter_mut() {
            match expression {
                E::Binary { op, .. } if *op == B::LogicalAnd => *op = B::And,
                E::Binary { op, .. } if *op == B::LogicalOr => *op = B::InclusiveOr,
                E::Math { fun: M::Modf, .. } => modf = true,
                E::Math { fun: M::Frexp, .. } => frexp = true,
                _ => {}
            }
        }
    }
    let sizes = [None, Some(naga::VectorSize::Bi), Some(naga::VectorSize::Tri), Some(naga::VectorSize::Quad)];
    // An f64 module (`lower_f64`) may take modf of f64s too; its frexp is f32 or a routine.
    let f64 = module.types.iter().any(|(_, t)| matches!(t.inner, naga::TypeInner::Scalar(naga::Scalar::F64)));
    for size in sizes {
        let scalar = naga::Scalar::F32;
        if modf {
            module.generate_predeclared_type(naga::PredeclaredType::ModfResult { size, scalar });
            if f64 {
                let scalar = naga::Scalar::F64;
                module.generate_predeclared_type(naga::PredeclaredType::ModfResult { size, scalar });
            }
        }
        if frexp {
            module.generate_predeclared_type(naga::PredeclaredType::FrexpResult { size, scalar });
        }
    }
}

/// How many components the IR's `Size` query has for an image of dimension `dim`.
fn dimensions(dim: naga::ImageDimension) -> u32 {
    match dim {
        naga::ImageDimension::D1 => 1,
        naga::ImageDimension::D2 | naga::ImageDimension::Cube => 2,
        naga::ImageDimension::D3 => 3,
    }
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

#[cfg(test)]
mod guard_tests {
    /// A reader that panics is an error saying what was being done, not an unwinding panic.
    #[test]
    fn a_panicking_reader_becomes_an_error() {
        let outcome: Result<(), String> = super::guarded("re-reading a test", || panic!("inside the reader"));
        let message = outcome.expect_err("the panic is caught");
        assert!(message.contains("naga panicked re-reading a test") && message.contains("nothing was written"));
        assert_eq!(super::guarded("re-reading a test", || 7), Ok(7));
    }

    /// The largest f32 is written exactly: what naga's writer prints for it (Rust's shortest
    /// form) is above it, and the exact digits read back as the same f32.
    #[test]
    fn the_largest_f32_is_written_within_its_type() {
        assert_eq!(format!("{}f", f32::MAX), super::F32_MAX_AS_WRITTEN);
        let exact = super::F32_MAX_EXACT.trim_end_matches('f');
        assert_eq!(exact.parse::<f32>(), Ok(f32::MAX));
        // (2 − 2⁻²³)·2¹²⁷ = (2²⁴ − 1)·2¹⁰⁴, in decimal digits.
        let mut digits = vec![0u32];
        let mut multiply = |by: u64, add: u64| {
            let mut carry = add;
            for d in digits.iter_mut() {
                let v = u64::from(*d) * by + carry;
                *d = (v % 10) as u32;
                carry = v / 10;
            }
            while carry > 0 {
                digits.push((carry % 10) as u32);
                carry /= 10;
            }
        };
        multiply(1, (1 << 24) - 1);
        for _ in 0..104 {
            multiply(2, 0);
        }
        let decimal: String = digits.iter().rev().map(|d| char::from_digit(*d, 10).unwrap_or('?')).collect();
        assert_eq!(decimal, exact);
        let text = super::exact_f32_max("const M: f32 = -340282350000000000000000000000000000000f;".into());
        assert_eq!(text, "const M: f32 = -340282346638528859811704183484516925440f;");
    }
}

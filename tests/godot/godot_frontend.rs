//! The differential front-end check (issue #6): real Godot 4.6 against gdsky on every test shader.
//!
//! One oracle (crates/skyoracle: Godot 4.6.stable's Web export, Compatibility renderer, headless
//! Chromium) is asked whether each shader of `tests/shaders/{valid,invalid}` compiles. gdsky must
//! accept exactly the shaders Godot accepts, except the entries of [`DISAGREEMENTS`] (known,
//! justified, each saying which side is right and why) and of [`EXCLUDED`] (shaders this oracle
//! cannot judge: Godot 4.6 Compatibility limitations that are not language rules, or a test that
//! needs files the oracle does not have). Every entry of both lists is checked to be still true.
//!
//! Where both reject, the line of Godot's first error is compared with the line of gdsky's primary
//! label: they must agree, except the entries of [`LINE_DIFFERENCES`], and except where Godot gives
//! no line or its preprocessor failed (see below), which are only reported.
//!
//! [`PROBES`], small inline shaders for rules of Godot's that the test shaders do not cover (each
//! found by probing Godot with this oracle, most of them once gdsky bugs), go through the same
//! comparison, so those rules are held to Godot too.
//!
//! Both sides' verdicts (Godot's first error line and message; gdsky's first error code, file,
//! line and message) are kept in one snapshot, `snapshots/godot__godot_frontend__verdicts.snap`, so a
//! change on either side shows up in review.
//!
//! How the code reaches Godot:
//! * The oracle has no project files, so every `#include` of a file that exists is inlined (each
//!   file once per shader, as Godot's preprocessor does) and Godot's line numbers are mapped back
//!   to the file and line they came from. An `#include` of a missing file is sent as written.
//! * Godot runs its preprocessor in `Shader::set_code` and, when it fails, compiles the raw text,
//!   whose first directive then stops the tokenizer with "Unknown character #35: '#'". That
//!   message is how a preprocessor error shows here; its line is the first directive's, not the
//!   error's, so it is not compared.
//! * Invalid UTF-8 is sent as U+FFFD, as Godot's loader decodes it.
//!
//! Without the oracle installed (`bash scripts/install-oracle.sh`) this test fails with the
//! oracle's message naming what is missing. It takes about 20 s on 2 cores (5 s to start the
//! oracle and measure its 8-bit store, then about 0.1 s per shader; more under load).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use gdsky::FrontendOutput;
use skyoracle::{CompileOutcome, Oracle, OracleError};

/// Which side of a disagreement is right. A disagreement where Godot is right is a gdsky bug: it
/// is fixed in the front end, not listed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Right {
    /// gdsky follows Godot's language; Godot 4.6 does something else (a bug, or a fallback).
    Gdsky,
}

/// A known, justified disagreement on whether a shader is valid.
struct Disagreement {
    /// The shader, relative to `tests/shaders`.
    file: &'static str,
    /// Which side is right.
    right: Right,
    /// Godot's verdict must still be this: `None` accepted, `Some(text)` an error containing text.
    godot_says: Option<&'static str>,
    /// Why, with Godot's message and where in Godot's source or issues it comes from.
    evidence: &'static str,
}

const DISAGREEMENTS: &[Disagreement] = &[
    Disagreement {
        file: "valid/arrays_initializers.gdshader",
        right: Right::Gdsky,
        godot_says: Some("Unknown identifier in expression: 'b'."),
        evidence: "a Godot parser bug: `a.length() + b.length()` (line 15). In _parse_expression \
                   (servers/rendering/shader_language.cpp), a `.` after an unindexed array parses the whole rest \
                   of the expression, `length() + b.length()`, with the block tag TAG_ARRAY, in which only \
                   `length` resolves, so `b` is unknown. Probed in the oracle: `a.length() + 1` is accepted, \
                   `a.length() + x` is rejected the same way for any variable x, `float(a.length()) + x` is \
                   accepted, and `vec3(b.length() > 1 ? 1.0 : 0.0)` passes the parser but the generated GLSL \
                   `b.(length() > 1 ? …)` fails (\"'(' : Illegal character at fieldname start\"). The same \
                   cause as godotengine/godot#39259 (`array.length() - 1` emitted as `m_array.(length()-1)`), \
                   still open. GLSL and Godot's documentation make `.length()` an ordinary int expression.",
    },
    Disagreement {
        file: "invalid/unterminated_block_comment.gdshader",
        right: Right::Gdsky,
        godot_says: None,
        evidence: "Godot's preprocessor rejects it: ShaderPreprocessor::CommentRemover::get_error returns \"Block \
                   comment mismatch\" and preprocess() returns FAILED (servers/rendering/shader_preprocessor.cpp), \
                   which the shader editor shows. At run time Shader::set_code then compiles the raw text (the \
                   fallback that makes every other preprocessor error here read \"Unknown character #35\"), and \
                   the compiler's tokenizer ends an open block comment at the end of the input without an error \
                   (ShaderLanguage::_get_token). gdsky follows the preprocessor (docs/semantics.md: an \
                   unclosed `/*` is an error).",
    },
    Disagreement {
        file: "invalid/wrong_shader_type_spatial.gdshader",
        right: Right::Gdsky,
        godot_says: None,
        evidence: "valid Godot, but not a sky shader: Godot compiles it as a spatial shader (no error; the shader \
                   says so itself) and a sky material whose shader is not `shader_type sky` is not used as one. \
                   gdsky checks and converts sky shaders only (E102).",
    },
];

/// A shader the oracle cannot judge.
struct Exclusion {
    /// The shader, relative to `tests/shaders`.
    file: &'static str,
    /// `Some(text)`: the shader is still sent, and one of Godot's errors must contain `text` (so the
    /// reason stays true). `None`: it is not sent.
    godot_says: Option<&'static str>,
    /// Why the oracle cannot judge it, with the evidence.
    reason: &'static str,
}

const EXCLUDED: &[Exclusion] = &[
    Exclusion {
        file: "valid/builtin_functions_overloads.gdshader",
        godot_says: Some("Built-in function \"fma(float, float, float)\" is only supported on high-end platforms."),
        reason: "Compatibility limitation: built-ins marked high_end in Godot's table are refused when \
                 RenderingServer::is_low_end() (ShaderLanguage::_validate_function_call), i.e. by the \
                 Compatibility renderer, and accepted by Forward+ and Mobile, whose rules gdsky follows \
                 (CURRENT_RENDERER is RENDERER_FORWARD_PLUS)",
    },
    Exclusion {
        file: "valid/builtin_texture_functions_extra.gdshader",
        godot_says: Some(
            "Built-in function \"textureQueryLevels(sampler2D)\" is only supported on high-end platforms.",
        ),
        reason: "Compatibility limitation: a high-end-only built-in (as builtin_functions_overloads)",
    },
    Exclusion {
        file: "valid/texture_sampling.gdshader",
        godot_says: Some(
            "Built-in function \"textureQueryLevels(sampler2D)\" is only supported on high-end platforms.",
        ),
        reason: "Compatibility limitation: a high-end-only built-in (as builtin_functions_overloads)",
    },
    Exclusion {
        file: "valid/globals_in_helper_function.gdshader",
        godot_says: Some("'position' : undeclared identifier"),
        reason: "Compatibility limitation: Godot's parser accepts it (POSITION, TIME and AT_*_PASS are global \
                 built-ins of sky shaders), but the GLES3 back end emits the shader's functions before it \
                 declares `position`, `time` and the AT_*_PASS macros, so the GLSL fails (\"'position' : \
                 undeclared identifier\", \"'AT_CUBEMAP_PASS' : undeclared identifier\", \"'time' : undeclared \
                 identifier\"). Fixed for TIME after 4.6 by godotengine/godot#118318 (\"Compile error when \
                 using TIME in a custom function … time was defined below where the custom functions are \
                 defined\")",
    },
    Exclusion {
        file: "valid/render_modes_split_statements.gdshader",
        godot_says: Some("'sampler2D' : cannot construct this type"),
        reason: "Compatibility limitation: HALF_RES_COLOR/QUARTER_RES_COLOR compile to GLSL that constructs a \
                 sampler2D with SAMPLER_LINEAR_CLAMP, copied from the Vulkan back end (\"'sampler2D' : cannot \
                 construct this type\"); godotengine/godot#118318 (after 4.6): \"HALF_RES_COLOR and \
                 QUARTER_RES_COLOR lead to compile errors since they are copy-pasted from the vulkan backend. \
                 The compatibility renderer doesn't support half or quarter res rendering\"; also \
                 godotengine/godot-docs#10905",
    },
    Exclusion {
        file: "valid/sky_builtins_in_sky.gdshader",
        godot_says: Some("'samplerCube' : cannot construct this type"),
        reason: "Compatibility limitation: HALF_RES_COLOR/QUARTER_RES_COLOR in the cubemap pass construct a \
                 samplerCube with SAMPLER_LINEAR_WITH_MIPMAPS_CLAMP (as render_modes_split_statements; \
                 godotengine/godot#118318)",
    },
    Exclusion {
        file: "probe/local_named_like_sky_only_builtin_used",
        godot_says: Some("'cube_normal' : undeclared identifier"),
        reason: "Compatibility back end: Godot's parser accepts a local named EYEDIR in a helper function (a \
                 local clashes only with the built-ins of its own function: _find_identifier with the helper's \
                 FunctionInfo), and probe/local_named_like_sky_only_builtin_in_helper shows it; but its compiler \
                 renames every use of the name to the sky pass's variable, also where it means the local, so \
                 once the helper is called the GLSL fails (\"'cube_normal' : undeclared identifier\")",
    },
    Exclusion {
        file: "invalid/pp_include_cycle.gdshader",
        godot_says: None,
        reason: "an include cycle needs the included files, which the oracle's Web export does not have, and \
                 inlined, a cycle cannot be written down",
    },
];

/// Shaders both sides reject where the first error's line differs on purpose.
const LINE_DIFFERENCES: &[(&str, &str)] = &[(
    "invalid/missing_return_in_non_void_function.gdshader",
    "Godot reports a missing `return` at the function's closing `}` (line 7); gdsky points at the function's \
     name (line 5), as the shader's `// expect:` says",
)];

/// Small shaders for rules the test shaders do not cover, each written to show one rule of
/// Godot's that gdsky once got wrong (found by probing Godot 4.6 with this oracle) or that sits
/// next to one: `(name, code after "shader_type sky;")`. The file name in the snapshot is
/// `probe/NAME`. They go through the same comparison as the test shaders.
const PROBES: &[(&str, &str)] = &[
    // Uniform defaults: Godot folds literals, `-` and constructors, then convert_constant.
    (
        "uniform_default_int_to_float",
        "uniform float f : hint_range(0, 10) = 5;\nglobal uniform float g = 1;\nvoid sky() { COLOR = vec3(f); }",
    ),
    (
        "uniform_default_int_uint",
        "uniform uint u = 1;\nuniform int i = 1u;\nvoid sky() { COLOR = vec3(float(u) + float(i)); }",
    ),
    (
        "uniform_default_negated_and_constructed",
        "uniform float n = -(1);\nuniform vec3 c = vec3(1, -2, 3u);\nvoid sky() { COLOR = c * n; }",
    ),
    ("uniform_default_binary_operator", "uniform float f = 1.0 + 1.0;\nvoid sky() { COLOR = vec3(f); }"),
    ("uniform_default_named_constant", "const float K = 2.0;\nuniform float f = K;\nvoid sky() { COLOR = vec3(f); }"),
    ("uniform_default_float_to_int_constructor", "uniform int i = int(1.5);\nvoid sky() { COLOR = vec3(float(i)); }"),
    ("uniform_default_negative_uint", "uniform uint u = -1;\nvoid sky() { COLOR = vec3(float(u)); }"),
    ("uniform_default_scalar_for_vector", "uniform vec3 v = 1;\nvoid sky() { COLOR = v; }"),
    // Implicit conversion of constant arguments.
    ("convert_negated_literals", "void sky() { float a = abs(-3); vec3 v = vec3(-1, 2, +3); COLOR = v * a; }"),
    (
        "convert_constructed_constants",
        "void sky() { float a = sin(int(1)); vec2 v = vec2(1.0, int(2)); COLOR = vec3(v, a); }",
    ),
    ("convert_int_to_bool", "void sky() { bvec2 b = bvec2(1, 0); COLOR = vec3(b.x ? 1.0 : 0.0); }"),
    ("convert_negative_to_uint", "void sky() { uvec2 u = uvec2(-1); COLOR = vec3(float(u.x)); }"),
    ("convert_negative_to_uint_parameter", "float f(uint x) { return float(x); }\nvoid sky() { COLOR = vec3(f(-1)); }"),
    ("convert_in_struct_constructor", "struct S { float a; };\nvoid sky() { S s = S(1); COLOR = vec3(s.a); }"),
    ("convert_in_array_constructor", "void sky() { float a[2] = float[2](1, 2); COLOR = vec3(a[0]); }"),
    // Operators.
    (
        "operators_accepted",
        "void sky() {\n int i = 1 << 2; uint u = 1u >> 1u; ivec2 a = ivec2(1) << 2;\n \
         uvec2 b = uvec2(1u) << uvec2(1u);\n a &= 3; b |= 1u; a %= 2; ivec2 m = ivec2(1) % 2;\n \
         bool t = +true; mat2 p = +mat2(1.0);\n \
         COLOR = vec3(float(i + a.x + m.y) + float(u + b.x) + p[0][0], t ? 1.0 : 0.0, 0.0);\n}",
    ),
    ("shift_int_by_uint", "void sky() { int x = 1 << 2u; COLOR = vec3(float(x)); }"),
    ("shift_ivec_by_uint", "void sky() { ivec2 x = ivec2(1) << 1u; COLOR = vec3(float(x.x)); }"),
    ("modulo_scalar_by_vector", "void sky() { ivec2 x = 2 % ivec2(1); COLOR = vec3(float(x.x)); }"),
    ("bitwise_vector_and_scalar", "void sky() { ivec2 x = ivec2(1) & 3; COLOR = vec3(float(x.x)); }"),
    ("negate_matrix", "void sky() { mat2 m = -mat2(1.0); COLOR = vec3(m[0][0]); }"),
    ("increment_matrix", "void sky() { mat2 m = mat2(1.0); m++; COLOR = vec3(m[0][0]); }"),
    ("compare_arrays", "void sky() { float a[2] = {1.0, 2.0}; bool c = a == a; COLOR = vec3(c ? 1.0 : 0.0); }"),
    // Names.
    // (h() is not called: Godot's compiler leaves it out of the GLSL; see the exclusion of
    // local_named_like_sky_only_builtin_used for what happens when it is.)
    (
        "local_named_like_sky_only_builtin_in_helper",
        "float h() { vec3 EYEDIR = vec3(1.0); float ALPHA = EYEDIR.x; return ALPHA; }\nstruct S { float a; };\n\
         void sky() { float S = 1.0; COLOR = vec3(S); }",
    ),
    (
        "local_named_like_sky_only_builtin_used",
        "float h() { vec3 EYEDIR = vec3(1.0); return EYEDIR.x; }\nvoid sky() { COLOR = vec3(h()); }",
    ),
    ("local_named_like_builtin_in_sky", "void sky() { vec3 EYEDIR = vec3(1.0); COLOR = EYEDIR; }"),
    (
        "local_named_like_global_builtin_in_helper",
        "float h() { float TIME = 1.0; return TIME; }\nvoid sky() { COLOR = vec3(h()); }",
    ),
    (
        "parameter_named_like_uniform",
        "uniform float u;\nfloat h(float u) { return u; }\nvoid sky() { COLOR = vec3(h(1.0)); }",
    ),
    (
        "parameter_named_like_constant",
        "const float K = 1.0;\nfloat h(float K) { return K; }\nvoid sky() { COLOR = vec3(h(1.0)); }",
    ),
];

/// One side's verdict on a shader: accepted, or its first error.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Verdict {
    accepted: bool,
    /// `file:line` of the first error (the file relative to `tests/shaders`), if it has one.
    place: Option<String>,
    /// The first error, as this side words it.
    message: String,
}

impl Verdict {
    fn describe(&self) -> String {
        if self.accepted {
            return "accept".into();
        }
        format!("reject {} {}", self.place.as_deref().unwrap_or("(no line)"), self.message)
    }
}

/// The code sent to Godot and, for each of its lines, the file (relative to `tests/shaders`)
/// and 1-based line it came from.
struct Sent {
    code: String,
    origin: Vec<(String, usize)>,
}

fn shaders_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/shaders")
}

/// `path` relative to `tests/shaders`, with `/` separators.
fn short(path: &Path) -> String {
    let dir = shaders_dir();
    let dir = dir.canonicalize().unwrap_or(dir);
    let path = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
    path.strip_prefix(&dir).unwrap_or(&path).to_string_lossy().replace('\\', "/")
}

/// The quoted path of an `#include` directive line, if the line is one.
fn include_target(line: &str) -> Option<&str> {
    let rest = line.trim_start().strip_prefix('#')?.trim_start().strip_prefix("include")?;
    let rest = rest.trim_start().strip_prefix('"')?;
    rest.split_once('"').map(|(target, _)| target)
}

/// Appends `path`'s text to `sent`, with every `#include` of an existing file replaced by that
/// file's text (each file once per shader, as Godot's preprocessor does: a later `#include` of the
/// same file becomes an empty line). An `#include` of a missing file stays as written: the oracle
/// does not have it either. Invalid UTF-8 becomes U+FFFD, as Godot's loader decodes it.
fn inline(path: &Path, seen: &mut Vec<PathBuf>, sent: &mut Sent) {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let text = String::from_utf8_lossy(&bytes).into_owned();
    let name = short(path);
    let mut lines: Vec<&str> = text.split('\n').collect();
    // A trailing newline ends the last line; it does not start another.
    if text.ends_with('\n') {
        lines.pop();
    }
    for (i, line) in lines.iter().enumerate() {
        let included = include_target(line).map(|target| path.parent().expect("a file has a directory").join(target));
        match included.filter(|file| file.is_file()) {
            Some(file) => {
                let file = file.canonicalize().expect("an existing file canonicalizes");
                if seen.contains(&file) {
                    sent.code.push('\n');
                    sent.origin.push((name.clone(), i + 1));
                } else {
                    seen.push(file.clone());
                    inline(&file, seen, sent);
                }
            }
            None => {
                sent.code.push_str(line);
                sent.code.push('\n');
                sent.origin.push((name.clone(), i + 1));
            }
        }
    }
}

/// The code to send to Godot for the shader at `path`.
fn code_for(path: &Path) -> Sent {
    let mut sent = Sent { code: String::new(), origin: Vec::new() };
    let root = path.canonicalize().expect("a test shader canonicalizes");
    inline(path, &mut vec![root], &mut sent);
    sent
}

/// gdsky's verdict: its first error (code, place of the primary label, message), or acceptance.
fn gdsky_verdict(output: &FrontendOutput) -> Verdict {
    match output.diagnostics.iter().find(|d| d.is_error()) {
        None => Verdict { accepted: true, place: None, message: String::new() },
        Some(error) => {
            let place = error.primary_label().map(|label| {
                let (line, _) = output.db.line_col(label.file, label.range.start);
                format!("{}:{line}", short(Path::new(output.db.name(label.file))))
            });
            Verdict { accepted: false, place, message: format!("{} {}", error.code, error.message) }
        }
    }
}

/// The GLES3 back end's summary line, which the GLSL compiler's own errors follow.
const GLSL_FAILED: &str = "SkyShaderGLES3: Fragment shader compilation failed:";
/// What Godot's compiler says when its preprocessor failed and it was given the raw text.
const RAW_DIRECTIVE: &str = "Tokenizer: Unknown character #35: '#'";

/// Godot's verdict: its first error, with the line mapped back through the inlining (and, for a
/// GLSL failure, the GLSL compiler's first error, which says what failed).
fn godot_verdict(outcome: &CompileOutcome, sent: &Sent) -> Verdict {
    let Some(first) = outcome.errors.first() else {
        return if outcome.accepted {
            Verdict { accepted: true, place: None, message: String::new() }
        } else {
            Verdict { accepted: false, place: None, message: "(an error without a message)".into() }
        };
    };
    let place = first.line.map(|line| match sent.origin.get((line as usize).wrapping_sub(1)) {
        Some((file, line)) => format!("{file}:{line}"),
        None => format!("?:{line} (past the end of the code sent)"),
    });
    let mut message = first.message.clone();
    if message == GLSL_FAILED
        && let Some(next) = outcome.errors.get(1)
    {
        write!(message, " {}", next.message).unwrap();
    }
    Verdict { accepted: false, place, message }
}

/// Compiles `code` in Godot; an oracle failure (not a rejected shader) restarts it once.
fn compile(oracle: &mut Oracle, code: &str, name: &str) -> CompileOutcome {
    match oracle.compile(code) {
        Ok(outcome) | Err(OracleError::Shader(outcome)) => outcome,
        Err(first) => {
            eprintln!("{name}: the oracle failed ({first}); restarting it once");
            oracle.restart().unwrap_or_else(|e| panic!("{name}: the oracle could not restart: {e}"));
            oracle.compile(code).unwrap_or_else(|e| panic!("{name}: the oracle failed twice: {e}"))
        }
    }
}

/// Whether Godot's verdict is `says` (`None`: accepted; `Some(text)`: an error containing text).
fn godot_still_says(outcome: &CompileOutcome, says: Option<&str>) -> bool {
    match says {
        None => outcome.accepted,
        Some(text) => !outcome.accepted && outcome.errors.iter().any(|e| e.message.contains(text)),
    }
}

/// Every test shader, valid ones first, each directory sorted.
fn test_shaders() -> Vec<PathBuf> {
    let mut files = Vec::new();
    for dir in ["valid", "invalid"] {
        let mut entries: Vec<PathBuf> = std::fs::read_dir(shaders_dir().join(dir))
            .expect("test shader directory")
            .map(|e| e.expect("directory entry").path())
            .filter(|p| p.extension().is_some_and(|e| e == "gdshader"))
            .collect();
        entries.sort();
        files.extend(entries);
    }
    files
}

#[test]
fn gdsky_accepts_exactly_what_godot_accepts() {
    let started = Instant::now();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut oracle = skytest::oracle();
    let boot = started.elapsed();

    let files = test_shaders();
    // Each case: its name, gdsky's output, and the code Godot gets (the file's, inlined).
    let mut cases: Vec<(String, FrontendOutput, Sent)> = files
        .iter()
        .map(|path| {
            let rel = path.strip_prefix(root).unwrap_or(path);
            let output = gdsky::check_file(rel).expect("test shader is readable");
            (short(path), output, code_for(path))
        })
        .collect();
    for (probe, body) in PROBES {
        let name = format!("probe/{probe}");
        let code = format!("shader_type sky;\n{body}\n");
        let output = gdsky::check_source(&name, code.clone().into_bytes(), None, &mut gdsky::frontend::FsLoader);
        let origin = (1..=code.lines().count()).map(|line| (name.clone(), line)).collect();
        cases.push((name, output, Sent { code, origin }));
    }
    let names: Vec<String> = cases.iter().map(|c| c.0.clone()).collect();
    let mut problems = Vec::new();
    for listed in DISAGREEMENTS.iter().map(|d| d.file).chain(EXCLUDED.iter().map(|e| e.file)) {
        if !names.iter().any(|n| n == listed) {
            problems.push(format!("{listed} is listed but is not a test shader"));
        }
    }

    let mut report = String::new();
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    // Where both reject: with a line Godot's compiler gave for the error itself, and of those,
    // on the same line.
    let (mut both_reject, mut comparable, mut same_line) = (0, 0, 0);
    for (name, output, sent) in &cases {
        let gdsky = gdsky_verdict(output);
        writeln!(report, "{name}").unwrap();
        let exclusion = EXCLUDED.iter().find(|e| e.file == name);
        let outcome = match exclusion {
            Some(Exclusion { godot_says: None, .. }) => None,
            _ => {
                let outcome = compile(&mut oracle, &sent.code, name);
                let godot = godot_verdict(&outcome, sent);
                Some((outcome, godot))
            }
        };
        if let Some((_, godot)) = &outcome {
            writeln!(report, "  godot: {}", godot.describe()).unwrap();
        }
        writeln!(report, "  gdsky: {}", gdsky.describe()).unwrap();

        if let Some(exclusion) = exclusion {
            let how = if exclusion.godot_says.is_some() { "Godot's reason checked" } else { "not sent" };
            writeln!(report, "  excluded ({how}; see EXCLUDED)").unwrap();
            *counts.entry("excluded").or_default() += 1;
            if let Some((outcome, godot)) = &outcome
                && !godot_still_says(outcome, exclusion.godot_says)
            {
                problems.push(format!(
                    "{name}: excluded because Godot says {:?}, but Godot now says: {}",
                    exclusion.godot_says,
                    godot.describe()
                ));
            }
            continue;
        }
        let Some((outcome, godot)) = outcome else { unreachable!("only exclusions are not sent") };
        match (godot.accepted == gdsky.accepted, DISAGREEMENTS.iter().find(|d| d.file == name)) {
            (true, None) => {
                let key = match (name.starts_with("probe/"), godot.accepted) {
                    (false, true) => "agree valid",
                    (false, false) => "agree invalid",
                    (true, true) => "probes agree valid",
                    (true, false) => "probes agree invalid",
                };
                *counts.entry(key).or_default() += 1;
            }
            (false, Some(d)) if godot_still_says(&outcome, d.godot_says) => {
                writeln!(report, "  documented disagreement: {:?} is right (see DISAGREEMENTS)", d.right).unwrap();
                *counts.entry("disagree (documented)").or_default() += 1;
            }
            (_, Some(d)) => problems.push(format!(
                "{name}: listed as a disagreement where Godot says {:?}, but now Godot: {}; gdsky: {}",
                d.godot_says,
                godot.describe(),
                gdsky.describe()
            )),
            (false, None) => problems.push(format!(
                "{name}: Godot and gdsky disagree\n  godot: {}\n  gdsky: {}\n  Godot's log:\n    {}",
                godot.describe(),
                gdsky.describe(),
                outcome.log.join("\n    ")
            )),
        }

        if !godot.accepted && !gdsky.accepted {
            both_reject += 1;
            let line_note = LINE_DIFFERENCES.iter().find(|(file, _)| file == name);
            let verdict = if godot.place.is_none() {
                "not compared (Godot gives no line)".to_string()
            } else if godot.message == RAW_DIRECTIVE {
                "not compared (Godot's preprocessor failed; its line is the raw text's first directive)".to_string()
            } else {
                comparable += 1;
                let same = godot.place == gdsky.place;
                same_line += usize::from(same);
                match (same, line_note) {
                    (true, None) => "same".to_string(),
                    (false, Some(_)) => "differs (documented in LINE_DIFFERENCES)".to_string(),
                    (true, Some(_)) => {
                        problems.push(format!("{name}: listed in LINE_DIFFERENCES, but both report the same line"));
                        "same, but listed as different".to_string()
                    }
                    (false, None) => {
                        problems.push(format!(
                            "{name}: the first error's line differs\n  godot: {}\n  gdsky: {}",
                            godot.describe(),
                            gdsky.describe()
                        ));
                        "differs".to_string()
                    }
                }
            };
            writeln!(report, "  line: {verdict}").unwrap();
        }
    }
    for (file, _) in LINE_DIFFERENCES {
        if !names.iter().any(|n| n == file) {
            problems.push(format!("{file} is listed in LINE_DIFFERENCES but is not a test shader"));
        }
    }

    let summary = format!(
        "{} test shaders and {} probes: {}\nboth reject {both_reject}: Godot's first error has a comparable line in \
         {comparable}, the same line as gdsky's in {same_line}",
        files.len(),
        PROBES.len(),
        counts.iter().map(|(k, v)| format!("{k} {v}")).collect::<Vec<_>>().join(", ")
    );
    println!("{summary}");
    for d in DISAGREEMENTS {
        println!("documented disagreement, {}: {:?} is right: {}", d.file, d.right, d.evidence);
    }
    for e in EXCLUDED {
        println!("excluded, {}: {}", e.file, e.reason);
    }
    for (file, why) in LINE_DIFFERENCES {
        println!("line difference, {file}: {why}");
    }
    println!("oracle start {boot:.1?}, whole test {:.1?}", started.elapsed());
    for problem in &problems {
        eprintln!("{problem}\n");
    }
    insta::assert_snapshot!("verdicts", format!("{summary}\n\n{report}"));
    assert!(problems.is_empty(), "{} problem(s):\n{}", problems.len(), problems.join("\n"));
}

//! # gdshader: the Godot shading language front end
//!
//! gdsky ports Godot 4 sky shaders to WGSL and SPIR-V. This crate is its first half: it reads a
//! `.gdshader` file and decides, with Godot's own rules, whether it is a valid sky shader, and
//! what every name and expression in it means. It knows nothing of naga or GPUs; the lowering
//! crate takes a [`CheckedShader`] from here.
//!
//! ## Stages
//!
//! ```text
//! bytes ─ UTF-8 check ─ preprocess ─ parse ─ check ─▶ CheckedShader + diagnostics
//! ```
//!
//! * [`preprocess`] runs `#define`/`#if`/`#include` as Godot's shader preprocessor does, and
//!   keeps a [`SourceMap`] from every byte of its output back to the file it came from.
//! * [`parse`] is a pest grammar for the whole language as sky shaders use it, preceded by a
//!   pre-scan that bounds nesting (so no input can overflow the stack) and followed by a builder
//!   that makes an AST with a span on every node.
//! * [`check`] resolves names, types expressions, folds constants and enforces Godot's rules.
//!
//! Each stage reports [`Diagnostic`]s instead of stopping at the first problem (the parser is the
//! exception: a syntax error ends parsing, since pest does not recover). Stages after the
//! preprocessor report in preprocessed-text coordinates; [`check_source`] maps them back through
//! the source map so every diagnostic names the file, line and column the user wrote.
//!
//! ## Example
//!
//! ```
//! use gdshader::{FsLoader, check_source};
//!
//! let source = b"shader_type sky;\nuniform float exposure : hint_range(0.0, 4.0) = 1.0;\n\
//!                void sky() { COLOR = EYEDIR * exposure; }";
//! let output = check_source("sky.gdshader", source.to_vec(), None, &mut FsLoader);
//! assert!(!output.has_errors());
//! let shader = output.shader.expect("valid");
//! assert_eq!(shader.uniforms[0].name, "exposure");
//! assert_eq!(shader.uniforms[0].default_text.as_deref(), Some("1.0"));
//! assert!(shader.builtins_used.contains("EYEDIR"));
//! ```
//!
//! ## Safety on hostile input
//!
//! Any bytes give diagnostics, never a panic, hang or unbounded memory: invalid UTF-8 and control
//! characters are reported before parsing; nesting is bounded before pest recurses; expression
//! trees are bounded in depth; macro expansion is bounded in size; array sizes are bounded. The
//! front end also runs on a thread with a generous stack, so a recursion bound that is generous
//! to real shaders cannot become a crash on a small default stack. `fuzz/` holds a cargo-fuzz
//! target for all of it.

pub mod check;
pub mod diag;
pub mod parse;
pub mod preprocess;
pub mod values;

pub use check::CheckedShader;
pub use diag::{Diagnostic, FileId, Label, Severity, SourceDb};
pub use preprocess::{FsLoader, Loader, SourceMap};

use parse::SpannedDiagnostic;
use std::path::{Path, PathBuf};

/// Stack size of the thread the front end runs on: enough for [`parse::MAX_NESTING`] levels of
/// pest recursion in an unoptimised build, with a wide margin.
const FRONTEND_STACK_BYTES: usize = 256 << 20;

/// Everything one run of the front end produced.
pub struct FrontendOutput {
    /// Every file read (the shader and its includes), for rendering diagnostics.
    pub db: SourceDb,
    /// The file that was checked.
    pub root: FileId,
    /// Errors and warnings, in the order found.
    pub diagnostics: Vec<Diagnostic>,
    /// The checked shader, when there were no errors.
    pub shader: Option<CheckedShader>,
    /// The text the parser saw, its map back to the files, and the files read through
    /// `#include`. Spans in [`CheckedShader`] are offsets of this text.
    pub preprocessed: preprocess::Preprocessed,
}

impl FrontendOutput {
    /// The file and byte range a span of the checked shader stands for.
    pub fn locate(&self, span: parse::ast::Span) -> (FileId, std::ops::Range<usize>) {
        self.preprocessed.map.locate(span.range()).unwrap_or((self.root, 0..0))
    }

    /// True when any diagnostic is an error.
    pub fn has_errors(&self) -> bool {
        self.diagnostics.iter().any(Diagnostic::is_error)
    }
}

/// Reads and checks the shader at `path`, reading includes from disk.
///
/// The file is read with [`skycore::io::read_limited`]: it must be a regular file (a FIFO, a
/// device, a socket or a directory is refused before it is opened) of at most
/// [`preprocess::MAX_SOURCE_BYTES`] (4 MiB, the most a shader and its includes may come to);
/// anything else is an error, as is a file that cannot be read.
pub fn check_file(path: &Path) -> std::io::Result<FrontendOutput> {
    let bytes = skycore::io::read_limited(path, preprocess::MAX_SOURCE_BYTES)?;
    Ok(check_source(&path.display().to_string(), bytes, Some(path.to_path_buf()), &mut FsLoader))
}

/// Checks shader source `bytes` named `name` (a display name; `path`, when given, is where
/// relative `#include`s are resolved from).
pub fn check_source(
    name: &str,
    bytes: Vec<u8>,
    path: Option<PathBuf>,
    loader: &mut (dyn Loader + Send),
) -> FrontendOutput {
    std::thread::scope(|scope| {
        let worker = std::thread::Builder::new()
            .stack_size(FRONTEND_STACK_BYTES)
            .spawn_scoped(scope, || run(name, bytes, path, loader));
        match worker.map(|handle| handle.join()) {
            Ok(Ok(output)) => output,
            // A failed spawn or a panic is a bug in gdsky, not in the shader; say so plainly.
            _ => internal_error(name),
        }
    })
}

fn internal_error(name: &str) -> FrontendOutput {
    let mut db = SourceDb::new();
    let root = db.add(name, String::new(), None);
    let diagnostics = vec![
        Diagnostic::error("E999", "internal error in the gdsky front end")
            .with_primary(root, 0..0, "")
            .with_note("this is a bug in gdsky; please report it with the shader that caused it"),
    ];
    FrontendOutput { db, root, diagnostics, shader: None, preprocessed: preprocess::Preprocessed::default() }
}

fn run(name: &str, bytes: Vec<u8>, path: Option<PathBuf>, loader: &mut dyn Loader) -> FrontendOutput {
    let mut db = SourceDb::new();
    let mut diagnostics = Vec::new();
    let text = match String::from_utf8(bytes) {
        Ok(text) => text,
        Err(err) => {
            let at = err.utf8_error().valid_up_to();
            let lossy = String::from_utf8_lossy(err.as_bytes()).into_owned();
            let root = db.add(name, lossy, path);
            diagnostics.push(
                Diagnostic::error(diag::codes::INVALID_UTF8, "the file is not valid UTF-8")
                    .with_primary(root, at..at + 1, "invalid byte sequence here")
                    .with_note("Godot reads shaders as UTF-8 text; re-save the file as UTF-8"),
            );
            return FrontendOutput {
                db,
                root,
                diagnostics,
                shader: None,
                preprocessed: preprocess::Preprocessed::default(),
            };
        }
    };
    let root = db.add(name, text, path);
    let pre = preprocess::preprocess(&mut db, root, loader, &mut diagnostics);
    let shader = parse_and_check(&pre, root, &mut diagnostics);
    FrontendOutput { db, root, diagnostics, shader, preprocessed: pre }
}

/// Parses and checks preprocessed text; `None` when there were errors.
fn parse_and_check(
    pre: &preprocess::Preprocessed,
    root: FileId,
    diagnostics: &mut Vec<Diagnostic>,
) -> Option<CheckedShader> {
    if diagnostics.iter().any(Diagnostic::is_error) {
        // Like Godot, stop at preprocessor errors: the text they leave behind is not what the
        // author meant, and parsing it would only report the consequences.
        return None;
    }
    let (ast, parse_diags) = parse::parse(&pre.text);
    diagnostics.extend(parse_diags.into_iter().map(|d| locate(d, &pre.map, root)));
    if diagnostics.iter().any(Diagnostic::is_error) {
        return None;
    }
    let (checked, check_diags) = check::check(ast);
    diagnostics.extend(check_diags.into_iter().map(|d| locate(d, &pre.map, root)));
    (!diagnostics.iter().any(Diagnostic::is_error)).then_some(checked)
}

/// Turns a diagnostic in preprocessed-text coordinates into one with file labels.
fn locate(d: SpannedDiagnostic, map: &SourceMap, root: FileId) -> Diagnostic {
    let mut out = d.diagnostic;
    let place = |span: parse::ast::Span| map.locate(span.range()).unwrap_or((root, 0..0));
    let (file, range) = place(d.primary.0);
    if map.in_expansion(d.primary.0.start as usize) {
        out.notes.push("the problem is in the text this macro invocation expands to".into());
    }
    out.labels.push(Label { file, range, message: d.primary.1, primary: true });
    for (span, message) in d.secondary {
        let (file, range) = place(span);
        out.labels.push(Label { file, range, message, primary: false });
    }
    out
}

//! The preprocessor: `#define`, `#if`, `#include` and friends, as Godot's shader preprocessor
//! runs them, producing one text for the parser and a [`SourceMap`] back to the files.
//!
//! One pass over each file. Ordinary text is copied byte for byte (comments included, since the
//! parser wants `/** … */` doc comments) except where a macro name is found: the invocation is
//! expanded with C's rules (see `expand.rs`) and the result mapped to the invocation. A line whose
//! first non-blank character is `#` (outside a comment) is a directive; directive lines, their
//! `\` continuation lines and the lines of branches not taken become empty lines, so the output
//! keeps the line structure of the input.
//!
//! Where Godot's behaviour (`servers/rendering/shader_preprocessor.cpp`) is followed rather than
//! C's: a macro may not be redefined (even to the same text) until it is `#undef`ined; `##`
//! pastes tokens (the docs show it); `#if` conditions use GDScript's operator precedence (see
//! `expr.rs`); each file is included at most once per shader (a second `#include` of it is
//! skipped); conditionals cannot span files; `#pragma disable_preprocessor` turns the
//! preprocessor off for all the text after it, in the files that included this one too; and
//! these are errors: an unclosed `/*` or a stray `*/` ("Block comment mismatch"), `#` after code
//! on a line, a blank between `#` and the directive name, any pragma but `disable_preprocessor`,
//! `#define F()`, and an empty macro argument. Unlike Godot (which stops at the first error), processing goes on
//! after an error, dropping the failed directive, so later problems are reported too.
//!
//! Everything is bounded: include depth 25, macro nesting 256, expansion work and output length
//! proportional to the input. No input makes it panic, recurse without bound, or loop.

mod expand;
mod expr;
mod lex;
mod source_map;
#[cfg(test)]
mod tests;

pub use source_map::SourceMap;

use crate::diag::{Diagnostic, FileId, SourceDb, codes};
use expand::{Expander, Limit, Macro, Sink, SrcCursor, Stop};
use lex::{Kind, Tok};
use skycore::io::normalize;
use std::collections::HashSet;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// Reads the files `#include` names. The CLI reads from disk; tests and the fuzzer from memory.
pub trait Loader {
    /// The bytes of the file at `path`.
    fn load(&mut self, path: &Path) -> std::io::Result<Vec<u8>>;
}

/// Reads includes from the file system, each through [`skycore::io::read_limited`] with the limit
/// [`MAX_SOURCE_BYTES`]: an include that is a FIFO, a device, a socket or a directory, or that is
/// larger than the whole shader may be, is refused before it is read.
pub struct FsLoader;

impl Loader for FsLoader {
    fn load(&mut self, path: &Path) -> std::io::Result<Vec<u8>> {
        skycore::io::read_limited(path, MAX_SOURCE_BYTES)
    }
}

/// Most bytes one shader may read: the file itself and all its includes together (4 MiB; a real
/// sky shader is tens of KiB, the Freeman sky 18 KB). [`crate::check_file`] refuses a larger
/// shader file unread; an include that would take the total over it is an `E016` error.
pub const MAX_SOURCE_BYTES: u64 = MAX_TOTAL_INPUT as u64;

/// What the preprocessor hands to the parser.
#[derive(Clone, Debug, Default)]
pub struct Preprocessed {
    /// The text with directives removed (each directive line left as an empty line) and macros
    /// expanded.
    pub text: String,
    /// Maps offsets of `text` back to source files.
    pub map: SourceMap,
    /// Every file read through `#include`, in order first read (for `cargo:rerun-if-changed`).
    pub includes: Vec<PathBuf>,
}

/// Deepest nesting of `#include`s Godot accepts.
const MAX_INCLUDE_DEPTH: usize = 25;
/// Most files one shader may include in all, and most bytes it may read with them. (Godot has
/// no such limits, but a real shader comes nowhere near them, and without them 25 levels of
/// includes each naming new paths could read exponentially many files.)
const MAX_INCLUDED_FILES: usize = 1024;
const MAX_TOTAL_INPUT: usize = 4 << 20;
/// The preprocessed text never grows past this many bytes...
const OUTPUT_CAP: usize = 4 << 20;
/// ...nor past this many times the input (but always allows [`OUTPUT_FLOOR`]).
const OUTPUT_FACTOR: usize = 32;
const OUTPUT_FLOOR: usize = 1 << 20;
/// Tokens macro expansion may read in all: this many, plus [`WORK_FACTOR`] per byte of input, up
/// to [`WORK_CAP`]. (2 MB of nothing but nested macro calls reads about 4 per byte; a token takes
/// some 30–100 ns.)
const WORK_FLOOR: u64 = 2 << 20;
const WORK_FACTOR: u64 = 8;
const WORK_CAP: u64 = 8 << 20;
/// The preprocessor stops reporting after this many diagnostics.
const MAX_DIAGNOSTICS: usize = 200;

/// Godot's built-in defines (4.4+). gdsky emulates the Forward+ renderer.
const BUILTINS: [(&str, &str); 4] = [
    ("CURRENT_RENDERER", "2"),
    ("RENDERER_COMPATIBILITY", "0"),
    ("RENDERER_MOBILE", "1"),
    ("RENDERER_FORWARD_PLUS", "2"),
];

const DIRECTIVES_NOTE: &str = "expected one of `#define`, `#undef`, `#if`, `#ifdef`, `#ifndef`, `#elif`, `#else`, `#endif`, `#include`, `#pragma` or `#error`";

/// Preprocesses the file `root` of `db`, reading includes through `loader` and adding them to
/// `db`. Problems are pushed onto `diagnostics`; the returned text is still usable for parsing
/// when there were errors (failed directives are dropped).
pub fn preprocess(
    db: &mut SourceDb,
    root: FileId,
    loader: &mut dyn Loader,
    diagnostics: &mut Vec<Diagnostic>,
) -> Preprocessed {
    let root_path = db.path(root).map(normalize);
    let root_name = db.name(root).to_string();
    let root_len = db.text(root).len();
    let mut pp = Pp {
        db,
        loader,
        diags: diagnostics,
        reported: 0,
        out: String::with_capacity(root_len + root_len / 8),
        map: SourceMap::new(),
        includes: Vec::new(),
        seen: HashSet::new(),
        files: vec![Frame { path: root_path, name: root_name, site: None }],
        exp: Expander::new(),
        disabled: false,
        input_len: 0,
        project_root: None,
        include_limit_hit: false,
        reported_cycle: false,
        reported_depth: false,
    };
    for (name, value) in BUILTINS {
        pp.exp.define(Macro {
            name: Rc::from(name),
            params: None,
            body: lex::lex_all(value).into(),
            builtin: true,
            def: None,
        });
    }
    pp.add_input(root_len);
    pp.process_file(root);
    Preprocessed { text: pp.out, map: pp.map, includes: pp.includes }
}

/// A file being preprocessed (the root, or an include being read).
struct Frame {
    path: Option<PathBuf>,
    name: String,
    /// The path of the `#include` that read it (file and range), for includes.
    site: Option<(FileId, Range<usize>)>,
}

/// An open `#if` / `#ifdef` / `#ifndef`.
struct Cond {
    /// Text of the current branch is kept.
    active: bool,
    /// A branch has been taken (or the whole conditional is inside a skipped branch).
    taken: bool,
    /// The text around the conditional is kept.
    parent_active: bool,
    seen_else: bool,
    /// The opening directive (`#if` and its name), for the "never closed" error.
    open: Range<usize>,
    name: String,
}

/// One directive: its logical line (continuations joined, comments replaced by a space) and
/// where each byte of that came from.
struct DirLine {
    text: String,
    /// `src[i]` is the file offset of `text[i]`.
    src: Vec<usize>,
    /// Offset of the `#`.
    hash: usize,
    /// Where ordinary scanning resumes: the line break ending the directive, the end of a
    /// comment that ran onto later lines, or the end of the file.
    end: usize,
    /// Line breaks inside the directive (continuations, comments), each kept in the output.
    newlines: Vec<usize>,
    /// Scanning resumes mid-line after a comment, still at the start of a line as far as
    /// directives are concerned.
    resume_blank: bool,
}

impl DirLine {
    /// File range of `text[a..b]`.
    fn range(&self, a: usize, b: usize) -> Range<usize> {
        let at = |i: usize| self.src.get(i).copied();
        let start = at(a).or_else(|| at(self.src.len().wrapping_sub(1)).map(|p| p + 1)).unwrap_or(self.hash + 1);
        let end = if b > a { at(b - 1).map_or(start, |p| p + 1) } else { start };
        start..end.max(start)
    }

    /// The whole directive, from `#` to its last non-blank character.
    fn whole(&self) -> Range<usize> {
        let trimmed = self.text.trim_end_matches(|c: char| c.is_ascii_whitespace()).len();
        self.hash..self.range(0, trimmed).end.max(self.hash + 1)
    }
}

fn skip_blanks(t: &[u8], mut p: usize) -> usize {
    while p < t.len() && lex::is_blank(t[p]) {
        p += 1;
    }
    p
}

/// `(start, end)` of the identifier at `p`, if one starts there.
fn ident_at(t: &[u8], p: usize) -> Option<(usize, usize)> {
    t.get(p).filter(|&&b| lex::is_ident_start(b)).map(|_| (p, lex::word_end(t, p)))
}

/// Control characters the parser also rejects (tab, CR, VT, FF are fine).
fn is_control(b: u8) -> bool {
    (b < 0x20 && !matches!(b, b'\t' | b'\n' | b'\r' | 0x0b | 0x0c)) || b == 0x7f
}

/// Offset of the first whole-word occurrence of `word` in `hay`.
fn find_word(hay: &str, word: &str) -> Option<usize> {
    let h = hay.as_bytes();
    let mut from = 0;
    while let Some(p) = hay.get(from..).and_then(|rest| rest.find(word)) {
        let at = from + p;
        let end = at + word.len();
        let before_ok = at == 0 || !lex::is_ident_char(h[at - 1]);
        let after_ok = end >= h.len() || !lex::is_ident_char(h[end]);
        if before_ok && after_ok {
            return Some(at);
        }
        from = at + 1;
    }
    None
}

struct Pp<'a> {
    db: &'a mut SourceDb,
    loader: &'a mut dyn Loader,
    diags: &'a mut Vec<Diagnostic>,
    reported: usize,
    out: String,
    map: SourceMap,
    includes: Vec<PathBuf>,
    /// Every include read so far (Godot includes each file once).
    seen: HashSet<PathBuf>,
    /// The include chain, root first.
    files: Vec<Frame>,
    exp: Expander,
    /// `#pragma disable_preprocessor` was reached: the rest is copied as it is.
    disabled: bool,
    input_len: usize,
    project_root: Option<PathBuf>,
    /// The include limits were reached (reported once; later includes are skipped).
    include_limit_hit: bool,
    /// An include cycle, and includes nested too deep, are reported once each (Godot stops at
    /// the first error; reporting every path of a fan of includes would bury the rest).
    reported_cycle: bool,
    reported_depth: bool,
}

impl Pp<'_> {
    fn report(&mut self, d: Diagnostic) {
        if self.reported < MAX_DIAGNOSTICS {
            self.reported += 1;
            self.diags.push(d);
        }
    }

    fn add_input(&mut self, len: usize) {
        self.input_len = self.input_len.saturating_add(len);
        self.exp.out_limit = OUTPUT_CAP.min(OUTPUT_FLOOR.max(self.input_len.saturating_mul(OUTPUT_FACTOR)));
        let input = self.input_len as u64;
        self.exp.work_limit = WORK_CAP.min(WORK_FLOOR.saturating_add(WORK_FACTOR.saturating_mul(input)));
    }

    /// Copies `text[a..b]` of `file` to the output unchanged.
    fn flush(&mut self, file: FileId, text: &str, a: usize, b: usize) {
        if a < b
            && let Some(piece) = text.get(a..b)
        {
            let start = self.out.len();
            self.out.push_str(piece);
            self.map.push_verbatim(start..self.out.len(), file, a..b);
        }
    }

    /// Writes the line break at `pos` of `file` (of a directive or skipped line).
    fn newline(&mut self, file: FileId, pos: usize) {
        let start = self.out.len();
        self.out.push('\n');
        self.map.push_verbatim(start..start + 1, file, pos..pos + 1);
    }

    fn newlines_in(&mut self, file: FileId, s: &[u8], range: Range<usize>) {
        for p in range {
            if s.get(p) == Some(&b'\n') {
                self.newline(file, p);
            }
        }
    }

    fn unclosed_comment(&mut self, file: FileId, at: usize) {
        self.report(
            Diagnostic::error(codes::UNCLOSED_COMMENT, "this comment is never closed")
                .with_primary(file, at..at + 2, "comment starts here")
                .with_note("expected `*/` before the end of the file (Godot: \"Block comment mismatch\")"),
        );
    }

    fn stray_comment_end(&mut self, file: FileId, at: usize) {
        self.report(
            Diagnostic::error(codes::UNCLOSED_COMMENT, "`*/` without a `/*` before it")
                .with_primary(file, at..at + 2, "no comment is open here")
                .with_note("Godot's preprocessor rejects this (\"Block comment mismatch\")"),
        );
    }

    fn process_file(&mut self, file: FileId) {
        let text: Rc<str> = Rc::from(self.db.text(file));
        let s = text.as_bytes();
        self.exp.unclosed = None;
        let mut conds: Vec<Cond> = Vec::new();
        // A byte-order mark is dropped.
        let mut i = if text.starts_with('\u{FEFF}') { 3 } else { 0 };
        // Start of text not yet copied to the output (only meaningful while active).
        let mut vstart = i;
        // Only blanks and comments since the start of the line; they start at `blank_start`.
        let mut line_blank = true;
        let mut blank_start = i;
        while i < s.len() && !self.disabled {
            let active = conds.last().is_none_or(|c| c.active);
            let c = s[i];
            match c {
                b'\n' => {
                    if !active {
                        self.newline(file, i);
                    }
                    i += 1;
                    line_blank = true;
                    blank_start = i;
                    if !active {
                        vstart = i;
                    }
                }
                _ if lex::is_blank(c) => i += 1,
                b'#' if line_blank => {
                    if active {
                        self.flush(file, &text, vstart, blank_start.max(vstart));
                    }
                    let dl = self.scan_directive(file, &text, i);
                    self.directive(file, &dl, &mut conds, active);
                    for &nl in &dl.newlines {
                        self.newline(file, nl);
                    }
                    i = dl.end;
                    vstart = i;
                    line_blank = dl.resume_blank;
                    blank_start = i;
                }
                b'/' if s.get(i + 1) == Some(&b'/') => i = lex::line_end(s, i),
                b'/' if s.get(i + 1) == Some(&b'*') => {
                    let (end, closed) = lex::block_comment_end(s, i + 2);
                    if !closed {
                        self.unclosed_comment(file, i);
                    }
                    let spans_lines = s[i..end].contains(&b'\n');
                    if !active {
                        self.newlines_in(file, s, i..end);
                        vstart = end;
                    }
                    i = end;
                    // Godot removes comments before looking for directives.
                    if spans_lines {
                        line_blank = true;
                    }
                    blank_start = i;
                }
                b'"' => {
                    i = lex::string_end(s, i);
                    line_blank = false;
                }
                _ if lex::is_ident_start(c) => {
                    let start = i;
                    i = lex::word_end(s, i);
                    line_blank = false;
                    if active
                        && self.exp.limit.is_none()
                        && let Some(id) = self.exp.lookup(&text[start..i])
                    {
                        (i, vstart) = self.expand_here(file, &text, vstart, start, i, id);
                    }
                }
                _ if c.is_ascii_digit() => {
                    i = lex::word_end(s, i);
                    line_blank = false;
                }
                b'#' if active => {
                    // Godot: "Invalid symbols placed before directive." The would-be directive
                    // is dropped.
                    self.flush(file, &text, vstart, i);
                    self.report(
                        Diagnostic::error(codes::PP_BAD_DIRECTIVE, "a directive must be the first thing on its line")
                            .with_primary(file, i..i + 1, "code comes before this `#`")
                            .with_note("move the directive to a line of its own"),
                    );
                    let dl = self.scan_directive(file, &text, i);
                    for &nl in &dl.newlines {
                        self.newline(file, nl);
                    }
                    i = dl.end;
                    vstart = i;
                    line_blank = dl.resume_blank;
                    blank_start = i;
                }
                b'*' if s.get(i + 1) == Some(&b'/') => {
                    self.stray_comment_end(file, i);
                    i += 2;
                    line_blank = false;
                }
                _ => {
                    i += 1;
                    line_blank = false;
                }
            }
        }
        if self.disabled || conds.last().is_none_or(|c| c.active) {
            self.flush(file, &text, vstart, s.len());
        }
        if !self.disabled {
            for cond in conds {
                self.report(
                    Diagnostic::error(
                        codes::PP_UNBALANCED_CONDITIONAL,
                        format!("this `#{}` is never closed", cond.name),
                    )
                    .with_primary(file, cond.open, "opened here")
                    .with_note("expected `#endif` before the end of the file"),
                );
            }
        }
    }

    /// Expands the macro `id` named at `start..name_end` of ordinary text. Returns where scanning
    /// resumes and where uncopied text starts.
    fn expand_here(
        &mut self,
        file: FileId,
        text: &str,
        vstart: usize,
        start: usize,
        name_end: usize,
        id: u32,
    ) -> (usize, usize) {
        let mut cur = SrcCursor { text, pos: name_end };
        if self.exp.is_function_like(id) && !cur.peek_lparen() {
            // A function-like macro's name without arguments is left alone.
            return (name_end, vstart);
        }
        self.flush(file, text, vstart, start);
        let mut buf = String::new();
        let result = self.exp.expand_from_source(id, &mut cur, &mut Sink::Text { buf: &mut buf, base: self.out.len() });
        let site = start..cur.pos.max(name_end);
        if let Some(err) = self.exp.take_errors().into_iter().next() {
            let at = if matches!(result, Ok(false)) { start..name_end } else { site.clone() };
            self.report(
                Diagnostic::error(codes::PP_MACRO_ARGUMENTS, err.message)
                    .with_primary(file, at, "in this macro invocation")
                    .with_notes(err.note),
            );
        }
        match result {
            Ok(true) => {
                let out_start = self.out.len();
                self.out.push_str(&buf);
                self.map.push_expansion(out_start..self.out.len(), file, site.clone());
                self.newlines_in(file, text.as_bytes(), site.clone());
                (site.end, site.end)
            }
            // Never closed: left as text (the error is reported above).
            Ok(false) => (name_end, start),
            Err(Stop) => {
                self.report_limit(file, start..name_end);
                (name_end, start)
            }
        }
    }

    fn report_limit(&mut self, file: FileId, at: Range<usize>) {
        let message = match self.exp.limit {
            Some(Limit::Depth) => format!("macro expansion nests more than {} levels deep", expand::MAX_DEPTH),
            Some(Limit::Output) => {
                format!("macro expansion makes the preprocessed text longer than {} bytes", self.exp.out_limit)
            }
            Some(Limit::Held) => format!("one macro expansion builds up more than {} tokens", expand::MAX_HELD),
            Some(Limit::Work) | None => format!("macro expansion reads more than {} tokens", self.exp.work_limit),
        };
        self.report(
            Diagnostic::error(codes::PP_EXPANSION_LIMIT, message)
                .with_primary(file, at, "while expanding this")
                .with_note("macros that expand to several copies of each other grow exponentially")
                .with_note("no further macros are expanded"),
        );
    }

    /// Reads the directive starting at `hash` (its `#`).
    fn scan_directive(&mut self, file: FileId, text: &str, hash: usize) -> DirLine {
        let s = text.as_bytes();
        let mut bytes = Vec::new();
        let mut src = Vec::new();
        let mut newlines = Vec::new();
        let mut resume_blank = false;
        let mut bad = None;
        let mut j = hash + 1;
        let end = loop {
            let Some(&c) = s.get(j) else { break s.len() };
            let next = s.get(j + 1).copied();
            match c {
                b'\n' => break j,
                b'\\' if next == Some(b'\n') => {
                    newlines.push(j + 1);
                    j += 2;
                }
                b'\\' if next == Some(b'\r') && s.get(j + 2) == Some(&b'\n') => {
                    newlines.push(j + 2);
                    j += 3;
                }
                b'/' if next == Some(b'/') => j = lex::line_end(s, j),
                b'/' if next == Some(b'*') => {
                    let (e, closed) = lex::block_comment_end(s, j + 2);
                    if !closed {
                        self.unclosed_comment(file, j);
                    }
                    bytes.push(b' ');
                    src.push(j);
                    let before = newlines.len();
                    newlines.extend((j..e).filter(|&p| s[p] == b'\n'));
                    if newlines.len() > before {
                        // Godot ends the directive at the comment's first line break; the text
                        // after the comment is ordinary text.
                        resume_blank = true;
                        break e;
                    }
                    j = e;
                }
                b'"' => {
                    let e = lex::string_end(s, j);
                    for (k, &b) in s.iter().enumerate().take(e).skip(j) {
                        bytes.push(b);
                        src.push(k);
                    }
                    j = e;
                }
                b'\r' => {
                    bytes.push(b' ');
                    src.push(j);
                    j += 1;
                }
                b'*' if next == Some(b'/') => {
                    self.stray_comment_end(file, j);
                    j += 2;
                }
                _ => {
                    if bad.is_none() && is_control(c) {
                        bad = Some(j);
                    }
                    bytes.push(c);
                    src.push(j);
                    j += 1;
                }
            }
        };
        if let Some(at) = bad {
            let what = if s[at] == 0 { "a NUL byte".to_string() } else { format!("control character U+{:04X}", s[at]) };
            self.report(
                Diagnostic::error(codes::INVALID_CHARACTER, format!("the source contains {what}")).with_primary(
                    file,
                    at..at + 1,
                    "not allowed in shader source",
                ),
            );
        }
        let text = String::from_utf8(bytes).unwrap_or_else(|e| String::from_utf8_lossy(e.as_bytes()).into_owned());
        DirLine { text, src, hash, end, newlines, resume_blank }
    }

    fn directive(&mut self, file: FileId, dl: &DirLine, conds: &mut Vec<Cond>, active: bool) {
        let t = dl.text.as_bytes();
        let name_start = skip_blanks(t, 0);
        let name_end = lex::word_end(t, name_start);
        let name = dl.text.get(name_start..name_end).unwrap_or("");
        let head = dl.hash..dl.range(name_start, name_end).end.max(dl.hash + 1);
        let closes_open = matches!(name, "elif" | "else" | "endif") && conds.last().is_some_and(|c| c.parent_active);
        if name_start > 0 && !name.is_empty() && (active || closes_open) {
            // Godot reads the directive name right after `#`, so it rejects `# define`.
            self.report(
                Diagnostic::error(
                    codes::PP_BAD_DIRECTIVE,
                    format!("`# {name}` has a blank between `#` and the directive name"),
                )
                .with_primary(file, head.clone(), "blank after `#`")
                .with_note(format!("Godot rejects this; write `#{name}`")),
            );
        }
        match name {
            "if" | "ifdef" | "ifndef" if !active => {
                conds.push(Cond {
                    active: false,
                    taken: true,
                    parent_active: false,
                    seen_else: false,
                    open: head,
                    name: name.to_string(),
                });
                return;
            }
            "elif" => return self.do_elif(file, dl, name_end, head, conds),
            "else" | "endif" => return self.do_else_endif(file, dl, name, name_end, head, conds),
            _ if !active => return,
            _ => {}
        }
        match name {
            "define" => self.do_define(file, dl, name_end),
            "undef" => self.do_undef(file, dl, name_end, head),
            "if" => {
                let v = self.condition(file, dl, name_end, &head);
                conds.push(Cond {
                    active: v,
                    taken: v,
                    parent_active: true,
                    seen_else: false,
                    open: head,
                    name: "if".into(),
                });
            }
            "ifdef" | "ifndef" => {
                let v = match self.sole_name(file, dl, name_end, &head, name) {
                    Some(macro_name) => self.exp.lookup(&macro_name).is_some() == (name == "ifdef"),
                    None => false,
                };
                conds.push(Cond {
                    active: v,
                    taken: v,
                    parent_active: true,
                    seen_else: false,
                    open: head,
                    name: name.into(),
                });
            }
            "include" => self.do_include(file, dl, name_end, head),
            "error" => {
                let message = dl.text[name_end..].trim();
                let message = if message.is_empty() { "`#error` directive reached" } else { message };
                self.report(Diagnostic::error(codes::PP_ERROR_DIRECTIVE, message).with_primary(
                    file,
                    dl.whole(),
                    "`#error` reached here",
                ));
            }
            "pragma" => self.do_pragma(file, dl, name_end, head),
            "" => {
                let at = dl.hash..dl.range(name_start, name_start + 1).end.max(dl.hash + 1);
                self.report(
                    Diagnostic::error(codes::PP_BAD_DIRECTIVE, "expected a directive name after `#`")
                        .with_primary(file, at, "not a directive")
                        .with_note(DIRECTIVES_NOTE),
                );
            }
            _ => {
                let mut d = Diagnostic::error(codes::PP_BAD_DIRECTIVE, format!("unknown directive `#{name}`"))
                    .with_primary(file, head, "not a directive Godot knows");
                d = match name {
                    "elifdef" | "elifndef" => d.with_note(format!(
                        "Godot has no `#{name}`; write `#elif {}defined(NAME)`",
                        if name == "elifndef" { "!" } else { "" }
                    )),
                    _ => d.with_note(DIRECTIVES_NOTE),
                };
                self.report(d);
            }
        }
    }

    /// The single macro name after `#ifdef` / `#ifndef`.
    fn sole_name(
        &mut self,
        file: FileId,
        dl: &DirLine,
        from: usize,
        head: &Range<usize>,
        directive: &str,
    ) -> Option<String> {
        let t = dl.text.as_bytes();
        let p = skip_blanks(t, from);
        let Some((a, b)) = ident_at(t, p) else {
            self.report(
                Diagnostic::error(codes::PP_BAD_DIRECTIVE, format!("expected a macro name after `#{directive}`"))
                    .with_primary(file, head.clone(), "needs a macro name"),
            );
            return None;
        };
        let rest = skip_blanks(t, b);
        if rest < t.len() {
            self.report(
                Diagnostic::error(
                    codes::PP_BAD_DIRECTIVE,
                    format!("unexpected text after the macro name in `#{directive}`"),
                )
                .with_primary(file, dl.range(rest, t.len()), "unexpected")
                .with_note(format!("`#{directive}` takes exactly one macro name")),
            );
            return None;
        }
        Some(dl.text[a..b].to_string())
    }

    /// Checks that nothing but blanks follows `from` (for `#else`, `#endif`, ...).
    fn expect_end(&mut self, file: FileId, dl: &DirLine, from: usize, what: &str) {
        let t = dl.text.as_bytes();
        let rest = skip_blanks(t, from);
        if rest < t.len() {
            self.report(
                Diagnostic::error(codes::PP_BAD_DIRECTIVE, format!("unexpected text after {what}"))
                    .with_primary(file, dl.range(rest, t.len()), "unexpected")
                    .with_note(format!("expected the end of the line after {what}")),
            );
        }
    }

    fn do_elif(&mut self, file: FileId, dl: &DirLine, from: usize, head: Range<usize>, conds: &mut [Cond]) {
        let Some(top) = conds.last_mut() else {
            self.report(
                Diagnostic::error(codes::PP_UNBALANCED_CONDITIONAL, "`#elif` without a matching `#if`")
                    .with_primary(file, head, "no `#if` is open here")
                    .with_note("`#elif` continues an `#if`, `#ifdef` or `#ifndef` earlier in the same file"),
            );
            return;
        };
        if top.seen_else {
            top.active = false;
            if top.parent_active {
                self.report(
                    Diagnostic::error(codes::PP_UNBALANCED_CONDITIONAL, "`#elif` after `#else`")
                        .with_primary(file, head, "comes after the `#else`")
                        .with_note("expected `#endif` to close the conditional after its `#else` branch"),
                );
            }
            return;
        }
        if !top.parent_active || top.taken {
            top.active = false;
            return;
        }
        let v = self.condition(file, dl, from, &head);
        if let Some(top) = conds.last_mut() {
            top.active = v;
            top.taken = v;
        }
    }

    fn do_else_endif(
        &mut self,
        file: FileId,
        dl: &DirLine,
        name: &str,
        from: usize,
        head: Range<usize>,
        conds: &mut Vec<Cond>,
    ) {
        let Some(top) = conds.last_mut() else {
            self.report(
                Diagnostic::error(codes::PP_UNBALANCED_CONDITIONAL, format!("`#{name}` without a matching `#if`"))
                    .with_primary(file, head, "no `#if` is open here")
                    .with_note(format!("`#{name}` closes an `#if`, `#ifdef` or `#ifndef` earlier in the same file")),
            );
            return;
        };
        let checked = top.parent_active;
        if name == "endif" {
            conds.pop();
        } else if top.seen_else {
            top.active = false;
            if checked {
                self.report(
                    Diagnostic::error(codes::PP_UNBALANCED_CONDITIONAL, "a second `#else` in the same conditional")
                        .with_primary(file, head, "second `#else`")
                        .with_note("expected `#endif`"),
                );
            }
        } else {
            top.active = top.parent_active && !top.taken;
            top.taken = true;
            top.seen_else = true;
        }
        if checked {
            self.expect_end(file, dl, from, &format!("`#{name}`"));
        }
    }

    /// Evaluates the condition of `#if` / `#elif` (text from `from`); errors count as false.
    fn condition(&mut self, file: FileId, dl: &DirLine, from: usize, head: &Range<usize>) -> bool {
        let t = dl.text.as_bytes();
        let a = skip_blanks(t, from);
        let b = dl.text.trim_end_matches(|c: char| c.is_ascii_whitespace()).len().max(a);
        let directive = &dl.text[skip_blanks(t, 0)..from];
        if a >= b {
            self.report(
                Diagnostic::error(codes::PP_BAD_EXPRESSION, format!("`#{directive}` needs a condition"))
                    .with_primary(file, head.clone(), "no condition")
                    .with_note("expected an expression such as `defined(NAME)` or `NAME > 1`"),
            );
            return false;
        }
        let at = dl.range(a, b);
        if self.exp.limit.is_some() {
            return false;
        }
        let toks = lex::lex_all(&dl.text[a..b]);
        let mut resolved = Vec::with_capacity(toks.len());
        let mut k = 0;
        while k < toks.len() {
            let tok = &toks[k];
            if tok.kind != Kind::Ident || &*tok.text != "defined" {
                resolved.push(tok.clone());
                k += 1;
                continue;
            }
            let skip_ws = |mut m: usize| {
                while toks.get(m).is_some_and(Tok::is_ws) {
                    m += 1;
                }
                m
            };
            let mut m = skip_ws(k + 1);
            let paren = toks.get(m).is_some_and(|t| t.kind == Kind::LParen);
            if paren {
                m = skip_ws(m + 1);
            }
            let Some(name) = toks.get(m).filter(|t| t.kind == Kind::Ident) else {
                self.report(
                    Diagnostic::error(codes::PP_BAD_EXPRESSION, "`defined` must be followed by a macro name")
                        .with_primary(file, at, "in this condition")
                        .with_note("expected `defined(NAME)` or `defined NAME`"),
                );
                return false;
            };
            let is_defined = self.exp.lookup(&name.text).is_some();
            m += 1;
            if paren {
                m = skip_ws(m);
                if !toks.get(m).is_some_and(|t| t.kind == Kind::RParen) {
                    self.report(
                        Diagnostic::error(codes::PP_BAD_EXPRESSION, "expected `)` after the macro name in `defined(`")
                            .with_primary(file, at, "in this condition")
                            .with_note("`defined(…)` takes exactly one macro name"),
                    );
                    return false;
                }
                m += 1;
            }
            resolved.push(Tok::new(Kind::Number, if is_defined { "1" } else { "0" }));
            k = m;
        }
        self.exp.begin();
        let expanded = match self.exp.expand_list(resolved) {
            Ok(toks) => toks,
            Err(Stop) => {
                self.report_limit(file, at);
                return false;
            }
        };
        if let Some(err) = self.exp.take_errors().into_iter().next() {
            self.report(
                Diagnostic::error(codes::PP_MACRO_ARGUMENTS, err.message)
                    .with_primary(file, at.clone(), "in this condition")
                    .with_notes(err.note),
            );
        }
        let joined: String = expanded.iter().map(|t| &*t.text).collect();
        match expr::eval(&joined) {
            Ok(v) => v != 0,
            Err(e) => {
                let place = e
                    .ident
                    .as_deref()
                    .and_then(|id| find_word(&dl.text[a..b], id).map(|p| dl.range(a + p, a + p + id.len())))
                    .unwrap_or(at);
                self.report(
                    Diagnostic::error(codes::PP_BAD_EXPRESSION, e.message)
                        .with_primary(file, place, "in this condition")
                        .with_notes(e.note),
                );
                false
            }
        }
    }

    fn do_define(&mut self, file: FileId, dl: &DirLine, from: usize) {
        let t = dl.text.as_bytes();
        let ns = skip_blanks(t, from);
        // Godot reads the name up to a blank or one of `( ) , ;`, then checks it.
        let mut stop = ns;
        while stop < t.len() && !lex::is_blank(t[stop]) && !matches!(t[stop], b'(' | b')' | b',' | b';') {
            stop += 1;
        }
        let ne = lex::word_end(t, ns);
        if ns == stop || !lex::is_ident_start(t[ns]) || ne != stop {
            let message = if ns == stop {
                "expected a macro name after `#define`".to_string()
            } else {
                format!("`{}` is not a valid macro name", &dl.text[ns..stop])
            };
            let at = if ns == stop { dl.whole() } else { dl.range(ns, stop) };
            self.report(
                Diagnostic::error(codes::PP_BAD_DIRECTIVE, message)
                    .with_primary(file, at, "invalid macro name")
                    .with_note("a macro name is a letter or `_` followed by letters, digits and `_`"),
            );
            return;
        }
        let name = &dl.text[ns..ne];
        let name_at = dl.range(ns, ne);
        if let Some(id) = self.exp.lookup(name) {
            let prev = &self.exp.macros[id as usize];
            let mut d = Diagnostic::error(codes::PP_MACRO_REDEFINED, format!("macro `{name}` is already defined"))
                .with_primary(file, name_at, "defined again here");
            if let Some((pfile, prange)) = prev.def.clone() {
                d = d.with_secondary(pfile, prange, "first defined here");
            }
            d = if prev.builtin {
                d.with_note(format!("`{name}` is one of Godot's built-in defines"))
            } else {
                d.with_note(format!("Godot does not allow redefining a macro; use `#undef {name}` first"))
            };
            self.report(d);
            return;
        }
        let mut p = ne;
        let mut params = None;
        if t.get(p) == Some(&b'(') {
            p += 1;
            let mut list: Vec<Rc<str>> = Vec::new();
            loop {
                let a = skip_blanks(t, p);
                let Some((a, b)) = ident_at(t, a)
                    .filter(|&(_, b)| t.get(b).is_none_or(|&c| lex::is_blank(c) || c == b',' || c == b')'))
                else {
                    let at = dl.range(a, (a + 1).min(t.len()).max(a));
                    self.report(
                        Diagnostic::error(
                            codes::PP_BAD_DIRECTIVE,
                            format!("invalid parameter list in the definition of `{name}`"),
                        )
                        .with_primary(file, at, "expected a parameter name")
                        .with_note(
                            "parameters are identifiers separated by `,`; Godot does not accept an empty list `()`",
                        ),
                    );
                    return;
                };
                list.push(Rc::from(&dl.text[a..b]));
                p = skip_blanks(t, b);
                match t.get(p) {
                    Some(b')') => {
                        p += 1;
                        break;
                    }
                    Some(b',') => p += 1,
                    _ => {
                        self.report(
                            Diagnostic::error(
                                codes::PP_BAD_DIRECTIVE,
                                format!("expected `,` or `)` in the parameter list of `{name}`"),
                            )
                            .with_primary(
                                file,
                                dl.range(p, (p + 1).min(t.len())),
                                "expected `,` or `)`",
                            ),
                        );
                        return;
                    }
                }
            }
            params = Some(list);
        }
        let body_text = dl.text[p..].trim_matches(|c: char| c.is_ascii_whitespace());
        for (bad, place) in [(body_text.starts_with("##"), "start"), (body_text.ends_with("##"), "end")] {
            if bad {
                self.report(
                    Diagnostic::error(
                        codes::PP_BAD_DIRECTIVE,
                        format!("`##` cannot be at the {place} of a macro body"),
                    )
                    .with_primary(file, dl.whole(), "in this definition")
                    .with_note("`##` joins the tokens on either side of it"),
                );
                return;
            }
        }
        let mut body = lex::lex_all(body_text);
        while body.last().is_some_and(Tok::is_ws) {
            body.pop();
        }
        let lead = body.iter().take_while(|t| t.is_ws()).count();
        body.drain(..lead);
        if let Some(list) = &params {
            for tok in &mut body {
                if tok.kind == Kind::Ident
                    && let Some(i) = list.iter().position(|p| **p == *tok.text)
                {
                    tok.kind = Kind::Param;
                    tok.param = i as u32;
                }
            }
        }
        self.exp.define(Macro {
            name: Rc::from(name),
            params,
            body: body.into(),
            builtin: false,
            def: Some((file, dl.whole())),
        });
    }

    fn do_undef(&mut self, file: FileId, dl: &DirLine, from: usize, head: Range<usize>) {
        let Some(name) = self.sole_name(file, dl, from, &head, "undef") else {
            return;
        };
        if let Some(id) = self.exp.lookup(&name) {
            if self.exp.macros[id as usize].builtin {
                self.report(
                    Diagnostic::error(codes::PP_BAD_DIRECTIVE, format!("`{name}` is built in and cannot be undefined"))
                        .with_primary(file, dl.whole(), "cannot `#undef` a built-in define"),
                );
                return;
            }
            self.exp.undefine(&name);
        }
    }

    fn do_pragma(&mut self, file: FileId, dl: &DirLine, from: usize, head: Range<usize>) {
        let t = dl.text.as_bytes();
        let p = skip_blanks(t, from);
        let Some((a, b)) = ident_at(t, p) else {
            self.report(
                Diagnostic::error(codes::PP_BAD_DIRECTIVE, "expected a pragma name after `#pragma`")
                    .with_primary(file, head, "needs a name")
                    .with_note("the only pragma is `disable_preprocessor`"),
            );
            return;
        };
        let name = &dl.text[a..b];
        if name == "disable_preprocessor" {
            self.expect_end(file, dl, b, "`#pragma disable_preprocessor`");
            self.disabled = true;
        } else {
            self.report(
                Diagnostic::error(codes::PP_BAD_DIRECTIVE, format!("unknown pragma `{name}`"))
                    .with_primary(file, dl.range(a, b), "unknown pragma")
                    .with_note("the only pragma Godot knows is `disable_preprocessor`"),
            );
        }
    }

    fn do_include(&mut self, file: FileId, dl: &DirLine, from: usize, head: Range<usize>) {
        let t = dl.text.as_bytes();
        let p = skip_blanks(t, from);
        let close =
            if t.get(p) == Some(&b'"') { t[p + 1..].iter().position(|&b| b == b'"').map(|q| p + 1 + q) } else { None };
        let Some(q) = close else {
            self.report(
                Diagnostic::error(codes::PP_BAD_DIRECTIVE, "expected a path in double quotes after `#include`")
                    .with_primary(file, head, "needs a path")
                    .with_note("for example `#include \"res://shaders/common.gdshaderinc\"`"),
            );
            return;
        };
        let path_at = dl.range(p, q + 1);
        let path = &dl.text[p + 1..q];
        if path.trim().is_empty() {
            self.report(Diagnostic::error(codes::PP_BAD_DIRECTIVE, "the `#include` path is empty").with_primary(
                file,
                path_at,
                "empty path",
            ));
            return;
        }
        self.expect_end(file, dl, q + 1, "the `#include` path");
        self.include(file, path, path_at);
    }

    fn project_root(&mut self) -> PathBuf {
        if let Some(root) = &self.project_root {
            return root.clone();
        }
        let root_dir = self
            .files
            .first()
            .and_then(|f| f.path.as_deref())
            .and_then(Path::parent)
            .map(Path::to_path_buf)
            .unwrap_or_default();
        let mut found = None;
        for dir in root_dir.ancestors() {
            if self.loader.load(&dir.join("project.godot")).is_ok() {
                found = Some(dir.to_path_buf());
                break;
            }
        }
        // However the input's path is spelled (`x.gdshader` from inside the project has no
        // parent to walk up from): the folders above it on disk too.
        if found.is_none() && root_dir.is_relative() {
            let absolute =
                std::path::absolute(if root_dir.as_os_str().is_empty() { Path::new(".") } else { &root_dir });
            for dir in absolute.iter().flat_map(|a| a.ancestors()) {
                if self.loader.load(&dir.join("project.godot")).is_ok() {
                    found = Some(normalize(dir));
                    break;
                }
            }
        }
        let root = found.unwrap_or(root_dir);
        self.project_root = Some(root.clone());
        root
    }

    /// The folder an include must lie in: the project's (the folder of `project.godot`, as
    /// Godot reads includes as `res://` resources), else the input's own folder. `None` when
    /// `resolved` is inside it; the folder otherwise. Lexical, after `..` is resolved: the file
    /// is not opened, so nothing of a file outside is read or shown.
    fn outside_of(&mut self, resolved: &Path) -> Option<PathBuf> {
        let root = self.project_root();
        let absolute = |p: &Path| std::path::absolute(p).map(|a| normalize(&a)).unwrap_or_else(|_| normalize(p));
        let (root_abs, path_abs) =
            (absolute(if root.as_os_str().is_empty() { Path::new(".") } else { &root }), absolute(resolved));
        (!path_abs.starts_with(&root_abs)).then_some(root_abs)
    }

    fn resolve(&mut self, path: &str) -> PathBuf {
        let joined = if let Some(rest) = path.strip_prefix("res://") {
            self.project_root().join(rest)
        } else {
            let base = self
                .files
                .last()
                .and_then(|f| f.path.as_deref())
                .and_then(Path::parent)
                .map(Path::to_path_buf)
                .unwrap_or_default();
            base.join(path)
        };
        normalize(&joined)
    }

    fn include(&mut self, file: FileId, written: &str, at: Range<usize>) {
        let resolved = self.resolve(written);
        let display = resolved.display().to_string();
        if let Some(pos) = self.files.iter().position(|f| f.path.as_ref() == Some(&resolved)) {
            let chain: Vec<&str> =
                self.files[pos..].iter().map(|f| f.name.as_str()).chain([display.as_str()]).collect();
            let message = format!("cyclic include: {}", chain.join(" → "));
            // Reported at the `#include` that enters the cycle, with the one that closes it.
            let d = match self.files[pos].site.clone() {
                Some((entry_file, entry_at)) => Diagnostic::error(codes::PP_INCLUDE, message)
                    .with_primary(entry_file, entry_at, "this include leads back to itself")
                    .with_secondary(file, at, format!("`{display}` is included again here")),
                None => {
                    Diagnostic::error(codes::PP_INCLUDE, message).with_primary(file, at, "includes the shader itself")
                }
            };
            if !self.reported_cycle {
                self.reported_cycle = true;
                self.report(d.with_note("Godot does not allow a file to include itself, directly or through others"));
            }
            return;
        }
        if self.seen.contains(&resolved) {
            // Godot includes each file once per shader and skips later `#include`s of it.
            return;
        }
        if self.files.len() > MAX_INCLUDE_DEPTH {
            if std::mem::replace(&mut self.reported_depth, true) {
                return;
            }
            self.report(
                Diagnostic::error(
                    codes::PP_INCLUDE,
                    format!("includes are nested more than {MAX_INCLUDE_DEPTH} levels deep"),
                )
                .with_primary(file, at, "one include too many")
                .with_note(format!("Godot allows at most {MAX_INCLUDE_DEPTH} nested `#include`s")),
            );
            return;
        }
        if self.include_limit_hit {
            return;
        }
        if let Some(root) = self.outside_of(&resolved) {
            self.report(
                Diagnostic::error(
                    codes::PP_INCLUDE,
                    format!("shader include `{written}` is outside the project ({})", root.display()),
                )
                .with_primary(file, at, "outside the project")
                .with_note(
                    "Godot reads includes from inside its project only (the folder of project.godot, or without one \
                     the shader's own folder); the file was not read",
                ),
            );
            return;
        }
        if self.includes.len() >= MAX_INCLUDED_FILES {
            self.include_limit_hit = true;
            self.report(
                Diagnostic::error(
                    codes::PP_INCLUDE,
                    format!("the shader includes more than {MAX_INCLUDED_FILES} files"),
                )
                .with_primary(file, at, "one include too many")
                .with_note("no further files are included"),
            );
            return;
        }
        let bytes = match self.loader.load(&resolved) {
            Ok(bytes) => bytes,
            Err(e) => {
                let message = if e.kind() == std::io::ErrorKind::NotFound {
                    format!("shader include `{display}` does not exist")
                } else {
                    format!("cannot read shader include `{display}`: {e}")
                };
                let mut d = Diagnostic::error(codes::PP_INCLUDE, message).with_primary(file, at, "included here");
                if !written.starts_with("res://") {
                    d = d.with_note("a relative path is resolved from the directory of the file that includes it");
                }
                self.report(d);
                return;
            }
        };
        if self.input_len.saturating_add(bytes.len()) > MAX_TOTAL_INPUT {
            self.include_limit_hit = true;
            self.report(
                Diagnostic::error(
                    codes::PP_INCLUDE,
                    format!("the shader and its includes come to more than {} MiB", MAX_TOTAL_INPUT >> 20),
                )
                .with_primary(file, at, "one include too many")
                .with_note("no further files are included"),
            );
            return;
        }
        self.seen.insert(resolved.clone());
        self.includes.push(resolved.clone());
        match String::from_utf8(bytes) {
            Ok(text) => {
                self.add_input(text.len());
                let id = self.db.add(display.clone(), text, Some(resolved.clone()));
                self.files.push(Frame { path: Some(resolved), name: display, site: Some((file, at)) });
                self.process_file(id);
                self.files.pop();
                // What is known of unclosed argument lists was about the included text.
                self.exp.unclosed = None;
            }
            Err(e) => {
                let valid = e.utf8_error().valid_up_to();
                let lossy = String::from_utf8_lossy(e.as_bytes()).into_owned();
                let id = self.db.add(display.clone(), lossy, Some(resolved));
                self.report(
                    Diagnostic::error(codes::INVALID_UTF8, format!("`{display}` is not valid UTF-8"))
                        .with_primary(id, valid..valid + '\u{FFFD}'.len_utf8(), "first invalid byte")
                        .with_secondary(file, at, "included here")
                        .with_note("shader files must be UTF-8 text"),
                );
            }
        }
    }
}

//! Macro expansion, with C's rules: arguments are fully expanded before they are substituted
//! (except next to `##`), the result is rescanned, and a macro is never expanded inside its own
//! expansion.
//!
//! Expansion runs on a stack of *contexts*, one per macro being rescanned. While a macro's
//! context is on the stack the macro is *active*; a token naming an active macro is marked
//! `noexpand` when it is read, and stays unexpandable wherever it goes afterwards (the scheme
//! clang uses in place of hide sets). So `#define A A` stops after one step, and every expansion
//! ends.
//!
//! Nothing here recurses without a bound: argument pre-expansion recurses once per level of
//! nested invocation, and contexts plus those levels are capped together at [`MAX_DEPTH`]. The
//! total work (tokens read) and the output length are capped too, so a macro that doubles at
//! each of 40 levels stops with an error instead of running for hours.

use super::lex::{self, Kind, Tok};
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::rc::Rc;

/// Deepest nesting of macro expansions (contexts being rescanned plus levels of argument
/// pre-expansion).
pub(crate) const MAX_DEPTH: usize = 256;

/// Most tokens one expansion (one invocation in the text, or one `#if` condition) may build up in
/// memory: argument pre-expansions plus substituted bodies.
pub(crate) const MAX_HELD: u64 = 1 << 20;

/// FNV-1a: identifiers are short, and this is hashed once per identifier of the shader.
#[derive(Default)]
pub(crate) struct Fnv(u64);

impl Hasher for Fnv {
    fn write(&mut self, bytes: &[u8]) {
        let mut h = if self.0 == 0 { 0xcbf2_9ce4_8422_2325 } else { self.0 };
        for &b in bytes {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
        self.0 = h;
    }

    fn finish(&self) -> u64 {
        self.0
    }
}

pub(crate) type FnvMap<K, V> = HashMap<K, V, BuildHasherDefault<Fnv>>;

/// One `#define`.
pub(crate) struct Macro {
    pub name: Rc<str>,
    /// `None` for an object-like macro; parameter names for a function-like one.
    pub params: Option<Vec<Rc<str>>>,
    /// The replacement, lexed, parameters resolved to [`Kind::Param`] tokens.
    pub body: Rc<[Tok]>,
    /// One of Godot's built-in defines (cannot be undefined).
    pub builtin: bool,
    /// Where it was defined: file and byte range of the directive.
    pub def: Option<(crate::diag::FileId, std::ops::Range<usize>)>,
}

/// Why expansion stopped early.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Limit {
    /// Expansions nested more than [`MAX_DEPTH`] deep.
    Depth,
    /// More than `work_limit` tokens read.
    Work,
    /// Preprocessed text longer than `out_limit` bytes.
    Output,
    /// One expansion holding more than [`MAX_HELD`] tokens in memory.
    Held,
}

/// Expansion was abandoned because a limit was reached (recorded in [`Expander::limit`]).
#[derive(Debug)]
pub(crate) struct Stop;

/// A problem with one macro invocation (reported as E014 at the outermost invocation).
pub(crate) struct ArgError {
    pub message: String,
    pub note: Option<String>,
}

struct Ctx {
    toks: Vec<Tok>,
    pos: usize,
    mac: Option<u32>,
}

/// Where expanded tokens go.
pub(crate) enum Sink<'a> {
    /// Text for the parser; `base` bytes of output already exist, for the output cap.
    Text { buf: &'a mut String, base: usize },
    /// Tokens (argument pre-expansion, `#if` conditions).
    Toks(&'a mut Vec<Tok>),
}

/// The source text after a macro name in ordinary code: the argument list of a function-like
/// macro, and of one named last in an expansion, is read from here.
pub(crate) struct SrcCursor<'t> {
    pub text: &'t str,
    pub pos: usize,
}

impl SrcCursor<'_> {
    /// Skips blanks, line breaks and comments from `i`. Returns the next significant position, or
    /// `None` at the end of the text or at a directive line (which argument lists do not cross).
    fn skip_space(&self, mut i: usize) -> Option<usize> {
        let s = self.text.as_bytes();
        loop {
            let c = *s.get(i)?;
            match c {
                b'\n' => {
                    i += 1;
                    let mut k = i;
                    while k < s.len() && lex::is_blank(s[k]) {
                        k += 1;
                    }
                    if s.get(k) == Some(&b'#') {
                        return None;
                    }
                }
                _ if lex::is_blank(c) => i += 1,
                b'/' if s.get(i + 1) == Some(&b'/') => i = lex::line_end(s, i),
                b'/' if s.get(i + 1) == Some(&b'*') => i = lex::block_comment_end(s, i + 2).0,
                _ => return Some(i),
            }
        }
    }

    pub(crate) fn peek_lparen(&self) -> bool {
        self.lparen().is_some()
    }

    /// Position of the `(` that follows (after blanks, line breaks and comments), if one does.
    pub(crate) fn lparen(&self) -> Option<usize> {
        self.skip_space(self.pos).filter(|&i| self.text.as_bytes()[i] == b'(')
    }

    /// The next token, or `None` at the end of the text or a directive line.
    fn next_tok(&mut self) -> Option<Tok> {
        let j = self.skip_space(self.pos)?;
        if j > self.pos {
            self.pos = j;
            return Some(Tok::space());
        }
        let s = self.text.as_bytes();
        let (kind, end) = lex::lex_one(s, j);
        let end = end.max(j + 1).min(s.len());
        self.pos = end;
        Some(Tok::new(kind, self.text.get(j..end).unwrap_or("")))
    }
}

/// The macro table and the machinery that expands it.
pub(crate) struct Expander {
    pub macros: Vec<Macro>,
    pub by_name: FnvMap<Rc<str>, u32>,
    active: Vec<bool>,
    depth: usize,
    work: u64,
    pub work_limit: u64,
    pub out_limit: usize,
    /// Tokens built up by the current expansion (see [`MAX_HELD`]).
    held: u64,
    /// Set once a limit is hit; after that nothing more is expanded.
    pub limit: Option<Limit>,
    /// Problems with invocations since the last [`Expander::take_errors`].
    errors: Vec<ArgError>,
    /// Argument lists known never to close in the text being read (cleared by the caller when
    /// that text changes).
    pub unclosed: Option<Unclosed>,
}

/// Positions of `(` in ordinary text whose argument list is known never to close (it runs into
/// the end of the file or a directive line). Filled when the first such list is found, so that
/// the many invocations of `F(F(F(…` that fail the same way are not each scanned again.
pub(crate) struct Unclosed {
    pub start: usize,
    pub end: usize,
    /// Ascending.
    pub unmatched: Vec<usize>,
}

impl Unclosed {
    /// Scans from the `(` at `lparen` to the end of the file or the next directive line.
    pub fn scan(text: &str, lparen: usize) -> Self {
        let mut cur = SrcCursor { text, pos: lparen };
        let mut open = Vec::new();
        loop {
            let at = cur.pos;
            let Some(tok) = cur.next_tok() else { break };
            match tok.kind {
                Kind::LParen => open.push(at),
                Kind::RParen => {
                    open.pop();
                }
                _ => {}
            }
        }
        // `open` holds positions in the order they were met: ascending.
        Unclosed { start: lparen, end: cur.pos, unmatched: open }
    }

    /// Whether the argument list opened at `lparen` is known to be unclosed (`Some(true)`), known
    /// to close (`Some(false)`), or unknown.
    pub fn verdict(&self, lparen: usize) -> Option<bool> {
        (self.start..self.end).contains(&lparen).then(|| self.unmatched.binary_search(&lparen).is_ok())
    }
}

impl Expander {
    pub fn new() -> Self {
        Expander {
            macros: Vec::new(),
            by_name: FnvMap::default(),
            active: Vec::new(),
            depth: 0,
            work: 0,
            work_limit: 1 << 20,
            out_limit: 1 << 20,
            held: 0,
            unclosed: None,
            limit: None,
            errors: Vec::new(),
        }
    }

    pub fn lookup(&self, name: &str) -> Option<u32> {
        self.by_name.get(name).copied()
    }

    pub fn is_function_like(&self, id: u32) -> bool {
        self.macros.get(id as usize).is_some_and(|m| m.params.is_some())
    }

    pub fn define(&mut self, mac: Macro) -> u32 {
        let id = self.macros.len() as u32;
        self.by_name.insert(mac.name.clone(), id);
        self.macros.push(mac);
        self.active.push(false);
        id
    }

    pub fn undefine(&mut self, name: &str) {
        self.by_name.remove(name);
    }

    pub fn take_errors(&mut self) -> Vec<ArgError> {
        std::mem::take(&mut self.errors)
    }

    fn hit(&mut self, limit: Limit) -> Stop {
        if self.limit.is_none() {
            self.limit = Some(limit);
        }
        Stop
    }

    /// Starts a new expansion (for [`MAX_HELD`]).
    pub fn begin(&mut self) {
        self.held = 0;
    }

    fn hold(&mut self, n: u64) -> Result<(), Stop> {
        self.held += n;
        if self.held > MAX_HELD {
            return Err(self.hit(Limit::Held));
        }
        Ok(())
    }

    fn known_unclosed(&self, lparen: usize) -> bool {
        self.unclosed.as_ref().and_then(|u| u.verdict(lparen)) == Some(true)
    }

    fn tick(&mut self) -> Result<(), Stop> {
        self.work += 1;
        if self.work > self.work_limit {
            return Err(self.hit(Limit::Work));
        }
        Ok(())
    }

    fn push_ctx(&mut self, stack: &mut Vec<Ctx>, toks: Vec<Tok>, mac: Option<u32>) -> Result<(), Stop> {
        if self.depth >= MAX_DEPTH {
            return Err(self.hit(Limit::Depth));
        }
        self.depth += 1;
        if let Some(m) = mac {
            self.active[m as usize] = true;
        }
        stack.push(Ctx { toks, pos: 0, mac });
        Ok(())
    }

    fn pop_ctx(&mut self, stack: &mut Vec<Ctx>) {
        if let Some(ctx) = stack.pop() {
            self.depth -= 1;
            if let Some(m) = ctx.mac {
                self.active[m as usize] = false;
            }
        }
    }

    /// The next token from the contexts (dropping finished ones), with the macro it names if that
    /// macro may be expanded here. A name of an active macro is marked `noexpand` for good.
    fn read_ctx(&mut self, stack: &mut Vec<Ctx>) -> Option<(Tok, Option<u32>)> {
        loop {
            let top = stack.last_mut()?;
            if let Some(tok) = top.toks.get(top.pos) {
                let mut tok = tok.clone();
                top.pos += 1;
                let mut mac = None;
                if tok.kind == Kind::Ident
                    && !tok.noexpand
                    && let Some(id) = self.lookup(&tok.text)
                {
                    if self.active[id as usize] {
                        tok.noexpand = true;
                    } else {
                        mac = Some(id);
                    }
                }
                return Some((tok, mac));
            }
            self.pop_ctx(stack);
        }
    }

    /// Like [`Self::read_ctx`], then from the source when the contexts run out.
    fn read_any(&mut self, stack: &mut Vec<Ctx>, src: Option<&mut SrcCursor<'_>>) -> Option<Tok> {
        if let Some((tok, _)) = self.read_ctx(stack) {
            return Some(tok);
        }
        src?.next_tok()
    }

    fn peek_lparen(stack: &[Ctx], src: Option<&SrcCursor<'_>>) -> bool {
        for ctx in stack.iter().rev() {
            for tok in ctx.toks.get(ctx.pos..).unwrap_or(&[]) {
                match tok.kind {
                    Kind::Ws => {}
                    Kind::LParen => return true,
                    _ => return false,
                }
            }
        }
        src.is_some_and(SrcCursor::peek_lparen)
    }

    fn emit(&mut self, sink: &mut Sink<'_>, tok: Tok) -> Result<(), Stop> {
        match sink {
            Sink::Text { buf, base } => {
                buf.push_str(&tok.text);
                if *base + buf.len() > self.out_limit {
                    return Err(self.hit(Limit::Output));
                }
            }
            Sink::Toks(v) => {
                self.hold(1)?;
                v.push(tok);
            }
        }
        Ok(())
    }

    /// Expands the invocation of macro `id` whose name was just read from `src` (which is left
    /// after the name). Returns `Ok(false)` when a function-like macro's argument list is never
    /// closed: nothing was expanded and `src` is unchanged.
    pub fn expand_from_source(&mut self, id: u32, src: &mut SrcCursor<'_>, sink: &mut Sink<'_>) -> Result<bool, Stop> {
        self.begin();
        let mut stack = Vec::new();
        let result = self.expand_from_source_inner(id, &mut stack, src, sink);
        while !stack.is_empty() {
            self.pop_ctx(&mut stack);
        }
        debug_assert_eq!(self.depth, 0);
        debug_assert!(!self.active.contains(&true));
        result
    }

    fn expand_from_source_inner(
        &mut self,
        id: u32,
        stack: &mut Vec<Ctx>,
        src: &mut SrcCursor<'_>,
        sink: &mut Sink<'_>,
    ) -> Result<bool, Stop> {
        let args = if self.is_function_like(id) {
            let start = src.pos;
            let lparen = src.lparen();
            if lparen.is_some_and(|lp| self.known_unclosed(lp)) {
                // Reported when the first list running into the same place was found.
                return Ok(false);
            }
            match self.collect_args(id, stack, Some(src))? {
                Collected::Args(args) => args,
                Collected::Unterminated => {
                    src.pos = start;
                    if let Some(lp) = lparen {
                        self.unclosed = Some(Unclosed::scan(src.text, lp));
                    }
                    return Ok(false);
                }
                Collected::Bad => return Ok(true),
            }
        } else {
            Vec::new()
        };
        let body = self.substitute(id, &args)?;
        self.push_ctx(stack, body, Some(id))?;
        self.run(stack, Some(src), sink)?;
        Ok(true)
    }

    /// Fully expands a token list on its own (an argument, an `#if` condition). Macros active
    /// around it stay active.
    pub fn expand_list(&mut self, mut toks: Vec<Tok>) -> Result<Vec<Tok>, Stop> {
        // Most arguments name no macro: mark names of active macros and hand them back as they are.
        let mut plain = true;
        for tok in &mut toks {
            if tok.kind == Kind::Ident
                && !tok.noexpand
                && let Some(id) = self.lookup(&tok.text)
            {
                if self.active[id as usize] {
                    tok.noexpand = true;
                } else {
                    plain = false;
                    break;
                }
            }
        }
        if plain {
            self.work += toks.len() as u64;
            if self.work > self.work_limit {
                return Err(self.hit(Limit::Work));
            }
            return Ok(toks);
        }
        if self.depth >= MAX_DEPTH {
            return Err(self.hit(Limit::Depth));
        }
        self.depth += 1;
        let mut stack = Vec::new();
        let mut out = Vec::with_capacity(toks.len());
        let result = match self.push_ctx(&mut stack, toks, None) {
            Ok(()) => self.run(&mut stack, None, &mut Sink::Toks(&mut out)),
            Err(stop) => Err(stop),
        };
        while !stack.is_empty() {
            self.pop_ctx(&mut stack);
        }
        self.depth -= 1;
        result.map(|()| out)
    }

    /// Rescans until the stack is empty.
    fn run(
        &mut self,
        stack: &mut Vec<Ctx>,
        mut src: Option<&mut SrcCursor<'_>>,
        sink: &mut Sink<'_>,
    ) -> Result<(), Stop> {
        while let Some((tok, mac)) = self.read_ctx(stack) {
            self.tick()?;
            let Some(id) = mac else {
                self.emit(sink, tok)?;
                continue;
            };
            let args = if self.is_function_like(id) {
                if !Self::peek_lparen(stack, src.as_deref()) {
                    self.emit(sink, tok)?;
                    continue;
                }
                let src_pos = src.as_deref().map(|s| s.pos);
                // The `(` is in the source text when the contexts hold nothing else.
                let from_src = stack.iter().all(|c| c.toks.get(c.pos..).unwrap_or(&[]).iter().all(Tok::is_ws));
                let lparen = if from_src { src.as_deref().and_then(SrcCursor::lparen) } else { None };
                if lparen.is_some_and(|lp| self.known_unclosed(lp)) {
                    self.emit(sink, tok)?;
                    continue;
                }
                match self.collect_args(id, stack, src.as_deref_mut())? {
                    Collected::Args(args) => args,
                    Collected::Bad => continue,
                    Collected::Unterminated => {
                        // Give the source text back; the error is reported at the invocation.
                        if let (Some(s), Some(pos)) = (src.as_deref_mut(), src_pos) {
                            s.pos = pos;
                            if let Some(lp) = lparen {
                                self.unclosed = Some(Unclosed::scan(s.text, lp));
                            }
                        }
                        continue;
                    }
                }
            } else {
                Vec::new()
            };
            let body = self.substitute(id, &args)?;
            self.push_ctx(stack, body, Some(id))?;
        }
        Ok(())
    }

    /// Reads `( a, b, … )` after the name of function-like macro `id`.
    fn collect_args(
        &mut self,
        id: u32,
        stack: &mut Vec<Ctx>,
        mut src: Option<&mut SrcCursor<'_>>,
    ) -> Result<Collected, Stop> {
        let name = self.macros[id as usize].name.clone();
        let want = self.macros[id as usize].params.as_ref().map_or(0, Vec::len);
        // Up to and including the `(`.
        loop {
            let Some(tok) = self.read_any(stack, src.as_deref_mut()) else {
                return Ok(self.unterminated(&name));
            };
            self.tick()?;
            if tok.kind == Kind::LParen {
                break;
            }
        }
        let mut args: Vec<Vec<Tok>> = vec![Vec::new()];
        let mut depth = 0usize;
        loop {
            let Some(tok) = self.read_any(stack, src.as_deref_mut()) else {
                return Ok(self.unterminated(&name));
            };
            self.tick()?;
            self.hold(1)?;
            match tok.kind {
                Kind::LParen => depth += 1,
                Kind::RParen if depth == 0 => break,
                Kind::RParen => depth -= 1,
                Kind::Comma if depth == 0 => {
                    args.push(Vec::new());
                    continue;
                }
                _ => {}
            }
            if let Some(arg) = args.last_mut() {
                arg.push(tok);
            }
        }
        for arg in &mut args {
            while arg.last().is_some_and(Tok::is_ws) {
                arg.pop();
            }
            let lead = arg.iter().take_while(|t| t.is_ws()).count();
            arg.drain(..lead);
        }
        if args.len() != want {
            let (s, were) = (if want == 1 { "" } else { "s" }, if args.len() == 1 { "was" } else { "were" });
            self.errors.push(ArgError {
                message: format!("macro `{name}` takes {want} argument{s} but {} {were} given", args.len()),
                note: None,
            });
            return Ok(Collected::Bad);
        }
        if let Some(i) = args.iter().position(Vec::is_empty) {
            self.errors.push(ArgError {
                message: format!("argument {} of macro `{name}` is empty", i + 1),
                note: Some("Godot requires every macro argument to be given".into()),
            });
            return Ok(Collected::Bad);
        }
        Ok(Collected::Args(args))
    }

    fn unterminated(&mut self, name: &str) -> Collected {
        self.errors.push(ArgError {
            message: format!("the argument list of macro `{name}` is never closed"),
            note: Some("expected `)` before the end of the file or the next directive".into()),
        });
        Collected::Unterminated
    }

    /// The replacement of macro `id` for these arguments, before rescanning, with a space on each
    /// side so that it never glues onto its neighbours (Godot does the same).
    fn substitute(&mut self, id: u32, args: &[Vec<Tok>]) -> Result<Vec<Tok>, Stop> {
        let body = self.macros[id as usize].body.clone();
        let mut expanded: Vec<Option<Vec<Tok>>> = vec![None; args.len()];
        let mut out = vec![Tok::space()];
        let mut paste = false;
        for (k, bt) in body.iter().enumerate() {
            match bt.kind {
                Kind::Paste => {
                    while out.len() > 1 && out.last().is_some_and(Tok::is_ws) {
                        out.pop();
                    }
                    paste = true;
                }
                Kind::Param => {
                    let i = bt.param as usize;
                    let Some(raw) = args.get(i) else { continue };
                    let next_is_paste =
                        body[k + 1..].iter().find(|t| !t.is_ws()).is_some_and(|t| t.kind == Kind::Paste);
                    let toks = if paste || next_is_paste {
                        raw
                    } else {
                        if expanded[i].is_none() {
                            expanded[i] = Some(self.expand_list(raw.clone())?);
                        }
                        expanded[i].as_deref().unwrap_or(&[])
                    };
                    self.work += toks.len() as u64;
                    if self.work > self.work_limit {
                        return Err(self.hit(Limit::Work));
                    }
                    self.hold(toks.len() as u64)?;
                    for t in toks {
                        push_pasting(&mut out, t.clone(), &mut paste);
                    }
                }
                _ => push_pasting(&mut out, bt.clone(), &mut paste),
            }
            self.tick()?;
        }
        out.push(Tok::space());
        Ok(out)
    }
}

enum Collected {
    Args(Vec<Vec<Tok>>),
    /// No closing `)`: not an invocation after all.
    Unterminated,
    /// Wrong number of arguments, or an empty one: the invocation is dropped.
    Bad,
}

/// Appends `tok`, joining it onto the previous token when a `##` is pending.
fn push_pasting(out: &mut Vec<Tok>, tok: Tok, paste: &mut bool) {
    if !*paste {
        out.push(tok);
        return;
    }
    if tok.is_ws() {
        return;
    }
    *paste = false;
    if out.len() > 1
        && let Some(left) = out.pop()
    {
        let joined = format!("{}{}", left.text, tok.text);
        out.extend(lex::lex_all(&joined));
    } else {
        out.push(tok);
    }
}

//! The preprocessor's tokens: just enough structure to find macro names, argument lists and
//! `##`, with every token keeping its exact text so expansions read like the code they came from.

use std::rc::Rc;

/// What a preprocessing token is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Kind {
    /// `[A-Za-z_][A-Za-z0-9_]*`
    Ident,
    /// A run of identifier characters starting with a digit (`12`, `0xFF`, `1e5`, `2u`).
    Number,
    LParen,
    RParen,
    Comma,
    /// `"…"` (to the closing quote or the end of the line).
    Str,
    /// Blanks, line breaks and comments, all written as one space.
    Ws,
    /// `##` in a macro body: joins the tokens on either side.
    Paste,
    /// Anything else: a run of punctuation or non-ASCII text.
    Other,
    /// A parameter of a function-like macro, in its body (index in `Tok::param`).
    Param,
}

/// One preprocessing token.
#[derive(Clone, Debug)]
pub(crate) struct Tok {
    pub text: Rc<str>,
    /// Parameter index for [`Kind::Param`].
    pub param: u32,
    pub kind: Kind,
    /// Set on a macro name met while that macro was being expanded: it is never expanded.
    pub noexpand: bool,
}

thread_local! {
    static SPACE: Rc<str> = Rc::from(" ");
}

impl Tok {
    pub fn new(kind: Kind, text: &str) -> Self {
        if kind == Kind::Ws {
            return Self::space();
        }
        Tok { text: Rc::from(text), param: 0, kind, noexpand: false }
    }

    /// A single space.
    pub fn space() -> Self {
        Tok { text: SPACE.with(Rc::clone), param: 0, kind: Kind::Ws, noexpand: false }
    }

    pub fn is_ws(&self) -> bool {
        self.kind == Kind::Ws
    }
}

pub(crate) fn is_ident_start(b: u8) -> bool {
    b.is_ascii_alphabetic() || b == b'_'
}

pub(crate) fn is_ident_char(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

/// Blanks inside a line (a line break is not one).
pub(crate) fn is_blank(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | 0x0b | 0x0c)
}

/// End of the identifier-character run starting at `i`.
pub(crate) fn word_end(s: &[u8], mut i: usize) -> usize {
    while i < s.len() && is_ident_char(s[i]) {
        i += 1;
    }
    i
}

/// Position of the next `\n` at or after `i`, or the end.
pub(crate) fn line_end(s: &[u8], i: usize) -> usize {
    s.get(i..).and_then(|rest| rest.iter().position(|&b| b == b'\n')).map_or(s.len(), |p| i + p)
}

/// End of a block comment whose body starts at `i` (just after `/*`): the position after `*/`,
/// and whether it was closed at all (if not, the end of the text).
pub(crate) fn block_comment_end(s: &[u8], i: usize) -> (usize, bool) {
    let mut j = i;
    while j + 1 < s.len() {
        if s[j] == b'*' && s[j + 1] == b'/' {
            return (j + 2, true);
        }
        j += 1;
    }
    (s.len(), false)
}

/// End of a string literal whose opening quote is at `i`: after the closing quote, or at the end
/// of the line when there is none.
pub(crate) fn string_end(s: &[u8], i: usize) -> usize {
    let mut j = i + 1;
    while j < s.len() {
        match s[j] {
            b'"' => return j + 1,
            b'\n' => return j,
            _ => j += 1,
        }
    }
    j
}

/// Lexes one token of `s` at `i` (which must be `< s.len()`), returning its kind and end.
/// Comments count as whitespace. Token boundaries always fall on ASCII bytes, so slicing the
/// text at them is safe.
pub(crate) fn lex_one(s: &[u8], i: usize) -> (Kind, usize) {
    let c = s[i];
    let next = s.get(i + 1).copied();
    match c {
        b'\n' | b' ' | b'\t' | b'\r' | 0x0b | 0x0c => {
            let mut j = i + 1;
            while j < s.len() && (is_blank(s[j]) || s[j] == b'\n') {
                j += 1;
            }
            (Kind::Ws, j)
        }
        b'/' if next == Some(b'/') => (Kind::Ws, line_end(s, i)),
        b'/' if next == Some(b'*') => (Kind::Ws, block_comment_end(s, i + 2).0),
        b'(' => (Kind::LParen, i + 1),
        b')' => (Kind::RParen, i + 1),
        b',' => (Kind::Comma, i + 1),
        b'"' => (Kind::Str, string_end(s, i)),
        b'#' => {
            let mut j = i + 1;
            while j < s.len() && s[j] == b'#' {
                j += 1;
            }
            (if j - i == 2 { Kind::Paste } else { Kind::Other }, j)
        }
        _ if is_ident_start(c) => (Kind::Ident, word_end(s, i)),
        _ if c.is_ascii_digit() => (Kind::Number, word_end(s, i)),
        _ => {
            let mut j = i + 1;
            while j < s.len() {
                let b = s[j];
                let stops = is_ident_char(b)
                    || is_blank(b)
                    || matches!(b, b'\n' | b'(' | b')' | b',' | b'"' | b'#')
                    || (b == b'/' && matches!(s.get(j + 1), Some(b'/' | b'*')));
                if stops {
                    break;
                }
                j += 1;
            }
            (Kind::Other, j)
        }
    }
}

/// Lexes a whole text (a macro body, an `#if` condition, a pasted token).
pub(crate) fn lex_all(text: &str) -> Vec<Tok> {
    let s = text.as_bytes();
    let mut toks = Vec::new();
    let mut i = 0;
    while i < s.len() {
        let (kind, end) = lex_one(s, i);
        let end = end.max(i + 1).min(s.len());
        toks.push(Tok::new(kind, text.get(i..end).unwrap_or("")));
        i = end;
    }
    toks
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kinds(text: &str) -> Vec<(Kind, String)> {
        lex_all(text).into_iter().map(|t| (t.kind, t.text.to_string())).collect()
    }

    #[test]
    fn lexes_the_pieces_macros_care_about() {
        use Kind::*;
        assert_eq!(
            kinds("f(a, 1.5e3) ## \"x,y\" /* c */ <<= é"),
            vec![
                (Ident, "f".into()),
                (LParen, "(".into()),
                (Ident, "a".into()),
                (Comma, ",".into()),
                (Ws, " ".into()),
                (Number, "1".into()),
                (Other, ".".into()),
                (Number, "5e3".into()),
                (RParen, ")".into()),
                (Ws, " ".into()),
                (Paste, "##".into()),
                (Ws, " ".into()),
                (Str, "\"x,y\"".into()),
                (Ws, " ".into()),
                (Ws, " ".into()),
                (Ws, " ".into()),
                (Other, "<<=".into()),
                (Ws, " ".into()),
                (Other, "é".into()),
            ]
        );
        assert_eq!(kinds("###")[0].0, Other);
    }
}

//! `#if` / `#elif` conditions: integer expressions, evaluated after `defined` and macro
//! expansion have been applied.
//!
//! Godot evaluates conditions with its `Expression` class, whose precedence is GDScript's, not
//! C's: `& ^ |` bind tighter than the comparisons, all six comparisons share one level, and `!`
//! binds looser than the comparisons (`!A == B` is `!(A == B)`). That order is followed here,
//! loosest first: `||`, `&&`, `!`, comparisons, `|`, `^`, `&`, shifts, `+ -`, `* / %`, then the
//! unary `- + ~` (and `!` directly before an operand).

/// Why a condition could not be evaluated.
#[derive(Debug)]
pub(crate) struct ExprError {
    pub message: String,
    pub note: Option<String>,
    /// The identifier at fault, when there is one (to point at it).
    pub ident: Option<String>,
}

fn err(message: impl Into<String>) -> ExprError {
    ExprError { message: message.into(), note: None, ident: None }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum T {
    Num(i64),
    Op(&'static str),
    LParen,
    RParen,
}

const OPS: [&str; 21] =
    ["&&", "||", "<<", ">>", "<=", ">=", "==", "!=", "!", "~", "-", "+", "*", "/", "%", "<", ">", "&", "^", "|", "="];

/// Deepest nesting of parentheses and prefix operators.
const MAX_NESTING: usize = 128;

fn tokenize(text: &str) -> Result<Vec<T>, ExprError> {
    let s = text.as_bytes();
    let mut toks = Vec::new();
    let mut i = 0;
    while i < s.len() {
        let c = s[i];
        if c.is_ascii_whitespace() {
            i += 1;
        } else if c.is_ascii_digit() {
            let end = super::lex::word_end(s, i);
            let word = &text[i..end];
            if s.get(end) == Some(&b'.') {
                return Err(ExprError {
                    message: "floating-point numbers are not supported in `#if` conditions".into(),
                    note: Some("gdsky evaluates `#if` conditions with integers".into()),
                    ident: None,
                });
            }
            toks.push(T::Num(parse_int(word)?));
            i = end;
        } else if super::lex::is_ident_start(c) {
            let end = super::lex::word_end(s, i);
            let word = &text[i..end];
            match word {
                "true" => toks.push(T::Num(1)),
                "false" => toks.push(T::Num(0)),
                "defined" => return Err(err("`defined` must be followed by a macro name")),
                _ => {
                    return Err(ExprError {
                        message: format!("`{word}` is not defined"),
                        note: Some(format!(
                            "an `#if` condition may only use integers, operators and defined macros; `defined({word})` tests whether a macro exists"
                        )),
                        ident: Some(word.to_string()),
                    });
                }
            }
            i = end;
        } else if c == b'(' {
            toks.push(T::LParen);
            i += 1;
        } else if c == b')' {
            toks.push(T::RParen);
            i += 1;
        } else if let Some(op) = OPS.iter().find(|op| s[i..].starts_with(op.as_bytes())) {
            if *op == "=" {
                return Err(ExprError {
                    message: "unexpected `=` in the `#if` condition".into(),
                    note: Some("use `==` to compare".into()),
                    ident: None,
                });
            }
            toks.push(T::Op(op));
            i += op.len();
        } else {
            let ch = text[i..].chars().next().unwrap_or('?');
            return Err(err(format!("unexpected `{ch}` in the `#if` condition")));
        }
    }
    Ok(toks)
}

fn parse_int(word: &str) -> Result<i64, ExprError> {
    let bad = || err(format!("`{word}` is not an integer"));
    let (digits, radix) = match word.strip_prefix("0x").or_else(|| word.strip_prefix("0X")) {
        Some(hex) => (hex, 16),
        None => (word, 10),
    };
    if digits.is_empty() || !digits.bytes().all(|b| (b as char).is_digit(radix)) {
        return Err(bad());
    }
    i64::from_str_radix(digits, radix).map_err(|_| err(format!("the integer `{word}` is too large")))
}

/// Binding priority of a binary operator (Godot's `Expression`: lower binds tighter).
fn priority(op: &str) -> Option<u8> {
    Some(match op {
        "*" | "/" | "%" => 3,
        "+" | "-" => 4,
        "<<" | ">>" => 5,
        "&" => 6,
        "^" => 7,
        "|" => 8,
        "==" | "!=" | "<" | "<=" | ">" | ">=" => 9,
        "&&" => 13,
        "||" => 14,
        _ => return None,
    })
}
/// Priority of the prefix `!` when it starts an operand of a loose operator.
const NOT_PRIORITY: u8 = 12;
const LOOSEST: u8 = 14;

struct Parser {
    toks: Vec<T>,
    pos: usize,
    depth: usize,
}

impl Parser {
    fn peek(&self) -> Option<T> {
        self.toks.get(self.pos).copied()
    }

    fn eat_op(&mut self, op: &'static str) -> bool {
        if self.peek() == Some(T::Op(op)) {
            self.pos += 1;
            return true;
        }
        false
    }

    fn enter(&mut self) -> Result<(), ExprError> {
        self.depth += 1;
        if self.depth > MAX_NESTING {
            return Err(err(format!("the `#if` condition is nested more than {MAX_NESTING} levels deep")));
        }
        Ok(())
    }

    /// Parses (and, when `eval`, evaluates) an expression whose binary operators all have
    /// priority `max` or tighter (precedence climbing, left-associative).
    fn binary(&mut self, max: u8, eval: bool) -> Result<i64, ExprError> {
        let mut lhs = if max >= NOT_PRIORITY && self.eat_op("!") {
            self.enter()?;
            let v = self.binary(NOT_PRIORITY, eval)?;
            self.depth -= 1;
            i64::from(v == 0)
        } else {
            self.unary(eval)?
        };
        while let Some(T::Op(op)) = self.peek() {
            let Some(p) = priority(op).filter(|&p| p <= max) else {
                break;
            };
            self.pos += 1;
            let rhs_eval = match op {
                "&&" => eval && lhs != 0,
                "||" => eval && lhs == 0,
                _ => eval,
            };
            let rhs = self.binary(p - 1, rhs_eval)?;
            lhs = match op {
                "&&" => i64::from(lhs != 0 && rhs != 0),
                "||" => i64::from(lhs != 0 || rhs != 0),
                _ => apply(op, lhs, rhs, eval)?,
            };
        }
        Ok(lhs)
    }

    fn unary(&mut self, eval: bool) -> Result<i64, ExprError> {
        match self.peek() {
            Some(T::Op(op @ ("-" | "+" | "~" | "!"))) => {
                self.pos += 1;
                self.enter()?;
                let v = self.unary(eval)?;
                self.depth -= 1;
                Ok(match op {
                    "-" => v.wrapping_neg(),
                    "+" => v,
                    "~" => !v,
                    _ => i64::from(v == 0),
                })
            }
            Some(T::Num(n)) => {
                self.pos += 1;
                Ok(n)
            }
            Some(T::LParen) => {
                self.pos += 1;
                self.enter()?;
                let v = self.binary(LOOSEST, eval)?;
                self.depth -= 1;
                if self.peek() != Some(T::RParen) {
                    return Err(match self.peek() {
                        None => err("expected `)` before the end of the `#if` condition"),
                        Some(t) => err(format!("expected `)` but found {}", describe(t))),
                    });
                }
                self.pos += 1;
                Ok(v)
            }
            None => Err(err("the `#if` condition ends where a value was expected")),
            Some(t) => Err(err(format!("expected a value but found {}", describe(t)))),
        }
    }
}

fn describe(t: T) -> String {
    match t {
        T::Num(n) => format!("`{n}`"),
        T::Op(op) => format!("`{op}`"),
        T::LParen => "`(`".into(),
        T::RParen => "`)`".into(),
    }
}

fn apply(op: &str, a: i64, b: i64, eval: bool) -> Result<i64, ExprError> {
    Ok(match op {
        "*" => a.wrapping_mul(b),
        "/" | "%" => {
            if b == 0 {
                if eval {
                    return Err(err("division by zero in the `#if` condition"));
                }
                0
            } else if op == "/" {
                a.wrapping_div(b)
            } else {
                a.wrapping_rem(b)
            }
        }
        "+" => a.wrapping_add(b),
        "-" => a.wrapping_sub(b),
        "<<" | ">>" => {
            if !(0..64).contains(&b) {
                if eval {
                    return Err(err(format!("shift by {b} is out of range in the `#if` condition")));
                }
                0
            } else if op == "<<" {
                a.wrapping_shl(b as u32)
            } else {
                a >> b
            }
        }
        "&" => a & b,
        "^" => a ^ b,
        "|" => a | b,
        "==" => i64::from(a == b),
        "!=" => i64::from(a != b),
        "<" => i64::from(a < b),
        "<=" => i64::from(a <= b),
        ">" => i64::from(a > b),
        ">=" => i64::from(a >= b),
        _ => return Err(err(format!("unexpected `{op}` in the `#if` condition"))),
    })
}

/// Evaluates a condition (already macro-expanded, `defined` already replaced).
pub(crate) fn eval(text: &str) -> Result<i64, ExprError> {
    let toks = tokenize(text)?;
    if toks.is_empty() {
        return Err(err("the condition is empty"));
    }
    let mut p = Parser { toks, pos: 0, depth: 0 };
    let v = p.binary(LOOSEST, true)?;
    if let Some(t) = p.peek() {
        return Err(err(format!("unexpected {} in the `#if` condition", describe(t))));
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::eval;

    #[test]
    fn arithmetic_and_precedence() {
        assert_eq!(eval("1 + 2 * 3").unwrap(), 7);
        assert_eq!(eval("(1 + 2) * 3").unwrap(), 9);
        assert_eq!(eval("0x10 >> 2").unwrap(), 4);
        assert_eq!(eval("-3 / 2").unwrap(), -1);
        assert_eq!(eval("7 % 4 == 3 && ~0 == -1").unwrap(), 1);
        assert_eq!(eval("1 < 2 || 1 / 0").unwrap(), 1);
        assert_eq!(eval("0 && 1 / 0").unwrap(), 0);
        // Godot (GDScript) precedence: `&` binds tighter than `==`, `!` looser.
        assert_eq!(eval("6 & 2 == 2").unwrap(), 1);
        assert_eq!(eval("!1 == 0").unwrap(), 1);
        assert_eq!(eval("!0 && 1").unwrap(), 1);
        assert_eq!(eval("1 == !0").unwrap(), 1);
        assert_eq!(eval("true && !false").unwrap(), 1);
    }

    #[test]
    fn errors() {
        assert!(eval("1 / 0").unwrap_err().message.contains("division by zero"));
        assert!(eval("5 % 0").is_err());
        let e = eval("FOO + 1").unwrap_err();
        assert_eq!(e.ident.as_deref(), Some("FOO"));
        assert!(e.message.contains("`FOO` is not defined"));
        assert!(eval("1 +").is_err());
        assert!(eval("(1").is_err());
        assert!(eval("1 2").is_err());
        assert!(eval("1.5").is_err());
        assert!(eval("99999999999999999999").is_err());
        assert!(eval("1 << 64").is_err());
        assert!(eval("a = 1").is_err());
        assert!(eval("").is_err());
        let deep = "(".repeat(10_000) + "1" + &")".repeat(10_000);
        assert!(eval(&deep).unwrap_err().message.contains("nested"));
        let nots = "!".repeat(10_000) + "1";
        assert!(eval(&nots).is_err());
    }
}

//! The parser of Godot's text resource format: text → [`Document`] of sections, properties and
//! [`Value`]s, each with its byte span.
//!
//! Two steps, as the shader parser does it. A pre-scan walks the text once, skipping strings and
//! comments, and refuses nesting deeper than [`MAX_NESTING`] before pest (which recurses once per
//! bracket) sees it. Then pest parses with `grammar.pest`, and the pairs become values: strings
//! unescaped, numbers read, constructors checked against Godot's variant types (name, argument
//! count and kinds), so a typo in a file is reported where it is.

use crate::codes;
use gdshader::diag::{Diagnostic, FileId};
use pest::Parser as _;
use pest::iterators::Pair;
use std::ops::Range;

/// A byte range of the file.
pub type Span = Range<usize>;

/// Deepest bracket nesting accepted. Resources nest a few levels (a dictionary of arrays of
/// vectors); the bound keeps hostile input from overflowing the stack of pest's recursion.
pub const MAX_NESTING: usize = 64;

#[derive(pest_derive::Parser)]
#[grammar = "grammar.pest"]
struct ResourceParser;

/// A parsed `.tres` or `.tscn`: its sections in file order.
#[derive(Clone, Debug, PartialEq)]
pub struct Document {
    /// The sections; the first is `gd_resource` or `gd_scene`.
    pub sections: Vec<Section>,
}

/// One `[tag attr=value …]` header and the `key = value` properties under it.
#[derive(Clone, Debug, PartialEq)]
pub struct Section {
    /// `gd_resource`, `ext_resource`, `sub_resource`, `resource`, `node`, `connection`, ….
    pub tag: String,
    /// The header, brackets included.
    pub span: Span,
    /// The header's attributes in order.
    pub attributes: Vec<Entry>,
    /// The properties in order.
    pub properties: Vec<Entry>,
}

/// An attribute of a header or a property: a name and a value.
#[derive(Clone, Debug, PartialEq)]
pub struct Entry {
    /// The name (`type`, `shader_parameter/sun_color`), unquoted.
    pub name: String,
    /// Where the name is.
    pub name_span: Span,
    /// The value.
    pub value: Value,
}

/// A Godot variant written in the file, and where.
#[derive(Clone, Debug, PartialEq)]
pub struct Value {
    /// What it is.
    pub kind: ValueKind,
    /// Where it is.
    pub span: Span,
}

/// The kinds of values the format writes.
#[derive(Clone, Debug, PartialEq)]
pub enum ValueKind {
    /// `null`.
    Null,
    /// `true`, `false`.
    Bool(bool),
    /// An integer (Godot's ints are 64-bit).
    Int(i64),
    /// A float, `inf`, `-inf`, `nan` included.
    Float(f64),
    /// A string, unescaped.
    String(String),
    /// `&"name"` or `StringName("name")`.
    StringName(String),
    /// `^"path"` or `NodePath("path")`.
    NodePath(String),
    /// `[a, b]`.
    Array(Vec<Value>),
    /// `Array[int]([1, 2])`: the element type as written, and the items.
    TypedArray {
        /// The element type (`int`, `ExtResource("1_x")`).
        element: String,
        /// The items.
        items: Vec<Value>,
    },
    /// `{ key: value }`.
    Dictionary(Vec<(Value, Value)>),
    /// `Dictionary[String, int]({ … })`.
    TypedDictionary {
        /// The key type as written.
        key: String,
        /// The value type as written.
        value: String,
        /// The entries.
        entries: Vec<(Value, Value)>,
    },
    /// A built-in type's constructor with its arguments checked: `Vector3(0, 1, 0)`,
    /// `Color(1, 1, 1, 1)`, `PackedFloat32Array(…)`, `Transform3D(…)`.
    Constructor {
        /// The type.
        name: String,
        /// The arguments.
        args: Vec<Value>,
    },
    /// `ExtResource("id")`.
    ExtResource(String),
    /// `SubResource("id")`.
    SubResource(String),
    /// `Resource("res://…")`.
    Resource(String),
    /// `Object(Class, "property": value, …)`.
    Object {
        /// The class.
        class: String,
        /// The properties in order.
        properties: Vec<(String, Value)>,
    },
}

impl Value {
    /// The number, when the value is an int or a float.
    pub fn number(&self) -> Option<f64> {
        match self.kind {
            ValueKind::Int(i) => Some(i as f64),
            ValueKind::Float(f) => Some(f),
            _ => None,
        }
    }

    /// The string, when the value is one (a plain string, a StringName or a NodePath).
    pub fn str(&self) -> Option<&str> {
        match &self.kind {
            ValueKind::String(s) | ValueKind::StringName(s) | ValueKind::NodePath(s) => Some(s),
            _ => None,
        }
    }

    /// The value as a resource id: a string, or an int (format 2 numbers its resources).
    pub fn id(&self) -> Option<String> {
        match &self.kind {
            ValueKind::Int(i) => Some(i.to_string()),
            _ => self.str().map(str::to_string),
        }
    }

    /// The kind in words, for messages: `a string`, `a Vector3`.
    pub fn describe(&self) -> String {
        match &self.kind {
            ValueKind::Null => "null".into(),
            ValueKind::Bool(_) => "a bool".into(),
            ValueKind::Int(_) => "an int".into(),
            ValueKind::Float(_) => "a float".into(),
            ValueKind::String(_) => "a string".into(),
            ValueKind::StringName(_) => "a StringName".into(),
            ValueKind::NodePath(_) => "a NodePath".into(),
            ValueKind::Array(_) | ValueKind::TypedArray { .. } => "an array".into(),
            ValueKind::Dictionary(_) | ValueKind::TypedDictionary { .. } => "a dictionary".into(),
            ValueKind::Constructor { name, .. } => format!("a {name}"),
            ValueKind::ExtResource(_) => "an ExtResource".into(),
            ValueKind::SubResource(_) => "a SubResource".into(),
            ValueKind::Resource(_) => "a Resource".into(),
            ValueKind::Object { class, .. } => format!("an Object({class})"),
        }
    }
}

impl Section {
    /// The header attribute `name`.
    pub fn attribute(&self, name: &str) -> Option<&Entry> {
        self.attributes.iter().find(|a| a.name == name)
    }

    /// The header attribute `name` as a string.
    pub fn attribute_str(&self, name: &str) -> Option<&str> {
        self.attribute(name).and_then(|a| a.value.str())
    }

    /// The property `name` (the last one when a file repeats it, as Godot reads it).
    pub fn property(&self, name: &str) -> Option<&Entry> {
        self.properties.iter().rev().find(|p| p.name == name)
    }
}

/// Parses `text`, the contents of `file`. The error is located in `file`.
pub fn parse(text: &str, file: FileId) -> Result<Document, Diagnostic> {
    prescan(text).map_err(|(span, message)| {
        Diagnostic::error(codes::TOO_DEEP, message.clone()).with_primary(file, span, "nested too deep here")
    })?;
    let root = match ResourceParser::parse(Rule::file, text) {
        Ok(mut pairs) => pairs.next(),
        Err(_) => return Err(syntax_error(text, file)),
    };
    let mut sections = Vec::new();
    for section in root.into_iter().flat_map(Pair::into_inner).filter(|p| p.as_rule() == Rule::section) {
        sections.push(build_section(section).map_err(|e| e.into_diagnostic(file))?);
    }
    Ok(Document { sections })
}

/// Refuses nesting deeper than [`MAX_NESTING`], skipping strings and comments. The error is the
/// bracket that goes too deep.
fn prescan(text: &str) -> Result<(), (Span, String)> {
    let bytes = text.as_bytes();
    let mut depth = 0usize;
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'"' => {
                i += 1;
                while i < bytes.len() && bytes[i] != b'"' {
                    i += if bytes[i] == b'\\' { 2 } else { 1 };
                }
            }
            b';' => {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
            }
            b'(' | b'[' | b'{' => {
                depth += 1;
                if depth > MAX_NESTING {
                    return Err((i..i + 1, format!("values nest deeper than {MAX_NESTING} brackets")));
                }
            }
            b')' | b']' | b'}' => depth = depth.saturating_sub(1),
            _ => {}
        }
        i += 1;
    }
    Ok(())
}

/// A value error before it has a file.
struct ValueError {
    code: &'static str,
    message: String,
    span: Span,
    label: String,
    note: Option<String>,
}

impl ValueError {
    fn new(span: Span, message: impl Into<String>, label: impl Into<String>) -> Self {
        Self { code: codes::BAD_VALUE, message: message.into(), span, label: label.into(), note: None }
    }

    fn note(mut self, note: impl Into<String>) -> Self {
        self.note = Some(note.into());
        self
    }

    fn into_diagnostic(self, file: FileId) -> Diagnostic {
        let d = Diagnostic::error(self.code, self.message).with_primary(file, self.span, self.label);
        match self.note {
            Some(n) => d.with_note(n),
            None => d,
        }
    }
}

fn span_of(pair: &Pair<'_, Rule>) -> Span {
    let s = pair.as_span();
    s.start()..s.end()
}

fn build_section(pair: Pair<'_, Rule>) -> Result<Section, ValueError> {
    let mut inner = pair.into_inner();
    let header = inner.next().ok_or_else(|| ValueError::new(0..0, "empty section", ""))?;
    let span = span_of(&header);
    let mut parts = header.into_inner();
    let tag = parts.next().map(|t| t.as_str().to_string()).unwrap_or_default();
    let attributes = parts.map(build_entry).collect::<Result<_, _>>()?;
    let properties = inner.map(build_entry).collect::<Result<_, _>>()?;
    Ok(Section { tag, span, attributes, properties })
}

/// An `attribute` or a `property`: a name, then a value.
fn build_entry(pair: Pair<'_, Rule>) -> Result<Entry, ValueError> {
    let mut inner = pair.into_inner();
    let (Some(name), Some(value)) = (inner.next(), inner.next()) else {
        return Err(ValueError::new(0..0, "an entry without a value", ""));
    };
    let name_span = span_of(&name);
    let bare = name.as_str().to_string();
    let name = match name.into_inner().next() {
        Some(quoted) if quoted.as_rule() == Rule::string => unescape(quoted)?,
        _ => bare,
    };
    Ok(Entry { name, name_span, value: build_value(value)? })
}

fn build_value(pair: Pair<'_, Rule>) -> Result<Value, ValueError> {
    let span = span_of(&pair);
    let kind = match pair.as_rule() {
        Rule::string => ValueKind::String(unescape(pair)?),
        Rule::string_name => ValueKind::StringName(unescape(first(pair)?)?),
        Rule::node_path_literal => ValueKind::NodePath(unescape(first(pair)?)?),
        Rule::number => number(pair.as_str(), span.clone())?,
        Rule::keyword => match pair.as_str() {
            "true" => ValueKind::Bool(true),
            "false" => ValueKind::Bool(false),
            _ => ValueKind::Null,
        },
        Rule::array => ValueKind::Array(pair.into_inner().map(build_value).collect::<Result<_, _>>()?),
        Rule::dictionary => ValueKind::Dictionary(entries(pair)?),
        Rule::typed_array => {
            let mut inner = pair.into_inner();
            let element = inner.next().map(|t| t.as_str().to_string()).unwrap_or_default();
            let items = match inner.next() {
                Some(array) => array.into_inner().map(build_value).collect::<Result<_, _>>()?,
                None => Vec::new(),
            };
            ValueKind::TypedArray { element, items }
        }
        Rule::typed_dictionary => {
            let mut inner = pair.into_inner();
            let key = inner.next().map(|t| t.as_str().to_string()).unwrap_or_default();
            let value = inner.next().map(|t| t.as_str().to_string()).unwrap_or_default();
            let entries = match inner.next() {
                Some(d) => entries(d)?,
                None => Vec::new(),
            };
            ValueKind::TypedDictionary { key, value, entries }
        }
        Rule::object => {
            let mut inner = pair.into_inner();
            let class = inner.next().map(|t| t.as_str().to_string()).unwrap_or_default();
            let mut properties = Vec::new();
            for p in inner {
                let mut kv = p.into_inner();
                let (Some(k), Some(v)) = (kv.next(), kv.next()) else { continue };
                properties.push((unescape(k)?, build_value(v)?));
            }
            ValueKind::Object { class, properties }
        }
        Rule::constructor => {
            let mut inner = pair.into_inner();
            let name_pair =
                inner.next().ok_or_else(|| ValueError::new(span.clone(), "a constructor without a name", ""))?;
            let name = name_pair.as_str().to_string();
            let args: Vec<Value> = inner.map(build_value).collect::<Result<_, _>>()?;
            constructor(name, span_of(&name_pair), args, span.clone())?
        }
        _ => return Err(ValueError::new(span, "expected a value", "here")),
    };
    Ok(Value { kind, span })
}

fn first(pair: Pair<'_, Rule>) -> Result<Pair<'_, Rule>, ValueError> {
    let span = span_of(&pair);
    pair.into_inner().next().ok_or_else(|| ValueError::new(span, "expected a string", "here"))
}

fn entries(pair: Pair<'_, Rule>) -> Result<Vec<(Value, Value)>, ValueError> {
    let mut out = Vec::new();
    for p in pair.into_inner() {
        let mut kv = p.into_inner();
        if let (Some(k), Some(v)) = (kv.next(), kv.next()) {
            out.push((build_value(k)?, build_value(v)?));
        }
    }
    Ok(out)
}

/// A number token: an int when it has no `.` and no exponent, else a float.
fn number(text: &str, span: Span) -> Result<ValueKind, ValueError> {
    let (negative, body) = match text.strip_prefix('-') {
        Some(rest) => (true, rest),
        None => (false, text),
    };
    let sign = if negative { -1.0 } else { 1.0 };
    match body {
        "inf" => return Ok(ValueKind::Float(sign * f64::INFINITY)),
        "inf_neg" => return Ok(ValueKind::Float(-sign * f64::INFINITY)),
        "nan" => return Ok(ValueKind::Float(f64::NAN)),
        _ => {}
    }
    if body.contains(['.', 'e', 'E']) {
        // Rust reads every decimal float Godot writes; an exponent too large gives ±inf, as
        // Godot's own reader does.
        return text
            .parse::<f64>()
            .map(ValueKind::Float)
            .map_err(|_| ValueError::new(span, format!("`{text}` is not a number"), "here"));
    }
    text.parse::<i64>().map(ValueKind::Int).map_err(|_| {
        ValueError::new(span, format!("`{text}` is out of range for an int"), "too large").note(format!(
            "Godot's ints are 64-bit: {} to {}",
            i64::MIN,
            i64::MAX
        ))
    })
}

/// A string token's contents with Godot's escapes resolved: `\"`, `\\`, `\n`, `\t`, `\r`, `\b`,
/// `\f`, `\'`, `\uXXXX` (surrogate pairs joined) and `\UXXXXXX`.
fn unescape(pair: Pair<'_, Rule>) -> Result<String, ValueError> {
    let body = pair.into_inner().next();
    let Some(body) = body else { return Ok(String::new()) };
    let base = body.as_span().start();
    let text = body.as_str();
    let mut out = String::with_capacity(text.len());
    let mut chars = text.char_indices().peekable();
    let mut pending_high: Option<(u32, usize)> = None;
    while let Some((i, c)) = chars.next() {
        if c != '\\' {
            if let Some((_, at)) = pending_high.take() {
                return Err(lone_surrogate(base + at));
            }
            out.push(c);
            continue;
        }
        let Some((_, e)) = chars.next() else {
            return Err(ValueError::new(base + i..base + i + 1, "a string ends in a lone `\\`", "here"));
        };
        let simple = match e {
            '"' => Some('"'),
            '\\' => Some('\\'),
            '\'' => Some('\''),
            'n' => Some('\n'),
            't' => Some('\t'),
            'r' => Some('\r'),
            'b' => Some('\u{8}'),
            'f' => Some('\u{c}'),
            _ => None,
        };
        if let Some(s) = simple {
            if let Some((_, at)) = pending_high.take() {
                return Err(lone_surrogate(base + at));
            }
            out.push(s);
            continue;
        }
        let digits = match e {
            'u' => 4,
            'U' => 6,
            _ => {
                let end = base + i + 1 + e.len_utf8();
                return Err(ValueError::new(base + i..end, format!("unknown escape `\\{e}` in a string"), "here")
                    .note("Godot's escapes: \\\" \\\\ \\' \\n \\t \\r \\b \\f \\uXXXX \\UXXXXXX"));
            }
        };
        let mut code = 0u32;
        let mut end = i + 2;
        for _ in 0..digits {
            match chars.peek().and_then(|(_, d)| d.to_digit(16)) {
                Some(d) => {
                    code = code * 16 + d;
                    chars.next();
                    end += 1;
                }
                None => {
                    return Err(ValueError::new(
                        base + i..base + end,
                        format!("`\\{e}` needs {digits} hexadecimal digits"),
                        "here",
                    ));
                }
            }
        }
        let span = base + i..base + end;
        match (pending_high.take(), code) {
            (None, 0xD800..=0xDBFF) => pending_high = Some((code, i)),
            (Some((high, _)), 0xDC00..=0xDFFF) => {
                let joined = 0x10000 + ((high - 0xD800) << 10) + (code - 0xDC00);
                out.push(char::from_u32(joined).unwrap_or(char::REPLACEMENT_CHARACTER));
            }
            (Some((_, at)), _) => return Err(lone_surrogate(base + at)),
            (None, _) => match char::from_u32(code) {
                Some(ch) => out.push(ch),
                None => {
                    return Err(ValueError::new(span, format!("`{}` is not a character", &text[i..end]), "here"));
                }
            },
        }
    }
    if let Some((_, at)) = pending_high {
        return Err(lone_surrogate(base + at));
    }
    Ok(out)
}

fn lone_surrogate(at: usize) -> ValueError {
    ValueError::new(at..at + 6, "a UTF-16 high surrogate without its low half", "here")
        .note("a character above U+FFFF is written `\\uD83D\\uDE00` or `\\U01F600`")
}

/// What a constructor's arguments must be.
enum Args {
    /// Exactly one of these counts of numbers.
    Numbers(&'static [usize]),
    /// Any count of numbers that is a multiple of this.
    NumberList(usize),
    /// Any count of strings.
    Strings,
    /// One string (or, in format 2, an int).
    Id,
    /// One or two strings.
    Path,
    /// Nothing.
    Empty,
}

/// Godot's built-in types that the format writes as constructors, and their arguments
/// (variant_parser.cpp). Godot 3's names (format 2) are accepted alongside.
const CONSTRUCTORS: &[(&str, Args)] = &[
    ("Vector2", Args::Numbers(&[2])),
    ("Vector2i", Args::Numbers(&[2])),
    ("Rect2", Args::Numbers(&[4])),
    ("Rect2i", Args::Numbers(&[4])),
    ("Vector3", Args::Numbers(&[3])),
    ("Vector3i", Args::Numbers(&[3])),
    ("Transform2D", Args::Numbers(&[6])),
    ("Vector4", Args::Numbers(&[4])),
    ("Vector4i", Args::Numbers(&[4])),
    ("Plane", Args::Numbers(&[4])),
    ("Quaternion", Args::Numbers(&[4])),
    ("Quat", Args::Numbers(&[4])),
    ("AABB", Args::Numbers(&[6])),
    ("Basis", Args::Numbers(&[9])),
    ("Transform3D", Args::Numbers(&[12])),
    ("Transform", Args::Numbers(&[12])),
    ("Projection", Args::Numbers(&[16])),
    ("Color", Args::Numbers(&[3, 4])),
    ("PackedByteArray", Args::NumberList(1)),
    ("PackedInt32Array", Args::NumberList(1)),
    ("PackedInt64Array", Args::NumberList(1)),
    ("PackedFloat32Array", Args::NumberList(1)),
    ("PackedFloat64Array", Args::NumberList(1)),
    ("PackedVector2Array", Args::NumberList(2)),
    ("PackedVector3Array", Args::NumberList(3)),
    ("PackedColorArray", Args::NumberList(4)),
    ("PackedVector4Array", Args::NumberList(4)),
    ("PackedStringArray", Args::Strings),
    ("PoolByteArray", Args::NumberList(1)),
    ("PoolIntArray", Args::NumberList(1)),
    ("PoolRealArray", Args::NumberList(1)),
    ("PoolVector2Array", Args::NumberList(2)),
    ("PoolVector3Array", Args::NumberList(3)),
    ("PoolColorArray", Args::NumberList(4)),
    ("PoolStringArray", Args::Strings),
    ("StringName", Args::Id),
    ("NodePath", Args::Id),
    ("ExtResource", Args::Id),
    ("SubResource", Args::Id),
    ("Resource", Args::Path),
    ("RID", Args::NumberList(1)),
    ("Callable", Args::Empty),
    ("Signal", Args::Empty),
];

/// Checks a constructor against [`CONSTRUCTORS`] and builds its value.
fn constructor(name: String, name_span: Span, args: Vec<Value>, span: Span) -> Result<ValueKind, ValueError> {
    let Some((_, expected)) = CONSTRUCTORS.iter().find(|(n, _)| *n == name) else {
        let known: Vec<&str> = CONSTRUCTORS.iter().map(|(n, _)| *n).filter(|n| !n.starts_with("Pool")).collect();
        let mut e =
            ValueError::new(name_span, format!("`{name}` is not a type the resource format writes"), "unknown type");
        e = match gdshader::diag::did_you_mean(&name, known.iter().copied()) {
            Some(m) => e.note(format!("did you mean `{m}`?")),
            None => e.note(format!("known: {}, Array[T](…), Dictionary[K, V](…), Object(Class, …)", known.join(", "))),
        };
        return Err(e);
    };
    let wrong = |what: String| {
        ValueError::new(span.clone(), format!("`{name}(…)` takes {what}"), format!("{} argument(s) here", args.len()))
    };
    let all_numbers = || args.iter().all(|a| a.number().is_some());
    match expected {
        Args::Numbers(counts) => {
            if !counts.contains(&args.len()) || !all_numbers() {
                let counts: Vec<String> = counts.iter().map(ToString::to_string).collect();
                return Err(wrong(format!("{} numbers", counts.join(" or "))));
            }
        }
        Args::NumberList(n) => {
            // A PackedByteArray may be written as one base64 string (Godot 4.3 and later).
            let base64 = name == "PackedByteArray" && args.len() == 1 && matches!(args[0].kind, ValueKind::String(_));
            if !base64 && (!all_numbers() || !args.len().is_multiple_of(*n)) {
                return Err(wrong(if *n == 1 { "numbers".into() } else { format!("numbers, {n} per element") }));
            }
        }
        Args::Strings => {
            if !args.iter().all(|a| matches!(a.kind, ValueKind::String(_))) {
                return Err(wrong("strings".into()));
            }
        }
        Args::Id => {
            let id = match args.as_slice() {
                [one] => one.id(),
                _ => None,
            };
            let Some(id) = id else { return Err(wrong("one string".into())) };
            return Ok(match name.as_str() {
                "StringName" => ValueKind::StringName(id),
                "NodePath" => ValueKind::NodePath(id),
                "ExtResource" => ValueKind::ExtResource(id),
                _ => ValueKind::SubResource(id),
            });
        }
        Args::Path => {
            let path = match args.as_slice() {
                [p] | [p, _] => p.str().map(str::to_string),
                _ => None,
            };
            let Some(path) = path else { return Err(wrong("a path string".into())) };
            return Ok(ValueKind::Resource(path));
        }
        Args::Empty => {
            if !args.is_empty() {
                return Err(wrong("no arguments".into()));
            }
        }
    }
    Ok(ValueKind::Constructor { name, args })
}

/// The syntax error at the farthest point pest reached, with what it expected there in words.
fn syntax_error(text: &str, file: FileId) -> Diagnostic {
    pest::set_error_detail(true);
    let result = ResourceParser::parse(Rule::file, text);
    pest::set_error_detail(false);
    let Err(err) = result else {
        return Diagnostic::error(codes::SYNTAX, "syntax error").with_primary(file, 0..0, "");
    };
    let rule_pos = match err.location {
        pest::error::InputLocation::Pos(p) => p,
        pest::error::InputLocation::Span((s, _)) => s,
    };
    // pest's location is the farthest place a rule was tried; a literal token tried farther
    // (the `,` or `]` after an array's last item) is where the text really went wrong.
    let pos = err.parse_attempts().map_or(rule_pos, |a| a.max_position.max(rule_pos));
    let mut expected: Vec<String> = Vec::new();
    let mut add = |s: String| {
        if !expected.contains(&s) {
            expected.push(s);
        }
    };
    if let Some(attempts) = err.parse_attempts() {
        for t in attempts.expected_tokens() {
            let t = t.to_string();
            if matches!(t.as_str(), "]" | "=" | "," | ")" | "}" | ":" | "\"" | "(" | "[" | "{") {
                add(format!("`{t}`"));
            }
        }
    }
    if let pest::error::ErrorVariant::ParsingError { positives, .. } = &err.variant
        && rule_pos == pos
    {
        for r in positives {
            if let Some(words) = english(*r) {
                add(words.to_string());
            }
        }
    }
    // Tokens that only start a value, and type names (which start constructors), add nothing
    // to "a value".
    if expected.iter().any(|e| e == "a value") {
        expected.retain(|e| !matches!(e.as_str(), "`\"`" | "`[`" | "`(`" | "`{`" | "a type name"));
    }
    if let Some(i) = expected.iter().position(|e| e == "the end of the file") {
        let eof = expected.remove(i);
        expected.push(eof);
    }
    let (span, found) = found_token(text, pos);
    let message = match expected.as_slice() {
        [] => format!("unexpected {found}"),
        [one] => format!("expected {one}, found {found}"),
        [rest @ .., last] => {
            let rest: Vec<&str> = rest.iter().take(5).map(String::as_str).collect();
            format!("expected {} or {last}, found {found}", rest.join(", "))
        }
    };
    // A missing `]` or `)` belongs at the end of what came before, not at the next line.
    let before = text[..pos.min(text.len())].trim_end().len();
    let closer_missing = expected.iter().any(|e| matches!(e.as_str(), "`]`" | "`)`" | "`}`" | "a value"));
    let mut d = if closer_missing && text[before..pos.min(text.len())].contains('\n') {
        let label = if expected.len() == 1 { format!("expected {} here", expected[0]) } else { "expected here".into() };
        Diagnostic::error(codes::SYNTAX, message).with_primary(file, before..before, label).with_secondary(
            file,
            span,
            "next token",
        )
    } else {
        Diagnostic::error(codes::SYNTAX, message).with_primary(file, span, "unexpected here")
    };
    if let Some(open) = unterminated_string(&text[..pos.min(text.len())]) {
        d = d
            .with_secondary(file, open..open + 1, "this string is not closed")
            .with_note("`\"` inside a string is written `\\\"`");
    }
    d
}

/// Where the string that `before` ends inside opens, if it does (quotes outside comments).
fn unterminated_string(before: &str) -> Option<usize> {
    let bytes = before.as_bytes();
    let (mut i, mut open) = (0, None);
    while i < bytes.len() {
        match bytes[i] {
            b'\\' if open.is_some() => i += 1,
            b'"' => open = if open.is_some() { None } else { Some(i) },
            b';' if open.is_none() => {
                while i < bytes.len() && bytes[i] != b'\n' {
                    i += 1;
                }
            }
            _ => {}
        }
        i += 1;
    }
    open
}

/// The grammar's rules in words; `None` for rules that only restate a token.
fn english(rule: Rule) -> Option<&'static str> {
    Some(match rule {
        Rule::section | Rule::header => "a section header `[…]`",
        Rule::tag => "a section name",
        Rule::attribute | Rule::attribute_name => "an attribute `name=value`",
        Rule::property | Rule::key | Rule::bare_key => "a property `name = value`",
        Rule::string
        | Rule::string_name
        | Rule::node_path_literal
        | Rule::number
        | Rule::keyword
        | Rule::array
        | Rule::dictionary
        | Rule::typed_array
        | Rule::typed_dictionary
        | Rule::object
        | Rule::constructor => "a value",
        Rule::pair => "a dictionary entry `key: value`",
        Rule::type_ref | Rule::type_name => "a type name",
        Rule::object_property => "a property `\"name\": value`",
        Rule::EOI => "the end of the file",
        _ => return None,
    })
}

/// The token at `pos` and its description.
fn found_token(text: &str, pos: usize) -> (Span, String) {
    let rest = text.get(pos..).unwrap_or("");
    let Some(first) = rest.chars().next() else {
        return (pos..pos, "the end of the file".into());
    };
    let len = if first.is_ascii_alphanumeric() || first == '_' {
        rest.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '.')).unwrap_or(rest.len())
    } else {
        first.len_utf8()
    };
    let desc = if first.is_ascii_graphic() {
        format!("`{}`", &rest[..len])
    } else if first == '\n' || first == '\r' {
        "the end of the line".into()
    } else {
        format!("character U+{:04X}", first as u32)
    };
    (pos..pos + len, desc)
}

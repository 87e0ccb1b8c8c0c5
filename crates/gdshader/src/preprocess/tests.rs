use super::*;
use crate::diag::Severity;
use std::collections::HashMap;
use std::time::Instant;

/// Includes read from memory.
#[derive(Default)]
struct MemLoader {
    files: HashMap<PathBuf, Vec<u8>>,
    /// Served for any other path (as the fuzz target serves the input itself).
    fallback: Option<Vec<u8>>,
}

impl Loader for MemLoader {
    fn load(&mut self, path: &Path) -> std::io::Result<Vec<u8>> {
        let found = self.files.get(path).or(self.fallback.as_ref());
        found.cloned().ok_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, "not found"))
    }
}

struct Run {
    db: SourceDb,
    out: Preprocessed,
    diags: Vec<Diagnostic>,
}

impl Run {
    fn codes(&self) -> Vec<&'static str> {
        self.diags.iter().map(|d| d.code).collect()
    }

    /// `(file name, line)` of the primary label of the first diagnostic with `code`.
    fn place(&self, code: &str) -> (String, usize) {
        let d = self.diags.iter().find(|d| d.code == code).unwrap_or_else(|| panic!("no {code} in {:?}", self.diags));
        let l = d.primary_label().expect("label");
        (self.db.name(l.file).to_string(), self.db.line_col(l.file, l.range.start).0)
    }

    /// The text of the primary label of the first diagnostic with `code`.
    fn label_text(&self, code: &str) -> String {
        let d = self.diags.iter().find(|d| d.code == code).unwrap_or_else(|| panic!("no {code} in {:?}", self.diags));
        let l = d.primary_label().expect("label");
        self.db.text(l.file)[l.range.clone()].to_string()
    }

    /// Where `needle` (first occurrence in the output) maps back to: file name and line.
    fn locate(&self, needle: &str) -> (String, usize) {
        let at = self.out.text.find(needle).unwrap_or_else(|| panic!("{needle:?} not in {:?}", self.out.text));
        let (file, range) = self.out.map.locate(at..at + needle.len()).expect("mapped");
        (self.db.name(file).to_string(), self.db.line_col(file, range.start).0)
    }
}

/// Preprocesses `files[0]` with the others readable as includes.
fn run_files(files: &[(&str, &[u8])]) -> Run {
    let mut db = SourceDb::new();
    let (name, text) = files[0];
    let root = db.add(name, String::from_utf8(text.to_vec()).expect("root is UTF-8"), Some(PathBuf::from(name)));
    let mut loader = MemLoader::default();
    for (name, text) in &files[1..] {
        loader.files.insert(PathBuf::from(name), text.to_vec());
    }
    let mut diags = Vec::new();
    let out = preprocess(&mut db, root, &mut loader, &mut diags);
    Run { db, out, diags }
}

/// Like the fuzz target: every include reads `src` itself.
fn run_self(src: &str) -> Run {
    let mut db = SourceDb::new();
    let root = db.add("fuzz.gdshader", src.to_string(), Some(PathBuf::from("fuzz.gdshader")));
    let mut loader = MemLoader { fallback: Some(src.as_bytes().to_vec()), ..MemLoader::default() };
    let mut diags = Vec::new();
    let out = preprocess(&mut db, root, &mut loader, &mut diags);
    Run { db, out, diags }
}

fn run(src: &str) -> Run {
    run_files(&[("main.gdshader", src.as_bytes())])
}

/// Each line as its tokens (words, and other characters one by one) separated by one space, so
/// expansions compare without caring about the spaces put around them.
fn squash(text: &str) -> String {
    let mut out = String::new();
    for (n, line) in text.trim_end_matches('\n').split('\n').enumerate() {
        if n > 0 {
            out.push('\n');
        }
        let mut toks: Vec<String> = Vec::new();
        let mut word = String::new();
        for c in line.chars() {
            if c.is_ascii_alphanumeric() || c == '_' || c == '.' {
                word.push(c);
                continue;
            }
            if !word.is_empty() {
                toks.push(std::mem::take(&mut word));
            }
            if !c.is_whitespace() {
                toks.push(c.to_string());
            }
        }
        if !word.is_empty() {
            toks.push(word);
        }
        out.push_str(&toks.join(" "));
    }
    out
}

/// Preprocesses `src`, which must give no diagnostics and keep its line count, and checks the
/// output against `expected` (token-wise, see [`squash`]).
#[track_caller]
fn check(src: &str, expected: &str) {
    let r = run(src);
    assert!(r.diags.is_empty(), "unexpected diagnostics: {:?}", r.diags);
    assert_eq!(r.out.text.matches('\n').count(), src.matches('\n').count(), "line count changed: {:?}", r.out.text);
    assert_eq!(squash(&r.out.text), squash(expected), "output: {:?}", r.out.text);
}

#[test]
fn text_without_macros_is_unchanged() {
    let src = "shader_type sky;\n/** A doc comment. */\nuniform vec3 c : source_color; // note\nvoid sky() {\n\tCOLOR = c * 2.0e1;\n}\n";
    let r = run(src);
    assert!(r.diags.is_empty());
    assert_eq!(r.out.text, src);
    assert_eq!(r.locate("COLOR"), ("main.gdshader".into(), 5));
}

#[test]
fn object_like_macros() {
    check("#define N 4\nfloat a[N];\n", "\nfloat a[4];");
    check("#define EMPTY\nx EMPTY y\n", "\nx y");
    check("#define A;\nA\n", "\n;");
    // Whole words only; not inside strings or comments; not after a digit.
    check("#define X 1\nXY X_ _X 2X X\n", "\nXY X_ _X 2X 1");
    check("#define A 1\nhint_enum(\"A\", \"B\") // A\n/* A */ A\n", "\nhint_enum(\"A\", \"B\") // A\n/* A */ 1");
}

#[test]
fn function_like_macros() {
    check("#define ADD(a, b) ((a) + (b))\nx = ADD(1, 2);\n", "\nx = ((1) + (2));");
    // Nested parentheses and commas inside them.
    check("#define F(a, b) a|b\nF(g(1, 2), (3, 4))\n", "\ng(1, 2)|(3, 4)");
    // Arguments spanning lines keep the line count (the line breaks follow the expansion).
    check("#define F(a, b) a+b\nF(1,\n  2) tail\nnext\n", "\n1+2\n tail\nnext");
    // Name without `(` is left alone; `(` on the next line still counts.
    check("#define F(x) [x]\nfloat F;\nF\n(1)\n", "\nfloat F;\n[1]");
    // Continuation lines in the body.
    check("#define F(a) a + \\\n  a\nF(2)\n", "\n\n2 + 2");
    // Godot's documented example.
    let src = "#define SAMPLE(p1, p2) long_call( \\\n p1, \\\n p2 \\\n)\nSAMPLE(x, y);\n";
    check(src, "\n\n\n\nlong_call( x, y );");
}

#[test]
fn token_pasting() {
    check(
        "#define SAMPLE(N) vec4 tex##N = texture(material ## N, UV)\nSAMPLE(0);\n",
        "\nvec4 tex0 = texture(material0, UV);",
    );
    // Operands of `##` are not expanded first; the pasted result is rescanned.
    check("#define AB 7\n#define CAT(a, b) a##b\n#define A x\nCAT(A, B)\n", "\n\n\n7");
    let r = run("#define BAD ## x\n#define BAD2(a) a ##\n");
    assert_eq!(r.codes(), vec!["E011", "E011"]);
}

#[test]
fn nested_macros_and_argument_pre_expansion() {
    check("#define ONE 1\n#define TWO (ONE + ONE)\nTWO\n", "\n\n(1 + 1)");
    check("#define SQ(x) ((x) * (x))\n#define N 3\nSQ(SQ(N))\n", "\n\n((((3) * (3))) * (((3) * (3))))");
    // A function-like macro named last in an expansion takes its arguments from the text after.
    check("#define F(x) <x>\n#define G F\nG(1)\n", "\n\n<1>");
    // Source map: the whole expansion maps to the outermost invocation.
    let r = run("#define ONE 1\n#define TWO (ONE + ONE)\nfloat x = TWO;\n");
    let at = r.out.text.find('(').unwrap();
    let (file, range) = r.out.map.locate(at..at + 1).unwrap();
    assert_eq!(&r.db.text(file)[range], "TWO");
    let r = run("#define F(a, b) a\nF(1,\n2);\n");
    let at = r.out.text.find('1').unwrap();
    let (file, range) = r.out.map.locate(at..at + 1).unwrap();
    assert_eq!(&r.db.text(file)[range], "F(1,\n2)");
}

#[test]
fn self_reference_terminates() {
    check("#define A A\nA\n", "\nA");
    check("#define A B\n#define B A\nA B\n", "\n\nA B");
    check("#define f(x) x + f(x)\nf(1)\n", "\n1 + f(1)");
    check("#define f(x) g(x)\n#define g(x) f(x)\nf(1)\n", "\n\nf(1)");
    // A name in an argument is expanded (the macro is not active while its arguments expand).
    check("#define f(x) [x]\nf(f(1))\n", "\n[[1]]");
}

#[test]
fn exponential_growth_hits_the_limit_quickly() {
    let mut src = String::new();
    for i in 0..40 {
        src.push_str(&format!("#define M{i} M{} M{}\n", i + 1, i + 1));
    }
    src.push_str("#define M40 x\nM0\nafter\n");
    let start = Instant::now();
    let r = run(&src);
    assert!(start.elapsed().as_secs() < 20);
    assert_eq!(r.codes(), vec!["E017"]);
    assert_eq!(r.label_text("E017"), "M0");
    assert!(r.out.text.ends_with("M0\nafter\n"), "{}", &r.out.text[r.out.text.len().saturating_sub(40)..]);

    // Growth that produces nothing is bounded by the work limit.
    let mut src = String::new();
    for i in 0..40 {
        src.push_str(&format!("#define E{i} E{} E{}\n", i + 1, i + 1));
    }
    src.push_str("#define E40\nE0\n");
    let r = run(&src);
    assert_eq!(r.codes(), vec!["E017"]);

    // Doubling through arguments.
    let src = format!("#define D(x) x x\n{}1{}\n", "D(".repeat(40), ")".repeat(40));
    let r = run(&src);
    assert_eq!(r.codes(), vec!["E017"]);

    // Deep nesting of invocations.
    let src = format!("#define I(x) x\n{}1{}\n", "I(".repeat(5000), ")".repeat(5000));
    let r = run(&src);
    assert_eq!(r.codes(), vec!["E017"]);
    // A long chain of distinct macros.
    let mut src = String::new();
    for i in 0..1000 {
        src.push_str(&format!("#define C{i} C{}\n", i + 1));
    }
    src.push_str("C0\n");
    assert_eq!(run(&src).codes(), vec!["E017"]);
}

#[test]
fn conditionals() {
    let src = "#define A 2\n#if A * 2 == 4 && defined(A)\nyes1\n#else\nno1\n#endif\n\
               #if !defined B\nyes2\n#elif 1\nno2\n#endif\n\
               #if A == 1\nno3\n#elif A == 2\nyes3\n#elif A == 2\nno3b\n#else\nno3c\n#endif\n\
               #if 0\n#if 1\nno4\n#else\nno4b\n#endif\n#elif (1 << 3) > 7\nyes4\n#endif\n\
               #if CURRENT_RENDERER == RENDERER_FORWARD_PLUS && RENDERER_MOBILE == 1 && !RENDERER_COMPATIBILITY\nyes5\n#endif\n\
               #if true\nyes6\n#endif\n";
    let r = run(src);
    assert!(r.diags.is_empty(), "{:?}", r.diags);
    let out = r.out.text;
    for line in out.lines().filter(|l| !l.is_empty()) {
        assert!(line.starts_with("yes"), "{line} in {out:?}");
    }
    assert_eq!(out.lines().filter(|l| !l.is_empty()).count(), 6);
}

#[test]
fn ifdef_and_ifndef() {
    let out = run("#define A\n#ifdef A\na\n#endif\n#ifndef A\nnot_a\n#endif\n#ifdef B\nb\n#else\nnot_b\n#endif\n#ifndef B\nnot_b2\n#endif\n").out.text;
    assert_eq!(out.split_whitespace().collect::<Vec<_>>(), vec!["a", "not_b", "not_b2"]);
    let r = run("#ifdef\n#endif\n#ifdef A B\n#endif\n");
    assert_eq!(r.codes(), vec!["E011", "E011"]);
}

#[test]
fn skipped_branches_leave_empty_lines() {
    let src = "a\n#if 0\nb\nc /* x\n#endif\n*/ d\n#endif\ne\n";
    let r = run(src);
    assert!(r.diags.is_empty(), "{:?}", r.diags);
    assert_eq!(r.out.text, "a\n\n\n\n\n\n\ne\n");
    assert_eq!(r.locate("e"), ("main.gdshader".into(), 8));
}

#[test]
fn condition_errors() {
    let r = run("#if FOO > 1\nx\n#endif\ny\n");
    assert_eq!(r.codes(), vec!["E015"]);
    assert!(r.diags[0].message.contains("`FOO`"));
    assert_eq!(r.label_text("E015"), "FOO");
    assert_eq!(squash(&r.out.text), squash("\n\n\ny"));
    assert_eq!(run("#if 1 / 0\n#endif\n").codes(), vec!["E015"]);
    assert_eq!(run("#if\n#endif\n").codes(), vec!["E015"]);
    assert_eq!(run("#if defined(\n#endif\n").codes(), vec!["E015"]);
    assert_eq!(run("#if defined(A B)\n#endif\n").codes(), vec!["E015"]);
    // Not evaluated in a branch already taken, or in a skipped region.
    assert!(run("#if 1\n#elif 1/0\n#endif\n#if 0\n#if FOO\n#endif\n#endif\n").diags.is_empty());
    // Macro arguments in a condition.
    assert!(
        run("#define MAX(a, b) ((a) > (b) ? (a) : (b))\n#define SUM(a, b) (a + b)\n#if SUM(1, 2) == 3\n#endif\n")
            .diags
            .is_empty()
    );
}

#[test]
fn unbalanced_conditionals() {
    let r = run("#if 1\nx\n");
    assert_eq!(r.codes(), vec!["E012"]);
    assert_eq!(r.place("E012"), ("main.gdshader".into(), 1));
    assert!(r.diags[0].notes[0].contains("#endif"));
    assert_eq!(run("#endif\n").codes(), vec!["E012"]);
    assert_eq!(run("#else\n").codes(), vec!["E012"]);
    assert_eq!(run("#elif 1\n").codes(), vec!["E012"]);
    assert_eq!(run("#if 1\n#else\n#else\n#endif\n").codes(), vec!["E012"]);
    assert_eq!(run("#if 1\n#else\n#elif 1\n#endif\n").codes(), vec!["E012"]);
    assert_eq!(run("#ifdef A\n#ifndef B\n").codes(), vec!["E012", "E012"]);
    assert_eq!(run("#if 1\n#endif junk\n").codes(), vec!["E011"]);
    // A comment after `#endif` is fine.
    assert!(run("#if 1\n#endif // done\n#if 0\n#endif /* done */\n").diags.is_empty());
}

#[test]
fn redefinition_and_undef() {
    let r = run("#define A 1\n#define A 1\n");
    assert_eq!(r.codes(), vec!["E013"]);
    assert_eq!(r.place("E013"), ("main.gdshader".into(), 2));
    assert_eq!(r.diags[0].labels.len(), 2);
    assert_eq!(run("#define CURRENT_RENDERER 0\n").codes(), vec!["E013"]);
    check("#define A 1\n#undef A\n#define A 2\nA\n#undef NEVER_DEFINED\n", "\n\n\n2");
    assert_eq!(run("#undef CURRENT_RENDERER\n").codes(), vec!["E011"]);
    assert_eq!(run("#undef\n#undef A B\n").codes(), vec!["E011", "E011"]);
    assert_eq!(run("#define\n#define 1A\n#define A+B 1\n#define F() 1\n#define G(a b) 1\n").codes(), vec!["E011"; 5]);
}

#[test]
fn argument_errors() {
    let r = run("#define F(a, b) a\nF(1)\nF(1, 2, 3)\nF(1, )\nok\n");
    assert_eq!(r.codes(), vec!["E014"; 3]);
    assert!(r.diags[0].message.contains("takes 2 arguments but 1 was given"), "{}", r.diags[0].message);
    assert_eq!(r.label_text("E014"), "F(1)");
    assert_eq!(squash(&r.out.text), squash("\n\n\n\nok"));
    let r = run("#define F(a) a\nF(1\nmore\n");
    assert_eq!(r.codes(), vec!["E014"]);
    assert_eq!(r.label_text("E014"), "F");
    let r = run("#define F(a) a\nF(1,\n#define X\n2)\n");
    assert!(r.codes().contains(&"E014"));
}

#[test]
fn comments_hide_directives_and_macros() {
    let src = "#define A 1\n/* #define A 2\n#error no\n A */\n// #error no\nA\n/** doc A */\n";
    let r = run(src);
    assert!(r.diags.is_empty(), "{:?}", r.diags);
    assert_eq!(r.out.text, "\n/* #define A 2\n#error no\n A */\n// #error no\n 1 \n/** doc A */\n");
    // A comment on a directive line is ignored; one that continues onto later lines ends the
    // directive (as Godot strips comments first).
    let r = run("#define B 2 // two\n#define C 3 /* three\n   still */ B C\n");
    assert!(r.diags.is_empty(), "{:?}", r.diags);
    assert_eq!(squash(&r.out.text), squash("\n\n2 3"));
    // A comment before `#` on the same line does not stop it being a directive.
    let r = run("/* x */ #define D 4\nD\n");
    assert!(r.diags.is_empty(), "{:?}", r.diags);
    assert_eq!(squash(&r.out.text), squash("/* x */\n4"));
}

#[test]
fn unclosed_comment_is_an_error() {
    let r = run("a\n/* never closed\n#define A\nA\n");
    assert_eq!(r.codes(), vec!["E018"]);
    assert_eq!(r.diags[0].severity, Severity::Error);
    assert_eq!(r.place("E018"), ("main.gdshader".into(), 2));
    // The text still runs to the end of the file.
    assert_eq!(r.out.text, "a\n/* never closed\n#define A\nA\n");
    assert_eq!(run("#define X 1 /* open\n").codes(), vec!["E018"]);
    assert_eq!(run("#if 0\n/* open\n").codes(), vec!["E018", "E012"]);
    // A `*/` with no `/*` is the same error in Godot.
    let r = run("a */ b\n/* c */ d */\n");
    assert_eq!(r.codes(), vec!["E018", "E018"]);
    assert_eq!(r.place("E018"), ("main.gdshader".into(), 1));
}

#[test]
fn error_and_unknown_directives() {
    let r = run("#if 1\n#error LOD exceeds MAX_LOD\n#endif\n#if 0\n#error not reached\n#endif\n");
    assert_eq!(r.codes(), vec!["E010"]);
    assert_eq!(r.diags[0].message, "LOD exceeds MAX_LOD");
    assert_eq!(r.place("E010"), ("main.gdshader".into(), 2));
    let r = run("#elifdef A\n#line 3\n#version 450\n#\n#foo\n");
    assert_eq!(r.codes(), vec!["E011"; 5]);
    assert!(r.diags[0].notes[0].contains("#elif defined"));
    assert_eq!(r.out.text, "\n\n\n\n\n");
    // Unknown directives inside skipped branches are not reported.
    assert!(run("#if 0\n#version 450\n#endif\n").diags.is_empty());
    // Godot wants the name right after `#` (but the directive still acts).
    let r = run("#  define A 1\nA\n#if 0\n# if 1\n# endif\n #  else\nx\n#endif\n");
    assert_eq!(r.codes(), vec!["E011", "E011"]);
    assert_eq!(squash(&r.out.text), squash("\n1\n\n\n\n\nx\n"));
    // `#` after code on a line is an error, and the rest of the line is dropped.
    let r = run("const float K = 1.0; #define A 1\nA\n\"#\" // #\n");
    assert_eq!(r.codes(), vec!["E011"]);
    assert_eq!(r.out.text, "const float K = 1.0; \nA\n\"#\" // #\n");
    // In a skipped branch it is not looked at.
    assert!(run("#if 0\na # b\n#endif\n").diags.is_empty());
}

#[test]
fn pragmas() {
    let r = run("#define A 1\n#pragma disable_preprocessor\nA\n#if\n#define\n");
    assert!(r.diags.is_empty(), "{:?}", r.diags);
    assert_eq!(r.out.text, "\n\nA\n#if\n#define\n");
    let r = run("#pragma once\nx\n");
    assert_eq!(r.codes(), vec!["E011"]);
    assert_eq!(r.label_text("E011"), "once");
    assert_eq!(r.out.text, "\nx\n");
    assert_eq!(run("#pragma\n").codes(), vec!["E011"]);
}

#[test]
fn includes() {
    let r = run_files(&[
        ("shaders/main.gdshader", b"#include \"inc/a.gdshaderinc\"\nfloat m = A + B;\n"),
        ("shaders/inc/a.gdshaderinc", b"#define A 1\n#include \"../common/b.gdshaderinc\"\nfloat a;\n"),
        ("shaders/common/b.gdshaderinc", b"#define B 2\nfloat b;\n"),
    ]);
    assert!(r.diags.is_empty(), "{:?}", r.diags);
    // Each include's text replaces its directive line, whose line break follows it.
    assert_eq!(r.out.text.trim_end(), "\n\nfloat b;\n\nfloat a;\n\nfloat m =  1  +  2 ;");
    assert_eq!(
        r.out.includes,
        vec![PathBuf::from("shaders/inc/a.gdshaderinc"), PathBuf::from("shaders/common/b.gdshaderinc")]
    );
    assert_eq!(r.locate("float b"), ("shaders/common/b.gdshaderinc".into(), 2));
    assert_eq!(r.locate("float a"), ("shaders/inc/a.gdshaderinc".into(), 3));
    assert_eq!(r.locate("float m"), ("shaders/main.gdshader".into(), 2));

    // A file is included once; later includes of it are skipped (as in Godot).
    let r = run_files(&[
        ("main.gdshader", b"#include \"a.gdshaderinc\"\n#include \"./a.gdshaderinc\"\n"),
        ("a.gdshaderinc", b"#define A 1\nfloat a;\n"),
    ]);
    assert!(r.diags.is_empty(), "{:?}", r.diags);
    assert_eq!(r.out.text.matches("float a").count(), 1);

    // res:// paths resolve against the directory holding project.godot.
    let r = run_files(&[
        ("proj/shaders/sky/main.gdshader", b"#include \"res://lib/x.gdshaderinc\"\n"),
        ("proj/project.godot", b"config_version=5\n"),
        ("proj/lib/x.gdshaderinc", b"float x;\n"),
    ]);
    assert!(r.diags.is_empty(), "{:?}", r.diags);
    assert_eq!(r.out.includes, vec![PathBuf::from("proj/lib/x.gdshaderinc")]);
    // Without project.godot, against the root file's directory.
    let r = run_files(&[
        ("sky/main.gdshader", b"#include \"res://x.gdshaderinc\"\n"),
        ("sky/x.gdshaderinc", b"float x;\n"),
    ]);
    assert!(r.diags.is_empty(), "{:?}", r.diags);
}

/// Includes are confined to the project (or, without one, the root file's folder), as Godot
/// reads them as `res://` resources: a path outside is refused unread, whatever its spelling.
#[test]
fn includes_outside_the_project_are_refused_unread() {
    let secret: &[u8] = b"SECRET-CONTENT\n";
    for written in ["/etc/passwd", "res://../outside.txt", "../outside.txt", "res://lib/../../outside.txt"] {
        let main = format!("#include \"{written}\"\n");
        let r = run_files(&[
            ("proj/shaders/main.gdshader", main.as_bytes()),
            ("proj/project.godot", b"config_version=5\n"),
            ("proj/outside.txt", b"float inside;\n"),
            ("outside.txt", secret),
            ("/etc/passwd", secret),
        ]);
        let shown: String = r.diags.iter().map(|d| format!("{} {:?}", d.message, d.notes)).collect();
        // `../outside.txt` from proj/shaders is proj/outside.txt: inside, and read.
        if written == "../outside.txt" {
            assert!(r.diags.is_empty(), "{written}: {shown}");
            continue;
        }
        assert_eq!(r.codes(), vec!["E016"], "{written}: {shown}");
        assert!(shown.contains("outside the project"), "{written}: {shown}");
        assert!(!r.out.text.contains("SECRET") && !shown.contains("SECRET"), "{written}: nothing of it is shown");
        assert!(r.out.includes.is_empty(), "{written}: not read");
    }
    // Without project.godot, the root file's folder bounds them.
    let r = run_files(&[("sky/main.gdshader", b"#include \"../x.gdshaderinc\"\n"), ("x.gdshaderinc", b"float x;\n")]);
    assert_eq!(r.codes(), vec!["E016"]);
}

#[test]
fn include_errors() {
    let r = run("a\n#include \"missing.gdshaderinc\"\n");
    assert_eq!(r.codes(), vec!["E016"]);
    assert_eq!(r.place("E016"), ("main.gdshader".into(), 2));
    assert_eq!(r.label_text("E016"), "\"missing.gdshaderinc\"");
    assert!(r.diags[0].message.contains("does not exist"));
    assert_eq!(run("#include\n#include missing\n#include \"\"\n").codes(), vec!["E011"; 3]);

    // Cycle.
    let r = run_files(&[
        ("main.gdshader", b"#include \"a.gdshaderinc\"\n"),
        ("a.gdshaderinc", b"#include \"b.gdshaderinc\"\n"),
        ("b.gdshaderinc", b"\n#include \"a.gdshaderinc\"\n"),
    ]);
    assert_eq!(r.codes(), vec!["E016"]);
    // At the include that enters the cycle, with the one that closes it as a second label.
    assert_eq!(r.place("E016"), ("main.gdshader".into(), 1));
    assert_eq!(r.label_text("E016"), "\"a.gdshaderinc\"");
    let closing = &r.diags[0].labels[1];
    assert_eq!((r.db.name(closing.file), r.db.line_col(closing.file, closing.range.start).0), ("b.gdshaderinc", 2));
    assert!(r.diags[0].message.contains("a.gdshaderinc → b.gdshaderinc → a.gdshaderinc"), "{}", r.diags[0].message);
    let r = run_files(&[("main.gdshader", b"#include \"main.gdshader\"\n")]);
    assert_eq!(r.codes(), vec!["E016"]);

    // Depth: 25 nested includes are fine, 26 are not.
    let chain = |n: usize| {
        let mut files: Vec<(String, Vec<u8>)> =
            vec![("main.gdshader".into(), b"#include \"f1.gdshaderinc\"\n".to_vec())];
        for i in 1..=n {
            let body = if i < n { format!("#include \"f{}.gdshaderinc\"\n", i + 1) } else { "float deepest;\n".into() };
            files.push((format!("f{i}.gdshaderinc"), body.into_bytes()));
        }
        let refs: Vec<(&str, &[u8])> = files.iter().map(|(n, b)| (n.as_str(), b.as_slice())).collect();
        run_files(&refs)
    };
    let r = chain(25);
    assert!(r.diags.is_empty(), "{:?}", r.diags);
    assert!(r.out.text.contains("float deepest;"));
    let r = chain(26);
    assert_eq!(r.codes(), vec!["E016"]);
    assert_eq!(r.place("E016"), ("f25.gdshaderinc".into(), 1));

    // Invalid UTF-8 in an include.
    let r = run_files(&[
        ("main.gdshader", b"\n#include \"bad.gdshaderinc\"\n"),
        ("bad.gdshaderinc", b"ok\nbad \xff here\n"),
    ]);
    assert_eq!(r.codes(), vec!["E001"]);
    assert_eq!(r.place("E001"), ("bad.gdshaderinc".into(), 2));
    let l = &r.diags[0].labels[1];
    assert!(!l.primary);
    assert_eq!(r.db.line_col(l.file, l.range.start).0, 2);

    // Conditionals do not span files.
    let r = run_files(&[("main.gdshader", b"#if 1\n#include \"a.gdshaderinc\"\n"), ("a.gdshaderinc", b"#endif\n")]);
    assert_eq!(r.codes(), vec!["E012", "E012"]);
}

#[test]
fn includes_that_fan_out_are_bounded() {
    // Every path reads the shader itself: each level names new paths (`d1/d1/x`, `d1/d2/x`,
    // ...), so only the limit on included files stops it.
    let src = "#include \"d1/x\"\n#include \"d2/x\"\n#include \"d3/x\"\nfloat f;\n";
    let start = Instant::now();
    let r = run_self(src);
    eprintln!("fan-out: {:?}", start.elapsed());
    assert_eq!(r.out.includes.len(), MAX_INCLUDED_FILES);
    assert!(r.diags.iter().all(|d| d.code == "E016"), "{:?}", r.diags);
    assert!(r.diags.iter().any(|d| d.message.contains("more than 1024 files")));
}

#[test]
fn source_map_after_include_points_into_the_right_file() {
    let r = run_files(&[
        ("main.gdshader", b"shader_type sky;\n#include \"lib.gdshaderinc\"\nvoid sky() {\n\tCOLOR = @;\n}\n"),
        ("lib.gdshaderinc", b"// helpers\nfloat helper() {\n\treturn 1.0;\n}\n"),
    ]);
    assert!(r.diags.is_empty());
    assert_eq!(r.locate("@"), ("main.gdshader".into(), 4));
    assert_eq!(r.locate("return"), ("lib.gdshaderinc".into(), 3));
    assert_eq!(r.locate("// helpers"), ("lib.gdshaderinc".into(), 1));
    // The same through a macro defined in the include.
    let r = run_files(&[
        ("main.gdshader", b"#include \"lib.gdshaderinc\"\n\nfloat x = BAD;\n"),
        ("lib.gdshaderinc", b"#define BAD @\n"),
    ]);
    assert_eq!(r.locate("@"), ("main.gdshader".into(), 3));
}

#[test]
fn control_characters_in_directives() {
    let r = run("#define A 1\0\nA\n");
    assert_eq!(r.codes(), vec!["E002"]);
}

#[test]
fn byte_order_mark_is_dropped() {
    let r = run("\u{FEFF}#define A 1\nA\n");
    assert!(r.diags.is_empty(), "{:?}", r.diags);
    assert_eq!(squash(&r.out.text), "\n1");
}

#[test]
fn crlf_line_endings() {
    let r = run("#define A 1\r\n#if A\r\nx = A;\r\n#endif\r\n");
    assert!(r.diags.is_empty(), "{:?}", r.diags);
    assert_eq!(squash(&r.out.text), squash("\n\nx = 1;"));
}

#[test]
fn large_file_is_processed() {
    let mut src = String::from("shader_type sky;\n#define SCALE 2.0\n#define MIX(a, b) mix(a, b, 0.5)\n");
    let mut i = 0;
    while src.len() < 2 << 20 {
        src.push_str(&format!(
            "/* block {i} */\nfloat f{i}(float x) {{\n\t// line comment\n\treturn MIX(x * SCALE, x) + float({i}) + sin(x * 0.25);\n}}\n"
        ));
        if i % 50 == 0 {
            src.push_str(
                "#if CURRENT_RENDERER == RENDERER_FORWARD_PLUS\nconst int ok = 1;\n#else\nconst int no = 0;\n#endif\n",
            );
        }
        i += 1;
    }
    let start = Instant::now();
    let r = run(&src);
    let elapsed = start.elapsed();
    eprintln!("2 MB file: {elapsed:?} ({} bytes out)", r.out.text.len());
    assert!(r.diags.is_empty());
    assert_eq!(r.out.text.matches('\n').count(), src.matches('\n').count());
    // Plain text, no directives or macros: byte-identical.
    let plain: String = src.lines().filter(|l| !l.starts_with('#')).map(|l| l.replace("MIX", "mix3") + "\n").collect();
    let start = Instant::now();
    let r = run(&plain);
    eprintln!("2 MB plain file: {:?}", start.elapsed());
    assert!(r.out.text == plain);
}

/// Random mixtures of directive and macro fragments: nothing may panic or hang.
#[test]
fn random_inputs_do_not_panic() {
    const PIECES: &[&str] = &[
        "#define ",
        "#undef ",
        "#if ",
        "#ifdef ",
        "#ifndef ",
        "#elif ",
        "#else",
        "#endif",
        "#include \"",
        "#error ",
        "#pragma ",
        "\n",
        "\\\n",
        " ",
        "A",
        "B",
        "F",
        "G",
        "(",
        ")",
        ",",
        "\"",
        "/*",
        "*/",
        "//",
        "##",
        "#",
        "defined",
        "1",
        "0x",
        "/",
        "&&",
        "||",
        "!",
        "<<",
        "-",
        "é",
        "\0",
        "\r\n",
        "F(",
        "A(x) x x",
        "B(y) F(y) y",
        "G G",
        "a.gdshaderinc",
    ];
    let mut seed: u64 = 0x2545_F491_4F6C_DD1D;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    for _ in 0..3000 {
        let n = (next() % 60) as usize;
        let src: String = (0..n).map(|_| PIECES[(next() % PIECES.len() as u64) as usize]).collect();
        let inc: String = (0..n).map(|_| PIECES[(next() % PIECES.len() as u64) as usize]).collect();
        let r = if next() % 2 == 0 {
            run_self(&src)
        } else {
            run_files(&[("main.gdshader", src.as_bytes()), ("a.gdshaderinc", inc.as_bytes())])
        };
        // Every mapped offset lies inside its file.
        for at in 0..r.out.text.len() {
            if let Some((file, range)) = r.out.map.locate(at..at + 1) {
                assert!(range.end <= r.db.text(file).len().max(1), "{src:?}");
            }
        }
        for d in &r.diags {
            for l in &d.labels {
                assert!(l.range.start <= l.range.end && l.range.end <= r.db.text(l.file).len() + 3, "{d:?} in {src:?}");
            }
        }
    }
}

/// Longer random run: `cargo test --release stress_random_inputs -- --ignored` (SEED=n varies it).
#[test]
#[ignore]
fn stress_random_inputs() {
    const PIECES: &[&str] = &[
        "#define ",
        "#undef ",
        "#if ",
        "#ifdef ",
        "#ifndef ",
        "#elif ",
        "#else",
        "#endif",
        "#include \"",
        "#error ",
        "#pragma ",
        "\n",
        "\\\n",
        " ",
        "A",
        "B",
        "F",
        "G",
        "(",
        ")",
        ",",
        "\"",
        "/*",
        "*/",
        "//",
        "##",
        "#",
        "defined",
        "1",
        "0x",
        "/",
        "&&",
        "||",
        "!",
        "<<",
        "-",
        "é",
        "\0",
        "\r\n",
        "F(",
        "A(x) x x",
        "B(y) F(y) y",
        "G G",
        "a.gdshaderinc",
        "b.gdshaderinc\"\n",
        "#define A(x) x x\n",
        "#define B A(A(A(A(A(A(1))))))\n",
        "#define F(a, b) a##b F(a, b)\n",
        "#include \"a.gdshaderinc\"\n",
        "#include \"b.gdshaderinc\"\n",
        "#pragma disable_preprocessor\n",
        "A(",
        "B",
        "CURRENT_RENDERER",
        "res://",
        "../",
    ];
    let mut seed: u64 = std::env::var("SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(0x9E37_79B9_7F4A_7C15);
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    let mut worst = std::time::Duration::ZERO;
    let mut worst_src = String::new();
    for iter in 0..200_000 {
        let n = (next() % 120) as usize;
        let mut make = |n: usize| -> String {
            (0..n)
                .map(|_| {
                    if next() % 10 == 0 {
                        ((next() % 127) as u8 as char).to_string()
                    } else {
                        PIECES[(next() % PIECES.len() as u64) as usize].to_string()
                    }
                })
                .collect()
        };
        let src = make(n);
        let a = make(n / 2);
        let mut b = make(n / 3).into_bytes();
        if iter % 7 == 0 {
            b.push(0xff);
        }
        let start = Instant::now();
        let r = if iter % 2 == 0 {
            run_self(&src)
        } else {
            run_files(&[("main.gdshader", src.as_bytes()), ("a.gdshaderinc", a.as_bytes()), ("b.gdshaderinc", &b)])
        };
        let el = start.elapsed();
        if el > worst {
            worst = el;
            worst_src = src.clone();
        }
        for d in &r.diags {
            for l in &d.labels {
                assert!(l.range.start <= l.range.end && l.range.end <= r.db.text(l.file).len() + 3, "{d:?} in {src:?}");
            }
            let _ = crate::diag::render_human(&r.db, std::slice::from_ref(d), false);
        }
    }
    eprintln!("worst {worst:?} for {worst_src:?}");
}

#[test]
fn dense_macro_use_stays_within_the_limits() {
    let mut src = String::from("#define SCALE 2.0\n#define MIX(a, b) mix(a, b, 0.5)\n#define SQ(x) ((x) * (x))\n");
    while src.len() < 512 << 10 {
        src.push_str("v = MIX(SQ(SCALE), SQ(MIX(SCALE, 1.0)));\n");
    }
    let r = run(&src);
    assert!(r.diags.is_empty(), "{:?}", r.diags);
    // The inner `MIX` is copied by both uses of `x` in `SQ`.
    assert_eq!(r.out.text.matches("mix(").count(), 3 * (src.lines().count() - 3));
}

/// Inputs built to be slow all stop with one error (each takes well under a second in release).
#[test]
fn hostile_inputs_stop_quickly() {
    let n = 1 << 16;
    let cases = [
        format!("#define F(x) x\n{}\n", "F(".repeat(n)),
        format!("#define F(x) x\n#define G F\n{}\n", "G(".repeat(n)),
        format!(
            "#define F(x) x x x x x x x x x x x x x x x x\n{}\n",
            "F(".repeat(10) + &"a ".repeat(n) + &")".repeat(10)
        ),
    ];
    for (i, src) in cases.iter().enumerate() {
        let start = Instant::now();
        let r = run(src);
        eprintln!("case {i}: {:?}", start.elapsed());
        assert_eq!(r.diags.len(), 1, "case {i}: {:?}", r.diags);
    }
    // An unclosed list inside closed ones: only the unclosed one is an error.
    let r = run(&format!("#define F(x) <x>\n{}\n", "F( F(x) ".repeat(1000)));
    assert_eq!(r.codes(), vec!["E014"]);
    assert_eq!(r.out.text.matches("<x>").count(), 1000);
}

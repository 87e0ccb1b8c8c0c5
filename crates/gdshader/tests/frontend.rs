//! The front end's suite: every test shader of `tests/shaders` checked with Godot's rules.
//!
//! Test shaders live in `tests/shaders/{valid,invalid}`. Each invalid shader names, in a
//! `// expect: LINE:COL what` comment written when the shader was written (from Godot's rules,
//! not from gdsky's output), where its error is; the test holds gdsky's primary label to that
//! line, and snapshots the whole rendered diagnostic for review.

use gdshader::diag::render_human;
use std::path::{Path, PathBuf};

/// The workspace root, the tests' working folder: paths in diagnostics are as a user at the
/// root types them (`tests/shaders/...`).
fn at_root() -> &'static Path {
    let root = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."));
    // Every test sets the same folder, so their order does not matter.
    std::env::set_current_dir(root).expect("the workspace root");
    root
}

/// The path of a test file relative to the package root, as a user would type it.
fn relative(path: &Path) -> PathBuf {
    let root = std::fs::canonicalize(at_root()).expect("the workspace root");
    let path = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    path.strip_prefix(&root).unwrap_or(&path).to_path_buf()
}

/// The `// expect: LINE:COL` line of a test shader (line 1 for an empty file, which cannot
/// say it).
fn expected_line(path: &Path) -> usize {
    let bytes = std::fs::read(path).expect("test shader is readable");
    if bytes.is_empty() {
        return 1;
    }
    let text = String::from_utf8_lossy(&bytes);
    let at = text.find("// expect: ").unwrap_or_else(|| panic!("{} has no `// expect:` line", path.display()));
    let rest = &text[at + "// expect: ".len()..];
    let line = rest.split(':').next().unwrap_or("");
    line.trim().parse().unwrap_or_else(|_| panic!("{}: bad expect line", path.display()))
}

/// The file an invalid shader's error is reported in: the shader itself, or the include named
/// by `(in PATH)` on its expect line.
fn expected_file(path: &Path) -> String {
    let text = String::from_utf8_lossy(&std::fs::read(path).expect("readable")).into_owned();
    let expect = text.lines().find(|l| l.contains("// expect: ")).unwrap_or("");
    match expect.split_once("(in ").and_then(|(_, rest)| rest.split_once(')')) {
        Some((include, _)) => include.to_string(),
        None => relative(path).display().to_string(),
    }
}

#[test]
fn invalid_shaders_fail_where_expected() {
    let mut wrong = Vec::new();
    insta::glob!(concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/shaders"), "invalid/*.gdshader", |path| {
        let rel = relative(path);
        let output = gdshader::check_file(&rel).expect("readable");
        let rendered = render_human(&output.db, &output.diagnostics, false);
        match output.diagnostics.iter().find(|d| d.is_error()) {
            None => wrong.push(format!("{} was accepted", rel.display())),
            Some(error) => {
                let label = error.primary_label().expect("an error has a label");
                let (line, _) = output.db.line_col(label.file, label.range.start);
                // Errors inside an included file are reported there; the expect line names the
                // line in the file that holds the problem.
                let expected = expected_line(path);
                let file = output.db.name(label.file);
                let expected_file = expected_file(path);
                if line != expected || !file.ends_with(&expected_file) {
                    wrong.push(format!(
                        "{}: expected {expected_file}:{expected}, reported {file}:{line}:\n{rendered}",
                        rel.display()
                    ));
                }
            }
        }
        insta::assert_snapshot!(rendered);
    });
    assert!(wrong.is_empty(), "{} invalid shaders misreported:\n{}", wrong.len(), wrong.join("\n"));
}

#[test]
fn valid_shaders_are_accepted() {
    insta::glob!(concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/shaders"), "valid/*.gdshader", |path| {
        let rel = relative(path);
        let output = gdshader::check_file(&rel).expect("readable");
        assert!(
            !output.has_errors(),
            "{} was rejected:\n{}",
            rel.display(),
            render_human(&output.db, &output.diagnostics, false)
        );
        assert!(output.shader.is_some());
    });
}

#[test]
fn freeman_sky_uniforms_as_the_checker_sees_them() {
    at_root();
    let output = gdshader::check_file(Path::new("fixtures/freeman_sky.gdshader")).expect("fixture is readable");
    assert!(output.diagnostics.is_empty(), "{}", render_human(&output.db, &output.diagnostics, false));
    let shader = output.shader.expect("valid");
    // Every `uniform` declaration of the fixture starts a line; count them independently.
    let text = std::fs::read_to_string("fixtures/freeman_sky.gdshader").expect("readable");
    let declared = text.lines().filter(|l| l.starts_with("uniform ")).count();
    assert_eq!(declared, 22);
    assert_eq!(shader.uniforms.len(), declared);
    let view: Vec<serde_json::Value> = shader
        .uniforms
        .iter()
        .map(|u| {
            serde_json::json!({
                "name": u.name,
                "type": u.type_name,
                "default": u.default_text,
                "hints": u.hints.iter().map(|h| if h.args.is_empty() { h.name.clone() } else { format!("{}({})", h.name, h.args.join(", ")) }).collect::<Vec<_>>(),
                "group": u.group.join("."),
                "doc": u.doc,
            })
        })
        .collect();
    insta::assert_yaml_snapshot!(view);
}

#[test]
fn a_two_megabyte_file_gets_its_error_on_the_last_line() {
    let mut text = String::from("shader_type sky;\n");
    let mut n = 0;
    while text.len() < 2 << 20 {
        text.push_str(&format!("float f{n}(float x) {{ return x * 2.0 + {n}.0; }}\n"));
        n += 1;
    }
    text.push_str("void sky() { COLOR = vec3(f0(1.0)) }\n");
    let lines = text.lines().count();
    let output = gdshader::check_source("big.gdshader", text.into_bytes(), None, &mut gdshader::FsLoader);
    let error = output.diagnostics.iter().find(|d| d.is_error()).expect("the missing `;` is found");
    let label = error.primary_label().expect("labelled");
    assert_eq!(output.db.line_col(label.file, label.range.start).0, lines);
}

//! End-to-end tests of the front end through the `gdsky` library facade and binary.
//!
//! Test shaders live in `tests/shaders/{valid,invalid}`. Each invalid shader names, in a
//! `// expect: LINE:COL what` comment written when the shader was written (from Godot's rules,
//! not from gdsky's output), where its error is; the test holds gdsky's primary label to that
//! line, and snapshots the whole rendered diagnostic for review.

use gdsky::frontend::diag::{render_human, render_json};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The path of a test file relative to the package root, as a user would type it.
fn relative(path: &Path) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    path.strip_prefix(root).unwrap_or(path).to_path_buf()
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
    insta::glob!("shaders/invalid/*.gdshader", |path| {
        let rel = relative(path);
        let output = gdsky::check_file(&rel).expect("readable");
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
    insta::glob!("shaders/valid/*.gdshader", |path| {
        let rel = relative(path);
        let output = gdsky::check_file(&rel).expect("readable");
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
    let output = gdsky::check_file(Path::new("fixtures/freeman_sky.gdshader")).expect("fixture is readable");
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

fn gdsky() -> Command {
    Command::new(env!("CARGO_BIN_EXE_gdsky"))
}

#[test]
fn check_exit_codes_follow_the_cli_contract() {
    let ok = gdsky().args(["check", "fixtures/freeman_sky.gdshader"]).output().expect("runs");
    assert_eq!(ok.status.code(), Some(0), "{}", String::from_utf8_lossy(&ok.stderr));
    let bad = gdsky()
        .args(["check", "fixtures/freeman_sky.gdshader", "tests/shaders/invalid/missing_semicolon.gdshader"])
        .output()
        .expect("runs");
    assert_eq!(bad.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&bad.stderr);
    assert!(stderr.contains("tests/shaders/invalid/missing_semicolon.gdshader:"), "{stderr}");
    let missing = gdsky().args(["check", "tests/shaders/no_such_file.gdshader"]).output().expect("runs");
    assert_eq!(missing.status.code(), Some(2));
}

#[test]
fn json_diagnostics_have_the_contract_fields() {
    let out = gdsky()
        .args(["check", "--diagnostics", "json", "tests/shaders/invalid/int_plus_float.gdshader"])
        .output()
        .expect("runs");
    assert_eq!(out.status.code(), Some(1));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert!(!lines.is_empty());
    for line in lines {
        let v: serde_json::Value = serde_json::from_str(line).expect("each line is JSON");
        for key in ["file", "line", "column", "end_line", "end_column", "severity", "code", "message"] {
            assert!(v.get(key).is_some(), "{key} missing from {line}");
        }
        assert_eq!(v["file"], "tests/shaders/invalid/int_plus_float.gdshader");
        assert_eq!(v["line"], expected_line(Path::new("tests/shaders/invalid/int_plus_float.gdshader")));
    }
    // The library's JSON and the binary's agree.
    let output = gdsky::check_file(Path::new("tests/shaders/invalid/int_plus_float.gdshader")).expect("readable");
    assert_eq!(render_json(&output.db, &output.diagnostics), stdout);
}

#[test]
fn hostile_inputs_get_a_diagnostic_and_exit_1() {
    let dir = std::env::temp_dir().join(format!("gdsky-hostile-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "parens",
            format!("shader_type sky; void sky() {{ COLOR = vec3({}1.0{}); }}", "(".repeat(20_000), ")".repeat(20_000))
                .into_bytes(),
            "E500",
        ),
        (
            "blocks",
            format!("shader_type sky; void sky() {}{}", "{".repeat(20_000), "}".repeat(20_000)).into_bytes(),
            "E500",
        ),
        (
            "macro_bomb",
            {
                let mut s = String::from("shader_type sky;\n#define A0 x\n");
                for i in 0..40 {
                    s.push_str(&format!("#define A{} A{i} A{i}\n", i + 1));
                }
                s.push_str("A40\n");
                s.into_bytes()
            },
            "E017",
        ),
        ("nul", b"shader_type sky;\0void sky() {}".to_vec(), "E002"),
        ("utf8", b"shader_type sky;\n\xff\xfe".to_vec(), "E001"),
        ("array", b"shader_type sky; void sky() { float a[2000000000]; }".to_vec(), "E501"),
    ];
    for (name, bytes, code) in cases {
        let path = dir.join(format!("{name}.gdshader"));
        std::fs::write(&path, bytes).expect("write");
        let out = gdsky().args(["check", "--diagnostics", "json"]).arg(&path).output().expect("runs");
        assert_eq!(out.status.code(), Some(1), "{name}: {}", String::from_utf8_lossy(&out.stderr));
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(stdout.contains(&format!("\"code\":\"{code}\"")), "{name}: {stdout}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

//! `gdsky check`: the CLI contract's exit codes and JSON diagnostics, and hostile inputs that
//! must end in a diagnostic (the front end's own suite is crates/gdshader/tests/frontend.rs).

use gdsky::frontend::diag::render_json;
use std::path::Path;
use std::process::Command;

/// The `// expect: LINE:COL` line of a test shader.
fn expected_line(path: &Path) -> usize {
    let text = std::fs::read_to_string(path).expect("test shader is readable");
    let at = text.find("// expect: ").unwrap_or_else(|| panic!("{} has no `// expect:` line", path.display()));
    let line = text[at + "// expect: ".len()..].split(':').next().unwrap_or("");
    line.trim().parse().unwrap_or_else(|_| panic!("{}: bad expect line", path.display()))
}

fn gdsky() -> Command {
    skytest::gdsky!().command()
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

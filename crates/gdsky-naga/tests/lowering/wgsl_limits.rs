//! WGSL's own limits, which GLSL (and so Godot) does not have: naga's WGSL parser stops at 200
//! levels of recursion and at 127 nested braces. Long expressions are given names so their text
//! stays shallow; statements nested deeper than WGSL allows are refused as untranslatable (E600)
//! at the statement, never written as text that does not read back.

fn front(source: &str) -> gdshader::FrontendOutput {
    gdshader::check_source("limits.gdshader", source.as_bytes().to_vec(), None, &mut gdshader::FsLoader)
}

/// `n` nested `if` blocks around one statement.
fn nested_ifs(n: usize) -> String {
    format!(
        "shader_type sky;\nvoid sky() {{\n\tfloat x = 0.0;\n{}\tx += (x * (x + (x * (x + 1.0))));\n{}\tCOLOR = vec3(x);\n}}\n",
        "\tif (x < 1.0) {\n".repeat(n),
        "\t}\n".repeat(n)
    )
}

#[test]
fn a_long_expression_chain_reads_back() {
    // 400 additions print as 400 nested parentheses unless parts get names.
    let source =
        format!("shader_type sky;\nuniform float u;\nvoid sky() {{ COLOR = vec3(u{}); }}\n", " + u".repeat(400));
    let front = front(&source);
    let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).expect("lowers");
    let wgsl = gdsky_naga::to_wgsl(&lowered).expect("the WGSL reads back");
    assert!(wgsl.contains("let part"), "long chains are cut into named parts:\n{wgsl}");
    gdsky_naga::to_spirv(&lowered).expect("the SPIR-V reads back");
}

#[test]
fn deep_but_legal_nesting_reads_back() {
    // The function body's braces and 125 `if`s: 126 of WGSL's 127.
    let front = front(&nested_ifs(125));
    let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).expect("lowers");
    gdsky_naga::to_wgsl(&lowered).expect("the WGSL reads back");
}

#[test]
fn nesting_deeper_than_wgsl_allows_is_refused_at_the_statement() {
    // GLSL braces a switch once; WGSL braces it and each case: 70 nested switches are 70 levels
    // for the front end (and Godot) but 1 + 2 × 70 braces in WGSL.
    let source = format!(
        "shader_type sky;\nvoid sky() {{\n\tint x = 0;\n{}\tx += 1;\n{}\tCOLOR = vec3(float(x));\n}}\n",
        "\tswitch (x) { case 0:\n".repeat(70),
        "\tbreak; }\n".repeat(70)
    );
    let front = front(&source);
    assert!(front.shader.is_some(), "the front end accepts it, as Godot does");
    let diagnostics = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).err().expect("refused");
    assert_eq!(diagnostics.len(), 1);
    let d = &diagnostics[0];
    assert_eq!(d.code, gdsky_naga::UNSUPPORTED, "{d:?}");
    let label = d.primary_label().expect("located");
    let (line, _) = front.db.line_col(label.file, label.range.start);
    // Switch k (line 3 + k) opens braces 2k and 2k + 1; the 64th's case would be the 129th.
    assert_eq!(line, 3 + 64, "{d:?}");
}

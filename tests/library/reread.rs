//! Whatever gdsky emits is read back by naga's own front ends before it is handed out: a module
//! that naga's IR validator accepts but whose WGSL text no WGSL compiler would take is refused
//! with a diagnostic at the user's function, no text comes back and no file is written.

use gdsky::frontend as gdshader;
use std::path::Path;

fn freeman() -> (gdshader::FrontendOutput, gdsky_naga::Lowered) {
    let _ = std::env::set_current_dir(env!("CARGO_MANIFEST_DIR"));
    let front = gdshader::check_file(Path::new("fixtures/freeman_sky.gdshader")).expect("fixture reads");
    let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).expect("the Freeman sky lowers");
    (front, lowered)
}

/// Drops every `return` from the top level of the named function's body: naga's IR validator
/// does not require a non-void function to return, WGSL does.
fn without_returns(lowered: gdsky_naga::Lowered, function: &str) -> gdsky_naga::Lowered {
    let mut module = lowered.module;
    let handle = module
        .functions
        .iter()
        .find(|(_, f)| f.name.as_deref() == Some(function))
        .map(|(h, _)| h)
        .expect("the function is in the module");
    let body = std::mem::take(&mut module.functions[handle].body);
    let mut kept = naga::Block::new();
    for (statement, span) in body.span_into_iter() {
        if !matches!(statement, naga::Statement::Return { .. }) {
            kept.push(statement, span);
        }
    }
    module.functions[handle].body = kept;
    let info = gdsky_naga::validator().validate(&module).expect("naga's IR validator still accepts the module");
    gdsky_naga::Lowered { module, info, ..lowered }
}

#[test]
fn the_emitted_texts_of_a_valid_shader_read_back() {
    let (_, lowered) = freeman();
    let wgsl = gdsky_naga::to_wgsl(&lowered).expect("WGSL re-reads");
    assert!(wgsl.contains("fn get_mie_phase("));
    let words = gdsky_naga::to_spirv(&lowered).expect("SPIR-V re-reads");
    assert_eq!(words.first(), Some(&0x0723_0203), "SPIR-V magic number");
}

#[test]
fn wgsl_that_does_not_read_back_is_refused_at_the_users_function() {
    let (front, lowered) = freeman();
    let broken = without_returns(lowered, "get_mie_phase");
    let err = gdsky_naga::to_wgsl(&broken).expect_err("the WGSL must be refused");
    assert!(err.reread, "the writer succeeded; the re-read failed: {err}");
    assert!(err.message.contains("get_mie_phase"), "the message quotes naga on the emitted text: {}", err.message);

    let diagnostic = err.diagnostic(&front);
    assert_eq!(diagnostic.code, gdsky_naga::REREAD);
    let label = diagnostic.primary_label().expect("located in the shader");
    let (line, _) = front.db.line_col(label.file, label.range.start);
    // `float get_mie_phase(float cos_theta, ...) {` is line 190 of the fixture.
    assert_eq!(line, 190, "{diagnostic:?}");
    let text = gdshader::diag::render_human(&front.db, &[diagnostic], false);
    assert!(text.contains("error[E604]") && text.contains("freeman_sky.gdshader:190:"), "{text}");
    assert!(text.contains("nothing was written"), "{text}");
}

#[test]
fn corrupt_text_is_refused_with_naga_s_message() {
    let (_, lowered) = freeman();
    let err = gdsky_naga::reread_wgsl(&lowered.module, "fn f() -> i32 { return 1i << 40u; }")
        .expect_err("text naga cannot read must be refused");
    assert!(err.reread);
    assert_eq!(err.format, "WGSL");
}

#[test]
fn a_module_that_does_not_read_back_writes_nothing() {
    let (front, lowered) = freeman();
    let options = gdsky::Options::default();
    let out = crate::common::scratch("reread", "writes_nothing");

    // The same module, intact, writes its four files: the directory is usable.
    let good = crate::common::scratch("reread", "writes_four");
    let (front_again, _) = freeman();
    let intact = gdsky::emit(front_again, &lowered, &options).expect("an intact module emits");
    intact.write_into(&good).expect("an intact module is written");
    assert_eq!(std::fs::read_dir(&good).expect("listable").count(), 4);

    // A module that does not read back never becomes a `Converted`, so there is nothing to write.
    let broken = without_returns(lowered, "get_mie_phase");
    match gdsky::emit(front, &broken, &options) {
        Err(e) => {
            let text = e.to_string();
            assert!(text.contains("error[E604]") && text.contains("freeman_sky.gdshader:190:"), "{text}");
        }
        Ok(_) => panic!("expected an E604 refusal"),
    }
    let left: Vec<_> = std::fs::read_dir(&out).expect("listable").map(|e| e.map(|e| e.file_name())).collect();
    assert!(left.is_empty(), "nothing may be written, found {left:?}");
}

//! Work and size budgets at the edges of what the GPU stack holds (issue #22, item 1): arrays
//! within one SPIR-V instruction, uniform blocks within one uniform binding. Each is a located
//! error in the user's terms, before anything is written, in well under a second — not a panic
//! in naga's SPIR-V reader (a 64-byte shader used to crash `convert` after 10 s) or a driver's
//! message at `render`.

use crate::common::{gdsky, scratch, text};

fn convert(name: &str, source: &str) -> (std::process::Output, std::path::PathBuf) {
    let dir = scratch("budgets", name);
    let shader = dir.join(format!("{name}.gdshader"));
    std::fs::write(&shader, source).expect("write");
    let out = dir.join("out");
    let o = gdsky(&["convert", shader.to_str().expect("utf-8"), "-o", out.to_str().expect("utf-8")]);
    (o, out)
}

#[test]
fn an_array_longer_than_one_spirv_instruction_holds_is_refused_at_its_size() {
    let (o, out) = convert("spirv_words", "shader_type sky;uniform float U[65536];void sky(){COLOR.x=U[0];}\n");
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let said = text(&o);
    assert!(said.contains("E501") && said.contains("spirv_words.gdshader:1:33") && said.contains("65532"), "{said}");
    assert!(!out.exists(), "nothing is written");
}

#[test]
fn a_uniform_block_larger_than_a_binding_is_refused_at_its_largest_uniform() {
    let (o, out) = convert(
        "binding",
        "shader_type sky;\nuniform vec3 tint = vec3(1.0);\nuniform float U[4097];\nvoid sky(){COLOR = tint * U[0];}\n",
    );
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let said = text(&o);
    assert!(said.contains("E600") && said.contains("binding.gdshader:3:15"), "{said}");
    assert!(said.contains("65552 bytes") && said.contains("`U`"), "{said}");
    assert!(!out.exists(), "nothing is written");
    // One element fewer fits: the bound is the binding's, not a guess.
    let (o, _) = convert("binding_fits", "shader_type sky;\nuniform float U[4096];\nvoid sky(){COLOR.x = U[0];}\n");
    assert!(o.status.success(), "{}", text(&o));
}

/// A shader the driver compiles for minutes (lavapipe: still compiling after 900 s) ends at the
/// driver budget with exit 1, naming the shader, the budget and how to raise it; nothing written.
#[test]
fn a_pipeline_build_past_the_driver_budget_ends_the_command() {
    let dir = scratch("budgets", "driver");
    let shader = dir.join("heavy.gdshader");
    let source = "shader_type sky;\nvoid sky() {\n\tfloat A[60000];\n\tfor (int i = 0; i < 60000; i++) { A[i] = float(i); }\n\tCOLOR.x = A[int(EYEDIR.x * 100.0) + 200];\n}\n";
    std::fs::write(&shader, source).expect("write");
    let out = dir.join("heavy.exr");
    let started = std::time::Instant::now();
    let budget = std::path::Path::new("3");
    let o = crate::common::gdsky_with(
        &["render", shader.to_str().expect("utf-8"), "-o", out.to_str().expect("utf-8"), "--size", "8x4"],
        &[("GDSKY_DRIVER_BUDGET", budget)],
    );
    let took = started.elapsed();
    let said = text(&o);
    assert_eq!(o.status.code(), Some(1), "{said}");
    assert!(said.contains("heavy.gdshader") && said.contains("longer than 3 s, the driver budget"), "{said}");
    assert!(said.contains("GDSKY_DRIVER_BUDGET=SECONDS"), "{said}");
    // A hang detector, not a speed claim: without the budget this runs for a quarter of an hour.
    assert!(took < std::time::Duration::from_secs(120), "ended at the budget, not at the driver's pace: {took:?}");
    assert!(!out.exists(), "nothing is written");
}

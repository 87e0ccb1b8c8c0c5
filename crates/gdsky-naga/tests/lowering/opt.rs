//! The optimizing stage and specialization (issue #11): pruning, the clean-up the lowering
//! does, `--set` through control flow, `--override`.

use std::collections::HashMap;
use std::path::Path;

use crate::front;

fn freeman() -> gdshader::FrontendOutput {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/freeman_sky.gdshader");
    gdshader::check_file(&path).expect("fixture readable")
}

fn wgsl(front: &gdshader::FrontendOutput) -> String {
    gdsky_naga::to_wgsl(&gdsky_naga::lower(front, &gdsky_naga::LowerOptions::default()).expect("lowers")).expect("WGSL")
}

/// The text of `fn sky()` in emitted WGSL.
fn sky_body(w: &str) -> &str {
    let start = w.find("fn sky(").expect("a sky function");
    let end = w[start..].find("\n}\n").map_or(w.len(), |e| start + e);
    &w[start..end]
}

#[test]
fn unread_builtins_leave_no_loads() {
    let w = wgsl(&front("shader_type sky;\nvoid sky() { COLOR = EYEDIR * 0.5 + LIGHT0_DIRECTION * LIGHT0_ENERGY; }\n"));
    for field in [".time", ".position", "lights[1]", "lights[2]", "lights[3]", "SKY_COORDS", "SCREEN_UV", "FOG"] {
        assert!(!w.contains(field), "`{field}` is loaded though the shader does not read it:\n{w}");
    }
    assert!(w.contains("lights[0]"), "{w}");
}

#[test]
fn unused_functions_and_constants_are_not_emitted() {
    let w = wgsl(&front(
        "shader_type sky;\nconst float UNUSED_K = 3.0;\nconst float USED_K = 2.0;\n\
         float helper(float x) { return x * UNUSED_K; }\n\
         float twice(float x) { return x * USED_K; }\n\
         float unused_caller(float x) { return helper(x); }\n\
         void sky() { float dead = sin(EYEDIR.x); COLOR = vec3(twice(EYEDIR.y)); }\n",
    ));
    assert!(!w.contains("fn helper") && !w.contains("fn unused_caller"), "{w}");
    assert!(!w.contains("UNUSED_K"), "{w}");
    assert!(w.contains("fn twice"), "{w}");
    assert!(!sky_body(&w).contains("sin("), "a value nothing reads is dropped:\n{w}");
}

#[test]
fn never_written_locals_are_lets() {
    let w = wgsl(&front(
        "shader_type sky;\nvoid sky() { float a = EYEDIR.x * 2.0; float b = a + 1.0; float c = 0.0; \
         c += b; COLOR = vec3(a, b, c); }\n",
    ));
    assert!(w.contains("let a = ") && w.contains("let b = "), "{w}");
    assert!(w.contains("var c: f32"), "an assigned local stays a variable:\n{w}");
    assert!(!w.contains("var a") && !w.contains("var b"), "{w}");
}

#[test]
fn max_against_a_constant_is_one_select() {
    let w =
        wgsl(&front("shader_type sky;\nvoid sky() { COLOR = vec3(max(0.0, EYEDIR.y), min(EYEDIR.x, 1.0), 0.0); }\n"));
    assert!(w.contains("> 0f"), "{w}");
    assert!(w.contains("< 1f"), "{w}");
    assert!(!w.contains("bitcast"), "no NaN bit tests against a constant:\n{w}");
    // Between two run-time values the NaN tests stay.
    let w = wgsl(&front("shader_type sky;\nvoid sky() { COLOR = vec3(max(EYEDIR.x, EYEDIR.y)); }\n"));
    assert!(w.contains("bitcast<u32>"), "{w}");
}

#[test]
fn clamp_to_a_uniform_bound_has_no_nan_bit_tests() {
    // max(x, 0.5) is never NaN, so the min against the uniform is one select too (a NaN
    // uniform yields the max's result, as maxNum does).
    let w = wgsl(&front(
        "shader_type sky;\nuniform float top = 2.0;\nvoid sky() { COLOR = vec3(clamp(EYEDIR.y, 0.5, top), \
         min(max(EYEDIR.x, 0.0), top), 0.0); }\n",
    ));
    assert!(!w.contains("bitcast"), "no NaN bit tests when one operand is never NaN:\n{w}");
    assert_eq!(sky_body(&w).matches("select(").count(), 4, "{w}");
    // A max of two run-time values may be NaN: the min against it keeps its tests.
    let w = wgsl(&front(
        "shader_type sky;\nuniform float top = 2.0;\nvoid sky() { COLOR = vec3(min(max(EYEDIR.x, EYEDIR.y), top)); }\n",
    ));
    assert_eq!(sky_body(&w).matches("bitcast<u32>").count(), 4, "{w}");
}

#[test]
fn a_baked_bool_removes_the_branch_not_taken() {
    let source = "shader_type sky;\nuniform bool fancy = false;\nuniform float k = 1.0;\n\
                  void sky() { if (fancy) { COLOR = vec3(sin(EYEDIR.x)); } else if (k > 2.0) { COLOR = vec3(cos(EYEDIR.y)); } \
                  else { COLOR = vec3(EYEDIR.z); } }\n";
    let f = front(source);
    let generic = wgsl(&f);
    let generic = sky_body(&generic);
    assert!(generic.contains("sin(") && generic.contains("cos("), "{generic}");
    let baked: HashMap<String, String> = [("fancy".to_string(), "false".to_string())].into();
    let w = gdsky_naga::to_wgsl(
        &gdsky_naga::lower(&f, &gdsky_naga::LowerOptions { baked: baked.clone(), ..Default::default() })
            .expect("lowers"),
    )
    .expect("WGSL");
    let w = sky_body(&w);
    assert!(!w.contains("sin("), "the branch of a false baked bool is gone:\n{w}");
    assert!(w.contains("cos("), "{w}");
    let baked: HashMap<String, String> = [("fancy".to_string(), "false".into()), ("k".into(), "1.0".into())].into();
    let w = gdsky_naga::to_wgsl(
        &gdsky_naga::lower(&f, &gdsky_naga::LowerOptions { baked: baked.clone(), ..Default::default() })
            .expect("lowers"),
    )
    .expect("WGSL");
    let w = sky_body(&w);
    assert!(!w.contains("sin(") && !w.contains("cos(") && !w.contains("if "), "only the else is left:\n{w}");
    let baked: HashMap<String, String> = [("fancy".to_string(), "true".to_string())].into();
    let w = gdsky_naga::to_wgsl(
        &gdsky_naga::lower(&f, &gdsky_naga::LowerOptions { baked: baked.clone(), ..Default::default() })
            .expect("lowers"),
    )
    .expect("WGSL");
    let w = sky_body(&w);
    assert!(w.contains("sin(") && !w.contains("cos(") && !w.contains("if "), "only the taken branch:\n{w}");
}

#[test]
fn three_sets_on_the_freeman_sky_remove_three_uniforms_and_shrink_the_spirv() {
    let f = freeman();
    let generic = gdsky_naga::lower(&f, &gdsky_naga::LowerOptions::default()).expect("lowers");
    let baked: HashMap<String, String> = [
        ("view_samples".to_string(), "24".to_string()),
        ("sun_samples".into(), "8".into()),
        ("ozone_width".into(), "30000.0".into()),
    ]
    .into();
    let set = gdsky_naga::lower(&f, &gdsky_naga::LowerOptions { baked: baked.clone(), ..Default::default() })
        .expect("lowers");
    assert_eq!(set.uniforms.len() + 3, generic.uniforms.len());
    for n in baked.keys() {
        assert!(!set.uniforms.contains_key(n));
    }
    let (a, b) = (gdsky_naga::to_spirv(&generic).expect("SPIR-V"), gdsky_naga::to_spirv(&set).expect("SPIR-V"));
    eprintln!("SPIR-V words: generic {}, three --set {}", a.len(), b.len());
    assert!(b.len() < a.len(), "SPIR-V: generic {} words, baked {}", a.len(), b.len());
    assert!(set.material_size < generic.material_size || set.uniforms.len() < generic.uniforms.len());
}

#[test]
fn overrides_are_wgsl_overrides_and_listed_in_the_reflection() {
    let f = freeman();
    let names = ["sun_intensity".to_string(), "view_samples".to_string()];
    let lowered = gdsky_naga::lower(&f, &gdsky_naga::LowerOptions { overrides: names.to_vec(), ..Default::default() })
        .expect("lowers");
    let w = gdsky_naga::to_wgsl(&lowered).expect("WGSL");
    assert!(w.contains("@id(0) override sun_intensity: f32 = 62.832f;"), "{w}");
    assert!(w.contains("@id(1) override view_samples: i32 = 24i;"), "{w}");
    assert!(!w.contains("material.sun_intensity") && !w.contains("material.view_samples"), "{w}");
    let shader = f.shader.as_ref().expect("checked");
    let r = gdsky_naga::reflect::reflection("freeman", shader, &lowered);
    let overrides = &r.overrides;
    assert_eq!(overrides.len(), 2);
    assert_eq!(overrides[1].name.as_deref(), Some("view_samples"));
    assert_eq!(overrides[1].id, Some(1));
    assert_eq!(overrides[1].default, Some(serde_json::json!(24)));
    let uniforms: Vec<&str> = r.uniforms.iter().map(|u| u.name.as_str()).collect();
    assert!(!uniforms.contains(&"view_samples") && uniforms.contains(&"sun_samples"), "{uniforms:?}");
    // In SPIR-V each override is a specialization constant: `OpSpecConstant` (opcode 50) with its
    // default, decorated `SpecId` (decoration 1) with its id.
    let words = gdsky_naga::to_spirv(&lowered).expect("SPIR-V with specialization constants");
    let mut spec = Vec::new();
    let mut spec_ids = Vec::new();
    let mut at = 5;
    while at < words.len() {
        let (len, opcode) = ((words[at] >> 16) as usize, words[at] & 0xffff);
        match opcode {
            50 => spec.push((words[at + 2], words[at + 3])),
            71 if words[at + 2] == 1 => spec_ids.push((words[at + 1], words[at + 3])),
            _ => {}
        }
        at += len.max(1);
    }
    assert_eq!(spec.len(), 2, "{spec:?}");
    let default_of =
        |id: u32| spec_ids.iter().find(|s| s.1 == id).and_then(|s| spec.iter().find(|c| c.0 == s.0)).map(|c| c.1);
    assert_eq!(default_of(0), Some(62.832f32.to_bits()));
    assert_eq!(default_of(1), Some(24));
}

#[test]
fn an_override_the_spirv_writer_folds_into_a_composite_is_refused() {
    // `vec3(k)` of constants is an `OpConstantComposite`, which cannot hold a specialization
    // constant: refused (E602) rather than written wrong; the WGSL is fine.
    let src = "shader_type sky;\nuniform float k = 0.5;\nvoid sky() { COLOR = vec3(k) * EYEDIR; }\n";
    let f = gdshader::check_source("splat.gdshader", src.as_bytes().to_vec(), None, &mut gdshader::FsLoader);
    let lowered =
        gdsky_naga::lower(&f, &gdsky_naga::LowerOptions { overrides: vec!["k".to_string()], ..Default::default() })
            .expect("lowers");
    gdsky_naga::to_wgsl(&lowered).expect("WGSL");
    let err = gdsky_naga::to_spirv(&lowered).expect_err("refused");
    assert!(!err.reread && err.message.contains("cannot write the override `k` as a specialization constant"), "{err}");
    let d = err.diagnostic(&f);
    assert_eq!(d.code, gdsky_naga::BACKEND);
    assert!(d.notes.iter().any(|n| n.contains("not a bug")), "{d:?}");
}

#[test]
fn bad_overrides_are_refused() {
    let f = freeman();
    for (names, baked, why) in [
        (vec!["nope"], vec![], "has no uniform"),
        (vec!["sun_wavelengths"], vec![], "only scalar"),
        (vec!["view_samples"], vec![("view_samples", "8")], "baked"),
        (vec!["view_samples", "view_samples"], vec![], "twice"),
    ] {
        let names: Vec<String> = names.into_iter().map(String::from).collect();
        let baked: HashMap<String, String> = baked.into_iter().map(|(a, b)| (a.to_string(), b.to_string())).collect();
        let errors = gdsky_naga::lower(
            &f,
            &gdsky_naga::LowerOptions { baked: baked.clone(), overrides: names.to_vec(), ..Default::default() },
        )
        .err()
        .expect("refused");
        assert!(
            errors.iter().any(|d| d.code == gdsky_naga::BAD_SET && d.message.contains(why)),
            "{names:?}: {errors:?}"
        );
    }
}

#[test]
fn uniform_loads_are_at_function_entry() {
    // A uniform read in a loop and in a branch is loaded before the loop, at the top.
    let w = wgsl(&front(
        "shader_type sky;\nuniform float k = 2.0;\nuniform int n = 4;\n\
         void sky() { float s = 0.0; for (int i = 0; i < n; i++) { if (EYEDIR.y > 0.0) { s += k; } } COLOR = vec3(s); }\n",
    ));
    let body = sky_body(&w);
    let first_loop = body.find("loop {").expect("a loop");
    for load in ["material.k", "material.n"] {
        let at = body.find(load).unwrap_or_else(|| panic!("{load} in:\n{body}"));
        assert!(at < first_loop, "{load} before the loop:\n{body}");
    }
}

/// The `let _eN = NAME;` loads of the variable `name` in `w`.
fn loads_of(w: &str, name: &str) -> usize {
    w.lines().filter(|l| l.trim_start().starts_with("let ") && l.trim_end().ends_with(&format!(" = {name};"))).count()
}

#[test]
fn a_local_written_then_read_is_forwarded_and_its_variable_goes() {
    // `c` is written, read (whole and one component), across an `if` that does not write it:
    // every read is the value stored, and the variable is gone with its stores.
    let w = wgsl(&front(
        "shader_type sky;\nvoid sky() { vec3 c = EYEDIR; c = c * 2.0; float h = c.y; \
         if (EYEDIR.z > 0.5) { COLOR = vec3(h); } c = c + vec3(h); COLOR += c; }\n",
    ));
    let body = sky_body(&w);
    assert!(!body.contains("var c"), "{body}");
    assert_eq!(loads_of(body, "c"), 0, "{body}");
    assert!(!body.contains("c.y"), "{body}");
}

#[test]
fn a_store_nothing_reads_is_removed() {
    // `t` is written before and in a loop and never read: its stores, the variable and the
    // `sin` only they used are gone; the loop stays.
    let w = wgsl(&front(
        "shader_type sky;\nvoid sky() { float t = EYEDIR.x; t = sin(EYEDIR.y); \
         for (int i = 0; i < 3; i++) { t = cos(EYEDIR.z * float(i)); } COLOR = vec3(1.0); }\n",
    ));
    let body = sky_body(&w);
    assert!(!body.contains("var t") && !body.contains("t = "), "{body}");
    assert!(!body.contains("sin(") && !body.contains("cos("), "{body}");
    assert!(body.contains("loop {"), "{body}");
}

#[test]
fn a_write_in_a_loop_is_not_forwarded() {
    // Each iteration reads what the last one wrote, and the read after the loop the last write.
    let w = wgsl(&front(
        "shader_type sky;\nvoid sky() { float s = EYEDIR.x; for (int i = 0; i < 4; i++) { s = s * EYEDIR.y; } \
         COLOR = vec3(s); }\n",
    ));
    let body = sky_body(&w);
    assert!(body.contains("var s"), "{body}");
    let in_loop = &body[body.find("loop {").expect("a loop")..];
    assert!(loads_of(in_loop, "s") >= 2, "one load in the loop, one after it:\n{body}");
}

#[test]
fn a_write_through_an_inout_argument_is_not_forwarded() {
    // After the call, the variable holds what `bump` wrote, not what was stored before it.
    let w = wgsl(&front(
        "shader_type sky;\nvoid bump(inout float x) { x = x * 2.0; }\n\
         void twice(float a, out float y) { y = a * 2.0; }\n\
         void sky() { float v = EYEDIR.x; bump(v); float o = EYEDIR.z; twice(EYEDIR.y, o); COLOR = vec3(v, o, 0.0); }\n",
    ));
    let body = sky_body(&w);
    for call in ["bump(", "twice("] {
        let at = body.find(call).unwrap_or_else(|| panic!("{call} in:\n{body}"));
        let arg = at + body[at..].find("(&").expect("a pointer argument") + 2;
        let name = body[arg..].split(')').next().expect("an argument");
        assert!(loads_of(&body[at..], name) >= 1, "`{name}` is loaded after the call:\n{body}");
    }
}

#[test]
fn a_write_in_one_branch_or_of_a_constant_is_not_forwarded() {
    // After the `if`, `v` is either value: it is loaded.
    let w = wgsl(&front(
        "shader_type sky;\nvoid sky() { float v = EYEDIR.x; if (EYEDIR.y > 0.0) { v = EYEDIR.z; } COLOR = vec3(v); }\n",
    ));
    let body = sky_body(&w);
    assert!(body.contains("var v"), "{body}");
    let after = &body[body.rfind('}').expect("the if's end")..];
    assert_eq!(loads_of(after, "v"), 1, "{body}");
    // A constant stays behind its variable: forwarded, `k * 10.0` would be a WGSL constant
    // expression, evaluated (and overflowing) when the shader is created.
    let w =
        wgsl(&front("shader_type sky;\nvoid sky() { float k = 1e38; k = k * 10.0; COLOR = vec3(k * EYEDIR.x); }\n"));
    let body = sky_body(&w);
    assert!(body.contains("var k") && loads_of(body, "k") >= 1, "{body}");
    // So does a value computed from uniforms only: `--override` makes it an override
    // expression, evaluated when the pipeline is created.
    let w = wgsl(&front(
        "shader_type sky;\nuniform float u = 2.0;\nvoid sky() { float t = u * 3.0; t = t * EYEDIR.x; COLOR = vec3(t); }\n",
    ));
    let body = sky_body(&w);
    assert!(body.contains("var t") && loads_of(body, "t") >= 1, "{body}");
}

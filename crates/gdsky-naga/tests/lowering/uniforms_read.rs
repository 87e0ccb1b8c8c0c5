//! `reflect::uniforms_read`: which uniforms a lowered module reads, the notion `gdsky bench`
//! uses to sweep only the knobs a shader reads.

use std::collections::{BTreeSet, HashMap};
use std::path::Path;

use crate::front;

fn read(lowered: &gdsky_naga::Lowered) -> Vec<String> {
    gdsky_naga::reflect::uniforms_read(lowered).into_iter().collect()
}

#[test]
fn declared_but_unread_uniforms_are_not_read() {
    // `dead` is read only by a function nothing calls and by a value nothing uses; `global` is
    // a global uniform (another block); `a` is read through a loop bound.
    let f = front(
        "shader_type sky;\nuniform float a = 1.0;\nuniform int n = 3;\nuniform float dead = 2.0;\n\
         uniform vec3 never;\nglobal uniform float global_k;\n\
         float unused() { return dead * 2.0; }\n\
         void sky() { float d = dead + 1.0; vec3 c = vec3(0.0); for (int i = 0; i < n; i++) { c += EYEDIR * a; } \
         COLOR = c * global_k; }\n",
    );
    let lowered = gdsky_naga::lower(&f, &gdsky_naga::LowerOptions::default()).expect("lowers");
    assert_eq!(read(&lowered), ["a", "global_k", "n"]);
    // An override is read when an expression refers to it; a baked uniform is no uniform.
    let lowered = gdsky_naga::lower(
        &f,
        &gdsky_naga::LowerOptions {
            baked: HashMap::from([("a".into(), "2.0".into())]),
            overrides: vec!["n".into()],
            ..Default::default()
        },
    )
    .expect("lowers");
    assert_eq!(read(&lowered), ["global_k", "n"]);
}

#[test]
fn the_fast_sky_never_reads_sun_samples_and_the_original_reads_everything() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let original = gdshader::check_file(&root.join("fixtures/freeman_sky.gdshader")).expect("fixture readable");
    let original = gdsky_naga::lower(&original, &gdsky_naga::LowerOptions::default()).expect("lowers");
    let all: BTreeSet<String> = original.uniforms.keys().cloned().collect();
    assert_eq!(gdsky_naga::reflect::uniforms_read(&original), all);
    let fast = root.join("shaders/freeman_fast.gdshader");
    let fast =
        gdsky_naga::lower(&gdshader::check_file(&fast).expect("shader readable"), &gdsky_naga::LowerOptions::default())
            .expect("lowers");
    let read = gdsky_naga::reflect::uniforms_read(&fast);
    assert!(fast.uniforms.contains_key("sun_samples"), "declared");
    assert!(!read.contains("sun_samples") && read.contains("view_samples"), "{read:?}");
}

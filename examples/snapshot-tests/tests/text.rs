//! The converted shader as text, for review in pull requests: the WGSL, the reflection (bindings,
//! uniform offsets) and the SPIR-V disassembly. `INSTA_UPDATE=always cargo test` (or
//! `cargo insta review`) accepts a change.

const SHADER: &str = "godot/shaders/noise_sky.gdshader";

#[test]
fn noise_sky_wgsl() {
    insta::assert_snapshot!(gdsky::testing::wgsl_text(SHADER));
}

#[test]
fn noise_sky_reflection() {
    insta::assert_snapshot!(gdsky::testing::reflection_text(SHADER));
}

#[test]
fn noise_sky_spirv() {
    insta::assert_snapshot!(gdsky::testing::spirv_text(SHADER));
}

//! Text snapshots of a conversion: the WGSL, the reflection and a SPIR-V disassembly, as text
//! that is the same in every build profile, on every machine and in every checkout, for
//! `insta::assert_snapshot!`.
//!
//! gdsky's conversion is deterministic: its SPIR-V carries no debug information and no paths
//! in any profile. What could still differ between machines is where the crate is checked out,
//! which diagnostics and the reflection may name: the crate's directory is written `<crate>`.

use crate::engine::{Input, Sky};

/// The WGSL gdsky converts the shader at `shader_path` (relative to the crate; a `.tres` gives
/// its shader) to, with Godot 4.6's defaults. Panics with the diagnostics when it does not
/// convert.
///
/// ```no_run
/// insta::assert_snapshot!(gdsky::testing::wgsl_text("shaders/sky.gdshader"));
/// ```
#[track_caller]
pub fn wgsl_text(shader_path: &str) -> String {
    normalise(&converted(shader_path).wgsl)
}

/// The reflection JSON (`gdsky convert`'s `<name>.json`: entry points, bindings, uniforms
/// with offsets and types, textures). Panics like [`wgsl_text`].
#[track_caller]
pub fn reflection_text(shader_path: &str) -> String {
    normalise(&converted(shader_path).reflection_json())
}

/// The SPIR-V disassembled (rspirv's text: one instruction a line, `%id` names). Panics like
/// [`wgsl_text`].
#[track_caller]
pub fn spirv_text(shader_path: &str) -> String {
    use rspirv::binary::Disassemble;
    let words = converted(shader_path).spirv;
    match rspirv::dr::load_words(&words) {
        Ok(module) => normalise(&module.disassemble()),
        // gdsky re-read these words with naga before handing them out: not the user's fault.
        Err(e) => panic!("gdsky's SPIR-V of {shader_path} does not disassemble: {e}"),
    }
}

#[track_caller]
fn converted(shader_path: &str) -> crate::Converted {
    let path = super::resolve(shader_path);
    let fail = |message: String| -> ! { panic!("{shader_path} does not convert:\n{message}") };
    let input = Input::open(Some(&path)).unwrap_or_else(|e| fail(e.render(false)));
    let sky = Sky::load(input.shader.as_deref(), &gdsky_naga::LowerOptions::default())
        .unwrap_or_else(|e| fail(e.render(false)));
    crate::emit(sky.front, &sky.lowered, &crate::Options::default()).unwrap_or_else(|e| fail(e.render(false)))
}

/// The crate's directory as `<crate>`, and line ends as `\n`.
fn normalise(text: &str) -> String {
    let root = super::crate_root();
    let text = text.replace("\r\n", "\n");
    match root.to_str().filter(|r| r.len() > 1) {
        Some(r) => text.replace(r, "<crate>"),
        None => text,
    }
}

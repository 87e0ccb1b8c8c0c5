//! Feeds arbitrary bytes to Godot's text-resource parser, then, as a `.tres` in a throwaway
//! project beside a valid sky shader, to the material loader and its settings (values checked
//! against the shader's uniforms, textures, generated noise and gradients described). Any panic
//! is a bug: every input gets a diagnostic or a material.
#![no_main]

use std::path::PathBuf;
use std::sync::OnceLock;

const SKY: &str = "shader_type sky;\nuniform vec3 tint : source_color = vec3(1.0);\nuniform float gain = 1.0;\n\
uniform sampler2D clouds;\nvoid sky() { COLOR = tint * gain * texture(clouds, SKY_COORDS).r; }\n";

/// A project with `project.godot` and `sky.gdshader`, made once per fuzzing process.
fn project() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("gdsky_fuzz_resource_{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        std::fs::write(dir.join("project.godot"), "config_version=5\n").expect("write");
        std::fs::write(dir.join("sky.gdshader"), SKY).expect("write");
        dir
    })
}

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let mut db = gdshader::diag::SourceDb::new();
        let file = db.add("fuzz.tres", text.to_string(), None);
        let _ = gdresource::text::parse(text, file);
    }
    let path = project().join("fuzz.tres");
    std::fs::write(&path, data).expect("write");
    if let Ok(material) = gdresource::load_sky_material(&path)
        && let Ok(front) = material.check_shader()
        && let Some(shader) = front.shader.as_ref()
    {
        let _ = material.settings(shader);
    }
});

//! `gdsky::build` with [`Options`](gdsky::build::Options): baked uniforms leave the material
//! struct and the reflection's `uniforms` and are listed in its `baked`; a bad name or value is
//! refused with E603.

use gdsky::build::{BuildError, Options, compile_into, compile_into_with};
use std::path::{Path, PathBuf};

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gdsky-build-api-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).expect("json written")).expect("valid JSON")
}

fn uniform_names(json: &serde_json::Value) -> Vec<String> {
    json["uniforms"].as_array().expect("uniforms").iter().map(|u| u["name"].as_str().unwrap_or("").into()).collect()
}

#[test]
fn options_bake_into_the_reflection_and_the_material_struct() {
    let shader = Path::new("fixtures/freeman_sky.gdshader");
    let plain_dir = temp_dir("plain");
    let plain = compile_into(shader, &plain_dir).expect("compiles");
    let plain_json = json(&plain.reflection);
    let plain_rust = std::fs::read_to_string(&plain.rust).expect("rust written");
    assert!(uniform_names(&plain_json).contains(&"view_samples".to_string()));
    assert!(plain_rust.contains("pub view_samples: i32,"), "{plain_rust}");

    let baked_dir = temp_dir("baked");
    let options = Options::new().set("view_samples", "16").set("ground_color", "0.1,0.2,0.3");
    let baked = compile_into_with(shader, &baked_dir, &options).expect("compiles with bakes");
    let baked_json = json(&baked.reflection);
    let names = uniform_names(&baked_json);
    assert_eq!(names.len(), uniform_names(&plain_json).len() - 2);
    assert!(!names.iter().any(|n| n == "view_samples" || n == "ground_color"), "{names:?}");
    assert_eq!(baked_json["baked"]["view_samples"], "16");
    assert_eq!(baked_json["baked"]["ground_color"], "0.1,0.2,0.3");
    let rust = std::fs::read_to_string(&baked.rust).expect("rust written");
    assert!(!rust.contains("view_samples") && !rust.contains("ground_color"), "{rust}");
    assert!(
        rust.lines().filter(|l| l.starts_with("    pub ")).count()
            < plain_rust.lines().filter(|l| l.starts_with("    pub ")).count()
    );
    let wgsl = std::fs::read_to_string(&baked.wgsl).expect("wgsl written");
    assert!(wgsl.contains("const view_samples: i32 = 16i;"), "{wgsl}");

    // An override leaves the struct and the uniforms, is listed with its id, and the SPIR-V
    // carries it as a specialization constant (OpSpecConstant, opcode 50).
    let over_dir = temp_dir("override");
    let over =
        compile_into_with(shader, &over_dir, &Options::new().override_uniform("sun_intensity")).expect("compiles");
    let over_json = json(&over.reflection);
    assert!(!uniform_names(&over_json).contains(&"sun_intensity".to_string()));
    assert_eq!(over_json["overrides"][0]["name"], "sun_intensity");
    assert_eq!(over_json["overrides"][0]["id"], 0);
    assert!(!std::fs::read_to_string(&over.rust).expect("rust").contains("pub sun_intensity"));
    let spv = std::fs::read(&over.spirv).expect("spv written");
    let words: Vec<u32> = spv.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
    assert!(words.contains(&((4 << 16) | 50)), "an OpSpecConstant");
    let _ = std::fs::remove_dir_all(&over_dir);

    for (tag, options) in [
        ("name", Options::new().set("no_such_uniform", "1")),
        ("value", Options::new().set("view_samples", "1.5")),
        ("override", Options::new().override_uniform("ground_color")),
    ] {
        let dir = temp_dir(tag);
        match compile_into_with(shader, &dir, &options) {
            Err(BuildError::Shader(e)) => assert!(e.diagnostics().iter().any(|d| d.code == "E603"), "{tag}: {e}"),
            other => panic!("{tag}: expected E603, got {other:?}"),
        }
        assert_eq!(std::fs::read_dir(&dir).expect("dir").count(), 0, "{tag}: nothing written");
        let _ = std::fs::remove_dir_all(&dir);
    }
    let _ = std::fs::remove_dir_all(&plain_dir);
    let _ = std::fs::remove_dir_all(&baked_dir);
}

//! `gdsky convert` end to end: the three files, the reflection's layout against naga's own
//! reading of the emitted WGSL, atomic behaviour on failure, and `--set`.

use std::path::PathBuf;
use std::process::Command;

fn gdsky() -> Command {
    Command::new(env!("CARGO_BIN_EXE_gdsky"))
}

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gdsky-convert-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// Member offsets of struct `name` in a WGSL module, as naga's WGSL front end lays it out.
fn wgsl_offsets(wgsl: &str, name: &str) -> Vec<(String, u32)> {
    let module = naga::front::wgsl::parse_str(wgsl).expect("the emitted WGSL parses");
    let (_, ty) = module.types.iter().find(|(_, t)| t.name.as_deref() == Some(name)).expect("struct exists");
    match &ty.inner {
        naga::TypeInner::Struct { members, .. } => {
            members.iter().map(|m| (m.name.clone().unwrap_or_default(), m.offset)).collect()
        }
        _ => panic!("{name} is not a struct"),
    }
}

#[test]
fn convert_writes_wgsl_spirv_and_reflection_with_naga_offsets() {
    let out = temp_dir("freeman");
    let run = gdsky().args(["convert", "fixtures/freeman_sky.gdshader", "-o"]).arg(&out).output().expect("runs");
    assert_eq!(run.status.code(), Some(0), "{}", String::from_utf8_lossy(&run.stderr));
    let wgsl = std::fs::read_to_string(out.join("freeman_sky.wgsl")).expect("wgsl written");
    let spv = std::fs::read(out.join("freeman_sky.spv")).expect("spv written");
    assert_eq!(&spv[..4], &0x0723_0203u32.to_le_bytes(), "SPIR-V magic number");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("freeman_sky.json")).expect("json written"))
            .expect("valid JSON");
    let uniforms = json["uniforms"].as_array().expect("uniforms array");
    assert_eq!(uniforms.len(), 22);
    let from_json: Vec<(String, u32)> = uniforms
        .iter()
        .map(|u| (u["name"].as_str().unwrap_or("").to_string(), u["offset"].as_u64().unwrap_or(u64::MAX) as u32))
        .collect();
    assert_eq!(from_json, wgsl_offsets(&wgsl, "Material"));
    assert_eq!(uniforms[0]["default"], serde_json::json!(62.832));
    assert_eq!(uniforms[0]["group"], "Sun");
    // No temporary files are left behind.
    let names: Vec<String> = std::fs::read_dir(&out)
        .expect("dir")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 3, "{names:?}");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_failed_convert_writes_nothing() {
    let out = temp_dir("invalid");
    let run = gdsky()
        .args(["convert", "tests/shaders/invalid/int_plus_float.gdshader", "-o"])
        .arg(&out)
        .output()
        .expect("runs");
    assert_eq!(run.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&run.stderr).contains("int_plus_float.gdshader:8:15"));
    assert!(!out.exists() || std::fs::read_dir(&out).map(|d| d.count()).unwrap_or(0) == 0);
    // Valid Godot that gdsky does not translate yet: a sampler array indexed at run time.
    let shader = std::env::temp_dir().join(format!("gdsky-untranslatable-{}.gdshader", std::process::id()));
    std::fs::write(
        &shader,
        "shader_type sky;\nuniform sampler2D layers[2];\nvoid sky() {\n    int i = int(TIME) % 2;\n    COLOR = texture(layers[i], SKY_COORDS).rgb;\n}\n",
    )
    .expect("temp shader");
    let untranslatable = gdsky().arg("convert").arg(&shader).arg("-o").arg(&out).output().expect("runs");
    let _ = std::fs::remove_file(&shader);
    assert_eq!(untranslatable.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&untranslatable.stderr).contains("E600"));
    assert!(!out.exists() || std::fs::read_dir(&out).map(|d| d.count()).unwrap_or(0) == 0);
    let missing = gdsky().args(["convert", "no/such.gdshader"]).output().expect("runs");
    assert_eq!(missing.status.code(), Some(2));
}

#[test]
fn set_bakes_a_uniform_into_a_constant() {
    let out = temp_dir("set");
    let run = gdsky()
        .args([
            "convert",
            "fixtures/freeman_sky.gdshader",
            "--set",
            "view_samples=16",
            "--set",
            "ground_color=0.1,0.2,0.3",
            "-o",
        ])
        .arg(&out)
        .output()
        .expect("runs");
    assert_eq!(run.status.code(), Some(0), "{}", String::from_utf8_lossy(&run.stderr));
    let wgsl = std::fs::read_to_string(out.join("freeman_sky.wgsl")).expect("written");
    assert!(wgsl.contains("const view_samples: i32 = 16i;"), "{wgsl}");
    assert!(!wgsl_offsets(&wgsl, "Material").iter().any(|(n, _)| n == "view_samples" || n == "ground_color"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("freeman_sky.json")).expect("json")).expect("valid");
    assert_eq!(json["uniforms"].as_array().map(Vec::len), Some(20));
    assert_eq!(json["baked"]["view_samples"], "16");
    for bad in ["no_such_uniform=1", "view_samples=1.5", "ground_color=1,2"] {
        let run = gdsky()
            .args(["convert", "fixtures/freeman_sky.gdshader", "--set", bad, "-o"])
            .arg(&out)
            .output()
            .expect("runs");
        assert_eq!(run.status.code(), Some(1), "{bad}");
        assert!(String::from_utf8_lossy(&run.stderr).contains("E603"), "{bad}");
    }
    let _ = std::fs::remove_dir_all(&out);
}

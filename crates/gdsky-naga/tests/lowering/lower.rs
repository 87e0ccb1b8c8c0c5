//! Every valid shader the front end accepts is lowered, validated by naga, written as WGSL
//! (re-parsed and validated again by naga's WGSL front end) and as SPIR-V (checked by
//! `spirv-val --target-env vulkan1.1`). WGSL and reflection of each are snapshots.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Shaders that use what the lowering does not translate yet, with the reason. Keeping the list
/// here makes a shader that starts (or stops) lowering a visible change.
const NOT_YET: &[(&str, &str)] = &[];

struct Converted {
    wgsl: String,
    reflection: gdsky_naga::reflect::Reflection,
}

fn convert(rel: &str) -> Result<Converted, String> {
    // Front-end paths are relative to the repository root, as a user would give them.
    let _ = std::env::set_current_dir(root());
    let front = gdshader::check_file(Path::new(rel)).map_err(|e| e.to_string())?;
    let shader =
        front.shader.as_ref().ok_or_else(|| gdshader::diag::render_human(&front.db, &front.diagnostics, false))?;
    let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default())
        .map_err(|d| gdshader::diag::render_human(&front.db, &d, false))?;
    let wgsl = gdsky_naga::to_wgsl(&lowered).map_err(|e| format!("WGSL writer: {e}"))?;
    let reparsed = naga::front::wgsl::parse_str(&wgsl)
        .map_err(|e| format!("WGSL does not re-parse: {}", e.emit_to_string(&wgsl)))?;
    gdsky_naga::validator()
        .validate(&reparsed)
        .map_err(|e| format!("re-parsed WGSL does not validate: {}", e.emit_to_string(&wgsl)))?;
    let words = gdsky_naga::to_spirv(&lowered).map_err(|e| format!("SPIR-V writer: {e}"))?;
    spirv_val(rel, &words)?;
    let name = Path::new(rel).file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let reflection = gdsky_naga::reflect::reflection(&name, shader, &lowered);
    Ok(Converted { wgsl, reflection })
}

fn spirv_val(rel: &str, words: &[u32]) -> Result<(), String> {
    let path = std::env::temp_dir().join(format!("gdsky-{}-{}.spv", std::process::id(), rel.replace('/', "_")));
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    std::fs::write(&path, bytes).map_err(|e| e.to_string())?;
    let out = Command::new("spirv-val")
        .args(["--target-env", "vulkan1.1"])
        .arg(&path)
        .output()
        .map_err(|e| format!("cannot run spirv-val (Debian package spirv-tools): {e}"))?;
    let _ = std::fs::remove_file(&path);
    if out.status.success() {
        Ok(())
    } else {
        Err(format!("spirv-val: {}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr)))
    }
}

#[test]
fn freeman_sky_converts() {
    let c = convert("fixtures/freeman_sky.gdshader").unwrap_or_else(|e| panic!("{e}"));
    insta::assert_snapshot!("freeman_sky.wgsl", c.wgsl);
    insta::assert_json_snapshot!("freeman_sky.json", c.reflection);
}

#[test]
fn every_valid_test_shader_converts() {
    let mut failures = Vec::new();
    let mut converted = 0;
    let dir = root().join("tests/shaders/valid");
    let mut paths: Vec<PathBuf> =
        std::fs::read_dir(&dir).expect("test shaders").filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    for path in paths.iter().filter(|p| p.extension().is_some_and(|e| e == "gdshader")) {
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let rel = format!("tests/shaders/valid/{name}");
        let expected_failure = NOT_YET.iter().find(|(n, _)| *n == name);
        match (convert(&rel), expected_failure) {
            (Ok(c), None) => {
                converted += 1;
                insta::assert_snapshot!(format!("{name}.wgsl"), c.wgsl);
                insta::assert_json_snapshot!(format!("{name}.json"), c.reflection);
            }
            (Ok(_), Some(_)) => failures.push(format!("{name} now converts: remove it from NOT_YET")),
            (Err(e), None) => failures.push(format!("{name}:\n{e}")),
            (Err(_), Some(_)) => {}
        }
    }
    assert!(failures.is_empty(), "{} shaders:\n{}", failures.len(), failures.join("\n"));
    assert!(converted >= 20, "only {converted} shaders converted");
}

/// The built-ins block is an interface hosts fill by hand: its layout is pinned here, and in
/// docs/binding-interface.md.
#[test]
fn builtins_block_layout_is_fixed() {
    let _ = std::env::set_current_dir(root());
    let front = gdshader::check_file(Path::new("fixtures/freeman_sky.gdshader")).expect("readable");
    let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).expect("lowers");
    let module = &lowered.module;
    let layout = |name: &str| {
        let ty = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some(name))
            .map(|(_, t)| t.inner.clone())
            .expect("struct exists");
        match ty {
            naga::TypeInner::Struct { members, span } => {
                (members.iter().map(|m| (m.name.clone().unwrap_or_default(), m.offset)).collect::<Vec<_>>(), span)
            }
            _ => panic!("{name} is not a struct"),
        }
    };
    let (fields, size) = layout("SkyBuiltins");
    let expect: Vec<(String, u32)> = [
        ("camera_basis", 0),
        ("position", 48),
        ("time", 60),
        ("screen_size", 64),
        ("tan_half_fov", 72),
        ("render_pass", 76),
        ("luminance_multiplier", 80),
        ("cube_face", 84),
        ("lights", 96),
    ]
    .iter()
    .map(|(n, o)| (n.to_string(), *o))
    .collect();
    assert_eq!(fields, expect);
    assert_eq!(size, 288);
    let (light, light_size) = layout("SkyLight");
    let expect: Vec<(String, u32)> = [("direction", 0), ("energy", 12), ("color", 16), ("size", 28), ("enabled", 32)]
        .iter()
        .map(|(n, o)| (n.to_string(), *o))
        .collect();
    assert_eq!(light, expect);
    assert_eq!(light_size, 48);
}

/// A module naga rejects is reported at the .gdshader line its bad code came from. (A valid
/// shader never produces one unless gdsky has a bug, so the bug is planted: the function that
/// returns `mie_scattering / mie_albedo` is told it returns an int.)
#[test]
fn a_validation_error_points_at_the_shader_line() {
    let _ = std::env::set_current_dir(root());
    let path = Path::new("fixtures/freeman_sky.gdshader");
    let front = gdshader::check_file(path).expect("readable");
    let mut module = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).expect("lowers").module;
    let int = module
        .types
        .insert(naga::Type { name: None, inner: naga::TypeInner::Scalar(naga::Scalar::I32) }, naga::Span::UNDEFINED);
    let (_, f) = module
        .functions
        .iter_mut()
        .find(|(_, f)| f.name.as_deref() == Some("get_mie_extinction"))
        .expect("function exists");
    f.result = Some(naga::FunctionResult { ty: int, binding: None });
    let diagnostic = gdsky_naga::validate(&front, &module).expect_err("the planted bug is caught");
    assert_eq!(diagnostic.code, gdsky_naga::INVALID_MODULE);
    let label = diagnostic.primary_label().expect("the error has a place in the shader");
    assert_eq!(front.db.name(label.file), "fixtures/freeman_sky.gdshader");
    let (line, _) = front.db.line_col(label.file, label.range.start);
    let text = std::fs::read_to_string(path).expect("readable");
    let expected =
        text.lines().position(|l| l.contains("return mie_scattering / mie_albedo;")).expect("the line exists") + 1;
    assert_eq!(line, expected, "{}", gdshader::diag::render_human(&front.db, std::slice::from_ref(&diagnostic), false));
}

//! The f64 evaluation (`gdsky_naga::lower_f64`): every shader gdsky converts widens to a module
//! naga validates with FLOAT64, whose SPIR-V (decorated `NoContraction`, as the driver gets it)
//! `spirv-val` accepts, and whose f32 lowering (and so the snapshots) does not change.

use gdsky_naga::{F64Output, lower, to_spirv};
use std::path::{Path, PathBuf};

fn shaders() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut out = vec![root.join("fixtures/freeman_sky.gdshader")];
    for dir in ["tests/shaders/valid", "tests/shaders/textures", "shaders"] {
        let Ok(entries) = std::fs::read_dir(root.join(dir)) else { continue };
        let mut found: Vec<_> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "gdshader"))
            .collect();
        found.sort();
        out.extend(found);
    }
    out
}

/// Runs `spirv-val --target-env vulkan1.1`; the error text on failure.
fn spirv_val(words: &[u32], name: &str) -> Result<(), String> {
    let path = std::env::temp_dir().join(format!("gdsky-f64-{}-{name}.spv", std::process::id()));
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
    std::fs::write(&path, bytes).map_err(|e| e.to_string())?;
    let out = std::process::Command::new("spirv-val")
        .args(["--target-env", "vulkan1.1"])
        .arg(&path)
        .output()
        .map_err(|e| format!("spirv-val does not run (Debian package spirv-tools): {e}"))?;
    let _ = std::fs::remove_file(&path);
    if out.status.success() {
        Ok(())
    } else {
        Err(format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr)))
    }
}

#[test]
fn every_shader_widens_validates_and_passes_spirv_val() {
    let mut failures = Vec::new();
    let mut count = 0;
    for path in shaders() {
        let front = gdshader::check_file(&path).expect("readable");
        // Shaders the f32 path refuses are not the f64 path's business.
        if front.shader.is_none() || gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).is_err() {
            continue;
        }
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("shader").to_string();
        for output in [F64Output::Nearest, F64Output::Residual] {
            match lower(
                &front,
                &gdsky_naga::LowerOptions { precision: gdsky_naga::Precision::F64(output), ..Default::default() },
            ) {
                Err(d) => failures.push(format!(
                    "{name} {output:?}: {}",
                    d.iter().map(|d| format!("{} {:?}", d.message, d.notes)).collect::<Vec<_>>().join("; ")
                )),
                Ok(lowered) => match to_spirv(&lowered) {
                    Err(e) => failures.push(format!("{name} {output:?}: SPIR-V: {e:?}")),
                    Ok(words) => {
                        // The binary the driver gets: with the exact-arithmetic decorations.
                        let words = gdsky_naga::exact_arithmetic(&words);
                        if let Err(e) = spirv_val(&words, &name) {
                            failures.push(format!("{name} {output:?}: spirv-val: {e}"));
                        }
                    }
                },
            }
        }
        count += 1;
    }
    eprintln!("{count} shaders widened");
    assert!(count > 0);
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}

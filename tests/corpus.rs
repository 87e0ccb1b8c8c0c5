//! The corpus (issue #14, build item 6): sky shaders from public Godot 4 projects under
//! permissive licences. `tests/corpus/` holds one sidecar per shader, `<project>__<name>.toml`,
//! naming its origin (repository, path, commit), licence and copyright, and the material values
//! its project gives it where one was found. The shaders themselves are not copied into this
//! repository (they were found through the project's search library, whose terms are that facts
//! carry over and code does not): `scripts/fetch-corpus.sh DIR` downloads each from its
//! repository at the recorded commit, and the pipeline test below runs on them
//! (`GDSKY_CORPUS_DIR=DIR cargo test --test corpus -- --ignored`).
//!
//! Every corpus shader goes through the whole pipeline:
//!
//! * **convert**: `gdsky::frontend` checks it and `gdsky_naga::lower` lowers it;
//! * **validate**: the WGSL is read back by naga's front end and validated, the SPIR-V passes
//!   `spirv-val`;
//! * **render**: a 64×32 panorama on the Vulkan adapter (lavapipe without a GPU) at the default
//!   uniforms, and again with the sidecar's material values if it has any, without NaN or Inf.
//!
//! A shader may fail only if [`EXPECTED_FAILURES`] lists it with the stage and the reason (the
//! diagnostic's code and message, or the validator's words); a listed shader that passes, or
//! fails elsewhere or otherwise, fails the test, so the table cannot rot. The test prints
//! `corpus: N shaders from P projects; convert C, validate V, render R (no NaN), failures F` and
//! writes the table of results to `CARGO_TARGET_TMPDIR/corpus/results.md` (copied into
//! `docs/corpus.md`).
//!
//! Without a Vulkan adapter or `spirv-val` the test fails with what is missing.

use gdsky::frontend as gdshader;
use skyref::{Projection, Scene};
use skyrun::{Gpu, SkyBuiltins, SkyShader, SubPasses, material_with_defaults, texture_defaults};
use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

const SIZE: (u32, u32) = (64, 32);

/// The licences a corpus shader may carry.
const LICENCES: &[&str] = &["MIT", "CC0-1.0", "Apache-2.0", "BSD-2-Clause", "BSD-3-Clause", "Unlicense", "Zlib"];

/// Where a shader stops.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stage {
    Convert,
    Validate,
    Render,
}

/// The shaders allowed to fail: (corpus name, stage, text the failure's reason contains).
const EXPECTED_FAILURES: &[(&str, Stage, &str)] = &[];

/// The sidecars: provenance (repository, path, commit, licence) and material values, facts
/// about each shader. The shaders themselves are not in this repository: they stay in their
/// projects and are fetched from there at the recorded commits (`scripts/fetch-corpus.sh DIR`).
fn corpus_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus")
}

/// Where `scripts/fetch-corpus.sh` put the shaders (`GDSKY_CORPUS_DIR`), files named as their
/// sidecars (`<project>__<name>.gdshader`, includes as the sidecar's `[includes]` say).
fn fetched_dir() -> PathBuf {
    std::env::var_os("GDSKY_CORPUS_DIR").map(PathBuf::from).unwrap_or_else(|| {
        panic!("set GDSKY_CORPUS_DIR to the folder `bash scripts/fetch-corpus.sh DIR` filled (the shaders are fetched from their projects, not kept here)")
    })
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("corpus").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

fn set_runtime_dir() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // SAFETY: called at the start of the test, before it starts any thread.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
}

/// A corpus shader and its sidecar.
struct Entry {
    name: String,
    project: String,
    licence: String,
    /// The file name the shader had in its project (its `#include`s resolve next to it).
    file_name: String,
    /// (path relative to the shader, corpus file) for each include.
    includes: Vec<(String, String)>,
    /// The sidecar's material values, as `gdsky convert --set` text.
    material: Vec<(String, String)>,
}

fn string(table: &toml::Table, key: &str, file: &str) -> String {
    table
        .get(key)
        .and_then(toml::Value::as_str)
        .unwrap_or_else(|| panic!("{file}: `{key}` is missing or not a string"))
        .to_string()
}

fn entries() -> Vec<Entry> {
    let mut names: Vec<String> = std::fs::read_dir(corpus_dir())
        .expect("tests/corpus is listable")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter_map(|f| f.strip_suffix(".toml").map(str::to_string))
        .collect();
    names.sort();
    names
        .into_iter()
        .map(|name| {
            let file = format!("{name}.toml");
            let text = std::fs::read_to_string(corpus_dir().join(&file)).unwrap_or_else(|e| panic!("{file}: {e}"));
            let table: toml::Table = text.parse().unwrap_or_else(|e| panic!("{file}: {e}"));
            for key in ["repo", "path", "commit", "copyright"] {
                assert!(!string(&table, key, &file).is_empty(), "{file}: `{key}` is empty");
            }
            let project = string(&table, "project", &file);
            assert!(name.starts_with(&format!("{project}__")), "{file}: the project is the name's prefix");
            let licence = string(&table, "licence", &file);
            assert!(LICENCES.contains(&licence.as_str()), "{file}: licence {licence} is not one the corpus takes");
            let path = string(&table, "path", &file);
            let file_name = path.rsplit('/').next().expect("a path").to_string();
            let includes = table
                .get("includes")
                .and_then(toml::Value::as_table)
                .map(|t| t.iter().map(|(k, v)| (k.clone(), v.as_str().expect("include file").to_string())).collect())
                .unwrap_or_default();
            let material = table
                .get("material")
                .and_then(|m| m.get("values"))
                .and_then(toml::Value::as_table)
                .map(|t| t.iter().map(|(k, v)| (k.clone(), v.as_str().expect("value text").to_string())).collect())
                .unwrap_or_default();
            Entry { name, project, licence, file_name, includes, material }
        })
        .collect()
}

/// What happened to one shader.
struct Outcome {
    reads_time: Option<bool>,
    samplers: Option<usize>,
    /// The stage that failed and why; `None` when every stage passed.
    failure: Option<(Stage, String)>,
}

fn first_error(diagnostics: &[gdshader::diag::Diagnostic]) -> String {
    diagnostics
        .iter()
        .find(|d| d.severity == gdshader::diag::Severity::Error)
        .map(|d| format!("{}: {}", d.code, d.message))
        .unwrap_or_else(|| "no error diagnostic".to_string())
}

fn non_finite(image: &[[f32; 4]]) -> usize {
    image.iter().flat_map(|p| &p[..3]).filter(|c| !c.is_finite()).count()
}

fn run(gpu: &Gpu, entry: &Entry) -> Outcome {
    let mut outcome = Outcome { reads_time: None, samplers: None, failure: None };
    let dir = scratch(&entry.name);
    let path = dir.join(&entry.file_name);
    let fetched = fetched_dir();
    std::fs::copy(fetched.join(format!("{}.gdshader", entry.name)), &path)
        .unwrap_or_else(|e| panic!("{}: not fetched into {} ({e})", entry.name, fetched.display()));
    for (relative, file) in &entry.includes {
        let to = dir.join(relative);
        std::fs::create_dir_all(to.parent().expect("a parent")).expect("include dir");
        std::fs::copy(fetched.join(file), &to).unwrap_or_else(|e| panic!("{file}: {e}"));
    }

    // Convert.
    let front = gdshader::check_file(&path).unwrap_or_else(|e| panic!("{}: {e}", entry.name));
    let Some(checked) = front.shader.as_ref() else {
        outcome.failure = Some((Stage::Convert, first_error(&front.diagnostics)));
        return outcome;
    };
    outcome.reads_time = Some(checked.builtins_used.contains("TIME"));
    outcome.samplers = Some(checked.uniforms.iter().filter(|u| u.type_name.contains("sampler")).count());
    let lowered = match gdsky_naga::lower(&front) {
        Ok(lowered) => lowered,
        Err(diagnostics) => {
            outcome.failure = Some((Stage::Convert, first_error(&diagnostics)));
            return outcome;
        }
    };

    // Validate: naga reads the WGSL back and validates it; spirv-val takes the SPIR-V.
    let wgsl = match gdsky_naga::to_wgsl(&lowered) {
        Ok(wgsl) => wgsl,
        Err(e) => {
            outcome.failure = Some((Stage::Validate, format!("WGSL: {e}")));
            return outcome;
        }
    };
    match naga::front::wgsl::parse_str(&wgsl) {
        Ok(module) => {
            if let Err(e) = gdsky_naga::validator().validate(&module) {
                outcome.failure = Some((Stage::Validate, format!("re-read WGSL does not validate: {e}")));
                return outcome;
            }
        }
        Err(e) => {
            outcome.failure = Some((Stage::Validate, format!("naga's WGSL front end: {e}")));
            return outcome;
        }
    }
    let words = match gdsky_naga::to_spirv(&lowered) {
        Ok(words) => words,
        Err(e) => {
            outcome.failure = Some((Stage::Validate, format!("SPIR-V: {e}")));
            return outcome;
        }
    };
    let spv = dir.join(format!("{}.spv", entry.name));
    std::fs::write(&spv, words.iter().flat_map(|w| w.to_le_bytes()).collect::<Vec<u8>>()).expect("writes");
    let out = Command::new("spirv-val")
        .args(["--target-env", "vulkan1.1"])
        .arg(&spv)
        .output()
        .unwrap_or_else(|e| panic!("cannot run spirv-val (Debian package spirv-tools): {e}"));
    if !out.status.success() {
        let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
        outcome.failure = Some((Stage::Validate, format!("spirv-val: {}", text.lines().next().unwrap_or(""))));
        return outcome;
    }

    // Render: default uniforms, then the project's material values.
    let shader = match SkyShader::new(gpu, &wgsl, SubPasses::of(&front)) {
        Ok(shader) => shader,
        Err(e) => {
            outcome.failure = Some((Stage::Render, format!("pipeline: {e}")));
            return outcome;
        }
    };
    let shader = shader
        .with_texture_defaults(texture_defaults(checked, &lowered))
        .with_material_textures(gpu, gdsky_naga::reflect::texture_bindings(checked, &lowered));
    let mut builtins = SkyBuiltins::from_scene(&Scene::default(), SIZE.0, SIZE.1);
    builtins.time = 1.5;
    let sets: Vec<(&str, Vec<(String, String)>)> = if entry.material.is_empty() {
        vec![("defaults", Vec::new())]
    } else {
        vec![("defaults", Vec::new()), ("material", entry.material.clone())]
    };
    for (label, set) in sets {
        let material = match material_with_defaults(checked, &lowered, &set) {
            Ok(material) => material,
            Err(e) => {
                outcome.failure = Some((Stage::Render, format!("{label}: {e}")));
                return outcome;
            }
        };
        match shader.render(gpu, Projection::Panorama, SIZE.0, SIZE.1, &builtins, &material) {
            Ok(rendered) => {
                let bad = non_finite(&rendered.pixels);
                if bad > 0 {
                    outcome.failure = Some((Stage::Render, format!("{label}: {bad} NaN/Inf channels")));
                    return outcome;
                }
            }
            Err(e) => {
                outcome.failure = Some((Stage::Render, format!("{label}: {e}")));
                return outcome;
            }
        }
    }
    outcome
}

#[test]
fn corpus_sidecars_are_complete() {
    let entries = entries();
    assert!(!entries.is_empty(), "the corpus is empty");
    for (name, _, _) in EXPECTED_FAILURES {
        assert!(entries.iter().any(|e| e.name == *name), "EXPECTED_FAILURES names {name}, which is not in the corpus");
    }
}

#[test]
#[ignore = "needs the shaders fetched from their projects: bash scripts/fetch-corpus.sh DIR, then GDSKY_CORPUS_DIR=DIR cargo test --test corpus -- --ignored"]
fn corpus_converts_validates_and_renders_finite() {
    set_runtime_dir();
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("this test needs a Vulkan adapter: {e}"));
    let entries = entries();
    let projects: BTreeSet<&str> = entries.iter().map(|e| e.project.as_str()).collect();
    let (mut converted, mut validated, mut rendered, mut failed) = (0, 0, 0, 0);
    let mut table = String::from(
        "| shader | project | licence | convert | validate | render | TIME | samplers | reason |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    let mut wrong = Vec::new();
    for entry in &entries {
        let outcome = run(&gpu, entry);
        let stage = outcome.failure.as_ref().map(|(s, _)| *s);
        let passed = |at: Stage| match stage {
            None => true,
            Some(failed_at) => (failed_at as u8) > (at as u8),
        };
        let mark = |at: Stage| match stage {
            Some(s) if s == at => "fail",
            _ if passed(at) => "ok",
            _ => "–",
        };
        converted += usize::from(passed(Stage::Convert));
        validated += usize::from(passed(Stage::Validate));
        rendered += usize::from(passed(Stage::Render));
        failed += usize::from(stage.is_some());
        let reason = outcome.failure.as_ref().map(|(_, r)| r.replace('|', "\\|")).unwrap_or_default();
        let yes_no = |b: Option<bool>| b.map_or("?", |b| if b { "yes" } else { "no" });
        let _ = writeln!(
            table,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            entry.name,
            entry.project,
            entry.licence,
            mark(Stage::Convert),
            mark(Stage::Validate),
            mark(Stage::Render),
            yes_no(outcome.reads_time),
            outcome.samplers.map_or("?".to_string(), |n| n.to_string()),
            reason
        );
        let expected = EXPECTED_FAILURES.iter().find(|(name, _, _)| *name == entry.name);
        match (expected, &outcome.failure) {
            (None, None) => {}
            (None, Some((s, r))) => wrong.push(format!("{}: fails at {s:?}, not listed: {r}", entry.name)),
            (Some((_, s, _)), None) => {
                wrong.push(format!("{}: listed as failing at {s:?} but passes; remove it from the table", entry.name))
            }
            (Some((_, s, text)), Some((at, r))) => {
                if s != at || !r.contains(text) {
                    wrong.push(format!("{}: listed as {s:?} `{text}`, fails at {at:?}: {r}", entry.name));
                }
            }
        }
    }
    println!(
        "corpus: {} shaders from {} projects; convert {converted}, validate {validated}, render {rendered} (no NaN), failures {failed}",
        entries.len(),
        projects.len()
    );
    println!("{table}");
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("corpus");
    std::fs::create_dir_all(&out).expect("out dir");
    std::fs::write(out.join("results.md"), &table).expect("writes the results table");
    assert!(wrong.is_empty(), "the corpus disagrees with EXPECTED_FAILURES:\n{}", wrong.join("\n"));
}

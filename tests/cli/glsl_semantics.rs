//! Where WGSL or naga's constant evaluator is stricter than GLSL (issue #10): one small sky
//! shader per construct, each converted by gdsky, its WGSL re-read by naga's WGSL front end and
//! validated, its SPIR-V checked by `spirv-val --target-env vulkan1.1`, and rendered on the
//! Vulkan adapter (lavapipe without a GPU) at 4×2; COLOR carries the construct's values and each
//! is compared with the value worked out by hand and written here.
//!
//! An int travels as two floats, its high and low 16 bits (`v >> 16`, `v & 0xFFFF`, both exact
//! in f32); a float travels as itself (the target is Rgba32Float; infinities, NaN and -0.0
//! survive the read-back, checked bit for bit). The semantics gdsky chooses where GLSL leaves the
//! result undefined are the ones of its run-time code (see the lowering essay): `x / 0 = x`,
//! `x % 0 = 0`, `INT_MIN / -1 = INT_MIN`, `INT_MIN % -1 = 0`, a shift amount keeps its low 5
//! bits, a float converts to an int by clamping, floats are IEEE-754 (`pow` is C's `powf`), a
//! non-void function that falls off its end returns zero.
//!
//! The shaders Godot refuses (an integer division by a constant zero where Godot evaluates it,
//! a read of a screen texture) are checked through the binary: the error's code and its
//! `file:line:col`.

use crate::common::{gdsky, scratch, text};
use crate::glsl_cases::{Case, X, cases, source};
use std::path::Path;
use std::process::Command;

fn matches(x: X, v: f32) -> bool {
    match x {
        X::F(f) => f.to_bits() == v.to_bits(),
        X::Inf => v == f32::INFINITY,
        X::NegInf => v == f32::NEG_INFINITY,
        X::NaN => v.is_nan(),
    }
}

fn spirv_val(path: &Path) -> Result<(), String> {
    let out = Command::new("spirv-val")
        .args(["--target-env", "vulkan1.1"])
        .arg(path)
        .output()
        .map_err(|e| format!("cannot run spirv-val (Debian package spirv-tools): {e}"))?;
    if out.status.success() {
        Ok(())
    } else {
        Err(format!("spirv-val: {}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr)))
    }
}

/// Converts, re-validates and renders one case; the values read back, or what failed.
fn run(gpu: &skyrun::Gpu, c: &Case, dir: &Path) -> Result<[f32; 3], String> {
    let path = dir.join(format!("{}.gdshader", c.name));
    std::fs::write(&path, source(c)).map_err(|e| e.to_string())?;
    let front = gdshader::check_file(&path).map_err(|e| e.to_string())?;
    let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).map_err(|ds| format!("{ds:#?}"))?;
    let wgsl = gdsky_naga::to_wgsl(&lowered).map_err(|e| format!("WGSL: {e:?}"))?;
    std::fs::write(path.with_extension("wgsl"), &wgsl).map_err(|e| e.to_string())?;
    let reread = naga::front::wgsl::parse_str(&wgsl)
        .map_err(|e| format!("naga's WGSL front end: {}", e.emit_to_string(&wgsl)))?;
    gdsky_naga::validator().validate(&reread).map_err(|e| format!("re-read WGSL does not validate: {e:?}"))?;
    let words = gdsky_naga::to_spirv(&lowered).map_err(|e| format!("SPIR-V: {e:?}"))?;
    let spv = path.with_extension("spv");
    std::fs::write(&spv, words.iter().flat_map(|w| w.to_le_bytes()).collect::<Vec<u8>>()).map_err(|e| e.to_string())?;
    spirv_val(&spv)?;
    let shader = skyrun::SkyShader::new(gpu, &wgsl, skyrun::SubPasses::default()).map_err(|e| format!("{e:?}"))?;
    let builtins = skyrun::SkyBuiltins::from_scene(&skyref::Scene::default(), 4, 2);
    let material = vec![0u8; lowered.material_size as usize];
    let rendered = shader
        .render(gpu, skyrun::Projection::Panorama, 4, 2, &builtins, &material)
        .map_err(|e| format!("render: {e:?}"))?;
    let first = rendered.pixels[0];
    for (i, p) in rendered.pixels.iter().enumerate() {
        let same = p.iter().zip(&first).take(3).all(|(a, b)| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()));
        if !same {
            return Err(format!("pixel {i} is {p:?}, pixel 0 {first:?}: every pixel should hold the same values"));
        }
    }
    Ok([first[0], first[1], first[2]])
}

#[test]
fn glsl_semantics() {
    let gpu = skytest::gpu();
    let dir = scratch("glsl_semantics", "cases");
    let mut failures = Vec::new();
    for c in cases() {
        match run(&gpu, &c, &dir) {
            Ok(got) => {
                if !c.expect.iter().zip(got).all(|(x, v)| matches(*x, v)) {
                    failures.push(format!("{}: expected {:?}, rendered {got:?}", c.name, c.expect));
                }
            }
            Err(e) => failures.push(format!("{}: {e}", c.name)),
        }
    }
    assert!(failures.is_empty(), "{} of {} cases failed:\n{}", failures.len(), cases().len(), failures.join("\n\n"));

    refusals(&dir);
}

/// What Godot refuses is refused, located in the user's terms; what it accepts with a
/// warning is accepted with one.
fn refusals(dir: &Path) {
    let check = |name: &str, src: &str| {
        let path = dir.join(format!("{name}.gdshader"));
        std::fs::write(&path, src).expect("write shader");
        let o = gdsky(&["check", path.to_str().expect("utf-8 path")]);
        (o.status.code(), text(&o), path.display().to_string())
    };
    // Godot 4.6: "Division by zero error." for a global constant, a local `const` and an
    // expression statement; "Modulo by zero error." for `%`.
    for (name, src, code_at, what) in [
        (
            "global_div_zero",
            "shader_type sky;\nconst int Z = 7 / 0;\nvoid sky() { COLOR = vec3(float(Z)); }\n",
            "2:15",
            "Division by zero error.",
        ),
        (
            "global_rem_zero",
            "shader_type sky;\nconst int Z = 7 % 0;\nvoid sky() { COLOR = vec3(float(Z)); }\n",
            "2:15",
            "Modulo by zero error.",
        ),
        (
            "local_const_div_zero",
            "shader_type sky;\nvoid sky() {\n  const int z = 7 / 0;\n  COLOR = vec3(float(z));\n}\n",
            "3:17",
            "Division by zero error.",
        ),
        (
            "statement_div_zero",
            "shader_type sky;\nvoid sky() {\n  int z;\n  z = 7 / 0;\n  COLOR = vec3(float(z));\n}\n",
            "4:7",
            "Division by zero error.",
        ),
    ] {
        let (status, out, file) = check(name, src);
        assert_eq!(status, Some(1), "{name}: {out}");
        assert!(out.contains("error[E310]") && out.contains(what), "{name}: {out}");
        assert!(out.contains(&format!("{file}:{code_at}")), "{name}: expected {file}:{code_at} in {out}");
        assert!(!out.contains("E601"), "{name}: {out}");
    }
    // A screen texture: declaring it is a warning, reading it an error at the read.
    let (status, out, _) = check(
        "screen_unread",
        "shader_type sky;\nuniform sampler2D s : hint_screen_texture;\nvoid sky() { COLOR = vec3(1.0); }\n",
    );
    assert_eq!(status, Some(0), "{out}");
    assert!(out.contains("warning[W005]"), "{out}");
    let (status, out, file) = check(
        "screen_read",
        "shader_type sky;\nuniform sampler2D s : hint_screen_texture;\nvoid sky() {\n  COLOR = texture(s, SKY_COORDS).rgb;\n}\n",
    );
    assert_eq!(status, Some(1), "{out}");
    assert!(out.contains("error[E405]") && out.contains(&format!("{file}:4:19")), "{out}");
}

//! `gdsky tune` through the binary at small sizes: the Freeman sky's cheapest knobs within a
//! budget, the specialized shader (knobs baked as consts) passing the pixel test against skyref
//! at those sample counts; a shader with a const knob tuned against its sampling truth; wrong
//! budgets refused. No timing assertions (which configuration is cheapest depends on the
//! machine; every assertion holds for whichever is chosen). Needs a Vulkan adapter (lavapipe on
//! a machine without a GPU).

use crate::common::{gdsky, scratch as scratch_in, text};
use skyref::{FreemanParams, Projection, Scene};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    scratch_in("tune_cli", name)
}

/// The `tuned:` line's knob values, e.g. `tuned:   view_samples=16, sun_samples=4 — …`.
fn tuned(out: &str) -> Vec<(String, i32)> {
    let line = out.lines().find(|l| l.starts_with("tuned:")).unwrap_or_else(|| panic!("no tuned line:\n{out}"));
    let settings = line.trim_start_matches("tuned:").split('—').next().unwrap_or_default();
    settings
        .split(',')
        .filter_map(|kv| kv.trim().split_once('='))
        .map(|(k, v)| (k.to_string(), v.trim().parse().unwrap_or_else(|_| panic!("{line}"))))
        .collect()
}

/// Renders a converted shader file on the GPU at its uniforms' defaults.
fn render_file(gpu: &skyrun::Gpu, path: &Path, scene: &Scene, (w, h): (u32, u32)) -> Vec<[f32; 4]> {
    let front = gdshader::check_file(path).expect("readable");
    let shader =
        front.shader.as_ref().unwrap_or_else(|| panic!("{} does not check: {:?}", path.display(), front.diagnostics));
    let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).expect("lowers");
    let wgsl = gdsky_naga::to_wgsl(&lowered).expect("WGSL");
    let sky = skyrun::SkyShader::new(gpu, &wgsl, skyrun::SubPasses::of(&front)).expect("compiles");
    let material = skyrun::material_with_defaults(shader, &lowered, &[]).expect("material");
    let builtins = skyrun::SkyBuiltins::from_scene(scene, w, h);
    sky.render(gpu, Projection::Panorama, w, h, &builtins, &material).expect("renders").pixels
}

#[test]
fn tuned_freeman_sky_passes_the_pixel_test_against_skyref_at_its_knobs() {
    let dir = scratch("freeman");
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/freeman_sky.gdshader");
    let args = [
        "tune",
        fixture.to_str().unwrap(),
        "--max-error",
        "0.2",
        "--suns",
        "10,60",
        "--size",
        "32x16",
        "--knob",
        "view_samples=8,16,32",
        "--knob",
        "sun_samples=4,8",
        "--runs",
        "1",
        "-o",
        dir.to_str().unwrap(),
    ];
    let o = gdsky(&args);
    assert!(o.status.success(), "{}", text(&o));
    let out = text(&o);
    assert!(out.contains("truth    skyref::truth"), "{out}");
    assert!(out.contains("(default)"), "the defaults are timed with the rest:\n{out}");
    let knobs = tuned(&out);
    let value = |n: &str| knobs.iter().find(|(k, _)| k == n).map(|(_, v)| *v).unwrap_or_else(|| panic!("{n}: {out}"));
    let (view, sun) = (value("view_samples"), value("sun_samples"));
    let path = dir.join("freeman_sky.tuned.gdshader");
    let source = std::fs::read_to_string(&path).expect("the tuned shader is written");
    assert!(source.contains(&format!("const int view_samples = {view};")), "{source}");
    assert!(
        source.contains(&format!("const int sun_samples = {sun};")) && !source.contains("uniform int view_samples")
    );
    assert!(
        std::fs::read_to_string(dir.join("tune.csv"))
            .expect("tune.csv")
            .starts_with("view_samples,sun_samples,time_ms")
    );

    // The pixel test of the demo (p99.9 ≤ 1e-3, no NaN/Inf) against skyref's f32 port of the
    // same sums at the tuned sample counts.
    let gpu = skytest::gpu();
    let params = FreemanParams::default().with_samples(view, sun);
    let size = (64, 32);
    for sun_deg in [10.0, 60.0] {
        let scene = Scene::default().with_sun(sun_deg, 0.0);
        let image = render_file(&gpu, &path, &scene, size);
        let reference = skyref::f32::render(&params, &scene, Projection::Panorama, size.0, size.1);
        let m = skyrun::compare(&image, &reference, 1e-4);
        assert_eq!(m.nan + m.inf, 0, "sun {sun_deg}°");
        assert!(m.p999_rel <= 1e-3, "sun {sun_deg}°, {view}/{sun} samples: p99.9 {:e}", m.p999_rel);
    }
}

#[test]
fn a_const_knob_is_tuned_against_the_sampling_truth() {
    let dir = scratch("const");
    let file = dir.join("riemann.gdshader");
    // A midpoint sum of ∫₀¹ e^(−4x) dx with STEPS steps: error ~ 1/STEPS², so it converges.
    std::fs::write(
        &file,
        "shader_type sky;\nconst int STEPS = 32;\nvoid sky() { float a = 0.0;\n\
         for (int i = 0; i < STEPS; i++) { a += exp(-4.0 * (float(i) + 0.5) / float(STEPS)); }\n\
         COLOR = vec3(a / float(STEPS)) * (1.5 + EYEDIR.y); }\n",
    )
    .unwrap();
    let args =
        ["tune", file.to_str().unwrap(), "--max-error", "0.01", "--suns", "30", "--size", "16x8", "--runs", "1", "-o"];
    let mut args: Vec<&str> = args.to_vec();
    args.push(dir.to_str().unwrap());
    let o = gdsky(&args);
    assert!(o.status.success(), "{}", text(&o));
    let out = text(&o);
    assert!(out.contains("the sampling truth: f64 at STEPS="), "{out}");
    let steps = tuned(&out)[0].1;
    // 4 steps: relative error ~3 %; 8: ~0.8 %. Whatever the timings, the tuned STEPS is within
    // the budget.
    assert!(steps >= 8, "{out}");
    let source = std::fs::read_to_string(dir.join("riemann.tuned.gdshader")).expect("written");
    assert!(source.contains(&format!("const int STEPS = {steps};")), "{source}");
    // An impossible budget: exit 1, no shader written.
    let dir2 = scratch("const_none");
    let mut args2: Vec<&str> =
        ["tune", file.to_str().unwrap(), "--max-error", "1e-9", "--suns", "30", "--size", "16x8"].to_vec();
    args2.extend(["--knob", "STEPS=2,4", "--runs", "1", "-o", dir2.to_str().unwrap()]);
    let o = gdsky(&args2);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(!dir2.join("riemann.tuned.gdshader").exists());
}

#[test]
fn bad_budgets_and_knobs_are_wrong_input() {
    let dir = scratch("bad");
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/freeman_sky.gdshader");
    for extra in [["--max-error", "0"], ["--max-error", "x"], ["--knob", "view_samples=0"]] {
        let mut args = vec!["tune", fixture.to_str().unwrap(), "-o", dir.to_str().unwrap()];
        if extra[0] == "--knob" {
            args.extend(["--max-error", "0.1"]);
        }
        args.extend(extra);
        let o = gdsky(&args);
        assert_eq!(o.status.code(), Some(1), "{extra:?}: {}", text(&o));
    }
}

/// The two tuned Freeman shaders in docs/measure (mean ≤ 5 % and ≤ 1 % over sun 0–90°) pass the
/// demo's pixel test against skyref's f32 port at the sample counts baked into them.
#[test]
fn the_documented_tuned_freeman_shaders_pass_the_pixel_test() {
    let gpu = skytest::gpu();
    for budget in ["5pct", "1pct"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join(format!("docs/measure/tune_freeman_{budget}/freeman_sky.tuned.gdshader"));
        let source = std::fs::read_to_string(&path).expect("the documented tuned shader");
        let baked = |name: &str| -> i32 {
            let at = source.find(&format!("const int {name} = ")).unwrap_or_else(|| panic!("{name} baked in {budget}"));
            let rest = &source[at + format!("const int {name} = ").len()..];
            rest[..rest.find(';').expect(";")].trim().parse().expect("an int")
        };
        let params = FreemanParams::default().with_samples(baked("view_samples"), baked("sun_samples"));
        let size = (48, 24);
        for sun_deg in [10.0, 60.0] {
            let scene = Scene::default().with_sun(sun_deg, 0.0);
            let image = render_file(&gpu, &path, &scene, size);
            let reference = skyref::f32::render(&params, &scene, Projection::Panorama, size.0, size.1);
            let m = skyrun::compare(&image, &reference, 1e-4);
            assert_eq!(m.nan + m.inf, 0, "{budget}, sun {sun_deg}°");
            assert!(m.p999_rel <= 1e-3, "{budget}, sun {sun_deg}°: p99.9 {:e}", m.p999_rel);
        }
    }
}

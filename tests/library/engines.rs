//! The engines behind `bench`, `stress` and `tune`, called from Rust without the binary, on a
//! small shader that is not Freeman-compatible (so each measures it against its own f64
//! evaluation at converged knobs: the whole path, on lavapipe).

use gdsky::engine::{Quiet, Setup};
use gdsky::measure::bench::{BenchOptions, bench};
use gdsky::measure::stress::{StressOptions, stress};
use gdsky::measure::tune::{TuneOptions, tune};
use std::path::PathBuf;

/// A sky whose colour is a midpoint sum over `steps`: its error against the integral falls as
/// 1/steps², so the sampling truth converges and more steps are more accurate.
const SUM_SKY: &str = "shader_type sky;
uniform int steps : hint_range(1, 64) = 4;
void sky() {
    float acc = 0.0;
    for (int i = 0; i < steps; i++) {
        float t = (float(i) + 0.5) / float(steps);
        acc += exp(-3.0 * t * (1.0 - 0.5 * EYEDIR.y)) / float(steps);
    }
    COLOR = vec3(acc, 0.8 * acc, 0.6 * acc) * (1.0 + max(dot(EYEDIR, LIGHT0_DIRECTION), 0.0));
}
";

fn shader(dir: &std::path::Path) -> PathBuf {
    let path = dir.join("sum_sky.gdshader");
    std::fs::write(&path, SUM_SKY).expect("writes the shader");
    path
}

#[test]
fn bench_measures_a_sweep_from_rust() {
    let dir = crate::common::scratch("engines", "bench");
    let options = BenchOptions {
        shaders: vec![Some(shader(&dir))],
        setup: Setup { width: 32, height: 16, ..Setup::default() },
        out_dir: dir.join("out"),
        runs: 1,
        knobs: vec!["steps=1,2,4".into()],
        ..BenchOptions::default()
    };
    let report = bench(&options, &Quiet).unwrap_or_else(|e| panic!("{e}"));
    let errors: Vec<f64> = report.configurations.iter().map(|c| c.errors.mean).collect();
    assert_eq!(report.configurations.len(), 3, "{}", report.text);
    assert!(errors.iter().all(|e| e.is_finite() && *e > 0.0), "{errors:?}");
    // The midpoint rule: halving the step cuts the error about four times.
    assert!(errors[0] > 2.0 * errors[1] && errors[1] > 2.0 * errors[2], "{errors:?}");
    assert!(report.csv.is_file() && report.plot.is_file());
    assert!(report.text.contains("the sampling truth"), "{}", report.text);
}

#[test]
fn stress_finds_no_nan_in_a_finite_sky_from_rust() {
    let dir = crate::common::scratch("engines", "stress");
    let options =
        StressOptions { shader: Some(shader(&dir)), quick: true, out_dir: dir.join("out"), ..Default::default() };
    let report = stress(&options, &Quiet).unwrap_or_else(|e| panic!("{e}"));
    assert!(report.cases.len() >= 5, "{:?}", report.cases);
    assert_eq!(report.nonfinite_at_defaults, (0, 0), "{}", report.text);
    assert!(report.markdown.is_file() && report.csv.is_file());
}

#[test]
fn tune_finds_the_cheapest_setting_within_a_budget_from_rust() {
    let dir = crate::common::scratch("engines", "tune");
    let options = TuneOptions {
        file: shader(&dir),
        max_error: (0.01, None),
        suns: vec![10.0, 60.0],
        size: (32, 16),
        time: 0.0,
        knobs: vec!["steps=1,2,4,8,16".into()],
        runs: 1,
        sampling: Default::default(),
        out_dir: dir.join("out"),
    };
    let report = tune(&options, &Quiet).unwrap_or_else(|e| panic!("{e}"));
    let tuned = report.shader.as_ref().unwrap_or_else(|| panic!("a setting within 1 %: {}", report.text));
    let setting = report.setting.clone().unwrap_or_default();
    // One step is off by far more than 1 %; sixteen are within it: the choice lies between.
    assert!(setting.starts_with("steps=") && setting != "steps=1", "{setting}");
    let text = std::fs::read_to_string(tuned).expect("the tuned shader");
    assert!(text.contains("const int steps"), "{text}");
    assert!(gdsky::convert("tuned.gdshader", &text, &gdsky::Options::default()).is_ok());
}

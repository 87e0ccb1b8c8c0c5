//! `gdsky compare --mode pixel|stats`: pixel mode prints one line (the CLI contract), stats mode a
//! second `ssim=… region_mean_max_rel=… region_var_max_rel=…` line, and `--min-ssim` /
//! `--max-region-rel` fail (exit 1) only when violated. Needs a Vulkan adapter (lavapipe).

use crate::common::{gdsky, scratch, text};
use std::path::Path;

#[test]
fn stats_mode_adds_a_line_and_its_bounds_decide_the_exit_code() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = scratch("compare_stats", "modes");
    let shader = root.join("tests/shaders/valid/debanding_gradient.gdshader");
    let (a, b) = (dir.join("godot.exr"), dir.join("none.exr"));
    for (mode, out) in [("godot", &a), ("none", &b)] {
        let o = gdsky(&[
            "render",
            &shader.to_string_lossy(),
            "--size",
            "64x32",
            "--debanding",
            mode,
            "-o",
            &out.to_string_lossy(),
        ]);
        assert!(o.status.success(), "{}", text(&o));
    }
    let (a, b) = (a.to_string_lossy().into_owned(), b.to_string_lossy().into_owned());
    let run = |extra: &[&str]| {
        let mut args = vec!["compare", a.as_str(), b.as_str()];
        args.extend_from_slice(extra);
        gdsky(&args)
    };
    let pixel = run(&[]);
    let lines: Vec<String> = String::from_utf8_lossy(&pixel.stdout).lines().map(String::from).collect();
    assert_eq!(lines.len(), 1, "{}", text(&pixel));
    assert!(lines[0].starts_with("max_rel=") && lines[0].contains(" pixels=2048"), "{}", lines[0]);
    let stats = run(&["--mode", "stats"]);
    let lines: Vec<String> = String::from_utf8_lossy(&stats.stdout).lines().map(String::from).collect();
    assert_eq!(lines.len(), 2, "{}", text(&stats));
    assert!(
        lines[1].starts_with("ssim=")
            && lines[1].contains(" region_mean_max_rel=")
            && lines[1].contains(" region_var_max_rel=")
    );
    let ssim: f64 = lines[1]["ssim=".len()..].split(' ').next().and_then(|v| v.parse().ok()).expect("a number");
    // The dither (±1/255 on a dark gradient) is visible in the preview: SSIM well below 1.
    assert!(ssim > 0.0 && ssim < 0.95, "{ssim}");
    assert_eq!(run(&["--mode", "stats", "--min-ssim", "0.99"]).status.code(), Some(1));
    assert_eq!(run(&["--mode", "stats", "--min-ssim", "0.1"]).status.code(), Some(0));
    // The region means agree to ~1.6e-3 (the noise averages out), the variances do not.
    assert_eq!(run(&["--mode", "stats", "--max-region-rel", "0.01"]).status.code(), Some(1));
    assert_eq!(run(&["--mode", "stats", "--max-region-rel", "100"]).status.code(), Some(0));
    assert_eq!(run(&["--min-ssim", "0.1"]).status.code(), Some(1), "bounds of stats mode need --mode stats");
    assert_eq!(run(&["--mode", "stats", "--min-ssim", "2"]).status.code(), Some(1), "a wrong input exits 1");
}

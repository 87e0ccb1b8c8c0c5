//! `gdsky bench` through the binary on a tiny sweep: the CSV's columns and rows, the plot, the
//! truth cache (reused, and recomputed when corrupt); two shaders on one chart (each sweeping
//! only the knobs it reads) with the comparison lines. No timing assertions. Needs a Vulkan
//! adapter (lavapipe on a machine without a GPU).

use crate::common::{gdsky_with, scratch as scratch_in, text};
use std::path::{Path, PathBuf};
use std::process::Output;

/// `gdsky` with its truth cache in `cache`.
fn gdsky(args: &[&str], cache: &Path) -> Output {
    gdsky_with(args, &[("GDSKY_CACHE_DIR", cache)])
}

fn scratch(name: &str) -> PathBuf {
    scratch_in("bench_cli", name)
}

const COLUMNS: &str = "shader,view_samples,sun_samples,time_ms,time_min_ms,time_max_ms,runs,timer,mean_rel,p99_rel,max_rel,\
                       mean_abs_tonemapped,nan,inf,pareto";

#[test]
fn tiny_sweep_writes_csv_plot_and_reuses_the_truth() {
    let dir = scratch("tiny");
    let (out, cache) = (dir.join("out"), dir.join("cache"));
    let args = [
        "bench",
        "--knob",
        "view_samples=4,8",
        "--knob",
        "sun_samples=2",
        "--size",
        "32x16",
        "--runs",
        "1",
        // A cheaper truth than the default 1024/256: this tests the plumbing, not convergence.
        "--truth-samples",
        "128,32",
        "-o",
        out.to_str().unwrap(),
    ];
    let o = gdsky(&args, &cache);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("truth: computed"), "{}", text(&o));
    assert!(
        text(&o).contains("truth    skyref f64 sums at 128/32 samples"),
        "the output names the truth:\n{}",
        text(&o)
    );
    assert!(text(&o).contains("Pareto front"), "{}", text(&o));

    let csv = std::fs::read_to_string(out.join("bench.csv")).expect("bench.csv written");
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], COLUMNS);
    assert_eq!(lines.len(), 3, "a header and one row per configuration:\n{csv}");
    for (line, (view, sun)) in lines[1..].iter().zip([("4", "2"), ("8", "2")]) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells.len(), COLUMNS.split(',').count(), "{line}");
        assert_eq!((cells[0], cells[1], cells[2]), ("freeman_sky (bundled)", view, sun), "{line}");
        assert_eq!(cells[6], "1", "{line}");
        // GPU timestamps where the adapter has them (lavapipe does), else wall time.
        assert!(["gpu_timestamps", "wall"].contains(&cells[7]), "{line}");
        let mean: f64 = cells[8].parse().expect("mean_rel is a number");
        let max: f64 = cells[10].parse().expect("max_rel is a number");
        // Four view samples against 128: a coarse quadrature, far from the truth but finite.
        assert!(mean > 1e-3 && mean <= max && max.is_finite(), "{line}");
        assert_eq!((cells[12], cells[13]), ("0", "0"), "{line}");
    }
    // At least one configuration is on the front, whatever the timings.
    assert!(lines[1..].iter().any(|l| l.ends_with(",1")), "{csv}");
    let png = std::fs::read(out.join("bench.png")).expect("bench.png written");
    assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"), "a PNG");

    // The second run takes the truth from the cache, with the same errors (columns mean_rel …
    // inf; not pareto, which follows the timings).
    let o = gdsky(&args, &cache);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("truth: cached"), "{}", text(&o));
    let again = std::fs::read_to_string(out.join("bench.csv")).unwrap();
    let errors =
        |csv: &str| csv.lines().map(|l| l.split(',').skip(8).take(6).collect::<Vec<_>>().join(",")).collect::<Vec<_>>();
    assert_eq!(errors(&csv), errors(&again));

    // A corrupt entry is recomputed, not trusted.
    let exr = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "exr"))
        .expect("a cached truth");
    std::fs::write(&exr, b"not an EXR").unwrap();
    let o = gdsky(&args, &cache);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("truth: computed"), "{}", text(&o));
    assert_eq!(errors(&csv), errors(&std::fs::read_to_string(out.join("bench.csv")).unwrap()));
}

#[test]
fn bad_knobs_are_wrong_input() {
    let dir = scratch("bad");
    for knob in ["sun_intensity=1,2", "view_samples=a", "view_samples"] {
        let o = gdsky(&["bench", "--knob", knob, "-o", dir.to_str().unwrap()], &dir);
        assert_eq!(o.status.code(), Some(1), "--knob {knob}: {}", text(&o));
    }
}

#[test]
fn two_shaders_on_one_chart_sweep_what_they_read_and_are_compared() {
    let dir = scratch("two");
    let (out, cache) = (dir.join("out"), dir.join("cache"));
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let original = root.join("fixtures/freeman_sky.gdshader");
    let fast = root.join("shaders/freeman_fast.gdshader");
    // The default truth (the integral), view_samples at its default sweeps: the original's
    // eight values (sun_samples fixed at its default 8), the fast sky's finer eleven.
    let args = [
        "bench",
        original.to_str().unwrap(),
        fast.to_str().unwrap(),
        "--knob",
        "sun_samples=8",
        "--size",
        "32x16",
        "--runs",
        "1",
        "-o",
        out.to_str().unwrap(),
    ];
    let o = gdsky(&args, &cache);
    assert!(o.status.success(), "{}", text(&o));
    let all = text(&o);
    assert!(all.contains("truth    skyref::truth"), "the output names the integral truth:\n{all}");
    assert!(all.contains("freeman_fast declares but never reads sun_samples"), "{all}");
    for name in ["freeman_sky", "freeman_fast"] {
        assert!(all.contains(&format!("Pareto front of {name}")), "{all}");
    }
    // The two lines of issue #12's "Must show", whatever the timings say (a configuration or
    // "none").
    assert!(all.contains("against freeman_sky's default (view_samples=24, sun_samples=8)"), "{all}");
    assert!(all.contains("freeman_fast at ≤ 1.0× freeman_sky's default time: "), "{all}");
    assert!(all.contains("freeman_fast at no more than freeman_sky's default's mean, p99 and max error: "), "{all}");

    let csv = std::fs::read_to_string(out.join("bench.csv")).expect("bench.csv written");
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], COLUMNS);
    let rows = |shader: &str| -> Vec<Vec<&str>> {
        lines[1..].iter().map(|l| l.split(',').collect::<Vec<_>>()).filter(|c| c[0] == shader).collect()
    };
    let (orig_rows, fast_rows) = (rows("freeman_sky"), rows("freeman_fast"));
    assert_eq!(orig_rows.len() + fast_rows.len(), lines.len() - 1, "{csv}");
    let views = |rows: &[Vec<&str>]| rows.iter().map(|c| c[1].parse::<i32>().expect("a count")).collect::<Vec<_>>();
    assert_eq!(views(&orig_rows), [4, 8, 12, 16, 24, 32, 48, 64], "{csv}");
    assert!(orig_rows.iter().all(|c| c[2] == "8"), "{csv}");
    assert_eq!(views(&fast_rows), [2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64], "{csv}");
    // freeman_fast never reads sun_samples: not swept, its cell empty.
    assert!(fast_rows.iter().all(|c| c[2].is_empty()), "{csv}");
    for c in orig_rows.iter().chain(&fast_rows) {
        let mean: f64 = c[8].parse().expect("mean_rel");
        assert!(mean.is_finite() && mean > 0.0 && (c[12], c[13]) == ("0", "0"), "{c:?}");
    }
    // Each shader has its own front.
    assert!(orig_rows.iter().any(|c| c[14] == "1") && fast_rows.iter().any(|c| c[14] == "1"), "{csv}");
    // The fast sky's quadrature is far better at equal samples (against the integral): at 24 view
    // samples its mean error is below the original's at 64.
    let mean_at = |rows: &[Vec<&str>], v: &str| rows.iter().find(|c| c[1] == v).map(|c| c[8].parse::<f64>().unwrap());
    assert!(mean_at(&fast_rows, "24") < mean_at(&orig_rows, "64"), "{csv}");
    let png = std::fs::read(out.join("bench.png")).expect("bench.png written");
    assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"), "a PNG");
}

#[test]
fn the_integral_truth_cannot_take_sample_counts_and_a_second_scene_is_refused() {
    let dir = scratch("truth_flags");
    let out = dir.to_str().unwrap();
    let o = gdsky(&["bench", "--truth", "integral", "--truth-samples", "64,16", "-o", out], &dir);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let scene = dir.join("s.toml");
    std::fs::write(&scene, "").unwrap();
    let o = gdsky(&["bench", "fixtures/freeman_sky.gdshader", scene.to_str().unwrap(), "-o", out], &dir);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("only the first FILE can be a scene file"), "{}", text(&o));
}

/// A shader that is not Freeman-compatible is benched against its sampling truth: its const
/// loop bound is found and swept (baked per configuration), the convergence is printed, and the
/// CSV has the knob's column; the error falls as the steps rise (a midpoint sum, error ~1/N²).
#[test]
fn a_shader_that_is_not_freeman_compatible_is_benched_against_its_sampling_truth() {
    let dir = scratch("any");
    let file = dir.join("riemann.gdshader");
    std::fs::write(
        &file,
        "shader_type sky;\nconst int STEPS = 16;\nuniform int unused_preset : hint_range(0, 3) = 1;\n\
         void sky() { float a = 0.0;\nfor (int i = 0; i < STEPS; i++) { a += exp(-4.0 * (float(i) + 0.5) / float(STEPS)); }\n\
         COLOR = vec3(a / float(STEPS)) * (1.5 + EYEDIR.y); }\n",
    )
    .unwrap();
    let out = dir.join("out");
    let args = ["bench", file.to_str().unwrap(), "--size", "16x8", "--runs", "1", "-o", out.to_str().unwrap()];
    let o = gdsky(&args, &dir);
    assert!(o.status.success(), "{}", text(&o));
    let t = text(&o);
    assert!(t.contains("the sampling truth") && t.contains("convergence"), "{t}");
    assert!(t.contains("  STEPS "), "the convergence table names the knob:\n{t}");
    let csv = std::fs::read_to_string(out.join("bench.csv")).expect("bench.csv");
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines[0].starts_with("shader,STEPS,time_ms"), "only the loop bound is swept:\n{csv}");
    let mean = |steps: &str| -> f64 {
        let line =
            lines.iter().find(|l| l.split(',').nth(1) == Some(steps)).unwrap_or_else(|| panic!("{steps}: {csv}"));
        line.split(',').nth(8).and_then(|v| v.parse().ok()).expect("mean_rel")
    };
    assert!(mean("2") > mean("8") && mean("8") > mean("32"), "{csv}");
    assert!(out.join("bench.png").exists());
    // skyref's truth flags do not apply to it.
    let o = gdsky(&["bench", file.to_str().unwrap(), "--truth", "integral", "-o", out.to_str().unwrap()], &dir);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
}

/// `--truth-supersample N` makes the sampling truth each pixel's area average: a shader with a
/// hard edge inside pixels is then off at the edge by its aliasing, which the pixel-centre truth
/// cannot see (there the only error is the loop's sampling). The flag is refused for skyref's
/// truth.
#[test]
fn a_supersampled_truth_sees_aliasing_at_a_hard_edge() {
    let dir = scratch("supersample");
    let file = dir.join("edge.gdshader");
    // EYEDIR.x = 0.3 crosses pixels of a 16×8 panorama away from their centres; the loop
    // converges fast (the knob exists so there is a truth to converge).
    std::fs::write(
        &file,
        "shader_type sky;\nconst int STEPS = 16;\n\
         void sky() { float a = 0.0;\nfor (int i = 0; i < STEPS; i++) { a += exp(-4.0 * (float(i) + 0.5) / float(STEPS)); }\n\
         COLOR = vec3(a / float(STEPS)) * (EYEDIR.x > 0.3 ? 1.0 : 0.25); }\n",
    )
    .unwrap();
    let default_max = |supersample: &str| -> f64 {
        let out = dir.join(format!("out{supersample}"));
        let args = [
            "bench",
            file.to_str().unwrap(),
            "--size",
            "16x8",
            "--runs",
            "1",
            "--truth-supersample",
            supersample,
            "-o",
            out.to_str().unwrap(),
        ];
        let o = gdsky(&args, &dir);
        assert!(o.status.success(), "{}", text(&o));
        let t = text(&o);
        let line = t.lines().find(|l| l.starts_with("default")).unwrap_or_else(|| panic!("{t}"));
        let max = line.split("max ").nth(1).and_then(|v| v.split(',').next()).unwrap_or_else(|| panic!("{line}"));
        max.trim().parse().unwrap_or_else(|_| panic!("{line}"))
    };
    let centre = default_max("1");
    let area = default_max("4");
    // Centre truth: STEPS=16 against the converged loop only (a smooth, small error). Area
    // truth: a pixel the edge crosses averages 1 and 0.25, so the centre sample is off by a
    // large fraction of it.
    assert!(centre < 0.05, "pixel-centre truth: max {centre}");
    assert!(area > 0.2, "area truth: max {area} (the edge's aliasing should show)");
    let freeman = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/freeman_sky.gdshader");
    let o = gdsky(&["bench", freeman.to_str().unwrap(), "--truth-supersample", "2"], &dir);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
}

/// `--sky-resolution full,half,quarter` adds the shading resolution as a dimension of the sweep:
/// a `sky_resolution` column (divisor 1, 2, 4), every configuration at each, measured against
/// the full-resolution truth. A sky with a hard edge loses accuracy as the resolution drops.
#[test]
fn the_sky_resolution_is_swept_against_the_full_resolution_truth() {
    let dir = scratch("sky_resolution");
    let file = dir.join("edge.gdshader");
    std::fs::write(
        &file,
        "shader_type sky;\nconst int STEPS = 8;\n\
         void sky() { float a = 0.0;\nfor (int i = 0; i < STEPS; i++) { a += exp(-4.0 * (float(i) + 0.5) / float(STEPS)); }\n\
         COLOR = vec3(a / float(STEPS)) * (EYEDIR.y > 0.3 ? 1.0 : 0.25); }\n",
    )
    .unwrap();
    let out = dir.join("out");
    let args = [
        "bench",
        file.to_str().unwrap(),
        "--size",
        "32x16",
        "--runs",
        "1",
        "--knob",
        "STEPS=64",
        "--sky-resolution",
        "full,half,quarter",
        "-o",
        out.to_str().unwrap(),
    ];
    let o = gdsky(&args, &dir);
    assert!(o.status.success(), "{}", text(&o));
    let csv = std::fs::read_to_string(out.join("bench.csv")).expect("bench.csv");
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines[0].starts_with("shader,STEPS,sky_resolution,time_ms"), "{csv}");
    let mean = |divisor: &str| -> f64 {
        let line = lines.iter().find(|l| l.split(',').nth(2) == Some(divisor)).unwrap_or_else(|| panic!("{csv}"));
        line.split(',').nth(9).and_then(|v| v.parse().ok()).expect("mean_rel")
    };
    let (full, half, quarter) = (mean("1"), mean("2"), mean("4"));
    // Full: only the 64-step loop's sampling error against the converged truth (~1e-3).
    assert!(full < 5e-3, "{csv}");
    assert!(half > 2.0 * full && quarter > half, "the edge blurs over more pixels as the resolution drops:\n{csv}");
    let bad = ["bench", file.to_str().unwrap(), "--sky-resolution", "full,eighth", "-o", out.to_str().unwrap()];
    let o = gdsky(&bad, &dir);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("not a sky resolution"), "{}", text(&o));
}

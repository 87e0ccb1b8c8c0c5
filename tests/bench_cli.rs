//! `gdsky bench` through the binary on a tiny sweep: the CSV's columns and rows, the plot, the
//! truth cache (reused, and recomputed when corrupt). No timing assertions. Needs a Vulkan
//! adapter (lavapipe on a machine without a GPU).

mod common;

use common::{gdsky_with, scratch as scratch_in, text};
use std::path::{Path, PathBuf};
use std::process::Output;

/// `gdsky` with its truth cache in `cache`.
fn gdsky(args: &[&str], cache: &Path) -> Output {
    gdsky_with(args, &[("GDSKY_CACHE_DIR", cache)])
}

fn scratch(name: &str) -> PathBuf {
    scratch_in("bench_cli", name)
}

const COLUMNS: &str = "view_samples,sun_samples,time_ms,time_min_ms,time_max_ms,runs,timer,mean_rel,p99_rel,max_rel,\
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
    assert!(text(&o).contains("Pareto front"), "{}", text(&o));

    let csv = std::fs::read_to_string(out.join("bench.csv")).expect("bench.csv written");
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], COLUMNS);
    assert_eq!(lines.len(), 3, "a header and one row per configuration:\n{csv}");
    for (line, (view, sun)) in lines[1..].iter().zip([("4", "2"), ("8", "2")]) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells.len(), COLUMNS.split(',').count(), "{line}");
        assert_eq!((cells[0], cells[1]), (view, sun), "{line}");
        assert_eq!(cells[5], "1", "{line}");
        // GPU timestamps where the adapter has them (lavapipe does), else wall time.
        assert!(["gpu_timestamps", "wall"].contains(&cells[6]), "{line}");
        let mean: f64 = cells[7].parse().expect("mean_rel is a number");
        let max: f64 = cells[9].parse().expect("max_rel is a number");
        // Four view samples against 128: a coarse quadrature, far from the truth but finite.
        assert!(mean > 1e-3 && mean <= max && max.is_finite(), "{line}");
        assert_eq!((cells[11], cells[12]), ("0", "0"), "{line}");
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
        |csv: &str| csv.lines().map(|l| l.split(',').skip(7).take(6).collect::<Vec<_>>().join(",")).collect::<Vec<_>>();
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

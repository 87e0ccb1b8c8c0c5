//! The rendering commands end to end, through the binary: `render`, `reference`, `compare`,
//! `demo`, their outputs and their exit codes (0 ok, 1 wrong input or failed comparison,
//! 2 wrong environment). They need a Vulkan adapter (lavapipe on a machine without a GPU).

use crate::common::{gdsky, gdsky_with, scratch as scratch_in, text};
use std::path::{Path, PathBuf};
use std::process::Output;

fn scratch(name: &str) -> PathBuf {
    scratch_in("render_cli", name)
}

fn arg(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Parses compare's one line into (max_rel, p999_rel, nan, inf, pixels).
fn compare_line(o: &Output) -> (f64, f64, usize, usize, usize) {
    let stdout = String::from_utf8_lossy(&o.stdout);
    let line = stdout.lines().next().unwrap_or_default();
    let field = |key: &str| -> String {
        line.split_whitespace()
            .find_map(|kv| kv.strip_prefix(&format!("{key}=")).map(str::to_string))
            .unwrap_or_else(|| panic!("no {key}= in `{line}`"))
    };
    let keys: Vec<&str> = line.split_whitespace().filter_map(|kv| kv.split_once('=').map(|(k, _)| k)).collect();
    assert_eq!(keys, ["max_rel", "mean_rel", "p999_rel", "nan", "inf", "pixels"], "{line}");
    let f = |k| field(k).parse::<f64>().expect("number");
    let n = |k| field(k).parse::<usize>().expect("count");
    (f("max_rel"), f("p999_rel"), n("nan"), n("inf"), n("pixels"))
}

#[test]
fn render_reference_compare_round_trip() {
    let dir = scratch("round_trip");
    let (gpu, cpu, png) = (dir.join("gpu.exr"), dir.join("cpu.exr"), dir.join("gpu.png"));
    let scene = ["--size", "48x24", "--sun", "-4,30", "--position", "0,2000,0"];
    let o = gdsky(&[&["render", "-o", arg(&gpu), "--png", arg(&png)], &scene[..]].concat());
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("adapter: "), "render names its adapter: {}", text(&o));
    let o = gdsky(&[&["reference", "-o", arg(&cpu)], &scene[..]].concat());
    assert!(o.status.success(), "{}", text(&o));
    let image = skyrun::read_exr(&gpu).expect("render wrote an EXR");
    assert_eq!((image.width, image.height), (48, 24));
    assert!(png.is_file());

    let heatmap = dir.join("heat.png");
    let o = gdsky(&["compare", arg(&gpu), arg(&cpu), "--max-rel", "1e-2", "--heatmap", arg(&heatmap)]);
    assert!(o.status.success(), "{}", text(&o));
    let (max_rel, p999, nan, inf, pixels) = compare_line(&o);
    assert_eq!((nan, inf, pixels), (0, 0, 48 * 24));
    assert!(p999 <= 1e-3 && max_rel <= 1e-2, "{}", text(&o));
    assert!(heatmap.is_file());

    // A reference of a different scene fails a tight bound: exit 1.
    let other = dir.join("other.exr");
    let o = gdsky(&[&["reference", "-o", arg(&other), "--sun", "10,30"], &scene[..2]].concat());
    assert!(o.status.success(), "{}", text(&o));
    let o = gdsky(&["compare", arg(&gpu), arg(&other), "--max-rel", "1e-3"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
}

#[test]
fn cubemap_renders_six_faces_that_match_the_reference() {
    let dir = scratch("cubemap");
    let (gpu, cpu) = (dir.join("cube.exr"), dir.join("cube_ref.exr"));
    let o = gdsky(&["render", "--projection", "cubemap", "--size", "16x16", "-o", arg(&gpu)]);
    assert!(o.status.success(), "{}", text(&o));
    let o = gdsky(&["reference", "--projection", "cubemap", "--size", "16x16", "-o", arg(&cpu)]);
    assert!(o.status.success(), "{}", text(&o));
    let image = skyrun::read_exr(&gpu).expect("EXR");
    assert_eq!((image.width, image.height), (96, 16), "a 6x1 strip of 16x16 faces");
    let o = gdsky(&["compare", arg(&gpu), arg(&cpu), "--max-rel", "1e-2"]);
    assert!(o.status.success(), "{}", text(&o));
    let (_, p999, ..) = compare_line(&o);
    assert!(p999 <= 1e-3, "{}", text(&o));
    // Face 3 (−Y) looks at the ground, face 2 (+Y) at the zenith: the ground is darker.
    let mean = |face: usize| {
        let mut sum = 0.0;
        for y in 0..16 {
            for x in 0..16 {
                sum += image.pixels[y * 96 + face * 16 + x][2];
            }
        }
        sum / 256.0
    };
    assert!(mean(3) < mean(2), "−Y face {} vs +Y face {}", mean(3), mean(2));
}

#[test]
fn bad_input_is_exit_1_and_a_bad_environment_exit_2() {
    let dir = scratch("errors");
    let out = dir.join("x.exr");
    // An invalid shader: its diagnostic, exit 1, no output.
    let shader = dir.join("bad.gdshader");
    std::fs::write(&shader, "shader_type sky;\nvoid sky() { COLOR = vec2(1.0); }\n").expect("write");
    let o = gdsky(&["render", arg(&shader), "-o", arg(&out)]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("bad.gdshader:2:"), "{}", text(&o));
    assert!(!out.exists());
    // Malformed flags and uniforms: exit 1.
    for args in [
        &["render", "-o", arg(&out), "--size", "0x4"][..],
        &["render", "-o", arg(&out), "--sun", "ten"],
        &["render", "-o", arg(&out), "--set", "no_such_uniform=1"],
        &["render", "-o", arg(&out), "--set", "view_samples=1.5"],
        &["render", "-o", arg(&out), "--projection", "cubemap", "--size", "8x4"],
        &["reference", "-o", arg(&out), "--set", "view_samples"],
    ] {
        let o = gdsky(args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", text(&o));
    }
    assert!(!out.exists());
    // Unreadable inputs and unwritable outputs: exit 2, nothing half-written left behind.
    let o = gdsky(&["render", arg(&dir.join("missing.gdshader")), "-o", arg(&out)]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let o = gdsky(&["compare", arg(&dir.join("missing.exr")), arg(&out)]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let o = gdsky(&["reference", "--size", "8x4", "-o", arg(&dir.join("no/such/dir/x.exr"))]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let leftovers: Vec<_> = std::fs::read_dir(&dir).expect("dir").flatten().map(|e| e.file_name()).collect();
    assert_eq!(leftovers, [std::ffi::OsString::from("bad.gdshader")], "stray files");
    // A garbage EXR is a clear error, not a panic.
    let garbage = dir.join("garbage.exr");
    std::fs::write(&garbage, b"not an exr at all").expect("write");
    let o = gdsky(&["compare", arg(&garbage), arg(&garbage)]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("garbage.exr"), "{}", text(&o));
}

#[test]
fn no_vulkan_adapter_is_exit_2_with_the_package_to_install() {
    let dir = scratch("no_adapter");
    // Point the Vulkan loader at a driver list that does not exist.
    let none = dir.join("none.json");
    let o = gdsky_with(
        &["render", "-o", arg(&dir.join("x.exr"))],
        &[("VK_ICD_FILENAMES", &none), ("VK_DRIVER_FILES", &none)],
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("mesa-vulkan-drivers"), "{}", text(&o));
}

#[test]
fn demo_writes_its_outputs_and_passes() {
    let dir = scratch("demo");
    let o = gdsky(&["demo", "-o", arg(&dir)]);
    assert!(o.status.success(), "{}", text(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("PASS"), "{stdout}");
    for name in ["freeman_sky.wgsl", "freeman_sky.spv", "freeman_sky.json", "panorama.exr", "camera.exr", "demo.png"] {
        assert!(dir.join(name).is_file(), "{name} missing: {stdout}");
    }
}

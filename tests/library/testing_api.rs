//! `gdsky::testing` (feature `testing`, which `cargo test --workspace` turns on through
//! examples/snapshot-tests) end to end on the adapter: the golden workflow a user goes through —
//! no golden, review, pass, a changed constant — the adapter policy, and port tests of SPIR-V
//! and of a port that breaks the interface. examples/snapshot-tests holds the goldens, the
//! hand ports and the text snapshots a user copies.

use gdsky::testing::{PortTest, Snapshot, Verdict, View};
use std::path::{Path, PathBuf};

/// gradient_sun.gdshader with its sun glow replaced.
fn gradient_sun(dir: &Path, sun_glow: &str) -> PathBuf {
    let source = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders/gradient_sun.gdshader"))
        .expect("the shipped shader");
    let changed = source.replace("sun_glow : hint_range(0.0, 4.0) = 0.6", &format!("sun_glow = {sun_glow}"));
    assert_ne!(source, changed, "the constant to change is still in the shader");
    let path = dir.join("sky.gdshader");
    std::fs::write(&path, changed).expect("scratch is writable");
    path
}

fn snapshot(dir: &Path, shader: &Path) -> Snapshot {
    let (dir, shader) = (dir.display().to_string(), shader.display().to_string());
    Snapshot::new("sky", &shader).directory(&dir).size(64, 32)
}

#[test]
fn golden_missing_then_reviewed_then_passing_then_a_changed_constant_fails_with_the_diff_files() {
    let dir = crate::common::scratch("testing_api", "golden_workflow");
    let at = |name: &str| dir.join(name);

    // No golden: the render is written for review and the test fails, saying what to do.
    let shader = gradient_sun(&dir, "0.6");
    let missing = snapshot(&dir, &shader).check();
    assert_eq!(missing.verdict, Verdict::Missing, "{}", missing.report());
    assert!(missing.report().contains("review it and commit it"), "{}", missing.report());
    assert!(at("sky.new.exr").is_file() && at("sky.new.png").is_file());

    // The reviewer accepts it (what UPDATE_SNAPSHOTS=1 does, by hand): the next run passes,
    // bit for bit, and leaves no review files.
    std::fs::rename(at("sky.new.exr"), at("sky.exr")).expect("rename");
    std::fs::rename(at("sky.new.png"), at("sky.png")).expect("rename");
    let passed = snapshot(&dir, &shader).check();
    assert_eq!(passed.verdict, Verdict::Passed, "{}", passed.report());
    assert_eq!(passed.views.len(), View::defaults().len());
    assert_eq!(passed.max_over_views(|m| m.max_rel), 0.0, "same adapter, same gdsky: identical");
    assert!(!at("sky.new.exr").exists());

    // One constant changed: the glow around the sun is 5 % brighter. It fails with the render, its preview
    // and the heatmap beside the golden, and names the worst pixels with their directions,
    // which look at the sun.
    let shader = gradient_sun(&dir, "0.63");
    let changed = snapshot(&dir, &shader).check();
    assert_eq!(changed.verdict, Verdict::Mismatch, "{}", changed.report());
    for file in ["sky.new.exr", "sky.new.png", "sky.diff.png"] {
        assert!(at(file).is_file(), "{file} is written on a mismatch");
        assert!(changed.files.contains(&at(file)), "{file} is reported");
    }
    let report = changed.report();
    assert!(report.contains("pixel (") && report.contains("EYEDIR"), "{report}");
    let view = changed.worst_view().expect("views");
    let worst = view.worst.first().expect("a worst pixel");
    let sun = view.view.scene.sun().direction();
    let angle = glam::DVec3::from(worst.eyedir).angle_between(sun).to_degrees();
    assert!(angle < 10.0, "the worst pixel looks {angle:.1}° away from the sun: {worst:?}");

    // Another size is another golden: refused with what changed, not compared.
    let resized = snapshot(&dir, &shader).size(32, 16).check();
    assert!(
        matches!(&resized.verdict, Verdict::Error(m) if m.contains("changed since the golden was made")),
        "{}",
        resized.report()
    );
}

#[test]
fn a_golden_from_another_adapter_is_skipped() {
    let dir = crate::common::scratch("testing_api", "other_adapter");
    let shader = gradient_sun(&dir, "0.6");
    let first = snapshot(&dir, &shader).views(View::defaults().into_iter().take(1)).check();
    assert_eq!(first.verdict, Verdict::Missing, "{}", first.report());
    // The golden as another machine would have made it: the same pixels and views, another adapter.
    let new = dir.join("sky.new.exr");
    let image = skyrun::read_exr(&new).expect("the render");
    let notes = skyrun::read_exr_notes(&new).expect("its notes");
    assert!(notes.iter().any(|(k, v)| k == "gdsky.adapter" && *v == first.adapter), "{notes:?}");
    assert!(notes.iter().any(|(k, v)| k == "gdsky.version" && v == env!("CARGO_PKG_VERSION")), "{notes:?}");
    let other: Vec<(&str, &str)> = notes
        .iter()
        .map(|(k, v)| (k.as_str(), if k == "gdsky.adapter" { "Some Other GPU" } else { v.as_str() }))
        .collect();
    skyrun::write_exr_annotated(&dir.join("sky.exr"), &image, &other).expect("write");
    let outcome = snapshot(&dir, &shader).views(View::defaults().into_iter().take(1)).check();
    let why = outcome.skipped_because().unwrap_or_else(|| panic!("skipped: {}", outcome.report()));
    assert!(why.contains("Some Other GPU") && why.contains(&first.adapter), "{why}");
}

#[test]
fn a_spirv_port_passes_and_a_port_without_an_entry_point_is_refused() {
    let dir = crate::common::scratch("testing_api", "ports");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let original = root.join("shaders/gradient_sun.gdshader");
    let converted = gdsky::convert_file(&original, &gdsky::Options::default()).expect("readable").expect("converts");
    let spv = dir.join("port.spv");
    std::fs::write(&spv, converted.spirv_bytes()).expect("write");
    let original = original.display().to_string();
    let outcome = PortTest::new(&original, &spv.display().to_string()).size(64, 32).check();
    assert_eq!(outcome.verdict, Verdict::Passed, "{}", outcome.report());

    let no_camera = converted.wgsl.replace("fn fs_camera(", "fn fs_camera_renamed(");
    let wgsl = dir.join("port.wgsl");
    std::fs::write(&wgsl, no_camera).expect("write");
    let refused = PortTest::new(&original, &wgsl.display().to_string()).size(64, 32).check();
    assert!(
        matches!(&refused.verdict, Verdict::Error(m) if m.contains("no entry point `fs_camera`")),
        "{}",
        refused.report()
    );
}

#[test]
fn a_cubemap_snapshot_reports_the_face_of_its_worst_pixel() {
    let dir = crate::common::scratch("testing_api", "cubemap");
    let cube = |shader: &Path| {
        snapshot(&dir, shader)
            .views(View::defaults().into_iter().skip(2).take(1))
            .projection(gdsky::Projection::CubeFace(0))
            .size(16, 16)
            .check()
    };
    let first = cube(&gradient_sun(&dir, "0.6"));
    assert_eq!(first.verdict, Verdict::Missing, "{}", first.report());
    let image = skyrun::read_exr(&dir.join("sky.new.exr")).expect("the render");
    assert_eq!((image.width, image.height), (6 * 16, 16), "the six faces side by side");
    std::fs::rename(dir.join("sky.new.exr"), dir.join("sky.exr")).expect("rename");

    let changed = cube(&gradient_sun(&dir, "0.63"));
    assert_eq!(changed.verdict, Verdict::Mismatch, "{}", changed.report());
    let worst = changed.views[0].worst.first().expect("a worst pixel");
    // The sun is at azimuth 180° (+Z), 20° up: on the +Z face (layer 4).
    assert_eq!(worst.face, Some(4), "{worst:?}");
    assert!(worst.x < 16 && worst.y < 16, "within the face: {worst:?}");
}

//! The hand ports against gdsky's conversion of their originals, in gdsky's default views: the
//! Freeman sky, and the noise cloud sky from its Godot material (values and noise texture). Then
//! the same ports with one deliberate mistake each, which must fail: a port test that cannot fail
//! proves nothing.

use gdsky::testing::{Outcome, PortTest, Verdict, View, assert_port_matches};
use std::path::PathBuf;

#[test]
fn freeman_port_matches_the_original() {
    assert_port_matches("shaders/freeman_sky.gdshader", "ports/freeman_sky.wgsl", &View::defaults());
}

#[test]
fn noise_port_matches_the_material() {
    let outcome = PortTest::new("godot/materials/noise_clouds.tres", "ports/noise_sky.wgsl")
        .rename("cloud_cover", "coverage")
        .assert();
    println!("{}", outcome.report());
}

#[test]
fn freeman_port_with_rayleigh_and_mie_phases_swapped_fails() {
    let wrong = mistake(
        "ports/freeman_sky.wgsl",
        "get_rayleigh_scattering() * rayleigh_phase\n                + step_optical_depth.y * material.mie_scattering * mie_phase",
        "get_rayleigh_scattering() * mie_phase\n                + step_optical_depth.y * material.mie_scattering * rayleigh_phase",
    );
    expect_mismatch(PortTest::new("shaders/freeman_sky.gdshader", &wrong).check());
}

/// The texture read with its coordinates transposed: the same clouds, turned about the zenith.
#[test]
fn noise_port_with_texture_coordinates_transposed_fails() {
    let wrong = mistake("ports/noise_sky.wgsl", "let uv = eyedir.xz", "let uv = eyedir.zx");
    let test = PortTest::new("godot/materials/noise_clouds.tres", &wrong).rename("cloud_cover", "coverage");
    expect_mismatch(test.check());
}

/// The port at `port` with `right` replaced by `wrong`, written to the test's scratch folder.
fn mistake(port: &str, right: &str, wrong: &str) -> String {
    let source = std::fs::read_to_string(port).expect("the port is there");
    assert!(source.contains(right), "{port} no longer contains the text the mistake replaces");
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("wrong_{}", port.replace('/', "_")));
    std::fs::write(&path, source.replace(right, wrong)).expect("the scratch folder is writable");
    path.display().to_string()
}

fn expect_mismatch(outcome: Outcome) {
    println!("{}", outcome.report());
    if outcome.skipped_because().is_some() {
        // No adapter here: the skip is reported (and a failure under GDSKY_FAIL_ON_SKIP=1).
        let _ = outcome.assert();
        return;
    }
    assert_eq!(outcome.verdict, Verdict::Mismatch, "the wrong port must fail:\n{}", outcome.report());
    let worst = outcome.worst_view().expect("views were compared");
    assert!(!worst.worst.is_empty(), "the report names the worst pixels");
}

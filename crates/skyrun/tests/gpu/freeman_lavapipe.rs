//! The Freeman sky converted by gdsky, rendered on a Vulkan device (lavapipe on a machine
//! without a GPU), against skyref's f32 reference.
//!
//! One test function, so the environment is set before any thread reads it and one device
//! serves both projections. Without a Vulkan adapter the test fails: it does not skip.

use skyref::{FreemanParams, Projection, Scene};
use skyrun::{SkyBuiltins, compare, freeman_material, render, worst_pixels};
use std::time::Instant;

const WIDTH: u32 = 64;
const HEIGHT: u32 = 32;
/// Relative errors are |gpu − ref| / max(|ref|, FLOOR).
const FLOOR: f32 = 1e-4;
/// Bound on the 99th percentile of the relative error.
const P99_BOUND: f64 = 1e-3;

#[test]
fn freeman_on_the_gpu_matches_skyref() {
    let start = Instant::now();

    let gpu = crate::common::gpu();
    let (_, lowered, wgsl) = crate::common::converted_freeman();
    let params = FreemanParams::default();
    let material = freeman_material(&lowered, &params);

    let panorama_scene = Scene::default().with_sun(10.0, 30.0).with_position(glam::DVec3::new(0.0, 1.0, 0.0));
    let camera_scene = panorama_scene.with_fov(90.0).with_view(0.0, 10.0);

    let mut failures = Vec::new();
    for (projection, scene) in [(Projection::Panorama, panorama_scene), (Projection::Camera, camera_scene)] {
        let builtins = SkyBuiltins::from_scene(&scene, WIDTH, HEIGHT);
        let t = Instant::now();
        let gpu_image = render(&gpu, &wgsl, projection, WIDTH, HEIGHT, &builtins, &material)
            .unwrap_or_else(|e| panic!("{projection:?}: render failed: {e}"));
        let gpu_time = t.elapsed();
        let reference = skyref::f32::render(&params, &scene, projection, WIDTH, HEIGHT);
        let m = compare(&gpu_image, &reference, FLOOR);
        eprintln!("{projection:?} {WIDTH}×{HEIGHT} (GPU {gpu_time:.2?}): {m}");
        for p in worst_pixels(&gpu_image, &reference, FLOOR, WIDTH as usize, 8) {
            eprintln!("    {p}");
        }
        if m.nan != 0 || m.inf != 0 {
            failures.push(format!("{projection:?}: {} NaN and {} Inf channels", m.nan, m.inf));
        }
        if m.p99_rel > P99_BOUND {
            failures.push(format!("{projection:?}: p99 relative error {:.3e} > {P99_BOUND:.0e}", m.p99_rel));
        }
    }
    // The comparison has power: the sun mirrored to azimuth −30° must fail it by far.
    let mirrored = panorama_scene.with_sun(10.0, -30.0);
    let builtins = SkyBuiltins::from_scene(&mirrored, WIDTH, HEIGHT);
    let wrong = render(&gpu, &wgsl, Projection::Panorama, WIDTH, HEIGHT, &builtins, &material).expect("render");
    let reference = skyref::f32::render(&params, &panorama_scene, Projection::Panorama, WIDTH, HEIGHT);
    let m = compare(&wrong, &reference, FLOOR);
    eprintln!("negative control (sun at −30° against +30°): {m}");
    if m.p99_rel < 100.0 * P99_BOUND {
        failures.push(format!("a mirrored sun passes the comparison (p99 {:.3e}): the check has no power", m.p99_rel));
    }

    // Errors come back as values, not panics from wgpu's uncaptured-error handler.
    let builtins = SkyBuiltins::from_scene(&panorama_scene, WIDTH, HEIGHT);
    let bad_wgsl = render(&gpu, "fn oops(", Projection::Panorama, 4, 4, &builtins, &[]);
    eprintln!("invalid WGSL: {bad_wgsl:?}");
    if !matches!(bad_wgsl, Err(skyrun::RenderError::Binding(skyrun::bindings::BindingError::Parse(_)))) {
        failures.push(format!("invalid WGSL gave {bad_wgsl:?}"));
    }
    let no_material = render(&gpu, &wgsl, Projection::Panorama, 4, 4, &builtins, &[]);
    eprintln!("no material: {no_material:?}");
    if !matches!(no_material, Err(skyrun::RenderError::Material { .. })) {
        failures.push(format!("a missing material block gave {no_material:?}"));
    }

    eprintln!("total {:.2?}", start.elapsed());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

//! The converted Freeman sky on the Vulkan adapter (lavapipe without a GPU) against skyref's
//! f32 reference over the scene matrix of issue #4: sun elevations −4°, 0.5°, 10°, 45° and 90°,
//! camera altitudes 1 m, 2 km and 30 km, panorama and camera projections (30 renders).
//!
//! Each scene is also computed by skyref in f64, so the table this test prints shows the GPU's
//! difference from the f32 reference beside the f32 reference's own difference from f64: the
//! first is the translation's error, the second the shader's f32 error, which bounds how close
//! any two f32 implementations can be expected to agree.
//!
//! ## Thresholds, and why
//!
//! Measured on lavapipe (docs/measured.md, "Pixels"): GPU against skyref f32 has p99.9 ≤ 3.9e-4
//! in every scene, below skyref's own f32-versus-f64 p99.9 in the same scene (up to 5e-3 with
//! the sun 0.5° up). So:
//!
//! * no NaN or Inf anywhere;
//! * p99.9 ≤ 1e-3 in every scene ([`P999_BOUND`], the aim, met with 2.5× margin);
//! * a channel may exceed 1e-3 only in the two regions where the shader itself is
//!   ill-conditioned in f32, and never by more than 1e-2 ([`MAX_BOUND`]):
//!   - the **edge of the sun disk**, `smoothstep(0.9998, 1.0, cos_theta)`: the ramp is 2e-4
//!     wide in cos θ while one f32 ulp of cos θ near 1 is 6e-8, so one ulp of difference in
//!     EYEDIR or the light direction moves the disk's value by ~5e-4 of itself; the GPU and the
//!     CPU round `dot` differently (fused multiply-adds). Measured worst: 6.2e-3 at 1.04° from
//!     the sun, where skyref's f32 is itself 7.8e-4 off f64. Allowed within [`SUN_EDGE_DEG`];
//!   - **ground pixels seen from 1 m**, where the ray–planet test subtracts numbers of size
//!     R² = 4e13 m² in f32 (issue #5 measures this cancellation): the GPU and CPU round it
//!     differently. Measured worst: 1.9e-3 at 11.5° below the horizon.
//!
//! The bounds have power: rendering with `rayleigh_scale_height` 1 % off (a parameter error a
//! port could make) must fail the p99.9 bound, and a failing scene writes a heatmap of its
//! relative error into the test's temporary directory.
//!
//! One test function, so the environment is set before any thread reads it and one device
//! serves all renders. Without a Vulkan adapter the test fails: it does not skip.

use skyref::{FreemanParams, Projection, Scene};
use skyrun::{SkyBuiltins, SkyShader, SubPasses, compare, freeman_material, worst_pixels};
use std::path::Path;
use std::time::Instant;

/// Relative errors are |a − b| / max(|b|, FLOOR) per channel. 1e-4 is well below the darkest
/// sky the matrix renders that is not black (sun −4°: ~1e-3) so it only stops 0/0.
const FLOOR: f32 = 1e-4;
const SUNS_DEG: [f64; 5] = [-4.0, 0.5, 10.0, 45.0, 90.0];
const ALTITUDES_M: [f64; 3] = [1.0, 2_000.0, 30_000.0];
const PANORAMA: (u32, u32) = (128, 64);
/// Bound on the 99.9th percentile of the relative error, every scene.
const P999_BOUND: f64 = 1e-3;
/// Bound on any channel's relative error; above [`P999_BOUND`] only in the regions below.
const MAX_BOUND: f64 = 1e-2;
/// Angular radius around the sun of the disk's edge region (the smoothstep ends at 1.146°).
const SUN_EDGE_DEG: f64 = 1.5;
/// The altitude at and below which ground pixels may exceed [`P999_BOUND`].
const GROUND_CANCELLATION_ALTITUDE_M: f64 = 1.0;
const CAMERA: (u32, u32) = (96, 64);

#[test]
fn freeman_scene_matrix_matches_skyref_f32() {
    let start = Instant::now();
    let gpu = crate::common::gpu();
    let (front, lowered, wgsl) = crate::common::converted_freeman();
    let params = FreemanParams::default();
    let material = freeman_material(&lowered, &params);
    let shader = SkyShader::new(&gpu, &wgsl, SubPasses::of(&front)).expect("the converted module compiles");

    eprintln!(
        "{:<9} {:>6} {:>7} | {:>9} {:>9} {:>9} {:>9} {:>5} | {:>9} {:>9} {:>9} | {:>9} {:>9}",
        "proj",
        "sun",
        "alt",
        "max",
        "p99.9",
        "p99",
        "mean",
        "nan",
        "f32 max",
        "f32p99.9",
        "f32 mean",
        "gpu-f64",
        "gpu-f64"
    );
    eprintln!("{:<24} | {:^50} | {:^29} | {:>9} {:>9}", "", "GPU vs skyref f32", "skyref f32 vs f64", "max", "p99.9");
    let mut failures = Vec::new();
    for projection in [Projection::Panorama, Projection::Camera] {
        for altitude in ALTITUDES_M {
            for sun in SUNS_DEG {
                let scene = Scene::default()
                    .with_sun(sun, 30.0)
                    .with_position(glam::DVec3::new(0.0, altitude, 0.0))
                    .with_fov(90.0)
                    .with_view(-30.0, 5.0);
                let (w, h) = if projection == Projection::Panorama { PANORAMA } else { CAMERA };
                let builtins = SkyBuiltins::from_scene(&scene, w, h);
                let rendered = shader
                    .render(&gpu, projection, w, h, &builtins, &material)
                    .unwrap_or_else(|e| panic!("{projection:?} sun {sun} alt {altitude}: {e}"));
                // Where the device has timestamp queries, every render is timed by them.
                if gpu.has_timestamps() && rendered.gpu_time.is_none_or(|t| t <= std::time::Duration::ZERO) {
                    failures.push(format!("{projection:?}: no GPU time although the device has timestamps"));
                }
                let gpu_image = rendered.pixels;
                let f32_image = skyref::f32::render(&params, &scene, projection, w, h);
                let f64_image = skyref::f64::render(&params, &scene, projection, w, h);
                let f64_as_f32: Vec<[f32; 4]> =
                    f64_image.iter().map(|p| [p[0] as f32, p[1] as f32, p[2] as f32, p[3] as f32]).collect();
                let gpu_vs_f32 = compare(&gpu_image, &f32_image, FLOOR);
                let f32_vs_f64 = compare(&f32_image, &f64_as_f32, FLOOR);
                let gpu_vs_f64 = compare(&gpu_image, &f64_as_f32, FLOOR);
                eprintln!(
                    "{:<9} {:>6} {:>7} | {:>9.2e} {:>9.2e} {:>9.2e} {:>9.2e} {:>5} | {:>9.2e} {:>9.2e} {:>9.2e} | {:>9.2e} {:>9.2e}",
                    format!("{projection:?}"),
                    sun,
                    altitude,
                    gpu_vs_f32.max_rel,
                    gpu_vs_f32.p999_rel,
                    gpu_vs_f32.p99_rel,
                    gpu_vs_f32.mean_rel,
                    gpu_vs_f32.nan + gpu_vs_f32.inf,
                    f32_vs_f64.max_rel,
                    f32_vs_f64.p999_rel,
                    f32_vs_f64.mean_rel,
                    gpu_vs_f64.max_rel,
                    gpu_vs_f64.p999_rel,
                );
                for p in worst_pixels(&gpu_image, &f32_image, FLOOR, w as usize, 3) {
                    let i = p.y * w as usize + p.x;
                    let d = skyref::f64::eyedir(&scene, projection, p.x as u32, p.y as u32, w, h);
                    let angle = d.normalize().dot(scene.sun().direction()).clamp(-1.0, 1.0).acos().to_degrees();
                    let elev = d.normalize().y.asin().to_degrees();
                    let r64 = (f64::from(f32_image[i][p.channel]) - f64_image[i][p.channel]).abs()
                        / f64_image[i][p.channel].abs().max(1e-4);
                    eprintln!("      {p}  sun {angle:.2}° elev {elev:.2}° f32-vs-f64 {r64:.2e}");
                }
                let name = format!("{projection:?} sun {sun}° altitude {altitude} m");
                let mut problems = Vec::new();
                if gpu_vs_f32.nan + gpu_vs_f32.inf != 0 {
                    problems.push(format!("{} NaN and {} Inf channels", gpu_vs_f32.nan, gpu_vs_f32.inf));
                }
                if gpu_vs_f32.p999_rel > P999_BOUND {
                    problems.push(format!("p99.9 {:.3e} > {P999_BOUND:.0e}", gpu_vs_f32.p999_rel));
                }
                if gpu_vs_f32.max_rel > MAX_BOUND {
                    problems.push(format!("max {:.3e} > {MAX_BOUND:.0e}", gpu_vs_f32.max_rel));
                }
                let mut outside = Vec::new();
                for p in worst_pixels(&gpu_image, &f32_image, FLOOR, w as usize, usize::MAX) {
                    if p.rel <= P999_BOUND {
                        break;
                    }
                    let d = skyref::f64::eyedir(&scene, projection, p.x as u32, p.y as u32, w, h).normalize();
                    let from_sun = d.dot(scene.sun().direction()).clamp(-1.0, 1.0).acos().to_degrees();
                    let ground = d.y < 0.0 && altitude <= GROUND_CANCELLATION_ALTITUDE_M;
                    if from_sun > SUN_EDGE_DEG && !ground {
                        outside.push(format!("{p} ({from_sun:.2}° from the sun)"));
                    }
                }
                if !outside.is_empty() {
                    problems.push(format!(
                        "{} channels above {P999_BOUND:.0e} outside the ill-conditioned regions, worst: {}",
                        outside.len(),
                        outside[..outside.len().min(3)].join(", ")
                    ));
                }
                if !problems.is_empty() {
                    let heatmap = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
                        "freeman_{}_sun{sun}_alt{altitude}.heatmap.png",
                        format!("{projection:?}").to_lowercase()
                    ));
                    let written = skyrun::Image::new(w, h, gpu_image.clone())
                        .and_then(|a| Ok((a, skyrun::Image::new(w, h, f32_image.clone())?)))
                        .and_then(|(a, b)| skyrun::write_heatmap_png(&heatmap, &a, &b, FLOOR));
                    match written {
                        Ok(()) => problems.push(format!("heatmap: {}", heatmap.display())),
                        Err(e) => problems.push(format!("heatmap not written: {e}")),
                    }
                    failures.push(format!("{name}: {}", problems.join("; ")));
                }
            }
        }
    }

    // Power: a 1 % error in one parameter must fail the p99.9 bound.
    let scene = Scene::default().with_position(glam::DVec3::new(0.0, 1.0, 0.0));
    let (w, h) = PANORAMA;
    let off = FreemanParams { rayleigh_scale_height: params.rayleigh_scale_height * 1.01, ..params };
    let wrong = shader
        .render(
            &gpu,
            Projection::Panorama,
            w,
            h,
            &SkyBuiltins::from_scene(&scene, w, h),
            &freeman_material(&lowered, &off),
        )
        .expect("render")
        .pixels;
    let m = compare(&wrong, &skyref::f32::render(&params, &scene, Projection::Panorama, w, h), FLOOR);
    eprintln!("negative control (rayleigh_scale_height 1 % off): {m}");
    if m.p999_rel <= P999_BOUND {
        failures.push(format!("a 1 % parameter error passes the p99.9 bound ({:.3e}): no power", m.p999_rel));
    }
    eprintln!("total {:.2?}", start.elapsed());
    assert!(failures.is_empty(), "{} failing:\n{}", failures.len(), failures.join("\n"));
}

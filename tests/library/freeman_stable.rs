//! `shaders/freeman_stable.gdshader` (issue #5): the Freeman sky evaluated without cancellation,
//! converted by gdsky and rendered on the Vulkan adapter (lavapipe without a GPU) in f32, against
//! the original (`fixtures/freeman_sky.gdshader`, converted and rendered the same way) and
//! against skyref's f64 rendering of the original. The stable shader is the same integral (same
//! samples, step positions and formulas, only evaluated differently), so skyref f64 is the truth
//! for both.
//!
//! ## What is asserted, and why these bounds
//!
//! Relative error per channel, |a − b| / max(|b|, 1e-4). Measured on lavapipe (llvmpipe, LLVM
//! 15.0.6); the bounds are the goals, the measurements show how much room they leave.
//!
//! * (a) **Camera 0.5 m above the ground, sun on the horizon** (elevations 0°, −1°, 0.5°, 2°),
//!   where the original's `|o|² − R²` cancels: the stable shader's p99.9 against f64 ≤ 1e-3 and
//!   its worst channel ≤ 1/10 of the original's worst in the same scene. Measured (128×64
//!   panorama): stable worst ≤ 1.5e-5, p99.9 ≤ 7e-6; the original's worst 3.5e-3 … 2.6e-1. The
//!   original must fail the p99.9 bound with the sun at 0°, so the bound tells the two apart.
//! * (b) **No NaN or Inf at the defaults** for camera altitudes 0.5 m … 100 km and above the
//!   atmosphere (150 km), sun −90° … 90°, panorama and camera.
//! * (c) **Corners of the hint ranges** (`rayleigh_scale_height`, `mie_scale_height`,
//!   `ozone_width`, `mie_albedo` = 0; `mie_g_forward` = 1 and `mie_g_backward` = −1 looking
//!   exactly along the lobe's axis; `atmosphere_height` < 0, which has no hint): the stable shader
//!   gives no NaN or Inf; the original gives NaN in every one of them except `ozone_width` = 0.
//!   There its 0/0 happens only at an altitude equal to `ozone_center`, and gdsky's NaN-proof
//!   `max` turns `max(0.0, NaN)` into 0 (GLSL leaves it undefined), so lavapipe shows none.
//! * (d) **Away from the horizon** (sun 45° and 90°, camera at 1 km and 20 km), where the
//!   original is accurate in f32, stable and original agree to ≤ 1e-4. Measured: ≤ 4e-5, which
//!   is the original's own f32 error there (the stable shader is within 3e-6 of f64). 1e-4 is
//!   2.5× that, and it has power: the stable shader with `rayleigh_scale_height` 0.1 % off (not
//!   the same integral) must exceed it.
//!
//! One test function, so the environment is set before any thread reads it and one device serves
//! all renders. Without a Vulkan adapter the test fails: it does not skip.

use gdshader::FrontendOutput;
use gdsky_naga::Lowered;
use skyref::{FreemanParams, Projection, Scene};
use skyrun::{Gpu, Metrics, SkyBuiltins, SkyShader, SubPasses, compare, material_with_defaults};
use std::path::Path;
use std::time::Instant;

const FLOOR: f32 = 1e-4;
/// The bound on the stable shader's p99.9 at the horizon.
const P999_BOUND: f64 = 1e-3;
/// The stable shader's worst channel at the horizon is at most this fraction of the original's.
const WORST_FRACTION: f64 = 0.1;
/// Bound on stable against original where the original is accurate in f32 (part d).
const SAME_INTEGRAL_BOUND: f64 = 1e-4;
const PANORAMA: (u32, u32) = (128, 64);
const SMALL_PANORAMA: (u32, u32) = (64, 32);
const SMALL_CAMERA: (u32, u32) = (48, 32);
/// Odd, so the centre pixel looks exactly along the camera axis (toward the sun or away from it).
const CENTRED_CAMERA: (u32, u32) = (63, 31);

/// A shader converted by gdsky, ready to render with any material overrides.
struct Sky {
    front: FrontendOutput,
    lowered: Lowered,
    shader: SkyShader,
}

impl Sky {
    fn load(gpu: &Gpu, relative: &str) -> Sky {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(relative);
        let front = gdshader::check_file(&path).unwrap_or_else(|e| panic!("{relative}: {e}"));
        assert!(front.shader.is_some(), "{relative} does not check: {:?}", front.diagnostics);
        let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default())
            .unwrap_or_else(|e| panic!("{relative} does not lower: {e:?}"));
        let wgsl = gdsky_naga::to_wgsl(&lowered).unwrap_or_else(|e| panic!("{relative}: WGSL: {e}"));
        let shader = SkyShader::new(gpu, &wgsl, SubPasses::of(&front))
            .unwrap_or_else(|e| panic!("{relative}: the converted module does not compile: {e}"));
        Sky { front, lowered, shader }
    }

    fn render(
        &self,
        gpu: &Gpu,
        scene: &Scene,
        projection: Projection,
        (w, h): (u32, u32),
        overrides: &[(&str, &str)],
    ) -> Vec<[f32; 4]> {
        let checked = self.front.shader.as_ref().expect("checked in load");
        let overrides: Vec<(String, String)> = overrides.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        let material = material_with_defaults(checked, &self.lowered, &overrides)
            .unwrap_or_else(|e| panic!("material {overrides:?}: {e}"));
        let builtins = SkyBuiltins::from_scene(scene, w, h);
        self.shader
            .render(gpu, projection, w, h, &builtins, &material)
            .unwrap_or_else(|e| panic!("render {projection:?} {scene:?}: {e}"))
            .pixels
    }
}

fn scene(altitude_m: f64, sun_elevation_deg: f64, sun_azimuth_deg: f64) -> Scene {
    Scene::default().with_sun(sun_elevation_deg, sun_azimuth_deg).with_position(glam::DVec3::new(0.0, altitude_m, 0.0))
}

/// skyref's f64 rendering of the original, rounded to f32 for [`compare`].
fn truth(scene: &Scene, projection: Projection, (w, h): (u32, u32)) -> Vec<[f32; 4]> {
    skyref::f64::render(&FreemanParams::default(), scene, projection, w, h)
        .iter()
        .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32, p[3] as f32])
        .collect()
}

/// RGB channels that are NaN or infinite.
fn non_finite(image: &[[f32; 4]]) -> usize {
    image.iter().flat_map(|p| &p[..3]).filter(|c| !c.is_finite()).count()
}

fn row(m: &Metrics) -> String {
    format!("max {:.2e} p99.9 {:.2e} mean {:.2e} NaN/Inf {}", m.max_rel, m.p999_rel, m.mean_rel, m.nan + m.inf)
}

#[test]
fn stable_freeman_sky_is_accurate_in_f32_and_finite_at_the_corners() {
    let start = Instant::now();
    let gpu = skytest::gpu();
    eprintln!("adapter: {}", gpu.adapter_info());
    let original = Sky::load(&gpu, "fixtures/freeman_sky.gdshader");
    let stable = Sky::load(&gpu, "shaders/freeman_stable.gdshader");
    let mut failures = Vec::new();

    // (a) The horizon seen from 0.5 m.
    eprintln!("(a) 0.5 m, sun on the horizon, {}x{} panorama, against skyref f64", PANORAMA.0, PANORAMA.1);
    for sun in [0.0, -1.0, 0.5, 2.0] {
        let scene = scene(0.5, sun, 0.0);
        let truth = truth(&scene, Projection::Panorama, PANORAMA);
        let before = compare(&original.render(&gpu, &scene, Projection::Panorama, PANORAMA, &[]), &truth, FLOOR);
        let after = compare(&stable.render(&gpu, &scene, Projection::Panorama, PANORAMA, &[]), &truth, FLOOR);
        eprintln!("  sun {sun:>4}°  original: {}\n             stable:   {}", row(&before), row(&after));
        if after.nan + after.inf != 0 || after.p999_rel > P999_BOUND {
            failures.push(format!("(a) sun {sun}°: stable {}", row(&after)));
        }
        if after.max_rel > WORST_FRACTION * before.max_rel {
            failures.push(format!(
                "(a) sun {sun}°: stable worst {:.2e} is more than {WORST_FRACTION} of the original's {:.2e}",
                after.max_rel, before.max_rel
            ));
        }
        if sun == 0.0 && before.p999_rel <= P999_BOUND {
            failures.push(format!("(a) the original passes the p99.9 bound at sun 0° ({}): no power", row(&before)));
        }
    }

    // (b) Defaults: no NaN or Inf anywhere in the sweep.
    let mut renders = 0;
    for altitude in [0.5, 1_000.0, 100_000.0, 150_000.0] {
        for sun in [-90.0, -1.0, 0.0, 2.0, 90.0] {
            for (projection, size) in [(Projection::Panorama, SMALL_PANORAMA), (Projection::Camera, SMALL_CAMERA)] {
                let scene = scene(altitude, sun, 30.0);
                let bad = non_finite(&stable.render(&gpu, &scene, projection, size, &[]));
                renders += 1;
                if bad != 0 {
                    failures
                        .push(format!("(b) {projection:?} altitude {altitude} m sun {sun}°: {bad} NaN/Inf channels"));
                }
            }
        }
    }
    eprintln!("(b) defaults, {renders} renders (0.5 m … 150 km, sun −90° … 90°, panorama and camera)");

    // (c) Corners: (overrides, whether the original gives NaN/Inf on lavapipe).
    let corners: [(&[(&str, &str)], bool); 8] = [
        (&[("rayleigh_scale_height", "0")], true),
        (&[("mie_scale_height", "0")], true),
        (&[("ozone_width", "0")], false),
        (&[("ozone_width", "0"), ("ozone_center", "0")], false),
        (&[("mie_albedo", "0")], true),
        (&[("atmosphere_height", "-5")], true),
        (&[("mie_g_forward", "1")], true),
        (&[("mie_g_backward", "-1")], true),
    ];
    // The ground at 0.5 m; zero-length paths from the top of the atmosphere (the camera clamped
    // from 150 km to 100 km); the centre pixel exactly toward the sun and exactly away from it.
    let corner_views = [
        (scene(0.5, 10.0, 0.0), Projection::Panorama, SMALL_PANORAMA),
        (scene(150_000.0, 0.0, 0.0), Projection::Panorama, SMALL_PANORAMA),
        (scene(1_000.0, 0.0, 0.0), Projection::Camera, CENTRED_CAMERA),
        (scene(1_000.0, 0.0, 180.0), Projection::Camera, CENTRED_CAMERA),
    ];
    eprintln!("(c) corners: NaN/Inf channels over {} views, original → stable", corner_views.len());
    for (overrides, original_breaks) in corners {
        let (mut before, mut after) = (0, 0);
        for (scene, projection, size) in &corner_views {
            before += non_finite(&original.render(&gpu, scene, *projection, *size, overrides));
            after += non_finite(&stable.render(&gpu, scene, *projection, *size, overrides));
        }
        eprintln!("  {overrides:?}: {before} → {after}");
        if after != 0 {
            failures.push(format!("(c) {overrides:?}: the stable shader gives {after} NaN/Inf channels"));
        }
        if original_breaks && before == 0 {
            failures.push(format!("(c) {overrides:?}: the original gives no NaN/Inf here: the corner tests nothing"));
        }
    }

    // (d) Away from the horizon: the same integral as the original.
    eprintln!("(d) away from the horizon, {}x{} panorama", PANORAMA.0, PANORAMA.1);
    for (altitude, sun) in [(1_000.0, 45.0), (1_000.0, 90.0), (20_000.0, 45.0), (20_000.0, 90.0)] {
        let scene = scene(altitude, sun, 30.0);
        let truth = truth(&scene, Projection::Panorama, PANORAMA);
        let before = original.render(&gpu, &scene, Projection::Panorama, PANORAMA, &[]);
        let after = stable.render(&gpu, &scene, Projection::Panorama, PANORAMA, &[]);
        let same = compare(&after, &before, FLOOR);
        eprintln!(
            "  {altitude:>6} m sun {sun}°  stable vs original: {}\n                     original vs f64: {}\n                     stable vs f64:   {}",
            row(&same),
            row(&compare(&before, &truth, FLOOR)),
            row(&compare(&after, &truth, FLOOR))
        );
        if same.nan + same.inf != 0 || same.max_rel > SAME_INTEGRAL_BOUND {
            failures.push(format!("(d) {altitude} m sun {sun}°: stable vs original {}", row(&same)));
        }
    }
    let scene = scene(1_000.0, 45.0, 30.0);
    let before = original.render(&gpu, &scene, Projection::Panorama, PANORAMA, &[]);
    let off = stable.render(&gpu, &scene, Projection::Panorama, PANORAMA, &[("rayleigh_scale_height", "8008")]);
    let other = compare(&off, &before, FLOOR);
    eprintln!("  power: stable with rayleigh_scale_height 8008 vs original: {}", row(&other));
    if other.max_rel <= SAME_INTEGRAL_BOUND {
        failures.push(format!("(d) a 0.1 % different integral passes the {SAME_INTEGRAL_BOUND:.0e} bound: no power"));
    }

    eprintln!("done in {:.1?}", start.elapsed());
    assert!(failures.is_empty(), "{} failure(s):\n{}", failures.len(), failures.join("\n"));
}

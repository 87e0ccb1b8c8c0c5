//! Unit tests of the reference: defaults against the fixture's text, conventions, f32 versus
//! f64, physical sanity checks and the converged mode.

use crate::FreemanParams;
use crate::converged::{Converged, REL_FLOOR, convergence_check, relative_changes, summarize};
use glam::{DVec3, Vec3};
use skycore::{Projection, Scene};

fn fixture_text() -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/freeman_sky.gdshader");
    std::fs::read_to_string(path).expect("fixtures/freeman_sky.gdshader is readable")
}

/// Parses a default value as written in the shader: a number or `vec3(a, b, c)`.
fn parse_value(text: &str) -> Vec<f64> {
    let text = text.trim();
    let inner = text.strip_prefix("vec3(").and_then(|t| t.strip_suffix(')')).unwrap_or(text);
    inner.split(',').map(|n| n.trim().parse::<f64>().expect("a number")).collect()
}

/// The default of `FreemanParams` for the uniform called `name`, with its GLSL type.
fn default_of(name: &str) -> Option<(&'static str, Vec<f64>)> {
    let p = FreemanParams::default();
    let f = |x: f64| Some(("float", vec![x]));
    let v = |x: DVec3| Some(("vec3", vec![x.x, x.y, x.z]));
    let i = |x: i32| Some(("int", vec![f64::from(x)]));
    match name {
        "sun_intensity" => f(p.sun_intensity),
        "sun_wavelengths" => v(p.sun_wavelengths),
        "rayleigh_scale_height" => f(p.rayleigh_scale_height),
        "rayleigh_multi_scattering" => f(p.rayleigh_multi_scattering),
        "mie_scale_height" => f(p.mie_scale_height),
        "mie_scattering" => f(p.mie_scattering),
        "mie_albedo" => f(p.mie_albedo),
        "mie_g_forward" => f(p.mie_g_forward),
        "mie_g_backward" => f(p.mie_g_backward),
        "mie_weight" => f(p.mie_weight),
        "mie_multi_scattering" => f(p.mie_multi_scattering),
        "multiscattering_mie_g_forward" => f(p.multiscattering_mie_g_forward),
        "multiscattering_mie_g_backward" => f(p.multiscattering_mie_g_backward),
        "multiscattering_mie_weight" => f(p.multiscattering_mie_weight),
        "ozone_center" => f(p.ozone_center),
        "ozone_width" => f(p.ozone_width),
        "planet_radius" => f(p.planet_radius),
        "atmosphere_height" => f(p.atmosphere_height),
        "base_altitude" => f(p.base_altitude),
        "ground_color" => v(p.ground_color),
        "view_samples" => i(p.view_samples),
        "sun_samples" => i(p.sun_samples),
        _ => None,
    }
}

#[test]
fn defaults_match_fixture() {
    let text = fixture_text();
    let mut seen = Vec::new();
    for line in text.lines().map(str::trim) {
        let Some(rest) = line.strip_prefix("uniform ") else {
            continue;
        };
        let (decl, value) = rest.split_once('=').expect("every uniform has a default");
        let value = value.trim().strip_suffix(';').expect("ends with ;");
        let mut words = decl.split([' ', '\t', ':']).filter(|w| !w.is_empty());
        let ty = words.next().expect("a type");
        let name = words.next().expect("a name");
        let (our_ty, ours) = default_of(name).unwrap_or_else(|| panic!("uniform {name} has no field in FreemanParams"));
        assert_eq!(ty, our_ty, "type of {name}");
        assert_eq!(parse_value(value), ours, "default of {name}");
        seen.push(name.to_string());
    }
    assert_eq!(seen.len(), 22, "uniforms found in the fixture: {seen:?}");

    // The one constant, too.
    let line = text.lines().find(|l| l.contains("const vec3 ozone_extinction")).expect("ozone_extinction is declared");
    let (_, rhs) = line.split_once('=').expect("has a value");
    let (vec, scale) = rhs.split_once('*').expect("vec3(...) * scale");
    let scale: f64 = scale.trim().trim_end_matches(';').parse().expect("a number");
    let v = parse_value(vec);
    let ours = crate::f64::ozone_extinction();
    assert_eq!([ours.x, ours.y, ours.z], [v[0] * scale, v[1] * scale, v[2] * scale]);
}

#[test]
fn sun_direction_convention() {
    let dir = |e: f64, a: f64| Scene::default().with_sun(e, a).sun().direction();
    assert!((dir(0.0, 0.0) - DVec3::NEG_Z).length() < 1e-15);
    assert!((dir(0.0, 90.0) - DVec3::X).length() < 1e-15);
    assert!((dir(90.0, 37.0) - DVec3::Y).length() < 1e-15);
    let d = dir(30.0, 45.0);
    assert!((d.length() - 1.0).abs() < 1e-15);
    assert!((d.y - 0.5).abs() < 1e-15);
}

#[test]
fn panorama_eyedir_inverts_sky_coords() {
    let scene = Scene::default();
    let (w, h) = (64, 32);
    for y in 0..h {
        for x in 0..w {
            let d = crate::f64::eyedir(&scene, Projection::Panorama, x, y, w, h);
            // SKY_COORDS: u = atan2(d.x, −d.z) / 2π wrapped to [0, 1), v = acos(d.y) / π.
            let u = (d.x.atan2(-d.z) / std::f64::consts::TAU).rem_euclid(1.0);
            let v = d.y.acos() / std::f64::consts::PI;
            let (eu, ev) = ((f64::from(x) + 0.5) / 64.0, (f64::from(y) + 0.5) / 32.0);
            assert!((u - eu).abs() < 1e-12 && (v - ev).abs() < 1e-12, "({x}, {y})");
            assert!((d.length() - 1.0).abs() < 1e-12);
        }
    }
    // Row 0 is at the top (toward the zenith), column 0 just right of −Z toward +X.
    let top = crate::f32::eyedir(&scene, Projection::Panorama, 0, 0, w, h);
    assert!(top.y > 0.99);
    let mid = crate::f32::eyedir(&scene, Projection::Panorama, w / 4, h / 2, w, h);
    assert!(mid.x > 0.99, "u = 1/4 looks toward +X: {mid}");
}

#[test]
fn camera_eyedir_follows_godot() {
    let eye = |yaw: f64, pitch: f64, x: u32, y: u32, w: u32, h: u32| {
        let scene = Scene::default().with_view(yaw, pitch);
        crate::f64::eyedir(&scene, Projection::Camera, x, y, w, h)
    };
    // The centre of an odd-sized image looks toward −Z at yaw 0, pitch 0.
    assert!((eye(0.0, 0.0, 2, 2, 5, 5) - DVec3::NEG_Z).length() < 1e-12);
    // Pitch 90 looks up, and the top of the image is toward +Z.
    assert!((eye(0.0, 90.0, 2, 2, 5, 5) - DVec3::Y).length() < 1e-12);
    assert!(eye(0.0, 90.0, 2, 0, 5, 5).z > 0.5);
    // Yaw 90 turns the view from −Z to −X.
    assert!((eye(90.0, 0.0, 2, 2, 5, 5) - DVec3::NEG_X).length() < 1e-12);
    // Row 0 is at the top; the right edge is toward +X.
    assert!(eye(0.0, 0.0, 2, 0, 5, 5).y > 0.5);
    assert!(eye(0.0, 0.0, 4, 2, 5, 5).x > 0.5);
    // Vertical FOV 90: the top edge of the image (v = 0) is 45° up. Pixel centres of a tall
    // image approach it.
    let d = eye(0.0, 0.0, 0, 0, 1, 1001);
    let elevation = d.y.asin().to_degrees();
    assert!((elevation - 45.0).abs() < 0.1, "{elevation}");
    // Horizontal extent follows the aspect ratio: in a 2:1 image the right edge is at
    // x/−z = 2 · tan(45°).
    let d = eye(0.0, 0.0, 1999, 499, 2000, 1000);
    assert!((d.x / -d.z - 2.0).abs() < 2e-3, "{d}");
}

fn scene_10deg_1m() -> Scene {
    Scene::default().with_sun(10.0, 0.0).with_position(DVec3::new(0.0, 1.0, 0.0))
}

/// f32 against f64 at defaults, 64×32 panorama, sun 10°, camera at 1 m. Measured (this test
/// prints it): max 3.5e-4, p99 7.8e-5, mean 1.5e-5 of |f32 − f64| / max(|f64|, 1e-4) per
/// channel; the worst pixels are the grazing ones just below the horizon. The bounds below
/// (about 3× the measurement) leave room for other platforms' libm, not for changes of the
/// algorithm.
#[test]
fn f32_vs_f64_at_defaults() {
    let params = FreemanParams::default();
    let scene = scene_10deg_1m();
    let a = crate::f32::render(&params, &scene, Projection::Panorama, 64, 32);
    let b = crate::f64::render(&params, &scene, Projection::Panorama, 64, 32);
    let mut rel = relative_changes(&a, &b, REL_FLOOR);
    let (max, p99, mean) = summarize(&mut rel);
    println!("f32 vs f64, 64x32 panorama: max_rel={max:.3e} p99_rel={p99:.3e} mean_rel={mean:.3e}");
    assert!(max < 1e-3, "max_rel={max:e}");
    assert!(p99 < 2.5e-4, "p99_rel={p99:e}");
}

#[test]
fn light_disabled_is_black() {
    let params = FreemanParams::default();
    let scene = scene_10deg_1m().with_sun_enabled(false);
    for projection in [Projection::Panorama, Projection::Camera] {
        let a = crate::f32::render(&params, &scene, projection, 16, 8);
        assert!(a.iter().all(|p| *p == [0.0; 4]));
        let b = crate::f64::render(&params, &scene, projection, 16, 8);
        assert!(b.iter().all(|p| *p == [0.0; 4]));
    }
}

#[test]
fn alpha_is_zero_and_colours_finite() {
    let a = crate::f32::render(&FreemanParams::default(), &scene_10deg_1m(), Projection::Camera, 12, 9);
    assert_eq!(a.len(), 12 * 9);
    assert!(a.iter().all(|p| p[3] == 0.0 && p[..3].iter().all(|c| c.is_finite() && *c >= 0.0)));
}

/// Sun at the zenith, looking straight up: the sun disk adds sun_intensity × the view
/// transmittance (the same trapezoid sum, so `get_transmittance` with `view_samples` gives it).
/// The disk is isolated by subtracting the sky without it, extrapolated to 0° from 1.25° and
/// 1.5° away (just outside the disk, whose edge is at acos 0.9998 = 1.146°) with the sky's
/// s₀ + a·θ² dependence near the sun. What remains is the θ⁴ term of that extrapolation: it
/// shrinks with the angles (measured in f64: 1.6e-3 from 3°/4°, 4.5e-4 from 2°/3°, 4.6e-5 from
/// 1.2°/1.5°). This test prints its own numbers: 5.0e-5 in f64 and in f32 at 1.25°/1.5°.
#[test]
fn sun_disk_at_zenith() {
    let params = FreemanParams::default();
    let scene = scene_10deg_1m().with_sun(90.0, 0.0);
    let u = crate::f64::Uniforms::from(&params);
    let origin = DVec3::new(0.0, params.planet_radius + 1.0, 0.0);
    let transmittance = u.get_transmittance(origin, DVec3::Y, params.atmosphere_height - 1.0, params.view_samples);
    let expected = transmittance * params.sun_intensity;

    let at = |deg: f64| DVec3::new(deg.to_radians().sin(), deg.to_radians().cos(), 0.0);
    let (a1, a2) = (1.25, 1.5);
    let (t1, t2) = (a1 * a1, a2 * a2);
    let sky64 = |deg: f64| crate::f64::sky_color(&params, &scene, at(deg));
    let sky0 = (sky64(a1) * t2 - sky64(a2) * t1) / (t2 - t1);
    let disk = sky64(0.0) - sky0;
    let rel = ((disk - expected) / expected).abs().max_element();
    println!("sun disk f64: disk={disk} expected={expected} rel={rel:.3e}");

    let sky32 = |deg: f64| crate::f32::sky_color(&params, &scene, at(deg).as_vec3()).as_dvec3();
    let sky0 = (sky32(a1) * t2 - sky32(a2) * t1) / (t2 - t1);
    let disk32 = sky32(0.0) - sky0;
    let rel32 = ((disk32 - expected) / expected).abs().max_element();
    println!("sun disk f32: disk={disk32} rel={rel32:.3e}");
    assert!(rel < 2e-4, "{rel:e}");
    assert!(rel32 < 2e-4, "{rel32:e}");
    // The disk is most of what one sees there: T ≈ 0.85–0.94 across rgb.
    assert!(transmittance.min_element() > 0.8 && transmittance.max_element() < 1.0);
    let _ = Vec3::ZERO;
}

/// The sky is symmetric about the vertical plane through the sun: panorama column x and its
/// mirror about the sun's azimuth agree. Sun azimuth 135° on a 64-wide panorama puts the mirror
/// of column x at 47 − x (mod 64).
#[test]
fn panorama_symmetric_about_sun_azimuth() {
    let params = FreemanParams::default();
    let scene = scene_10deg_1m().with_sun(5.0, 135.0);
    let (w, h) = (64usize, 32usize);
    let img = crate::f64::render(&params, &scene, Projection::Panorama, w as u32, h as u32);
    let img32 = crate::f32::render(&params, &scene, Projection::Panorama, w as u32, h as u32);
    let (mut worst, mut worst32) = (0.0f64, 0.0f64);
    for y in 0..h {
        for x in 0..w {
            let m = (47 - x as i64).rem_euclid(w as i64) as usize;
            let a = &img[y * w..][x..=x];
            let b = &img[y * w..][m..=m];
            worst = worst.max(summarize(&mut relative_changes(a, b, REL_FLOOR)).0);
            let a = &img32[y * w..][x..=x];
            let b = &img32[y * w..][m..=m];
            worst32 = worst32.max(summarize(&mut relative_changes(a, b, REL_FLOOR)).0);
        }
    }
    println!("mirror about the sun's azimuth: f64 max_rel={worst:.3e}, f32 max_rel={worst32:.3e}");
    assert!(worst < 1e-9, "{worst:e}");
    assert!(worst32 < 5e-3, "{worst32:e}");
}

/// The brightest panorama pixel is the one toward the sun.
#[test]
fn brightest_pixel_is_the_sun() {
    let params = FreemanParams::default();
    let scene = scene_10deg_1m().with_sun(30.0, 90.0);
    let (w, h) = (72u32, 36u32);
    let img = crate::f64::render(&params, &scene, Projection::Panorama, w, h);
    let (i, _) = img.iter().enumerate().max_by(|a, b| a.1[0].total_cmp(&b.1[0])).expect("not empty");
    let (x, y) = (i as u32 % w, i as u32 / w);
    // Azimuth 90° is u = 0.25 (column 18), elevation 30° is v = 60/180 (row 12).
    assert!((17..=18).contains(&x) && (11..=12).contains(&y), "({x}, {y})");
}

#[test]
fn sky_is_blue_and_ground_is_dim() {
    let params = FreemanParams::default();
    let scene = scene_10deg_1m().with_sun(45.0, 0.0);
    let zenith = crate::f64::sky_color(&params, &scene, DVec3::Y);
    assert!(zenith.z > zenith.y && zenith.y > zenith.x, "{zenith}");
    let ground = crate::f64::sky_color(&params, &scene, DVec3::NEG_Y);
    assert!(ground.max_element() > 0.0 && ground.max_element() < zenith.max_element() * 10.0);
}

#[test]
fn odd_inputs_do_not_panic() {
    let scene = scene_10deg_1m();
    let odd = [
        FreemanParams::default().with_samples(0, 0),
        FreemanParams::default().with_samples(1, 1),
        FreemanParams::default().with_samples(-5, -3),
        FreemanParams { atmosphere_height: 0.1, ..FreemanParams::default() },
        FreemanParams { mie_g_forward: 1.0, mie_albedo: 0.0, ..FreemanParams::default() },
    ];
    for params in &odd {
        let _ = crate::f32::render(params, &scene, Projection::Panorama, 8, 4);
        let _ = crate::f64::render(params, &scene, Projection::Camera, 8, 4);
    }
    // Zero samples: no sky, but the ground is still lit (transmittance 1, no ambient).
    let zero = crate::f64::render(&odd[0], &scene, Projection::Panorama, 8, 4);
    assert!(zero.iter().all(|p| p.iter().all(|c| c.is_finite())));
    assert!(zero[..8].iter().all(|p| p[..3] == [0.0; 3]), "upper row is black");
    let nan_scene = scene.with_position(DVec3::NAN);
    // maxNum: a NaN altitude clamps to 0.5 m, as on the GPU.
    let a = crate::f64::sky_color(&FreemanParams::default(), &nan_scene, DVec3::Y);
    let b = crate::f64::sky_color(&FreemanParams::default(), &scene.with_position(DVec3::ZERO), DVec3::Y);
    assert_eq!(a, b);
    assert!(crate::f32::render(&FreemanParams::default(), &scene, Projection::Camera, 0, 7).is_empty());
    assert!(crate::f64::render(&FreemanParams::default(), &scene, Projection::Panorama, 7, 0).is_empty());
}

#[test]
fn half_samples_for_ground_rays() {
    // view_samples 3 → 1 sample for a ground ray (integer division), 3 for a sky ray: with 2
    // view samples the ground ray is the same (2 / 2 = 1) and the sky ray differs.
    let scene = scene_10deg_1m();
    let p3 = FreemanParams::default().with_samples(3, 8);
    let p2 = FreemanParams::default().with_samples(2, 8);
    let down = DVec3::new(0.0, -1.0, 0.0);
    let u3 = crate::f64::Uniforms::from(&p3);
    let u2 = crate::f64::Uniforms::from(&p2);
    let origin = DVec3::new(0.0, p3.planet_radius + 1.0, 0.0);
    let sun = scene.sun().direction();
    assert_eq!(
        u3.integrate_radiance(origin, down, 1.0, 3 / 2, sun),
        u2.integrate_radiance(origin, down, 1.0, 2 / 2, sun)
    );
    let up3 = crate::f64::sky_color(&p3, &scene, DVec3::Y);
    let up2 = crate::f64::sky_color(&p2, &scene, DVec3::Y);
    assert_ne!(up3, up2);
}

#[test]
fn convergence_check_runs_small() {
    let report = convergence_check(
        &FreemanParams::default(),
        &scene_10deg_1m(),
        &Converged { view_samples: 48, sun_samples: 16 },
        8,
        4,
    );
    println!("{report:?}");
    assert_eq!(report.pixels, 32);
    assert_eq!(report.doubled.view_samples, 96);
    assert!(report.max_rel_change.is_finite() && report.max_rel_change < 0.1);
}

/// The documented convergence measurement (run with
/// `cargo test -p skyref --release -- --ignored --nocapture convergence_at_default_counts`;
/// 25 s in release on 2 cores, far longer in debug). Measured over a 32×16 panorama (relative
/// change per channel, floor 1e-4):
///
/// | counts | max | p99 | mean |
/// | --- | --- | --- | --- |
/// | 256/64 → 512/128 | 1.09e-2 | 8.96e-3 | 2.75e-3 |
/// | 512/128 → 1024/256 | 5.35e-3 | 4.19e-3 | 8.7e-4 |
/// | 1024/256 → 2048/512 | 2.65e-3 | 2.02e-3 | 3.2e-4 |
/// | 24/8 (the material's) vs 1024/256 | 0.45 | 0.21 | 0.11 |
#[test]
#[ignore = "slow: 25 s in release, minutes in debug"]
fn convergence_at_default_counts() {
    let params = FreemanParams::default();
    let scene = scene_10deg_1m();
    for counts in [
        Converged { view_samples: 256, sun_samples: 64 },
        Converged { view_samples: 512, sun_samples: 128 },
        Converged::default(),
    ] {
        let r = convergence_check(&params, &scene, &counts, 32, 16);
        println!(
            "{}/{} -> {}/{}: max_rel={:.3e} p99_rel={:.3e} mean_rel={:.3e}",
            r.base.view_samples,
            r.base.sun_samples,
            r.doubled.view_samples,
            r.doubled.sun_samples,
            r.max_rel_change,
            r.p99_rel_change,
            r.mean_rel_change
        );
    }
    let truth =
        crate::converged::render_converged(&params, &scene, Projection::Panorama, 32, 16, &Converged::default());
    let shader = crate::f64::render(&params, &scene, Projection::Panorama, 32, 16);
    let (max, p99, mean) = summarize(&mut relative_changes(&shader, &truth, REL_FLOOR));
    println!("default 24/8 vs converged: max_rel={max:.3e} p99_rel={p99:.3e} mean_rel={mean:.3e}");
    let r = convergence_check(&params, &scene, &Converged::default(), 32, 16);
    assert!(r.max_rel_change < 5e-3, "{r:?}");
}

/// A survey of f32 against f64 over 128×64 panoramas for several sun elevations and camera
/// altitudes (prints a table; no assertion). Run with
/// `cargo test -p skyref --release -- --ignored --nocapture f32_vs_f64_survey`.
#[test]
#[ignore = "a measurement, not a check: a few seconds in release"]
fn f32_vs_f64_survey() {
    let params = FreemanParams::default();
    for altitude in [1.0, 1000.0, 20000.0] {
        for elevation in [-6.0, -2.0, 0.0, 2.0, 10.0, 45.0, 90.0] {
            let scene = Scene::default().with_sun(elevation, 0.0).with_position(DVec3::new(0.0, altitude, 0.0));
            let a = crate::f32::render(&params, &scene, Projection::Panorama, 128, 64);
            let b = crate::f64::render(&params, &scene, Projection::Panorama, 128, 64);
            let mut rel = relative_changes(&a, &b, REL_FLOOR);
            let worst = rel.iter().enumerate().max_by(|x, y| x.1.total_cmp(y.1)).map_or(0, |(i, _)| i / 3);
            let (max, p99, mean) = summarize(&mut rel);
            println!(
                "altitude {altitude} m, sun {elevation}°: max_rel={max:.2e} p99_rel={p99:.2e} \
                 mean_rel={mean:.2e} (worst pixel {}, {})",
                worst % 128,
                worst / 128
            );
        }
    }
}

/// The truth converges: doubling its steps and panels changes a 16×8 panorama by well under
/// 1e-6 at sun 10° (measured 1.0e-7 max on 32×16, release build), and by under 1e-5 with the sun
/// below the horizon, where the shadow's edge is a breakpoint (measured 4.9e-6).
#[test]
fn truth_converges() {
    let params = FreemanParams::default();
    for (sun, bound) in [(10.0, 1e-6), (-4.0, 1e-5)] {
        let scene = Scene::default().with_sun(sun, 0.0);
        let (max, _, _) = crate::truth::convergence_check(&params, &scene, &crate::truth::Truth::default(), 16, 8);
        assert!(max < bound, "sun {sun}°: the truth moves by {max:.2e} when its steps double");
    }
}

/// The fast sky (same model, other quadratures) at its default 24 steps is within 1e-3 mean of
/// the truth, where the Freeman sky's own sums at 24/8 are ~0.1 off; f32 and f64 agree to 1e-5.
#[test]
fn fast_sky_is_close_to_the_truth() {
    let params = FreemanParams::default();
    let scene = Scene::default();
    let truth = crate::truth::render(&params, &scene, Projection::Panorama, 16, 8, &crate::truth::Truth::default());
    let fast = crate::fast::f64::render(&params, &scene, Projection::Panorama, 16, 8);
    let fast32 = crate::fast::f32::render(&params, &scene, Projection::Panorama, 16, 8);
    let original = crate::f64::render(&params, &scene, Projection::Panorama, 16, 8);
    let (_, _, fast_mean) = summarize(&mut relative_changes(&fast, &truth, REL_FLOOR));
    let (_, _, original_mean) = summarize(&mut relative_changes(&original, &truth, REL_FLOOR));
    let (precision_max, _, _) = summarize(&mut relative_changes(&fast32, &fast, REL_FLOOR));
    assert!(fast_mean < 1e-3, "fast: mean {fast_mean:.2e} against the truth");
    assert!(original_mean > 0.05, "the original at 24/8: mean {original_mean:.2e} (expected ~0.1)");
    assert!(precision_max < 1e-5, "fast f32 against f64: max {precision_max:.2e}");
}

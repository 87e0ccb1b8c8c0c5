//! The Freeman sky evaluated in f64 on the GPU (`gdsky_naga::lower_f64`, `skyrun::F64Sky`)
//! against skyref's f64 instance, which is the same sums in f64: they agree to ~1e-12
//! relative. The reference is given exactly the inputs the GPU sees — the uniforms and the
//! light direction rounded to f32 as the host writes them into f32 buffers, EYEDIR computed in
//! f64 from the pixel centre as the wrapper does — so what remains is f64 rounding (the GPU's
//! fused or reordered operations, the f64 routines' few ulps). The same shader's f32 module is
//! checked against skyref's f32 as `freeman_lavapipe` does, and a 256×128 f64 render is timed.

use glam::DVec3;
use skyref::{FreemanParams, Projection, Scene};
use skyrun::{F64Sky, SkyBuiltins, compare, freeman_material, render};
use std::time::Instant;

const WIDTH: u32 = 64;
const HEIGHT: u32 = 32;
/// Bound on the worst relative error per channel, |gpu − ref| / max(|ref|, 1e-6).
const F64_BOUND: f64 = 1e-12;

/// `p` with every value rounded to f32, as the material block holds it.
fn rounded(p: &FreemanParams) -> FreemanParams {
    let r = |x: f64| f64::from(x as f32);
    let v = |d: DVec3| DVec3::new(r(d.x), r(d.y), r(d.z));
    FreemanParams {
        sun_intensity: r(p.sun_intensity),
        sun_wavelengths: v(p.sun_wavelengths),
        rayleigh_scale_height: r(p.rayleigh_scale_height),
        rayleigh_multi_scattering: r(p.rayleigh_multi_scattering),
        mie_scale_height: r(p.mie_scale_height),
        mie_scattering: r(p.mie_scattering),
        mie_albedo: r(p.mie_albedo),
        mie_g_forward: r(p.mie_g_forward),
        mie_g_backward: r(p.mie_g_backward),
        mie_weight: r(p.mie_weight),
        mie_multi_scattering: r(p.mie_multi_scattering),
        multiscattering_mie_g_forward: r(p.multiscattering_mie_g_forward),
        multiscattering_mie_g_backward: r(p.multiscattering_mie_g_backward),
        multiscattering_mie_weight: r(p.multiscattering_mie_weight),
        ozone_center: r(p.ozone_center),
        ozone_width: r(p.ozone_width),
        planet_radius: r(p.planet_radius),
        atmosphere_height: r(p.atmosphere_height),
        base_altitude: r(p.base_altitude),
        ground_color: v(p.ground_color),
        ..*p
    }
}

/// skyref's f64 sky for the panorama, with the GPU's inputs (see the essay).
fn reference(params: &FreemanParams, scene: &Scene, builtins: &SkyBuiltins, width: u32, height: u32) -> Vec<[f64; 4]> {
    let uniforms = skyref::f64::Uniforms::from(&rounded(params));
    let l = builtins.lights[0].direction;
    let p = builtins.position;
    let mut out = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let eyedir = skyref::f64::eyedir(scene, Projection::Panorama, x, y, width, height);
            let inputs = skyref::f64::SkyInputs {
                light0_enabled: builtins.lights[0].is_enabled(),
                light0_direction: DVec3::new(l[0].into(), l[1].into(), l[2].into()),
                position: DVec3::new(p[0].into(), p[1].into(), p[2].into()),
                eyedir,
            };
            let c = uniforms.sky(&inputs);
            out.push([c.x, c.y, c.z, 0.0]);
        }
    }
    out
}

#[test]
fn freeman_in_f64_on_the_gpu_matches_skyref_f64() {
    let gpu = crate::common::gpu();
    let (front, lowered, wgsl) = crate::common::converted_freeman();
    let params = FreemanParams::default();
    let material = freeman_material(&lowered, &params);
    let scene = Scene::default().with_sun(10.0, 30.0).with_position(DVec3::new(0.0, 1.0, 0.0));
    let builtins = SkyBuiltins::from_scene(&scene, WIDTH, HEIGHT);

    let t = Instant::now();
    let sky =
        F64Sky::new(&gpu, &front, &gdsky_naga::LowerOptions::default()).unwrap_or_else(|e| panic!("f64 sky: {e}"));
    eprintln!("f64 modules compiled in {:.2?}", t.elapsed());
    let t = Instant::now();
    let image = sky.render(&gpu, Projection::Panorama, WIDTH, HEIGHT, &builtins, &material).expect("f64 render");
    eprintln!("f64 render {WIDTH}×{HEIGHT} (two passes): {:.2?}", t.elapsed());
    let truth = reference(&params, &scene, &builtins, WIDTH, HEIGHT);

    let mut rel: Vec<f64> = Vec::new();
    let mut worst = (0.0f64, 0usize);
    for (i, (g, r)) in image.iter().zip(&truth).enumerate() {
        for c in 0..3 {
            let e = (g[c] - r[c]).abs() / r[c].abs().max(1e-6);
            rel.push(e);
            if e.is_nan() || e > worst.0 {
                worst = (e, i);
            }
        }
    }
    rel.sort_by(f64::total_cmp);
    let p99 = rel[rel.len() * 99 / 100];
    let (wx, wy) = (worst.1 % WIDTH as usize, worst.1 / WIDTH as usize);
    eprintln!(
        "f64 GPU vs skyref f64 (f32-rounded inputs): max rel {:.3e} at ({wx}, {wy}) gpu {:?} ref {:?}, p99 {p99:.3e}, median {:.3e}",
        worst.0,
        image[worst.1],
        truth[worst.1],
        rel[rel.len() / 2]
    );
    // Against plain skyref::f64::render (unrounded f64 inputs): the f32 rounding of the inputs.
    let plain = skyref::f64::render(&params, &scene, Projection::Panorama, WIDTH, HEIGHT);
    let input_rounding = image
        .iter()
        .zip(&plain)
        .flat_map(|(g, r)| (0..3).map(move |c| (g[c] - r[c]).abs() / r[c].abs().max(1e-6)))
        .fold(0.0f64, f64::max);
    eprintln!("f64 GPU vs skyref::f64::render with unrounded inputs: max rel {input_rounding:.3e}");

    // The f32 module of the same shader still agrees with skyref f32 as before.
    let f32_image = render(&gpu, &wgsl, Projection::Panorama, WIDTH, HEIGHT, &builtins, &material).expect("f32 render");
    let f32_truth = skyref::f32::render(&params, &scene, Projection::Panorama, WIDTH, HEIGHT);
    let m = compare(&f32_image, &f32_truth, 1e-4);
    eprintln!("f32 GPU vs skyref f32: {m}");
    // The nearest-f32 image of the f64 evaluation vs skyref f64: the f32 rounding only.
    let nearest = sky.render_nearest(&gpu, Projection::Panorama, WIDTH, HEIGHT, &builtins, &material).expect("nearest");
    let nearest_err = nearest
        .iter()
        .zip(&truth)
        .flat_map(|(g, r)| (0..3).map(move |c| (f64::from(g[c]) - r[c]).abs() / r[c].abs().max(1e-6)))
        .fold(0.0f64, f64::max);
    eprintln!("f64 evaluation rounded to f32 vs skyref f64: max rel {nearest_err:.3e}");

    // Speed: 256×128 in f64 (both passes).
    let (w, h) = (256, 128);
    let big = SkyBuiltins::from_scene(&scene, w, h);
    let t = Instant::now();
    let _ = sky.render(&gpu, Projection::Panorama, w, h, &big, &material).expect("256×128 f64 render");
    let big_time = t.elapsed();
    eprintln!("f64 render {w}×{h} (two passes): {big_time:.2?}");

    let mut failures = Vec::new();
    if worst.0.is_nan() || worst.0 > F64_BOUND {
        failures.push(format!("f64 max relative error {:.3e} > {F64_BOUND:.0e}", worst.0));
    }
    if m.p99_rel.is_nan() || m.p99_rel > 1e-3 || m.nan != 0 {
        failures.push(format!("f32 module vs skyref f32: {m}"));
    }
    if nearest_err.is_nan() || nearest_err > 1e-7 {
        failures.push(format!("nearest-f32 image off skyref f64 by {nearest_err:.3e} (> 1e-7)"));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

//! Specialization of the Freeman sky (issue #11) rendered on the Vulkan device (lavapipe
//! without a GPU): the module with every uniform baked at its default (`gdsky convert --set`)
//! and the module with scalar uniforms as overrides (`--override`), both as WGSL `override`s and
//! as SPIR-V specialization constants, against the generic module drawn with the same values.
//!
//! One test function, so the environment is set before any thread reads it and one device
//! serves every render. Without a Vulkan adapter the test fails: it does not skip.

use skyref::{FreemanParams, Projection, Scene};
use skyrun::{SkyBuiltins, SkyShader, SubPasses, freeman_material};

const WIDTH: u32 = 64;
const HEIGHT: u32 = 32;
/// Bound on the relative difference per channel: |a − b| / max(|b|, FLOOR).
const MAX_REL: f64 = 1e-6;
const FLOOR: f64 = 1e-4;

/// The largest relative difference between two images, and whether they are bit-identical.
fn difference(a: &[[f32; 4]], b: &[[f32; 4]]) -> (f64, bool) {
    assert_eq!(a.len(), b.len());
    let mut worst = 0.0f64;
    let mut identical = true;
    for (pa, pb) in a.iter().zip(b) {
        for (x, y) in pa.iter().zip(pb) {
            identical &= x.to_bits() == y.to_bits();
            let rel = (f64::from(*x) - f64::from(*y)).abs() / f64::from(y.abs()).max(FLOOR);
            worst = worst.max(rel);
        }
    }
    (worst, identical)
}

#[test]
fn baked_and_override_modules_render_as_the_generic_one() {
    let gpu = crate::common::gpu();
    let (front, lowered, generic_wgsl) = crate::common::converted_freeman();
    let shader = front.shader.as_ref().expect("checked");
    let scene = Scene::default().with_sun(10.0, 30.0).with_position(glam::DVec3::new(0.0, 1.0, 0.0));
    let builtins = SkyBuiltins::from_scene(&scene, WIDTH, HEIGHT);
    let generic = SkyShader::new(&gpu, &generic_wgsl, SubPasses::default()).expect("compiles");
    let draw = |s: &SkyShader, material: &[u8], projection| {
        s.render(&gpu, projection, WIDTH, HEIGHT, &builtins, material).expect("renders").pixels
    };

    // Baked at the defaults: every uniform folded into the module.
    let baked_lowered = gdsky_naga::lower(
        &front,
        &gdsky_naga::LowerOptions { baked: gdshader::values::defaults_as_set(shader), ..Default::default() },
    )
    .expect("the baked sky lowers");
    assert!(baked_lowered.uniforms.is_empty(), "every uniform is baked");
    let baked_wgsl = gdsky_naga::to_wgsl(&baked_lowered).expect("WGSL");
    assert!(!baked_wgsl.contains("var<uniform> material"), "no material block is left:\n{baked_wgsl}");
    let baked = SkyShader::new(&gpu, &baked_wgsl, SubPasses::default()).expect("compiles");
    let params = FreemanParams::default();
    let material = freeman_material(&lowered, &params);
    for projection in [Projection::Panorama, Projection::Camera] {
        let (worst, identical) = difference(&draw(&baked, &[], projection), &draw(&generic, &material, projection));
        eprintln!("baked at defaults, {projection:?}: worst relative difference {worst:e}, bit-identical {identical}");
        assert!(worst <= MAX_REL, "{projection:?}: baked differs from generic by {worst:e}");
    }

    // Overrides: three values of three uniforms, set at pipeline creation, against the generic
    // module with the same values in its material block.
    let names = ["sun_intensity", "mie_g_forward", "view_samples"].map(String::from);
    let over_lowered =
        gdsky_naga::lower(&front, &gdsky_naga::LowerOptions { overrides: names.to_vec(), ..Default::default() })
            .expect("the override sky lowers");
    for n in &names {
        assert!(!over_lowered.uniforms.contains_key(n), "`{n}` left the uniforms");
    }
    let over_wgsl = gdsky_naga::to_wgsl(&over_lowered).expect("WGSL");
    assert!(over_wgsl.contains("@id(0) override sun_intensity"), "{over_wgsl}");
    // The same overrides as SPIR-V specialization constants: valid for Vulkan, read back by
    // naga as overrides with their ids and defaults, and rendered through wgpu's SPIR-V input.
    let over_spirv = gdsky_naga::to_spirv(&over_lowered).expect("SPIR-V with specialization constants");
    crate::common::spirv_val(&over_spirv);
    let bytes: Vec<u8> = over_spirv.iter().flat_map(|w| w.to_le_bytes()).collect();
    let reread = naga::front::spv::parse_u8_slice(&bytes, &naga::front::spv::Options::default()).expect("re-reads");
    let read: Vec<(Option<u16>, Option<naga::Literal>)> = reread
        .overrides
        .iter()
        .map(|(_, o)| {
            let init = o.init.and_then(|i| match reread.global_expressions[i] {
                naga::Expression::Literal(l) => Some(l),
                _ => None,
            });
            (o.id, init)
        })
        .collect();
    for expected in [
        (Some(0), Some(naga::Literal::F32(62.832))),
        (Some(1), Some(naga::Literal::F32(0.85))),
        (Some(2), Some(naga::Literal::I32(24))),
    ] {
        assert!(read.contains(&expected), "{expected:?} not among the SPIR-V's overrides {read:?}");
    }
    let cases: [(f32, f32, i32); 3] = [(62.832, 0.85, 24), (20.0, 0.7, 16), (120.0, 0.95, 8)];
    for (sun, g, samples) in cases {
        let constants =
            vec![("0".to_string(), f64::from(sun)), ("1".into(), f64::from(g)), ("2".into(), f64::from(samples))];
        let over =
            SkyShader::new(&gpu, &over_wgsl, SubPasses::default()).expect("compiles").with_constants(constants.clone());
        let over_spv = SkyShader::from_spirv(&gpu, &over_wgsl, &over_spirv, SubPasses::default())
            .expect("the SPIR-V compiles")
            .with_constants(constants);
        let p = FreemanParams {
            sun_intensity: f64::from(sun),
            mie_g_forward: f64::from(g),
            view_samples: samples,
            ..FreemanParams::default()
        };
        let over_material = freeman_material(&over_lowered, &p);
        let generic_material = freeman_material(&lowered, &p);
        let (worst, identical) = difference(
            &draw(&over, &over_material, Projection::Panorama),
            &draw(&generic, &generic_material, Projection::Panorama),
        );
        eprintln!("overrides ({sun}, {g}, {samples}): worst relative difference {worst:e}, bit-identical {identical}");
        assert!(worst <= MAX_REL, "overrides ({sun}, {g}, {samples}) differ from generic by {worst:e}");
        let (worst, identical) = difference(
            &draw(&over_spv, &over_material, Projection::Panorama),
            &draw(&generic, &generic_material, Projection::Panorama),
        );
        eprintln!(
            "specialization constants ({sun}, {g}, {samples}): worst relative difference {worst:e}, bit-identical {identical}"
        );
        assert!(worst <= MAX_REL, "SPIR-V ({sun}, {g}, {samples}) differs from generic by {worst:e}");
    }
}

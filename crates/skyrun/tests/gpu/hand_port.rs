//! The hand-written WGSL port of the Freeman sky (`benches/freeman_hand.wgsl`, the human
//! baseline of the render-time benchmark) rendered on a Vulkan device (lavapipe on a machine
//! without a GPU): against skyref's f32 reference, and against gdsky's converted shader drawn
//! with the same inputs.
//!
//! One test function, so the environment is set before any thread reads it and one device
//! serves every render. Without a Vulkan adapter the test fails: it does not skip.

use skyref::{FreemanParams, Projection, Scene};
use skyrun::{SkyBuiltins, compare, freeman_material, render, worst_pixels};

/// The hand port, as the benchmark loads it.
const HAND_WGSL: &str = include_str!("../../benches/freeman_hand.wgsl");
const WIDTH: u32 = 64;
const HEIGHT: u32 = 32;
/// Relative errors are |gpu − ref| / max(|ref|, FLOOR).
const FLOOR: f32 = 1e-4;
/// Bound on the 99.9th percentile of the relative error, against skyref and against the
/// converted shader.
const P999_BOUND: f64 = 1e-4;

/// Member names and offsets, and the span, of the struct `name` in `module`.
fn struct_layout(module: &naga::Module, name: &str) -> (Vec<(String, u32)>, u32) {
    let (_, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no struct {name} in the module"));
    match &ty.inner {
        naga::TypeInner::Struct { members, span } => {
            (members.iter().map(|m| (m.name.clone().unwrap_or_default(), m.offset)).collect(), *span)
        }
        other => panic!("{name} is not a struct: {other:?}"),
    }
}

/// (group, binding, struct name) of every uniform buffer in `module`, sorted.
fn uniform_bindings(module: &naga::Module) -> Vec<(u32, u32, String)> {
    let mut found: Vec<_> = module
        .global_variables
        .iter()
        .filter(|(_, g)| g.space == naga::AddressSpace::Uniform)
        .map(|(_, g)| {
            let binding = g.binding.as_ref().expect("a uniform has a binding");
            (binding.group, binding.binding, module.types[g.ty].name.clone().unwrap_or_default())
        })
        .collect();
    found.sort();
    found
}

#[test]
fn hand_port_matches_skyref_and_the_converted_shader() {
    let gpu = crate::common::gpu();
    let (_, lowered, converted) = crate::common::converted_freeman();
    let params = FreemanParams::default();
    // Filled at the lowering's offsets: the hand port must lay its block out the same way.
    let material = freeman_material(&lowered, &params);

    let mut failures = Vec::new();

    // A drop-in at the binding level: same uniform blocks at the same bindings, same layouts,
    // same entry points.
    let hand = naga::front::wgsl::parse_str(HAND_WGSL).unwrap_or_else(|e| panic!("{}", e.emit_to_string(HAND_WGSL)));
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::empty())
        .validate(&hand)
        .unwrap_or_else(|e| panic!("the hand port does not validate: {e:?}"));
    if uniform_bindings(&hand) != uniform_bindings(&lowered.module) {
        failures.push(format!(
            "uniform bindings differ: hand {:?}, converted {:?}",
            uniform_bindings(&hand),
            uniform_bindings(&lowered.module)
        ));
    }
    for name in ["SkyBuiltins", "SkyLight", "Material"] {
        let (h, c) = (struct_layout(&hand, name), struct_layout(&lowered.module, name));
        if h != c {
            failures.push(format!("{name} layout differs: hand {h:?}, converted {c:?}"));
        }
    }
    for entry in ["vs_main", "fs_panorama", "fs_camera"] {
        if !hand.entry_points.iter().any(|e| e.name == entry) {
            failures.push(format!("the hand port has no entry point {entry}"));
        }
    }

    let panorama_scene = Scene::default().with_sun(10.0, 30.0).with_position(glam::DVec3::new(0.0, 1.0, 0.0));
    let camera_scene = panorama_scene.with_fov(90.0).with_view(0.0, 10.0);

    for (projection, scene) in [(Projection::Panorama, panorama_scene), (Projection::Camera, camera_scene)] {
        let builtins = SkyBuiltins::from_scene(&scene, WIDTH, HEIGHT);
        let hand_image = render(&gpu, HAND_WGSL, projection, WIDTH, HEIGHT, &builtins, &material)
            .unwrap_or_else(|e| panic!("{projection:?}: rendering the hand port failed: {e}"));
        let converted_image = render(&gpu, &converted, projection, WIDTH, HEIGHT, &builtins, &material)
            .unwrap_or_else(|e| panic!("{projection:?}: rendering the converted shader failed: {e}"));
        let reference = skyref::f32::render(&params, &scene, projection, WIDTH, HEIGHT);

        for (against, other) in [("skyref f32", &reference), ("converted", &converted_image)] {
            let m = compare(&hand_image, other, FLOOR);
            eprintln!("{projection:?} {WIDTH}×{HEIGHT}, hand port against {against}: {m}");
            for p in worst_pixels(&hand_image, other, FLOOR, WIDTH as usize, 4).iter().filter(|p| p.rel > 0.0) {
                eprintln!("    {p}");
            }
            if m.nan != 0 || m.inf != 0 {
                failures.push(format!("{projection:?} vs {against}: {} NaN and {} Inf channels", m.nan, m.inf));
            }
            if m.p999_rel > P999_BOUND {
                failures.push(format!(
                    "{projection:?} vs {against}: p99.9 relative error {:.3e} > {P999_BOUND:.0e}",
                    m.p999_rel
                ));
            }
        }
        // Alpha: 0 in the full pass, as the wrapper writes it.
        if let Some(p) = hand_image.iter().zip(&converted_image).find(|(h, c)| h[3] != c[3]) {
            failures.push(format!("{projection:?}: alpha differs from the converted shader: {p:?}"));
        }
    }

    // The comparison has power: the sun mirrored to azimuth −30° must fail it by far.
    let mirrored = panorama_scene.with_sun(10.0, -30.0);
    let builtins = SkyBuiltins::from_scene(&mirrored, WIDTH, HEIGHT);
    let wrong = render(&gpu, HAND_WGSL, Projection::Panorama, WIDTH, HEIGHT, &builtins, &material).expect("render");
    let reference = skyref::f32::render(&params, &panorama_scene, Projection::Panorama, WIDTH, HEIGHT);
    let m = compare(&wrong, &reference, FLOOR);
    eprintln!("negative control (sun at −30° against +30°): {m}");
    if m.p999_rel < 1000.0 * P999_BOUND {
        failures
            .push(format!("a mirrored sun passes the comparison (p99.9 {:.3e}): the check has no power", m.p999_rel));
    }

    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

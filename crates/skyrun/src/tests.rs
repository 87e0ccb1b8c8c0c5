//! Host-side checks that need no GPU: the byte layouts against naga's.

use crate::*;
use std::path::Path;

fn freeman() -> gdsky_naga::Lowered {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/freeman_sky.gdshader");
    let front = gdshader::check_file(&path).expect("fixture readable");
    gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).expect("the Freeman sky lowers")
}

/// Member offsets and the span of the struct `name` in the lowered module.
fn struct_layout(module: &naga::Module, name: &str) -> (Vec<(String, u32)>, u32) {
    let ty = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no struct {name} in the module"));
    match &ty.1.inner {
        naga::TypeInner::Struct { members, span } => {
            (members.iter().map(|m| (m.name.clone().unwrap_or_default(), m.offset)).collect(), *span)
        }
        other => panic!("{name} is not a struct: {other:?}"),
    }
}

#[test]
fn builtins_offsets_match_the_wrapper() {
    let lowered = freeman();
    let (members, span) = struct_layout(&lowered.module, "SkyBuiltins");
    assert_eq!(span as usize, SkyBuiltins::SIZE);
    let expected = [
        ("camera_basis", offsets::CAMERA_BASIS),
        ("position", offsets::POSITION),
        ("time", offsets::TIME),
        ("screen_size", offsets::SCREEN_SIZE),
        ("tan_half_fov", offsets::TAN_HALF_FOV),
        ("render_pass", offsets::RENDER_PASS),
        ("luminance_multiplier", offsets::LUMINANCE_MULTIPLIER),
        ("cube_face", offsets::CUBE_FACE),
        ("lights", offsets::LIGHTS),
    ];
    let got: Vec<(&str, usize)> = members.iter().map(|(n, o)| (n.as_str(), *o as usize)).collect();
    assert_eq!(got, expected);

    let (members, span) = struct_layout(&lowered.module, "SkyLight");
    assert_eq!(span as usize, offsets::LIGHT_STRIDE);
    let expected = [
        ("direction", offsets::LIGHT_DIRECTION),
        ("energy", offsets::LIGHT_ENERGY),
        ("color", offsets::LIGHT_COLOR),
        ("size", offsets::LIGHT_SIZE),
        ("enabled", offsets::LIGHT_ENABLED),
    ];
    let got: Vec<(&str, usize)> = members.iter().map(|(n, o)| (n.as_str(), *o as usize)).collect();
    assert_eq!(got, expected);
}

fn f32_at(bytes: &[u8], offset: usize) -> f32 {
    f32::from_le_bytes(bytes[offset..offset + 4].try_into().unwrap())
}

fn u32_at(bytes: &[u8], offset: usize) -> u32 {
    u32::from_le_bytes(bytes[offset..offset + 4].try_into().unwrap())
}

#[test]
fn builtins_bytes_from_a_scene() {
    let mut scene = skycore::Scene::default()
        .with_sun(10.0, 30.0)
        .with_position(glam::DVec3::new(0.0, 1.0, 0.0))
        .with_view(0.0, 10.0);
    scene.lights[2] = skycore::Light { angular_diameter_deg: 0.5, ..skycore::Light::default() };
    let b = SkyBuiltins::from_scene(&scene, 64, 32).to_bytes();
    let basis = scene.camera.basis();
    // Column 1 (up) of the basis at 16..28, its padding lane zero.
    assert_eq!(f32_at(&b, 16 + 4), basis.y_axis.y as f32);
    assert_eq!(f32_at(&b, 16 + 8), basis.y_axis.z as f32);
    assert_eq!(u32_at(&b, 28), 0);
    assert_eq!(f32_at(&b, offsets::POSITION + 4), 1.0);
    assert_eq!(f32_at(&b, offsets::SCREEN_SIZE), 64.0);
    assert_eq!(f32_at(&b, offsets::SCREEN_SIZE + 4), 32.0);
    assert_eq!(f32_at(&b, offsets::TAN_HALF_FOV), scene.camera.tan_half_fov() as f32);
    assert_eq!(u32_at(&b, offsets::RENDER_PASS), 0);
    assert_eq!(f32_at(&b, offsets::LUMINANCE_MULTIPLIER), 1.0);
    let sun = scene.sun().direction();
    let l0 = offsets::LIGHTS;
    assert_eq!(f32_at(&b, l0 + offsets::LIGHT_DIRECTION + 4), sun.y as f32);
    assert_eq!(f32_at(&b, l0 + offsets::LIGHT_ENERGY), 1.0);
    assert_eq!(f32_at(&b, l0 + offsets::LIGHT_COLOR + 8), 1.0);
    assert_eq!(u32_at(&b, l0 + offsets::LIGHT_ENABLED), 1);
    let light = |n: usize| offsets::LIGHTS + n * offsets::LIGHT_STRIDE;
    let off = light(1);
    assert_eq!((u32_at(&b, off + offsets::LIGHT_ENABLED), f32_at(&b, off + offsets::LIGHT_ENERGY)), (0, 0.0));
    assert!(b[off + offsets::LIGHT_COLOR..off + offsets::LIGHT_COLOR + 12].iter().all(|&x| x == 0), "no colour");
    assert_eq!(u32_at(&b, light(2) + offsets::LIGHT_ENABLED), 1);
    assert_eq!(f32_at(&b, light(2) + offsets::LIGHT_SIZE), 0.5f64.to_radians() as f32);
}

#[test]
fn freeman_material_follows_the_lowered_offsets() {
    let lowered = freeman();
    let params = skyref::FreemanParams::default();
    let bytes = freeman_material(&lowered, &params);
    assert_eq!(bytes.len(), lowered.material_size as usize);
    assert_eq!(lowered.uniforms.len(), 22);
    let slot = |n: &str| lowered.uniforms[n].offset as usize;
    assert_eq!(f32_at(&bytes, slot("sun_intensity")), 62.832);
    assert_eq!(f32_at(&bytes, slot("sun_wavelengths") + 8), 0.48);
    assert_eq!(f32_at(&bytes, slot("planet_radius")), 6_360_000.0);
    assert_eq!(f32_at(&bytes, slot("ground_color") + 4), 0.11);
    assert_eq!(u32_at(&bytes, slot("view_samples")), 24);
    assert_eq!(u32_at(&bytes, slot("sun_samples")), 8);
}

#[test]
fn material_values_are_type_checked() {
    let lowered = freeman();
    let err = material_bytes(&lowered, &[("view_samples", UniformValue::Float(24.0))]).unwrap_err();
    assert_eq!(
        err,
        MaterialError::TypeMismatch { name: "view_samples".into(), expected: "int".into(), given: "float".into() }
    );
    let err = material_bytes(&lowered, &[("no_such", UniformValue::Int(1))]).unwrap_err();
    assert_eq!(err, MaterialError::NoSuchUniform("no_such".into()));
}

#[test]
fn shader_defaults_equal_skyrefs_hand_written_defaults() {
    // skyref's `FreemanParams::default()` was written by hand from the shader text; the
    // material built from the checker's constant-folded defaults must be the same bytes.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/freeman_sky.gdshader");
    let front = gdshader::check_file(&path).expect("fixture readable");
    let shader = front.shader.as_ref().expect("checks");
    let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).expect("lowers");
    let from_shader = material_with_defaults(shader, &lowered, &[]).expect("defaults");
    assert_eq!(from_shader, freeman_material(&lowered, &skyref::FreemanParams::default()));

    let set = |name: &str, value: &str| vec![(name.to_string(), value.to_string())];
    let sixteen = material_with_defaults(shader, &lowered, &set("view_samples", "16")).expect("override");
    let at = lowered.uniforms["view_samples"].offset as usize;
    assert_eq!(i32::from_le_bytes(sixteen[at..at + 4].try_into().unwrap()), 16);
    let ground = material_with_defaults(shader, &lowered, &set("ground_color", "0.5, 0.25, 1")).expect("override");
    let at = lowered.uniforms["ground_color"].offset as usize;
    let read = |i: usize| f32::from_le_bytes(ground[at + 4 * i..at + 4 * i + 4].try_into().unwrap());
    assert_eq!([read(0), read(1), read(2)], [0.5, 0.25, 1.0]);

    assert!(matches!(
        material_with_defaults(shader, &lowered, &set("no_such", "1")),
        Err(MaterialError::NoSuchUniform(_))
    ));
    assert!(matches!(
        material_with_defaults(shader, &lowered, &set("view_samples", "1.5")),
        Err(MaterialError::BadValue { .. })
    ));
}

/// The bounded selection of `worst_pixels` gives what sorting every channel gives (the obvious
/// algorithm, which needed memory for every channel), ties included, for every count.
#[test]
fn worst_pixels_selects_what_a_full_sort_selects() {
    // A deterministic pseudo-random image with repeated values (ties) and a NaN.
    let mut state = 0x2545_f491_u32;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        (state % 7) as f32 * 0.25
    };
    let a: Vec<[f32; 4]> = (0..300).map(|_| [next(), next(), next(), 1.0]).collect();
    let mut b: Vec<[f32; 4]> = (0..300).map(|_| [next(), next(), next(), 1.0]).collect();
    b[77][1] = f32::NAN;
    let width = 20;
    let mut all: Vec<crate::PixelDiff> = crate::worst_pixels(&a, &b, 1e-4, width, usize::MAX / 4);
    assert_eq!(all.len(), 900);
    // The reference: every channel, stably sorted worst first (pixel order breaks ties).
    let mut reference: Vec<(f64, usize, usize)> = Vec::new();
    for (i, (pa, pb)) in a.iter().zip(&b).enumerate() {
        for c in 0..3 {
            let rel = if pa[c].is_finite() && pb[c].is_finite() {
                (f64::from(pa[c]) - f64::from(pb[c])).abs() / f64::from(pb[c]).abs().max(1e-4)
            } else {
                f64::INFINITY
            };
            reference.push((rel, i, c));
        }
    }
    reference.sort_by(|p, q| q.0.total_cmp(&p.0));
    for count in [1, 2, 3, 10, 37, 899, 900, 1000] {
        let got = crate::worst_pixels(&a, &b, 1e-4, width, count);
        let want: Vec<(usize, usize, usize)> =
            reference.iter().take(count).map(|&(_, i, c)| (i % width, i / width, c)).collect();
        let got: Vec<(usize, usize, usize)> = got.iter().map(|d| (d.x, d.y, d.channel)).collect();
        assert_eq!(got, want, "count {count}");
    }
    all.truncate(1);
    assert_eq!((all[0].x, all[0].y, all[0].channel), (77 % width, 77 / width, 1), "NaN first");
}

//! The user-facing defects of the architecture issue, each held by a test: the output format
//! follows `-o`'s extension, every light's size and fields reach the shader from flags and scene
//! files, a shader's own `use_debanding` and Godot 4.6's SKY_COORDS are the defaults, a shader
//! without uniforms declares no material block (and the reflection says so), and the SPIR-V is
//! the same bytes from every build profile.

use crate::common::{gdsky, scratch, text};
use std::path::Path;

fn arg(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[test]
fn the_output_format_follows_the_extension() {
    let dir = scratch("defects", "format");
    let png = dir.join("sky.png");
    let o = gdsky(&["render", "--size", "16x8", "-o", arg(&png)]);
    assert!(o.status.success(), "{}", text(&o));
    let bytes = std::fs::read(&png).expect("a PNG was written");
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "-o sky.png writes a PNG, not an EXR");
    let exr = dir.join("sky.exr");
    let o = gdsky(&["render", "--size", "16x8", "-o", arg(&exr)]);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(&std::fs::read(&exr).expect("an EXR")[..4], &[0x76, 0x2f, 0x31, 0x01]);
    let jpg = dir.join("sky.jpg");
    let o = gdsky(&["render", "--size", "16x8", "-o", arg(&jpg)]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("`.exr`") && text(&o).contains("`.png`"), "{}", text(&o));
    assert!(!jpg.exists(), "nothing is written under a name of the wrong format");
}

/// A sky that shows LIGHT0_SIZE, LIGHT1_SIZE, LIGHT1_ENERGY and LIGHT1_ENABLED as its colour.
const LIGHTS_SKY: &str = "shader_type sky;
void sky() {
    COLOR = vec3(LIGHT0_SIZE, LIGHT1_SIZE, LIGHT1_ENABLED ? LIGHT1_ENERGY : -1.0);
}
";

fn centre(path: &Path) -> [f32; 4] {
    let image = skyrun::read_exr(path).expect("an EXR");
    image.pixels[(image.height / 2 * image.width + image.width / 2) as usize]
}

#[test]
fn every_light_s_size_and_fields_reach_the_shader() {
    let dir = scratch("defects", "lights");
    let shader = dir.join("lights.gdshader");
    std::fs::write(&shader, LIGHTS_SKY).expect("writes");
    let out = dir.join("flags.exr");
    let o = gdsky(&[
        "render",
        arg(&shader),
        "--size",
        "8x4",
        "--sun-size",
        "2",
        "--light",
        "1:elevation=40:azimuth=180:energy=0.25:size=0.5",
        "-o",
        arg(&out),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let p = centre(&out);
    assert!((p[0] - 2f32.to_radians()).abs() < 1e-6 && (p[1] - 0.5f32.to_radians()).abs() < 1e-6, "{p:?}");
    assert_eq!(p[2], 0.25);

    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        "shader = \"lights.gdshader\"\nsize = [8, 4]\n[sun]\nsize = 2.0\n[[lights]]\nelevation = 30\nenergy = 0.75\nsize = 1.0\n",
    )
    .expect("writes");
    let out = dir.join("scene.exr");
    let o = gdsky(&["render", arg(&scene), "-o", arg(&out)]);
    assert!(o.status.success(), "a scene's [sun] size is read: {}", text(&o));
    let p = centre(&out);
    assert!((p[0] - 2f32.to_radians()).abs() < 1e-6 && (p[1] - 1f32.to_radians()).abs() < 1e-6, "{p:?}");
    assert_eq!(p[2], 0.75);

    let o = gdsky(&["render", arg(&shader), "--light", "4:energy=1", "-o", arg(&dir.join("x.exr"))]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("0 to 3"), "{}", text(&o));
}

/// A sky that declares `use_debanding` and reads SKY_COORDS.
const GODOT_LOOK_SKY: &str = "shader_type sky;
render_mode use_debanding;
void sky() {
    COLOR = vec3(SKY_COORDS.y, 0.25, 0.25);
}
";

#[test]
fn godot_4_6_s_look_is_the_default() {
    let dir = scratch("defects", "godot_look");
    let shader = dir.join("look.gdshader");
    std::fs::write(&shader, GODOT_LOOK_SKY).expect("writes");
    let render = |name: &str, flags: &[&str]| {
        let out = dir.join(name);
        let o = gdsky(&[&["render", arg(&shader), "--size", "64x32", "-o", arg(&out)], flags].concat());
        assert!(o.status.success(), "{}", text(&o));
        skyrun::read_exr(&out).expect("an EXR").pixels
    };
    let default = render("default.exr", &[]);
    let plain = render("plain.exr", &["--debanding", "none", "--sky-coords", "exact"]);
    let plain_godot46 = render("plain46.exr", &["--debanding", "none"]);
    // Godot's dither: ±1/255 on the constant channels, where the shader wrote exactly 0.25.
    let dithered = default.iter().filter(|p| p[1] != 0.25).count();
    assert!(dithered > default.len() / 2, "the dither is on by default: {dithered} pixels");
    assert!(plain.iter().all(|p| p[1] == 0.25 && p[2] == 0.25));
    // The dither is all that `--debanding none` takes away: the coordinates stay Godot 4.6's.
    // Godot's dither is (r, -r, r), so red moves exactly as blue does.
    let off_by_dither = default.iter().zip(&plain_godot46).all(|(a, b)| {
        let blue = a[2] - b[2];
        blue.abs() <= 1.01 / 255.0 && (a[1] - b[1] + blue).abs() < 1e-6 && (a[0] - b[0] - blue).abs() < 1e-6
    });
    assert!(off_by_dither, "--debanding none removes the dither and nothing else");
    // SKY_COORDS: Godot 4.6's acos_approx moves v by up to 2.9e-3 from the exact value.
    let largest = plain.iter().zip(&plain_godot46).map(|(a, b)| (a[0] - b[0]).abs()).fold(0f32, f32::max);
    assert!(largest > 1e-4 && largest < 3e-3, "godot46 SKY_COORDS by default: {largest}");
}

#[test]
fn a_shader_without_uniforms_declares_no_material_block() {
    let sky =
        gdsky::convert("plain.gdshader", "shader_type sky;\nvoid sky() { COLOR = EYEDIR; }\n", &Default::default())
            .expect("converts");
    assert!(!sky.reflection.bindings.material.declared);
    assert_eq!(sky.reflection.bindings.material.size, 0);
    assert!(!sky.wgsl.contains("@group(1)"), "{}", sky.wgsl);
    assert!(!sky.rust.contains("struct"), "no empty struct: {}", sky.rust);
    let tinted = gdsky::convert(
        "tinted.gdshader",
        "shader_type sky;\nuniform vec3 tint = vec3(1.0);\nvoid sky() { COLOR = tint; }\n",
        &Default::default(),
    )
    .expect("converts");
    assert!(tinted.reflection.bindings.material.declared);
    assert!(tinted.rust.contains("pub struct TintedMaterial"));
}

#[test]
fn build_errors_are_returned_once_and_readable() {
    let dir = scratch("defects", "build_error");
    let shader = dir.join("bad.gdshader");
    std::fs::write(&shader, "shader_type sky;\nvoid sky() { COLOR = 1; }\n").expect("writes");
    let err = gdsky::build::compile_into(&shader, &dir).expect_err("the shader is wrong");
    let debug = format!("{err:?}");
    assert_eq!(debug, err.to_string(), "`.expect()` shows the same text as Display");
    assert!(debug.contains("error[E300]") && debug.contains("bad.gdshader:2:"), "{debug}");
    assert!(!debug.contains("\\n"), "no escaped newlines: {debug}");
}

//! Material textures on a real device (lavapipe): `--texture NAME=PATH` and a scene file's
//! `[textures]` bind images to sampler uniforms in place of the 1×1 stand-ins.
//!
//! * A 32-bit float EXR read with `texelFetch` comes back bit for bit (a 16-bit path would
//!   round every value below).
//! * A PNG for a `source_color` uniform is decoded from sRGB by the GPU; without the hint it is
//!   byte / 255.
//! * Wrong names, missing and malformed files are clear errors with the CLI's exit codes (1 the
//!   input is wrong, 2 the file cannot be read), located in a scene file when they come from one.

use crate::common::{gdsky, scratch, text};
use std::path::{Path, PathBuf};

const TABLE_SHADER: &str = "tests/shaders/textures/texel_table.gdshader";
const COLOUR_SHADER: &str = "tests/shaders/textures/colour_and_data.gdshader";

fn arg(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

/// The 4×2 table: values a 16-bit float cannot hold (each has mantissa bits below binary16's
/// 10), small, large and negative, row 0 at the top.
fn table() -> skyrun::Image {
    let values: [[f32; 4]; 8] = [
        [1e-7, std::f32::consts::PI, 12345.678, 1.0], // 3.14159265 as f32
        [1.000_000_1, -1.732_050_8, 6.0e30, 0.5],
        [0.1, 0.2, 0.3, 0.0],
        [-1e-5, 65519.5, 1.0 / 3.0, 1.0],
        [123_456.79, 7.777_777, -0.001_234_5, 1.0],
        [2.5e-20, 9.999_999e9, 0.999_999_9, 1.0],
        [42.424_244, -42.424_244, 1.5e-3, 1.0],
        [std::f32::consts::E, std::f32::consts::LN_2, std::f32::consts::SQRT_2, 1.0],
    ];
    skyrun::Image::new(4, 2, values.to_vec()).expect("4×2 image")
}

fn write_table(dir: &Path) -> PathBuf {
    let path = dir.join("table.exr");
    skyrun::write_exr(&path, &table()).expect("writes the table");
    path
}

/// A `width`×`height` 8-bit RGB PNG of one grey level.
fn write_grey_png(path: &Path, width: u32, height: u32, level: u8) {
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().expect("PNG header");
    writer.write_image_data(&vec![level; (width * height * 3) as usize]).expect("PNG data");
    writer.finish().expect("PNG end");
    std::fs::write(path, bytes).expect("writes the PNG");
}

#[test]
fn texel_fetch_of_an_f32_exr_returns_its_floats_bit_for_bit() {
    let dir = scratch("textures", "texel_fetch");
    let table_path = write_table(&dir);
    let out = dir.join("out.exr");
    let o = gdsky(&[
        "render",
        TABLE_SHADER,
        "--texture",
        &format!("table={}", arg(&table_path)),
        "--size",
        "4x2",
        "-o",
        arg(&out),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let rendered = skyrun::read_exr(&out).expect("reads the render");
    let expected = table();
    for (i, (got, want)) in rendered.pixels.iter().zip(&expected.pixels).enumerate() {
        // RGB: the wrapper forces alpha to 0 in the full pass, as Godot does.
        for c in 0..3 {
            assert_eq!(got[c].to_bits(), want[c].to_bits(), "texel {i} channel {c}: {} vs {}", got[c], want[c]);
        }
    }
    // The check has teeth: binary16 keeps 10 mantissa bits, and these values need more.
    assert!(expected.pixels.iter().flat_map(|p| &p[..3]).filter(|v| v.to_bits() & 0x1fff != 0).count() >= 20);
}

#[test]
fn a_png_for_a_source_color_uniform_is_decoded_from_srgb() {
    let dir = scratch("textures", "srgb");
    let grey = dir.join("grey.png");
    write_grey_png(&grey, 4, 4, 128);
    let out = dir.join("out.exr");
    let o = gdsky(&[
        "render",
        COLOUR_SHADER,
        "--texture",
        &format!("albedo={}", arg(&grey)),
        "--texture",
        &format!("data={}", arg(&grey)),
        "--size",
        "8x4",
        "-o",
        arg(&out),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let rendered = skyrun::read_exr(&out).expect("reads the render");
    // The sRGB transfer function at 128/255.
    let c: f64 = 128.0 / 255.0;
    let linear = ((c + 0.055) / 1.055).powf(2.4) as f32;
    assert!((linear - 0.2158).abs() < 1e-4);
    for p in &rendered.pixels {
        // Vulkan allows the decode some slack (lavapipe's is within 1e-6 here).
        assert!((p[0] - linear).abs() < 1e-3, "source_color: {} vs {linear}", p[0]);
        assert!((p[1] - 128.0 / 255.0).abs() < 1e-6, "no hint: {} vs {}", p[1], 128.0 / 255.0);
    }
}

#[test]
fn an_f32_texture_for_a_sampled_uniform_is_refused_with_advice() {
    let dir = scratch("textures", "not_filterable");
    let table_path = write_table(&dir);
    let grey = dir.join("grey.png");
    write_grey_png(&grey, 1, 1, 200);
    let o = gdsky(&[
        "render",
        COLOUR_SHADER,
        "--texture",
        &format!("data={}", arg(&table_path)),
        "--texture",
        &format!("albedo={}", arg(&grey)),
        "-o",
        arg(&dir.join("out.exr")),
    ]);
    let err = text(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("`data` is sampled with filtering") && err.contains("texelFetch"), "{err}");
}

#[test]
fn wrong_names_and_bad_files_are_clear_errors() {
    let dir = scratch("textures", "errors");
    let table_path = write_table(&dir);
    let out = dir.join("out.exr");
    let render = |texture: &str| gdsky(&["render", TABLE_SHADER, "--texture", texture, "-o", arg(&out)]);

    // A typo: exit 1 with a suggestion; a name far from any: the list of sampler uniforms.
    let o = render(&format!("tabel={}", arg(&table_path)));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("no sampler uniform `tabel`; did you mean `table`?"), "{}", text(&o));
    let o = render(&format!("clouds={}", arg(&table_path)));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("its sampler uniforms are: table"), "{}", text(&o));
    let o = render("table");
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("expected NAME=PATH"), "{}", text(&o));

    // A missing file cannot be read: the environment's exit code, 2, as for every input file
    // (shader, scene, occluder); the message names the file.
    let missing = dir.join("no_such_table.exr");
    let o = render(&format!("table={}", arg(&missing)));
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("cannot read texture") && text(&o).contains("no_such_table.exr"), "{}", text(&o));

    // A file that is there but not an image, or a truncated EXR: the input is wrong, exit 1.
    let junk = dir.join("junk.png");
    std::fs::write(&junk, "not an image").expect("writes");
    let o = render(&format!("table={}", arg(&junk)));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("junk.png") && text(&o).contains("neither an OpenEXR nor a PNG"), "{}", text(&o));
    let truncated = dir.join("truncated.exr");
    let bytes = std::fs::read(&table_path).expect("reads");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).expect("writes");
    let o = render(&format!("table={}", arg(&truncated)));
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("truncated.exr"), "{}", text(&o));
    assert!(!out.exists(), "no image is written when a texture is wrong");

    // Commands that cannot use a texture say so instead of ignoring it.
    let o = gdsky(&["reference", "--texture", &format!("table={}", arg(&table_path)), "-o", arg(&out)]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let o = gdsky(&["bench", "--texture", &format!("table={}", arg(&table_path)), "-o", arg(&dir.join("bench"))]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("Freeman-compatible"), "{}", text(&o));
}

/// A scene file for the table shader in `dir` with `textures` as its `[textures]` body.
fn write_scene(dir: &Path, textures: &str) -> PathBuf {
    let shader = std::fs::canonicalize(TABLE_SHADER).expect("the test shader");
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        format!("shader = {:?}\nsize = [4, 2]\n\n[textures]\n{textures}", shader.to_str().expect("UTF-8")),
    )
    .expect("writes the scene");
    scene
}

#[test]
fn a_scene_files_textures_are_relative_to_it_and_located_when_wrong() {
    let dir = scratch("textures", "scene");
    std::fs::create_dir_all(dir.join("luts")).expect("mkdir");
    skyrun::write_exr(&dir.join("luts/table.exr"), &table()).expect("writes the table");
    let scene = write_scene(&dir, "table = \"luts/table.exr\"\n");
    let out = dir.join("out.exr");
    // Run from elsewhere: the path is the scene file's folder's, not the working directory's.
    let o = gdsky(&["render", arg(&scene), "-o", arg(&out)]);
    assert!(o.status.success(), "{}", text(&o));
    let rendered = skyrun::read_exr(&out).expect("reads the render");
    let bits = |img: &skyrun::Image| -> Vec<u32> {
        img.pixels.iter().flat_map(|p| p[..3].iter().map(|v| v.to_bits()).collect::<Vec<_>>()).collect()
    };
    assert_eq!(bits(&rendered), bits(&table()));

    // `--texture` replaces the scene's texture of the same name.
    let other = skyrun::Image::new(4, 2, vec![[0.25, 0.5, 0.75, 1.0]; 8]).expect("image");
    let other_path = dir.join("other.exr");
    skyrun::write_exr(&other_path, &other).expect("writes");
    let o = gdsky(&["render", arg(&scene), "--texture", &format!("table={}", arg(&other_path)), "-o", arg(&out)]);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(bits(&skyrun::read_exr(&out).expect("reads")), bits(&other));

    // `animate` binds them too.
    let frames = dir.join("frames");
    let o = gdsky(&["animate", arg(&scene), "-o", arg(&frames)]);
    assert!(o.status.success(), "{}", text(&o));
    assert_eq!(bits(&skyrun::read_exr(&frames.join("frame_0000.exr")).expect("reads")), bits(&table()));

    // An unknown name: located at the entry (line 5), exit 1.
    let bad = write_scene(&dir, "tabel = \"luts/table.exr\"\n");
    let o = gdsky(&["render", arg(&bad), "-o", arg(&out)]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("scene.toml:5:9") && text(&o).contains("did you mean `table`?"), "{}", text(&o));
    // A missing file: located at its path, exit 2.
    let bad = write_scene(&dir, "table = \"luts/missing.exr\"\n");
    let o = gdsky(&["render", arg(&bad), "-o", arg(&out)]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("scene.toml:5:9") && text(&o).contains("missing.exr"), "{}", text(&o));
}

#[test]
fn filter_and_repeat_hints_shape_the_samplers() {
    let dir = scratch("textures", "hints");
    // 2×1: black at u = 0.25, white at u = 0.75.
    let path = dir.join("black_white.png");
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, 2, 1);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.write_header().and_then(|mut w| w.write_image_data(&[0, 255])).expect("encodes");
    std::fs::write(&path, bytes).expect("writes");
    let out = dir.join("out.exr");
    let mut args = vec!["render".to_string(), "tests/shaders/textures/sampler_hints.gdshader".into()];
    for name in ["nearest_tex", "linear_clamp", "linear_repeat"] {
        args.extend(["--texture".into(), format!("{name}={}", arg(&path))]);
    }
    args.extend(["--size".into(), "8x2".into(), "-o".into(), arg(&out).into()]);
    let o = gdsky(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", text(&o));
    let image = skyrun::read_exr(&out).expect("reads the render");
    // Row 1, pixel x at u ≈ (x + ½)/8.
    let px = |x: usize| image.pixels[8 + x];
    let near = |a: f32, b: f32| (a - b).abs() < 0.02;
    // Nearest: black left of u = ½, white right of it.
    assert!((0..4).all(|x| px(x)[0] == 0.0) && (4..8).all(|x| px(x)[0] == 1.0), "{:?}", image.pixels);
    // Linear, clamped: black up to the first texel's centre (u = 0.0625 < 0.25), then a ramp.
    assert!(near(px(0)[1], 0.0) && near(px(3)[1], 0.375) && near(px(7)[1], 1.0), "{:?}", image.pixels);
    // Linear, repeating: at u = 0.0625 the wrapped white texel (centre −0.25) weighs 0.375.
    assert!(near(px(0)[2], 0.375) && near(px(3)[2], 0.375) && near(px(7)[2], 0.625), "{:?}", image.pixels);
}

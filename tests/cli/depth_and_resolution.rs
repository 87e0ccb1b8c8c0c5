//! Issue #11 items 3 and 4: the sky on the far plane (both depth conventions), the occluder
//! (`render --occluder MASK.png`: covered pixels are never shaded) and reduced sky resolution
//! (`render --sky-resolution half|quarter`). The GPU tests need a Vulkan adapter (lavapipe).
//! No test asserts on time.

use crate::common::{gdsky, scratch as scratch_in, text};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    scratch_in("depth_and_resolution", name)
}

fn arg(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// The z of the position `vs_main` returns in WGSL text, read back by naga's WGSL front end.
fn vertex_z(wgsl: &str) -> f32 {
    let module = naga::front::wgsl::parse_str(wgsl).expect("the emitted WGSL parses");
    gdsky_naga::depth_convention(&module).expect("vs_main returns vec4(x, y, z_literal, 1)").far_plane()
}

#[test]
fn vertex_entry_puts_the_sky_on_the_far_plane_in_both_conventions() {
    for (flag, far, convention, compare) in
        [(None, 1.0, "standard_z", "less_equal"), (Some("--reversed-z"), 0.0, "reversed_z", "greater_equal")]
    {
        let out = scratch(convention);
        let mut args = vec!["convert", "fixtures/freeman_sky.gdshader", "-o", arg(&out)];
        args.extend(flag);
        let run = gdsky(&args);
        assert_eq!(run.status.code(), Some(0), "{}", text(&run));
        let wgsl = std::fs::read_to_string(out.join("freeman_sky.wgsl")).expect("wgsl");
        assert_eq!(vertex_z(&wgsl), far, "{convention}: the WGSL's vs_main z");
        // The text itself, as a reader sees it: vec4<f32>(x, y, 1f or 0f, 1f).
        let vs = &wgsl[wgsl.find("fn vs_main").expect("vs_main")..];
        let ret = vs.lines().find(|l| l.trim_start().starts_with("return vec4")).expect("return line");
        assert!(ret.contains(if far == 1.0 { ", 1f, 1f)" } else { ", 0f, 1f)" }), "{ret}");
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("freeman_sky.json")).expect("json")).expect("json");
        assert_eq!(json["depth"]["far_plane"], serde_json::json!(far), "{json:#}");
        assert_eq!(json["depth"]["convention"], convention);
        assert_eq!(json["depth"]["compare"], compare);
        assert_eq!(json["depth"]["clear"], serde_json::json!(far));
    }
}

/// Writes an 8-bit grey PNG: `covered(x, y)` white, else black.
fn write_mask(path: &Path, w: u32, h: u32, covered: impl Fn(u32, u32) -> bool) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).expect("mask file"));
    let mut encoder = png::Encoder::new(file, w, h);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Eight);
    let data: Vec<u8> =
        (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| if covered(x, y) { 255 } else { 0 }).collect();
    encoder.write_header().expect("header").write_image_data(&data).expect("pixels");
}

const CONSTANT_SKY: &str = "shader_type sky;\nvoid sky() {\n\tCOLOR = vec3(0.25, 0.5, 0.75);\n}\n";
/// A smooth sky: a gradient in EYEDIR, no sun disk.
const SMOOTH_SKY: &str = "shader_type sky;\nvoid sky() {\n\tCOLOR = vec3(0.5 + 0.5 * EYEDIR.y, 0.5 + 0.25 * EYEDIR.x, 0.6 - 0.3 * EYEDIR.z);\n}\n";

fn render(dir: &Path, shader: &str, extra: &[&str], name: &str) -> skyrun::Image {
    let file = dir.join(format!("{name}.gdshader"));
    std::fs::write(&file, shader).expect("shader");
    let out = dir.join(format!("{name}.exr"));
    let mut args = vec!["render", arg(&file), "-o", arg(&out)];
    args.extend_from_slice(extra);
    let run = gdsky(&args);
    assert_eq!(run.status.code(), Some(0), "{args:?}: {}", text(&run));
    skyrun::read_exr(&out).expect("the EXR reads back")
}

#[test]
fn occluder_leaves_covered_pixels_at_the_clear_value() {
    let dir = scratch("occluder");
    // A 32×16 mask for a 64×32 render (scaled ×2, nearest): the left half and a block covered.
    let mask = dir.join("mask.png");
    write_mask(&mask, 32, 16, |x, y| x < 16 || (x >= 24 && y < 4));
    for projection in ["panorama", "camera"] {
        let image = render(
            &dir,
            CONSTANT_SKY,
            &["--size", "64x32", "--projection", projection, "--occluder", arg(&mask)],
            projection,
        );
        assert_eq!((image.width, image.height), (64, 32));
        for y in 0..32u32 {
            for x in 0..64u32 {
                let covered = x < 32 || (x >= 48 && y < 8);
                let px = image.pixels[(y * 64 + x) as usize];
                let want = if covered { skyrun::OCCLUDED } else { [0.25, 0.5, 0.75, 0.0] };
                assert_eq!(px, want, "{projection} pixel ({x}, {y}), covered {covered}");
            }
        }
    }
    // Reduced resolution with an occluder: covered pixels still hold the clear value, visible
    // ones are the sky (the reduced pass shades every texel a visible pixel reads).
    for resolution in ["half", "quarter"] {
        for filter in ["bilinear", "catmull-rom"] {
            let image = render(
                &dir,
                CONSTANT_SKY,
                &["--size", "64x32", "--occluder", arg(&mask), "--sky-resolution", resolution, "--upsample", filter],
                &format!("{resolution}-{filter}"),
            );
            for (i, px) in image.pixels.iter().enumerate() {
                let (x, y) = (i as u32 % 64, i as u32 / 64);
                let covered = x < 32 || (x >= 48 && y < 8);
                let want = if covered { skyrun::OCCLUDED } else { [0.25, 0.5, 0.75, 0.0] };
                assert_eq!(*px, want, "{resolution} {filter} pixel ({x}, {y})");
            }
        }
    }
}

#[test]
fn reversed_z_shader_is_occluded_alike() {
    // The skyrun API on a module lowered for reversed Z: the renderer reads the far plane from
    // vs_main and tests GreaterEqual against a depth buffer cleared to 0.
    let front = gdsky::check_source(
        "constant.gdshader",
        CONSTANT_SKY.as_bytes().to_vec(),
        None,
        &mut gdsky::frontend::FsLoader,
    );
    let reversed = gdsky_naga::LowerOptions { depth: gdsky::DepthConvention::Reversed, ..Default::default() };
    let lowered = gdsky_naga::lower(&front, &reversed).expect("lowers");
    let wgsl = gdsky_naga::to_wgsl(&lowered).expect("wgsl");
    let gpu = skytest::gpu();
    let shader = skyrun::SkyShader::new(&gpu, &wgsl, skyrun::SubPasses::default()).expect("compiles");
    assert_eq!(shader.depth_convention(), gdsky::DepthConvention::Reversed);
    let builtins = skyrun::SkyBuiltins::from_scene(&skyref::Scene::default(), 16, 8);
    let occluder = skyrun::Occluder::left_columns(16, 8, 0.25);
    let options = skyrun::RenderOptions { occluder: Some(&occluder), ..Default::default() };
    let r = shader.render_with(&gpu, skyref::Projection::Panorama, 16, 8, &builtins, &[], &options).expect("renders");
    for (i, px) in r.pixels.iter().enumerate() {
        let want = if i % 16 < 4 { skyrun::OCCLUDED } else { [0.25, 0.5, 0.75, 0.0] };
        assert_eq!(*px, want, "pixel {i}");
    }
}

#[test]
fn reduced_sky_resolution_has_the_target_size_and_is_close_on_a_smooth_sky() {
    let dir = scratch("resolution");
    for size in ["64x32", "66x30"] {
        let (w, h) = size.split_once('x').map(|(a, b)| (a.parse::<u32>().unwrap(), b.parse::<u32>().unwrap())).unwrap();
        for projection in ["panorama", "camera"] {
            let full = render(&dir, SMOOTH_SKY, &["--size", size, "--projection", projection], "full");
            for resolution in ["half", "quarter"] {
                for filter in ["bilinear", "catmull-rom"] {
                    let reduced = render(
                        &dir,
                        SMOOTH_SKY,
                        &[
                            "--size",
                            size,
                            "--projection",
                            projection,
                            "--sky-resolution",
                            resolution,
                            "--upsample",
                            filter,
                        ],
                        "reduced",
                    );
                    assert_eq!((reduced.width, reduced.height), (w, h), "{size} {resolution}");
                    let worst = full
                        .pixels
                        .iter()
                        .zip(&reduced.pixels)
                        .flat_map(|(a, b)| (0..4).map(move |c| (a[c] - b[c]).abs()))
                        .fold(0f32, f32::max);
                    // The gradient spans 1.0 over the image; a quarter-resolution texel is ≤ 1/8
                    // of it (32 rows / 4 over a span of π): bilinear on a smooth field errs by a
                    // small fraction of that, edges (clamped, or the panorama's poles) the most.
                    let bound = if resolution == "half" { 0.02 } else { 0.05 };
                    assert!(worst < bound, "{size} {projection} {resolution} {filter}: worst {worst}");
                }
            }
        }
    }
}

#[test]
fn bad_occluder_and_resolution_flags_are_refused() {
    let dir = scratch("bad_flags");
    let out = dir.join("out.exr");
    let run = gdsky(&["render", "-o", arg(&out), "--sky-resolution", "eighth"]);
    assert_eq!(run.status.code(), Some(1), "{}", text(&run));
    assert!(text(&run).contains("--sky-resolution"), "{}", text(&run));
    let run = gdsky(&["render", "-o", arg(&out), "--upsample", "nearest"]);
    assert_eq!(run.status.code(), Some(1), "{}", text(&run));
    let missing = dir.join("missing.png");
    let run = gdsky(&["render", "-o", arg(&out), "--occluder", arg(&missing)]);
    assert_eq!(run.status.code(), Some(2), "{}", text(&run));
    assert!(text(&run).contains("missing.png"), "{}", text(&run));
    let not_png = dir.join("not.png");
    std::fs::write(&not_png, "not a png").expect("write");
    let run = gdsky(&["render", "-o", arg(&out), "--occluder", arg(&not_png)]);
    assert_eq!(run.status.code(), Some(1), "{}", text(&run));
    assert!(text(&run).contains("not.png") && text(&run).contains("not a readable PNG"), "{}", text(&run));
    let run = gdsky(&["render", "-o", arg(&out), "--occluder", arg(&dir)]);
    assert_eq!(run.status.code(), Some(2), "a directory: {}", text(&run));
    let mask = dir.join("mask.png");
    write_mask(&mask, 4, 4, |x, _| x < 2);
    let run = gdsky(&["render", "-o", arg(&out), "--projection", "cubemap", "--size", "8x8", "--occluder", arg(&mask)]);
    assert_eq!(run.status.code(), Some(1), "{}", text(&run));
    assert!(text(&run).contains("cubemap"), "{}", text(&run));
    assert!(!out.exists(), "nothing rendered");
}

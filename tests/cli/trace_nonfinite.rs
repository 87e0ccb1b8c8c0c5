//! `gdsky render --trace-nonfinite` end to end on lavapipe: the instrumented module names the
//! first expression that made a NaN or an infinity, through `#include`s, with the pixels where
//! it did; a shader without one reports `no NaN or Inf` and writes no PNG.

use crate::common::{gdsky, scratch, text};
use std::path::{Path, PathBuf};
use std::process::Output;

fn arg(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Renders `shader` (64×32 panorama, or `extra` flags) with `--trace-nonfinite` into `dir`.
fn trace(dir: &Path, shader: &Path, extra: &[&str]) -> (Output, PathBuf) {
    let out = dir.join("sky.exr");
    let o = gdsky(&[&["render", arg(shader), "-o", arg(&out), "--size", "64x32", "--trace-nonfinite"], extra].concat());
    assert!(o.status.success(), "{}", text(&o));
    (o, dir.join("sky.nonfinite.png"))
}

/// The report's place lines (`  FILE:L:C: `EXPR` (KIND in FUNCTION): N pixels (COLOUR)`).
fn places(o: &Output) -> Vec<String> {
    String::from_utf8_lossy(&o.stdout).lines().filter(|l| l.starts_with("  ")).map(|l| l.trim().to_string()).collect()
}

/// Which pixels of the PNG are drawn in `colour`, row 0 at the top.
fn marked(png: &Path, colour: [u8; 3]) -> (u32, u32, Vec<bool>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(png).expect("the PNG exists")));
    let mut reader = decoder.read_info().expect("a PNG");
    let mut buf = vec![0; reader.output_buffer_size().expect("size")];
    let info = reader.next_frame(&mut buf).expect("a frame");
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let rgb = &buf[..info.buffer_size()];
    (info.width, info.height, rgb.chunks_exact(3).map(|c| c == colour).collect())
}

const MAGENTA: [u8; 3] = [255, 0, 255];

#[test]
fn planted_nan_in_an_included_helper_is_named_with_its_pixels() {
    let dir = scratch("trace_nonfinite", "planted");
    // sqrt of a negative number in the upper half of the panorama: x = 1 - EYEDIR.y < 1 there.
    std::fs::write(dir.join("helpers.gdshaderinc"), "// helpers\nfloat f(float x) { return sqrt(x - 1.0); }\n")
        .expect("write");
    let shader = dir.join("planted.gdshader");
    std::fs::write(
        &shader,
        "shader_type sky;\n#include \"helpers.gdshaderinc\"\nvoid sky() {\n    COLOR = vec3(f(1.0 - EYEDIR.y));\n}\n",
    )
    .expect("write");
    let (o, png) = trace(&dir, &shader, &[]);
    let lines = places(&o);
    assert_eq!(lines.len(), 1, "{}", text(&o));
    // Pixel row r of a 32-row panorama looks at EYEDIR.y = cos((r + 0.5) / 32 · π), positive
    // for rows 0..16: the upper half, 16 × 64 pixels.
    let expected = 16 * 64;
    assert!(
        lines[0]
            .ends_with(&format!("helpers.gdshaderinc:2:27: `sqrt(x - 1.0)` (sqrt in f): {expected} pixels (magenta)")),
        "{}",
        text(&o)
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains(&format!("in {expected} of 2048 pixels")), "{}", text(&o));
    let (w, h, m) = marked(&png, MAGENTA);
    assert_eq!((w, h), (64, 32));
    for (i, is_marked) in m.iter().enumerate() {
        assert_eq!(*is_marked, i / 64 < 16, "pixel {i}");
    }
    // The EXR is the shader's own render, bit for bit: the trace is a second render.
    let plain = dir.join("plain.exr");
    let p = gdsky(&["render", arg(&shader), "-o", arg(&plain), "--size", "64x32"]);
    assert!(p.status.success(), "{}", text(&p));
    let (a, b) = (skyrun::read_exr(&plain).expect("exr"), skyrun::read_exr(&dir.join("sky.exr")).expect("exr"));
    let bits = |i: &skyrun::Image| i.pixels.iter().flat_map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
    assert_eq!(bits(&a), bits(&b));
    assert!(!String::from_utf8_lossy(&p.stdout).contains("NaN"), "no report without the flag");
}

#[test]
fn freeman_with_zero_rayleigh_scale_height_names_the_division() {
    let dir = scratch("trace_nonfinite", "freeman_rayleigh_0");
    // At the camera (altitude 0.5 m, the clamp's floor) -altitude / 0 is -inf in IEEE (then
    // exp(-inf) = 0): every pixel's first non-finite value is that division, at the first call
    // of get_optical_depth_at_point, before any NaN the ground half ends with.
    let shader = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/freeman_sky.gdshader");
    let (o, png) = trace(&dir, &shader, &["--set", "rayleigh_scale_height=0"]);
    assert_eq!(
        places(&o),
        [format!(
            "{}:205:7: `-altitude / rayleigh_scale_height` (division in get_optical_depth_at_point): 2048 pixels (magenta)",
            shader.display()
        )],
        "{}",
        text(&o)
    );
    let (_, _, m) = marked(&png, MAGENTA);
    assert!(m.iter().all(|&b| b));
}

#[test]
fn the_half_res_pass_keeps_its_colour_and_alpha() {
    // The id goes to the full pass's alpha only: the sub-pass writes what it writes without the
    // trace (here a NaN colour and ALPHA 0.5), and the full pass computes with it. Were the
    // sub-pass's alpha the id (≥ 1), `sqrt(0.75 - HALF_RES_COLOR.a)` would be the first NaN; with
    // 0.5 it is 0.5, and the first NaN is the product with the sub-pass's NaN colour.
    let dir = scratch("trace_nonfinite", "half_res");
    let shader = dir.join("half.gdshader");
    std::fs::write(
        &shader,
        "shader_type sky;\nrender_mode use_half_res_pass;\nvoid sky() {\n    if (AT_HALF_RES_PASS) {\n        COLOR = vec3(sqrt(EYEDIR.y - 2.0));\n        ALPHA = 0.5;\n    } else {\n        COLOR = sqrt(0.75 - HALF_RES_COLOR.a) * HALF_RES_COLOR.rgb * 2.0;\n    }\n}\n",
    )
    .expect("write");
    let (o, _) = trace(&dir, &shader, &[]);
    let lines = places(&o);
    assert_eq!(lines.len(), 1, "{}", text(&o));
    assert!(
        lines[0].ends_with(
            "half.gdshader:8:17: `sqrt(0.75 - HALF_RES_COLOR.a) * HALF_RES_COLOR.rgb` (multiplication in sky): 2048 pixels (magenta)"
        ),
        "{}",
        text(&o)
    );
}

#[test]
fn nan_free_shaders_report_nothing() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (name, shader) in
        [("gradient_sun", "shaders/gradient_sun.gdshader"), ("freeman_defaults", "fixtures/freeman_sky.gdshader")]
    {
        let dir = scratch("trace_nonfinite", name);
        let (o, png) = trace(&dir, &root.join(shader), &[]);
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert_eq!(
            stdout.lines().filter(|l| !l.starts_with("wrote ")).collect::<Vec<_>>(),
            ["no NaN or Inf"],
            "{name}"
        );
        assert!(!png.exists(), "{name}: no PNG without a NaN or Inf");
    }
}

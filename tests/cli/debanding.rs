//! `gdsky render --debanding none|godot`: Godot's sky debanding, checked against the formula
//! computed here independently (docs/godot.md, "Debanding"), and absent from shaders that do
//! not declare `use_debanding`. Needs a Vulkan adapter (lavapipe).

use crate::common::{gdsky, scratch, text};
use std::path::Path;

const SHADER: &str = "tests/shaders/valid/debanding_gradient.gdshader";

/// Godot's `interleaved_gradient_noise(gl_FragCoord.xy)` in f32, for the pixel (x, y) (row 0 at
/// the top, FRAGCOORD at the pixel centre): `vec3(r, −r, r) / 255`.
#[allow(clippy::excessive_precision)] // Godot's literals as its GLSL writes them, rounded to f32.
fn godot_noise(x: usize, y: usize) -> [f32; 3] {
    let (fx, fy) = (x as f32 + 0.5, y as f32 + 0.5);
    let fract = |v: f32| v - v.floor();
    let r = fract(52.982_918_9 * fract(fx * 0.067_110_56 + fy * 0.005_837_15)) * 2.0 - 1.0;
    [r / 255.0, -r / 255.0, r / 255.0]
}

fn render(shader: &Path, mode: &str, out: &Path) -> skyrun::Image {
    let o = gdsky(&[
        "render",
        &shader.to_string_lossy(),
        "--projection",
        "camera",
        "--size",
        "64x32",
        "--debanding",
        mode,
        "-o",
        &out.to_string_lossy(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    skyrun::read_exr(out).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn godot_debanding_adds_godots_noise_exactly() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = scratch("debanding", "noise");
    let none = render(&root.join(SHADER), "none", &dir.join("none.exr"));
    let godot = render(&root.join(SHADER), "godot", &dir.join("godot.exr"));
    let mut largest = 0.0f32;
    for (i, (a, b)) in godot.pixels.iter().zip(&none.pixels).enumerate() {
        let (x, y) = (i % 64, i / 64);
        let n = godot_noise(x, y);
        for c in 0..3 {
            // The GPU may fuse the dot product (one rounding fewer: ≤ 2e-7 here) and the sum
            // rounds at the colour's ulp (≤ 1.5e-8 below 0.2); the noise itself is up to 3.9e-3.
            let err = ((a[c] - b[c]) - n[c]).abs();
            largest = largest.max(err);
            assert!(err < 1e-6, "({x}, {y}) channel {c}: godot − none = {}, Godot's noise {}", a[c] - b[c], n[c]);
        }
    }
    // The noise is there, at its full size somewhere: ±1/255.
    let peak = godot.pixels.iter().zip(&none.pixels).map(|(a, b)| (a[0] - b[0]).abs()).fold(0.0, f32::max);
    assert!(peak > 0.9 / 255.0, "largest difference {peak}");
    eprintln!("largest deviation from the formula: {largest:e}; largest noise {peak:e}");
}

#[test]
fn shaders_without_use_debanding_are_unchanged() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = scratch("debanding", "plain");
    let source = std::fs::read_to_string(root.join(SHADER)).expect("readable");
    assert!(source.contains("render_mode use_debanding;"));
    let plain = dir.join("plain.gdshader");
    std::fs::write(&plain, source.replace("render_mode use_debanding;", "")).expect("writable");
    let none = render(&plain, "none", &dir.join("none.exr"));
    let godot = render(&plain, "godot", &dir.join("godot.exr"));
    assert!(none.pixels == godot.pixels, "--debanding godot changed a shader without use_debanding");
}

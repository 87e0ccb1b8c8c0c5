//! Godot's half- and quarter-resolution sub-passes on the Vulkan adapter: the quarter pass runs
//! first, then the half pass (which can read QUARTER_RES_COLOR), then the full pass reading
//! both; a sub-pass texture that is not rendered reads as Godot's white stand-in.
//!
//! Expected values are worked out by hand from the shaders below (values exact in f16, the
//! sub-pass format), not taken from a render.

use skyref::Projection;
use skyrun::{Gpu, SkyBuiltins, SkyShader, SubPasses};

/// Converts shader text and renders a 64×32 panorama with its sub-passes.
fn render(gpu: &Gpu, source: &str) -> Vec<[f32; 4]> {
    let front =
        gdshader::check_source("sub_passes.gdshader", source.as_bytes().to_vec(), None, &mut gdshader::FsLoader);
    assert!(!front.has_errors(), "{:?}", front.diagnostics);
    let lowered = gdsky_naga::lower(&front, &gdsky_naga::LowerOptions::default()).expect("lowers");
    let wgsl = gdsky_naga::to_wgsl(&lowered).expect("WGSL");
    let shader = SkyShader::new(gpu, &wgsl, SubPasses::of(&front)).expect("compiles");
    let builtins = SkyBuiltins::from_scene(&skyref::Scene::default(), 64, 32);
    shader.render(gpu, Projection::Panorama, 64, 32, &builtins, &[]).expect("renders").pixels
}

#[test]
fn sub_passes_run_in_godots_order_and_feed_the_full_pass() {
    let gpu = crate::common::gpu();

    // Quarter writes a constant; half doubles what quarter wrote and adds its own texture
    // (white, because the half pass is being rendered); the full pass combines both.
    let chained = render(
        &gpu,
        "shader_type sky;
         render_mode use_half_res_pass, use_quarter_res_pass;
         void sky() {
             if (AT_QUARTER_RES_PASS) {
                 COLOR = vec3(0.25, 0.5, 0.75);
             } else if (AT_HALF_RES_PASS) {
                 COLOR = QUARTER_RES_COLOR.rgb * 2.0 + HALF_RES_COLOR.rgb;
             } else {
                 COLOR = HALF_RES_COLOR.rgb + QUARTER_RES_COLOR.rgb * 10.0;
             }
         }",
    );
    // half = (0.5, 1, 1.5) + 1 = (1.5, 2, 2.5); full = half + 10 · (0.25, 0.5, 0.75).
    for (i, p) in chained.iter().enumerate() {
        assert_eq!([p[0], p[1], p[2]], [4.0, 7.0, 10.0], "pixel {i}");
    }

    // Without the render modes the textures are Godot's white stand-in (1 / luminance 1).
    let unasked =
        render(&gpu, "shader_type sky; void sky() { COLOR = HALF_RES_COLOR.rgb + 2.0 * QUARTER_RES_COLOR.rgb; }");
    assert!(unasked.iter().all(|p| [p[0], p[1], p[2]] == [3.0, 3.0, 3.0]), "{:?}", unasked[0]);

    // The half pass draws SCREEN_UV; the full pass reads it back at its own SCREEN_UV through
    // linear filtering, which reproduces a linear function exactly away from the clamped
    // border. So the full pass sees its own SCREEN_UV, up to f16 rounding (2^-11 relative):
    // this pins the sub-pass's orientation (no flip) and the sampling position.
    let uv = render(
        &gpu,
        "shader_type sky;
         render_mode use_half_res_pass;
         void sky() {
             if (AT_HALF_RES_PASS) { COLOR = vec3(SCREEN_UV, 0.0); }
             else { COLOR = HALF_RES_COLOR.rgb - vec3(SCREEN_UV, 0.0); }
         }",
    );
    let mut worst = 0.0f32;
    for y in 1..31 {
        for x in 1..63 {
            let p = uv[y * 64 + x];
            worst = worst.max(p[0].abs()).max(p[1].abs());
        }
    }
    eprintln!("half-res SCREEN_UV read back in the full pass: worst |error| {worst:.2e} (interior)");
    assert!(worst <= 1e-3, "HALF_RES_COLOR at SCREEN_UV is off by {worst}");
    // At the border the clamp holds the edge texel: the first column reads the half-res
    // pixel centre u = 1/64 where the full pass is at u = 1/128.
    let border = uv[16 * 64][0];
    assert!((border - (1.0 / 64.0 - 1.0 / 128.0)).abs() < 1e-3, "border {border}");
}

//! The loop-budget canary (`gdsky_naga::trace::loop_budget`, `gdsky::measure::any`): a module
//! that reports, per pixel, whether the device ran every loop. lavapipe stops an invocation's
//! loops after 65,535 passes in total (tests/cli/lavapipe_loop_limit.rs, docs/lavapipe-loop-limit.md);
//! the canary must say so exactly where that happens, keep the shader's colour, and report
//! nothing on a device without the limit. `bench`/`tune`'s sampling truth rejects a step the
//! canary flags. Needs a Vulkan adapter (lavapipe is enough).

use gdsky::measure::any::{Shot, Sky};

/// A loop of `PASSES` passes (a const knob), its count as the colour.
const SHADER: &str = "shader_type sky;\n\
    const int PASSES = 1000;\n\
    void sky() {\n\
        float n = 0.0;\n\
        for (int i = 0; i < PASSES; i++) { n += 1.0; }\n\
        COLOR = vec3(n * 1e-5, EYEDIR.y, 0.0);\n\
    }\n";

#[test]
fn the_canary_flags_exactly_the_renders_whose_loops_were_cut() {
    let gpu = skytest::gpu();
    let llvmpipe = gpu.adapter_info().to_string().contains("llvmpipe");
    let dir = std::env::temp_dir().join(format!("gdsky-loop-budget-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch folder");
    let file = dir.join("passes.gdshader");
    std::fs::write(&file, SHADER).expect("writes the shader");
    let sky = Sky::new(gdsky::frontend::check_file(&file).expect("readable"), Vec::new()).expect("checks");
    let shot = Shot::panorama(10.0, 16, 8);
    let pixels = 16 * 8;
    // Well inside the budget (the canary's own two passes included) and well past it; the
    // exact edge is tests/cli/lavapipe_loop_limit.rs's business.
    for (passes, cut_on_llvmpipe) in [(1000, 0), (60_000, 0), (100_000, pixels)] {
        let variant = sky.variant(&[("PASSES".into(), passes)]).expect("the variant checks");
        let canary = variant.compile_canary(&gpu).expect("the canary compiles");
        let cut = canary.loops_cut(&gpu, &shot).expect("renders");
        let want = if llvmpipe { cut_on_llvmpipe } else { 0 };
        assert_eq!(cut, want, "PASSES={passes} on {}", gpu.adapter_info());
        // The canary's colour is the shader's own.
        let plain = variant.compile(&gpu).expect("compiles").render(&gpu, &shot).expect("renders").0;
        let flagged = canary.render(&gpu, &shot).expect("renders").0;
        for (p, f) in plain.iter().zip(&flagged) {
            assert_eq!(p[..3], f[..3], "PASSES={passes}: the canary changed the colour");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

//! lavapipe (llvmpipe) ends a shader's loops early: every loop of one invocation draws on a single
//! budget of 65,535 passes, and a loop whose pass empties it exits as if its condition had failed
//! (Mesa's gallivm, `LP_MAX_TGSI_LOOP_ITERATIONS`, decremented at each loop's back edge in
//! `lp_exec_endloop`). This is the driver's, not gdsky's: the WGSL and SPIR-V gdsky writes keep
//! the loops whole, and any conformant Vulkan driver runs them to the end. It is why
//! `shaders/nishita.gdshader` with `view_samples=1024` darkens as `light_samples` grows, in f32
//! and in f64 alike (docs/lavapipe-loop-limit.md has the numbers and the analysis).
//!
//! These are the minimal reproducers, rendered by `gdsky render` at a few pixels. On llvmpipe
//! each must show the cut exactly where the budget says; on any other adapter, the loops whole.
//! A failure on llvmpipe means Mesa changed the limit: update docs/lavapipe-loop-limit.md.
//! Needs a Vulkan adapter (lavapipe is enough).

use crate::common::{gdsky, scratch, text};
use std::path::Path;

/// llvmpipe's loop budget per invocation.
const BUDGET: i64 = 65_535;

/// Renders `source` at `size` with `sets` (`NAME=VALUE`); the image and whether the adapter is
/// llvmpipe (from the `adapter:` line on stderr).
fn render(name: &str, source: &str, size: &str, sets: &[&str]) -> (skyrun::Image, bool) {
    let dir = scratch("lavapipe_loop_limit", name);
    let shader = dir.join(format!("{name}.gdshader"));
    std::fs::write(&shader, source).expect("write the shader");
    let out = dir.join("out.exr");
    let mut args = vec!["render", shader.to_str().unwrap(), "-o", out.to_str().unwrap(), "--size", size];
    for s in sets {
        args.extend(["--set", s]);
    }
    let o = gdsky(&args);
    assert!(o.status.success(), "{}", text(&o));
    let adapter = text(&o).lines().find(|l| l.starts_with("adapter:")).map(str::to_owned).unwrap_or_default();
    (skyrun::read_exr(Path::new(&out)).unwrap_or_else(|e| panic!("{e}")), adapter.contains("llvmpipe"))
}

/// One loop of `n` passes counting them: COLOR = (count, n, 0).
const ONE_LOOP: &str = "shader_type sky;
uniform int n = 1;
void sky() {
	float c = 0.0;
	for (int i = 0; i < n; i++) {
		c += 1.0;
	}
	COLOR = vec3(c, float(n), 0.0);
}
";

#[test]
fn one_loop_stops_after_65535_passes() {
    for n in [65_535, 65_536, 100_000] {
        let (image, llvmpipe) = render(&format!("one_loop_{n}"), ONE_LOOP, "1x1", &[&format!("n={n}")]);
        let want = if llvmpipe { n.min(BUDGET) } else { n };
        assert_eq!(image.pixels[0][..2], [want as f32, n as f32], "n = {n}, llvmpipe: {llvmpipe}");
    }
}

/// The nishita shader's loop structure: `outer` passes, each running `inner` passes of an inner
/// loop. COLOR = (inner bodies run, outer bodies run, outer · inner).
const NESTED: &str = "shader_type sky;
uniform int outer = 1;
uniform int inner = 1;
void sky() {
	float c = 0.0;
	float k = 0.0;
	for (int i = 0; i < outer; i++) {
		for (int j = 0; j < inner; j++) {
			c += 1.0;
		}
		k += 1.0;
	}
	COLOR = vec3(c, k, float(outer * inner));
}
";

/// On llvmpipe, (inner bodies, outer bodies) of [`NESTED`]: an outer pass costs `inner + 2` of
/// the budget (the inner bodies, the inner loop's exiting pass, the outer back edge); the pass
/// that empties it ends the inner loop there, and the outer loop after that body.
fn nested_on_llvmpipe(outer: i64, inner: i64) -> (i64, i64) {
    let full = (BUDGET / (inner + 2)).min(outer);
    if full == outer {
        return (outer * inner, outer);
    }
    match BUDGET - full * (inner + 2) {
        // Emptied by the outer back edge itself.
        0 => (full * inner, full),
        left => (full * inner + left.min(inner), full + 1),
    }
}

#[test]
fn nested_loops_share_one_budget() {
    // 1024 × 64 is nishita's view_samples=1024, light_samples=64: 993 of 1024 view steps run.
    assert_eq!(nested_on_llvmpipe(1024, 64), (63_551, 993));
    for (outer, inner) in [(16, 8), (1024, 64), (1024, 128), (1024, 256)] {
        let sets = [format!("outer={outer}"), format!("inner={inner}")];
        let (image, llvmpipe) =
            render(&format!("nested_{outer}x{inner}"), NESTED, "1x1", &[sets[0].as_str(), sets[1].as_str()]);
        let (c, k) = if llvmpipe { nested_on_llvmpipe(outer, inner) } else { (outer * inner, outer) };
        assert_eq!(
            image.pixels[0][..3],
            [c as f32, k as f32, (outer * inner) as f32],
            "{outer} × {inner}, llvmpipe: {llvmpipe}"
        );
    }
}

/// Pixel x = 0 of a 16×1 panorama runs 1000 inner passes per outer one, every other pixel 10:
/// COLOR = (inner bodies run, outer bodies run, 0).
const DIVERGENT: &str = "shader_type sky;
void sky() {
	int inner = SKY_COORDS.x < 1.0 / 16.0 ? 1000 : 10;
	float c = 0.0;
	float k = 0.0;
	for (int i = 0; i < 100; i++) {
		for (int j = 0; j < inner; j++) {
			c += 1.0;
		}
		k += 1.0;
	}
	COLOR = vec3(c, k, 0.0);
}
";

#[test]
fn a_pixel_is_cut_short_by_the_loops_of_its_simd_neighbours() {
    let (image, llvmpipe) = render("divergent", DIVERGENT, "16x1", &[]);
    let got: Vec<[f32; 2]> = image.pixels.iter().map(|p| [p[0], p[1]]).collect();
    if !llvmpipe {
        assert_eq!(got[0], [100_000.0, 100.0]);
        assert!(got[1..].iter().all(|&p| p == [1000.0, 100.0]), "{got:?}");
        return;
    }
    // Pixel 0 alone would need 100 · 1002 passes: it stops in its 66th outer pass.
    let (c, k) = nested_on_llvmpipe(100, 1000);
    assert_eq!(got[0], [c as f32, k as f32]);
    // A pixel needing only 100 · 12 passes is stopped with it when they share a SIMD group: the
    // inner loop runs while any lane of the group is active, and the budget counts those passes.
    // Which pixels share pixel 0's group is llvmpipe's business; some do.
    assert!(got[1..].iter().all(|&p| p == [1000.0, 100.0] || p == [660.0, 66.0]), "{got:?}");
    assert!(got[1..].contains(&[660.0, 66.0]), "no neighbour of pixel 0 was cut short: {got:?}");
}

//! What the oracle recovers from a sky shader with `render_mode use_debanding` (docs/godot.md,
//! "Debanding"). Godot's Compatibility sky pass adds the dither n = (r, −r, r)/255 after its
//! sRGB encoding, scaled by the energy e: the store is code(f(e·COLOR) + e·n), with
//! f(y) = L2S(S2L(y)). These tests check that derivation code for code against Godot's frames,
//! that the recovery of the derived frames is the oracle's answer, and why no single linear
//! image (gdsky's `--debanding godot` renders COLOR + n) can equal it where a channel is about as
//! dark as the dither. Needs the oracle (`bash scripts/install-oracle.sh`); about 15 s.

use skycore::UniformValue;
use skyoracle::recover::{self, Transfer, l2s, s2l};
use skyoracle::{Brackets, Job, Oracle, Parameter, RawRender};

const PROBE: &str = "shader_type sky;\nrender_mode use_debanding;\nuniform float g;\nvoid sky() { COLOR = vec3(g); }\n";
const W: u32 = 64;
const H: u32 = 32;

/// The sky pass's store without the dither: L2S(S2L(y)) (tonemap_inc.glsl, linear tonemapper).
fn f(y: f64) -> f64 {
    l2s(s2l(y))
}

/// Godot's `interleaved_gradient_noise(gl_FragCoord.xy)` in f32 at pixel (x, y), row 0 at the top.
#[allow(clippy::excessive_precision)] // Godot's literals as its GLSL writes them, rounded to f32.
fn dither(x: u32, y: u32) -> [f32; 3] {
    let (fx, fy) = (x as f32 + 0.5, y as f32 + 0.5);
    let fract = |v: f32| v - v.floor();
    let r = fract(52.982_918_9 * fract(fx * 0.067_110_56 + fy * 0.005_837_15)) * 2.0 - 1.0;
    [r / 255.0, -r / 255.0, r / 255.0]
}

/// The frames the derivation predicts for COLOR = vec3(g): code(f(e·g) + e·n) through the
/// oracle's measured thresholds t(q), which sit on y, so on the store's output at f(t(q)).
fn derived_frames(transfer: &Transfer, g: f32, energies: &[f32]) -> Vec<Vec<u8>> {
    let on_output: Vec<f64> = (1..=255u8).map(|q| f(f64::from(transfer.threshold(q)))).collect();
    energies
        .iter()
        .map(|&e| {
            let e = f64::from(e);
            let mut frame = vec![255u8; (W * H * 4) as usize];
            for y in 0..H {
                for x in 0..W {
                    let i = (y * W + x) as usize;
                    let n = dither(x, y);
                    for c in 0..3 {
                        let out = f(e * f64::from(g)) + e * f64::from(n[c]);
                        frame[4 * i + c] = on_output.partition_point(|&t| t <= out) as u8;
                    }
                }
            }
            frame
        })
        .collect()
}

fn probe(oracle: &mut Oracle, g: f32, brackets: Brackets) -> RawRender {
    let job = Job {
        uniforms: vec![("g".into(), Parameter::Value(UniformValue::Float(g)))],
        brackets,
        ..Job::new(PROBE, W, H)
    };
    oracle.render_raw(&job).unwrap_or_else(|e| panic!("g = {g}: {e}"))
}

/// p99 of |a − b| / max(|b|, 1e-3) over every channel (the parity suite's measure).
fn p99(a: &[[f64; 3]], b: &[[f32; 4]]) -> f64 {
    let mut rel: Vec<f64> = a
        .iter()
        .zip(b)
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - f64::from(b[c])).abs() / f64::from(b[c]).abs().max(1e-3)))
        .collect();
    rel.sort_by(f64::total_cmp);
    rel[(rel.len() - 1) * 99 / 100]
}

#[test]
fn godots_dithered_store_is_the_derivation_and_no_linear_image_recovers_as_it() {
    let mut oracle = skytest::oracle();
    let transfer = oracle.transfer().clone();
    // gdsky's `--debanding godot`: COLOR + n in linear units.
    let gdsky = |g: f32| -> Vec<[f64; 3]> {
        (0..H).flat_map(|y| (0..W).map(move |x| dither(x, y).map(|n| f64::from(g + n)))).collect()
    };
    // (g, p99 of COLOR + n against the oracle's octave recovery: at most / at least).
    let cases: [(f32, f64, f64); 5] = [
        (0.0, f64::INFINITY, 3.0),
        (0.0039, f64::INFINITY, 0.25),
        (0.02, 0.01, 0.0),
        (0.1, 0.01, 0.0),
        (0.5, 0.01, 0.0),
    ];
    for (g, at_most, at_least) in cases {
        let raw = probe(&mut oracle, g, Brackets::default());
        let derived = derived_frames(&transfer, g, &raw.energies);
        let codes = raw.frames.iter().flatten().zip(derived.iter().flatten());
        let off: Vec<i32> = codes.map(|(&a, &b)| (i32::from(a) - i32::from(b)).abs()).filter(|&d| d > 0).collect();
        // Measured: no code of the 165,888 differs (g = 1: one, by 1).
        assert!(
            off.len() <= 4 && off.iter().all(|&d| d <= 1),
            "g = {g}: {} codes differ from the derivation",
            off.len()
        );
        let godot = recover::recover(&transfer, W, H, &raw.energies, &raw.frames);
        let model = recover::recover(&transfer, W, H, &raw.energies, &derived);
        let model_px: Vec<[f64; 3]> = model.pixels.iter().map(|p| [0, 1, 2].map(|c| f64::from(p[c]))).collect();
        assert!(p99(&model_px, &godot.pixels) < 1e-3, "g = {g}: the derived frames recover differently");
        let miss = p99(&gdsky(g), &godot.pixels);
        eprintln!(
            "g = {g}: COLOR + n against the oracle: p99 {miss:.3e}; inconsistent channels {}",
            godot.inconsistent
        );
        assert!(miss <= at_most && miss >= at_least, "g = {g}: p99 {miss:.3e} outside [{at_least}, {at_most}]");
        if g < 0.01 {
            // No linear value reproduces Godot's code in every bracket for most channels (a
            // constant without the dither never contradicts itself): the oracle's answer there is
            // its best bracket's, which depends on the bracket set.
            assert!(godot.inconsistent > 3000, "g = {g}: {} inconsistent", godot.inconsistent);
        }
        if g == 0.0039 {
            let quarter = probe(&mut oracle, g, Brackets::octaves(-12, 14, 4));
            let fine = recover::recover(&transfer, W, H, &quarter.energies, &quarter.frames);
            let fine_px: Vec<[f64; 3]> = fine.pixels.iter().map(|p| [0, 1, 2].map(|c| f64::from(p[c]))).collect();
            let shift = p99(&fine_px, &godot.pixels);
            eprintln!("g = {g}: quarter-stop against octave recovery: p99 {shift:.3e}");
            assert!(shift > 0.1, "g = {g}: the bracket set moved the recovery by only {shift:.3e}");
        }
    }
}

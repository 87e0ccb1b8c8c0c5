//! Prints the facts the crate documentation reports: boot and calibration time, how far Godot's
//! 8-bit store sits from its formula, the recovery error of constant colours per decade, and the
//! Freeman sky's frame times. Run from the repository root after `bash scripts/install-oracle.sh`:
//!
//! ```sh
//! cargo run --release -p skyoracle --example measure
//! ```

use std::path::Path;
use std::time::Duration;

use skycore::{Scene, UniformValue};
use skyoracle::recover::{l2s, s2l};
use skyoracle::{Brackets, Job, Oracle, Parameter, Transfer};

fn percentile(values: &mut [f64], p: f64) -> f64 {
    values.sort_by(f64::total_cmp);
    values[((values.len() - 1) as f64 * p).round() as usize]
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut oracle = Oracle::start(&root).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2)
    });
    let info = oracle.info().clone();
    println!(
        "Godot {} ({}) on {}; Chromium {}",
        info.godot_version, info.rendering_method, info.webgl_renderer, info.browser_version
    );
    println!("boot {:.2?}, calibration {:.2?} in {} passes", info.boot, info.calibration, info.calibration_passes);

    // Where the measured thresholds sit on the formula's unrounded scale (q − ½ if the formula held).
    let measured = oracle.transfer().clone();
    let model = Transfer::model();
    let (mut worst, mut worst_q, mut differ) = (0f64, 0u8, 0);
    for q in 1..=255u8 {
        let raw = 255.0 * l2s(s2l(f64::from(measured.threshold(q))));
        let off = raw - (f64::from(q) - 0.5);
        if off.abs() > worst.abs() {
            (worst, worst_q) = (off, q);
        }
        differ += usize::from(measured.threshold(q) != model.threshold(q));
    }
    println!(
        "store vs formula: {differ} of 255 thresholds differ; the farthest, code {worst_q}, sits {worst:+.3} code from q - 1/2"
    );

    let n = 256u32;
    let ks: Vec<f32> = (0..n).map(|i| 10f64.powf(-5.0 + 8.0 * f64::from(i) / f64::from(n - 1)) as f32).collect();
    let code = format!(
        "shader_type sky;\nuniform float K[{n}];\nvoid sky() {{\n\tCOLOR = vec3(K[clamp(int(FRAGCOORD.x), 0, {})]);\n}}\n",
        n - 1
    );
    for (name, brackets) in
        [("octave (27 frames)", Brackets::default()), ("quarter-stop (105 frames)", Brackets::octaves(-12, 14, 4))]
    {
        let job = Job {
            uniforms: vec![("K".into(), Parameter::Value(UniformValue::FloatArray(ks.clone())))],
            brackets,
            ..Job::new(code.clone(), n, 2)
        };
        let image = oracle.render(&job).unwrap_or_else(|e| panic!("{e}"));
        println!("constant colours, {name}: {:.2?}, inconsistent {}", image.timing.wall, image.inconsistent);
        println!("| COLOR | n | median | max | fewest valid brackets |");
        let mut all = Vec::new();
        for decade in -5..3 {
            let mut errors = Vec::new();
            let mut fewest = u8::MAX;
            for (x, &k) in ks.iter().enumerate() {
                if (f64::from(k).log10().floor() as i32) == decade {
                    errors.push((f64::from(image.pixels[x][0]) / f64::from(k) - 1.0).abs());
                    fewest = fewest.min(image.valid[x][0]);
                }
            }
            all.extend_from_slice(&errors);
            let count = errors.len();
            println!(
                "| 1e{decade}…1e{} | {count} | {:.3} % | {:.3} % | {fewest} |",
                decade + 1,
                100.0 * percentile(&mut errors, 0.5),
                100.0 * percentile(&mut errors, 1.0)
            );
        }
        println!(
            "| all | {} | {:.3} % | {:.3} % | |",
            all.len(),
            100.0 * percentile(&mut all, 0.5),
            100.0 * percentile(&mut all, 1.0)
        );
    }

    let freeman = std::fs::read_to_string(root.join("fixtures/freeman_sky.gdshader")).unwrap_or_else(|e| panic!("{e}"));
    let scene = |w, h, brackets| Job {
        scene: Scene::default().with_position(glam::DVec3::new(0.0, 1.0, 0.0)),
        brackets,
        ..Job::new(freeman.clone(), w, h)
    };
    for (w, h, brackets) in [
        (64, 32, Brackets::default()),
        (64, 32, Brackets::default()),
        (256, 128, Brackets::default()),
        (64, 32, Brackets::octaves(-12, 14, 4)),
    ] {
        let count = brackets.energies().len();
        let image = oracle.render(&scene(w, h, brackets)).unwrap_or_else(|e| panic!("{e}"));
        let mut frames: Vec<f64> = image.timing.frames.iter().map(Duration::as_secs_f64).collect();
        let nan = image.pixels.iter().filter(|p| p.iter().any(|c| !c.is_finite())).count();
        let clipped =
            (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).filter(|&(x, y)| image.valid_min(x, y) == 0).count();
        println!(
            "Freeman {w}x{h}, {count} frames: {:.2?} in all ({:.2?} in Godot); per frame median {:.3} s, max {:.3} s; NaN {nan}, clipped everywhere {clipped}, inconsistent {}",
            image.timing.wall,
            image.timing.godot,
            percentile(&mut frames, 0.5),
            percentile(&mut frames, 1.0),
            image.inconsistent
        );
    }
}

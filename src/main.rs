//! The `gdsky` command line. Commands and flag names follow the CLI contract in docs/cli.md;
//! scripts outside the project depend on them.

mod cli;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use std::process::ExitCode;

/// Ports Godot 4 sky shaders to WGSL and SPIR-V, checks them with Godot's rules, renders them
/// headlessly and compares them with a Rust reference.
#[derive(Parser)]
#[command(name = "gdsky", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Check sky shaders with Godot's rules and print diagnostics.
    ///
    /// Exit status: 0 when every file is a valid sky shader (warnings allowed), 1 when any has an
    /// error, 2 when a file cannot be read.
    Check(cli::check::CheckArgs),
    /// Convert a sky shader to WGSL, SPIR-V and a reflection JSON.
    ///
    /// Writes DIR/<stem>.wgsl, DIR/<stem>.spv (SPIR-V 1.3, Vulkan) and DIR/<stem>.json, each
    /// atomically. Exit status: 0 written, 1 the shader is invalid or cannot be translated, 2 a
    /// file cannot be read or written.
    Convert(cli::convert::ConvertArgs),
    /// Render a sky shader headlessly on the best Vulkan adapter into an EXR or a PNG.
    ///
    /// Converts FILE (default: the bundled Freeman sky), renders it on a GPU, or on lavapipe
    /// (Mesa's CPU Vulkan driver) where there is none, and writes RGBA f32 linear radiance
    /// (`-o OUT.exr`) or a tone-mapped preview (`-o OUT.png`). Godot 4.6's look by default: a
    /// shader's own `use_debanding`, Godot 4.6's SKY_COORDS (--debanding, --sky-coords).
    /// Uniforms keep the shader's defaults unless set with --set; --override NAME renders a scalar
    /// uniform as a pipeline constant of one module (the same image). The outputs are checked before
    /// anything is rendered: their directory must exist, and a directory, device, FIFO or socket
    /// is never replaced (a symbolic link is written through to its target). Exit status: 0
    /// written, 1 the shader or a flag is invalid, 2 no Vulkan adapter or a file cannot be read
    /// or written.
    Render(cli::render::RenderArgs),
    /// Render the Freeman sky on the CPU with skyref, the Rust reference, into an EXR.
    ///
    /// Same scene flags as `render`; --set takes the Freeman sky's uniform names. Exit status:
    /// 0 written, 1 a flag is invalid, 2 the file cannot be written.
    Reference(cli::render::ReferenceArgs),
    /// Compare two EXR images; print max, mean and p99.9 relative error and NaN/Inf counts.
    ///
    /// Prints one line: max_rel=… mean_rel=… p999_rel=… nan=… inf=… pixels=…, where a channel's
    /// relative error is |a − b| / max(|b|, floor). Exit status: 0 compared (and within
    /// --max-rel), 1 over --max-rel, non-finite values under --max-rel, or sizes differ, 2 a file
    /// cannot be read.
    Compare(cli::compare::CompareArgs),
    /// Convert the bundled Freeman sky, render it on the GPU, check it against skyref, write
    /// everything to out/.
    ///
    /// Renders a 512x256 panorama and a 384x256 camera view (sun 10° up), the f32 reference
    /// of both, compares them (bound: p99.9 relative error <= 1e-3, no NaN/Inf), and writes the
    /// WGSL/SPIR-V/JSON, EXRs, PNG previews, heatmaps and demo.png. Exit status: 0 pass, 1 the
    /// comparison failed, 2 no Vulkan adapter or an output cannot be written.
    Demo(cli::demo::DemoArgs),
    /// Render a sky shader in real Godot 4.6 (its Web export, headless) and write the recovered
    /// linear radiance as an EXR.
    ///
    /// Godot's Compatibility renderer stores 8 bits; the oracle renders at 27 background energies
    /// (2^-12 … 2^14) and inverts Godot's measured transfer curve, recovering COLOR to ~0.1 %
    /// median, ~0.6 % worst. Camera projection only; TIME cannot be set. Needs `bash
    /// scripts/install-oracle.sh` (chromium, node, the Godot export). Exit status: 0 written, 1
    /// the shader, a flag or Godot's compilation failed, 2 the oracle is not installed or a file
    /// cannot be read or written.
    Oracle(cli::oracle::OracleArgs),
    /// Benchmark sky shaders: render time against error over a sweep of their quality knobs.
    ///
    /// Each configuration is rendered on the adapter and timed (the median of --runs renders
    /// after a warm-up; GPU timestamp queries around the passes where the adapter has them, else
    /// wall time submit → idle; all configurations of all shaders in the same interleaved rounds)
    /// and measured against a truth: mean, p99 and max relative error in linear radiance, mean
    /// error after tone mapping. A Freeman-compatible shader (the Freeman sky's uniforms) sweeps
    /// view_samples × sun_samples (and any --knob) against skyref's integrals of the model (about
    /// 1e-7; cached on disk), and several of them share one chart. Any other shader sweeps its
    /// quality knobs (hint_range int uniforms and int consts bounding loops) against its
    /// sampling truth: itself at converged knobs, evaluated in f64 on the device (the
    /// convergence is printed). Writes DIR/bench.csv and DIR/bench.png (log-log, Pareto fronts)
    /// and prints the fronts. Exit status: 0 written, 1 a flag or the shader is invalid, 2 no
    /// Vulkan adapter or an output cannot be written.
    Bench(cli::bench::BenchArgs),
    /// Stress-test the numerical stability of a sky shader in f32 against f64.
    ///
    /// A Freeman-compatible shader sweeps camera altitude (0.5 m … 100 km and above the
    /// atmosphere), sun elevation (−90° … 90°, dense near 0°), a panorama and a narrow view of
    /// the horizon, and each uniform at the ends of its hint_range, on the adapter and with
    /// skyref's own f32 on the CPU, against skyref in f64. Any other shader sweeps sun, camera,
    /// TIME (to 1e6 s), views and hint-range ends against its own f64 evaluation on the device,
    /// with a few-ulp sensitivity measure that marks ill-conditioned pixels. NaN and Inf are
    /// traced to the source line that made them. Writes DIR/stress.md, DIR/stress.csv and
    /// heatmaps; prints a `summary:` line. --quick runs a small subset (for CI). Exit status: 0
    /// report written, 1 a flag is invalid or --quick found NaN/Inf at default uniforms, 2 no
    /// Vulkan adapter or an output cannot be written.
    Stress(cli::stress::StressArgs),
    /// Render a scene file's sequence of frames (the sun over a day, TIME advancing, the camera
    /// moving), re-rendering a frame only when an input the shader reads has changed.
    ///
    /// A frame is re-rendered when TIME (if the shader reads TIME), POSITION (if read), a light
    /// it reads, the camera's orientation (camera projection only) or a uniform's value differs
    /// from the last rendered frame; otherwise the previous frame's files are written again.
    /// The cubemap projection emulates Godot's radiance process modes (real_time: all six faces;
    /// incremental: one face a frame). Writes DIR/frame_NNNN.exr, DIR/frame_NNNN.png and
    /// DIR/animate.csv, and prints frames rendered and reused and the time against rendering
    /// every frame (measured in the same run). Exit status: 0 written, 1 the scene, the shader
    /// or a flag is invalid, 2 no Vulkan adapter or a file cannot be read or written.
    Animate(cli::animate::AnimateArgs),
    /// Bake the transmittance table of shaders/freeman_lut.gdshader from the material's uniform
    /// values (f64, Bruneton's axes).
    ///
    /// The table holds per-layer optical depths, so only the scale heights, the ozone centre and
    /// width, the planet radius and the atmosphere height are baked in; the wavelengths, Mie
    /// scattering and albedo stay live uniforms. render, bench and stress bake it themselves when
    /// a shader declares `transmittance_table` and no --texture gives it. Exit status: 0 written,
    /// 1 a flag or value is invalid, 2 the output cannot be written.
    BakeLut(cli::bake_lut::BakeLutArgs),
    /// Find the cheapest knob setting of a sky shader within an error budget over a set of
    /// scenes, and write the shader with those knobs baked.
    ///
    /// Sweeps the quality knobs (int uniforms and int consts that bound loops; --knob sets or
    /// adds one), measures each configuration at every scene (default: sun at 0, 10, 30, 60,
    /// 90°) against the truth (skyref for Freeman-compatible shaders, else the shader at
    /// converged knobs in f64), and picks the fastest whose mean (and p99) error stays within
    /// --max-error at every scene. Writes DIR/<stem>.tuned.gdshader (knobs as consts) and
    /// DIR/tune.csv; prints the time against the shader's defaults, timed in the same
    /// interleaved rounds. Exit status: 0 written, 1 a flag or the shader is invalid or no
    /// configuration is within the budget, 2 no Vulkan adapter or an output cannot be written.
    Tune(cli::tune::TuneArgs),
    /// Show a sky shader live in the browser: its WGSL in WebGPU, Godot's inspector built from
    /// the reflection, reloaded when the file, an include or a texture changes.
    ///
    /// Serves one page on http://127.0.0.1:PORT/ (never another interface; nothing from the file
    /// system by path) and opens the default browser unless --no-open. The page needs WebGPU
    /// (Chrome, Edge; Firefox and Safari with WebGPU on). A change that breaks the shader shows
    /// gdsky's located diagnostic over the last good frame. Runs until Ctrl-C. Exit status: 0
    /// stopped, 1 a flag is invalid, 2 the port cannot be bound (docs/preview.md).
    Preview(cli::preview::PreviewArgs),
}

fn main() -> ExitCode {
    // The matches are kept: commands that read a scene file ask them which flags were given on
    // the command line (those override the file) and which are defaults.
    let parsed = Cli::command().try_get_matches().and_then(|m| Cli::from_arg_matches(&m).map(|cli| (cli, m)));
    let (cli, matches) = match parsed {
        Ok(parsed) => parsed,
        Err(err) => {
            let _ = err.print();
            // --help and --version are successes; a malformed command line is wrong input,
            // exit 1 by the CLI contract (clap's own code for it would be 2, which the
            // contract keeps for a wrong environment).
            return if err.use_stderr() { ExitCode::from(1) } else { ExitCode::SUCCESS };
        }
    };
    let sub = matches.subcommand().map(|(_, m)| m.clone()).unwrap_or_default();
    match cli.command {
        Command::Check(args) => cli::check::run(&args),
        Command::Convert(args) => cli::convert::run(&args),
        Command::Render(args) => cli::render::run(&args, &sub),
        Command::Reference(args) => cli::render::run_reference(&args),
        Command::Compare(args) => cli::compare::run(&args),
        Command::Demo(args) => cli::demo::run(&args),
        Command::Oracle(args) => cli::oracle::run(&args),
        Command::Bench(args) => cli::bench::run(&args, &sub),
        Command::Stress(args) => cli::stress::run(&args),
        Command::Animate(args) => cli::animate::run(&args, &sub),
        Command::BakeLut(args) => cli::bake_lut::run(&args),
        Command::Tune(args) => cli::tune::run(&args),
        Command::Preview(args) => cli::preview::run(&args, &sub),
    }
}

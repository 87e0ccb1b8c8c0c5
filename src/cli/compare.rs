//! `gdsky compare A.exr B.exr [--max-rel X] [--floor F] [--heatmap OUT.png]`

use super::scene::{F32_LIMIT, Range, parse_number};
use clap::Args;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Args)]
pub struct CompareArgs {
    /// The image under test.
    #[arg(value_name = "A.exr")]
    a: PathBuf,
    /// The reference: relative errors are taken against it.
    #[arg(value_name = "B.exr")]
    b: PathBuf,
    /// Fail (exit 1) when the largest relative error is above X, or any channel is NaN or
    /// infinite. X is a finite number ≥ 0. Without it, compare only reports.
    #[arg(long, value_name = "X", value_parser = parse_max_rel, allow_hyphen_values = true)]
    max_rel: Option<f64>,
    /// Relative error per RGB channel is |a − b| / max(|b|, F): F keeps near-black pixels from
    /// dominating. F is more than 0 and finite in f32 (≤ 3.4028235e38).
    #[arg(long, value_name = "F", default_value = "1e-4", value_parser = parse_floor, allow_hyphen_values = true)]
    floor: f32,
    /// Write a heatmap of the per-pixel relative error (log scale 1e-7 … 1; NaN/Inf magenta).
    #[arg(long, value_name = "OUT.png")]
    heatmap: Option<PathBuf>,
    /// Write the two images' previews next to each other, A left and B right (tone mapped as
    /// `render --png`).
    #[arg(long, value_name = "OUT.png")]
    side_by_side: Option<PathBuf>,
}

/// `--max-rel X`: a bound on a relative error, 0 or more.
const MAX_REL: Range = Range::closed(0.0, f64::MAX, "a finite number ≥ 0");
/// `--floor F`: a positive denominator, finite in f32 (the images' precision).
const FLOOR: Range =
    Range { min: 0.0, max: F32_LIMIT, min_open: true, max_open: true, text: "more than 0, ≤ 3.4028235e38" };

fn parse_max_rel(s: &str) -> Result<f64, String> {
    parse_number(s, "", &MAX_REL)
}

fn parse_floor(s: &str) -> Result<f32, String> {
    // Rounded to f32 after the check, so a tiny positive value that rounds to 0 is refused too.
    parse_number(s, "", &FLOOR).map(|f| f as f32).and_then(|f| {
        if f > 0.0 { Ok(f) } else { Err(format!("`{}` rounds to 0 in f32; accepted: {}", s.trim(), FLOOR.text)) }
    })
}

pub fn run(args: &CompareArgs) -> ExitCode {
    // The outputs first: a typo in --heatmap costs nothing.
    for path in [&args.heatmap, &args.side_by_side].into_iter().flatten() {
        if let Err(code) = super::check_output(path) {
            return code;
        }
    }
    let read = |path: &PathBuf| {
        skyrun::read_exr(path).map_err(|err| {
            eprintln!("error: {err}");
            ExitCode::from(2)
        })
    };
    let (a, b) = match (read(&args.a), read(&args.b)) {
        (Ok(a), Ok(b)) => (a, b),
        (Err(code), _) | (_, Err(code)) => return code,
    };
    if (a.width, a.height) != (b.width, b.height) {
        eprintln!(
            "error: {} is {}x{} but {} is {}x{}",
            args.a.display(),
            a.width,
            a.height,
            args.b.display(),
            b.width,
            b.height
        );
        return ExitCode::from(1);
    }
    let m = skyrun::compare(&a.pixels, &b.pixels, args.floor);
    println!(
        "max_rel={:.6e} mean_rel={:.6e} p999_rel={:.6e} nan={} inf={} pixels={}",
        m.max_rel, m.mean_rel, m.p999_rel, m.nan, m.inf, m.pixels
    );
    eprintln!("p99_rel={:.6e} psnr={:.2} dB", m.p99_rel, m.psnr_db);
    for p in skyrun::worst_pixels(&a.pixels, &b.pixels, args.floor, a.width as usize, 3) {
        eprintln!("  worst {p}");
    }
    if let Some(path) = &args.heatmap {
        if let Err(err) = skyrun::write_heatmap_png(path, &a, &b, args.floor) {
            eprintln!("error: {err}");
            return ExitCode::from(2);
        }
        eprintln!("wrote {}", path.display());
    }
    if let Some(path) = &args.side_by_side {
        let written = skyrun::write_side_by_side_png(path, &[&a, &b], skyrun::DEFAULT_EXPOSURE, skyrun::DEFAULT_WHITE);
        if let Err(err) = written {
            eprintln!("error: {err}");
            return ExitCode::from(2);
        }
        eprintln!("wrote {}", path.display());
    }
    match args.max_rel {
        Some(bound) if m.max_rel > bound || m.nan + m.inf > 0 => {
            eprintln!(
                "FAIL: max_rel {:.3e} > {bound:e} or non-finite channels ({} NaN, {} Inf)",
                m.max_rel, m.nan, m.inf
            );
            ExitCode::from(1)
        }
        _ => ExitCode::SUCCESS,
    }
}

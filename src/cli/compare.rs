//! `gdsky compare A.exr B.exr [--max-rel X] [--floor F] [--heatmap OUT.png]
//! [--mode pixel|stats] [--min-ssim S] [--max-region-rel R]`

use super::scene::{F32_LIMIT, Range, parse_number};
use clap::{Args, ValueEnum};
use std::path::{Path, PathBuf};
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
    /// `pixel`: per-channel relative errors (one line). `stats`: also a second line
    /// `ssim=… region_mean_max_rel=… region_var_max_rel=…`, for skies whose pixels may differ
    /// while their distribution must not (hash noise): SSIM of the `render --png` previews and,
    /// over an 8 × 4 grid of regions, the luminance's mean and variance compared relatively
    /// (docs/cli.md).
    #[arg(long, value_enum, default_value_t = Mode::Pixel)]
    mode: Mode,
    /// With `--mode stats`: fail (exit 1) when the SSIM is below S (a number in [−1, 1]).
    #[arg(long, value_name = "S", value_parser = parse_ssim, allow_hyphen_values = true)]
    min_ssim: Option<f64>,
    /// With `--mode stats`: fail (exit 1) when a region's mean or variance error is above R
    /// (a finite number ≥ 0).
    #[arg(long, value_name = "R", value_parser = parse_max_rel, allow_hyphen_values = true)]
    max_region_rel: Option<f64>,
}

/// What `compare` measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Mode {
    /// Per-channel relative errors only.
    Pixel,
    /// Relative errors, then SSIM and per-region luminance statistics.
    Stats,
}

/// `--min-ssim S`: SSIM lies in [−1, 1].
const SSIM: Range = Range::closed(-1.0, 1.0, "a number from -1 to 1");

fn parse_ssim(s: &str) -> Result<f64, String> {
    parse_number(s, "", &SSIM)
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
    if args.mode == Mode::Pixel && (args.min_ssim.is_some() || args.max_region_rel.is_some()) {
        errln!("error: --min-ssim and --max-region-rel need --mode stats");
        return ExitCode::from(1);
    }
    // The outputs first: a typo in --heatmap costs nothing.
    for path in [&args.heatmap, &args.side_by_side].into_iter().flatten() {
        if let Err(code) = super::check_output(path) {
            return code;
        }
    }
    let outputs: Vec<&Path> = [&args.heatmap, &args.side_by_side].into_iter().flatten().map(PathBuf::as_path).collect();
    if let Err(err) = gdsky::engine::check_outputs_apart(&outputs, &[args.a.as_path(), args.b.as_path()]) {
        return super::fail(err);
    }
    let read = |path: &PathBuf| {
        skyrun::read_exr(path).map_err(|err| {
            errln!("error: {err}");
            ExitCode::from(2)
        })
    };
    let (a, b) = match (read(&args.a), read(&args.b)) {
        (Ok(a), Ok(b)) => (a, b),
        (Err(code), _) | (_, Err(code)) => return code,
    };
    if (a.width, a.height) != (b.width, b.height) {
        errln!(
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
    outln!(
        "max_rel={:.6e} mean_rel={:.6e} p999_rel={:.6e} nan={} inf={} pixels={}",
        m.max_rel,
        m.mean_rel,
        m.p999_rel,
        m.nan,
        m.inf,
        m.pixels
    );
    errln!("p99_rel={:.6e} psnr={:.2} dB", m.p99_rel, m.psnr_db);
    for p in skyrun::worst_pixels(&a.pixels, &b.pixels, args.floor, a.width as usize, 3) {
        errln!("  worst {p}");
    }
    if let Some(path) = &args.heatmap {
        if let Err(err) = skyrun::write_heatmap_png(path, &a, &b, args.floor) {
            errln!("error: {err}");
            return ExitCode::from(2);
        }
        errln!("wrote {}", path.display());
    }
    if let Some(path) = &args.side_by_side {
        let written = skyrun::write_side_by_side_png(path, &[&a, &b], skyrun::DEFAULT_EXPOSURE, skyrun::DEFAULT_WHITE);
        if let Err(err) = written {
            errln!("error: {err}");
            return ExitCode::from(2);
        }
        errln!("wrote {}", path.display());
    }
    let mut failed = match args.max_rel {
        Some(bound) if m.max_rel > bound || m.nan + m.inf > 0 => {
            errln!("FAIL: max_rel {:.3e} > {bound:e} or non-finite channels ({} NaN, {} Inf)", m.max_rel, m.nan, m.inf);
            true
        }
        _ => false,
    };
    if args.mode == Mode::Stats {
        let s = skyrun::compare_stats(&a.pixels, &b.pixels, a.width as usize, a.height as usize, args.floor);
        outln!("{s}");
        let (c, r) = skyrun::STATS_GRID;
        errln!(
            "regions {c}x{r}: worst mean at {:?}, worst variance at {:?}; {} non-finite pixel(s) left out",
            s.worst_mean_region,
            s.worst_var_region,
            s.non_finite
        );
        if let Some(min) = args.min_ssim.filter(|min| s.ssim.is_nan() || s.ssim < *min) {
            errln!("FAIL: ssim {:.6} < {min}", s.ssim);
            failed = true;
        }
        let region = s.region_mean_max_rel.max(s.region_var_max_rel);
        if let Some(max) = args.max_region_rel.filter(|max| region.is_nan() || region > *max) {
            errln!(
                "FAIL: region error {region:.3e} > {max:e} (mean {:.3e}, variance {:.3e})",
                s.region_mean_max_rel,
                s.region_var_max_rel
            );
            failed = true;
        }
    }
    if failed { ExitCode::from(1) } else { ExitCode::SUCCESS }
}

//! Relative-error statistics between two images.

use std::fmt;

/// Relative error of an image `a` against a reference `b`, over the RGB channels (alpha is
/// ignored): rel = |a − b| / max(|b|, floor) per channel.
///
/// Channels where either image is NaN or infinite are counted in [`nan`](Self::nan) /
/// [`inf`](Self::inf) and left out of the statistics. Percentiles are nearest-rank over all
/// finite channels (3 per pixel).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Metrics {
    /// Largest relative error.
    pub max_rel: f64,
    /// Mean relative error.
    pub mean_rel: f64,
    /// 99.9th percentile of the relative error.
    pub p999_rel: f64,
    /// 99th percentile of the relative error.
    pub p99_rel: f64,
    /// Peak signal-to-noise ratio in dB over the finite channels, with the reference's largest
    /// |value| as the peak: 10·log10(peak² / mean((a − b)²)); ∞ for identical images. For HDR
    /// skies the peak is the sun, so PSNR weighs errors in bright pixels; the relative errors
    /// above are the measure that treats dark and bright sky alike.
    pub psnr_db: f64,
    /// RGB channels that are NaN in either image.
    pub nan: usize,
    /// RGB channels that are ±∞ in either image (and NaN in neither).
    pub inf: usize,
    /// Pixels compared.
    pub pixels: usize,
}

impl fmt::Display for Metrics {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} px: max {:.3e}, p99.9 {:.3e}, p99 {:.3e}, mean {:.3e}, PSNR {:.1} dB, NaN {}, Inf {}",
            self.pixels, self.max_rel, self.p999_rel, self.p99_rel, self.mean_rel, self.psnr_db, self.nan, self.inf
        )
    }
}

/// One channel of one pixel where two images differ, for reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelDiff {
    /// Column, 0 at the left.
    pub x: usize,
    /// Row, 0 at the top.
    pub y: usize,
    /// Channel 0, 1, 2 (R, G, B).
    pub channel: usize,
    /// The pixel in the image under test.
    pub a: [f32; 4],
    /// The pixel in the reference.
    pub b: [f32; 4],
    /// Relative error of that channel (∞ for a non-finite value).
    pub rel: f64,
}

impl fmt::Display for PixelDiff {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "({:>4}, {:>4}) {}: rel {:.3e}  got [{:.6e}, {:.6e}, {:.6e}]  ref [{:.6e}, {:.6e}, {:.6e}]",
            self.x,
            self.y,
            ["R", "G", "B"][self.channel],
            self.rel,
            self.a[0],
            self.a[1],
            self.a[2],
            self.b[0],
            self.b[1],
            self.b[2]
        )
    }
}

/// Relative error per RGB channel, ∞ when either value is not finite.
fn rel(a: f32, b: f32, floor: f32) -> f64 {
    if !a.is_finite() || !b.is_finite() {
        return f64::INFINITY;
    }
    (f64::from(a) - f64::from(b)).abs() / f64::from(b).abs().max(f64::from(floor))
}

/// Compares image `a` with reference `b` (same length; see [`Metrics`]).
///
/// # Panics
///
/// If the images differ in length.
pub fn compare(a: &[[f32; 4]], b: &[[f32; 4]], floor: f32) -> Metrics {
    assert_eq!(a.len(), b.len(), "images of different sizes");
    let mut m = Metrics { pixels: a.len(), ..Metrics::default() };
    let mut rels = Vec::with_capacity(a.len() * 3);
    let (mut peak, mut squared_error) = (0.0f64, 0.0f64);
    for (pa, pb) in a.iter().zip(b) {
        for c in 0..3 {
            let (x, y) = (pa[c], pb[c]);
            if x.is_nan() || y.is_nan() {
                m.nan += 1;
            } else if x.is_infinite() || y.is_infinite() {
                m.inf += 1;
            } else {
                rels.push(rel(x, y, floor));
                peak = peak.max(f64::from(y).abs());
                squared_error += (f64::from(x) - f64::from(y)).powi(2);
            }
        }
    }
    if rels.is_empty() {
        return m;
    }
    let mse = squared_error / rels.len() as f64;
    m.psnr_db = if mse == 0.0 { f64::INFINITY } else { 10.0 * (peak * peak / mse).log10() };
    rels.sort_by(f64::total_cmp);
    let rank = |q: f64| {
        let i = (q * rels.len() as f64).ceil() as usize;
        rels[i.clamp(1, rels.len()) - 1]
    };
    m.max_rel = rels[rels.len() - 1];
    m.mean_rel = rels.iter().sum::<f64>() / rels.len() as f64;
    m.p999_rel = rank(0.999);
    m.p99_rel = rank(0.99);
    m
}

/// The `count` channels with the largest relative error (non-finite values first), worst
/// first (ties: the earlier pixel, then channel, first), located in a `width`-wide image.
///
/// A bounded selection, not a sort of every channel: memory is O(`count`) whatever the image
/// size (a cubemap strip of six 4096² faces has 302 million channels).
///
/// # Panics
///
/// If the images differ in length or `width` is 0.
pub fn worst_pixels(a: &[[f32; 4]], b: &[[f32; 4]], floor: f32, width: usize, count: usize) -> Vec<PixelDiff> {
    assert_eq!(a.len(), b.len(), "images of different sizes");
    assert!(width > 0, "width must be positive");
    // More than every channel cannot be asked for (and would overflow the reservation below).
    let count = count.min(3 * a.len());
    if count == 0 {
        return Vec::new();
    }
    // (relative error, pixel index, channel), worst first.
    type Candidate = (f64, usize, usize);
    let worst_first = |p: &Candidate, q: &Candidate| q.0.total_cmp(&p.0).then(p.1.cmp(&q.1)).then(p.2.cmp(&q.2));
    let mut kept: Vec<Candidate> = Vec::with_capacity(2 * count + 1);
    for (i, (pa, pb)) in a.iter().zip(b).enumerate() {
        for c in 0..3 {
            kept.push((rel(pa[c], pb[c], floor), i, c));
            if kept.len() > 2 * count {
                kept.select_nth_unstable_by(count, worst_first);
                kept.truncate(count);
            }
        }
    }
    kept.sort_by(worst_first);
    kept.truncate(count);
    kept.into_iter()
        .map(|(rel, i, channel)| PixelDiff { x: i % width, y: i / width, channel, a: a[i], b: b[i], rel })
        .collect()
}

/// Columns and rows of the region grid of [`compare_stats`]: 8 × 4 regions, each 1/8 of the
/// width and 1/4 of the height (a panorama's 8 × 4 regions are 45° × 45°). Region (i, j) spans
/// columns ⌊i·W/8⌋ … ⌊(i+1)·W/8⌋ − 1 and rows ⌊j·H/4⌋ … ⌊(j+1)·H/4⌋ − 1, so every pixel is in
/// exactly one region.
pub const STATS_GRID: (usize, usize) = (8, 4);

/// Statistics that compare two images of a sky whose pixels may legitimately differ (hash
/// noise whose `fract(sin(…) · 43758.5453)` depends on the device's `sin`), while its
/// distribution must not: [`compare_stats`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    /// Structural similarity of the two images tone mapped as `render --png` (exposure
    /// [`DEFAULT_EXPOSURE`](crate::DEFAULT_EXPOSURE), white 1, gamma 2.2, 8 bits): image-compare's
    /// `rgb_similarity_structure` with `MSSIMSimple` (SSIM over 8 × 8 windows, averaged), the
    /// smallest of the R, G and B scores. 1 for identical previews.
    pub ssim: f64,
    /// Over the regions of [`STATS_GRID`], the largest |mean_a − mean_b| / max(|mean_b|, floor)
    /// of the luminance Y = 0.2126 R + 0.7152 G + 0.0722 B (linear, f64).
    pub region_mean_max_rel: f64,
    /// Over the regions, the largest |var_a − var_b| / max(var_b, floor²) of the luminance's
    /// population variance (floor² because a variance is in units of Y²).
    pub region_var_max_rel: f64,
    /// The region (column, row) of the largest mean error.
    pub worst_mean_region: (usize, usize),
    /// The region (column, row) of the largest variance error.
    pub worst_var_region: (usize, usize),
    /// Pixels left out of the region statistics because a channel is NaN or infinite in either
    /// image.
    pub non_finite: usize,
}

impl fmt::Display for Stats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "ssim={:.6} region_mean_max_rel={:.6e} region_var_max_rel={:.6e}",
            self.ssim, self.region_mean_max_rel, self.region_var_max_rel
        )
    }
}

/// Linear luminance (Rec. 709 weights) of a pixel, in f64.
pub fn luminance(p: [f32; 4]) -> f64 {
    0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])
}

/// Mean and population variance of the luminance in each region of [`STATS_GRID`], row by row
/// (index `row · 8 + column`), over the pixels finite in `mask` (all when `mask` is `None`).
/// A region with no pixel (an image narrower than 8 or lower than 4 pixels) has mean and
/// variance 0.
///
/// # Panics
///
/// If `pixels.len() != width · height`.
pub fn region_stats(pixels: &[[f32; 4]], width: usize, height: usize, mask: Option<&[bool]>) -> Vec<(f64, f64)> {
    assert_eq!(pixels.len(), width * height, "image size");
    let (cols, rows) = STATS_GRID;
    let mut out = Vec::with_capacity(cols * rows);
    for j in 0..rows {
        for i in 0..cols {
            let (x0, x1) = (i * width / cols, (i + 1) * width / cols);
            let (y0, y1) = (j * height / rows, (j + 1) * height / rows);
            let values: Vec<f64> = (y0..y1)
                .flat_map(|y| (x0..x1).map(move |x| y * width + x))
                .filter(|&k| mask.is_none_or(|m| m[k]))
                .map(|k| luminance(pixels[k]))
                .collect();
            if values.is_empty() {
                out.push((0.0, 0.0));
                continue;
            }
            let n = values.len() as f64;
            let mean = values.iter().sum::<f64>() / n;
            let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
            out.push((mean, var));
        }
    }
    out
}

/// Compares image `a` with reference `b` (both `width` × `height`) statistically: SSIM of the
/// tone-mapped previews and per-region luminance mean and variance (see [`Stats`]). Relative
/// errors use `floor` as [`compare`] does.
///
/// # Panics
///
/// If either image is not `width · height` pixels.
pub fn compare_stats(a: &[[f32; 4]], b: &[[f32; 4]], width: usize, height: usize, floor: f32) -> Stats {
    assert_eq!(a.len(), width * height, "image size");
    assert_eq!(b.len(), width * height, "image size");
    let finite = |p: &[f32; 4]| p[..3].iter().all(|c| c.is_finite());
    let mask: Vec<bool> = a.iter().zip(b).map(|(p, q)| finite(p) && finite(q)).collect();
    let mut s = Stats { non_finite: mask.iter().filter(|m| !**m).count(), ..Stats::default() };
    let floor = f64::from(floor);
    let (ra, rb) = (region_stats(a, width, height, Some(&mask)), region_stats(b, width, height, Some(&mask)));
    for (k, ((ma, va), (mb, vb))) in ra.iter().zip(&rb).enumerate() {
        let at = (k % STATS_GRID.0, k / STATS_GRID.0);
        let mean_rel = (ma - mb).abs() / mb.abs().max(floor);
        let var_rel = (va - vb).abs() / vb.max(floor * floor);
        if mean_rel > s.region_mean_max_rel {
            (s.region_mean_max_rel, s.worst_mean_region) = (mean_rel, at);
        }
        if var_rel > s.region_var_max_rel {
            (s.region_var_max_rel, s.worst_var_region) = (var_rel, at);
        }
    }
    s.ssim = ssim_of_previews(a, b, width, height);
    s
}

/// SSIM of the two images' `render --png` previews (see [`Stats::ssim`]); 1 for images too
/// small to hold one window.
fn ssim_of_previews(a: &[[f32; 4]], b: &[[f32; 4]], width: usize, height: usize) -> f64 {
    use image_compare::prelude::RgbImage;
    let preview = |img: &[[f32; 4]]| {
        let bytes: Vec<u8> = img
            .iter()
            .flat_map(|&p| crate::imageio::tonemap(p, crate::DEFAULT_EXPOSURE, crate::DEFAULT_WHITE))
            .collect();
        RgbImage::from_raw(width as u32, height as u32, bytes)
    };
    match (preview(a), preview(b)) {
        (Some(pa), Some(pb)) => {
            image_compare::rgb_similarity_structure(&image_compare::Algorithm::MSSIMSimple, &pa, &pb)
                .map_or(1.0, |sim| sim.score)
        }
        _ => 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_have_zero_error() {
        let img = vec![[0.5, 0.25, 1e-6, 0.0]; 10];
        let m = compare(&img, &img, 1e-4);
        assert_eq!(m.max_rel, 0.0);
        assert_eq!(m.pixels, 10);
        assert_eq!((m.nan, m.inf), (0, 0));
        assert_eq!(m.psnr_db, f64::INFINITY);
    }

    #[test]
    fn psnr_uses_the_reference_peak() {
        // Peak 2, one channel of six off by 0.02: MSE = 0.0004 / 6, PSNR = 10·log10(4·6 / 0.0004).
        let a = [[2.0, 1.0, 1.0, 0.0], [1.02, 1.0, 1.0, 0.0]];
        let b = [[2.0, 1.0, 1.0, 0.0], [1.0, 1.0, 1.0, 0.0]];
        let m = compare(&a, &b, 1e-4);
        assert!((m.psnr_db - 10.0 * (24.0f64 / 0.0004).log10()).abs() < 1e-3, "{}", m.psnr_db);
    }

    #[test]
    fn relative_error_uses_the_floor_and_ignores_alpha() {
        let a = [[1.1, 0.0, 2e-5, 7.0]];
        let b = [[1.0, 0.0, 1e-5, 0.0]];
        let m = compare(&a, &b, 1e-4);
        assert!((m.max_rel - 0.1).abs() < 1e-6, "{m}");
        // (2e-5 − 1e-5) / 1e-4 = 0.1 as well; the zero channel contributes 0.
        assert!((m.mean_rel - 0.2 / 3.0).abs() < 1e-6, "{m}");
    }

    #[test]
    fn non_finite_values_are_counted_not_averaged() {
        let a = [[f32::NAN, f32::INFINITY, 1.0, 0.0]];
        let b = [[1.0, 1.0, 1.0, 0.0]];
        let m = compare(&a, &b, 1e-4);
        assert_eq!((m.nan, m.inf), (1, 1));
        assert_eq!(m.max_rel, 0.0);
        let worst = worst_pixels(&a, &b, 1e-4, 1, 2);
        assert!(worst.iter().all(|p| p.rel.is_infinite()));
    }

    #[test]
    fn percentiles_are_nearest_rank() {
        // 1000 pixels × 3 channels: one channel with error 1, the rest 0.
        let b = vec![[1.0f32; 4]; 1000];
        let mut a = b.clone();
        a[500][1] = 2.0;
        let m = compare(&a, &b, 1e-4);
        assert_eq!(m.max_rel, 1.0);
        assert_eq!(m.p999_rel, 0.0);
        assert_eq!(m.p99_rel, 0.0);
        let worst = worst_pixels(&a, &b, 1e-4, 100, 1);
        assert_eq!((worst[0].x, worst[0].y, worst[0].channel), (0, 5, 1));
    }
    /// A 64 × 32 image of pseudo-random "stars" over a gradient, from a seed (an LCG: the
    /// same seed gives the same image).
    fn stars(seed: u64, density: f64) -> Vec<[f32; 4]> {
        stars_sized(seed, density, 64, 32)
    }

    fn stars_sized(seed: u64, density: f64, width: usize, height: usize) -> Vec<[f32; 4]> {
        let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (0..width * height)
            .map(|k| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                let u = (state >> 11) as f64 / (1u64 << 53) as f64;
                let bg = 0.02 + 0.03 * (k / width) as f32 / height as f32;
                let star = if u < density { 2.0 } else { 0.0 };
                [bg + star, bg + star, bg + star, 1.0]
            })
            .collect()
    }

    #[test]
    fn stats_of_identical_images_are_perfect() {
        let a = stars(1, 0.05);
        let s = compare_stats(&a, &a, 64, 32, 1e-4);
        assert_eq!((s.ssim, s.region_mean_max_rel, s.region_var_max_rel), (1.0, 0.0, 0.0));
        assert_eq!(format!("{s}"), "ssim=1.000000 region_mean_max_rel=0.000000e0 region_var_max_rel=0.000000e0");
    }

    #[test]
    fn region_stats_cover_the_grid() {
        // One bright pixel in region (3, 2) of a 64 × 32 image (8 × 8 pixels per region).
        let mut img = vec![[0.0f32; 4]; 64 * 32];
        img[20 * 64 + 30] = [1.0, 1.0, 1.0, 1.0];
        let r = region_stats(&img, 64, 32, None);
        assert_eq!(r.len(), 32);
        for (k, (mean, var)) in r.iter().enumerate() {
            if k == 2 * 8 + 3 {
                assert!((mean - 1.0 / 64.0).abs() < 1e-12, "{mean}");
                assert!((var - (1.0 / 64.0) * (63.0 / 64.0)).abs() < 1e-12, "{var}");
            } else {
                assert_eq!((*mean, *var), (0.0, 0.0), "region {k}");
            }
        }
        let mut b = img.clone();
        b[20 * 64 + 30] = [0.5, 0.5, 0.5, 1.0];
        let s = compare_stats(&img, &b, 64, 32, 1e-4);
        assert_eq!(s.worst_mean_region, (3, 2));
        assert!((s.region_mean_max_rel - 1.0).abs() < 1e-9, "{s}");
        assert!(s.ssim < 1.0);
    }

    #[test]
    fn another_realisation_keeps_statistics_a_different_sky_does_not() {
        // Same density, different stars: the region means move by sampling noise only; a
        // density 1.5 times higher moves them further. (Per-pixel SSIM sees two realisations
        // as unlike as two skies: it needs the pixels to agree, see docs/godot.md.)
        // 256 × 128: 1,024 pixels a region, so a region's star count varies by ~4 %.
        let a = stars_sized(1, 0.4, 256, 128);
        let same = compare_stats(&stars_sized(2, 0.4, 256, 128), &a, 256, 128, 1e-4);
        let denser = compare_stats(&stars_sized(2, 0.6, 256, 128), &a, 256, 128, 1e-4);
        assert!(same.region_mean_max_rel < 0.2, "{same}");
        assert!(denser.region_mean_max_rel > 0.3, "{denser}");
    }

    #[test]
    fn non_finite_pixels_are_left_out_and_counted() {
        let mut a = stars(1, 0.05);
        let b = a.clone();
        a[5] = [f32::NAN, 0.0, 0.0, 1.0];
        let s = compare_stats(&a, &b, 64, 32, 1e-4);
        assert_eq!(s.non_finite, 1);
        assert_eq!((s.region_mean_max_rel, s.region_var_max_rel), (0.0, 0.0));
    }
}

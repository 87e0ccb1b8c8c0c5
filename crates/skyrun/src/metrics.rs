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
/// first, located in a `width`-wide image.
///
/// # Panics
///
/// If the images differ in length or `width` is 0.
pub fn worst_pixels(a: &[[f32; 4]], b: &[[f32; 4]], floor: f32, width: usize, count: usize) -> Vec<PixelDiff> {
    assert_eq!(a.len(), b.len(), "images of different sizes");
    assert!(width > 0, "width must be positive");
    let mut all: Vec<PixelDiff> = a
        .iter()
        .zip(b)
        .enumerate()
        .flat_map(|(i, (pa, pb))| {
            (0..3).map(move |c| PixelDiff {
                x: i % width,
                y: i / width,
                channel: c,
                a: *pa,
                b: *pb,
                rel: rel(pa[c], pb[c], floor),
            })
        })
        .collect();
    all.sort_by(|p, q| q.rel.total_cmp(&p.rel));
    all.truncate(count);
    all
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
}

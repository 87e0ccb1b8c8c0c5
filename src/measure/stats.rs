//! Error statistics of an image under test against an f64 truth: relative error per RGB channel
//! with a floor (so a black night sky is not divided by zero), its mean, p99, p99.9 and max, the
//! error after the preview's tone map, and NaN/Inf counted apart from the statistics.

/// Floor of the relative error, as in `gdsky compare` and the pixel tests: a channel's error is
/// |a − b| / max(|b|, floor), so the black night sky is not divided by zero.
pub const FLOOR: f64 = 1e-4;

/// The preview's tone map per channel, in f64: `(1 − exp(−0.5 L))^(1/2.2)`, negative L as 0.
pub fn tonemap(l: f64) -> f64 {
    (1.0 - (-0.5 * l.max(0.0)).exp()).powf(1.0 / 2.2)
}

/// Error statistics of an f32 image (the one under test) against an f64 truth, over RGB.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorStats {
    /// Largest relative error over the channels where both images are finite.
    pub max: f64,
    /// 99.9th percentile (nearest rank).
    pub p999: f64,
    /// 99th percentile (nearest rank).
    pub p99: f64,
    /// Mean relative error.
    pub mean: f64,
    /// Mean absolute error after the preview's tone map (each channel in [0, 1]).
    pub mean_tonemapped: f64,
    /// Channels that are NaN in the image under test.
    pub nan: usize,
    /// Channels that are ±∞ in the image under test.
    pub inf: usize,
    /// Channels where the truth itself is NaN or ±∞ (whatever the image under test; left out
    /// of the statistics).
    pub truth_nonfinite: usize,
    /// The worst channel: pixel index and channel (0 R, 1 G, 2 B); `None` when nothing finite
    /// was compared.
    pub worst: Option<(usize, usize)>,
    /// Channels compared.
    pub channels: usize,
}

/// Compares `test` with `truth` channel by channel (RGB): |a − b| / max(|b|, [`FLOOR`]).
/// A channel counts in `nan`/`inf` when the image under test is non-finite there (whatever the
/// truth), in `truth_nonfinite` when the truth is; neither enters the error statistics.
pub fn error_stats(test: &[[f32; 4]], truth: &[[f64; 4]]) -> ErrorStats {
    error_stats_f64(&widen(test), truth)
}

/// [`error_stats`] of an f64 image under test (an f64 evaluation at other knob values, when a
/// sampling truth converges; a perturbed f64 render in the sensitivity measure).
pub fn error_stats_f64(test: &[[f64; 4]], truth: &[[f64; 4]]) -> ErrorStats {
    let mut s = ErrorStats::default();
    let mut rels = Vec::with_capacity(test.len() * 3);
    let mut tonemapped = 0.0;
    for (i, (a, b)) in test.iter().zip(truth).enumerate() {
        for c in 0..3 {
            let (x, y) = (a[c], b[c]);
            s.truth_nonfinite += usize::from(!y.is_finite());
            if x.is_nan() {
                s.nan += 1;
            } else if x.is_infinite() {
                s.inf += 1;
            } else if y.is_finite() {
                let rel = (x - y).abs() / y.abs().max(FLOOR);
                if s.worst.is_none() || rel > s.max {
                    s.max = rel;
                    s.worst = Some((i, c));
                }
                rels.push(rel);
                tonemapped += (tonemap(x) - tonemap(y)).abs();
            }
        }
    }
    s.channels = rels.len();
    if rels.is_empty() {
        return s;
    }
    s.mean = rels.iter().sum::<f64>() / rels.len() as f64;
    s.mean_tonemapped = tonemapped / rels.len() as f64;
    rels.sort_by(f64::total_cmp);
    let rank = |q: f64| rels[((q * rels.len() as f64).ceil() as usize).clamp(1, rels.len()) - 1];
    s.p999 = rank(0.999);
    s.p99 = rank(0.99);
    s
}

/// Widens an f32 image to f64.
pub fn widen(image: &[[f32; 4]]) -> Vec<[f64; 4]> {
    image.iter().map(|p| p.map(f64::from)).collect()
}

/// Rounds an f64 image to f32 (for EXRs and heatmaps).
pub fn narrow(image: &[[f64; 4]]) -> Vec<[f32; 4]> {
    image.iter().map(|p| p.map(|c| c as f32)).collect()
}

/// Formats a relative error compactly (`1.23e-4`), `—` for nothing measured.
pub fn sci(value: f64, measured: bool) -> String {
    if measured { format!("{value:.2e}") } else { "—".into() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_stats_counts_non_finite_apart() {
        let test = [[1.1, f32::NAN, f32::INFINITY, 0.0], [1.0, 1.0, 1.0, 0.0]];
        let truth = [[1.0, 1.0, 1.0, 0.0], [1.0, f64::NAN, 1.0, 0.0]];
        let s = error_stats(&test, &truth);
        assert_eq!((s.nan, s.inf, s.truth_nonfinite, s.channels), (1, 1, 1, 3));
        let both = error_stats(&[[f32::NAN; 4]], &[[f64::NAN; 4]]);
        assert_eq!((both.nan, both.truth_nonfinite, both.channels), (3, 3, 0));
        assert!((s.max - 0.1).abs() < 1e-6);
        assert_eq!(s.worst, Some((0, 0)));
        assert!((s.mean - 0.1 / 3.0).abs() < 1e-6);
    }

    #[test]
    fn tonemap_matches_the_preview() {
        assert_eq!(tonemap(0.0), 0.0);
        assert_eq!(tonemap(-3.0), 0.0);
        assert!((tonemap(2.0) - (1.0 - (-1.0f64).exp()).powf(1.0 / 2.2)).abs() < 1e-12);
    }
}

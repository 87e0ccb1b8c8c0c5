//! How far a render may be from what it is held against, and the configuration file that sets
//! it for a whole workspace.

use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

/// How far a render may be from its golden (or a port from its original), per view.
///
/// Per RGB channel the relative error is `|got − expected| / max(|expected|, floor)`; a view
/// passes when its 99th and 99.9th percentiles and its maximum are within the bounds, no
/// channel of either image is NaN or ±∞ (never allowed), and, when `min_ssim` is set, the SSIM
/// of the two tone-mapped previews (`skyrun::Stats::ssim`, what `gdsky compare --mode stats`
/// reports: 8×8 windows, the worst of R, G and B) is at least that.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerance {
    /// Below this magnitude errors count as absolute: `max(|expected|, floor)` divides.
    pub floor: f32,
    /// Bound on the 99th percentile of the relative error.
    pub p99: f64,
    /// Bound on the 99.9th percentile.
    pub p999: f64,
    /// Bound on the largest relative error (∞: none).
    pub max: f64,
    /// Least SSIM of the tone-mapped previews (`None`: not computed).
    pub min_ssim: Option<f64>,
}

impl Default for Tolerance {
    /// Floor 1e-4, p99 ≤ 2e-4, p99.9 ≤ 2e-3, no bound on the maximum, no SSIM.
    ///
    /// Why: two f32 evaluations of the same mathematics that differ only in rounding — a
    /// gdsky upgrade that reorders the lowering's arithmetic, a hand port written in another
    /// order — are each within f32's distance of the exact (f64) result, and so within twice
    /// that of each other. gdsky measured that distance on the Freeman sky over a matrix of
    /// scenes (sun −4° to 90°, camera at 1 m, 2 km and 30 km, panorama and camera; skyref's
    /// f32 against its f64, docs/measured.md): p99 7.8e-5, p99.9 ≤ 1e-3; and lavapipe's f32
    /// against skyref's CPU f32, p99.9 ≤ 1.5e-4. Twice those, rounded up: p99 2e-4, p99.9
    /// 2e-3. The maximum is not bounded: one channel on the sun's `smoothstep` edge moves by
    /// 6e-3 between two correct f32 evaluations (measured, same page). The bound has power: a
    /// 1 % change of the Freeman sky's `rayleigh_scale_height` moves p99.9 by 7.9e-3; a golden
    /// and its render on one adapter with one gdsky are identical bit for bit.
    fn default() -> Self {
        Tolerance { floor: 1e-4, p99: 2e-4, p999: 2e-3, max: f64::INFINITY, min_ssim: None }
    }
}

impl Tolerance {
    /// Bit for bit: every relative error 0 (a golden on its own adapter with the same gdsky).
    pub fn exact() -> Tolerance {
        Tolerance { floor: 1e-4, p99: 0.0, p999: 0.0, max: 0.0, min_ssim: None }
    }

    /// For skies of hashed noise (stars, sparkles) that no two adapters draw alike pixel for
    /// pixel: only the SSIM of the tone-mapped previews is bounded (and NaN/∞ refused).
    /// 0.98 to 0.995 suit most such skies; the report prints the SSIM measured.
    pub fn perceptual(min_ssim: f64) -> Tolerance {
        Tolerance { floor: 1e-4, p99: f64::INFINITY, p999: f64::INFINITY, max: f64::INFINITY, min_ssim: Some(min_ssim) }
    }

    /// Godot through gdsky's oracle against gdsky: floor 1e-3, p99 ≤ 1 %, p99.9 ≤ 5 %. The
    /// oracle recovers linear COLOR from bracketed 8-bit frames to 0.57 % at worst, and two
    /// devices round f32 differently: 1 % per resolved channel is gdsky's own parity bound.
    /// Channels no bracket resolved (black, or brighter than the top bracket: the sun) are a
    /// few per thousand at most, which p99.9 allows.
    pub fn godot() -> Tolerance {
        Tolerance { floor: 1e-3, p99: 1e-2, p999: 5e-2, max: f64::INFINITY, min_ssim: None }
    }

    /// What `metrics` (and `ssim`) break of this tolerance, one line each; empty when within.
    pub(super) fn violations(&self, metrics: &skyrun::Metrics, ssim: Option<f64>) -> Vec<String> {
        let mut out = Vec::new();
        if metrics.nan > 0 || metrics.inf > 0 {
            out.push(format!("{} NaN and {} infinite channel(s): never allowed", metrics.nan, metrics.inf));
        }
        let bounds = [
            ("p99", metrics.p99_rel, self.p99),
            ("p99.9", metrics.p999_rel, self.p999),
            ("max", metrics.max_rel, self.max),
        ];
        for (what, value, bound) in bounds {
            if value > bound {
                out.push(format!("{what} relative error {value:.3e} > {bound:.3e}"));
            }
        }
        if let (Some(least), Some(got)) = (self.min_ssim, ssim)
            && got < least
        {
            out.push(format!("SSIM of the tone-mapped previews {got:.4} < {least:.4}"));
        }
        out
    }

    fn apply(mut self, o: &ToleranceOverride) -> Tolerance {
        self.floor = o.floor.unwrap_or(self.floor);
        self.p99 = o.p99.unwrap_or(self.p99);
        self.p999 = o.p999.unwrap_or(self.p999);
        self.max = o.max.unwrap_or(self.max);
        self.min_ssim = o.min_ssim.or(self.min_ssim);
        self
    }
}

impl fmt::Display for Tolerance {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "floor {:e}, p99 ≤ {:e}, p99.9 ≤ {:e}, max ≤ {:e}", self.floor, self.p99, self.p999, self.max)?;
        if let Some(s) = self.min_ssim {
            write!(f, ", SSIM ≥ {s}")?;
        }
        write!(f, ", no NaN/Inf")
    }
}

/// What to do with a golden made on another adapter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OtherGoldens {
    /// Skip the comparison, with a message (the default; a failure under `GDSKY_FAIL_ON_SKIP=1`).
    #[default]
    Skip,
    /// Compare, with the tolerance of the adapter's section.
    Compare,
}

/// Tolerance fields a configuration sets; the rest come from below.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct ToleranceOverride {
    floor: Option<f32>,
    p99: Option<f64>,
    p999: Option<f64>,
    max: Option<f64>,
    min_ssim: Option<f64>,
}

#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct AdapterSection {
    #[serde(default)]
    tolerance: ToleranceOverride,
    #[serde(default)]
    other_goldens: OtherGoldens,
}

#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
struct ConfigFile {
    #[serde(default)]
    tolerance: ToleranceOverride,
    #[serde(default)]
    adapters: BTreeMap<String, AdapterSection>,
}

/// The workspace's snapshot configuration: `gdsky-snapshots.toml`, the first found in the
/// crate's directory or a directory above it (put it at the workspace root).
///
/// ```toml
/// # Every comparison of every crate below this directory (fields left out keep their defaults).
/// [tolerance]
/// p999 = 1e-3
///
/// # On an adapter whose name contains "NVIDIA": merged over [tolerance] there, and goldens
/// # made on another adapter are compared (with this tolerance) instead of skipped.
/// [adapters.NVIDIA]
/// other_goldens = "compare"
/// tolerance = { p99 = 1e-3, p999 = 1e-2, min_ssim = 0.99 }
/// ```
///
/// Precedence, lowest first: [`Tolerance::default`], `[tolerance]`, the first `[adapters.*]`
/// section (in name order) whose name the adapter's name contains, a test's own
/// [`super::Snapshot::tolerance`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Config {
    /// The file it was read from (`None`: no file, the defaults).
    pub path: Option<PathBuf>,
    file: ConfigFile,
}

/// The configuration file's name.
pub const CONFIG_FILE: &str = "gdsky-snapshots.toml";

impl Config {
    /// Finds and reads the configuration for a crate at `crate_root`; the defaults when there
    /// is none. An error names the file and the line when it is not valid.
    pub fn find(crate_root: &Path) -> Result<Config, String> {
        let Some(path) = crate_root.ancestors().map(|d| d.join(CONFIG_FILE)).find(|p| p.is_file()) else {
            return Ok(Config::default());
        };
        let bytes =
            skycore::io::read_limited(&path, 1 << 20).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        let text = String::from_utf8(bytes).map_err(|_| format!("{}: not UTF-8", path.display()))?;
        let file: ConfigFile = toml::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(Config { path: Some(path), file })
    }

    /// The tolerance on `adapter` (its name), over `base` (the built-in default, or a kind
    /// of comparison's own, like [`Tolerance::godot`]).
    pub fn tolerance(&self, adapter: &str, base: Tolerance) -> Tolerance {
        let t = base.apply(&self.file.tolerance);
        match self.section(adapter) {
            Some(s) => t.apply(&s.tolerance),
            None => t,
        }
    }

    /// What to do on `adapter` with a golden made on another one.
    pub fn other_goldens(&self, adapter: &str) -> OtherGoldens {
        self.section(adapter).map(|s| s.other_goldens).unwrap_or_default()
    }

    fn section(&self, adapter: &str) -> Option<&AdapterSection> {
        self.file.adapters.iter().find(|(key, _)| adapter.contains(key.as_str())).map(|(_, s)| s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sections_apply_by_adapter_name_over_the_base() {
        let file: ConfigFile = toml::from_str(
            "[tolerance]\np999 = 1e-3\n[adapters.llvmpipe]\nother_goldens = \"compare\"\ntolerance = { p99 = 5e-4 }\n",
        )
        .expect("valid");
        let config = Config { path: None, file };
        let on_lavapipe = config.tolerance("llvmpipe (LLVM 15.0.6, 256 bits)", Tolerance::default());
        assert_eq!((on_lavapipe.p99, on_lavapipe.p999), (5e-4, 1e-3));
        let elsewhere = config.tolerance("NVIDIA H200", Tolerance::default());
        assert_eq!((elsewhere.p99, elsewhere.p999), (2e-4, 1e-3));
        assert_eq!(config.other_goldens("llvmpipe (LLVM 15.0.6, 256 bits)"), OtherGoldens::Compare);
        assert_eq!(config.other_goldens("NVIDIA H200"), OtherGoldens::Skip);
    }

    #[test]
    fn unknown_fields_are_refused() {
        let err = toml::from_str::<ConfigFile>("[tolerance]\np9999 = 1\n").expect_err("unknown field");
        assert!(err.to_string().contains("p9999"), "{err}");
    }

    #[test]
    fn nan_and_inf_always_violate() {
        let m = skyrun::Metrics { nan: 1, ..Default::default() };
        assert_eq!(Tolerance::perceptual(0.0).violations(&m, Some(1.0)).len(), 1);
    }
}

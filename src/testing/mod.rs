//! # Testing sky shaders and their ports in your own test suite (feature `testing`)
//!
//! Two kinds of team test sky shaders. Teams that ship gdsky's conversion want to know when a
//! Godot shader edit or a gdsky upgrade changes their sky: **golden images** and **text
//! snapshots**. Teams that port a Godot sky to WGSL by hand, or keep an optimised port, must
//! prove the port draws what the original draws: **port tests**. Both run on the Vulkan adapter
//! the machine has (lavapipe, Mesa's CPU driver, in CI) through the same renderer as
//! `gdsky render`, and report in the sky's own terms: which view, which pixel, which direction.
//!
//! Add gdsky as a dev-dependency with this feature (it never reaches a build script, which
//! takes `default-features = false` without it):
//!
//! ```toml
//! [dev-dependencies]
//! gdsky = { version = "0.1", default-features = false, features = ["testing"] }
//! ```
//!
//! ## Golden images
//!
//! ```no_run
//! #[test]
//! fn sky_looks_the_same() {
//!     gdsky::testing::assert_sky_snapshot("sky", "shaders/sky.gdshader");
//! }
//! ```
//!
//! renders the shader (a path relative to the crate's manifest directory; a Godot material,
//! `.tres`, brings its values and textures) in the [default views](View::defaults) — four
//! panoramas with the sun over the day, a camera toward the sun and one toward the zenith —
//! and compares them with `tests/snapshots/sky.exr`, the golden image (linear HDR, the views
//! stacked top to bottom, with the adapter that drew it and gdsky's version in its header),
//! beside which `sky.png` is its preview for review. The first run has no golden: it writes
//! `sky.new.exr` and `sky.new.png` and fails ("review it and commit it"). `UPDATE_SNAPSHOTS=1`
//! blesses: the render becomes the golden, and the test passes. A mismatch writes
//! `sky.new.exr`, `sky.new.png` and `sky.diff.png` (the heatmap of the relative error) and fails
//! with the statistics of each view and its worst pixels with their view directions. A pass
//! removes stale `.new` and `.diff` files. [`Snapshot`] is the builder for the rest: views,
//! size, projection, uniform values, textures, tolerance, and a `#[must_use]` [`Outcome`] with
//! the statistics for tests that assert on them.
//!
//! ## Port tests
//!
//! ```no_run
//! gdsky::testing::assert_port_matches(
//!     "shaders/sky.gdshader",
//!     "src/sky_port.wgsl",
//!     &gdsky::testing::View::defaults(),
//! );
//! ```
//!
//! renders the original (converted by gdsky) and the port (WGSL, or SPIR-V `.spv`) with the
//! same built-ins, material values and textures, and compares every view. The port must expose
//! the converted module's interface (`docs/binding-interface.md`): the built-ins block at group
//! 0, the material block at group 1 and the textures at the converted module's bindings. Its
//! material struct may lay its members out differently — its members are matched to the
//! shader's uniforms by name ([`PortTest::rename`] where the names differ) and filled at the
//! port's own offsets.
//!
//! ## Text snapshots
//!
//! [`wgsl_text`], [`reflection_text`] and [`spirv_text`] give the converted WGSL, the
//! reflection JSON and a SPIR-V disassembly as text that does not depend on the build profile,
//! the machine or the checkout's path, for `insta::assert_snapshot!`.
//!
//! ## Against Godot
//!
//! [`assert_matches_godot`] renders the camera views in real Godot 4.6 through gdsky's oracle
//! (`scripts/install-oracle.sh` in gdsky's repository) and compares with gdsky's render.
//!
//! ## Tolerances
//!
//! [`Tolerance`]: relative-error percentiles with a floor (`|new − golden| / max(|golden|,
//! floor)` per RGB channel), NaN and ±∞ never, and SSIM of the tone-mapped previews for skies
//! whose hashed noise no two adapters draw alike. The defaults and why they are what they are:
//! [`Tolerance::default`]. A test sets its own with [`Snapshot::tolerance`]; a file
//! `gdsky-snapshots.toml` in the crate's directory or any above it (the workspace root) sets
//! them for every test, with per-adapter sections ([`Config`]).
//!
//! ## Adapters, skips and CI
//!
//! A golden made on one adapter is compared on that adapter only: on another, the comparison is
//! skipped with a message (two correct devices differ in the last bits of `exp`, `pow` and
//! `sin`), unless the configuration's section for the adapter says `other_goldens =
//! "compare"` with a tolerance of its own. Without a Vulkan adapter every test is skipped too,
//! and without the oracle [`assert_matches_godot`] is. `GDSKY_FAIL_ON_SKIP=1` turns every skip
//! into a failure: set it in CI, where a skip means the suite did not run.

mod godot;
mod port;
mod render;
mod snapshot;
mod text;
mod tolerance;
mod views;

pub use godot::assert_matches_godot;
pub use port::{PortTest, assert_port_matches};
pub use snapshot::{Snapshot, assert_sky_snapshot};
pub use text::{reflection_text, spirv_text, wgsl_text};
pub use tolerance::{Config, OtherGoldens, Tolerance};
pub use views::View;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The environment variable that blesses: `UPDATE_SNAPSHOTS=1` makes every render the golden.
pub const UPDATE_VAR: &str = "UPDATE_SNAPSHOTS";

/// The environment variable that turns skips into failures (for CI): `GDSKY_FAIL_ON_SKIP=1`.
pub const FAIL_ON_SKIP_VAR: &str = "GDSKY_FAIL_ON_SKIP";

/// What a comparison concluded.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// Within the tolerance in every view.
    Passed,
    /// `UPDATE_SNAPSHOTS=1`: the render was written as the golden.
    Blessed,
    /// Not compared, and why (no adapter, a golden of another adapter, no oracle).
    Skipped(String),
    /// No golden yet: `<name>.new.exr` and `<name>.new.png` were written for review.
    Missing,
    /// Outside the tolerance; the report says where.
    Mismatch,
    /// The comparison could not be made: the shader, a file or the device is wrong.
    Error(String),
}

/// One worst pixel of a view, for a report: where it is, which way it looks, both values.
#[derive(Clone, Debug, PartialEq)]
pub struct WorstPixel {
    /// Column within the view (0 at the left; a cube face's column within its face).
    pub x: u32,
    /// Row within the view (0 at the top).
    pub y: u32,
    /// The cube face, for a cubemap view.
    pub face: Option<u8>,
    /// `EYEDIR` at that pixel, world space.
    pub eyedir: [f64; 3],
    /// Channel 0, 1, 2 (R, G, B).
    pub channel: usize,
    /// The pixel under test (the new render, or the port).
    pub got: [f32; 4],
    /// The pixel it is held against (the golden, or the original).
    pub expected: [f32; 4],
    /// That channel's relative error (∞ where a value is not finite).
    pub rel: f64,
}

impl std::fmt::Display for WorstPixel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let face = self.face.map(|face| format!(" face {face}")).unwrap_or_default();
        let [dx, dy, dz] = self.eyedir;
        let (g, e) = (self.got, self.expected);
        write!(
            f,
            "pixel ({}, {}){face} EYEDIR ({dx:+.4}, {dy:+.4}, {dz:+.4}) {}: rel {:.3e}, got [{:.6e}, {:.6e}, {:.6e}], \
             expected [{:.6e}, {:.6e}, {:.6e}]",
            self.x,
            self.y,
            ["R", "G", "B"][self.channel.min(2)],
            self.rel,
            g[0],
            g[1],
            g[2],
            e[0],
            e[1],
            e[2]
        )
    }
}

/// One view of a comparison.
#[derive(Clone, Debug)]
pub struct ViewReport {
    /// The view.
    pub view: View,
    /// Relative-error statistics of the render against what it is held against.
    pub metrics: skyrun::Metrics,
    /// SSIM of the tone-mapped previews (0…1), when the tolerance asks for it.
    pub ssim: Option<f64>,
    /// The largest relative errors, worst first.
    pub worst: Vec<WorstPixel>,
    /// What is outside the tolerance (empty: the view passed).
    pub violations: Vec<String>,
    /// The GPU's time for this view (submit to idle).
    pub gpu_time: Duration,
}

/// What a snapshot, port or Godot comparison found. `#[must_use]`: call [`Outcome::assert`], or
/// check [`Outcome::passed`] and the statistics yourself.
#[must_use = "an Outcome asserts nothing until .assert() is called or .passed() is checked"]
#[derive(Clone, Debug)]
pub struct Outcome {
    /// What was compared (the snapshot's name, or "original vs port").
    pub name: String,
    /// The conclusion.
    pub verdict: Verdict,
    /// Each view, in order (empty when nothing was rendered).
    pub views: Vec<ViewReport>,
    /// The adapter that rendered (empty when none was opened).
    pub adapter: String,
    /// The tolerance the views were held to.
    pub tolerance: Tolerance,
    /// Files written: the golden when blessing, the `.new` and `.diff` files on failure.
    pub files: Vec<PathBuf>,
    /// From loading the shader to the verdict.
    pub total_time: Duration,
}

impl Outcome {
    fn error(name: &str, message: impl Into<String>) -> Outcome {
        Outcome {
            name: name.to_string(),
            verdict: Verdict::Error(message.into()),
            views: Vec::new(),
            adapter: String::new(),
            tolerance: Tolerance::default(),
            files: Vec::new(),
            total_time: Duration::ZERO,
        }
    }

    fn skipped(name: &str, why: impl Into<String>) -> Outcome {
        Outcome { verdict: Verdict::Skipped(why.into()), ..Outcome::error(name, "") }
    }

    /// Whether it passed: compared within the tolerance, or blessed.
    pub fn passed(&self) -> bool {
        matches!(self.verdict, Verdict::Passed | Verdict::Blessed)
    }

    /// Whether it was skipped.
    pub fn skipped_because(&self) -> Option<&str> {
        match &self.verdict {
            Verdict::Skipped(why) => Some(why),
            _ => None,
        }
    }

    /// The worst view: the largest p99.9 relative error (the first view on a tie).
    pub fn worst_view(&self) -> Option<&ViewReport> {
        self.views.iter().reduce(|a, b| if b.metrics.p999_rel > a.metrics.p999_rel { b } else { a })
    }

    /// The failing view with the largest p99.9 relative error.
    fn worst_failing_view(&self) -> Option<&ViewReport> {
        self.views
            .iter()
            .filter(|v| !v.violations.is_empty())
            .reduce(|a, b| if b.metrics.p999_rel > a.metrics.p999_rel { b } else { a })
    }

    /// The largest of a statistic over the views (`|m| m.p99_rel`, …); 0 with no views.
    pub fn max_over_views(&self, statistic: impl Fn(&skyrun::Metrics) -> f64) -> f64 {
        self.views.iter().map(|v| statistic(&v.metrics)).fold(0.0, f64::max)
    }

    /// Panics with [`Outcome::report`] unless it passed. A skip passes with a note on stderr,
    /// unless `GDSKY_FAIL_ON_SKIP=1`, under which it panics too. Returns the outcome for tests
    /// that go on to look at the statistics.
    #[track_caller]
    pub fn assert(self) -> Outcome {
        match &self.verdict {
            Verdict::Passed | Verdict::Blessed => self,
            Verdict::Skipped(why) if !env_flag(FAIL_ON_SKIP_VAR) => {
                eprintln!("gdsky::testing: {}: skipped: {why} ({FAIL_ON_SKIP_VAR}=1 makes this a failure)", self.name);
                self
            }
            _ => panic!("{}", self.report()),
        }
    }

    /// A report for people: the verdict, the adapter, each view's statistics and what it broke,
    /// the worst pixels with their view directions, and the files written.
    pub fn report(&self) -> String {
        let mut out = String::new();
        let headline = match &self.verdict {
            Verdict::Passed => "passed".to_string(),
            Verdict::Blessed => "blessed: the render is now the golden".to_string(),
            Verdict::Skipped(why) => format!("skipped: {why}"),
            Verdict::Missing => format!(
                "no golden image yet: the render was written for review; review it and commit it (rename \
                 {name}.new.exr to {name}.exr and {name}.new.png to {name}.png, or rerun with {UPDATE_VAR}=1)",
                name = self.name
            ),
            Verdict::Mismatch => "does not match".to_string(),
            Verdict::Error(message) => format!("could not be compared:\n{message}"),
        };
        let _ = writeln!(out, "{}: {headline}", self.name);
        if !self.adapter.is_empty() {
            let _ = writeln!(out, "  adapter: {}", self.adapter);
        }
        if matches!(self.verdict, Verdict::Mismatch) {
            let _ = writeln!(out, "  tolerance: {}", self.tolerance);
        }
        let failing: Vec<&ViewReport> = self.views.iter().filter(|v| !v.violations.is_empty()).collect();
        if let (Some(worst), false) = (self.worst_failing_view(), failing.is_empty()) {
            let _ = writeln!(
                out,
                "  {} of {} view(s) outside the tolerance; the worst is `{}`",
                failing.len(),
                self.views.len(),
                worst.view.name
            );
        }
        for v in &self.views {
            let ssim = v.ssim.map(|s| format!(", SSIM {s:.4}")).unwrap_or_default();
            let mark = if v.violations.is_empty() { "ok" } else { "FAILED" };
            let _ = writeln!(out, "  {} [{mark}]: {}{ssim}", v.view.name, v.metrics);
            if !v.violations.is_empty() {
                let _ = writeln!(out, "      {}", v.violations.join("; "));
            }
        }
        if let Some(worst) = self.worst_failing_view().filter(|w| !w.worst.is_empty()) {
            let _ = writeln!(out, "  worst pixels of `{}` (x, y within the view):", worst.view.name);
            for w in &worst.worst {
                let _ = writeln!(out, "      {w}");
            }
        }
        for f in &self.files {
            let _ = writeln!(out, "  wrote {}", f.display());
        }
        out
    }
}

/// Whether an environment variable is set to something other than empty, `0` or `false`.
fn env_flag(name: &str) -> bool {
    std::env::var(name).is_ok_and(|v| !matches!(v.trim(), "" | "0" | "false" | "no"))
}

/// The crate under test's root: `CARGO_MANIFEST_DIR`, which cargo sets when it runs a test
/// binary; the working directory otherwise (cargo runs tests there too).
fn crate_root() -> PathBuf {
    std::env::var_os("CARGO_MANIFEST_DIR")
        .map(PathBuf::from)
        .or_else(|| std::env::current_dir().ok())
        .unwrap_or_else(|| PathBuf::from("."))
}

/// A path a test names, relative to the crate root unless absolute.
fn resolve(path: &str) -> PathBuf {
    let p = Path::new(path);
    if p.is_absolute() { p.to_path_buf() } else { crate_root().join(p) }
}

/// The Vulkan adapter, opened once for the whole test binary (tests run on threads of one
/// process); the reason when there is none.
fn gpu() -> Result<&'static skyrun::Gpu, String> {
    static GPU: std::sync::OnceLock<Result<skyrun::Gpu, String>> = std::sync::OnceLock::new();
    GPU.get_or_init(|| skyrun::Gpu::new().map_err(|e| e.to_string())).as_ref().map_err(Clone::clone)
}

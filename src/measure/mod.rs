//! # The measuring engine: time against error, and numerical stability, for sky shaders
//!
//! `gdsky bench`, `gdsky stress` and `gdsky tune` are thin command lines over this module: they
//! parse flags and print; everything that decides a number lives here, so tests and users' own
//! tools can call it.
//!
//! ## What is measured against what
//!
//! A shader's error needs a truth. For a *Freeman-compatible* shader (the Freeman sky's 22
//! uniforms) the truth is skyref, a Rust model of the same integral ([`freeman`]): its integrals
//! to ~1e-7, independent of any sample count. Any other shader has no model, so its truth is
//! built from the shader itself, in two parts:
//!
//! * **sampling truth** — the shader at *converged knobs* ([`any::converge`]): every quality
//!   knob ([`knobs`]: hint_range'd int uniforms, int consts bounding loops) raised, doubling,
//!   until the image changes by less than a threshold. What the shader would show with
//!   unlimited samples.
//! * **precision truth** — that image evaluated in **f64** on the GPU (`skyrun::F64Sky`, the
//!   widened module of `gdsky_naga::lower_f64`), so the truth carries neither the sampling error
//!   nor f32 rounding.
//!
//! A configuration's error is then [`stats::error_stats`] of its f32 image against that truth:
//! relative error per RGB channel with a floor of [`stats::FLOOR`] (mean, p99, p99.9, max), the
//! mean after the preview's tone map, and NaN/Inf counted apart. The [`pareto`] front picks the
//! configurations no other one beats in both time and mean error.
//!
//! ## Stability
//!
//! [`stress`] lists the Freeman sweep (altitudes, sun elevations dense near the horizon, each
//! uniform's hint-range ends) measured against skyref; [`any::stress_cases`] the sweep for any
//! shader (sun below the horizon, camera high and below ground, TIME up to 1e6 s, views straight
//! up and down, each uniform's hint-range ends), measured against the same shader in f64. The
//! *sensitivity* measure ([`any::sensitivity`]) asks a different question than the error: when
//! EYEDIR, POSITION and TIME move by a few ulps, does the f32 output move far more than the f64
//! output does? A pixel where it does is ill-conditioned in f32 — the classic case is the hash
//! `fract(sin(x) * 43758.5453)` at large `x`, whose f32 result is noise that differs between
//! GPUs — even when its error against f64 looks like any other noise.
//!
//! ## Knobs and tuning
//!
//! [`knobs::discover`] finds the knobs; [`knobs::specialize_source`] bakes a const knob by
//! rewriting its initializer in the user's source (consts are folded by the checker, so the
//! uniform-baking map of `lower_with` cannot carry them). [`any::cheapest`] picks, from the
//! measured knob grid, the cheapest setting within an error budget at every scene of a set
//! (`gdsky tune`).
//!
//! Timing is never asserted on by the tests; only the shape of the results is.

/// Appends a line to a report (`say!(out, "…", …)`): what the CLI prints on stdout.
macro_rules! say {
    ($out:expr, $($arg:tt)*) => {{
        use std::fmt::Write as _;
        let _ = writeln!($out, $($arg)*);
    }};
}

/// Gives the user a note through a [`crate::engine::Progress`] (`note!(progress, "…", …)`):
/// what the CLI prints on stderr.
macro_rules! note {
    ($progress:expr, $($arg:tt)*) => {
        $progress.note(&format!($($arg)*))
    };
}

pub mod animate;
pub mod any;
pub mod bench;
pub mod freeman;
pub mod knobs;
pub mod pareto;
pub mod plot;
pub mod skipping;
pub mod stats;
pub mod stress;
pub mod tune;

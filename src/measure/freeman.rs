//! The truth of a Freeman-compatible shader: skyref, the Rust model of the Freeman sky, either
//! its integrals to about 1e-7 ([`skyref::truth`]) or its own sums in f64 at many samples
//! ([`skyref::converged`]), cached on disk as an EXR keyed by everything that changes its
//! pixels.
//!
//! The cache: an entry is used only when its key file matches exactly, its pixels match the
//! checksum recorded with them, and a few pixels recomputed now match it bit for bit. Anything
//! else is recomputed (and a failure to store is only reported: the truth is still returned).
//!
//! [`Sky::load_freeman`] loads a shader whose truth this is.

use crate::engine::{BUNDLED_NAME, Error, Progress, Sky, TRANSMITTANCE_TABLE, freeman_names};
use skyref::converged::Converged;
use skyref::truth::Truth;
use skyref::{FreemanParams, Projection, Scene};
use skyrun::Image;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The truth of a bench: which one, with its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TruthMode {
    /// [`skyref::truth`] at these settings.
    Integral(Truth),
    /// [`skyref::converged`]: skyref f64 at these sample counts.
    Samples(Converged),
}

impl TruthMode {
    /// `params` as far as this truth depends on them: the samples truth replaces the sample
    /// counts with its own; the integral reads no sample count, so they are zeroed and every
    /// configuration that differs only in them shares one truth (and one cache entry).
    pub fn params(&self, params: &FreemanParams) -> FreemanParams {
        match self {
            TruthMode::Integral(_) => params.with_samples(0, 0),
            TruthMode::Samples(c) => c.params(params),
        }
    }

    /// The truth's colour in direction `d` (`params` as [`TruthMode::params`] gives them).
    pub fn color(&self, params: &FreemanParams, scene: &Scene, d: glam::DVec3) -> glam::DVec3 {
        match self {
            TruthMode::Integral(t) => skyref::truth::sky_color(params, scene, d, t),
            TruthMode::Samples(_) => skyref::f64::sky_color(params, scene, d),
        }
    }

    /// The truth's image of one view (rows in parallel).
    pub fn render(&self, params: &FreemanParams, scene: &Scene, view: Projection, w: u32, h: u32) -> Vec<[f64; 4]> {
        match self {
            TruthMode::Integral(t) => skyref::truth::render(params, scene, view, w, h, t),
            TruthMode::Samples(_) => skyref::f64::render(params, scene, view, w, h),
        }
    }

    /// One line saying what the truth is (progress bar, output).
    pub fn describe(&self) -> String {
        match self {
            TruthMode::Integral(t) => format!(
                "skyref::truth, the model's integrals (Richardson on {}/{} view steps per piece, {} depth panels; ~1e-7)",
                t.view_steps,
                t.view_steps.saturating_mul(2),
                t.depth_panels
            ),
            TruthMode::Samples(c) => format!(
                "skyref f64 sums at {}/{} samples (--truth samples: the older truth, ~6e-4 mean off the integral)",
                c.view_samples, c.sun_samples
            ),
        }
    }

    /// A short name for the chart's axis.
    pub fn short(&self) -> String {
        match self {
            TruthMode::Integral(_) => "the integral (skyref::truth)".into(),
            TruthMode::Samples(c) => format!("skyref f64 at {}/{} samples", c.view_samples, c.sun_samples),
        }
    }

    /// The cache key's line for the truth: which one and every setting.
    pub fn key(&self) -> String {
        match self {
            TruthMode::Integral(t) => format!("integral {t:?}"),
            TruthMode::Samples(c) => format!("samples {c:?}"),
        }
    }
}

/// Where truth images are cached: `$GDSKY_CACHE_DIR`, else `$XDG_CACHE_HOME/gdsky`, else
/// `$HOME/.cache/gdsky`, else `gdsky-cache` in the temp dir.
pub fn cache_dir() -> PathBuf {
    let env = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty()).map(PathBuf::from);
    env("GDSKY_CACHE_DIR")
        .or_else(|| env("XDG_CACHE_HOME").map(|d| d.join("gdsky")))
        .or_else(|| env("HOME").map(|d| d.join(".cache").join("gdsky")))
        .unwrap_or_else(|| std::env::temp_dir().join("gdsky-cache"))
}

/// FNV-1a, 64 bits: a hash that is the same in every build (std's hashers promise no such
/// thing), for cache file names and pixel checksums.
pub fn fnv1a(bytes: impl IntoIterator<Item = u8>) -> u64 {
    bytes.into_iter().fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}

pub fn checksum(pixels: &[[f32; 4]]) -> u64 {
    fnv1a(pixels.iter().flat_map(|p| p.iter().flat_map(|c| c.to_le_bytes())))
}

/// The text a cached truth is keyed by: everything that changes its pixels, which truth and its
/// settings first.
fn truth_key(
    mode: &TruthMode,
    params: &FreemanParams,
    scene: &Scene,
    views: &[Projection],
    width: u32,
    height: u32,
) -> String {
    format!(
        "gdsky truth v2: skyref {}\ntruth={}\nviews={views:?}\nsize={width}x{height}\nscene={scene:?}\nparams={params:?}\n",
        skyref_version(),
        mode.key()
    )
}

/// skyref's version, part of the key: a changed reference must not reuse old truths (the
/// bit-for-bit spot check below catches a change without a version bump too).
fn skyref_version() -> &'static str {
    env!("CARGO_PKG_VERSION")
}

/// The truth pixel at column `x` of the strip and row `y`, computed now (for the spot check).
#[allow(clippy::too_many_arguments)] // one pixel of a strip: the strip's every dimension
fn truth_pixel(
    mode: &TruthMode,
    params: &FreemanParams,
    scene: &Scene,
    views: &[Projection],
    w: u32,
    h: u32,
    x: u32,
    y: u32,
) -> [f32; 4] {
    let view = views[((x / w) as usize).min(views.len() - 1)];
    let d = skyref::f64::eyedir(scene, view, x % w, y, w, h);
    let c = mode.color(params, scene, d);
    [c.x as f32, c.y as f32, c.z as f32, 0.0]
}

/// Largest cache key file read (a key is a few hundred bytes).
const MAX_KEY_BYTES: u64 = 64 << 10;

/// The truth of the scene, from the cache when a valid entry exists; else computed (rows in
/// parallel) and stored. The string says which.
pub fn cached_truth(
    dir: &Path,
    mode: &TruthMode,
    params: &FreemanParams,
    scene: &Scene,
    views: &[Projection],
    width: u32,
    height: u32,
) -> (Image, String) {
    let key = truth_key(mode, params, scene, views, width, height);
    let stem = format!("truth-{:016x}", fnv1a(key.bytes()));
    let exr = dir.join(format!("{stem}.exr"));
    let key_path = dir.join(format!("{stem}.key"));
    let strip_w = width * views.len() as u32;
    let spots =
        [(strip_w / 2, height / 2), (strip_w / 4, height / 2 - height.min(2) / 2), (0, 0), (strip_w - 1, height - 1)];
    let cached = (|| -> Result<Image, String> {
        if !key_path.exists() {
            return Err("not cached yet".into());
        }
        let stored = skycore::io::read_limited(&key_path, MAX_KEY_BYTES).map_err(|e| e.to_string())?;
        let stored = String::from_utf8(stored).map_err(|_| "the key is not UTF-8")?;
        let (stored_key, sum) = stored.rsplit_once("checksum=").ok_or("no checksum")?;
        if stored_key != key {
            return Err("the key differs (hash collision or another version)".into());
        }
        let image = skyrun::read_exr(&exr).map_err(|e| e.to_string())?;
        if (image.width, image.height) != (strip_w, height) {
            return Err("wrong size".into());
        }
        if format!("{:016x}", checksum(&image.pixels)) != sum.trim() {
            return Err("the pixels do not match their checksum".into());
        }
        for &(x, y) in &spots {
            let now = truth_pixel(mode, params, scene, views, width, height, x, y);
            let then = image.pixels[(y * strip_w + x) as usize];
            if now.map(f32::to_bits) != then.map(f32::to_bits) {
                return Err(format!("pixel ({x}, {y}) recomputed differs: {now:?} vs {then:?}"));
            }
        }
        Ok(image)
    })();
    match cached {
        Ok(image) => (image, format!("truth: cached {}", exr.display())),
        Err(why) => {
            let started = std::time::Instant::now();
            let rendered: Vec<Vec<[f32; 4]>> = views
                .iter()
                .map(|&view| super::stats::narrow(&mode.render(params, scene, view, width, height)))
                .collect();
            // `strip` only fails for an empty image, which SceneArgs rules out.
            let image = Image::side_by_side(rendered, width, height).unwrap_or_else(|_| Image {
                width: strip_w,
                height,
                pixels: vec![[0.0; 4]; (strip_w * height) as usize],
            });
            let elapsed = started.elapsed();
            let stored = skycore::io::create_output_dir(dir)
                .map_err(|e| format!("{}: {e}", dir.display()))
                .and_then(|()| skyrun::write_exr(&exr, &image).map_err(|e| e.to_string()))
                .and_then(|()| {
                    let text = format!("{key}checksum={:016x}\n", checksum(&image.pixels));
                    skycore::io::write_atomically(&key_path, text.as_bytes())
                        .map_err(|e| format!("cannot write {}: {e}", key_path.display()))
                });
            let note = match stored {
                Ok(()) => format!("truth: computed in {elapsed:.1?} ({why}), cached as {}", exr.display()),
                Err(e) => format!("truth: computed in {elapsed:.1?}; not cached ({e})"),
            };
            (image, note)
        }
    }
}

/// Whether `shader` is Freeman-compatible: exactly the Freeman sky's uniform names (and
/// optionally freeman_lut's `transmittance_table`, baked from them), so skyref is its truth.
/// The types are checked when the material is filled; this is the quiet test the commands use
/// to choose between skyref's truth and the sampling truth of any shader.
pub fn compatible(shader: &gdshader::CheckedShader) -> bool {
    let mut params = FreemanParams::default();
    let want: std::collections::BTreeSet<&str> = params.uniforms_mut().iter().map(|(n, _)| *n).collect();
    let have: std::collections::BTreeSet<&str> =
        shader.uniforms.iter().map(|u| u.name.as_str()).filter(|n| *n != "transmittance_table").collect();
    have == want
}

impl Sky {
    /// Loads FILE (the bundled Freeman sky without one) as the measuring engine lowers it and
    /// checks that it is Freeman-compatible: exactly the Freeman sky's uniforms, with the same
    /// types (and optionally freeman_lut's `transmittance_table`, which the commands bake from
    /// these uniforms). skyref models the Freeman sky's integral, so it is the truth only for
    /// such a shader: wrong input when it is not. A note for `progress` when FILE's own defaults
    /// differ from skyref's (both sides use skyref's).
    pub fn load_freeman(file: Option<&Path>, progress: &dyn Progress) -> Result<Sky, Error> {
        let loaded = Sky::load(file, &super::any::measuring_options())?;
        let shader = loaded.front.shader.as_ref().ok_or_else(|| Error::input("the shader has errors"))?;
        let name = file.map(|f| f.display().to_string()).unwrap_or_else(|| BUNDLED_NAME.to_string());
        // freeman_lut's table is an input of the same model, baked from these uniforms
        // (Sky::bake_tables), not a uniform skyref lacks.
        let have: BTreeSet<&str> =
            shader.uniforms.iter().map(|u| u.name.as_str()).filter(|n| *n != TRANSMITTANCE_TABLE).collect();
        let want: BTreeSet<&str> = freeman_names().into_iter().collect();
        if have != want {
            let list = |names: Vec<&str>| if names.is_empty() { "none".to_string() } else { names.join(", ") };
            return Err(Error::input(format!(
                "{name} is not Freeman-compatible: skyref, the truth, models the Freeman sky's 22 uniforms \
                 (missing: {}; not in the Freeman sky: {})",
                list(want.difference(&have).copied().collect()),
                list(have.difference(&want).copied().collect())
            )));
        }
        let skyrefs = loaded
            .freeman_material(&skyref::FreemanParams::default())
            .map_err(|err| Error::input(format!("{name} is not Freeman-compatible: {err}")))?;
        // The uniforms' defaults come from skyref on both sides; say so when FILE's own differ.
        let own = skyrun::material_with_defaults(shader, &loaded.lowered, &[]).unwrap_or_default();
        if skyrefs != own {
            progress.note(&format!(
                "note: {name}'s uniform defaults differ from the Freeman sky's; both the shader and skyref use the \
                 Freeman sky's (skyref's) values"
            ));
        }
        Ok(loaded)
    }
}

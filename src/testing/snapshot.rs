//! Golden images: render, compare with `tests/snapshots/<name>.exr`, bless, write what a
//! reviewer needs on failure.

use super::render::{self, Subject};
use super::{Config, OtherGoldens, Outcome, Tolerance, UPDATE_VAR, Verdict, View};
use skycore::Projection;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The golden test in one line: renders the sky at `shader_path` (relative to the crate's
/// manifest directory; a `.gdshader`, or a Godot material `.tres`) in [`View::defaults`] at
/// 256×128 and compares with `tests/snapshots/<name>.exr`. Panics with the report unless it
/// passes; see the [module documentation](super) for blessing and the files written.
///
/// ```no_run
/// gdsky::testing::assert_sky_snapshot("sunset", "shaders/sunset.gdshader");
/// ```
#[track_caller]
pub fn assert_sky_snapshot(name: &str, shader_path: &str) {
    let _ = Snapshot::new(name, shader_path).check().assert();
}

/// A golden-image test, built up: [`Snapshot::new`], then what differs from the defaults, then
/// [`Snapshot::check`] (an [`Outcome`] to look at) or [`Snapshot::assert`].
///
/// ```no_run
/// use gdsky::testing::{Snapshot, Tolerance, View};
///
/// let outcome = Snapshot::new("clouds_dusk", "materials/clouds.tres")
///     .views([View::panorama("dusk", View::scene_with_sun(-2.0))])
///     .size(128, 64)
///     .set("coverage", "0.7")
///     .texture("clouds", "textures/clouds.png")
///     .tolerance(Tolerance { p999: 1e-3, ..Tolerance::default() })
///     .check();
/// assert!(outcome.passed(), "{}", outcome.report());
/// assert!(outcome.max_over_views(|m| m.p99_rel) < 1e-4);
/// ```
#[derive(Clone, Debug)]
pub struct Snapshot {
    name: String,
    shader: String,
    views: Vec<View>,
    width: u32,
    height: u32,
    projection: Option<Projection>,
    sets: Vec<(String, String)>,
    textures: Vec<(String, String)>,
    tolerance: Option<Tolerance>,
    directory: Option<String>,
}

impl Snapshot {
    /// A snapshot called `name` (letters, digits, `-`, `_`, `.`: its file names) of the sky at
    /// `shader_path`, relative to the crate's manifest directory.
    pub fn new(name: &str, shader_path: &str) -> Snapshot {
        Snapshot {
            name: name.to_string(),
            shader: shader_path.to_string(),
            views: View::defaults(),
            width: 256,
            height: 128,
            projection: None,
            sets: Vec::new(),
            textures: Vec::new(),
            tolerance: None,
            directory: None,
        }
    }

    /// The views to render instead of [`View::defaults`].
    pub fn views(mut self, views: impl IntoIterator<Item = View>) -> Snapshot {
        self.views = views.into_iter().collect();
        self
    }

    /// Each view's size in pixels (default 256×128; a cubemap face's side for a cubemap).
    pub fn size(mut self, width: u32, height: u32) -> Snapshot {
        (self.width, self.height) = (width, height);
        self
    }

    /// Renders every view in this projection (a cubemap: the six faces side by side, at a
    /// square size).
    pub fn projection(mut self, projection: Projection) -> Snapshot {
        self.projection = Some(projection);
        self
    }

    /// A uniform's value in `gdsky render --set` syntax (`"0.5"`, `"vec3(1, 0.5, 0)"`), over
    /// the shader's default and a material's value.
    pub fn set(mut self, uniform: &str, value: &str) -> Snapshot {
        self.sets.push((uniform.to_string(), value.to_string()));
        self
    }

    /// A texture file (OpenEXR, PNG; a cube map's faces or a 3D texture's slices as
    /// `gdsky render --texture` reads them) for a sampler uniform, relative to the crate.
    pub fn texture(mut self, uniform: &str, path: &str) -> Snapshot {
        self.textures.push((uniform.to_string(), path.to_string()));
        self
    }

    /// The tolerance, instead of the configuration's ([`Config`]) and the default.
    pub fn tolerance(mut self, tolerance: Tolerance) -> Snapshot {
        self.tolerance = Some(tolerance);
        self
    }

    /// Where the goldens live, relative to the crate (default `tests/snapshots`).
    pub fn directory(mut self, directory: &str) -> Snapshot {
        self.directory = Some(directory.to_string());
        self
    }

    /// [`Snapshot::check`], then [`Outcome::assert`].
    #[track_caller]
    pub fn assert(self) -> Outcome {
        self.check().assert()
    }

    /// Renders, compares, blesses or writes the review files, and says what it found (no
    /// panic: see [`Outcome`]).
    pub fn check(self) -> Outcome {
        let started = Instant::now();
        let mut outcome = self.run();
        outcome.total_time = started.elapsed();
        outcome
    }

    fn run(&self) -> Outcome {
        let name = self.name.as_str();
        if let Err(why) = check_name(name) {
            return Outcome::error(name, why);
        }
        let root = super::crate_root();
        let config = match Config::find(&root) {
            Ok(c) => c,
            Err(e) => return Outcome::error(name, e),
        };
        let gpu = match super::gpu() {
            Ok(gpu) => gpu,
            Err(why) => return Outcome::skipped(name, format!("no Vulkan adapter to render on: {why}")),
        };
        let adapter = gpu.adapter_info().name;
        let views = self.views_to_render();
        let rendered = match self.render(gpu, &views) {
            Ok(r) => r,
            Err(e) => return Outcome { adapter, ..Outcome::error(name, e) },
        };
        let image = match render::stack(&rendered.iter().map(|(i, _)| i).collect::<Vec<_>>()) {
            Ok(i) => i,
            Err(e) => return Outcome { adapter, ..Outcome::error(name, e) },
        };
        let files = Files::new(&root.join(self.directory.as_deref().unwrap_or("tests/snapshots")), name);
        let notes = Notes::of(&adapter, &views, self.width, self.height);
        let tolerance = self.tolerance.unwrap_or_else(|| config.tolerance(&adapter, Tolerance::default()));
        let base = Outcome { adapter: adapter.clone(), tolerance, ..Outcome::error(name, "") };
        let size = (self.width, self.height);

        let nonfinite = image.pixels.iter().flat_map(|p| &p[..3]).filter(|c| !c.is_finite()).count();
        if super::env_flag(UPDATE_VAR) {
            if nonfinite > 0 {
                let written = files.write_new(&image, &notes, None);
                let why = format!("the render has {nonfinite} NaN or infinite channel(s): a golden never has one");
                return Outcome {
                    files: written.unwrap_or_default(),
                    ..Outcome { verdict: Verdict::Error(why), ..base }
                };
            }
            return match files.bless(&image, &notes) {
                Ok(written) => Outcome { verdict: Verdict::Blessed, files: written, ..base },
                Err(e) => Outcome { verdict: Verdict::Error(e), ..base },
            };
        }
        if !files.golden.exists() {
            return match files.write_new(&image, &notes, None) {
                Ok(written) => Outcome { verdict: Verdict::Missing, files: written, ..base },
                Err(e) => Outcome { verdict: Verdict::Error(e), ..base },
            };
        }
        let (golden, golden_notes) = match files.read_golden() {
            Ok(g) => g,
            Err(e) => return Outcome { verdict: Verdict::Error(e), ..base },
        };
        if let Some(why) = notes.differs_from(&golden_notes, &golden, &image) {
            let written = files.write_new(&image, &notes, None).unwrap_or_default();
            let why = format!("{why}; review the render and bless it with {UPDATE_VAR}=1");
            return Outcome { verdict: Verdict::Error(why), files: written, ..base };
        }
        let golden_adapter = golden_notes.get(ADAPTER).unwrap_or("an unknown adapter");
        if golden_adapter != adapter && config.other_goldens(&adapter) == OtherGoldens::Skip {
            let why = format!(
                "the golden was made on {golden_adapter}, this is {adapter}; goldens are compared on the adapter \
                 that made them (or say other_goldens = \"compare\" for this adapter in gdsky-snapshots.toml)"
            );
            return Outcome { verdict: Verdict::Skipped(why), ..base };
        }
        let expected = render::unstack(&golden, views.len(), image.height / views.len() as u32);
        let reports = render::compare_views(&views, &rendered, &expected, &tolerance, size);
        if reports.iter().all(|r| r.violations.is_empty()) {
            files.remove_review_files();
            return Outcome { verdict: Verdict::Passed, views: reports, ..base };
        }
        let written = files.write_new(&image, &notes, Some((&golden, tolerance.floor)));
        match written {
            Ok(written) => Outcome { verdict: Verdict::Mismatch, views: reports, files: written, ..base },
            Err(e) => Outcome { verdict: Verdict::Error(e), views: reports, ..base },
        }
    }

    fn views_to_render(&self) -> Vec<View> {
        let mut views = self.views.clone();
        if let Some(p) = self.projection {
            views.iter_mut().for_each(|v| v.projection = p);
        }
        views
    }

    fn render(&self, gpu: &skyrun::Gpu, views: &[View]) -> Result<Vec<(skyrun::Image, std::time::Duration)>, String> {
        if views.is_empty() {
            return Err("no views to render".into());
        }
        let textures: Vec<(String, PathBuf)> =
            self.textures.iter().map(|(n, p)| (n.clone(), super::resolve(p))).collect();
        let subject = Subject::load(&super::resolve(&self.shader), &self.sets, &textures)?;
        let compiled = subject.compile(gpu)?;
        render::draw(gpu, &compiled, views, self.width, self.height)
    }
}

/// Snapshot names become file names: a path separator or `..` would write elsewhere.
fn check_name(name: &str) -> Result<(), String> {
    let ok = |c: char| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.');
    if name.is_empty() || name.starts_with('.') || !name.chars().all(ok) {
        return Err(format!(
            "snapshot name `{name}`: use letters, digits, `-`, `_` and `.` (not first): it names the golden's files"
        ));
    }
    Ok(())
}

const VERSION: &str = "gdsky.version";
const ADAPTER: &str = "gdsky.adapter";
const VIEWS: &str = "gdsky.views";
const SIZE: &str = "gdsky.size";

/// What a golden records in its header.
struct Notes(Vec<(String, String)>);

impl Notes {
    fn of(adapter: &str, views: &[View], width: u32, height: u32) -> Notes {
        let views: Vec<String> = views.iter().map(View::describe).collect();
        Notes(vec![
            (ADAPTER.into(), adapter.into()),
            (SIZE.into(), format!("{width}x{height} per view")),
            (VERSION.into(), env!("CARGO_PKG_VERSION").into()),
            (VIEWS.into(), views.join("\n")),
        ])
    }

    fn get(&self, key: &str) -> Option<&str> {
        self.0.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
    }

    fn as_pairs(&self) -> Vec<(&str, &str)> {
        self.0.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect()
    }

    /// Why the golden is not of the same views (`None`: it is).
    fn differs_from(&self, golden: &Notes, golden_image: &skyrun::Image, image: &skyrun::Image) -> Option<String> {
        if let (Some(was), Some(now)) = (golden.get(SIZE), self.get(SIZE))
            && was != now
        {
            return Some(format!("the size changed since the golden was made: {was} then, {now} now"));
        }
        if golden.get(VIEWS).is_some_and(|v| Some(v) != self.get(VIEWS)) {
            return Some(format!(
                "the views changed since the golden was made\n  golden: {}\n  now:    {}",
                golden.get(VIEWS).unwrap_or_default().replace('\n', "\n          "),
                self.get(VIEWS).unwrap_or_default().replace('\n', "\n          ")
            ));
        }
        if (golden_image.width, golden_image.height) != (image.width, image.height) {
            return Some(format!(
                "the golden is {}x{}, the render {}x{} ({})",
                golden_image.width,
                golden_image.height,
                image.width,
                image.height,
                self.get(SIZE).unwrap_or_default()
            ));
        }
        None
    }
}

/// A snapshot's files: the golden and its preview, and the review files beside them.
struct Files {
    golden: PathBuf,
    preview: PathBuf,
    new: PathBuf,
    new_preview: PathBuf,
    diff: PathBuf,
}

impl Files {
    fn new(directory: &Path, name: &str) -> Files {
        let at = |suffix: &str| directory.join(format!("{name}{suffix}"));
        Files {
            golden: at(".exr"),
            preview: at(".png"),
            new: at(".new.exr"),
            new_preview: at(".new.png"),
            diff: at(".diff.png"),
        }
    }

    fn create_directory(&self) -> Result<(), String> {
        let dir = self.golden.parent().unwrap_or(Path::new("."));
        std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))
    }

    fn bless(&self, image: &skyrun::Image, notes: &Notes) -> Result<Vec<PathBuf>, String> {
        self.create_directory()?;
        skyrun::write_exr_annotated(&self.golden, image, &notes.as_pairs()).map_err(|e| e.to_string())?;
        write_preview(&self.preview, image)?;
        self.remove_review_files();
        Ok(vec![self.golden.clone(), self.preview.clone()])
    }

    /// Writes the render for review, and the heatmap against the golden when there is one.
    fn write_new(
        &self,
        image: &skyrun::Image,
        notes: &Notes,
        against: Option<(&skyrun::Image, f32)>,
    ) -> Result<Vec<PathBuf>, String> {
        self.create_directory()?;
        skyrun::write_exr_annotated(&self.new, image, &notes.as_pairs()).map_err(|e| e.to_string())?;
        write_preview(&self.new_preview, image)?;
        let mut written = vec![self.new.clone(), self.new_preview.clone()];
        match against {
            Some((golden, floor)) => {
                skyrun::write_heatmap_png(&self.diff, image, golden, floor).map_err(|e| e.to_string())?;
                written.push(self.diff.clone());
            }
            None => remove_if_present(&self.diff),
        }
        Ok(written)
    }

    fn read_golden(&self) -> Result<(skyrun::Image, Notes), String> {
        let image = skyrun::read_exr(&self.golden).map_err(|e| e.to_string())?;
        let notes = skyrun::read_exr_notes(&self.golden).map_err(|e| e.to_string())?;
        Ok((image, Notes(notes)))
    }

    fn remove_review_files(&self) {
        for f in [&self.new, &self.new_preview, &self.diff] {
            remove_if_present(f);
        }
    }
}

fn remove_if_present(path: &Path) {
    // Stale review files only: a file that cannot be removed is left for the user to see.
    let _ = std::fs::remove_file(path);
}

fn write_preview(path: &Path, image: &skyrun::Image) -> Result<(), String> {
    skyrun::write_png_preview(path, image, skyrun::DEFAULT_EXPOSURE, skyrun::DEFAULT_WHITE).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::check_name;

    #[test]
    fn names_cannot_leave_the_snapshot_directory() {
        for bad in ["", "../x", "a/b", "a\\b", ".hidden", "sky one"] {
            assert!(check_name(bad).is_err(), "{bad}");
        }
        for good in ["sky", "freeman-day_2", "v1.2"] {
            assert!(check_name(good).is_ok(), "{good}");
        }
    }
}

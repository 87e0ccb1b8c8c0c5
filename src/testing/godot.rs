//! Against real Godot: the camera views rendered by Godot 4.6 through gdsky's oracle (its Web
//! export in headless Chromium, linear COLOR recovered from bracketed 8-bit frames) and by
//! gdsky, compared with [`Tolerance::godot`].

use super::render::{self, Subject};
use super::{Outcome, Tolerance, Verdict, View};
use crate::engine::{self, Setup};
use skycore::Projection;
use std::path::PathBuf;
use std::time::Instant;

/// The environment variable naming the folder that holds the oracle's `.oracle/` (by default
/// the crate's directory or the nearest above it that has one).
pub const ORACLE_ROOT_VAR: &str = "GDSKY_ORACLE_ROOT";

/// Renders the camera views `views` (for instance [`View::default_cameras`]) of the sky at
/// `shader_path` (relative to the crate; a `.tres` brings its values and generated noise
/// textures) at 128×64 in Godot 4.6 and in gdsky, and panics unless every view is within
/// [`Tolerance::godot`]. Skipped, with a message, when the oracle is not installed
/// (`bash scripts/install-oracle.sh` in gdsky's repository puts it in `.oracle/`); a failure
/// under `GDSKY_FAIL_ON_SKIP=1`. The oracle starts Chromium and Godot once per view: seconds
/// each.
///
/// ```no_run
/// use gdsky::testing::{View, assert_matches_godot};
/// assert_matches_godot("shaders/sky.gdshader", &View::default_cameras());
/// ```
#[track_caller]
pub fn assert_matches_godot(shader_path: &str, views: &[View]) {
    let started = Instant::now();
    let name = format!("{shader_path} in gdsky vs Godot");
    let mut outcome = run(&name, shader_path, views).unwrap_or_else(|e| Outcome::error(&name, e));
    outcome.total_time = started.elapsed();
    // Slow and rare: the statistics are worth seeing even when it passes (`--nocapture`).
    let outcome = outcome.assert();
    if outcome.passed() {
        eprintln!("{}", outcome.report());
    }
}

/// The size of each view: Godot's frames are read back at every bracket, so small is fast.
const WIDTH: u32 = 128;
const HEIGHT: u32 = 64;

fn run(name: &str, shader_path: &str, views: &[View]) -> Result<Outcome, String> {
    if let Some(v) = views.iter().find(|v| v.projection != Projection::Camera) {
        return Err(format!("`{}`: the oracle renders Godot's camera view only", v.name));
    }
    let Some(root) = oracle_root() else {
        return Ok(Outcome::skipped(
            name,
            format!(
                "the Godot oracle is not installed (no .oracle/ here or above, and {ORACLE_ROOT_VAR} is not set): run \
                 scripts/install-oracle.sh from gdsky's repository"
            ),
        ));
    };
    let gpu = match super::gpu() {
        Ok(gpu) => gpu,
        Err(why) => return Ok(Outcome::skipped(name, format!("no Vulkan adapter to render on: {why}"))),
    };
    let path = super::resolve(shader_path);
    let subject = Subject::load(&path, &[], &[])?;
    let compiled = subject.compile(gpu)?;
    let gdsky = render::draw(gpu, &compiled, views, WIDTH, HEIGHT)?;
    let mut godot = Vec::with_capacity(views.len());
    for view in views {
        let options = engine::oracle::OracleOptions {
            file: Some(path.clone()),
            setup: Setup {
                scene: view.scene.with_time(0.0),
                projection: Projection::Camera,
                width: WIDTH,
                height: HEIGHT,
                sets: Vec::new(),
                textures: Vec::new(),
            },
            lowering: gdsky_naga::LowerOptions::default(),
            root: root.clone(),
        };
        godot.push(engine::oracle::render(&options, &engine::Quiet).map_err(|e| e.render(false))?);
    }
    let tolerance = Tolerance::godot();
    let reports = render::compare_views(views, &gdsky, &godot, &tolerance, (WIDTH, HEIGHT));
    let verdict = if reports.iter().all(|r| r.violations.is_empty()) { Verdict::Passed } else { Verdict::Mismatch };
    let adapter = gpu.adapter_info().name;
    Ok(Outcome { verdict, views: reports, adapter, tolerance, ..Outcome::error(name, "") })
}

/// `GDSKY_ORACLE_ROOT`, or the crate's directory or the nearest above it with `.oracle/`.
fn oracle_root() -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os(ORACLE_ROOT_VAR) {
        return Some(PathBuf::from(dir));
    }
    super::crate_root().ancestors().find(|d| d.join(".oracle").is_dir()).map(|d| d.to_path_buf())
}

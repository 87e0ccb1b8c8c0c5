//! Scene files: a TOML description of what to render (shader, uniform values, lights, camera,
//! projection, size, time, occluder, sky resolution) and, for `gdsky animate`, how it changes
//! over a sequence of frames.
//!
//! [`SceneFile::load`] reads a file with the bounded reader (regular files only, at most
//! [`MAX_SCENE_BYTES`]), parses it with serde (unknown keys refused, with a "did you mean") and
//! validates every value with the same rules as the command-line flags ([`Range`],
//! [`check_number`], [`check_size`]). Every error is a diagnostic located at file:line:col,
//! rendered like the shader diagnostics (codespan). Paths in the file (`shader`, `occluder`, the
//! `[textures]`) are relative to the scene file.
//!
//! ```toml
//! shader = "../../fixtures/freeman_sky.gdshader" # absent: the bundled Freeman sky
//! projection = "panorama"                          # panorama | camera | cubemap
//! size = [256, 128]                                # a cubemap: one face, square
//! time = 0.0
//! sky_resolution = "full"                          # full | half | quarter
//! occluder = "mask.png"
//! overrides = ["sun_intensity"]                  # scalar uniforms as pipeline constants
//!
//! [sun]                                            # LIGHT0
//! elevation = 10.0
//! azimuth = 0.0
//! enabled = true
//! energy = 1.0
//! color = [1.0, 1.0, 1.0]                          # linear
//! size = 0.5                                       # angular diameter, degrees
//!
//! [[lights]]                                       # LIGHT1 … LIGHT3
//! elevation = 40.0
//! azimuth = 180.0
//! energy = 0.2
//!
//! [camera]
//! position = [0.0, 1.0, 0.0]
//! fov = 90.0
//! yaw = 0.0
//! pitch = 0.0
//!
//! [uniforms]
//! view_samples = 16
//! ground_color = [0.1, 0.1, 0.1]
//!
//! [textures]                                       # sampler uniform = image (EXR or PNG)
//! noise = "noise.png"
//!
//! [animate]                                        # gdsky animate only
//! frames = 24
//! fps = 24.0                                       # or dt = 0.04; TIME advances by dt a frame
//! radiance_mode = "real_time"                      # cubemap: real_time | incremental
//! sun_elevation = [[0, -5.0], [12, 60.0], [23, -5.0]]   # [frame, value] keyframes, linear
//! ```

pub use gdresource::{TextureSetting, UniformSetting};
use gdshader::diag::{Diagnostic, FileId, SourceDb, render_human};
use serde::Deserialize;
use skycore::{Light, Projection, SkyResolution};
use std::collections::BTreeMap;
use std::ops::Range as Span;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// Largest scene file read (a scene is a few hundred bytes; keyframes of a long sequence a few
/// kilobytes).
pub const MAX_SCENE_BYTES: u64 = 1 << 20;

/// Diagnostic code of a scene file that is not valid TOML, has an unknown key or a value of the
/// wrong type.
pub const SCENE_SYNTAX: &str = "E700";
/// Diagnostic code of a scene value outside its accepted range, or a uniform the shader lacks.
pub const SCENE_VALUE: &str = "E701";

/// The range a number (a flag's or a scene file's) must lie in, and the words for it.
#[derive(Clone, Copy, Debug)]
pub struct Range {
    /// Lowest accepted value.
    pub min: f64,
    /// Highest accepted value.
    pub max: f64,
    /// `min` itself is refused (the range is open there).
    pub min_open: bool,
    /// `max` itself is refused.
    pub max_open: bool,
    /// How the accepted range reads in a message: `−90 to 90 degrees`.
    pub text: &'static str,
}

impl Range {
    /// A closed range `[min, max]`.
    pub const fn closed(min: f64, max: f64, text: &'static str) -> Self {
        Self { min, max, min_open: false, max_open: false, text }
    }

    /// Any value that rounds to a finite f32.
    pub const fn f32_finite(text: &'static str) -> Self {
        Self { min: -F32_LIMIT, max: F32_LIMIT, min_open: true, max_open: true, text }
    }

    /// Whether `v` lies in the range.
    pub fn contains(&self, v: f64) -> bool {
        let above = if self.min_open { v > self.min } else { v >= self.min };
        let below = if self.max_open { v < self.max } else { v <= self.max };
        above && below
    }
}

/// Where f64 values stop rounding to a finite f32 (exclusive): `f32::MAX` plus half its ulp.
/// Values travel to the GPU as f32, and one at or beyond this would arrive as infinity; below
/// it they round to at most `f32::MAX` (3.4028235e38, which is itself accepted).
pub const F32_LIMIT: f64 = f32::MAX as f64 + (1u128 << 103) as f64;

/// The sun's elevation: from straight down to straight up.
pub const SUN_ELEVATION: Range = Range::closed(-90.0, 90.0, "−90 to 90 degrees");
/// Angles around the vertical (the sun's azimuth, the camera's yaw): one turn either way.
pub const TURN: Range = Range::closed(-360.0, 360.0, "−360 to 360 degrees");
/// The camera's pitch: from straight down to straight up.
pub const PITCH: Range = Range::closed(-90.0, 90.0, "−90 to 90 degrees");
/// The camera's vertical field of view.
pub const FOV: Range =
    Range { min: 0.0, max: 180.0, min_open: true, max_open: true, text: "more than 0 and less than 180 degrees" };
/// A coordinate of the camera's position, in metres.
pub const POSITION: Range = Range::f32_finite("a finite f32, |v| ≤ 3.4028235e38 metres");
/// TIME, in seconds.
pub const TIME: Range = Range::f32_finite("a finite f32, |T| ≤ 3.4028235e38 seconds");
/// A light's energy.
pub const ENERGY: Range = Range::closed(0.0, 1e6, "0 to 1e6");
/// A light colour component (linear).
pub const COLOR: Range = Range::closed(0.0, 1e6, "0 to 1e6");
/// A light's angular diameter in degrees (Godot's `light_angular_distance`: 0 to 90).
pub const ANGULAR_SIZE: Range = Range::closed(0.0, 90.0, "0 to 90 degrees");
/// Frames per second of an animation.
pub const FPS: Range = Range { min: 0.0, max: 1e6, min_open: true, max_open: false, text: "more than 0, at most 1e6" };
/// Seconds per frame of an animation.
pub const DT: Range = Range::closed(0.0, 1e6, "0 to 1e6 seconds");
/// Most frames of an animation.
pub const MAX_FRAMES: u32 = 100_000;

/// Checks a number against `range`: finite and inside it. The message says which rule failed
/// and the accepted range; `what` names the quantity (`the elevation`), empty for none.
pub fn check_number(v: f64, shown: &str, what: &str, range: &Range) -> Result<f64, String> {
    let what = if what.is_empty() { String::new() } else { format!(" ({what})") };
    let accepted = range.text;
    if !v.is_finite() {
        return Err(format!("`{shown}`{what} is not a finite number; accepted: {accepted}"));
    }
    if !range.contains(v) {
        return Err(format!("`{shown}`{what} is out of range; accepted: {accepted}"));
    }
    Ok(v)
}

/// Parses and checks one number given as text (a flag's component).
pub fn parse_number(text: &str, what: &str, range: &Range) -> Result<f64, String> {
    let t = text.trim();
    let shown_what = if what.is_empty() { String::new() } else { format!(" ({what})") };
    let v: f64 = t.parse().map_err(|_| format!("`{t}`{shown_what} is not a number; accepted: {}", range.text))?;
    check_number(v, t, what, range)
}

/// Checks an image size: each side 1 to [`skyrun::MAX_RENDER_SIDE`], the pixel count within
/// the renderer's limit ([`skyrun::check_render_size`]).
pub fn check_size(w: u64, h: u64) -> Result<(u32, u32), String> {
    let max = skyrun::MAX_RENDER_SIDE;
    let side = |v: u64| match u32::try_from(v) {
        Ok(v) if (1..=max).contains(&v) => Ok(v),
        _ => Err(format!("`{v}` is not a size between 1 and {max} pixels")),
    };
    let (w, h) = (side(w)?, side(h)?);
    skyrun::check_render_size(w, h)?;
    Ok((w, h))
}

/// Godot's radiance process modes for the cubemap projection of `animate`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RadianceMode {
    /// `PROCESS_MODE_REALTIME`: every face every frame (when an input changed).
    #[default]
    RealTime,
    /// `PROCESS_MODE_INCREMENTAL`: one face a frame, the other five kept from earlier frames.
    Incremental,
}

/// A uniform the scene asks to be a pipeline-overridable constant (`overrides = [...]`, as
/// `--override NAME`), and where its name is in the file.
#[derive(Clone, Debug, PartialEq)]
pub struct OverrideSetting {
    /// The uniform's name.
    pub name: String,
    /// Byte range of the name in the scene file.
    pub span: Span<usize>,
}

/// Keyframes `[frame, value]`, ascending; between two, linear; before the first and after the
/// last, held.
#[derive(Clone, Debug, PartialEq)]
pub struct Track<const N: usize> {
    /// The keys.
    pub keys: Vec<(u32, [f64; N])>,
}

impl<const N: usize> Track<N> {
    /// The value at `frame`.
    pub fn at(&self, frame: u32) -> [f64; N] {
        let keys = &self.keys;
        let first = keys[0];
        if frame <= first.0 {
            return first.1;
        }
        for pair in keys.windows(2) {
            let ((f0, v0), (f1, v1)) = (pair[0], pair[1]);
            if frame <= f1 {
                let t = f64::from(frame - f0) / f64::from(f1 - f0);
                return std::array::from_fn(|i| v0[i] + (v1[i] - v0[i]) * t);
            }
        }
        keys[keys.len() - 1].1
    }
}

/// A uniform's keyframes; the values have as many components as the uniform.
#[derive(Clone, Debug, PartialEq)]
pub struct UniformTrack {
    /// The uniform's name.
    pub name: String,
    /// `[frame, components]` keys, ascending.
    pub keys: Vec<(u32, Vec<f64>)>,
    /// Byte range of the keys in the scene file.
    pub span: Span<usize>,
}

impl UniformTrack {
    /// The value at `frame` in `--set` syntax.
    pub fn text_at(&self, frame: u32, integer: bool) -> String {
        let keys = &self.keys;
        let value: Vec<f64> = if frame <= keys[0].0 {
            keys[0].1.clone()
        } else if let Some(pair) = keys.windows(2).find(|p| frame <= p[1].0) {
            let t = f64::from(frame - pair[0].0) / f64::from(pair[1].0 - pair[0].0);
            pair[0].1.iter().zip(&pair[1].1).map(|(a, b)| a + (b - a) * t).collect()
        } else {
            keys[keys.len() - 1].1.clone()
        };
        let one = |v: &f64| if integer { format!("{}", v.round() as i64) } else { format!("{v:?}") };
        value.iter().map(one).collect::<Vec<_>>().join(",")
    }
}

/// How a scene changes over `gdsky animate`'s frames.
#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    /// Number of frames, 1 to [`MAX_FRAMES`].
    pub frames: u32,
    /// Seconds a frame (from `dt`, or 1/`fps`; default 1/24): TIME = time + frame · dt unless
    /// `time` keyframes are given.
    pub dt: f64,
    /// Radiance process mode of the cubemap projection.
    pub radiance_mode: RadianceMode,
    /// Keyframes of TIME (replacing the dt ramp).
    pub time: Option<Track<1>>,
    /// Keyframes of the sun's elevation.
    pub sun_elevation: Option<Track<1>>,
    /// Keyframes of the sun's azimuth.
    pub sun_azimuth: Option<Track<1>>,
    /// Keyframes of the camera's position.
    pub camera_position: Option<Track<3>>,
    /// Keyframes of the camera's yaw.
    pub camera_yaw: Option<Track<1>>,
    /// Keyframes of the camera's pitch.
    pub camera_pitch: Option<Track<1>>,
    /// Keyframes of the camera's field of view.
    pub camera_fov: Option<Track<1>>,
    /// Keyframes of uniforms.
    pub uniforms: Vec<UniformTrack>,
}

/// A parsed, validated scene file. Every field is optional: what it leaves out, the flags (or
/// their defaults) give.
pub struct SceneFile {
    /// The scene file itself.
    pub path: PathBuf,
    /// The shader, resolved against the scene file's folder; `None`: the bundled Freeman sky.
    pub shader: Option<PathBuf>,
    /// The projection.
    pub projection: Option<Projection>,
    /// Image size (a cubemap: one face).
    pub size: Option<(u32, u32)>,
    /// TIME in seconds.
    pub time: Option<f32>,
    /// The sun's (LIGHT0's) elevation in degrees.
    pub sun_elevation: Option<f64>,
    /// The sun's azimuth in degrees.
    pub sun_azimuth: Option<f64>,
    /// LIGHT0_ENABLED.
    pub sun_enabled: Option<bool>,
    /// LIGHT0_ENERGY (default 1).
    pub sun_energy: Option<f32>,
    /// LIGHT0_COLOR (default white).
    pub sun_color: Option<[f32; 3]>,
    /// The sun's angular diameter in degrees (LIGHT0_SIZE is its radians; default 0).
    pub sun_size: Option<f64>,
    /// LIGHT1 … LIGHT3.
    pub lights: Vec<Light>,
    /// Camera POSITION.
    pub position: Option<[f64; 3]>,
    /// Vertical field of view in degrees.
    pub fov: Option<f64>,
    /// Yaw in degrees.
    pub yaw: Option<f64>,
    /// Pitch in degrees.
    pub pitch: Option<f64>,
    /// Uniform values the scene fixes, in file order.
    pub uniforms: Vec<UniformSetting>,
    /// Uniforms emitted as pipeline-overridable constants (`overrides`), in file order, each
    /// once.
    pub overrides: Vec<OverrideSetting>,
    /// Textures for sampler uniforms (`[textures]`), by name.
    pub textures: Vec<TextureSetting>,
    /// The occluder mask, resolved against the scene file's folder.
    pub occluder: Option<PathBuf>,
    /// The sky's resolution.
    pub sky_resolution: Option<SkyResolution>,
    /// The `[animate]` table.
    pub animate: Option<Animation>,
    /// Textures generated for sampler uniforms (a Godot material's `NoiseTexture2D`s).
    pub generated_textures: Vec<gdresource::GeneratedTexture>,
    /// 3D textures generated for sampler uniforms (a Godot material's `NoiseTexture3D`s).
    pub generated_volumes: Vec<gdresource::GeneratedVolume>,
    /// Gradient and curve textures generated for sampler uniforms (a Godot material's
    /// `GradientTexture1D`, `GradientTexture2D` and `CurveTexture`s).
    pub generated_ramps: Vec<gdresource::GeneratedRamp>,
    db: SourceDb,
    file: FileId,
}

impl std::fmt::Debug for SceneFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneFile").field("path", &self.path).field("shader", &self.shader).finish_non_exhaustive()
    }
}

/// Why a scene file was not loaded.
#[derive(Debug)]
pub enum SceneError {
    /// The file cannot be read (exit 2).
    Read(String),
    /// The file is wrong: diagnostics located in it (exit 1).
    Invalid(String),
}

impl std::fmt::Display for SceneError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SceneError::Read(m) | SceneError::Invalid(m) => f.write_str(m.trim_end()),
        }
    }
}

// ---- The file's shape, as serde reads it. ----

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    shader: Option<Spanned<String>>,
    projection: Option<Projection>,
    size: Option<Spanned<[u64; 2]>>,
    time: Option<Spanned<f64>>,
    sun: Option<RawSun>,
    lights: Option<Spanned<Vec<RawLight>>>,
    camera: Option<RawCamera>,
    uniforms: Option<BTreeMap<String, Spanned<UniformValueRaw>>>,
    overrides: Option<Vec<Spanned<String>>>,
    textures: Option<BTreeMap<String, Spanned<String>>>,
    occluder: Option<Spanned<String>>,
    sky_resolution: Option<SkyResolution>,
    animate: Option<RawAnimate>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSun {
    elevation: Option<Spanned<f64>>,
    azimuth: Option<Spanned<f64>>,
    enabled: Option<bool>,
    energy: Option<Spanned<f64>>,
    color: Option<Spanned<[f64; 3]>>,
    size: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLight {
    elevation: Spanned<f64>,
    azimuth: Option<Spanned<f64>>,
    enabled: Option<bool>,
    energy: Option<Spanned<f64>>,
    color: Option<Spanned<[f64; 3]>>,
    size: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCamera {
    position: Option<Spanned<[f64; 3]>>,
    fov: Option<Spanned<f64>>,
    yaw: Option<Spanned<f64>>,
    pitch: Option<Spanned<f64>>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum UniformValueRaw {
    Bool(bool),
    Int(i64),
    Float(f64),
    Vector(Vec<f64>),
}

#[derive(Deserialize)]
#[serde(untagged)]
enum KeyValue {
    Number(f64),
    Vector(Vec<f64>),
}

type RawKeys = Spanned<Vec<(u32, KeyValue)>>;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAnimate {
    frames: Spanned<u32>,
    fps: Option<Spanned<f64>>,
    dt: Option<Spanned<f64>>,
    radiance_mode: Option<RadianceMode>,
    time: Option<RawKeys>,
    sun_elevation: Option<RawKeys>,
    sun_azimuth: Option<RawKeys>,
    camera_position: Option<RawKeys>,
    camera_yaw: Option<RawKeys>,
    camera_pitch: Option<RawKeys>,
    camera_fov: Option<RawKeys>,
    uniforms: Option<BTreeMap<String, RawKeys>>,
}

/// Collects located errors while the raw scene is checked.
struct Checker {
    file: FileId,
    errors: Vec<Diagnostic>,
}

impl Checker {
    fn error(&mut self, span: Span<usize>, message: String) {
        self.errors.push(Diagnostic::error(SCENE_VALUE, message.clone()).with_primary(self.file, span, message));
    }

    fn number(&mut self, v: &Spanned<f64>, key: &str, range: &Range) -> Option<f64> {
        let shown = format!("{}", v.get_ref());
        match check_number(*v.get_ref(), &shown, "", range) {
            Ok(x) => Some(x),
            Err(m) => {
                self.error(v.span(), format!("`{key}`: {m}"));
                None
            }
        }
    }

    fn vec3(&mut self, v: &Spanned<[f64; 3]>, key: &str, range: &Range) -> Option<[f64; 3]> {
        let mut out = [0.0; 3];
        for (i, c) in v.get_ref().iter().enumerate() {
            match check_number(*c, &format!("{c}"), ["x", "y", "z"][i], range) {
                Ok(x) => out[i] = x,
                Err(m) => {
                    self.error(v.span(), format!("`{key}`: {m}"));
                    return None;
                }
            }
        }
        Some(out)
    }

    fn track<const N: usize>(
        &mut self,
        keys: &Option<RawKeys>,
        key: &str,
        frames: u32,
        range: &Range,
    ) -> Option<Track<N>> {
        let keys = keys.as_ref()?;
        let span = keys.span();
        let mut out = Vec::new();
        let mut last = None;
        for (frame, value) in keys.get_ref() {
            let components: Vec<f64> = match value {
                KeyValue::Number(v) => vec![*v],
                KeyValue::Vector(v) => v.clone(),
            };
            if components.len() != N {
                self.error(
                    span.clone(),
                    format!("`animate.{key}`: a key's value has {N} component(s), not {}", components.len()),
                );
                return None;
            }
            if *frame >= frames {
                self.error(
                    span.clone(),
                    format!("`animate.{key}`: key frame {frame} is not below `frames` = {frames}"),
                );
                return None;
            }
            if last.is_some_and(|l| *frame <= l) {
                self.error(
                    span.clone(),
                    format!("`animate.{key}`: key frames must ascend ({frame} after {})", last.unwrap_or(0)),
                );
                return None;
            }
            last = Some(*frame);
            let mut value = [0.0; N];
            for (i, c) in components.iter().enumerate() {
                match check_number(*c, &format!("{c}"), "", range) {
                    Ok(x) => value[i] = x,
                    Err(m) => {
                        self.error(span.clone(), format!("`animate.{key}` at frame {frame}: {m}"));
                        return None;
                    }
                }
            }
            out.push((*frame, value));
        }
        if out.is_empty() {
            self.error(span, format!("`animate.{key}`: give at least one [frame, value] key"));
            return None;
        }
        Some(Track { keys: out })
    }
}

/// The uniform value in `--set` syntax.
fn uniform_text(v: &UniformValueRaw) -> String {
    match v {
        UniformValueRaw::Bool(b) => b.to_string(),
        UniformValueRaw::Int(i) => i.to_string(),
        UniformValueRaw::Float(f) => format!("{f:?}"),
        UniformValueRaw::Vector(v) => v.iter().map(|c| format!("{c:?}")).collect::<Vec<_>>().join(","),
    }
}

/// serde's "unknown field `x`, expected one of `a`, `b`" with a "did you mean" note.
fn unknown_field_note(message: &str) -> Option<String> {
    let rest = message.strip_prefix("unknown field `")?;
    let (name, rest) = rest.split_once('`')?;
    let expected: Vec<&str> = rest.split('`').skip(1).step_by(2).collect();
    gdshader::diag::did_you_mean(name, expected.iter().copied()).map(|m| format!("did you mean `{m}`?"))
}

impl SceneFile {
    /// Reads, parses and validates the scene file at `path`.
    pub fn load(path: &Path) -> Result<SceneFile, SceneError> {
        let bytes = skycore::io::read_limited(path, MAX_SCENE_BYTES)
            .map_err(|e| SceneError::Read(format!("cannot read {}: {e}", path.display())))?;
        let text = String::from_utf8(bytes).map_err(|e| {
            // Located like every other scene-file error: the line and column of the first bad byte.
            let good = &e.as_bytes()[..e.utf8_error().valid_up_to()];
            let line = good.iter().filter(|&&b| b == b'\n').count() + 1;
            let column = good.iter().rev().take_while(|&&b| b != b'\n').count() + 1;
            SceneError::Invalid(format!(
                "error: {}:{line}:{column}: not UTF-8 text (a scene file is TOML, UTF-8)",
                path.display()
            ))
        })?;
        Self::parse(path, text)
    }

    /// Parses and validates `text`, the contents of the scene file `path`.
    pub fn parse(path: &Path, text: String) -> Result<SceneFile, SceneError> {
        let mut db = SourceDb::new();
        let file = db.add(path.display().to_string(), text.clone(), Some(path.to_path_buf()));
        let raw: RawScene = match toml::from_str(&text) {
            Ok(raw) => raw,
            Err(err) => {
                let message = err.message().trim().to_string();
                let span = err.span().unwrap_or(0..0);
                let mut d = Diagnostic::error(SCENE_SYNTAX, message.clone()).with_primary(file, span, message.clone());
                if let Some(note) = unknown_field_note(&message) {
                    d = d.with_note(note);
                }
                return Err(SceneError::Invalid(render_human(&db, &[d], false)));
            }
        };
        let base = path.parent().unwrap_or(Path::new("."));
        let mut c = Checker { file, errors: Vec::new() };
        let resolve = |s: &Spanned<String>| base.join(s.get_ref());
        let size = raw.size.as_ref().and_then(|s| {
            let [w, h] = *s.get_ref();
            match check_size(w, h) {
                Ok(v) => Some(v),
                Err(m) => {
                    c.error(s.span(), format!("`size`: {m}"));
                    None
                }
            }
        });
        if let (Some(Projection::CubeFace(_)), Some((w, h)), Some(s)) = (raw.projection, size, &raw.size)
            && w != h
        {
            c.error(s.span(), format!("`size`: a cubemap face must be square, not {w}x{h}"));
        }
        let time = raw.time.as_ref().and_then(|t| c.number(t, "time", &TIME)).map(|t| t as f32);
        let (mut sun_elevation, mut sun_azimuth, mut sun_energy, mut sun_color, mut sun_enabled, mut sun_size) =
            (None, None, None, None, None, None);
        if let Some(sun) = &raw.sun {
            sun_elevation = sun.elevation.as_ref().and_then(|v| c.number(v, "sun.elevation", &SUN_ELEVATION));
            sun_azimuth = sun.azimuth.as_ref().and_then(|v| c.number(v, "sun.azimuth", &TURN));
            sun_energy = sun.energy.as_ref().and_then(|v| c.number(v, "sun.energy", &ENERGY)).map(|v| v as f32);
            sun_color = sun.color.as_ref().and_then(|v| c.vec3(v, "sun.color", &COLOR)).map(|v| v.map(|x| x as f32));
            sun_enabled = sun.enabled;
            sun_size = sun.size.as_ref().and_then(|v| c.number(v, "sun.size", &ANGULAR_SIZE));
        }
        let mut lights = Vec::new();
        if let Some(list) = &raw.lights {
            if list.get_ref().len() > 3 {
                c.error(
                    list.span(),
                    format!("`lights`: at most 3 (LIGHT1 … LIGHT3; the sun is LIGHT0), not {}", list.get_ref().len()),
                );
            }
            for l in list.get_ref() {
                let elevation = c.number(&l.elevation, "lights.elevation", &SUN_ELEVATION).unwrap_or(0.0);
                let azimuth = l.azimuth.as_ref().and_then(|v| c.number(v, "lights.azimuth", &TURN)).unwrap_or(0.0);
                let energy = l.energy.as_ref().and_then(|v| c.number(v, "lights.energy", &ENERGY)).unwrap_or(1.0);
                let color = l.color.as_ref().and_then(|v| c.vec3(v, "lights.color", &COLOR)).unwrap_or([1.0; 3]);
                let size = l.size.as_ref().and_then(|v| c.number(v, "lights.size", &ANGULAR_SIZE)).unwrap_or(0.0);
                lights.push(Light {
                    elevation_deg: elevation,
                    azimuth_deg: azimuth,
                    energy: energy as f32,
                    color: color.map(|x| x as f32),
                    angular_diameter_deg: size,
                    enabled: l.enabled.unwrap_or(true),
                });
            }
        }
        let (mut position, mut fov, mut yaw, mut pitch) = (None, None, None, None);
        if let Some(cam) = &raw.camera {
            position = cam.position.as_ref().and_then(|v| c.vec3(v, "camera.position", &POSITION));
            fov = cam.fov.as_ref().and_then(|v| c.number(v, "camera.fov", &FOV));
            yaw = cam.yaw.as_ref().and_then(|v| c.number(v, "camera.yaw", &TURN));
            pitch = cam.pitch.as_ref().and_then(|v| c.number(v, "camera.pitch", &PITCH));
        }
        let uniforms = raw
            .uniforms
            .iter()
            .flatten()
            .map(|(name, v)| UniformSetting { name: name.clone(), text: uniform_text(v.get_ref()), span: v.span() })
            .collect();
        // A name listed twice is one override: the list says which uniforms, not how often.
        let mut overrides: Vec<OverrideSetting> = Vec::new();
        for o in raw.overrides.iter().flatten() {
            if !overrides.iter().any(|x| x.name == *o.get_ref()) {
                overrides.push(OverrideSetting { name: o.get_ref().clone(), span: o.span() });
            }
        }
        let animate = raw.animate.as_ref().and_then(|a| {
            let frames = *a.frames.get_ref();
            if !(1..=MAX_FRAMES).contains(&frames) {
                c.error(
                    a.frames.span(),
                    format!("`animate.frames`: `{frames}` is out of range; accepted: 1 to {MAX_FRAMES}"),
                );
                return None;
            }
            let dt = match (&a.fps, &a.dt) {
                (Some(_), Some(dt)) => {
                    c.error(dt.span(), "`animate`: give `fps` or `dt`, not both".into());
                    return None;
                }
                (Some(fps), None) => 1.0 / c.number(fps, "animate.fps", &FPS)?,
                (None, Some(dt)) => c.number(dt, "animate.dt", &DT)?,
                (None, None) => 1.0 / 24.0,
            };
            let uniforms = a
                .uniforms
                .iter()
                .flatten()
                .filter_map(|(name, keys)| {
                    let span = keys.span();
                    let mut out = Vec::new();
                    for (frame, value) in keys.get_ref() {
                        let v = match value {
                            KeyValue::Number(v) => vec![*v],
                            KeyValue::Vector(v) => v.clone(),
                        };
                        if *frame >= frames || out.last().is_some_and(|(l, _): &(u32, Vec<f64>)| *frame <= *l) {
                            c.error(
                                span.clone(),
                                format!(
                                    "`animate.uniforms.{name}`: key frames must ascend and be below `frames` = {frames}"
                                ),
                            );
                            return None;
                        }
                        out.push((*frame, v));
                    }
                    if out.is_empty() {
                        c.error(span, format!("`animate.uniforms.{name}`: give at least one [frame, value] key"));
                        return None;
                    }
                    Some(UniformTrack { name: name.clone(), keys: out, span })
                })
                .collect();
            Some(Animation {
                frames,
                dt,
                radiance_mode: a.radiance_mode.unwrap_or_default(),
                time: c.track(&a.time, "time", frames, &TIME),
                sun_elevation: c.track(&a.sun_elevation, "sun_elevation", frames, &SUN_ELEVATION),
                sun_azimuth: c.track(&a.sun_azimuth, "sun_azimuth", frames, &TURN),
                camera_position: c.track(&a.camera_position, "camera_position", frames, &POSITION),
                camera_yaw: c.track(&a.camera_yaw, "camera_yaw", frames, &TURN),
                camera_pitch: c.track(&a.camera_pitch, "camera_pitch", frames, &PITCH),
                camera_fov: c.track(&a.camera_fov, "camera_fov", frames, &FOV),
                uniforms,
            })
        });
        if !c.errors.is_empty() {
            return Err(SceneError::Invalid(render_human(&db, &c.errors, false)));
        }
        Ok(SceneFile {
            path: path.to_path_buf(),
            shader: raw.shader.as_ref().map(resolve),
            projection: raw.projection,
            size,
            time,
            sun_elevation,
            sun_azimuth,
            sun_enabled,
            sun_energy,
            sun_color,
            sun_size,
            lights,
            position,
            fov,
            yaw,
            pitch,
            uniforms,
            overrides,
            textures: raw
                .textures
                .iter()
                .flatten()
                .map(|(name, p)| TextureSetting { name: name.clone(), path: resolve(p), span: p.span() })
                .collect(),
            occluder: raw.occluder.as_ref().map(resolve),
            sky_resolution: raw.sky_resolution,
            animate,
            generated_textures: Vec::new(),
            generated_volumes: Vec::new(),
            generated_ramps: Vec::new(),
            db,
            file,
        })
    }

    /// The scene of a Godot material (`gdsky render sky.tres`): its shader, its values and its
    /// textures, located in the material's file; nothing else set (the flags' defaults apply).
    /// `shader` is the `.gdshader`, or the material file itself when the shader is embedded.
    pub fn from_material(
        material: gdresource::SkyMaterial,
        shader: PathBuf,
        settings: gdresource::MaterialSettings,
    ) -> SceneFile {
        SceneFile {
            path: material.path,
            shader: Some(shader),
            projection: None,
            size: None,
            time: None,
            sun_elevation: None,
            sun_azimuth: None,
            sun_enabled: None,
            sun_energy: None,
            sun_color: None,
            sun_size: None,
            lights: Vec::new(),
            position: None,
            fov: None,
            yaw: None,
            pitch: None,
            uniforms: settings.uniforms,
            overrides: Vec::new(),
            textures: settings.textures,
            occluder: None,
            sky_resolution: None,
            animate: None,
            generated_textures: settings.generated,
            generated_volumes: settings.generated_volumes,
            generated_ramps: settings.generated_ramps,
            db: material.db,
            file: material.file,
        }
    }

    /// Checks the scene's uniforms (values and keyframes) against `shader`: each must be a
    /// uniform of it, and each value must parse as its type (the `--set` rules); each name in
    /// `overrides` must be a scalar material uniform of it. The error is rendered, located in
    /// the scene file.
    pub fn check_uniforms(&self, shader: &gdshader::CheckedShader) -> Result<(), String> {
        let mut errors = Vec::new();
        let names: Vec<&str> = shader.uniforms.iter().map(|u| u.name.as_str()).collect();
        let check =
            |name: &str, text: &str, span: &Span<usize>, errors: &mut Vec<Diagnostic>| {
                let Some(u) = shader.uniforms.iter().find(|u| u.name == name) else {
                    let mut d = Diagnostic::error(SCENE_VALUE, format!("the shader has no uniform `{name}`"))
                        .with_primary(self.file, span.clone(), format!("`uniforms.{name}`"));
                    d = match gdshader::diag::did_you_mean(name, names.iter().copied()) {
                        Some(m) => d.with_note(format!("did you mean `{m}`?")),
                        None => d.with_note(format!("its uniforms are: {}", names.join(", "))),
                    };
                    errors.push(d);
                    return;
                };
                if let Err(why) = gdshader::values::parse_value(&u.ty, text) {
                    let m = format!("`{name}` = {text}: {why}");
                    errors.push(
                        Diagnostic::error(SCENE_VALUE, m.clone())
                            .with_primary(self.file, span.clone(), m)
                            .with_note(format!("`{name}` is a `{}`", u.type_name)),
                    );
                }
            };
        for u in &self.uniforms {
            check(&u.name, &u.text, &u.span, &mut errors);
        }
        for o in &self.overrides {
            let name = &o.name;
            let Some(u) = shader.uniforms.iter().find(|u| u.name == *name) else {
                let mut d = Diagnostic::error(SCENE_VALUE, format!("the shader has no uniform `{name}` to override"))
                    .with_primary(self.file, o.span.clone(), format!("`overrides`: `{name}`"));
                d = match gdshader::diag::did_you_mean(name, names.iter().copied()) {
                    Some(m) => d.with_note(format!("did you mean `{m}`?")),
                    None => d.with_note(format!("its uniforms are: {}", names.join(", "))),
                };
                errors.push(d);
                continue;
            };
            if u.global || !matches!(u.ty, gdshader::check::types::Type::Scalar(_)) {
                let m = format!(
                    "`{name}` cannot be an override: only scalar material uniforms can (WGSL overrides and SPIR-V \
                     specialization constants are scalars); it is a{} `{}`",
                    if u.global { " global" } else { "" },
                    u.type_name
                );
                errors.push(Diagnostic::error(SCENE_VALUE, m.clone()).with_primary(self.file, o.span.clone(), m));
            }
        }
        let textures = shader.texture_names();
        for t in &self.textures {
            if !textures.contains(&t.name) {
                let name = &t.name;
                let d = Diagnostic::error(SCENE_VALUE, format!("the shader has no sampler uniform `{name}`"))
                    .with_primary(self.file, t.span.clone(), format!("`textures.{name}`"));
                let d = match gdshader::diag::did_you_mean(name, textures.iter().map(String::as_str)) {
                    Some(m) => d.with_note(format!("did you mean `{m}`?")),
                    None if textures.is_empty() => d.with_note("it has no sampler uniforms"),
                    None => d.with_note(format!("its sampler uniforms are: {}", textures.join(", "))),
                };
                errors.push(d);
            }
        }
        for t in self.animate.iter().flat_map(|a| &a.uniforms) {
            let integer = shader.uniforms.iter().any(|u| u.name == t.name && is_integer_type(&u.ty));
            for (frame, _) in &t.keys {
                check(&t.name, &t.text_at(*frame, integer), &t.span, &mut errors);
            }
        }
        if errors.is_empty() { Ok(()) } else { Err(render_human(&self.db, &errors, false)) }
    }

    /// A located error at the uniform `name`'s value (the whole file when the scene does not
    /// set it), rendered.
    pub fn uniform_error(&self, name: &str, message: &str) -> String {
        let span = self.uniforms.iter().find(|u| u.name == name).map(|u| u.span.clone()).unwrap_or(0..0);
        let d = Diagnostic::error(SCENE_VALUE, message.to_string()).with_primary(self.file, span, message.to_string());
        render_human(&self.db, &[d], false)
    }

    /// A located error at the entry `name` of `overrides` (the whole file when it does not list
    /// it), rendered.
    pub fn override_error(&self, name: &str, message: &str) -> String {
        let span = self.overrides.iter().find(|o| o.name == name).map(|o| o.span.clone()).unwrap_or(0..0);
        let d = Diagnostic::error(SCENE_VALUE, message.to_string()).with_primary(self.file, span, message.to_string());
        render_human(&self.db, &[d], false)
    }

    /// A located error at the path of the texture `name` in `[textures]` (the whole file when
    /// the scene does not give it), rendered.
    pub fn texture_error(&self, name: &str, message: &str) -> String {
        let given = self.textures.iter().find(|t| t.name == name).map(|t| t.span.clone());
        let generated = || self.generated_textures.iter().find(|t| t.name == name).map(|t| t.span.clone());
        let volume = || self.generated_volumes.iter().find(|t| t.name == name).map(|t| t.span.clone());
        let ramp = || self.generated_ramps.iter().find(|t| t.name == name).map(|t| t.span.clone());
        let span = given.or_else(generated).or_else(volume).or_else(ramp).unwrap_or(0..0);
        let d = Diagnostic::error(SCENE_VALUE, message.to_string()).with_primary(self.file, span, message.to_string());
        render_human(&self.db, &[d], false)
    }

    /// The names of `overrides`, in file order.
    pub fn override_names(&self) -> Vec<String> {
        self.overrides.iter().map(|o| o.name.clone()).collect()
    }

    /// The uniforms the scene fixes as `(name, text)` pairs (`--set` syntax).
    pub fn uniform_pairs(&self) -> Vec<(String, String)> {
        self.uniforms.iter().map(|u| (u.name.clone(), u.text.clone())).collect()
    }
}

/// Whether uniform values of `ty` are integers (keyframes are rounded).
pub fn is_integer_type(ty: &gdshader::check::types::Type) -> bool {
    use gdshader::check::types::{Scalar, Type};
    matches!(ty, Type::Scalar(Scalar::Int | Scalar::UInt) | Type::Vector(Scalar::Int | Scalar::UInt, _))
}

/// The uniforms `--bake-scene` bakes: with a scene, the ones it fixes (then the `--set` pairs
/// over them); without one, every scalar or vector uniform with a default, at its default.
pub fn bake_values(
    shader: &gdshader::CheckedShader,
    scene: Option<&SceneFile>,
    sets: &[(String, String)],
) -> std::collections::HashMap<String, String> {
    let mut baked = std::collections::HashMap::new();
    match scene {
        Some(scene) => baked.extend(scene.uniform_pairs()),
        None => baked.extend(gdshader::values::defaults_as_set(shader)),
    }
    baked.extend(sets.iter().cloned());
    baked
}

/// Whether `path` names a scene file (`.toml`).
pub fn is_scene_path(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("toml"))
}

/// Whether `path` names a Godot resource or scene (`.tres`, `.tscn`): a material to render.
pub fn is_godot_resource(path: &Path) -> bool {
    gdresource::is_godot_path(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<SceneFile, SceneError> {
        SceneFile::parse(Path::new("dir/s.toml"), text.to_string())
    }

    #[test]
    fn a_full_scene_parses() {
        let s = parse(
            "shader = \"sky.gdshader\"\nprojection = \"camera\"\nsize = [64, 32]\ntime = 2\n[sun]\nelevation = 5\n\
             [camera]\nposition = [0, 2, 0]\nyaw = 30\n[uniforms]\nview_samples = 8\nground = [0.1, 0.2, 0.3]\n\
             [animate]\nframes = 6\nfps = 2\nsun_elevation = [[0, -5], [5, 20.5]]\n",
        )
        .unwrap();
        assert_eq!(s.shader, Some(PathBuf::from("dir/sky.gdshader")));
        assert_eq!(s.size, Some((64, 32)));
        assert_eq!(s.sun_elevation, Some(5.0));
        assert_eq!(
            s.uniform_pairs(),
            vec![("ground".into(), "0.1,0.2,0.3".into()), ("view_samples".into(), "8".into())]
        );
        let a = s.animate.unwrap();
        assert_eq!(a.dt, 0.5);
        let track = a.sun_elevation.unwrap();
        assert_eq!((track.at(0), track.at(5), track.at(9)), ([-5.0], [20.5], [20.5]));
    }

    #[test]
    fn overrides_keep_file_order_once_each_with_their_place() {
        let s = parse("overrides = [\"b\", \"a\", \"b\"]\n").unwrap();
        assert_eq!(s.override_names(), vec!["b".to_string(), "a".to_string()]);
        assert_eq!((s.overrides[0].span.clone(), s.overrides[1].span.clone()), (13..16, 18..21));
        let err = parse("overrides = \"a\"\n").unwrap_err().to_string();
        assert!(err.contains("dir/s.toml:1:13"), "{err}");
    }

    #[test]
    fn textures_resolve_against_the_scene_and_keep_their_place() {
        let s = parse("[textures]\nnoise = \"tex/noise.png\"\n").unwrap();
        assert_eq!(s.textures.len(), 1);
        assert_eq!(
            (s.textures[0].name.as_str(), s.textures[0].path.clone()),
            ("noise", PathBuf::from("dir/tex/noise.png"))
        );
        assert_eq!(s.textures[0].span, 19..34);
        assert!(parse("[textures]\nnoise = 3\n").is_err());
    }

    #[test]
    fn errors_are_located() {
        let err = parse("size = [64, 32]\n[sun]\nelevaton = 5\n").unwrap_err().to_string();
        assert!(err.contains("dir/s.toml:3:1"), "{err}");
        assert!(err.contains("did you mean `elevation`?"), "{err}");
        let err = parse("[sun]\nelevation = 95\n").unwrap_err().to_string();
        assert!(err.contains("dir/s.toml:2:13") && err.contains("out of range"), "{err}");
        let err = parse("time = \"soon\"\n").unwrap_err().to_string();
        assert!(err.contains("dir/s.toml:1:8"), "{err}");
    }
}

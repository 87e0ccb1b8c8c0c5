//! # skyoracle — real Godot 4.6 as a test oracle
//!
//! gdsky claims that its WGSL/SPIR-V port of a Godot sky shader computes what Godot computes.
//! `skyref` checks that claim against a hand-written Rust model of one shader; this crate checks
//! it against Godot itself. It runs the official Godot 4.6.stable Web export (the Compatibility
//! renderer, WebGL2) in headless Chromium, with no GPU, and asks it to render any sky shader in a
//! scene gdsky also knows how to render: a camera, a sun, uniform values. Godot only hands back
//! 8-bit pixels, so the oracle renders each scene at many energies and inverts Godot's own
//! transfer curve to recover the shader's linear COLOR, with an interval per pixel that says how
//! sure it is. It also answers the front end's question "does Godot accept this shader?", with
//! Godot's errors and line numbers.
//!
//! ## How it runs
//!
//! ```text
//! Oracle (Rust) ──JSON lines──▶ node driver.mjs ──playwright-core──▶ chromium --headless
//!                                    │ http://127.0.0.1:PORT                    │
//!                                    └─ serves .oracle/godot/index.{js,wasm}    └─ Godot 4.6 Web export
//!                                       and oracle.pck (written by write_pck)      boots oracle.pck:
//!                                                                                  project.godot, main.tscn,
//!                                                                                  main.gd (the job runner)
//! ```
//!
//! * [`Oracle::start`] finds the parts ([`Installation::find`]; what is absent comes back as
//!   [`Missing`], naming each part and `bash scripts/install-oracle.sh`), writes the driver and a
//!   PCK (format v3, text files only, [`write_pck`]) to a temporary directory, and spawns
//!   `node driver.mjs` in a process group of its own. The driver serves the export and the pack on
//!   127.0.0.1 (with the cross-origin isolation headers Godot's export asks for), launches
//!   Debian's `/usr/bin/chromium` through playwright-core (a fresh temporary profile; background
//!   networking, component updates and sync off; playwright never downloads a browser) and loads a
//!   page that starts Godot with `mainPack: "oracle.pck"`.
//! * `main.gd` builds a SubViewport (own World3D, no MSAA, no debanding) holding a
//!   WorldEnvironment (sky background, linear tonemapper, exposure 1, no glow, fog, adjustments,
//!   ambient or reflected sky light, so no radiance map is ever rendered), a Camera3D
//!   (`KEEP_HEIGHT`) and a DirectionalLight3D. Per [`Job`] it sets the shader, a fresh
//!   ShaderMaterial with the uniform overrides, the camera (`rotation_degrees = (pitch, yaw, 0)`,
//!   Euler YXZ), the sun (`rotation_degrees = (−e, 180° − a, 0)`, whose +Z is
//!   (cos e sin a, sin e, −cos e cos a)) and the image size, then for each bracket sets
//!   `Environment.background_energy_multiplier`, awaits `RenderingServer.frame_post_draw` and reads
//!   the viewport's image. Pages and Godot talk through `JavaScriptBridge.get_interface`; frames
//!   travel as base64 RGBA8.
//! * The oracle stays up between jobs. Every wait has a limit (boot 120 s; a job 60 s plus 50 µs
//!   per pixel per bracket unless [`Job::timeout`] says otherwise). A page error, a crash, a lost
//!   WebGL context, Godot exiting or a timeout becomes an [`OracleError`] and stops the oracle
//!   (later calls give [`OracleError::Dead`]; [`Oracle::restart`] boots a new one, about 3 s).
//!   Dropping the [`Oracle`] closes the driver's stdin (it closes the browser), then kills what is
//!   left of its process group. A shader Godot rejects is [`OracleError::Shader`], not a crash.
//!
//! ## Recovering linear radiance
//!
//! The Compatibility renderer's sky pass (drivers/gles3/shaders/sky.glsl, tonemap_inc.glsl) stores
//! round(255 · clamp(L2S(exposure · S2L(energy · COLOR)))) in an RGBA8 target, with
//! S2L(c) = c·(c·(0.305306011·c + 0.682171111) + 0.012522878) and
//! L2S(x) = max(1.055·x^0.41666667 − 0.055, 0); energy is `background_energy_multiplier`.
//! Measured, that formula is right in shape but not to the code: on SwiftShader every one of the
//! 255 thresholds sits away from the formula's q − ½, by up to 0.12 of a code (code 170 at
//! −0.123; code 1 at +0.12), which would bias a formula-based inversion near black. So the oracle
//! measures the store itself at start ([`Oracle::transfer`], about 0.6 s): a bisection over f32
//! bit patterns, built exactly in the shader with `uintBitsToFloat`, finds for each code q the
//! least y = energy · COLOR stored as q or above, to the last bit, in 3 passes of a 255×256 image.
//! It also checks that the store is monotonic and the same for R, G and B.
//!
//! A code q at energy e then means COLOR ∈ [t(q)/e, t(q+1)/e). [`recover::recover`] intersects
//! these intervals over the brackets, per channel, and reports the middle
//! ([`OracleImage::pixels`]), the interval ([`OracleImage::lower`], [`OracleImage::upper`]), the
//! number of unclipped brackets ([`OracleImage::valid`]; 0 = black everywhere, reported as 0, or
//! saturated everywhere, reported as its lower bound) and the channels whose brackets contradict
//! each other ([`OracleImage::inconsistent`]). The default brackets are 2^−12 … 2^14, one per
//! octave (27 frames): everything from about 2e−6 (code 0 covers y < 0.0286) to 4086
//! (t(255) · 2^12) is seen unclipped in some frame.
//!
//! Constant colours 10^(−5 + 8i/255), i = 0…255, one per column (`examples/measure.rs`):
//!
//! | COLOR | octave brackets (27): median / max error | quarter-stop (105): median / max |
//! | --- | --- | --- |
//! | 1e−5 … 1e−4 | 0.143 % / 0.567 % | 0.045 % / 0.315 % |
//! | 1e−4 … 1e−3 | 0.095 % / 0.279 % | 0.025 % / 0.112 % |
//! | 1e−3 … 1e−2 | 0.086 % / 0.293 % | 0.023 % / 0.084 % |
//! | 1e−2 … 1e−1 | 0.080 % / 0.327 % | 0.027 % / 0.116 % |
//! | 1e−1 … 1e0 | 0.111 % / 0.313 % | 0.020 % / 0.178 % |
//! | 1e0 … 1e1 | 0.133 % / 0.343 % | 0.023 % / 0.136 % |
//! | 1e1 … 1e2 | 0.106 % / 0.264 % | 0.023 % / 0.137 % |
//! | 1e2 … 1e3 | 0.094 % / 0.254 % | 0.030 % / 0.159 % |
//! | all | 0.099 % / 0.567 % | 0.026 % / 0.315 % |
//!
//! Every true value lay inside its reported interval, and no channel was inconsistent. The
//! quarter-stop set costs 3–4× the time (1.28 s against 0.36 s for the Freeman sky at 64×32).
//!
//! ## Measured on this machine (2 cores, no GPU, Chromium 156, SwiftShader through ANGLE/Vulkan)
//!
//! * Start: 2.7–5.7 s from spawning node to Godot's ready (Chromium's launch and the 37 MB wasm
//!   included; the spread is load from other processes), then 0.6–2 s of calibration.
//! * A new shader costs 0.3–0.5 s of compilation in its first frame (Godot's compiler, then
//!   SwiftShader's); the same code again is cached.
//! * Freeman sky (camera 1 m up, sun 10°): 64×32 × 27 frames in 0.36 s (12 ms per frame; 0.8 s
//!   with the first compile); 256×128 × 27 frames in 3.5 s (0.12 s per frame, 0.35–0.42 s per
//!   frame while another build ran). A trivial shader: 16 ms per frame at 64×32.
//! * Without `--disable-frame-rate-limit`, headless Chromium paces WebGL frames at about 1 Hz
//!   with no GPU (1 s per frame whatever is drawn); the driver passes it.
//! * The integration tests (`tests/godot/oracle.rs`, 10 tests sharing one oracle) took 36 s with other
//!   builds running (15–25 s for the first 7 on a quieter machine).
//!
//! ## Conventions, as Godot 4.6's Compatibility renderer showed them
//!
//! Confirmed (tests in `tests/godot/oracle.rs`):
//! * EYEDIR = normalize(R_y(yaw) R_x(pitch) ((2(x+½)/W − 1)·t·W/H, (1 − 2(y+½)/H)·t, −1)),
//!   t = tan(fov/2), row 0 at the top, yaw 0 pitch 0 looking toward −Z: within 2e−7, computed in
//!   the shader from FRAGCOORD with the basis's sines and cosines from the CPU.
//! * FRAGCOORD.y counts from the top row of the returned image (0.5 at row 0).
//! * LIGHT0_DIRECTION = (cos e sin a, sin e, −cos e cos a) within 1e−6; LIGHT0_COLOR arrives as
//!   set, not converted to linear (Forward+ converts it); LIGHT0_ENERGY as set; LIGHT0_SIZE is the
//!   angular diameter in radians (not its tangent); without a visible light LIGHT0_ENABLED is
//!   false (and LIGHT0_ENERGY keeps the last light's value).
//! * SKY_COORDS uses approximations: against exact trigonometry of the EYEDIR above, u is off by
//!   up to 2.15e−4 and v by up to 2.87e−3 (three camera poses, all the same maximum).
//! * TIME is wall-clock seconds since Godot started (it grew by 1.07 s over a 1 s pause); it
//!   cannot be set. POSITION is the camera's position.
//! * A new shader, size, camera, uniform or energy shows in the very next frame (checked with no
//!   settling frame; the recovery's consistency check would catch a stale one).
//! * `source_color` uniforms are not converted: a `vec3`/`vec4` set as a Vector3, a Vector4 or a
//!   Color arrives as given (so [`Parameter::Color`] and a `vec3` [`Parameter::Value`] agree).
//!
//! Not as expected:
//! * A negative COLOR is not stored as 0: S2L's cubic is positive for −2.22 < y < −0.0185, so
//!   y = −1 is stored as code 163. Across brackets such a channel contradicts itself and is
//!   counted in [`OracleImage::inconsistent`]; its value is meaningless.
//! * NaN (`sqrt(-1.0)`) is stored as 255 in every bracket: it reads as saturated (lower bound
//!   4086, no valid bracket), indistinguishable from radiance above the top bracket.
//! * SwiftShader's GLSL `sin`/`cos` are off by up to about 5e−5; parity thresholds for shaders
//!   that use them must allow for it.
//! * A SubViewport side of 1 pixel becomes 2 ([`MIN_SIDE`]).
//! * SCREEN_UV is FRAGCOORD.xy, in pixels (0.5 … W − 0.5), not the 0…1 the documentation
//!   describes (and Forward+ and gdsky give): equal to FRAGCOORD.xy within 1e−6, computed in the
//!   shader. A shader that reads SCREEN_UV differs between this oracle and gdsky.
//!
//! ## Textures
//!
//! [`Parameter::TextureRgbaF32`] gives a `sampler2D` uniform a 2D texture of RGBA 32-bit
//! floats: the job carries it as base64 of the little-endian bytes (for 256×64 texels, 349 528
//! bytes, against 653 580 as JSON numbers, and exact), and `main.gd` builds
//! `ImageTexture.create_from_image(Image.create_from_data(w, h, false, FORMAT_RGBAF, bytes))`.
//! [`Job`]'s check refuses sides outside 1 … [`MAX_TEXTURE_SIDE`], a texel count other than
//! w·h and non-finite texels. Texel (x, y) is `texels[y·w + x]`, which `texelFetch(t, ivec2(x,
//! y), 0)` reads.
//!
//! Measured (`tests/godot/oracle.rs`): the Compatibility renderer on WebGL2/SwiftShader keeps the
//! texels **bit for bit** through `texelFetch`. Four texels holding values no 16-bit float or
//! 8-bit format can hold (0.1, π, 1.2345e−5, 123.456, 1e5, 1e−30, 3.4e38, −2.5, …) were
//! compared inside the shader with their bit patterns (a `uint` array and `floatBitsToUint`): all
//! 16 channels equal, and the same comparison with one pattern one ulp off counts exactly one
//! mismatch, its relative difference read back as that ulp. Through the recovery, the RGB of
//! those texels came back within 0.27 %, and a 256×64 table of values over 1e−4 … 1e2 within
//! 0.38 %, each texel at its own pixel: the recovery's accuracy, nothing added. A 256×64 texture
//! adds about 0.1 s to a job (1.06 s at 256×64 × 27 frames, Godot 0.34 s of it, against 0.98 s
//! with a 1×1 texture whose job also compiled the shader).
//!
//! ## Noise textures
//!
//! [`Oracle::noise_image`] has Godot build a `NoiseTexture2D` with a `FastNoiseLite` (and a
//! `Gradient` colour ramp) from JSON maps of their properties ([`NoiseTextureSpec`], by Godot's
//! names; `main.gd` converts each value to the property's type and refuses an unknown name or a
//! value of the wrong shape, such as a fraction for an integer property), waits for its `changed` signal (the first generation runs
//! synchronously in a deferred call at the end of the frame) and returns level 0 of
//! `get_image()` in Godot's own format, L8 or RGBA8, as base64 ([`GodotNoiseImage`], with the
//! mip levels below it when Godot generated them). [`Oracle::noise_volume`] does
//! the same for a `NoiseTexture3D`, but reads its slices from the calls its generation makes
//! (`get_image_3d` / `get_seamless_image_3d`, then the colour ramp through `Gradient.sample`
//! of each texel's luminance): `NoiseTexture3D.get_data()` goes through the Compatibility
//! renderer's `texture_3d_get`, which on WebGL2 hands back wrong slices (measured: slices 0, 0,
//! 1, 3, 3, 4 of a depth-6 texture). [`Oracle::defaults`] reads the properties of a new
//! instance of any class, to check defaults against Godot's own.
//!
//! [`Parameter::NoiseTexture2D`] binds such a texture to a `sampler2D` in a render job;
//! `main.gd` builds it and waits for its generation before drawing. Measured
//! (`tests/noise_oracle.rs` in the root crate): a sky shader reading it with `texelFetch` sees
//! (v, v, v) for an L8 code v, and gdsky's `gdsky::noise` generates the same bytes as Godot in
//! every configuration tried (docs/noise.md). A 64×64 texture takes about 0.1 s.
//!
//! [`Oracle::ramp_image`] does the same for a `GradientTexture1D`, `GradientTexture2D` or
//! `CurveTexture` ([`RampTextureSpec`], with its `Gradient` or `Curve`), returning the image in
//! Godot's format (RGBA8, RGBAF with `use_hdr`, RGBF or RF for a curve), and
//! [`Parameter::RampTexture`] binds one to a `sampler2D` in a render job.
//!
//! ## Compile checks
//!
//! [`Oracle::compile`] sets the code on a fresh Shader, draws two frames (so the GL driver
//! compiles it too) and reads Godot's log: each `SHADER ERROR: …` line followed by
//! `   at: (null) (:N)` becomes a [`ShaderError`] with line N (1-based, in the code as given).
//! `#include` cannot work (the pack holds no other file) and a failed preprocessor leaves the raw
//! text to the compiler, which then reports "Unknown character #35: '#'". Empty code renders
//! black with no error. `dFdx` is accepted by the Compatibility renderer.
//!
//! ## Limits
//!
//! * One renderer: Compatibility (GLES3/WebGL2), single-threaded, 8-bit. Forward+ and Mobile
//!   differ (LIGHT0_COLOR conversion, exact SKY_COORDS in 4.3–4.5, the radiance map); this oracle
//!   does not see them. Only the background pass: no half/quarter-resolution or cubemap passes,
//!   no radiance map, no fog.
//! * Textures: 2D RGBA 32-bit float ones (and Godot's own noise textures, above) and RGBA 32-bit
//!   float cube maps ([`Parameter::CubeRgbaF32`]) only, one level, no mipmaps; 2D ones read
//!   exactly with `texelFetch` (above), cube maps with a `filter_nearest` hint. Filtered sampling
//!   (`texture()`) of them was not measured (WebGL2 filters 32-bit floats only with
//!   `OES_texture_float_linear`); other 8-bit, sRGB (`source_color`), 3D and array textures
//!   cannot be given, and a sampler uniform not given keeps Godot's default for its
//!   hint.
//! * The GPU is SwiftShader: its transcendental functions are approximations of their own.
//! * Alpha is not recovered (the background pass forces it; [`OracleImage::pixels`] has alpha 1).
//! * Negative values are not recoverable, and NaN looks like saturation (above).
//! * TIME is not settable, so time-dependent shaders are not reproducible.
//! * A job runs one frame per bracket: about 0.12 s × 27 for the Freeman sky at 256×128.
//!
//! ## Example
//!
//! ```no_run
//! use skycore::Scene;
//! use skyoracle::{Job, Oracle};
//!
//! let mut oracle = Oracle::start(".".as_ref())?; // the repository root
//! let code = std::fs::read_to_string("fixtures/freeman_sky.gdshader")?;
//! let scene = Scene::default().with_sun(10.0, 30.0).with_position(glam::DVec3::new(0.0, 1.0, 0.0));
//! let job = Job { scene, ..Job::new(code, 64, 32) };
//! let image = oracle.render(&job)?;
//! println!("centre {:?}, {} unclipped brackets", image.pixel(32, 16), image.valid_min(32, 16));
//! let outcome = oracle.compile("shader_type sky;\nvoid sky() { COLOR = 1.0; }\n")?;
//! for error in &outcome.errors {
//!     println!("line {:?}: {}", error.line, error.message);
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod compile;
mod install;
mod job;
mod noise;
mod pck;
mod process;
mod ramp;
pub mod recover;

use base64::Engine as _;
use std::fmt;
use std::path::Path;
use std::time::{Duration, Instant};

use serde_json::{Value, json};

pub use compile::{CompileOutcome, ShaderError};
pub use install::{INSTALL_COMMAND, Installation, Missing, MissingPart};
pub use job::{Brackets, Job, MAX_SIDE, MAX_TEXTURE_SIDE, MIN_SIDE, Parameter};
pub use noise::{GodotNoiseImage, NoiseTextureSpec};
pub use pck::write_pck;
pub use ramp::{GodotRampImage, RampTextureSpec};
pub use recover::Transfer;

use process::{Driver, WorkDir};
use recover::{CALIBRATION_SAMPLES, Calibrator};

/// The Node driver: static server, Chromium through playwright-core, JSON lines.
pub const DRIVER_MJS: &str = include_str!("../assets/driver.mjs");
/// The GDScript job runner the pack boots.
pub const MAIN_GD: &str = include_str!("../assets/main.gd");
/// The pack's main scene: one Node with `main.gd`.
pub const MAIN_TSCN: &str = include_str!("../assets/main.tscn");
/// The pack's project settings (Compatibility renderer).
pub const PROJECT_GODOT: &str = include_str!("../assets/project.godot");

/// The engine version the pack is stamped with (Godot refuses packs from newer engines).
const PACK_ENGINE: (u32, u32, u32) = (4, 6, 0);
/// From starting node to Godot's ready: Chromium's launch, the 37 MB wasm, Godot's boot.
const BOOT_TIMEOUT: Duration = Duration::from_secs(120);
/// Slack on top of a job's own time limit, which the driver enforces first.
const REPLY_SLACK: Duration = Duration::from_secs(15);
/// How long a compile job may take (Godot parses, then the GL driver compiles at first draw).
const COMPILE_TIMEOUT: Duration = Duration::from_secs(60);
/// Bisection passes allowed to the calibration (each narrows 255-fold; 3 are needed).
const CALIBRATION_PASSES: usize = 12;

/// Why the oracle could not start.
#[derive(Debug)]
pub enum StartError {
    /// A part is not installed.
    Missing(Missing),
    /// Everything is installed, but the driver, Chromium or Godot failed on the way up.
    Failed(OracleError),
}

impl fmt::Display for StartError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Missing(m) => m.fmt(f),
            Self::Failed(e) => write!(f, "the Godot oracle failed to start: {e}"),
        }
    }
}

impl std::error::Error for StartError {}

impl From<Missing> for StartError {
    fn from(m: Missing) -> Self {
        Self::Missing(m)
    }
}

/// What went wrong with a job.
#[derive(Debug)]
pub enum OracleError {
    /// The job asks for something Godot cannot be given (a size of 0, a NaN, no brackets).
    InvalidJob(String),
    /// Godot rejected the shader; its errors are inside.
    Shader(CompileOutcome),
    /// The GDScript runner refused the job (its message).
    Godot(String),
    /// No answer in time. The oracle is stopped: a later call gives [`OracleError::Dead`].
    Timeout {
        /// The job or phase that was waited for.
        what: String,
        /// How long.
        after: Duration,
    },
    /// The driver, Chromium or Godot died or reported a fatal error. The oracle is stopped.
    Crashed {
        /// What the driver said (or how it ended).
        message: String,
        /// The driver's last stderr lines (Chromium's console included).
        stderr_tail: String,
    },
    /// An answer did not have the expected shape. The oracle is stopped.
    Protocol(String),
    /// An earlier error stopped the oracle; [`Oracle::restart`] starts a new one.
    Dead(String),
    /// The temporary directory could not be written or the driver could not be spawned.
    Io(std::io::Error),
}

impl fmt::Display for OracleError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::InvalidJob(m) => write!(f, "invalid job: {m}"),
            Self::Shader(outcome) => {
                write!(f, "Godot rejected the shader")?;
                for e in &outcome.errors {
                    match e.line {
                        Some(line) => write!(f, "; line {line}: {}", e.message)?,
                        None => write!(f, "; {}", e.message)?,
                    }
                }
                Ok(())
            }
            Self::Godot(m) => write!(f, "the Godot job runner refused the job: {m}"),
            Self::Timeout { what, after } => write!(f, "no answer from Godot within {after:?} ({what})"),
            Self::Crashed { message, stderr_tail } => {
                write!(f, "the oracle crashed: {message}")?;
                if !stderr_tail.is_empty() {
                    write!(f, "\n--- driver stderr (last lines) ---\n{stderr_tail}")?;
                }
                Ok(())
            }
            Self::Protocol(m) => write!(f, "unexpected answer from the oracle: {m}"),
            Self::Dead(m) => write!(f, "the oracle is stopped after an earlier error: {m}"),
            Self::Io(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for OracleError {}

impl From<std::io::Error> for OracleError {
    fn from(e: std::io::Error) -> Self {
        Self::Io(e)
    }
}

/// What the running oracle is, as it reported itself at start.
#[derive(Clone, Debug, PartialEq)]
pub struct OracleInfo {
    /// Godot's version string (`4.6-stable (official)`).
    pub godot_version: String,
    /// Godot's rendering method (`gl_compatibility`).
    pub rendering_method: String,
    /// WebGL's unmasked renderer (ANGLE's backend and device).
    pub webgl_renderer: String,
    /// Chromium's version.
    pub browser_version: String,
    /// From spawning the driver to Godot's ready (Chromium's launch included).
    pub boot: Duration,
    /// The calibration of the 8-bit store that followed.
    pub calibration: Duration,
    /// Calibration passes used.
    pub calibration_passes: usize,
    /// True when FRAGCOORD.y = 0.5 is the first (top) row of the images the oracle returns.
    pub fragcoord_y_down: bool,
}

/// A render's 8-bit frames, before recovery.
#[derive(Clone, Debug, PartialEq)]
pub struct RawRender {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The energy of each frame.
    pub energies: Vec<f32>,
    /// One RGBA8 frame per energy, row 0 at the top, as Godot stored it.
    pub frames: Vec<Vec<u8>>,
    /// Everything Godot printed during the job.
    pub log: Vec<String>,
    /// Time measured.
    pub timing: Timing,
}

/// Where a job's time went.
#[derive(Clone, Debug, PartialEq)]
pub struct Timing {
    /// From sending the job to decoding its reply.
    pub wall: Duration,
    /// Inside Godot, from taking the job to handing back its reply.
    pub godot: Duration,
    /// Per captured frame: from setting its energy to reading the image back.
    pub frames: Vec<Duration>,
}

/// Linear radiance rendered by Godot, recovered from the bracketed frames.
#[derive(Clone, Debug, PartialEq)]
pub struct OracleImage {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Row 0 at the top: linear COLOR (the value before Godot's energy multiplier, sRGB
    /// approximation and 8-bit store), alpha 1.
    pub pixels: Vec<[f32; 4]>,
    /// Per pixel and channel, how many brackets stored it unclipped (a code strictly between
    /// 0 and 255). 0 means recovery failed there: black in every bracket (the pixel is 0 and
    /// [`Self::upper`] bounds it) or saturated in every bracket (it is [`Self::lower`] or more).
    pub valid: Vec<[u8; 3]>,
    /// Per pixel and channel: the true value is at least this (given the measured store).
    pub lower: Vec<[f32; 3]>,
    /// Per pixel and channel: the true value is below this (∞ when saturated everywhere).
    pub upper: Vec<[f32; 3]>,
    /// Channels whose brackets disagreed (see [`recover::Recovered::inconsistent`]); 0 normally.
    pub inconsistent: usize,
    /// Everything Godot printed during the job.
    pub log: Vec<String>,
    /// Time measured.
    pub timing: Timing,
}

impl OracleImage {
    /// The fewest unclipped brackets over the pixel's three channels.
    pub fn valid_min(&self, x: u32, y: u32) -> u8 {
        let v = self.valid[(y * self.width + x) as usize];
        v[0].min(v[1]).min(v[2])
    }

    /// The pixel at column x, row y (row 0 at the top).
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixels[(y * self.width + x) as usize]
    }
}

/// Real Godot, running headless: a Node driver, Chromium and Godot's Web export, kept up between
/// jobs. Dropping it ends them.
pub struct Oracle {
    install: Installation,
    // Field order matters: the driver (and with it Chromium) stops before its files go.
    driver: Driver,
    _work_dir: WorkDir,
    info: OracleInfo,
    transfer: Transfer,
    next_id: u64,
    dead: Option<String>,
}

impl Oracle {
    /// Checks that the oracle's parts are installed under `root` (the repository root), without
    /// starting anything.
    pub fn check(root: &Path) -> Result<Installation, Missing> {
        Installation::find(root)
    }

    /// Starts the oracle for the repository at `root`: boots Godot in Chromium and measures its
    /// 8-bit store ([`Oracle::transfer`]). Takes a few seconds.
    pub fn start(root: &Path) -> Result<Self, StartError> {
        let install = Installation::find(root)?;
        Self::start_installed(install).map_err(StartError::Failed)
    }

    fn start_installed(install: Installation) -> Result<Self, OracleError> {
        let work_dir = WorkDir::create()?;
        let driver_path = work_dir.path().join("driver.mjs");
        std::fs::write(&driver_path, DRIVER_MJS)?;
        let files: [(&str, &[u8]); 3] = [
            ("project.godot", PROJECT_GODOT.as_bytes()),
            ("main.tscn", MAIN_TSCN.as_bytes()),
            ("main.gd", MAIN_GD.as_bytes()),
        ];
        std::fs::write(work_dir.path().join("oracle.pck"), write_pck(PACK_ENGINE, &files))?;

        let started = Instant::now();
        let mut driver = Driver::spawn(&install, &driver_path, work_dir.path())?;
        let ready = driver.recv(BOOT_TIMEOUT, "boot")?;
        if ready.get("event").and_then(Value::as_str) != Some("ready") {
            return Err(OracleError::Protocol(format!("expected the ready event, got {ready:.300}")));
        }
        let text = |v: &Value, path: &[&str]| {
            path.iter().try_fold(v, |v, k| v.get(k)).and_then(Value::as_str).unwrap_or("").to_string()
        };
        let info = OracleInfo {
            godot_version: text(&ready, &["godot", "version"]),
            rendering_method: text(&ready, &["godot", "rendering_method"]),
            webgl_renderer: text(&ready, &["webgl", "renderer"]),
            browser_version: text(&ready, &["browser"]),
            boot: started.elapsed(),
            calibration: Duration::ZERO,
            calibration_passes: 0,
            fragcoord_y_down: true,
        };
        let mut oracle =
            Self { install, driver, _work_dir: work_dir, info, transfer: Transfer::model(), next_id: 1, dead: None };
        oracle.calibrate()?;
        Ok(oracle)
    }

    /// Stops this oracle (if it still runs) and starts a new one with the same installation.
    pub fn restart(&mut self) -> Result<(), OracleError> {
        self.driver.stop(Duration::from_secs(5));
        self.dead = Some("stopped for a restart that failed".into());
        *self = Self::start_installed(self.install.clone())?;
        Ok(())
    }

    /// What is running.
    pub fn info(&self) -> &OracleInfo {
        &self.info
    }

    /// The 8-bit store measured at start (see [`recover`]).
    pub fn transfer(&self) -> &Transfer {
        &self.transfer
    }

    /// False once an error has stopped the oracle.
    pub fn is_alive(&self) -> bool {
        self.dead.is_none()
    }

    /// Measures the orientation of FRAGCOORD and the 255 thresholds of the 8-bit store.
    fn calibrate(&mut self) -> Result<(), OracleError> {
        let started = Instant::now();
        let probe = Job {
            brackets: Brackets::from_energies(vec![1.0]),
            ..Job::new("shader_type sky;\nvoid sky() {\n\tCOLOR = vec3(FRAGCOORD.y < 1.0 ? 1.0 : 0.0);\n}\n", 2, 2)
        };
        let raw = self.render_raw(&probe)?;
        let (top, bottom) = (raw.frames[0][0], raw.frames[0][8]);
        self.info.fragcoord_y_down = match (top, bottom) {
            (255, 0) => true,
            (0, 255) => false,
            _ => return Err(OracleError::Protocol(format!("FRAGCOORD probe read {top} over {bottom}, not 255/0"))),
        };

        let mut calibrator = Calibrator::new();
        let mut passes = 0;
        while !calibrator.done() {
            if passes == CALIBRATION_PASSES {
                return Err(OracleError::Protocol(format!(
                    "the calibration of the 8-bit store did not converge in {passes} passes"
                )));
            }
            let job = Job {
                brackets: Brackets::from_energies(vec![1.0]),
                uniforms: calibrator.uniforms(),
                ..Job::new(Calibrator::shader(), 255, CALIBRATION_SAMPLES)
            };
            let raw = self.render_raw(&job)?;
            calibrator.update(&raw.frames[0], self.info.fragcoord_y_down);
            passes += 1;
        }
        if calibrator.non_monotonic > 0 || calibrator.channel_mismatches > 0 {
            return Err(OracleError::Protocol(format!(
                "the 8-bit store is not one monotonic curve shared by R, G and B ({} decreasing samples, {} \
                 channel mismatches)",
                calibrator.non_monotonic, calibrator.channel_mismatches
            )));
        }
        self.transfer = Transfer::from_thresholds(&calibrator.thresholds())
            .ok_or_else(|| OracleError::Protocol("the measured thresholds do not increase".into()))?;
        self.info.calibration = started.elapsed();
        self.info.calibration_passes = passes;
        Ok(())
    }

    /// Sends one job and waits for its reply (Godot's reply object and log); any failure stops
    /// the oracle.
    fn exchange(
        &mut self,
        mut message: Value,
        timeout: Duration,
        what: &str,
    ) -> Result<(Value, Vec<String>), OracleError> {
        if let Some(reason) = &self.dead {
            return Err(OracleError::Dead(reason.clone()));
        }
        let id = self.next_id;
        self.next_id += 1;
        message["id"] = json!(id);
        let result = self.driver.send(&message).and_then(|()| self.driver.recv(timeout + REPLY_SLACK, what));
        let reply = match result {
            Ok(reply) => reply,
            Err(e) => return Err(self.stop_after(e)),
        };
        if reply.get("id").and_then(Value::as_u64) != Some(id) {
            return Err(
                self.stop_after(OracleError::Protocol(format!("expected the reply to job {id}, got {reply:.300}")))
            );
        }
        let log = reply
            .get("log")
            .and_then(Value::as_array)
            .map(|lines| lines.iter().filter_map(Value::as_str).map(String::from).collect())
            .unwrap_or_default();
        Ok((reply.get("reply").cloned().unwrap_or(Value::Null), log))
    }

    /// The runner's refusal, if the reply is one.
    fn refusal(reply: &Value) -> Result<(), OracleError> {
        match reply.get("error").and_then(Value::as_str) {
            Some(message) => Err(OracleError::Godot(message.to_string())),
            None => Ok(()),
        }
    }

    fn stop_after(&mut self, error: OracleError) -> OracleError {
        self.dead = Some(error.to_string());
        self.driver.stop(Duration::from_secs(2));
        error
    }

    /// Renders `job` and returns its 8-bit frames as Godot stored them.
    pub fn render_raw(&mut self, job: &Job) -> Result<RawRender, OracleError> {
        job.validate().map_err(OracleError::InvalidJob)?;
        let started = Instant::now();
        let (reply, log) = self.exchange(job.to_json(0), job.time_allowed(), "a render job")?;
        // A rejected shader also makes the runner refuse uniform overrides: report the cause.
        let outcome = CompileOutcome::from_log(log);
        if !outcome.accepted {
            return Err(OracleError::Shader(outcome));
        }
        Self::refusal(&reply)?;
        let (width, height) = (job.width, job.height);
        let frames = reply
            .get("frames")
            .and_then(Value::as_array)
            .ok_or_else(|| self.protocol("a render reply without frames"))?
            .iter()
            .map(|f| f.as_str().and_then(|text| base64::engine::general_purpose::STANDARD.decode(text).ok()))
            .collect::<Option<Vec<Vec<u8>>>>()
            .ok_or_else(|| self.protocol("a frame that is not base64"))?;
        let expected = width as usize * height as usize * 4;
        if frames.len() != job.brackets.energies().len() || frames.iter().any(|f| f.len() != expected) {
            return Err(self.protocol(&format!(
                "expected {} frames of {width}×{height} RGBA8, got {} of {:?} bytes",
                job.brackets.energies().len(),
                frames.len(),
                frames.first().map(Vec::len)
            )));
        }
        let millis = |v: &Value| Duration::from_secs_f64(v.as_f64().unwrap_or(0.0).max(0.0) / 1000.0);
        let timing = Timing {
            wall: started.elapsed(),
            godot: millis(reply.get("godot_ms").unwrap_or(&Value::Null)),
            frames: reply
                .get("frame_ms")
                .and_then(Value::as_array)
                .map(|a| a.iter().map(millis).collect())
                .unwrap_or_default(),
        };
        Ok(RawRender { width, height, energies: job.brackets.energies().to_vec(), frames, log: outcome.log, timing })
    }

    fn protocol(&mut self, what: &str) -> OracleError {
        self.stop_after(OracleError::Protocol(what.to_string()))
    }

    /// Renders `job` in Godot and recovers linear radiance from its brackets.
    pub fn render(&mut self, job: &Job) -> Result<OracleImage, OracleError> {
        let raw = self.render_raw(job)?;
        let r = recover::recover(&self.transfer, raw.width, raw.height, &raw.energies, &raw.frames);
        Ok(OracleImage {
            width: raw.width,
            height: raw.height,
            pixels: r.pixels,
            valid: r.valid,
            lower: r.lower,
            upper: r.upper,
            inconsistent: r.inconsistent,
            log: raw.log,
            timing: raw.timing,
        })
    }

    /// Asks Godot whether it accepts `code` as a shader: sets it on the sky, draws two frames (so
    /// that the GL driver compiles it too) and reads the log.
    pub fn compile(&mut self, code: &str) -> Result<CompileOutcome, OracleError> {
        let message = json!({ "op": "compile", "code": code, "timeout_ms": COMPILE_TIMEOUT.as_millis() as u64 });
        let (reply, log) = self.exchange(message, COMPILE_TIMEOUT, "a compile job")?;
        Self::refusal(&reply)?;
        Ok(CompileOutcome::from_log(log))
    }
}

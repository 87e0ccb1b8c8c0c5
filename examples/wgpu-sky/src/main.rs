//! # wgpu-sky — a converted Godot sky behind a mesh, in a wgpu renderer of your own
//!
//! What an engine programmer copies: the shader converted in memory at start-up
//! (`gdsky::convert`, the converter alone), drawn by `skydraw` into the renderer's own HDR
//! target at the far plane behind a lit cube (reversed Z, as Bevy and many engines use), the
//! cube lit by the sky's own radiance cube map. `scene.rs` is the part that belongs in a
//! renderer; `window.rs` the winit shell (mouse look, sun drag, time); `headless.rs` the mode CI
//! and users check it with, which writes the frame as OpenEXR.
//!
//! The flags mean what `gdsky render --projection camera`'s mean, with the same defaults, so
//! `wgpu-sky --headless a.exr --no-mesh` and `gdsky render --projection camera -o b.exr` are the
//! same image.

mod headless;
mod scene;
mod window;

use clap::Parser;
use std::path::PathBuf;
use std::process::ExitCode;

/// A Godot sky shader behind a mesh in a wgpu renderer (skydraw). Without --headless, opens a
/// window: drag with the left mouse button to look around, with the right one to move the sun;
/// Space pauses TIME; Escape quits.
#[derive(Parser, Debug)]
#[command(name = "wgpu-sky", version)]
pub struct Args {
    /// Render without a window and write the last frame to OUT.exr (RGBA 32-bit float linear
    /// radiance, row 0 at the top) or OUT.png (an 8-bit preview tone mapped as `gdsky render`'s),
    /// then exit.
    #[arg(long, value_name = "OUT.exr|OUT.png")]
    pub headless: Option<PathBuf>,
    /// The sky shader (`.gdshader`); without one, gdsky's bundled Freeman sky.
    #[arg(long, value_name = "FILE")]
    pub shader: Option<PathBuf>,
    /// Give a sampler uniform a PNG (8-bit; sRGB-decoded when the uniform has `source_color`):
    /// `--texture noise_texture=shaders/sunfall_noise.png`. Repeatable.
    #[arg(long = "texture", value_name = "NAME=PATH")]
    pub textures: Vec<String>,
    /// Draw the sky alone, without the cube in front of it.
    #[arg(long)]
    pub no_mesh: bool,
    /// Image size WxH in pixels [default: 256x128 headless, as `gdsky render`; 1280x720 for
    /// the window].
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// The sun (LIGHT0): elevation and azimuth in degrees; azimuth 0 is toward −Z, 90 toward +X.
    #[arg(long, value_name = "ELEV,AZIM", default_value = "10,0", value_parser = parse_sun, allow_hyphen_values = true)]
    pub sun: (f64, f64),
    /// Camera yaw in degrees (rotation about +Y; 90 turns the view from −Z to −X).
    #[arg(long, value_name = "DEG", default_value = "0", allow_hyphen_values = true)]
    pub yaw: f64,
    /// Camera pitch in degrees, −90 to 90 (90 looks straight up).
    #[arg(long, value_name = "DEG", default_value = "0", allow_hyphen_values = true)]
    pub pitch: f64,
    /// Vertical field of view in degrees, more than 0 and less than 180.
    #[arg(long, value_name = "DEG", default_value = "90")]
    pub fov: f64,
    /// TIME of the first frame, in seconds.
    #[arg(long, value_name = "T", default_value = "0", allow_hyphen_values = true)]
    pub time: f32,
    /// Headless: frames to render, frame i at TIME + i/60 s; the image is the last one. Each
    /// frame's report (radiance faces rendered, how the sky was drawn) is printed.
    #[arg(long, value_name = "N", default_value = "1", value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub frames: u32,
}

fn main() -> ExitCode {
    let args = Args::parse();
    if let Err(message) = check(&args) {
        eprintln!("error: {message}");
        return ExitCode::from(1);
    }
    let result = match &args.headless {
        Some(out) => headless::run(&args, out),
        None => window::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {}", error.message);
            ExitCode::from(error.code)
        }
    }
}

/// Ranges the flags share with `gdsky render`.
fn check(args: &Args) -> Result<(), String> {
    if !(args.fov > 0.0 && args.fov < 180.0) {
        return Err(format!("--fov {}: expected more than 0 and less than 180 degrees", args.fov));
    }
    if !(-90.0..=90.0).contains(&args.pitch) || !(-360.0..=360.0).contains(&args.yaw) {
        return Err(format!("--yaw {} --pitch {}: expected −360 to 360 and −90 to 90", args.yaw, args.pitch));
    }
    if !args.time.is_finite() {
        return Err("--time: expected a finite number".into());
    }
    Ok(())
}

/// A failure and its exit status: 1 for wrong input, 2 for the environment (no adapter, a file
/// that cannot be read or written).
#[derive(Debug)]
pub struct Failure {
    pub message: String,
    pub code: u8,
}

impl Failure {
    pub fn input(message: impl std::fmt::Display) -> Self {
        Self { message: message.to_string(), code: 1 }
    }

    pub fn environment(message: impl std::fmt::Display) -> Self {
        Self { message: message.to_string(), code: 2 }
    }
}

fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(|| format!("`{text}`: expected WxH, e.g. 256x128"))?;
    let side = |s: &str| s.trim().parse::<u32>().ok().filter(|v| (1..=8192).contains(v));
    match (side(w), side(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!("`{text}`: each side must be 1 to 8192")),
    }
}

fn parse_sun(text: &str) -> Result<(f64, f64), String> {
    let (e, a) = text.split_once(',').ok_or_else(|| format!("`{text}`: expected ELEV,AZIM, e.g. 10,0"))?;
    match (e.trim().parse::<f64>(), a.trim().parse::<f64>()) {
        (Ok(e), Ok(a)) if (-90.0..=90.0).contains(&e) && (-360.0..=360.0).contains(&a) => Ok((e, a)),
        _ => Err(format!("`{text}`: elevation −90 to 90, azimuth −360 to 360 degrees")),
    }
}

//! What `render`, `reference` and `demo` share: the scene flags, loading a shader (or the
//! bundled Freeman sky), and writing images.

use clap::{Args, ValueEnum};
use gdsky::frontend::diag::render_human;
use skyref::{Projection, Scene};
use skyrun::Image;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The Freeman sky (seed 000, CC0), built into the binary so `gdsky render` and `gdsky demo`
/// work from any directory.
pub const BUNDLED_FREEMAN: &str = include_str!("../../fixtures/freeman_sky.gdshader");
/// The name diagnostics give the bundled shader.
pub const BUNDLED_NAME: &str = "freeman_sky.gdshader (bundled)";

/// How pixels map to view directions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ProjectionArg {
    /// Equirectangular, the inverse of SKY_COORDS: row 0 is the zenith, u = 0 looks toward −Z.
    Panorama,
    /// Godot's perspective camera: vertical --fov, --yaw and --pitch (Euler YXZ), looking toward
    /// −Z at yaw 0, pitch 0.
    Camera,
    /// Godot's radiance cubemap pass: six square faces (+X, −X, +Y, −Y, +Z, −Z) side by side
    /// in a 6N×N strip; --size gives one face (N×N).
    Cubemap,
}

/// The scene: image size, projection, sun and camera.
#[derive(Args, Clone, Debug)]
pub struct SceneArgs {
    /// How pixels map to view directions [default: panorama; `oracle`: camera, the only one it
    /// has].
    #[arg(long, value_enum)]
    pub projection: Option<ProjectionArg>,
    /// Image size WxH in pixels (a cubemap: the size of one face, which must be square).
    #[arg(long, value_name = "WxH", default_value = "256x128", value_parser = parse_size)]
    pub size: (u32, u32),
    /// The sun (LIGHT0): elevation and azimuth in degrees. Azimuth 0 is toward −Z, 90 toward +X.
    #[arg(long, value_name = "ELEV,AZIM", default_value = "10,0", value_parser = parse_pair, allow_hyphen_values = true)]
    pub sun: (f64, f64),
    /// Turn LIGHT0 off (LIGHT0_ENABLED = false).
    #[arg(long)]
    pub no_light: bool,
    /// Camera POSITION in metres (the Freeman sky uses the height .y, clamped to at least 0.5 m).
    #[arg(long, value_name = "X,Y,Z", default_value = "0,1,0", value_parser = parse_triple, allow_hyphen_values = true)]
    pub position: (f64, f64, f64),
    /// TIME in seconds.
    #[arg(long, value_name = "T", default_value_t = 0.0, allow_hyphen_values = true)]
    pub time: f32,
    /// Camera: vertical field of view in degrees.
    #[arg(long, value_name = "DEG", default_value_t = 90.0)]
    pub fov: f64,
    /// Camera: yaw in degrees (rotation about +Y; 90 turns the view from −Z to −X).
    #[arg(long, value_name = "DEG", default_value_t = 0.0, allow_hyphen_values = true)]
    pub yaw: f64,
    /// Camera: pitch in degrees (rotation about +X; 90 looks straight up).
    #[arg(long, value_name = "DEG", default_value_t = 0.0, allow_hyphen_values = true)]
    pub pitch: f64,
    /// Set a uniform for this render: `--set view_samples=16`, `--set ground_color=0.1,0.1,0.1`.
    /// Uniforms not set keep the shader's defaults.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
}

impl SceneArgs {
    /// The scene in skyref's terms.
    pub fn scene(&self) -> Scene {
        Scene {
            sun_elevation_deg: self.sun.0,
            sun_azimuth_deg: self.sun.1,
            light_enabled: !self.no_light,
            position: glam::DVec3::new(self.position.0, self.position.1, self.position.2),
            fov_deg: self.fov,
            yaw_deg: self.yaw,
            pitch_deg: self.pitch,
        }
    }

    /// The `--set` pairs, or a message naming the malformed one.
    pub fn overrides(&self) -> Result<Vec<(String, String)>, String> {
        self.set
            .iter()
            .map(|s| match s.split_once('=') {
                Some((name, value)) => Ok((name.trim().to_string(), value.trim().to_string())),
                None => Err(format!("`--set {s}`: expected NAME=VALUE")),
            })
            .collect()
    }

    /// The views to render: one projection, or the six cube faces; and the size of each.
    pub fn views(&self) -> Result<(Vec<Projection>, u32, u32), String> {
        let (w, h) = self.size;
        match self.projection.unwrap_or(ProjectionArg::Panorama) {
            ProjectionArg::Panorama => Ok((vec![Projection::Panorama], w, h)),
            ProjectionArg::Camera => {
                if !(self.fov > 0.0 && self.fov < 180.0) {
                    return Err(format!("--fov {} must be between 0 and 180 degrees", self.fov));
                }
                Ok((vec![Projection::Camera], w, h))
            }
            ProjectionArg::Cubemap if w == h => Ok(((0..6).map(Projection::CubeFace).collect(), w, h)),
            ProjectionArg::Cubemap => Err(format!("a cubemap face must be square, not {w}x{h}")),
        }
    }
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X', '×']).ok_or_else(|| format!("`{s}`: expected WxH, e.g. 256x128"))?;
    let side = |t: &str| match t.trim().parse::<u32>() {
        Ok(v) if (1..=16384).contains(&v) => Ok(v),
        _ => Err(format!("`{t}` is not a size between 1 and 16384")),
    };
    Ok((side(w)?, side(h)?))
}

fn numbers<const N: usize>(s: &str) -> Result<[f64; N], String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != N {
        return Err(format!("`{s}`: expected {N} comma-separated numbers"));
    }
    let mut out = [0.0; N];
    for (o, p) in out.iter_mut().zip(parts) {
        *o = p.trim().parse::<f64>().ok().filter(|v| v.is_finite()).ok_or_else(|| format!("`{p}` is not a number"))?;
    }
    Ok(out)
}

fn parse_pair(s: &str) -> Result<(f64, f64), String> {
    numbers::<2>(s).map(|[a, b]| (a, b))
}

fn parse_triple(s: &str) -> Result<(f64, f64, f64), String> {
    numbers::<3>(s).map(|[a, b, c]| (a, b, c))
}

/// A checked, lowered shader ready to render.
pub struct LoadedShader {
    /// The front end's output (the checked shader, its render modes and uniforms).
    pub front: gdsky::FrontendOutput,
    /// The validated naga module.
    pub lowered: gdsky_naga::Lowered,
    /// Its WGSL.
    pub wgsl: String,
}

impl LoadedShader {
    /// The shader compiled on `gpu`, with Godot's sub-passes and default textures. Exit 1 when
    /// the harness cannot bind it.
    pub fn compile(&self, gpu: &skyrun::Gpu) -> Result<skyrun::SkyShader, ExitCode> {
        let defaults =
            self.front.shader.as_ref().map(|s| skyrun::texture_defaults(s, &self.lowered)).unwrap_or_default();
        skyrun::SkyShader::new(gpu, &self.wgsl, skyrun::SubPasses::of(&self.front))
            .map(|shader| shader.with_texture_defaults(defaults))
            .map_err(|err| {
                eprintln!("error: {err}");
                ExitCode::from(1)
            })
    }
}

/// Checks and lowers `file`, or the bundled Freeman sky when there is none. Diagnostics are
/// printed; the error is the exit code (1 invalid, 2 unreadable).
pub fn load_shader(file: Option<&Path>) -> Result<LoadedShader, ExitCode> {
    let color = std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none();
    let front = match file {
        Some(path) => gdsky::check_file(path).map_err(|err| {
            eprintln!("error: cannot read {}: {err}", path.display());
            ExitCode::from(2)
        })?,
        None => {
            gdsky::check_source(BUNDLED_NAME, BUNDLED_FREEMAN.as_bytes().to_vec(), None, &mut gdsky::frontend::FsLoader)
        }
    };
    eprint!("{}", render_human(&front.db, &front.diagnostics, color));
    if front.shader.is_none() {
        return Err(ExitCode::from(1));
    }
    let lowered = gdsky_naga::lower(&front).map_err(|diags| {
        eprint!("{}", render_human(&front.db, &diags, color));
        ExitCode::from(1)
    })?;
    let wgsl = gdsky_naga::to_wgsl(&lowered).map_err(|err| {
        eprintln!("error[{}]: naga's WGSL writer failed: {err}", gdsky_naga::BACKEND);
        ExitCode::from(1)
    })?;
    Ok(LoadedShader { front, lowered, wgsl })
}

/// Opens the best Vulkan adapter and says which one, or explains why there is none (exit 2).
pub fn open_gpu() -> Result<skyrun::Gpu, ExitCode> {
    match skyrun::Gpu::new() {
        Ok(gpu) => {
            eprintln!("adapter: {}", gpu.adapter_info());
            Ok(gpu)
        }
        Err(err) => {
            eprintln!("error: {err}");
            Err(ExitCode::from(2))
        }
    }
}

/// Joins same-sized views left to right into one image (the cubemap strip).
pub fn strip(views: Vec<Vec<[f32; 4]>>, width: u32, height: u32) -> Result<Image, skyrun::ImageError> {
    let n = views.len();
    let (w, h) = (width as usize, height as usize);
    let mut pixels = vec![[0.0; 4]; n * w * h];
    for (i, view) in views.iter().enumerate() {
        for (y, row) in view.chunks_exact(w).enumerate() {
            let at = y * n * w + i * w;
            pixels[at..at + w].copy_from_slice(row);
        }
    }
    Image::new(width * n as u32, height, pixels)
}

/// Writes the EXR and, when asked, the PNG preview; says what it wrote. Exit 2 on failure.
pub fn write_outputs(image: &Image, exr: &Path, png: Option<&PathBuf>) -> Result<(), ExitCode> {
    let failed = |err: skyrun::ImageError| {
        eprintln!("error: {err}");
        ExitCode::from(2)
    };
    skyrun::write_exr(exr, image).map_err(failed)?;
    println!("wrote {} ({}x{} RGBA f32)", exr.display(), image.width, image.height);
    if let Some(png) = png {
        skyrun::write_png_preview(png, image, skyrun::DEFAULT_EXPOSURE, skyrun::DEFAULT_WHITE).map_err(failed)?;
        println!("wrote {}", png.display());
    }
    Ok(())
}

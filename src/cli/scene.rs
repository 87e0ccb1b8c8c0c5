//! The flags commands share: the scene (`SceneArgs`: what is rendered), what the sky may skip
//! (`SkipArgs`), Godot's look (`LoweringArgs`), and their value parsers; each turns into the
//! library's options ([`gdsky::engine::Setup`], [`skyrun::RenderOptions`],
//! [`gdsky_naga::LowerOptions`]).

use clap::{ArgMatches, Args};
use gdsky::engine::{Error, Setup};
use gdsky::scene::SceneFile;
use skycore::{Light, Projection, Scene, SkyResolution};
use skyrun::UpsampleFilter;
use std::path::PathBuf;

/// How the shader is lowered for Godot's look: its debanding and its SKY_COORDS.
#[derive(Args, Clone, Copy, Debug)]
pub struct LoweringArgs {
    /// Godot's sky debanding: `godot` (the default, as Godot 4.6) adds its dither to shaders
    /// that declare `render_mode use_debanding` (docs/godot.md, "Debanding"); `none` leaves
    /// COLOR as the shader writes it (for error measurement).
    #[arg(long, value_parser = super::named::<gdsky::Debanding>(&gdsky::Debanding::NAMES), default_value = "godot")]
    pub debanding: gdsky::Debanding,
    /// How SKY_COORDS is computed: `godot46` (the default), Godot 4.6's approximate
    /// trigonometry, which the oracle's Godot computes; `exact` as Godot 4.3–4.5 (docs/godot.md).
    #[arg(long, value_parser = super::named::<gdsky::SkyCoords>(&gdsky::SkyCoords::NAMES), default_value = "godot46")]
    pub sky_coords: gdsky::SkyCoords,
}

impl LoweringArgs {
    /// The lowering options these flags give.
    pub fn options(&self) -> gdsky_naga::LowerOptions {
        gdsky_naga::LowerOptions { debanding: self.debanding, sky_coords: self.sky_coords, ..Default::default() }
    }
}

/// The scene: image size, projection, sun and camera.
#[derive(Args, Clone, Debug)]
pub struct SceneArgs {
    /// How pixels map to view directions [default: panorama; `oracle`: camera, the only one it
    /// has]. `panorama`: equirectangular, the inverse of SKY_COORDS (row 0 is the zenith, u = 0
    /// looks toward −Z). `camera`: Godot's perspective camera (--fov, --yaw, --pitch; Euler YXZ,
    /// toward −Z at yaw 0, pitch 0). `cubemap`: Godot's radiance cubemap pass, six square faces
    /// (+X, −X, +Y, −Y, +Z, −Z) side by side in a 6N×N strip; --size gives one face (N×N).
    #[arg(long, value_parser = super::named::<Projection>(&Projection::NAMES))]
    pub projection: Option<Projection>,
    /// Image size WxH in pixels (a cubemap: the size of one face, which must be square). Each
    /// side 1 to 8192, at most 16,777,216 pixels (4096x4096, 8192x2048): the renderer's limits.
    #[arg(long, value_name = "WxH", default_value = "256x128", value_parser = parse_size)]
    pub size: (u32, u32),
    /// The sun (LIGHT0): elevation (−90 to 90) and azimuth (−360 to 360) in degrees. Azimuth 0
    /// is toward −Z, 90 toward +X.
    #[arg(long, value_name = "ELEV,AZIM", default_value = "10,0", value_parser = parse_sun, allow_hyphen_values = true)]
    pub sun: (f64, f64),
    /// Turn LIGHT0 off (LIGHT0_ENABLED = false).
    #[arg(long)]
    pub no_light: bool,
    /// The sun's LIGHT0_ENERGY, 0 to 1e6.
    #[arg(long, value_name = "E", default_value = "1", value_parser = parse_energy)]
    pub sun_energy: f32,
    /// The sun's LIGHT0_COLOR, linear R,G,B (each 0 to 1e6; not multiplied by the energy).
    #[arg(long, value_name = "R,G,B", default_value = "1,1,1", value_parser = parse_color)]
    pub sun_color: [f32; 3],
    /// The sun's angular diameter in degrees, 0 to 90 (Godot's `light_angular_distance`;
    /// LIGHT0_SIZE is its radians): skies that draw a sun disc from LIGHT0_SIZE show none at 0.
    /// The sun is about 0.5°.
    #[arg(long, value_name = "DEG", default_value = "0", value_parser = parse_angular_size)]
    pub sun_size: f64,
    /// Another light, LIGHT1 … LIGHT3 (or LIGHT0, replacing the sun flags):
    /// `N:KEY=VALUE:…` with keys `elevation`, `azimuth` (degrees, as --sun), `energy`, `color`
    /// (R,G,B), `size` (angular diameter, degrees) and `enabled` (true/false); e.g. `--light
    /// 1:elevation=40:azimuth=180:energy=0.2:color=0.6,0.7,1`. A light given is on unless
    /// `enabled=false`. Adds to a scene file's `[[lights]]` (the same index: this one).
    /// Repeatable.
    #[arg(long = "light", value_name = "N:KEY=VALUE:…", value_parser = parse_light)]
    pub lights: Vec<(usize, Light)>,
    /// Camera POSITION in metres, each coordinate finite in f32 (the Freeman sky uses the height
    /// .y, clamped to at least 0.5 m).
    #[arg(long, value_name = "X,Y,Z", default_value = "0,1,0", value_parser = parse_position, allow_hyphen_values = true)]
    pub position: (f64, f64, f64),
    /// TIME in seconds, finite in f32.
    #[arg(long, value_name = "T", default_value = "0", value_parser = parse_time, allow_hyphen_values = true)]
    pub time: f32,
    /// Camera: vertical field of view in degrees, more than 0 and less than 180.
    #[arg(long, value_name = "DEG", default_value = "90", value_parser = parse_fov, allow_hyphen_values = true)]
    pub fov: f64,
    /// Camera: yaw in degrees, −360 to 360 (rotation about +Y; 90 turns the view from −Z to −X).
    #[arg(long, value_name = "DEG", default_value = "0", value_parser = parse_yaw, allow_hyphen_values = true)]
    pub yaw: f64,
    /// Camera: pitch in degrees, −90 to 90 (rotation about +X; 90 looks straight up).
    #[arg(long, value_name = "DEG", default_value = "0", value_parser = parse_pitch, allow_hyphen_values = true)]
    pub pitch: f64,
    /// Set a uniform for this render: `--set view_samples=16`, `--set ground_color=0.1,0.1,0.1`.
    /// Uniforms not set keep the shader's defaults.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// Give a sampler uniform a texture: `--texture noise=noise.png`, `--texture table=lut.exr`
    /// (element i of a sampler array: `NAME_i`). OpenEXR is read as 32-bit floats (bind it to a
    /// texture the shader reads with texelFetch; sampling needs a filterable format), PNG as
    /// 8-bit, sRGB-decoded when the uniform has `source_color`. Each side at most 8192.
    /// A samplerCube takes six faces `px,nx,py,ny,pz,nz` (comma-separated, in that order: +X,
    /// −X, +Y, −Y, +Z, −Z) or one image: a horizontal (4:3) or vertical (3:4) cross, or Godot's
    /// 6x1, 3x2, 2x3 or 1x6 face grid, told by its aspect. A sampler3D takes slice files
    /// front to back, or one image of slices in a grid read row by row: `PATH@COLUMNSxROWS`,
    /// else the grid of its Godot import file (`PATH.import`), else 8x8 (Godot's default). A `filter_*_mipmap*` hint generates mipmaps (Godot's box
    /// filter). Adds to a scene file's `[textures]` (a name given in both: this one).
    /// Repeatable.
    #[arg(long = "texture", value_name = "NAME=PATH")]
    pub texture: Vec<String>,
}

impl SceneArgs {
    /// What to render: the scene (camera, every light, time), projection, size, the `--set`
    /// values and the `--texture`s, after [`SceneArgs::merge_file`]. Wrong input when a `--set`
    /// is not `NAME=VALUE`.
    pub fn setup(&self) -> Result<Setup, Error> {
        let mut scene = Scene::default()
            .with_sun(self.sun.0, self.sun.1)
            .with_sun_enabled(!self.no_light)
            .with_position(glam::DVec3::new(self.position.0, self.position.1, self.position.2))
            .with_fov(self.fov)
            .with_view(self.yaw, self.pitch)
            .with_time(f64::from(self.time));
        let sun = scene.sun_mut();
        (sun.energy, sun.color, sun.angular_diameter_deg) = (self.sun_energy, self.sun_color, self.sun_size);
        for (index, light) in &self.lights {
            scene.lights[*index] = *light;
        }
        let sets = self
            .set
            .iter()
            .map(|s| match s.split_once('=') {
                Some((name, value)) => Ok((name.trim().to_string(), value.trim().to_string())),
                None => Err(Error::input(format!("`--set {s}`: expected NAME=VALUE"))),
            })
            .collect::<Result<_, _>>()?;
        Ok(Setup {
            scene,
            projection: self.projection.unwrap_or_default(),
            width: self.size.0,
            height: self.size.1,
            sets,
            textures: self.texture.clone(),
        })
    }

    /// Fills every scene flag not given on the command line from the scene file `file`; flags
    /// given override it. `matches` are the subcommand's (clap's value source tells a flag given
    /// from a default). The scene's uniforms come first in `--set`, so a `--set` of the same
    /// uniform wins; its lights first in `--light`, so a `--light` of the same index wins.
    pub fn merge_file(&mut self, file: &SceneFile, matches: &ArgMatches) {
        let given = |id: &str| given(matches, id);
        if !given("projection") && file.projection.is_some() {
            self.projection = file.projection;
        }
        if !given("size") {
            self.size = file.size.unwrap_or(self.size);
        }
        if !given("sun") {
            self.sun = (file.sun_elevation.unwrap_or(self.sun.0), file.sun_azimuth.unwrap_or(self.sun.1));
        }
        if !given("no_light") {
            self.no_light = file.sun_enabled.map_or(self.no_light, |on| !on);
        }
        if !given("sun_energy") {
            self.sun_energy = file.sun_energy.unwrap_or(self.sun_energy);
        }
        if !given("sun_color") {
            self.sun_color = file.sun_color.unwrap_or(self.sun_color);
        }
        if !given("sun_size") {
            self.sun_size = file.sun_size.unwrap_or(self.sun_size);
        }
        let mut lights: Vec<(usize, Light)> = file.lights.iter().enumerate().map(|(i, l)| (i + 1, *l)).collect();
        lights.append(&mut self.lights);
        self.lights = lights;
        if !given("position") {
            self.position = file.position.map_or(self.position, |[x, y, z]| (x, y, z));
        }
        if !given("time") {
            self.time = file.time.unwrap_or(self.time);
        }
        if !given("fov") {
            self.fov = file.fov.unwrap_or(self.fov);
        }
        if !given("yaw") {
            self.yaw = file.yaw.unwrap_or(self.yaw);
        }
        if !given("pitch") {
            self.pitch = file.pitch.unwrap_or(self.pitch);
        }
        let mut set: Vec<String> = file.uniform_pairs().into_iter().map(|(n, v)| format!("{n}={v}")).collect();
        set.append(&mut self.set);
        self.set = set;
    }
}

// The ranges and the number check are the library's, shared with scene files.
pub use gdsky::scene::{
    ANGULAR_SIZE, COLOR, ENERGY, F32_LIMIT, FOV, PITCH, POSITION, Range, SUN_ELEVATION, TIME, TURN, parse_number,
};

/// Splits `N` comma-separated components.
fn components<'a, const N: usize>(s: &'a str, names: &str) -> Result<[&'a str; N], String> {
    let parts: Vec<&str> = s.split(',').collect();
    parts.try_into().map_err(|_| format!("`{s}`: expected {N} comma-separated numbers ({names})"))
}

/// `--size WxH`: each side and the pixel count within the renderer's limits
/// ([`skyrun::check_render_size`]).
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let max = skyrun::MAX_RENDER_SIDE;
    let (w, h) = s.split_once(['x', 'X', '×']).ok_or_else(|| format!("`{s}`: expected WxH, e.g. 256x128"))?;
    let side = |t: &str| match t.trim().parse::<u32>() {
        Ok(v) if (1..=max).contains(&v) => Ok(v),
        _ => Err(format!("`{}` is not a size between 1 and {max} pixels", t.trim())),
    };
    let (w, h) = (side(w)?, side(h)?);
    skyrun::check_render_size(w, h)?;
    Ok((w, h))
}

/// What the sky may skip (issue #11): pixels behind geometry and resolution it does not need.
#[derive(Args, Clone, Debug, Default)]
pub struct SkipArgs {
    /// A mask of the geometry in front of the sky: a PNG, white = covered (grey ≥ ½ and, with
    /// alpha, alpha ≥ ½), scaled to --size with nearest-neighbour sampling. It is drawn into
    /// the depth buffer first, so covered pixels are never shaded; they hold (0, 0, 0, 1).
    /// Not with --projection cubemap (Godot's radiance pass has no geometry in front).
    #[arg(long, value_name = "MASK.png")]
    pub occluder: Option<PathBuf>,
    /// Shade the sky at full, half (W/2×H/2) or quarter (W/4×H/4) resolution, Godot's own
    /// sub-passes scaled with it, and upsample to --size on the GPU.
    #[arg(long, value_parser = super::named::<SkyResolution>(&SkyResolution::NAMES), default_value = "full")]
    pub sky_resolution: SkyResolution,
    /// The upsampling filter of a reduced --sky-resolution: bilinear (2×2 texels; cheapest,
    /// blurs the sun disk's edge most) or catmull-rom (bicubic over 4×4 texels, clamped to the
    /// 2×2 neighbours' range: sharper).
    #[arg(long, value_parser = super::named::<UpsampleFilter>(&UpsampleFilter::NAMES), default_value = "bilinear")]
    pub upsample: UpsampleFilter,
}

impl SkipArgs {
    /// Takes the scene file's `occluder` and `sky_resolution` where `--occluder` and
    /// `--sky-resolution` were not given on the command line.
    pub fn merge_file(&mut self, file: &SceneFile, matches: &ArgMatches) {
        if !given(matches, "occluder") && file.occluder.is_some() {
            self.occluder = file.occluder.clone();
        }
        if !given(matches, "sky_resolution")
            && let Some(r) = file.sky_resolution
        {
            self.sky_resolution = r;
        }
    }

    /// Reads the occluder mask for `views` of `width`×`height` (before any GPU work): a wrong
    /// environment when the file cannot be read (missing, not a regular file, over
    /// [`skyrun::MAX_MASK_BYTES`]), wrong input when it is not a PNG or the projection is a
    /// cubemap.
    pub fn occluder(&self, views: &[Projection], width: u32, height: u32) -> Result<Option<skyrun::Occluder>, Error> {
        let Some(path) = &self.occluder else {
            return Ok(None);
        };
        if views.iter().any(|v| matches!(v, Projection::CubeFace(_))) {
            return Err(Error::input(
                "--occluder does not apply to --projection cubemap (Godot's radiance pass draws no geometry in front of the sky)",
            ));
        }
        skyrun::Occluder::from_png(path, width, height)
            .map(Some)
            .map_err(|err| if err.is_read() { Error::environment(err) } else { Error::input(err) })
    }
}

/// `--sun ELEV,AZIM`.
pub fn parse_sun(s: &str) -> Result<(f64, f64), String> {
    let [e, a] = components::<2>(s, "elevation, azimuth")?;
    Ok((parse_number(e, "the elevation", &SUN_ELEVATION)?, parse_number(a, "the azimuth", &TURN)?))
}

/// `--sun-energy E`.
pub fn parse_energy(s: &str) -> Result<f32, String> {
    parse_number(s, "", &ENERGY).map(|e| e as f32)
}

/// `--sun-color R,G,B`.
pub fn parse_color(s: &str) -> Result<[f32; 3], String> {
    let [r, g, b] = components::<3>(s, "R, G, B")?;
    let c = |t, what| parse_number(t, what, &COLOR).map(|v| v as f32);
    Ok([c(r, "R")?, c(g, "G")?, c(b, "B")?])
}

/// `--sun-size DEG`.
pub fn parse_angular_size(s: &str) -> Result<f64, String> {
    parse_number(s, "", &ANGULAR_SIZE)
}

/// `--light N:KEY=VALUE:…` (see [`SceneArgs::lights`]).
pub fn parse_light(s: &str) -> Result<(usize, Light), String> {
    let mut parts = s.split(':');
    let index = match parts.next().map(str::trim).and_then(|n| n.parse::<usize>().ok()) {
        Some(n) if n < skycore::MAX_LIGHTS => n,
        _ => return Err(format!("`{s}`: expected N:KEY=VALUE:…, N the light's index, 0 to 3")),
    };
    let mut light = Light { enabled: true, ..Light::OFF };
    light.energy = 1.0;
    light.color = [1.0; 3];
    for part in parts {
        let (key, value) = part.split_once('=').ok_or_else(|| format!("`{s}`: `{part}` is not KEY=VALUE"))?;
        match key.trim() {
            "elevation" => light.elevation_deg = parse_number(value, "the elevation", &SUN_ELEVATION)?,
            "azimuth" => light.azimuth_deg = parse_number(value, "the azimuth", &TURN)?,
            "energy" => light.energy = parse_energy(value)?,
            "color" => light.color = parse_color(value)?,
            "size" => light.angular_diameter_deg = parse_angular_size(value)?,
            "enabled" => {
                light.enabled = value.trim().parse().map_err(|_| format!("`{s}`: enabled is `true` or `false`"))?
            }
            other => {
                return Err(format!(
                    "`{s}`: `{other}` is no key of a light; the keys are elevation, azimuth, energy, color, size, enabled"
                ));
            }
        }
    }
    Ok((index, light))
}

/// `--position X,Y,Z`.
pub fn parse_position(s: &str) -> Result<(f64, f64, f64), String> {
    let [x, y, z] = components::<3>(s, "X, Y, Z")?;
    Ok((parse_number(x, "X", &POSITION)?, parse_number(y, "Y", &POSITION)?, parse_number(z, "Z", &POSITION)?))
}

/// `--time T`.
pub fn parse_time(s: &str) -> Result<f32, String> {
    parse_number(s, "", &TIME).map(|t| t as f32)
}

/// `--fov DEG`.
pub fn parse_fov(s: &str) -> Result<f64, String> {
    parse_number(s, "", &FOV)
}

/// `--yaw DEG`.
pub fn parse_yaw(s: &str) -> Result<f64, String> {
    parse_number(s, "", &TURN)
}

/// `--pitch DEG`.
pub fn parse_pitch(s: &str) -> Result<f64, String> {
    parse_number(s, "", &PITCH)
}

/// Whether the flag `id` was given on the command line (not a default, not absent).
pub fn given(matches: &ArgMatches, id: &str) -> bool {
    matches.try_contains_id(id).unwrap_or(false)
        && matches.value_source(id) == Some(clap::parser::ValueSource::CommandLine)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn f32_limit_is_where_rounding_overflows() {
        assert!((F32_LIMIT as f32).is_infinite());
        assert_eq!(f64::from_bits(F32_LIMIT.to_bits() - 1) as f32, f32::MAX);
        assert_eq!(parse_time("3.4028235e38"), Ok(f32::MAX));
        assert_eq!(parse_time("-3.4028235e38"), Ok(f32::MIN));
        for bad in ["3.4028236e38", "1e39", "nan", "-inf", "infinity", "1e400", "ten", ""] {
            assert!(parse_time(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn ranges_are_closed_or_open_as_documented() {
        assert!(parse_fov("180").is_err() && parse_fov("0").is_err() && parse_fov("179.9").is_ok());
        assert!(parse_pitch("90").is_ok() && parse_pitch("-90").is_ok() && parse_pitch("90.001").is_err());
        assert!(parse_yaw("-360").is_ok() && parse_yaw("360.5").is_err());
        assert_eq!(parse_sun(" 10 , -30 "), Ok((10.0, -30.0)));
        assert!(parse_sun("10").unwrap_err().contains("expected 2 comma-separated numbers"));
        let err = parse_sun("95,0").unwrap_err();
        assert!(err.contains("(the elevation) is out of range; accepted: −90 to 90 degrees"), "{err}");
        assert!(parse_position("0,1,0").is_ok() && parse_position("0,1e39,0").is_err());
        assert_eq!(parse_size("8192x2048"), Ok((8192, 2048)));
        assert!(parse_size("8192x2049").is_err() && parse_size("0x4").is_err() && parse_size("16384x1").is_err());
    }
}

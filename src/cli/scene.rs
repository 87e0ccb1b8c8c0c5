//! What `render`, `reference` and `demo` share: the scene flags, loading a shader (or the
//! bundled Freeman sky), and writing images.

use clap::{ArgMatches, Args};
use gdsky::frontend::diag::render_human;
use gdsky::scene::{SceneError, SceneFile};
use skycore::{Projection, Scene, SkyResolution};
use skyrun::Image;
use skyrun::UpsampleFilter;
use std::collections::HashMap;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The Freeman sky (seed 000, CC0), built into the binary so `gdsky render` and `gdsky demo`
/// work from any directory.
pub const BUNDLED_FREEMAN: &str = include_str!("../../fixtures/freeman_sky.gdshader");
/// The name diagnostics give the bundled shader.
pub const BUNDLED_NAME: &str = "freeman_sky.gdshader (bundled)";

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
    /// The scene in skyref's terms.
    pub fn scene(&self) -> Scene {
        Scene::default()
            .with_sun(self.sun.0, self.sun.1)
            .with_sun_enabled(!self.no_light)
            .with_position(glam::DVec3::new(self.position.0, self.position.1, self.position.2))
            .with_fov(self.fov)
            .with_view(self.yaw, self.pitch)
            .with_time(f64::from(self.time))
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

    /// The textures to read, by sampler uniform: the scene file's `[textures]` (paths relative
    /// to it), then each `--texture NAME=PATH` (a later one of a name replaces an earlier one).
    /// Checked against `loaded`'s material textures and read, before any GPU work. Exit 1 when a
    /// name is not a sampler uniform of the shader (located in the scene file when it comes from
    /// there), a `--texture` is not NAME=PATH, or a file is not an image that fits; 2 when a file
    /// cannot be read (missing, not a regular file, too large), as for every input file.
    pub fn textures(
        &self,
        scene: Option<&SceneFile>,
        loaded: &LoadedShader,
    ) -> Result<Vec<(String, skyrun::TextureData)>, ExitCode> {
        load_textures(&self.texture, scene, loaded)
    }

    /// Fills every scene flag not given on the command line from the scene file `file`; flags
    /// given override it. `matches` are the subcommand's (clap's value source tells a flag given
    /// from a default). The scene's uniforms come first in `--set`, so a `--set` of the same
    /// uniform wins.
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

    /// The built-ins of this scene for a `width`×`height` view: [`SkyBuiltins::from_scene`],
    /// TIME, and from a scene file the sun's energy and colour and LIGHT1 … LIGHT3.
    pub fn builtins(&self, file: Option<&SceneFile>, width: u32, height: u32) -> skyrun::SkyBuiltins {
        let mut scene = self.scene();
        if let Some(file) = file {
            scene.sun_mut().energy = file.sun_energy.unwrap_or(1.0);
            scene.sun_mut().color = file.sun_color.unwrap_or([1.0; 3]);
            for (slot, light) in scene.lights[1..].iter_mut().zip(&file.lights) {
                *slot = skycore::Light {
                    enabled: light.enabled,
                    elevation_deg: light.elevation,
                    azimuth_deg: light.azimuth,
                    energy: light.energy,
                    color: light.color,
                    angular_diameter_deg: 0.0,
                };
            }
        }
        skyrun::SkyBuiltins::from_scene(&scene, width, height)
    }

    /// The views to render: one projection, or the six cube faces; and the size of each.
    pub fn views(&self) -> Result<(Vec<Projection>, u32, u32), String> {
        let (w, h) = self.size;
        match self.projection.unwrap_or_default() {
            Projection::CubeFace(_) if w != h => Err(format!("a cubemap face must be square, not {w}x{h}")),
            projection => Ok((projection.views(), w, h)),
        }
    }
}

// The ranges and the number check are the library's, shared with scene files.
pub use gdsky::scene::{F32_LIMIT, FOV, PITCH, POSITION, Range, SUN_ELEVATION, TIME, TURN, parse_number};

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

    /// Reads the occluder mask for `views` of `width`×`height` (before any GPU work). Exit 2
    /// when the file cannot be read (missing, not a regular file, over
    /// [`skyrun::MAX_MASK_BYTES`]), 1 when it is not a PNG or the projection is a cubemap.
    pub fn occluder(
        &self,
        views: &[Projection],
        width: u32,
        height: u32,
    ) -> Result<Option<skyrun::Occluder>, ExitCode> {
        let Some(path) = &self.occluder else {
            return Ok(None);
        };
        if views.iter().any(|v| matches!(v, Projection::CubeFace(_))) {
            return Err(super::usage(
                "--occluder does not apply to --projection cubemap (Godot's radiance pass draws no geometry in front of the sky)",
            ));
        }
        skyrun::Occluder::from_png(path, width, height).map(Some).map_err(|err| {
            eprintln!("error: {err}");
            ExitCode::from(if err.is_read() { 2 } else { 1 })
        })
    }

    /// The render options with `occluder` (from [`SkipArgs::occluder`]).
    pub fn options<'a>(&self, occluder: Option<&'a skyrun::Occluder>) -> skyrun::RenderOptions<'a> {
        skyrun::RenderOptions { occluder, resolution: self.sky_resolution.into(), filter: self.upsample.into() }
    }
}

/// `--sun ELEV,AZIM`.
pub fn parse_sun(s: &str) -> Result<(f64, f64), String> {
    let [e, a] = components::<2>(s, "elevation, azimuth")?;
    Ok((parse_number(e, "the elevation", &SUN_ELEVATION)?, parse_number(a, "the azimuth", &TURN)?))
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

/// Checks the `--set NAME=VALUE` pairs given for the Freeman sky's parameters (`reference`,
/// `bench`) with the value parser `render` and `convert` use
/// ([`gdshader::values::parse_value`]: finite numbers within their type's range), then applies
/// them to `params`.
pub fn set_freeman(params: &mut skyref::FreemanParams, overrides: &[(String, String)]) -> Result<(), String> {
    use gdsky::frontend::check::types::{Scalar, Type};
    use skyref::UniformMut;
    for (name, text) in overrides {
        let ty = params.uniforms_mut().into_iter().find(|(n, _)| n == name).map(|(_, u)| match u {
            UniformMut::Float(_) => Type::Scalar(Scalar::Float),
            UniformMut::Int(_) => Type::Scalar(Scalar::Int),
            UniformMut::Vec3(_) => Type::Vector(Scalar::Float, 3),
        });
        let Some(ty) = ty else {
            return Err(format!("`--set {name}={text}`: the Freeman sky has no uniform `{name}`"));
        };
        gdshader::values::parse_value(&ty, text).map_err(|why| format!("`--set {name}={text}`: {why}"))?;
        params.set(name, text).map_err(|why| format!("`--set {name}={text}`: {why}"))?;
    }
    Ok(())
}

/// The sampler uniform of a baked transmittance table ([`LoadedShader::bake_tables`]).
pub const TRANSMITTANCE_TABLE: &str = "transmittance_table";

/// A checked, lowered shader ready to render.
pub struct LoadedShader {
    /// The front end's output (the checked shader, its render modes and uniforms).
    pub front: gdsky::FrontendOutput,
    /// The validated naga module.
    pub lowered: gdsky_naga::Lowered,
    /// Its WGSL.
    pub wgsl: String,
    /// Textures for sampler uniforms ([`SceneArgs::textures`]), bound by
    /// [`LoadedShader::compile`].
    pub textures: Vec<(String, skyrun::TextureData)>,
}

impl LoadedShader {
    /// The material block: the uniforms' defaults with `overrides` over them; overrides of
    /// baked uniforms (already constants) are left out.
    pub fn material(&self, overrides: &[(String, String)]) -> Result<Vec<u8>, skyrun::MaterialError> {
        let shader = self.front.shader.as_ref().ok_or(skyrun::MaterialError::NoSuchUniform(String::new()))?;
        // Uniforms that are overrides travel as pipeline constants ([`LoadedShader::constants`]),
        // not in the block.
        let kept: Vec<(String, String)> = overrides
            .iter()
            .filter(|(n, _)| !self.baked().contains_key(n) && !self.overrides().contains(n))
            .cloned()
            .collect();
        skyrun::material_with_defaults(shader, &self.lowered, &kept)
    }

    /// The pipeline constants of the overrides (`@id` as text → value) from `--set`-style pairs
    /// (the last pair of a name counts), each override not set at the uniform's default, so
    /// every override is listed. A value is checked as `--set` checks it.
    pub fn constants(&self, sets: &[(String, String)]) -> Result<Vec<(String, f64)>, String> {
        let Some(shader) = self.front.shader.as_ref() else {
            return Ok(Vec::new());
        };
        let mut constants = Vec::with_capacity(self.overrides().len());
        for (id, name) in self.overrides().iter().enumerate() {
            let Some(u) = shader.uniforms.iter().find(|u| u.name == *name) else {
                return Err(format!("the shader has no uniform `{name}` to override"));
            };
            let value = match sets.iter().rev().find(|(n, _)| n == name) {
                Some((_, text)) => {
                    gdshader::values::parse_value(&u.ty, text).map_err(|why| format!("`--set {name}={text}`: {why}"))?
                }
                None => u.default.clone().unwrap_or(gdsky::frontend::check::consteval::ConstValue::Int(0)),
            };
            constants.push((id.to_string(), constant_value(&value)));
        }
        Ok(constants)
    }

    /// Binds a baked transmittance table when the shader declares [`TRANSMITTANCE_TABLE`] (as
    /// `shaders/freeman_lut.gdshader` does) and no texture was given for it: the table is baked
    /// ([`skyref::lut::bake`], 256×64, ~0.1 s) from the material's own values — the shader's
    /// defaults, then `values` (`--set`, the scene's uniforms), then the baked constants — so
    /// it always matches the layers the shader is rendered with. Returns the note to print, or
    /// `None` when nothing was baked. An error when a value that shapes the table is not a
    /// number (the material check reports it first in practice).
    pub fn bake_tables(&mut self, values: &[(String, String)]) -> Result<Option<String>, String> {
        let Some(shader) = self.front.shader.as_ref() else { return Ok(None) };
        let declared = shader.texture_names().iter().any(|n| n == TRANSMITTANCE_TABLE);
        if !declared || self.textures.iter().any(|(n, _)| n == TRANSMITTANCE_TABLE) {
            return Ok(None);
        }
        let mut params = skyref::FreemanParams::default();
        let known: Vec<&'static str> = params.uniforms_mut().iter().map(|(n, _)| *n).collect();
        let defaults = gdshader::values::defaults_as_set(shader);
        let mut settings: Vec<(&String, &String)> = defaults.iter().collect();
        settings.sort();
        settings.extend(values.iter().map(|(n, v)| (n, v)));
        settings.extend(self.baked().iter());
        for (name, value) in settings {
            if known.contains(&name.as_str()) {
                params.set(name, value)?;
            }
        }
        let (width, height) = skyref::lut::DEFAULT_SIZE;
        let started = std::time::Instant::now();
        let table = skyref::lut::bake(&params, width, height);
        let image = skyrun::Image { width: table.width, height: table.height, pixels: table.texels };
        let data = skyrun::texture_from_image(&image).map_err(|e| e.to_string())?;
        self.textures.push((TRANSMITTANCE_TABLE.to_string(), data));
        Ok(Some(format!(
            "{TRANSMITTANCE_TABLE}: baked {width}x{height} from the material in {:.2?} (give --texture {TRANSMITTANCE_TABLE}=TABLE.exr to use another)",
            started.elapsed()
        )))
    }

    /// The shader compiled on `gpu`, with Godot's sub-passes, default textures, samplers from
    /// the uniforms' hints and [`LoadedShader::textures`] bound. Exit 1 when the harness cannot
    /// bind it or a texture does not fit its binding.
    pub fn compile(&self, gpu: &skyrun::Gpu) -> Result<skyrun::SkyShader, ExitCode> {
        self.compile_wgsl(gpu, &self.wgsl)
    }

    /// [`LoadedShader::compile`] with other WGSL of the same shader and bindings (the
    /// instrumented module of `render --trace-nonfinite`).
    pub fn compile_wgsl(&self, gpu: &skyrun::Gpu, wgsl: &str) -> Result<skyrun::SkyShader, ExitCode> {
        let failed = |err: &dyn std::fmt::Display| {
            eprintln!("error: {err}");
            ExitCode::from(1)
        };
        let (defaults, bindings) = match self.front.shader.as_ref() {
            Some(s) => {
                (skyrun::texture_defaults(s, &self.lowered), gdsky_naga::reflect::texture_bindings(s, &self.lowered))
            }
            None => Default::default(),
        };
        let mut shader = skyrun::SkyShader::new(gpu, wgsl, skyrun::SubPasses::of(&self.front))
            .map_err(|err| failed(&err))?
            .with_texture_defaults(defaults)
            .with_material_textures(gpu, bindings);
        for (name, data) in &self.textures {
            shader.set_texture(gpu, name, data).map_err(|err| failed(&err))?;
        }
        Ok(shader)
    }
}

/// A texture a Godot material generates.
enum Generated<'a> {
    /// A `NoiseTexture2D`.
    Plane(&'a gdresource::generated::NoiseTexture2D),
    /// A `NoiseTexture3D`.
    Volume(&'a gdresource::generated::NoiseTexture3D),
    /// A `GradientTexture1D`, `GradientTexture2D` or `CurveTexture`.
    Ramp(&'a gdresource::generated::RampTexture),
}

/// The texture shape a sampler uniform takes: a cube map for `samplerCube`, a 3D texture for
/// `sampler3D`, else one image (arrays and the rest are refused when bound).
fn texture_shape(shader: &gdsky::CheckedShader, uniform: &str) -> skyrun::TextureShape {
    use gdshader::check::types::{SamplerKind, Type};
    let ty = shader.uniforms.iter().find(|u| u.name == uniform).map(|u| &u.ty);
    let kind = match ty {
        Some(Type::Sampler(kind, _)) => Some(*kind),
        Some(Type::Array(element, _)) => match **element {
            Type::Sampler(kind, _) => Some(kind),
            _ => None,
        },
        _ => None,
    };
    match kind {
        Some(SamplerKind::Cube) => skyrun::TextureShape::Cube,
        Some(SamplerKind::Tex3D) => skyrun::TextureShape::D3,
        _ => skyrun::TextureShape::D2,
    }
}

/// The files of a texture value: the path itself when it names a file, else its
/// comma-separated parts (`px.png,nx.png,…`), each after the first resolved against `base` (the
/// scene file's folder, which the first part already carries) when the value came from a scene
/// file.
fn texture_files(path: &Path, base: Option<&Path>) -> Vec<PathBuf> {
    let text = path.to_string_lossy();
    if path.is_file() || !text.contains(',') {
        return vec![path.to_path_buf()];
    }
    text.split(',')
        .map(str::trim)
        .enumerate()
        .map(|(i, part)| match base {
            Some(base) if i > 0 => base.join(part),
            _ => PathBuf::from(part),
        })
        .collect()
}

/// Splits a `PATH@COLUMNSxROWS` grid suffix off a 3D texture's single image (unless the whole
/// text names a file), leaving the path in `path`. `None`: no suffix (Godot's 8×8 grid).
fn split_grid(path: &mut PathBuf) -> Result<Option<(u32, u32)>, String> {
    let text = path.to_string_lossy().into_owned();
    if path.is_file() {
        return Ok(None);
    }
    let Some((file, grid)) = text.rsplit_once('@') else { return Ok(None) };
    let parsed = grid
        .split_once(['x', 'X'])
        .and_then(|(c, r)| Some((c.trim().parse::<u32>().ok()?, r.trim().parse::<u32>().ok()?)))
        .filter(|&(c, r)| (1..=256).contains(&c) && (1..=256).contains(&r));
    let Some(grid) = parsed else {
        return Err(format!(
            "`{text}`: `@{grid}` is not a slice grid; write PATH@COLUMNSxROWS, each 1 to 256 (as Godot's \
             slices/horizontal and slices/vertical)"
        ));
    };
    *path = PathBuf::from(file);
    Ok(Some(grid))
}

/// The slice grid Godot's Texture3D import gives `image` (`slices/horizontal`,
/// `slices/vertical` in the `[params]` of `image.import`, beside it), or `None` when there is
/// no such file or it gives no grid (Godot's default 8×8 then applies). Read like every input:
/// a regular file of at most 1 MiB; a file that cannot be read counts as absent.
fn import_grid(image: &Path) -> Option<(u32, u32)> {
    let mut name = image.as_os_str().to_owned();
    name.push(".import");
    let bytes = skycore::io::read_limited(Path::new(&name), 1 << 20).ok()?;
    let text = String::from_utf8_lossy(&bytes);
    let value = |key: &str| {
        text.lines()
            .filter_map(|l| l.split_once('='))
            .find(|(k, _)| k.trim() == key)
            .and_then(|(_, v)| v.trim().parse::<u32>().ok())
            .filter(|v| (1..=256).contains(v))
    };
    match (value("slices/horizontal"), value("slices/vertical")) {
        (None, None) => None,
        (h, v) => Some((h.unwrap_or(8), v.unwrap_or(8))),
    }
}

/// A scalar constant as a pipeline constant: wgpu takes every override's value as an f64 and
/// converts it to the override's type, exactly for every f32, i32 and u32 (an f32 parsed from
/// `--set` is first rounded to f32, as the material block would hold it, so the override and
/// the generic module see the same bits). A bool is 0 or 1 (its override is a u32).
pub fn constant_value(v: &gdsky::frontend::check::consteval::ConstValue) -> f64 {
    use gdsky::frontend::check::consteval::ConstValue;
    match v {
        ConstValue::Float(f) => f64::from(*f as f32),
        ConstValue::Int(i) => *i as f64,
        ConstValue::UInt(u) => *u as f64,
        ConstValue::Bool(b) => f64::from(u8::from(*b)),
        ConstValue::Composite(_) => 0.0,
    }
}

/// The uniforms to emit as overrides: the scene file's `overrides`, then each `--override` not
/// already listed (the flags add to the file).
pub fn override_names(scene: Option<&SceneFile>, flags: &[String]) -> Vec<String> {
    let mut names = scene.map(SceneFile::override_names).unwrap_or_default();
    for f in flags {
        if !names.contains(f) {
            names.push(f.clone());
        }
    }
    names
}

/// Why `name` is baked on purpose: under `--bake-scene`, a `--set` of it or the scene file's
/// `[uniforms]` fixing it. `None` when it is not (baking "every uniform at its default", without
/// a scene file, leaves overrides alone).
pub fn bake_reason(
    name: &str,
    scene: Option<&SceneFile>,
    cli_sets: &[(String, String)],
    bake_scene: bool,
) -> Option<String> {
    if !bake_scene {
        return None;
    }
    if cli_sets.iter().any(|(n, _)| n == name) {
        return Some(format!("`--set {name}=… --bake-scene` bakes `{name}` into a constant"));
    }
    if scene.is_some_and(|s| s.uniforms.iter().any(|u| u.name == name)) {
        return Some(format!("`--bake-scene` bakes the scene's `[uniforms]`, which fix `{name}`"));
    }
    None
}

/// Refuses a uniform that is both an override and baked on purpose (`reason`, see
/// [`bake_reason`]): a uniform is a constant in the module or a pipeline constant, not both.
/// Exit 1 saying which; located in the scene file when its `overrides` lists the name.
pub fn check_override_conflicts(
    overrides: &[String],
    scene: Option<&SceneFile>,
    reason: impl Fn(&str) -> Option<String>,
) -> Result<(), ExitCode> {
    for name in overrides {
        let Some(why) = reason(name) else { continue };
        let message = format!("`{name}` cannot be an override and baked: {why}; drop `--override {name}` or the bake");
        match scene.filter(|s| s.overrides.iter().any(|o| o.name == *name)) {
            Some(scene) => {
                eprint!("{}", scene.override_error(name, &message));
                return Err(ExitCode::from(1));
            }
            None => return Err(super::usage(message)),
        }
    }
    Ok(())
}

/// Whether the flag `id` was given on the command line (not a default, not absent).
pub fn given(matches: &ArgMatches, id: &str) -> bool {
    matches.try_contains_id(id).unwrap_or(false)
        && matches.value_source(id) == Some(clap::parser::ValueSource::CommandLine)
}

/// What a command's FILE argument names: a shader, or a scene file and its shader.
pub struct Input {
    /// The shader; `None`: the bundled Freeman sky.
    pub shader: Option<PathBuf>,
    /// The scene file, when FILE is one (`.toml`).
    pub scene: Option<SceneFile>,
}

/// Opens FILE: a `.toml` is read as a scene file, a `.tres`/`.tscn` as a Godot material
/// ([`open_material`]); errors printed, located; exit 1 when it is wrong, 2 when it cannot be
/// read. Anything else is the shader.
pub fn open_input(file: Option<&Path>) -> Result<Input, ExitCode> {
    let Some(path) = file else {
        return Ok(Input { shader: None, scene: None });
    };
    if gdsky::scene::is_godot_resource(path) {
        return open_material(path);
    }
    if !gdsky::scene::is_scene_path(path) {
        return Ok(Input { shader: Some(path.to_path_buf()), scene: None });
    }
    match SceneFile::load(path) {
        Ok(scene) => Ok(Input { shader: scene.shader.clone(), scene: Some(scene) }),
        Err(SceneError::Read(m)) => Err(super::environment(m)),
        Err(SceneError::Invalid(m)) => {
            eprint!("{m}");
            Err(ExitCode::from(1))
        }
    }
}

/// Opens a Godot material (`.tres`) or scene (`.tscn`) as a scene file
/// ([`SceneFile::from_material`]): its shader (FILE itself when the shader is embedded: the
/// loaders check it through [`gdresource::check_file`]), its values as `[uniforms]` and its
/// textures as `[textures]`, every error located in the material's file. Warnings (values of
/// uniforms the shader lacks) are printed.
fn open_material(path: &Path) -> Result<Input, ExitCode> {
    use gdresource::{MaterialError, MaterialShader};
    let material = match gdresource::load_sky_material(path) {
        Ok(m) => m,
        Err(MaterialError::Read(m)) => {
            eprintln!("{}", m.trim_end());
            return Err(ExitCode::from(2));
        }
        Err(MaterialError::Invalid(m)) => {
            eprint!("{m}");
            return Err(ExitCode::from(1));
        }
    };
    let shader = match &material.shader {
        MaterialShader::File(p) => p.clone(),
        MaterialShader::Embedded { .. } => path.to_path_buf(),
    };
    // The values become `--set` text for the uniforms' types, so the shader is checked here;
    // its own diagnostics are printed once, when the command loads it.
    let front = material.check_shader().ok();
    let settings = match front.as_ref().and_then(|f| f.shader.as_ref()) {
        Some(checked) => material.settings(checked).map_err(|m| {
            eprint!("{m}");
            ExitCode::from(1)
        })?,
        None => Default::default(),
    };
    eprint!("{}", settings.warnings);
    Ok(Input { shader: Some(shader.clone()), scene: Some(SceneFile::from_material(material, shader, settings)) })
}

/// Checks the scene file's uniforms against the loaded shader (exit 1, located, when one is
/// not a uniform of it or its value does not fit).
pub fn check_scene_uniforms(scene: Option<&SceneFile>, loaded: &LoadedShader) -> Result<(), ExitCode> {
    let (Some(scene), Some(shader)) = (scene, loaded.front.shader.as_ref()) else {
        return Ok(());
    };
    scene.check_uniforms(shader).map_err(|m| {
        eprint!("{m}");
        ExitCode::from(1)
    })
}

/// Checks and lowers `file`, or the bundled Freeman sky when there is none, as `lowering` says
/// (Godot 4.6's defaults, or the measuring engine's). Diagnostics are printed; the error is the
/// exit code (1 invalid, 2 unreadable).
pub fn load_shader(file: Option<&Path>, lowering: &gdsky_naga::LowerOptions) -> Result<LoadedShader, ExitCode> {
    load_shader_specialized(file, None, lowering.clone(), |_| HashMap::new())
}

/// [`load_shader`] with the uniforms `bake` picks from the checked shader (name → value in
/// `--set` syntax) baked into constants and `lowering.overrides` emitted as pipeline-overridable
/// constants (taken out of what `bake` picks; the caller has refused a uniform baked on purpose,
/// see [`check_override_conflicts`]). The scene file's uniforms and overrides are checked first,
/// so a wrong name is reported located in the file. The shader is lowered once.
pub fn load_shader_specialized(
    file: Option<&Path>,
    scene: Option<&SceneFile>,
    mut lowering: gdsky_naga::LowerOptions,
    bake: impl FnOnce(&gdsky::CheckedShader) -> HashMap<String, String>,
) -> Result<LoadedShader, ExitCode> {
    let front = check_front(file)?;
    let Some(shader) = front.shader.as_ref() else {
        return Err(ExitCode::from(1));
    };
    if let Some(scene) = scene {
        scene.check_uniforms(shader).map_err(|m| {
            eprint!("{m}");
            ExitCode::from(1)
        })?;
    }
    let mut baked = bake(shader);
    baked.retain(|name, _| !lowering.overrides.contains(name));
    lowering.baked.extend(baked);
    let (lowered, wgsl) = lower_and_emit(&front, &lowering)?;
    Ok(LoadedShader { front, lowered, wgsl, textures: Vec::new() })
}

/// Reads and checks `file` (the bundled Freeman sky without one), printing its diagnostics.
/// Exit 1 when it is invalid, 2 when it cannot be read.
fn check_front(file: Option<&Path>) -> Result<gdsky::FrontendOutput, ExitCode> {
    let color = std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none();
    let front = match file {
        Some(path) => gdresource::check_file(path).map_err(|err| {
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
    Ok(front)
}

/// Lowers a checked shader as `lowering` says and emits its WGSL; diagnostics printed, exit 1.
fn lower_and_emit(
    front: &gdsky::FrontendOutput,
    lowering: &gdsky_naga::LowerOptions,
) -> Result<(gdsky_naga::Lowered, String), ExitCode> {
    let color = std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none();
    let lowered = gdsky_naga::lower(front, lowering).map_err(|diags| {
        eprint!("{}", render_human(&front.db, &diags, color));
        ExitCode::from(1)
    })?;
    let wgsl = gdsky_naga::to_wgsl(&lowered).map_err(|err| {
        eprint!("{}", render_human(&front.db, &[err.diagnostic(front)], color));
        ExitCode::from(1)
    })?;
    Ok((lowered, wgsl))
}

impl LoadedShader {
    /// The uniforms baked into constants (`--bake-scene`), name → value.
    pub fn baked(&self) -> &HashMap<String, String> {
        &self.lowered.options.baked
    }

    /// The uniforms emitted as pipeline-overridable constants (`--override`), the k-th with
    /// `@id(k)`.
    pub fn overrides(&self) -> &[String] {
        &self.lowered.options.overrides
    }

    /// Lowers the shader again with `baked` uniforms as constants (`--bake-scene` of `bench`,
    /// after the Freeman-compatibility check) and `overrides` as pipeline-overridable
    /// constants. Exit 1 when a value does not fit or an override is not a scalar uniform.
    pub fn respecialize(&mut self, baked: HashMap<String, String>, overrides: &[String]) -> Result<(), ExitCode> {
        let lowering =
            gdsky_naga::LowerOptions { baked, overrides: overrides.to_vec(), ..self.lowered.options.clone() };
        (self.lowered, self.wgsl) = lower_and_emit(&self.front, &lowering)?;
        Ok(())
    }
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

/// Joins same-sized views left to right into one image (the cubemap strip): the library's.
pub use gdsky::measure::freeman::strip;

/// Checks, before any work, that the EXR and the PNG preview can be written where asked: the
/// directory must exist (`render`, `reference` and `oracle` do not create it: a typo in `-o` is
/// reported, not turned into a new folder), the path must not be a directory or a special file.
/// Exit 2 with the reason.
pub fn check_outputs(exr: &Path, png: Option<&PathBuf>) -> Result<(), ExitCode> {
    super::check_output(exr)?;
    png.map_or(Ok(()), |png| super::check_output(png))
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

/// The textures for `loaded`'s sampler uniforms: `--texture NAME=PATH` flags (`flags`) over the
/// scene file's `[textures]` and a Godot material's generated textures (what
/// [`SceneArgs::textures`] gives; `stress`, which has no scene flags, calls it directly).
pub fn load_textures(
    flags: &[String],
    scene: Option<&SceneFile>,
    loaded: &LoadedShader,
) -> Result<Vec<(String, skyrun::TextureData)>, ExitCode> {
    // (name, path, from the scene file)
    let mut wanted: Vec<(String, PathBuf, bool)> =
        scene.iter().flat_map(|s| &s.textures).map(|t| (t.name.clone(), t.path.clone(), true)).collect();
    for t in flags {
        let Some((name, path)) = t.split_once('=').filter(|(n, p)| !n.trim().is_empty() && !p.is_empty()) else {
            return Err(super::usage(format!("`--texture {t}`: expected NAME=PATH")));
        };
        wanted.retain(|(n, _, _)| n != name.trim());
        wanted.push((name.trim().to_string(), PathBuf::from(path), false));
    }
    // A Godot material's generated textures (NoiseTexture2D, NoiseTexture3D), unless a file
    // is given for the same name.
    let generated: Vec<(&str, Generated)> = scene
        .iter()
        .flat_map(|s| {
            let planes = s.generated_textures.iter().map(|g| (g.name.as_str(), Generated::Plane(&g.texture)));
            let ramps = s.generated_ramps.iter().map(|g| (g.name.as_str(), Generated::Ramp(&g.texture)));
            planes
                .chain(s.generated_volumes.iter().map(|g| (g.name.as_str(), Generated::Volume(&g.texture))))
                .chain(ramps)
        })
        .filter(|(name, _)| !wanted.iter().any(|(n, _, _)| n == name))
        .collect();
    if wanted.is_empty() && generated.is_empty() {
        return Ok(Vec::new());
    }
    let Some(shader) = loaded.front.shader.as_ref() else {
        return Err(ExitCode::from(1));
    };
    let bindings = gdsky_naga::reflect::texture_bindings(shader, &loaded.lowered);
    // The module's resources, to refuse a texture its binding cannot take before any GPU
    // work (the same check `SkyShader::set_texture` makes); a module the harness cannot
    // bind fails later with its own message.
    let declared = skyrun::bindings::discover(&loaded.wgsl).unwrap_or_default();
    let names = shader.texture_names();
    let mut textures = Vec::with_capacity(wanted.len());
    for (name, path, from_scene) in wanted {
        let fail = |message: String, code: u8| {
            match scene.filter(|_| from_scene) {
                Some(scene) => eprint!("{}", scene.texture_error(&name, &message)),
                None => eprintln!("error: {message}"),
            }
            ExitCode::from(code)
        };
        let Some(binding) = bindings.iter().find(|b| b.name == name) else {
            // A sampler uniform the lowering did not give a material binding (a global
            // sampler uniform) is as unknown as a typo.
            let origin = if from_scene { format!("`textures.{name}`") } else { format!("`--texture {name}=…`") };
            let mut message = format!("{origin}: the shader has no sampler uniform `{name}`");
            match gdshader::diag::did_you_mean(&name, names.iter().map(String::as_str)) {
                Some(m) => message.push_str(&format!("; did you mean `{m}`?")),
                None if names.is_empty() => message.push_str(" (it has no sampler uniforms)"),
                None => message.push_str(&format!("; its sampler uniforms are: {}", names.join(", "))),
            }
            return Err(fail(message, 1));
        };
        // The uniform's sampler type says how PATH is read: one image, a cube map's faces
        // (six files or one cross/grid image), a 3D texture's slices (files or one grid).
        let base = scene.filter(|_| from_scene).and_then(|s| s.path.parent());
        let read_fail = |err: skyrun::TextureError| fail(format!("`{name}`: {err}"), if err.is_read() { 2 } else { 1 });
        let data = match texture_shape(shader, &binding.uniform) {
            skyrun::TextureShape::D2 => {
                let pieces = texture_files(&path, base);
                if pieces.len() > 1 {
                    let message = format!(
                        "`{name}` is a sampler2D and takes one image, but {} files were given ({}); six faces \
                             make a cube map for a samplerCube, slices a 3D texture for a sampler3D",
                        pieces.len(),
                        path.display()
                    );
                    return Err(fail(message, 1));
                }
                skyrun::read_texture(&path, binding.srgb).map_err(read_fail)?
            }
            skyrun::TextureShape::Cube => {
                skyrun::read_cube(&texture_files(&path, base), binding.srgb).map_err(read_fail)?
            }
            skyrun::TextureShape::D3 => {
                let mut pieces = texture_files(&path, base);
                let grid = match pieces.as_mut_slice() {
                    [single] => match split_grid(single).map_err(|m| fail(format!("`{name}`: {m}"), 1))? {
                        // Without `@CxR`: the grid Godot's import settings give the image.
                        None => import_grid(single),
                        grid => grid,
                    },
                    _ => None,
                };
                skyrun::read_volume(&pieces, grid, binding.srgb).map_err(read_fail)?
            }
        };
        if !declared.is_empty() {
            skyrun::check_texture(&declared, &bindings, &name, &data)
                .map_err(|err| fail(format!("{}: {err}", path.display()), 1))?;
        }
        textures.push((name, data));
    }
    for (name, g) in generated {
        let fail = |message: String| {
            match scene {
                Some(scene) => eprint!("{}", scene.texture_error(name, &message)),
                None => eprintln!("error: {message}"),
            }
            ExitCode::from(1)
        };
        if !bindings.iter().any(|b| b.name == name) {
            return Err(fail(format!("the shader has no sampler uniform `{name}` to bind a noise texture to")));
        }
        let data = match g {
            // Godot gives a NoiseTexture2D mip levels when `generate_mipmaps` (its default)
            // and samples them under a mipmap filter, hinted or Godot's default.
            Generated::Plane(t) => {
                t.generate().map_err(|err| fail(format!("`{name}`: {err}")))?.with_mipmaps(t.generate_mipmaps)
            }
            Generated::Volume(t) => {
                let slices = t.image().map_err(|err| fail(format!("`{name}`: {err}")))?;
                slices
                    .iter()
                    .map(|s| skyrun::TextureData::new(s.width, s.height, skyrun::TexelFormat::Rgba8Unorm, s.to_rgba8()))
                    .collect::<Result<Vec<_>, _>>()
                    .and_then(|s| skyrun::TextureData::volume(&s))
                    .map_err(|err| fail(format!("`{name}`: {err}")))?
            }
            // No mip levels: Godot creates gradient and curve textures without them.
            Generated::Ramp(t) => t.generate().map_err(|err| fail(format!("`{name}`: {err}")))?,
        };
        // Raw texels even for a `source_color` sampler: Godot 4.6's Compatibility renderer
        // (the oracle's) reads a generated noise texture undecoded (measured on the corpus:
        // decoding put shader_it's stars at p99 2.2 % from Godot, raw at 0.59 %;
        // docs/corpus.md), as gdsky passes colour uniforms as Compatibility does.
        // A NoiseTexture3D for a sampler2D and the like: refused before any GPU work.
        if !declared.is_empty() {
            let what = match g {
                Generated::Plane(_) => "NoiseTexture2D",
                Generated::Volume(_) => "NoiseTexture3D",
                Generated::Ramp(t) => t.class(),
            };
            skyrun::check_texture(&declared, &bindings, name, &data)
                .map_err(|err| fail(format!("the material's {what}: {err}")))?;
        }
        textures.push((name.to_string(), data));
    }
    Ok(textures)
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

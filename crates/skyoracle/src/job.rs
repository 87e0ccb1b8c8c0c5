//! What one render asks of Godot: the shader, the image size, the camera, the sun, uniform
//! overrides and the energy brackets; and how that travels to `main.gd` as JSON.

use std::time::Duration;

use base64::Engine as _;
use serde_json::{Value, json};

/// The camera, as Godot's `Camera3D` takes it. Yaw 0, pitch 0 looks toward −Z with +Y up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Vertical field of view in degrees (`Camera3D.fov` with `keep_aspect = KEEP_HEIGHT`).
    pub fov_deg: f64,
    /// Rotation about +Y in degrees; 90 turns the view from −Z to −X.
    pub yaw_deg: f64,
    /// Rotation about +X in degrees (applied before the yaw: Euler order YXZ); 90 looks up.
    pub pitch_deg: f64,
    /// Camera position (POSITION in the shader).
    pub position: [f64; 3],
}

impl Default for Camera {
    /// 90° vertical field of view at the origin, looking toward −Z.
    fn default() -> Self {
        Self { fov_deg: 90.0, yaw_deg: 0.0, pitch_deg: 0.0, position: [0.0; 3] }
    }
}

/// A `DirectionalLight3D`, seen by the shader as LIGHT0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sun {
    /// Elevation above the horizon in degrees.
    pub elevation_deg: f64,
    /// Azimuth in degrees: 0 toward −Z, 90 toward +X. With the elevation, LIGHT0_DIRECTION =
    /// (cos e · sin a, sin e, −cos e · cos a).
    pub azimuth_deg: f64,
    /// `light_color` as Godot's inspector shows it (sRGB). The Compatibility renderer passes it to
    /// LIGHT0_COLOR as is; Forward+ converts it to linear first.
    pub color: [f32; 3],
    /// `light_energy` (LIGHT0_ENERGY).
    pub energy: f32,
    /// `light_angular_distance` in degrees (LIGHT0_SIZE is its radians).
    pub angular_diameter_deg: f32,
}

impl Default for Sun {
    /// White, energy 1, 10° above the horizon toward −Z, no angular size.
    fn default() -> Self {
        Self { elevation_deg: 10.0, azimuth_deg: 0.0, color: [1.0; 3], energy: 1.0, angular_diameter_deg: 0.0 }
    }
}

/// A value for a shader uniform, set with `ShaderMaterial.set_shader_parameter`.
#[derive(Clone, Debug, PartialEq)]
pub enum UniformValue {
    /// `float`.
    Float(f32),
    /// `int`.
    Int(i32),
    /// `uint`.
    Uint(u32),
    /// `bool`.
    Bool(bool),
    /// `vec2`, sent as a `Vector2`.
    Vec2([f32; 2]),
    /// `vec3`, sent as a `Vector3` (see the crate documentation for what Godot does with it on a
    /// `source_color` uniform).
    Vec3([f32; 3]),
    /// `vec4`, sent as a `Vector4`.
    Vec4([f32; 4]),
    /// `ivec2`.
    IVec2([i32; 2]),
    /// `ivec3`.
    IVec3([i32; 3]),
    /// `ivec4`.
    IVec4([i32; 4]),
    /// A `float` array (`uniform float x[N]`), sent as a `PackedFloat32Array`.
    FloatArray(Vec<f32>),
    /// An `int` or `uint` array, sent as a `PackedInt32Array` (Godot's type for both; a `uint`
    /// element above 2³¹ − 1 goes as its two's-complement bit pattern).
    IntArray(Vec<i32>),
    /// A `Color` (r, g, b, a), as Godot's inspector sets a `vec3`/`vec4` uniform with a
    /// `source_color` hint (sRGB; see the crate documentation for the conversion measured).
    Color([f32; 4]),
    /// A `sampler2D`: `width` × `height` RGBA texels of 32-bit floats, row 0 first (texel
    /// (x, y) is `texels[y * width + x]`, what `texelFetch(t, ivec2(x, y), 0)` reads). `main.gd`
    /// builds an `Image` of `FORMAT_RGBAF` (no mipmaps) and an `ImageTexture` from it. The texels
    /// travel as base64 of their little-endian bytes: exact, and about a third the size of the
    /// same floats as JSON numbers (see the crate documentation for what Godot keeps of them).
    TextureRgbaF32 {
        /// Texels per row, 1 ..= [`MAX_TEXTURE_SIDE`].
        width: u32,
        /// Rows, 1 ..= [`MAX_TEXTURE_SIDE`].
        height: u32,
        /// `width × height` texels, row-major.
        texels: Vec<[f32; 4]>,
    },
    /// A `sampler2D` bound to a `NoiseTexture2D` that Godot itself generates from these
    /// properties (see [`crate::NoiseTextureSpec`]); the render waits until it has.
    NoiseTexture2D(crate::NoiseTextureSpec),
    /// A `sampler2D` bound to a `GradientTexture1D`, `GradientTexture2D` or `CurveTexture` that
    /// Godot builds from these properties (see [`crate::RampTextureSpec`]).
    RampTexture(crate::RampTextureSpec),
}

/// The largest side of a [`UniformValue::TextureRgbaF32`]: a 4096² RGBA f32 texture is 256 MiB,
/// already more than is sensible to push through JSON into a browser tab.
pub const MAX_TEXTURE_SIDE: u32 = 4096;

impl UniformValue {
    fn to_json(&self) -> (&'static str, Value) {
        match self {
            Self::Float(v) => ("float", json!([v])),
            Self::Int(v) => ("int", json!([v])),
            Self::Uint(v) => ("uint", json!([v])),
            Self::Bool(v) => ("bool", json!([v])),
            Self::Vec2(v) => ("vec2", json!(v)),
            Self::Vec3(v) => ("vec3", json!(v)),
            Self::Vec4(v) => ("vec4", json!(v)),
            Self::IVec2(v) => ("ivec2", json!(v)),
            Self::IVec3(v) => ("ivec3", json!(v)),
            Self::IVec4(v) => ("ivec4", json!(v)),
            Self::Color(v) => ("color", json!(v)),
            Self::FloatArray(v) => ("float_array", json!(v)),
            Self::IntArray(v) => ("int_array", json!(v)),
            Self::TextureRgbaF32 { width, height, texels } => {
                let bytes: Vec<u8> = texels.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
                let data = base64::engine::general_purpose::STANDARD.encode(bytes);
                ("texture_rgbaf", json!([width, height, data]))
            }
            Self::NoiseTexture2D(spec) => ("noise_texture_2d", spec.to_json()),
            Self::RampTexture(spec) => ("ramp_texture", spec.to_json()),
        }
    }

    fn is_finite(&self) -> bool {
        match self {
            Self::Float(v) => v.is_finite(),
            Self::Vec2(v) => v.iter().all(|c| c.is_finite()),
            Self::Vec3(v) => v.iter().all(|c| c.is_finite()),
            Self::Vec4(v) | Self::Color(v) => v.iter().all(|c| c.is_finite()),
            Self::FloatArray(v) => v.iter().all(|c| c.is_finite()),
            Self::TextureRgbaF32 { texels, .. } => texels.iter().flatten().all(|c| c.is_finite()),
            _ => true,
        }
    }

    /// For a texture, whether its size is one Godot takes and matches its texels.
    fn check_size(&self) -> Result<(), String> {
        let Self::TextureRgbaF32 { width, height, texels } = self else { return Ok(()) };
        let side = 1..=MAX_TEXTURE_SIDE;
        if !side.contains(width) || !side.contains(height) {
            return Err(format!("texture size {width}×{height} is outside 1…{MAX_TEXTURE_SIDE}"));
        }
        // u64: 4096 × 4096 fits u32, but the product is compared with a usize either way.
        let expected = u64::from(*width) * u64::from(*height);
        if texels.len() as u64 != expected {
            return Err(format!("a {width}×{height} texture needs {expected} texels, {} given", texels.len()));
        }
        Ok(())
    }
}

/// The `Environment.background_energy_multiplier` values one render is taken at, one frame each.
///
/// Godot multiplies the shader's COLOR by this energy before its 8-bit store, so a set of
/// energies spread over many octaves sees every pixel unclipped in some frame; [`crate::recover`]
/// inverts the frames back to linear COLOR.
#[derive(Clone, Debug, PartialEq)]
pub struct Brackets {
    energies: Vec<f32>,
}

impl Brackets {
    /// Energies 2^(lo + k/steps) for k = 0 ..= (hi − lo)·steps: `steps` frames per octave.
    /// `octaves(-12, 14, 1)` is the default (27 frames); `octaves(-12, 14, 4)` the quarter-stop set
    /// (105 frames).
    pub fn octaves(lo: i32, hi: i32, steps: u32) -> Self {
        let steps = steps.max(1);
        let count = (hi - lo).max(0) as u32 * steps + 1;
        let energies = (0..count).map(|k| 2f64.powf(f64::from(lo) + f64::from(k) / f64::from(steps)) as f32).collect();
        Self { energies }
    }

    /// Exactly these energies, in this order (each must be finite and above zero).
    pub fn from_energies(energies: Vec<f32>) -> Self {
        Self { energies }
    }

    /// The energies, in rendering order.
    pub fn energies(&self) -> &[f32] {
        &self.energies
    }
}

impl Default for Brackets {
    /// One frame per octave over 2^−12 … 2^14: linear COLOR from about 1e−5 to 4e3.
    fn default() -> Self {
        Self::octaves(-12, 14, 1)
    }
}

/// One render: a sky shader in Godot's shading language and the scene to draw it in.
#[derive(Clone, Debug, PartialEq)]
pub struct Job {
    /// The shader's text (`shader_type sky; …`). `#include` is not available: the pack holds no
    /// other file.
    pub code: String,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The camera.
    pub camera: Camera,
    /// The directional light, or `None` for no light (LIGHT0_ENABLED false).
    pub sun: Option<Sun>,
    /// Uniform overrides, by name; the rest keep the shader's defaults.
    pub uniforms: Vec<(String, UniformValue)>,
    /// The energy brackets.
    pub brackets: Brackets,
    /// How long Godot may take before the job is abandoned (and the oracle with it); `None`
    /// allows 60 s plus 50 µs per pixel per bracket.
    pub timeout: Option<Duration>,
}

/// The largest image side a job may ask for (Godot's viewports allow more; SwiftShader does not
/// make it worth it).
pub const MAX_SIDE: u32 = 4096;
/// The smallest image side: Godot gives a 1-pixel side of a SubViewport 2 pixels.
pub const MIN_SIDE: u32 = 2;

impl Job {
    /// A job for `code` at `width`×`height` with the default camera, no light, no uniform
    /// overrides and the default brackets.
    pub fn new(code: impl Into<String>, width: u32, height: u32) -> Self {
        Self {
            code: code.into(),
            width,
            height,
            camera: Camera::default(),
            sun: None,
            uniforms: Vec::new(),
            brackets: Brackets::default(),
            timeout: None,
        }
    }

    /// The time allowed for this job (plus the time allowed for generating each noise texture
    /// it binds).
    pub fn time_allowed(&self) -> Duration {
        self.timeout.unwrap_or_else(|| {
            let work = f64::from(self.width) * f64::from(self.height) * self.brackets.energies.len() as f64;
            let noise: Duration = self
                .uniforms
                .iter()
                .filter_map(|(_, v)| match v {
                    UniformValue::NoiseTexture2D(spec) => Some(spec.time_allowed(false)),
                    _ => None,
                })
                .sum();
            Duration::from_secs(60) + Duration::from_secs_f64(work * 50e-6) + noise
        })
    }

    /// Checks what Godot would otherwise choke on or silently change.
    pub(crate) fn validate(&self) -> Result<(), String> {
        let side = MIN_SIDE..=MAX_SIDE;
        if !side.contains(&self.width) || !side.contains(&self.height) {
            return Err(format!("image size {}×{} is outside {MIN_SIDE}…{MAX_SIDE}", self.width, self.height));
        }
        if self.brackets.energies.is_empty() {
            return Err("the bracket set is empty".into());
        }
        if let Some(e) = self.brackets.energies.iter().find(|e| !(e.is_finite() && **e > 0.0)) {
            return Err(format!("bracket energy {e} is not a finite number above zero"));
        }
        let c = &self.camera;
        if !(c.fov_deg > 0.0 && c.fov_deg < 180.0) {
            return Err(format!("field of view {} is outside (0, 180) degrees", c.fov_deg));
        }
        if ![c.yaw_deg, c.pitch_deg].iter().chain(&c.position).all(|v| v.is_finite()) {
            return Err("the camera has a non-finite value".into());
        }
        if let Some(s) = &self.sun {
            let values = [s.elevation_deg, s.azimuth_deg, f64::from(s.energy), f64::from(s.angular_diameter_deg)];
            if !values.iter().chain(&s.color.map(f64::from)).all(|v| v.is_finite()) {
                return Err("the sun has a non-finite value".into());
            }
        }
        for (name, value) in &self.uniforms {
            value.check_size().map_err(|e| format!("uniform `{name}`: {e}"))?;
        }
        if let Some((name, _)) = self.uniforms.iter().find(|(_, v)| !v.is_finite()) {
            // A texture could carry NaN in its bytes; refused all the same, since no sky
            // table has a reason to hold one and Godot's treatment of it was not measured.
            return Err(format!("uniform `{name}` has a non-finite value (JSON cannot carry it)"));
        }
        Ok(())
    }

    /// The job as `main.gd` reads it.
    pub(crate) fn to_json(&self, id: u64) -> Value {
        let uniforms: Vec<Value> = self
            .uniforms
            .iter()
            .map(|(name, value)| {
                let (kind, value) = value.to_json();
                json!({ "name": name, "type": kind, "value": value })
            })
            .collect();
        let sun = self.sun.map(|s| {
            json!({
                "elevation_deg": s.elevation_deg,
                "azimuth_deg": s.azimuth_deg,
                "color": s.color,
                "energy": s.energy,
                "angular_diameter_deg": s.angular_diameter_deg,
            })
        });
        json!({
            "id": id,
            "op": "render",
            "code": self.code,
            "width": self.width,
            "height": self.height,
            "camera": {
                "fov_deg": self.camera.fov_deg,
                "yaw_deg": self.camera.yaw_deg,
                "pitch_deg": self.camera.pitch_deg,
                "position": self.camera.position,
            },
            "sun": sun,
            "uniforms": uniforms,
            "energies": self.brackets.energies,
            // Measured: a new shader, size, camera or energy shows in the very next frame.
            "settle_frames": 0,
            "timeout_ms": self.time_allowed().as_millis() as u64,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture(width: u32, height: u32, texels: Vec<[f32; 4]>) -> Job {
        let value = UniformValue::TextureRgbaF32 { width, height, texels };
        Job { uniforms: vec![("t".into(), value)], ..Job::new("shader_type sky;", 4, 2) }
    }

    #[test]
    fn texture_sizes_and_values_are_validated() {
        assert_eq!(texture(2, 1, vec![[0.0; 4]; 2]).validate(), Ok(()));
        assert_eq!(texture(MAX_TEXTURE_SIDE, 1, vec![[0.0; 4]; MAX_TEXTURE_SIDE as usize]).validate(), Ok(()));
        let refused = |job: Job, what: &str| {
            let e = job.validate().expect_err(what);
            assert!(e.contains(what), "{e:?} does not say {what:?}");
        };
        refused(texture(2, 2, vec![[0.0; 4]; 3]), "needs 4 texels, 3 given");
        refused(texture(0, 1, Vec::new()), "outside 1…4096");
        refused(texture(1, MAX_TEXTURE_SIDE + 1, vec![[0.0; 4]; 4097]), "outside 1…4096");
        refused(texture(1, 1, vec![[0.0, f32::NAN, 0.0, 0.0]]), "non-finite");
        refused(texture(1, 1, vec![[f32::INFINITY, 0.0, 0.0, 0.0]]), "non-finite");
    }

    #[test]
    fn noise_texture_travels_as_its_properties_and_extends_the_time_allowed() {
        let mut spec = crate::NoiseTextureSpec::default();
        spec.texture.insert("width".into(), json!(1000));
        spec.texture.insert("height".into(), json!(1000));
        spec.noise = Some(serde_json::Map::new());
        let plain = Job::new("shader_type sky;", 4, 2);
        let job = Job { uniforms: vec![("n".into(), UniformValue::NoiseTexture2D(spec))], ..plain.clone() };
        let uniform = &job.to_json(1)["uniforms"][0];
        assert_eq!(uniform["type"], "noise_texture_2d");
        assert_eq!(uniform["value"]["texture"]["width"], 1000);
        assert_eq!(uniform["value"]["color_ramp"], Value::Null);
        // 60 s plus 20 µs per texel for the generation.
        assert_eq!(job.time_allowed() - plain.time_allowed(), Duration::from_secs(80));
        assert_eq!(job.validate(), Ok(()));
    }

    #[test]
    fn ramp_texture_travels_as_its_class_and_properties() {
        let mut spec = crate::RampTextureSpec { class: "CurveTexture".into(), ..Default::default() };
        spec.texture.insert("texture_mode".into(), json!(1));
        spec.curve = Some(serde_json::Map::from_iter([("points".to_string(), json!([[0.0, 1.0, 0.0, 0.0, 0, 0]]))]));
        let plain = Job::new("shader_type sky;", 4, 2);
        let job = Job { uniforms: vec![("c".into(), UniformValue::RampTexture(spec))], ..plain.clone() };
        let uniform = &job.to_json(1)["uniforms"][0];
        assert_eq!(uniform["type"], "ramp_texture");
        assert_eq!(uniform["value"]["class"], "CurveTexture");
        assert_eq!(uniform["value"]["texture"]["texture_mode"], 1);
        assert_eq!(uniform["value"]["curve"]["points"][0][1], 1.0);
        assert_eq!(uniform["value"]["gradient"], Value::Null);
        // Built synchronously: no time added.
        assert_eq!(job.time_allowed(), plain.time_allowed());
        assert_eq!(job.validate(), Ok(()));
    }

    #[test]
    fn texture_travels_as_base64_of_little_endian_f32() {
        let texels = vec![[1.0, -2.5, 1e-30, 3.4e38], [0.0, 0.5, 65504.0, 1.0]];
        let json = texture(2, 1, texels.clone()).to_json(7);
        let uniform = &json["uniforms"][0];
        assert_eq!(uniform["type"], "texture_rgbaf");
        assert_eq!((uniform["value"][0].as_u64(), uniform["value"][1].as_u64()), (Some(2), Some(1)));
        let text = uniform["value"][2].as_str().expect("a base64 string");
        let bytes = base64::engine::general_purpose::STANDARD.decode(text).expect("base64");
        let back: Vec<f32> = bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
        assert_eq!(back, texels.concat());
    }
}

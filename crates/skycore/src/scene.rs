//! What a sky is rendered for: the camera, the lights, the time, and how pixels become view
//! directions.
//!
//! The conventions are Godot's (docs/binding-interface.md; ../shared/reference/godot-sky.md): a
//! light is given by elevation and azimuth in degrees, its direction is the unit vector from the
//! scene toward it, `(cos e · sin a, sin e, −cos e · cos a)`, so azimuth 0 is toward −Z and 90
//! toward +X; the camera looks toward −Z with +Y up at yaw 0 and pitch 0, rotated by Godot's
//! Euler order YXZ, with a vertical field of view. Angles are f64 so that the CPU reference
//! (skyref) computes directions in f64 and the GPU side rounds the same f64 values to f32.

use glam::{DMat3, DVec3};
use std::str::FromStr;

/// Godot's number of directional lights a sky shader sees (`LIGHT0` … `LIGHT3`).
pub const MAX_LIGHTS: usize = 4;

/// Everything a sky shader reads from the scene: the camera (`POSITION`, and the view of the
/// camera projection), `TIME` and `LIGHT0` … `LIGHT3`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scene {
    /// The camera: its position is `POSITION`; its orientation and field of view shape the
    /// [`Projection::Camera`] view.
    pub camera: Camera,
    /// `LIGHT0` … `LIGHT3`; `LIGHT0` is the sun ([`Scene::sun`]).
    pub lights: [Light; MAX_LIGHTS],
    /// `TIME` in seconds. It reaches the GPU as an f32.
    pub time: f64,
}

impl Default for Scene {
    /// The sun 10° up toward −Z (white, energy 1, no angular size), the other lights
    /// [`Light::OFF`], the
    /// camera at the origin looking toward −Z with a 90° vertical field of view, time 0.
    fn default() -> Self {
        Self { camera: Camera::default(), lights: [Light::default(), Light::OFF, Light::OFF, Light::OFF], time: 0.0 }
    }
}

impl Scene {
    /// `LIGHT0`, the sun.
    pub fn sun(&self) -> &Light {
        &self.lights[0]
    }

    /// `LIGHT0`, the sun, to change.
    pub fn sun_mut(&mut self) -> &mut Light {
        &mut self.lights[0]
    }

    /// The scene with the sun (`LIGHT0`) at `elevation_deg`, `azimuth_deg`.
    #[must_use]
    pub fn with_sun(mut self, elevation_deg: f64, azimuth_deg: f64) -> Self {
        self.lights[0].elevation_deg = elevation_deg;
        self.lights[0].azimuth_deg = azimuth_deg;
        self
    }

    /// The scene with `LIGHT0_ENABLED` as given.
    #[must_use]
    pub fn with_sun_enabled(mut self, enabled: bool) -> Self {
        self.lights[0].enabled = enabled;
        self
    }

    /// The scene with the camera (`POSITION`) at `position`, in metres.
    #[must_use]
    pub fn with_position(mut self, position: DVec3) -> Self {
        self.camera.position = position;
        self
    }

    /// The scene with the camera turned by `yaw_deg` and `pitch_deg`.
    #[must_use]
    pub fn with_view(mut self, yaw_deg: f64, pitch_deg: f64) -> Self {
        self.camera.yaw_deg = yaw_deg;
        self.camera.pitch_deg = pitch_deg;
        self
    }

    /// The scene with the camera's vertical field of view `fov_deg`.
    #[must_use]
    pub fn with_fov(mut self, fov_deg: f64) -> Self {
        self.camera.fov_deg = fov_deg;
        self
    }

    /// The scene at `TIME` = `time` seconds.
    #[must_use]
    pub fn with_time(mut self, time: f64) -> Self {
        self.time = time;
        self
    }
}

/// The camera: `POSITION` and the view of the [`Projection::Camera`] projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// `POSITION`, the camera's position in metres.
    pub position: DVec3,
    /// Vertical field of view in degrees (more than 0, less than 180).
    pub fov_deg: f64,
    /// Rotation about +Y in degrees; 90 turns the view from −Z to −X.
    pub yaw_deg: f64,
    /// Rotation about +X in degrees (applied before the yaw: Euler order YXZ); 90 looks straight
    /// up, with the image's top toward +Z.
    pub pitch_deg: f64,
}

impl Default for Camera {
    /// At the origin, looking toward −Z with a 90° vertical field of view.
    fn default() -> Self {
        Self { position: DVec3::ZERO, fov_deg: 90.0, yaw_deg: 0.0, pitch_deg: 0.0 }
    }
}

impl Camera {
    /// The camera basis, Godot's Euler YXZ with no roll: R_y(yaw) · R_x(pitch). Its columns are
    /// the camera's right, up and back (+Z) axes in world space.
    pub fn basis(&self) -> DMat3 {
        DMat3::from_rotation_y(self.yaw_deg.to_radians()) * DMat3::from_rotation_x(self.pitch_deg.to_radians())
    }

    /// tan(fov / 2) of the vertical field of view.
    pub fn tan_half_fov(&self) -> f64 {
        (self.fov_deg.to_radians() * 0.5).tan()
    }
}

/// A directional light as a sky shader sees it (`LIGHTn_ENABLED`, `LIGHTn_DIRECTION`,
/// `LIGHTn_ENERGY`, `LIGHTn_COLOR`, `LIGHTn_SIZE`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// `LIGHTn_ENABLED`.
    pub enabled: bool,
    /// Elevation above the horizon in degrees (−90 to 90).
    pub elevation_deg: f64,
    /// Azimuth in degrees: 0 toward −Z, 90 toward +X.
    pub azimuth_deg: f64,
    /// `LIGHTn_ENERGY`.
    pub energy: f32,
    /// `LIGHTn_COLOR`, linear, not multiplied by the energy.
    pub color: [f32; 3],
    /// Angular diameter in degrees: Godot's `light_angular_distance`, which reaches the shader
    /// in radians as `LIGHTn_SIZE` (Godot 4.5 and later). The sun is about 0.5°.
    pub angular_diameter_deg: f64,
}

impl Default for Light {
    /// On, 10° up toward −Z, white, energy 1, no angular size.
    fn default() -> Self {
        Self {
            enabled: true,
            elevation_deg: 10.0,
            azimuth_deg: 0.0,
            energy: 1.0,
            color: [1.0; 3],
            angular_diameter_deg: 0.0,
        }
    }
}

impl Light {
    /// A light that is off, with no energy and no colour, so that a shader that reads it without
    /// looking at `LIGHTn_ENABLED` sees nothing either.
    pub const OFF: Light = Light {
        enabled: false,
        elevation_deg: 0.0,
        azimuth_deg: 0.0,
        energy: 0.0,
        color: [0.0; 3],
        angular_diameter_deg: 0.0,
    };

    /// `LIGHTn_DIRECTION`, the unit vector toward the light: (cos e · sin a, sin e, −cos e · cos a).
    pub fn direction(&self) -> DVec3 {
        direction(self.elevation_deg, self.azimuth_deg)
    }

    /// `LIGHTn_SIZE`: the angular diameter in radians.
    pub fn size_rad(&self) -> f64 {
        self.angular_diameter_deg.to_radians()
    }

    /// Elevation and azimuth in degrees of the direction `toward` (any length but zero), so
    /// that a light can be aimed by a vector: the inverse of [`Light::direction`].
    pub fn angles_of(toward: DVec3) -> (f64, f64) {
        let d = toward.normalize_or(DVec3::Y);
        let elevation = d.y.clamp(-1.0, 1.0).asin().to_degrees();
        let azimuth = d.x.atan2(-d.z).to_degrees();
        (elevation, azimuth)
    }
}

/// The unit vector at `elevation_deg` above the horizon and `azimuth_deg` around it.
pub fn direction(elevation_deg: f64, azimuth_deg: f64) -> DVec3 {
    let (se, ce) = elevation_deg.to_radians().sin_cos();
    let (sa, ca) = azimuth_deg.to_radians().sin_cos();
    DVec3::new(ce * sa, se, -ce * ca)
}

/// How pixel (x, y) of a W×H image becomes EYEDIR: pixel centres u = (x+½)/W, v = (y+½)/H, row 0
/// at the top. Each has its own fragment entry in a converted module ([`Projection::entry_point`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum Projection {
    /// Equirectangular, the inverse of SKY_COORDS: φ = 2πu, θ = πv,
    /// EYEDIR = (sin θ sin φ, cos θ, −sin θ cos φ).
    #[default]
    Panorama,
    /// Godot's perspective camera: EYEDIR = normalize(basis · ((2u−1)·t·W/H, (1−2v)·t, −1)) with
    /// t = tan(fov/2) and the basis of [`Camera::basis`].
    Camera,
    /// One face of the radiance cube map (0..6: +X, −X, +Y, −Y, +Z, −Z): the camera formula
    /// with t = 1 and the face's basis ([`cube_face_basis`]); the scene's camera is not used.
    CubeFace(u8),
}

impl Projection {
    /// The names the command line and scene files use, with what each renders: `panorama` and
    /// `camera` one view, `cubemap` the six faces.
    pub const NAMES: [&'static str; 3] = ["panorama", "camera", "cubemap"];

    /// The projections a converted module has a fragment entry for, in entry-point order (one
    /// entry serves every cube face).
    pub const ENTRIES: [Projection; 3] = [Projection::Panorama, Projection::Camera, Projection::CubeFace(0)];

    /// The fragment entry point of a converted module that renders this projection.
    pub fn entry_point(self) -> &'static str {
        match self {
            Projection::Panorama => "fs_panorama",
            Projection::Camera => "fs_camera",
            Projection::CubeFace(_) => "fs_cubemap",
        }
    }

    /// The name the command line and scene files use ([`Projection::NAMES`]).
    pub fn name(self) -> &'static str {
        match self {
            Projection::Panorama => "panorama",
            Projection::Camera => "camera",
            Projection::CubeFace(_) => "cubemap",
        }
    }

    /// The views a render of this projection draws: itself, or for a cube face the six faces.
    pub fn views(self) -> Vec<Projection> {
        match self {
            Projection::CubeFace(_) => (0..6).map(Projection::CubeFace).collect(),
            view => vec![view],
        }
    }
}

impl FromStr for Projection {
    type Err = String;

    /// `panorama`, `camera`, or `cubemap` (its first face; [`Projection::views`] gives all six).
    fn from_str(name: &str) -> Result<Self, String> {
        match name {
            "panorama" => Ok(Projection::Panorama),
            "camera" => Ok(Projection::Camera),
            "cubemap" => Ok(Projection::CubeFace(0)),
            _ => Err(format!("`{name}` is no projection; expected one of: {}", Projection::NAMES.join(", "))),
        }
    }
}

/// The basis cube face `face` is rendered with (faces above 5 are taken as 5), as columns x, y,
/// z, so that the camera formula with t = 1 gives every texel of the face the direction that
/// cube sampling assigns it: `textureSample(cube, dir)` returns the sky in direction `dir`.
///
/// Godot renders its radiance faces with `Basis::looking_at(normal, up)` for the normals +X, −X,
/// +Y, −Y, +Z, −Z with ups −Y, −Y, +Z, −Z, −Y, −Y, through a projection whose y is flipped (the
/// RD renderer's `set_depth_correction(true)`), which lands each texel where Vulkan's cube
/// convention (and wgpu's) samples it. The same here: `looking_at`'s y column negated. The
/// result is a mirror, not a rotation (determinant −1): for face k with major axis m and texel
/// centre (s, t) in [−1, 1]² (t growing down the rows), EYEDIR = normalize(m + s·x + t·(−y)),
/// which is the table of the Vulkan specification's "Cube Map Face Selection":
/// +X (1, −t, −s), −X (−1, −t, s), +Y (s, 1, t), −Y (s, −1, −t), +Z (s, −t, 1), −Z (−s, −t, −1).
pub fn cube_face_basis(face: u8) -> DMat3 {
    let (target, up) = match face {
        0 => (DVec3::X, DVec3::NEG_Y),
        1 => (DVec3::NEG_X, DVec3::NEG_Y),
        2 => (DVec3::Y, DVec3::Z),
        3 => (DVec3::NEG_Y, DVec3::NEG_Z),
        4 => (DVec3::Z, DVec3::NEG_Y),
        _ => (DVec3::NEG_Z, DVec3::NEG_Y),
    };
    let z = -target;
    let x = up.cross(z);
    DMat3::from_cols(x, -z.cross(x), z)
}

/// Where the sky lies in depth: on the far plane, so that a depth test against geometry drawn
/// before it skips every covered pixel (as Godot draws its sky behind its geometry). Which
/// depth the far plane has depends on the renderer's convention.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum DepthConvention {
    /// Near 0, far 1: the sky at depth 1, test `LessEqual`, depth cleared to 1.
    #[default]
    Standard,
    /// Near 1, far 0 (reversed Z, Bevy's and many engines' choice for precision): the sky at
    /// depth 0, test `GreaterEqual`, depth cleared to 0.
    Reversed,
}

impl DepthConvention {
    /// Both conventions' names, as [`DepthConvention::name`] gives them.
    pub const NAMES: [&'static str; 2] = ["standard_z", "reversed_z"];

    /// The depth of the far plane, where the sky is drawn (and the value the depth buffer is
    /// cleared to).
    pub fn far_plane(self) -> f32 {
        match self {
            DepthConvention::Standard => 1.0,
            DepthConvention::Reversed => 0.0,
        }
    }

    /// `standard_z` or `reversed_z`.
    pub fn name(self) -> &'static str {
        match self {
            DepthConvention::Standard => "standard_z",
            DepthConvention::Reversed => "reversed_z",
        }
    }

    /// The depth test that keeps what is nearer than the sky: `less_equal` or `greater_equal`
    /// (as WebGPU names the compare functions).
    pub fn compare_name(self) -> &'static str {
        match self {
            DepthConvention::Standard => "less_equal",
            DepthConvention::Reversed => "greater_equal",
        }
    }
}

/// The resolution the sky is shaded at, as a fraction of the view (gdsky's reduced sky
/// resolution, upsampled on the GPU; the same divisors as Godot's half- and quarter-resolution
/// passes).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum SkyResolution {
    /// Every pixel shaded.
    #[default]
    Full,
    /// Shaded at half the width and height.
    Half,
    /// Shaded at a quarter of the width and height.
    Quarter,
}

impl SkyResolution {
    /// Every resolution's name, as [`SkyResolution::name`] gives it.
    pub const NAMES: [&'static str; 3] = ["full", "half", "quarter"];

    /// Every resolution, full first.
    pub const ALL: [SkyResolution; 3] = [SkyResolution::Full, SkyResolution::Half, SkyResolution::Quarter];

    /// 1, 2 or 4.
    pub fn divisor(self) -> u32 {
        match self {
            SkyResolution::Full => 1,
            SkyResolution::Half => 2,
            SkyResolution::Quarter => 4,
        }
    }

    /// The shaded size of a `width`×`height` view: each side divided, rounded up, at least 1.
    pub fn shaded_size(self, width: u32, height: u32) -> (u32, u32) {
        let d = self.divisor();
        (width.div_ceil(d).max(1), height.div_ceil(d).max(1))
    }

    /// `full`, `half` or `quarter`: the name flags and scene files use.
    pub fn name(self) -> &'static str {
        match self {
            SkyResolution::Full => "full",
            SkyResolution::Half => "half",
            SkyResolution::Quarter => "quarter",
        }
    }
}

impl FromStr for SkyResolution {
    type Err = String;

    /// `full`, `half` or `quarter`.
    fn from_str(name: &str) -> Result<Self, String> {
        SkyResolution::ALL
            .into_iter()
            .find(|r| r.name() == name)
            .ok_or_else(|| format!("`{name}` is no sky resolution; expected one of: full, half, quarter"))
    }
}

/// Deserializes a value from the name its `FromStr` reads (scene files: `projection = "camera"`).
fn from_name<'de, T: FromStr<Err = String>, D: serde::Deserializer<'de>>(deserializer: D) -> Result<T, D::Error> {
    let name = <std::borrow::Cow<'de, str> as serde::Deserialize>::deserialize(deserializer)?;
    name.parse().map_err(serde::de::Error::custom)
}

impl<'de> serde::Deserialize<'de> for Projection {
    /// From its name: `panorama`, `camera`, `cubemap`.
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        from_name(deserializer)
    }
}

impl<'de> serde::Deserialize<'de> for SkyResolution {
    /// From its name: `full`, `half`, `quarter`.
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        from_name(deserializer)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn light_angles_round_trip() {
        for (e, a) in [(10.0, 0.0), (-4.0, 90.0), (45.0, -135.0), (89.0, 30.0)] {
            let (e2, a2) = Light::angles_of(direction(e, a));
            assert!((e - e2).abs() < 1e-9 && (a - a2).abs() < 1e-9, "{e},{a} -> {e2},{a2}");
        }
        assert!((direction(0.0, 90.0) - DVec3::X).length() < 1e-15);
        assert!((direction(0.0, 0.0) - DVec3::NEG_Z).length() < 1e-15);
    }

    #[test]
    fn names_parse_back() {
        for name in Projection::NAMES {
            assert_eq!(name.parse::<Projection>().map(Projection::name), Ok(name));
        }
        assert_eq!("cubemap".parse::<Projection>().map(|p| p.views().len()), Ok(6));
        for r in SkyResolution::ALL {
            assert_eq!(r.name().parse(), Ok(r));
        }
        assert!("fisheye".parse::<Projection>().is_err());
    }

    #[test]
    fn cube_faces_look_along_their_axes() {
        let axes = [DVec3::X, DVec3::NEG_X, DVec3::Y, DVec3::NEG_Y, DVec3::Z, DVec3::NEG_Z];
        for (face, axis) in axes.into_iter().enumerate() {
            let basis = cube_face_basis(face as u8);
            assert!((-basis.z_axis - axis).length() < 1e-15, "face {face}");
            assert!((basis.determinant() + 1.0).abs() < 1e-12, "a mirror, as cube sampling is");
        }
    }

    /// The Vulkan specification's cube face selection (table "Cube Map Face Selection", with
    /// s = sc/|ma|, t = tc/|ma| at texel centres, row 0 at t = −1), written out independently.
    #[test]
    fn cube_face_texels_have_the_directions_vulkan_samples_them_at() {
        let vulkan = |face: u8, s: f64, t: f64| match face {
            0 => DVec3::new(1.0, -t, -s),
            1 => DVec3::new(-1.0, -t, s),
            2 => DVec3::new(s, 1.0, t),
            3 => DVec3::new(s, -1.0, -t),
            4 => DVec3::new(s, -t, 1.0),
            _ => DVec3::new(-s, -t, -1.0),
        };
        for face in 0..6 {
            let basis = cube_face_basis(face);
            for (s, t) in [(-0.75, -0.75), (0.25, -0.5), (0.5, 0.75), (-0.25, 0.25)] {
                // The camera formula with t = 1: basis · (s, −t, −1), u = (s+1)/2, v = (t+1)/2.
                let ours = basis * DVec3::new(s, -t, -1.0);
                assert!((ours - vulkan(face, s, t)).length() < 1e-15, "face {face} at ({s}, {t}): {ours}");
            }
        }
    }
}

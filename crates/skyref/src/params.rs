//! The inputs shared by both precisions: the shader's uniforms ([`FreemanParams`]), Godot's
//! built-ins as a scene ([`Scene`]) and the pixel → EYEDIR mapping ([`Projection`]).
//!
//! Everything here is `f64`; each precision module rounds these values to its own scalar type,
//! as a host does when it fills the f32 uniform buffers of the converted shader.

use glam::DVec3;

/// The uniforms of `freeman_sky.gdshader`, one public field per `uniform`, with the shader's
/// names and declaration order.
///
/// [`Default`] gives the shader's default values (checked against the fixture's text by a unit
/// test). Values are stored as `f64` (float and vec3 uniforms) or `i32` (int uniforms) and
/// rounded to the working precision by [`crate::f32`] / [`crate::f64`]. The shader's hint
/// ranges are not enforced: any value is accepted, and the reference does what the shader's
/// arithmetic does with it (which may be `inf` or `NaN`, never a panic).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FreemanParams {
    /// Intensity of the sun (`sun_intensity`, default 62.832).
    pub sun_intensity: f64,
    /// Wavelengths, in micrometres, that the Rayleigh coefficient uses for R, G, B
    /// (`sun_wavelengths`, default (0.680, 0.550, 0.480)).
    pub sun_wavelengths: DVec3,
    /// Rayleigh scale height in metres (`rayleigh_scale_height`, default 8000).
    pub rayleigh_scale_height: f64,
    /// Strength of the isotropic Rayleigh multi-scattering term
    /// (`rayleigh_multi_scattering`, default 0.01).
    pub rayleigh_multi_scattering: f64,
    /// Mie scale height in metres (`mie_scale_height`, default 1200).
    pub mie_scale_height: f64,
    /// Mie scattering coefficient per metre (`mie_scattering`, default 5e-6).
    pub mie_scattering: f64,
    /// Mie single-scattering albedo (`mie_albedo`, default 0.9).
    pub mie_albedo: f64,
    /// Forward lobe of the double Henyey-Greenstein Mie phase (`mie_g_forward`, default 0.85).
    pub mie_g_forward: f64,
    /// Backward lobe of the Mie phase (`mie_g_backward`, default -0.15).
    pub mie_g_backward: f64,
    /// Weight of the forward lobe (`mie_weight`, default 0.85).
    pub mie_weight: f64,
    /// Strength of the Mie multi-scattering lobe (`mie_multi_scattering`, default 0.30).
    pub mie_multi_scattering: f64,
    /// Forward lobe of the multi-scattering Mie phase (`multiscattering_mie_g_forward`,
    /// default 0.5).
    pub multiscattering_mie_g_forward: f64,
    /// Backward lobe of the multi-scattering Mie phase (`multiscattering_mie_g_backward`,
    /// default -0.05).
    pub multiscattering_mie_g_backward: f64,
    /// Weight of the multi-scattering forward lobe (`multiscattering_mie_weight`,
    /// default 0.75).
    pub multiscattering_mie_weight: f64,
    /// Altitude of the centre of the ozone layer in metres (`ozone_center`, default 25000).
    pub ozone_center: f64,
    /// Width of the ozone layer in metres (`ozone_width`, default 30000).
    pub ozone_width: f64,
    /// Planet radius in metres (`planet_radius`, default 6360000).
    pub planet_radius: f64,
    /// Atmosphere thickness in metres (`atmosphere_height`, default 100000).
    pub atmosphere_height: f64,
    /// Altitude of the camera when `POSITION.y` is 0, in metres (`base_altitude`, default 0).
    pub base_altitude: f64,
    /// Albedo of the ground (`ground_color`, default (0.12, 0.11, 0.08)).
    pub ground_color: DVec3,
    /// Samples along the view ray (`view_samples`, default 24; halved for rays that hit the
    /// ground).
    pub view_samples: i32,
    /// Samples along each path toward the sun (`sun_samples`, default 8).
    pub sun_samples: i32,
}

impl Default for FreemanParams {
    fn default() -> Self {
        Self {
            sun_intensity: 62.832,
            sun_wavelengths: DVec3::new(0.680, 0.550, 0.480),
            rayleigh_scale_height: 8000.0,
            rayleigh_multi_scattering: 0.01,
            mie_scale_height: 1200.0,
            mie_scattering: 5e-6,
            mie_albedo: 0.9,
            mie_g_forward: 0.85,
            mie_g_backward: -0.15,
            mie_weight: 0.85,
            mie_multi_scattering: 0.30,
            multiscattering_mie_g_forward: 0.5,
            multiscattering_mie_g_backward: -0.05,
            multiscattering_mie_weight: 0.75,
            ozone_center: 25000.0,
            ozone_width: 30000.0,
            planet_radius: 6360000.0,
            atmosphere_height: 100000.0,
            base_altitude: 0.0,
            ground_color: DVec3::new(0.12, 0.11, 0.08),
            view_samples: 24,
            sun_samples: 8,
        }
    }
}

/// One uniform of the Freeman sky, borrowed mutably from [`FreemanParams`].
#[derive(Debug)]
pub enum UniformMut<'a> {
    /// A `float` uniform.
    Float(&'a mut f64),
    /// A `vec3` uniform.
    Vec3(&'a mut DVec3),
    /// An `int` uniform.
    Int(&'a mut i32),
}

impl FreemanParams {
    /// Every uniform with the shader's name, in declaration order: the one table that maps the
    /// shader's names to these fields (material bytes, `--set` on the command line).
    pub fn uniforms_mut(&mut self) -> [(&'static str, UniformMut<'_>); 22] {
        use UniformMut::{Float, Int, Vec3};
        [
            ("sun_intensity", Float(&mut self.sun_intensity)),
            ("sun_wavelengths", Vec3(&mut self.sun_wavelengths)),
            ("rayleigh_scale_height", Float(&mut self.rayleigh_scale_height)),
            ("rayleigh_multi_scattering", Float(&mut self.rayleigh_multi_scattering)),
            ("mie_scale_height", Float(&mut self.mie_scale_height)),
            ("mie_scattering", Float(&mut self.mie_scattering)),
            ("mie_albedo", Float(&mut self.mie_albedo)),
            ("mie_g_forward", Float(&mut self.mie_g_forward)),
            ("mie_g_backward", Float(&mut self.mie_g_backward)),
            ("mie_weight", Float(&mut self.mie_weight)),
            ("mie_multi_scattering", Float(&mut self.mie_multi_scattering)),
            ("multiscattering_mie_g_forward", Float(&mut self.multiscattering_mie_g_forward)),
            ("multiscattering_mie_g_backward", Float(&mut self.multiscattering_mie_g_backward)),
            ("multiscattering_mie_weight", Float(&mut self.multiscattering_mie_weight)),
            ("ozone_center", Float(&mut self.ozone_center)),
            ("ozone_width", Float(&mut self.ozone_width)),
            ("planet_radius", Float(&mut self.planet_radius)),
            ("atmosphere_height", Float(&mut self.atmosphere_height)),
            ("base_altitude", Float(&mut self.base_altitude)),
            ("ground_color", Vec3(&mut self.ground_color)),
            ("view_samples", Int(&mut self.view_samples)),
            ("sun_samples", Int(&mut self.sun_samples)),
        ]
    }

    /// Sets the uniform `name` from text as `gdsky --set` takes it (`1.5`, `24`,
    /// `0.1,0.2,0.3`).
    pub fn set(&mut self, name: &str, text: &str) -> Result<(), String> {
        let bad = |what: &str| format!("`{name}={text}`: expected {what}");
        let number = |t: &str| t.trim().parse::<f64>().map_err(|_| bad("a number"));
        let slot = self.uniforms_mut().into_iter().find(|(n, _)| *n == name).map(|(_, u)| u);
        match slot {
            Some(UniformMut::Float(v)) => *v = number(text)?,
            Some(UniformMut::Int(v)) => *v = text.trim().parse().map_err(|_| bad("an int"))?,
            Some(UniformMut::Vec3(v)) => {
                let parts = text.split(',').map(number).collect::<Result<Vec<_>, _>>()?;
                let [x, y, z] = parts[..] else { return Err(bad("three comma-separated numbers")) };
                *v = DVec3::new(x, y, z);
            }
            None => return Err(format!("the Freeman sky has no uniform `{name}`")),
        }
        Ok(())
    }

    /// The same parameters with other sample counts (`view_samples`, `sun_samples`).
    #[must_use]
    pub fn with_samples(self, view_samples: i32, sun_samples: i32) -> Self {
        Self { view_samples, sun_samples, ..self }
    }
}
